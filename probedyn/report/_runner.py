"""Running the report's sections: one after the other, or on several worker processes.

The sections are independent (each computes from the library and writes its own figures), so on
a machine with two cores two of them can run at once. :func:`run_sections` does either:

* **serial** (``jobs=1``): each section in this process, in the order of ``SECTIONS``; sections
  share this process's memoised solves.
* **parallel** (``jobs>=2``): a pool of ``jobs`` worker processes (``spawn``: a clean interpreter,
  nothing inherited from the command line's threads and signal handlers), sections submitted
  longest first (by :data:`EXPECTED_CPU_S`, so the longest does not start last and leave one
  core idle at the end). Each worker writes its figures into a private staging folder; the
  Markdown comes back to this process, which assembles it in the order of ``SECTIONS``, so the
  report reads the same whatever order the sections finished in. When every section has
  succeeded, the staged files are moved into ``outdir`` through :func:`probedyn.core.io.atomic_path`
  (so inside the command line's output transaction they appear together with ``report.md``).

Threads: MKL, OpenMP, OpenBLAS and numba are limited to one thread per worker (environment,
set before the worker imports numpy), so ``jobs`` workers use ``jobs`` cores, not ``jobs`` x 2.

Failures: a section that raises in a worker cancels the sections not started, kills the running
workers, removes the staging folder and re-raises the same exception here (a
:class:`~probedyn.core.errors.ProbedynError` stays one line on the command line); a worker that
dies (killed, out of memory) is a :class:`~probedyn.core.errors.ResourceError`. An interrupt
(Ctrl-C reaches the whole process group: the workers ignore SIGINT and this process handles it)
kills the workers and removes the staging folder; nothing is written into ``outdir``. Workers
also exit by themselves when this process disappears (they poll their parent), so a killed
report leaves no orphan writing files.

The staging folder is named like every probedyn temporary (``.report-stage.probedyn-tmp-...``),
so :func:`probedyn.core.io.clean_stale` removes one left by a killed run.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import importlib
import multiprocessing
import os
import shutil
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

from probedyn.core import io
from probedyn.core.errors import ProbedynError, ResourceError
from probedyn.core.resources import environment

#: CPU seconds of each section in the full (not quick) report, measured in the workers of a
#: fresh-clone run (benchmarks/results/report-times-s4.json, "after_fresh_clone_cold_parallel");
#: only the ORDER matters: the parallel runner starts the longest first. Sections not listed
#: count as 5 s.
EXPECTED_CPU_S: dict[str, float] = {
    "The plain cantilever": 4.3,
    "The smart probes: duo-bimorph and piezotube": 36.8,
    "Piezoelectric actuation of the smart probes": 3.2,
    "Path tracking and probe control": 5.1,
    "Nano-friction and FFM line scans": 12.2,
    "Tip-sample contact and adhesion-friction coupling": 10.5,
    "Nano-pushing": 24.2,
    "Two-mass stick-slip dynamics": 36.6,
    "Schemes on probes reduced from their FEM": 32.9,
    "Vibrational nano-placing": 15.4,
    "Measured data: diagnosis": 3.4,
}

#: environment of the workers: one thread each for the numeric libraries
WORKER_ENV = {
    "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1", "MKL_DYNAMIC": "FALSE", "VECLIB_MAXIMUM_THREADS": "1",
}

JOBS_ENV = "PROBEDYN_REPORT_JOBS"


@dataclass
class SectionResult:
    title: str
    body: str
    wall_s: float
    cpu_s: float


def default_jobs() -> int:
    """``$PROBEDYN_REPORT_JOBS`` if set (1 = serial), else min(2, usable cores)."""
    env = os.environ.get(JOBS_ENV, "").strip()
    if env:
        try:
            n = int(env)
        except ValueError:
            n = 0
        if n < 1:
            from probedyn.core.errors import ParameterError

            raise ParameterError(f"{JOBS_ENV} must be a whole number >= 1 (1 = serial), got {env!r}")
        return n
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover
        cores = os.cpu_count() or 1
    return max(1, min(2, cores))


def _call(target: str, outdir: Path, quick: bool) -> tuple[str, float, float]:
    mod_name, func_name = target.split(":")
    func = getattr(importlib.import_module(mod_name), func_name)
    t0, c0 = time.perf_counter(), time.process_time()
    body = func(outdir, quick)
    return body, time.perf_counter() - t0, time.process_time() - c0


def run_serial(sections: Sequence[tuple[str, str]], outdir: Path, quick: bool) -> list[SectionResult]:
    out = []
    for title, target in sections:
        body, wall, cpu = _call(target, outdir, quick)
        out.append(SectionResult(title, body, wall, cpu))
    return out


# ------------------------------------------------------------------------------------------
# Workers
# ------------------------------------------------------------------------------------------


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:  # re-parented: the report process is gone
            os._exit(1)


def _worker_init(parent: int) -> None:
    # Ctrl-C goes to the whole process group: the report process handles it and kills us (the
    # worker was started with SIGINT blocked, see _sigint_held: ignore it, then unblock)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    for s in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_DFL)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True, name="report-parent-watch").start()


def _worker_run(target: str, stage: str, quick: bool) -> tuple[str, float, float]:
    return _call(target, Path(stage), quick)


@contextlib.contextmanager
def _staging(outdir: Path) -> Iterator[Path]:
    """A private folder inside ``outdir`` named like a probedyn temporary; removed on exit."""
    io.make_dirs(outdir)
    stage = outdir / io._tmp_name("report-stage")
    io._register(stage)
    try:
        stage.mkdir()
        yield stage
    finally:
        io._remove(stage)
        io._unregister(stage)


def _stop(ex: cf.ProcessPoolExecutor) -> None:
    """Kill the workers (a running section cannot be cancelled otherwise) and reap them."""
    procs = list(getattr(ex, "_processes", {}).values())
    for p in procs:
        with contextlib.suppress(Exception):
            p.kill()
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(timeout=5.0)


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """Hold Ctrl-C while the workers are started (the first submits fork and exec them).

    SIGINT is blocked in this thread, and a child inherits the mask through fork and exec: a
    worker is immune to Ctrl-C from birth until its initializer ignores the signal (a Ctrl-C
    during its imports would print a KeyboardInterrupt traceback). A Ctrl-C that arrives
    meanwhile (another thread, e.g. the command line's watchdog, takes it) is recorded instead of
    interrupting this thread half-way through starting a worker, and handed to the previous
    handler once the workers are started: it is delayed by milliseconds, never lost.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    old_handler = signal.signal(signal.SIGINT, lambda signum, frame: pending.append(signum))
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)  # a pending SIGINT is recorded here
        signal.signal(signal.SIGINT, old_handler)
    if pending:
        if callable(old_handler):
            old_handler(signal.SIGINT, None)
        elif old_handler == signal.SIG_DFL:
            signal.raise_signal(signal.SIGINT)


