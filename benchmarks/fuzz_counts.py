"""The fuzz counts of issue 16's closing note: cases tried, clean errors, tracebacks, silent
results from nonsense, hangs -- for the default selection and for the slow one.

Runs the fuzz modules twice through pytest (``-m "not slow"``, then ``-m slow``) with
``PROBEDYN_FUZZ_SUMMARY`` set (tests/fuzzkit.py collects every classified case of the session)
and prints one table. A case is one command line or injected fault whose outcome was classified:
``clean-error`` (exit 2, one ``probedyn: error:`` line), ``ok`` (a good run that must keep
working), ``interrupted`` (128+signal, ``probedyn: interrupted``), or a failure: ``traceback``,
``silent`` (exit 0 for input that must be refused), ``hang``, ``wrong`` (another code/message).
Cases marked ``pending`` wait for another branch (diagnose's own input checks, i11) and are
counted apart.

    .venv/bin/python benchmarks/fuzz_counts.py [--default-only]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODULES = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests").glob("test_fuzz*.py"))
FAIL = ("traceback", "silent", "hang", "wrong")


def _default_signals() -> None:  # the fuzz cases send SIGINT: not inherited as ignored (background runs)
    import signal

    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_DFL)


def run(selection: str) -> tuple[dict, float, str]:
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "summary.json"
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", selection, *MODULES],
                           cwd=ROOT, capture_output=True, text=True, env={**os.environ, "PROBEDYN_FUZZ_SUMMARY": str(path)},
                           preexec_fn=_default_signals)
        dt = time.perf_counter() - t0
        tail = (r.stdout.strip().splitlines() or [""])[-1]
        data = json.loads(path.read_text()) if path.exists() else {"cases": []}
    return data, dt, tail


def counts(cases: list[dict]) -> dict:
    c = {"tried": len(cases)}
    for cat in ("clean-error", "ok", "interrupted", *FAIL):
        c[cat] = sum(1 for r in cases if r["category"] == cat and not r.get("pending"))
    c["pending (other branch)"] = sum(1 for r in cases if r.get("pending"))
    c["pending failing"] = sum(1 for r in cases if r.get("pending") and r["category"] in FAIL)
    return c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--default-only", action="store_true")
    a = ap.parse_args()
    rows = []
    for sel in ["not slow"] + ([] if a.default_only else ["slow"]):
        data, dt, tail = run(sel)
        rows.append((sel, counts(data["cases"]), dt, tail, data["cases"]))
    keys = list(rows[0][1])
    print("| selection | " + " | ".join(keys) + " | wall [s] | pytest |")
    print("|---" * (len(keys) + 3) + "|")
    for sel, c, dt, tail, _ in rows:
        print(f"| {sel} | " + " | ".join(str(c[k]) for k in keys) + f" | {dt:.0f} | {tail} |")
    by_class: dict[int, int] = {}
    for _, _, _, _, cases in rows:
        for r in cases:
            by_class[r["class"]] = by_class.get(r["class"], 0) + 1
    print("cases per failure class of issue 16: " + ", ".join(f"{k}: {v}" for k, v in sorted(by_class.items())))
    bad = [r for _, _, _, _, cases in rows for r in cases if r["category"] in FAIL and not r.get("pending")]
    for r in bad:
        print(f"  NOT AS REQUIRED: {r['id']}: {r['category']}: {r['detail']}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
