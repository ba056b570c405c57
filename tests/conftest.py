"""Test-suite set-up shared by all tests.

* Meshes are cached in a per-run temporary folder (``PROBEDYN_CACHE``) unless the caller set
  one, so tests never read a cache left by another run or by a user.
* Plots use the non-interactive Agg backend; pyvista renders off-screen.
"""

import os
import signal
import tempfile

import pytest

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see probedyn/__init__.py
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
