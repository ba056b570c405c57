"""probedyn: finite-element and reduced-order dynamics of AFM probes used as nanomanipulators.

The pipeline is geometry -> mesh -> modes -> lumped model -> scheme:

* ``probedyn.meshes``  parametric gmsh geometries of the probes (served from ``meshes/``)
* ``probedyn.fem``     scikit-fem modal analysis (``fem/``)
* ``probedyn.lumped``  analytic beam references and automatic model reduction (``lumped/``)
* ``probedyn.schemes`` friction, contact, pushing and placing simulations (``schemes/``)

All quantities are SI (m, kg, s, N, Pa, V).
"""

import os as _os
import sys as _sys

# OpenBLAS's spinning threads compete with MKL PARDISO's on few cores: ARPACK's dense steps ran
# 3-5x slower on 2 cores with them (benchmarks/modal.py). Read by OpenBLAS when numpy loads it.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
if _os.environ["OPENBLAS_NUM_THREADS"] == "1" and "numpy" in _sys.modules:
    # numpy (and its OpenBLAS) was loaded before probedyn and read the variable before it was set: the loaded
    # OpenBLAS libraries are held to one thread now, so that a session that imports numpy first runs as the
    # command line does and computes the same numbers (with two threads the reduced eigenproblems round
    # differently: the 6-mode modal example took 1756 evaluations instead of 1852, docs/diagnose.md 9.62)
    from threadpoolctl import ThreadpoolController as _ThreadpoolController

    _ThreadpoolController().select(internal_api="openblas").limit(limits=1)

__version__ = "0.1.0"
