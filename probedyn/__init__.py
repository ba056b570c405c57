"""probedyn: finite-element and reduced-order dynamics of AFM probes used as nanomanipulators.

The pipeline is geometry -> mesh -> modes -> lumped model -> scheme:

* ``probedyn.meshes``  parametric gmsh geometries of the probes (served from ``meshes/``)
* ``probedyn.fem``     scikit-fem modal analysis (``fem/``)
* ``probedyn.lumped``  analytic beam references and automatic model reduction (``lumped/``)
* ``probedyn.schemes`` friction, contact, pushing and placing simulations (``schemes/``)

All quantities are SI (m, kg, s, N, Pa, V).
"""

__version__ = "0.1.0"
