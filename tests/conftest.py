"""Test-suite set-up shared by all tests.

* Meshes are cached in a per-run temporary folder (``PROBEDYN_CACHE``) unless the caller set
  one, so tests never read a cache left by another run or by a user.
* Plots use the non-interactive Agg backend; pyvista renders off-screen.
* OpenBLAS and MKL run one thread per test process (two xdist workers on two cores).
"""

import os
import signal
import tempfile

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see probedyn/__init__.py
# MKL (PARDISO) one thread per test process: two xdist workers share two cores, and every native fault
# seen in MKL came from runs with more MKL threads than cores (docs/developing.md, "Native faults")
os.environ.setdefault("MKL_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
if "PROBEDYN_CACHE" not in os.environ:
    os.environ["PROBEDYN_CACHE"] = tempfile.mkdtemp(prefix="probedyn-test-cache-")


@pytest.fixture
def sigint_not_ignored():
    """For tests that deliver SIGINT: under a runner started with SIGINT ignored (``pytest &`` from
    a script, nohup), which probedyn rightly keeps ignoring, give the test the default handler
    (KeyboardInterrupt), and restore the runner's disposition afterwards."""
    old = signal.getsignal(signal.SIGINT)
    if old is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


# -- tests that crashed their worker (a native fault), for ``tools/run_tests.py`` ------------------
# A test that kills its xdist worker with a signal (a segfault in a native library) is reported by
# the controller as failed ("worker crashed"). ``tools/run_tests.py`` (what ``./dev test`` runs) sets
# PROBEDYN_CRASH_LOG; the controller then records the failed and the crashed node ids there, so
# that a run whose only failures are crashes can run those tests once more (docs/developing.md).
_CRASH = {"failed": set(), "crashed": set()}


def _controller(config) -> bool:
    return os.environ.get("PROBEDYN_CRASH_LOG") is not None and not hasattr(config, "workerinput")


@pytest.hookimpl(optionalhook=True)
def pytest_handlecrashitem(crashitem, report, sched):
    if _controller(sched.config):
        _CRASH["crashed"].add(crashitem)


def pytest_runtest_logreport(report):
    if report.failed:
        _CRASH["failed"].add(report.nodeid)


def pytest_sessionfinish(session, exitstatus):
    if _controller(session.config):
        import json

        with open(os.environ["PROBEDYN_CRASH_LOG"], "w") as f:  # the runner's own temporary file
            json.dump({k: sorted(v) for k, v in _CRASH.items()}, f)


# -- file-by-file scheduling that survives a crashed worker ------------------------------------------
# pytest-xdist 3.8's ``--dist loadfile`` scheduler hangs the whole run when a worker crashes after the
# last file was handed out (seen in CI: the run stopped at 96 % until the job's time limit). Two
# defects of ``LoadScopeScheduling``: ``remove_node`` puts *every* file the dead worker ever ran back
# in the queue, finished ones too, and a finished file handed to the replacement worker sends it no
# test, so no report ever comes back to reschedule it; and a worker given a single test holds it
# (it runs a test only once it knows the next one, or is told to shut down), which nobody tells it
# when the queue is already empty. The subclass re-queues only files with tests left, keeps giving a
# worker files until it holds two tests, and shuts a worker down as soon as the queue is empty
# (tests/test_run_tests.py crashes a worker in the last file of a small suite, at its first and its
# last test; docs/developing.md, "Native faults", also at every test of an 8-file suite).


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadfile":
        return None  # xdist's own scheduler for the other modes
    from xdist.scheduler import LoadFileScheduling

    class CrashSafeLoadFile(LoadFileScheduling):
        def remove_node(self, node):
            workload = self.assigned_work.get(node, {})
            for scope in [s for s, unit in workload.items() if all(unit.values())]:
                del workload[scope]  # a finished file is not run again
            return super().remove_node(node)

        def _reschedule(self, node):
            if node.shutting_down:
                return
            if self.workqueue and self._pending_of(self.assigned_work[node]) <= 2:
                self._assign_work_unit(node)
            while self.workqueue and self._pending_of(self.assigned_work[node]) < 2:
                self._assign_work_unit(node)
            if not self.workqueue:
                node.shutdown()

    return CrashSafeLoadFile(config, log)
