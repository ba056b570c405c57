"""Test-suite set-up shared by all tests.

* Meshes are cached in a per-run temporary folder (``PROBEDYN_CACHE``) unless the caller set
  one, so tests never read a cache left by another run or by a user.
* Plots use the non-interactive Agg backend; pyvista renders off-screen.
"""

import os
import tempfile

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # see probedyn/__init__.py
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
if "PROBEDYN_CACHE" not in os.environ:
    os.environ["PROBEDYN_CACHE"] = tempfile.mkdtemp(prefix="probedyn-test-cache-")