def _move_staged(stage: Path, outdir: Path) -> None:
    """Move every finished file of ``stage`` to the same place below ``outdir`` (through
    :func:`probedyn.core.io.atomic_path`: deferred inside a transaction)."""
    for root, _dirs, files in os.walk(stage):
        for name in sorted(files):
            if io._TAG in name:  # a temporary of a write that did not finish
                continue
            src = Path(root) / name
            dst = outdir / src.relative_to(stage)
            with io.atomic_path(dst) as tmp:
                os.replace(src, tmp)


def run_parallel(sections: Sequence[tuple[str, str]], outdir: Path, quick: bool, jobs: int) -> list[SectionResult]:
    order = sorted(range(len(sections)), key=lambda i: -EXPECTED_CPU_S.get(sections[i][0], 5.0))
    results: dict[int, SectionResult] = {}
    with _staging(outdir) as stage:
        with environment(WORKER_ENV):
            ex = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                        initializer=_worker_init, initargs=(os.getpid(),))
            try:
                with _sigint_held():  # the workers are started by the first submits
                    futs = {ex.submit(_worker_run, sections[i][1], str(stage), quick): i for i in order}
                for fut in cf.as_completed(futs):
                    i = futs[fut]
                    title = sections[i][0]
                    try:
                        body, wall, cpu = fut.result()
                    except cf.process.BrokenProcessPool:
                        raise ResourceError(f"report section {title!r}: its worker process died "
                                            "(killed, or out of memory); PROBEDYN_REPORT_JOBS=1 runs the "
                                            "sections one after the other") from None
                    results[i] = SectionResult(title, body, wall, cpu)
            except BaseException:
                _stop(ex)
                raise
            ex.shutdown(wait=True)
        _move_staged(stage, outdir)
    return [results[i] for i in range(len(sections))]


def run_sections(sections: Sequence[tuple[str, str]], outdir: Path, quick: bool,
                 jobs: int | None = None) -> list[SectionResult]:
    """Run ``sections`` (``(title, "module:function")``) and return their results in the given
    order; ``jobs`` worker processes (None: :func:`default_jobs`; 1: serial in this process)."""
    jobs = default_jobs() if jobs is None else int(jobs)
    if jobs < 1:
        from probedyn.core.errors import ParameterError

        raise ParameterError(f"jobs must be >= 1, got {jobs}")
    if jobs == 1 or len(sections) < 2:
        return run_serial(sections, outdir, quick)
    return run_parallel(sections, outdir, quick, min(jobs, len(sections)))


__all__ = ["EXPECTED_CPU_S", "JOBS_ENV", "SectionResult", "default_jobs", "run_sections", "run_serial",
           "run_parallel", "ProbedynError"]
