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
