"""``tools/run_tests.py`` (what ``./dev test`` and CI run): a test that crashes its xdist worker
(a native fault) gets one serial rerun only when crashes are the run's only failures; an assertion
failure, or a crash that repeats, still fails the run."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

PROBE = '''
import os, signal
from pathlib import Path

FLAG = Path(os.environ["CRASHPROBE_FLAG"])
MODE = os.environ["CRASHPROBE_MODE"]


def test_crashes():
    if MODE == "always" or not FLAG.exists():
        FLAG.touch()
        os.kill(os.getpid(), signal.SIGSEGV)


def test_asserts():
    assert MODE != "plus-failure"
'''


@pytest.mark.parametrize("mode, rc, reruns", [("once", 0, True), ("plus-failure", 1, False), ("always", 128 + 11, True)])
def test_only_crashes_are_rerun_once(tmp_path, mode, rc, reruns):
    shutil.copy(ROOT / "tests" / "conftest.py", tmp_path / "conftest.py")  # the crash-recording hooks
    (tmp_path / "test_probe.py").write_text(PROBE)
    env = {**os.environ, "CRASHPROBE_FLAG": str(tmp_path / "flag"), "CRASHPROBE_MODE": mode,
           "PYTHONFAULTHANDLER": ""}
    p = subprocess.run([sys.executable, str(ROOT / "tools" / "run_tests.py"), str(tmp_path), "-q", "-n", "2",
                        "--dist", "loadfile", "--rootdir", str(tmp_path), "-p", "no:cacheprovider",
                        "--max-worker-restart", "2"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == rc, p.stdout[-2000:] + p.stderr[-2000:]
    assert ("running them once more" in p.stderr) == reruns
