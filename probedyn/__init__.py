"""probedyn: finite-element and reduced-order dynamics of AFM probes used as nanomanipulators.

The pipeline is geometry -> mesh -> modes -> lumped model -> scheme:

* ``probedyn.meshes``  parametric gmsh geometries of the probes (served from ``meshes/``)
* ``probedyn.fem``     scikit-fem modal analysis (``fem/``)
* ``probedyn.lumped``  analytic beam references and automatic model reduction (``lumped/``)
* ``probedyn.schemes`` friction, contact, pushing and placing simulations (``schemes/``)

All quantities are SI (m, kg, s, N, Pa, V).
"""

import os as _os

# OpenBLAS's spinning threads compete with MKL PARDISO's on few cores: ARPACK's dense steps ran
# 3-5x slower on 2 cores with them (benchmarks/modal.py). Must be set before numpy is imported.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"
