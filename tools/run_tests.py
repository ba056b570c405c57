"""Run the test suite (what ``./dev test`` and CI run): pytest with the given arguments, and one
second chance for tests that *crashed* their worker.

A test that kills its pytest-xdist worker with a signal -- a segmentation or general-protection
fault inside a native library -- is reported by the controller as "worker crashed". probedyn has
met one such fault, rarely and not reproducibly: a general-protection fault at one instruction of
MKL 2026.2's DGEMM kernel for AMD Zen, called by PARDISO's factorisation (docs/developing.md,
"Native faults"). Where the *only* failures of a run are such crashes, the crashed tests are run
once more, serially, and that run decides the exit status; the rerun is announced on stderr. A
test that fails an assertion, errors, or crashes again fails the run as before: a deterministic
fault or a wrong number is never retried away.

Usage: ``python tools/run_tests.py [pytest args]`` (exit status: pytest's).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path


def _status(rc: int) -> int:
    """A shell's exit status for a child's return code (killed by signal N: 128 + N)."""
    return 128 - rc if rc < 0 else rc


def run(argv: list[str]) -> int:
    with tempfile.TemporaryDirectory(prefix="probedyn-tests-") as tmp:
        log = Path(tmp) / "outcome.json"
        env = {**os.environ, "PROBEDYN_CRASH_LOG": str(log)}
        rc = subprocess.call([sys.executable, "-m", "pytest", *argv], env=env)
        if rc != 1 or not log.exists():  # 1: tests failed (2-5: interrupted, internal or usage error, none collected)
            return _status(rc)  # also pytest itself killed by a signal (e.g. -n 0 and a crash)
        out = json.loads(log.read_text())
    crashed, failed = set(out["crashed"]), set(out["failed"])
    if not crashed or not failed <= crashed:
        return rc
    ids = sorted(crashed)
    print(f"[probedyn] {len(ids)} test(s) crashed their worker (a native fault; no other failure): "
          "running them once more, serially: " + " ".join(ids), file=sys.stderr, flush=True)
    # serially, without the configured selection (-m) and workers: the node ids are the selection
    rc = subprocess.call([sys.executable, "-m", "pytest", "-o", "addopts=-ra", "-p", "no:xdist", *ids])
    if rc < 0:  # killed by a signal again: the fault is reproducible
        print(f"[probedyn] the rerun crashed again (signal {-rc}): the fault is not a one-off", file=sys.stderr)
    return _status(rc)


if __name__ == "__main__":
    try:
        sys.exit(run(sys.argv[1:]))
    except KeyboardInterrupt:
        sys.exit(130)
