"""Harness of the fuzz-style CLI tests (tests/test_fuzz_cli.py, tests/test_fuzz_faults.py).

A :class:`Case` is one command line (bad input, an injected fault, or a good run that must
keep working) with what must happen; :func:`run_case` runs it in this process (through
``probedyn.cli.main``, stdout/stderr captured, a SIGALRM time limit) or in a child process
(``python -m probedyn.cli``), and :func:`classify` sorts the outcome:

* ``clean-error``: exit 2 and exactly one ``probedyn: error: ...`` line (matching the case's
  pattern), no traceback;
* ``ok`` / ``interrupted``: the expected success, or exit 128+signal with ``probedyn: interrupted``;
* failures: ``traceback`` (an exception escaped, or a traceback was printed), ``silent`` (exit 0
  for input that must be refused: a result computed from nonsense), ``hang`` (time limit),
  ``wrong`` (another exit code or message).

:data:`TALLY` collects every classified outcome of the session; the summary test prints it
(and writes it as JSON to ``$PROBEDYN_FUZZ_SUMMARY`` if set).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from probedyn.core.resources import environment

BAD = ("traceback", "silent", "hang", "wrong")
TALLY: list[dict[str, Any]] = []


@dataclass
class Case:
    id: str
    cls: int                      # failure class of issue 16 (1-11)
    argv: list[str]
    expect: str = "error"         # "error" | "ok" | "interrupted"
    match: str | None = None      # regex the error line must contain
    setup: Callable[[Path], dict[str, str] | None] | None = None  # make files; may return env vars
    env: dict[str, str] = field(default_factory=dict)
    child: bool = False           # run as a child process (else in this process)
    timeout: float = 60.0
    pending: str | None = None    # branch whose fix this case waits for (xfail until merged)
    check: Callable[[Path, "Outcome"], str | None] | None = None  # extra check; returns a problem

    def __str__(self) -> str:
        return self.id


@dataclass
class Outcome:
    code: int | None
    out: str
    err: str
    seconds: float
    hung: bool = False
    escaped: str | None = None    # traceback of an exception that escaped main()


class _Hang(BaseException):
    pass


def _fill(argv: list[str], tmp: Path) -> list[str]:
    return [a.replace("{tmp}", str(tmp)) for a in argv]


def run_inprocess(argv: list[str], env: dict[str, str] | None = None, timeout: float = 60.0) -> Outcome:
    from probedyn.cli import main

    out, err = io.StringIO(), io.StringIO()
    code: int | None = None
    escaped = None
    hung = False

    def alarm(signum, frame):
        raise _Hang()

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    t0 = time.perf_counter()
    try:
        with environment(env or {}), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except _Hang:
                hung = True
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 1
            except BaseException:  # noqa: BLE001 - a bug: record it
                escaped = traceback.format_exc()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    return Outcome(code, out.getvalue(), err.getvalue(), time.perf_counter() - t0, hung, escaped)


def child_cmd() -> list[str]:
    return [sys.executable, "-m", "probedyn.cli"]


#: heap limit of a child case (RLIMIT_DATA): a case that reads without bound fails there, not the machine
CHILD_DATA_LIMIT = 3 * 1024**3


def limit_memory() -> None:  # runs in the child before exec
    import resource

    resource.setrlimit(resource.RLIMIT_DATA, (CHILD_DATA_LIMIT, CHILD_DATA_LIMIT))
    # a runner started with SIGINT ignored (``pytest &`` from a script) would pass that on, and
    # probedyn keeps an inherited SIG_IGN: the children under test start with the default actions
    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_DFL)


def run_child(argv: list[str], env: dict[str, str] | None = None, timeout: float = 60.0,
              cwd: Path | None = None) -> Outcome:
    t0 = time.perf_counter()
    try:
        cp = subprocess.run(child_cmd() + argv, capture_output=True, text=True, timeout=timeout,
                            env={**os.environ, **(env or {})}, cwd=cwd, stdin=subprocess.DEVNULL,
                            preexec_fn=limit_memory)
    except subprocess.TimeoutExpired as exc:
        return Outcome(None, exc.stdout or "", exc.stderr or "", time.perf_counter() - t0, hung=True)
    return Outcome(cp.returncode, cp.stdout, cp.stderr, time.perf_counter() - t0)


def classify(case: Case, o: Outcome) -> tuple[str, str]:
    """(category, detail) of an outcome."""
    if o.hung:
        return "hang", f"no exit within {case.timeout:g} s"
    if o.escaped or "Traceback (most recent call last)" in o.err:
        return "traceback", (o.escaped or o.err).strip().splitlines()[-1]
    err_lines = [ln for ln in o.err.splitlines() if ln.strip()]
    errors = [ln for ln in err_lines if ln.startswith("probedyn: error:")]
    if case.expect == "ok":
        if o.code == 0:
            return "ok", ""
        return ("wrong", f"exit {o.code}: {errors[0] if errors else o.err.strip()[-200:]}")
    if case.expect == "interrupted":
        if o.code in (128 + signal.SIGINT, 128 + signal.SIGTERM, 128 + signal.SIGHUP) and \
                [ln for ln in err_lines if ln == "probedyn: interrupted"]:
            return "interrupted", ""
        return "wrong", f"exit {o.code}, stderr {o.err.strip()[-200:]!r}"
    # expect == "error"
    if o.code == 0:
        return "silent", f"exit 0 for input that must be refused; stdout {o.out.strip()[:120]!r}"
    if o.code != 2 or len(errors) != 1:
        return "wrong", f"exit {o.code}, {len(errors)} error lines: {o.err.strip()[-300:]!r}"
    if case.match and not re.search(case.match, errors[0]):
        return "wrong", f"message {errors[0]!r} does not match {case.match!r}"
    return "clean-error", errors[0]


def run_case(case: Case, tmp: Path) -> tuple[str, str, Outcome]:
    env = dict(case.env)
    if case.setup is not None:
        env.update(case.setup(tmp) or {})
    env = {k: v.replace("{tmp}", str(tmp)) for k, v in env.items()}
    argv = _fill(case.argv, tmp)
    if case.child or case.pending:  # unknown behaviour (not fixed yet): never in this process
        o = run_child(argv, env, case.timeout, cwd=tmp)
    else:
        cwd = os.getcwd()
        os.chdir(tmp)
        try:
            o = run_inprocess(argv, env, case.timeout)
        finally:
            os.chdir(cwd)
    cat, detail = classify(case, o)
    if cat in ("ok", "clean-error", "interrupted") and case.check is not None:
        problem = case.check(tmp, o)
        if problem:
            cat, detail = "wrong", problem
    TALLY.append({"id": case.id, "class": case.cls, "category": cat, "detail": detail,
                  "seconds": round(o.seconds, 2), "pending": case.pending, "child": case.child})
    return cat, detail, o


def summary() -> dict[str, Any]:
    cats: dict[str, int] = {}
    by_class: dict[int, dict[str, int]] = {}
    for r in TALLY:
        cats[r["category"]] = cats.get(r["category"], 0) + 1
        c = by_class.setdefault(r["class"], {})
        c[r["category"]] = c.get(r["category"], 0) + 1
    return {"tried": len(TALLY), "categories": cats, "by_class": dict(sorted(by_class.items())),
            "bad": [r for r in TALLY if r["category"] in BAD]}


def write_summary() -> None:
    path = os.environ.get("PROBEDYN_FUZZ_SUMMARY")
    if path:
        Path(path).write_text(json.dumps({**summary(), "cases": TALLY}, indent=2) + "\n")


# the cases of every fuzz module run in this session, written once more when the session ends
# (test_zz_fuzz_summary writes them too, but before the modules that follow it alphabetically)
import atexit  # noqa: E402

atexit.register(lambda: TALLY and write_summary())
