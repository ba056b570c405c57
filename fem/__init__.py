"""scikit-fem modal analysis of probe meshes: 3D elasticity, anisotropic materials, point masses and springs."""
