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


SUITE_FILE = '''
import os, signal, time
from pathlib import Path

import pytest


@pytest.mark.parametrize("i", range(3))
def test_t(i):
    time.sleep(0.1)
    flag = Path(os.environ["CRASHPROBE_FLAG"])
    if f"{Path(__file__).stem}-{i}" == os.environ["CRASHPROBE_AT"] and not flag.exists():
        flag.touch()
        os.kill(os.getpid(), signal.SIGSEGV)
'''


@pytest.mark.parametrize("at", ["test_d-0", "test_d-2"])
def test_a_crash_after_the_last_file_was_handed_out_does_not_hang_the_run(tmp_path, at):
    """The CI hang of session 12: a worker crashing once every file has been handed out (here in the
    last file, after the crashing worker finished an earlier one; at its first test and at its last,
    which leaves the replacement worker a single test). xdist 3.8's own ``loadfile`` scheduler re-queues
    the finished file and never shuts the replacement down; the conftest's scheduler finishes the run:
    every test runs, the crashed one is reported, rerun and passes."""
    shutil.copy(ROOT / "tests" / "conftest.py", tmp_path / "conftest.py")  # the hooks and the scheduler
    for name in "abcd":
        (tmp_path / f"test_{name}.py").write_text(SUITE_FILE)
    env = {**os.environ, "CRASHPROBE_FLAG": str(tmp_path / "flag"), "CRASHPROBE_AT": at, "PYTHONFAULTHANDLER": ""}
    try:
        p = subprocess.run([sys.executable, str(ROOT / "tools" / "run_tests.py"), str(tmp_path), "-q", "-n", "2",
                            "--dist", "loadfile", "--rootdir", str(tmp_path), "-p", "no:cacheprovider"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, timeout=90)
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"the run hung after the crash:\n{exc.stdout!s:.2000}") from None
    assert (tmp_path / "flag").exists()  # the crash happened
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    assert "1 failed, 12 passed" in p.stdout  # the crash reported, then all 12 tests passed
    assert "running them once more" in p.stderr
