"""scikit-fem modal analysis of probe meshes: 3D elasticity, anisotropic materials, point masses and springs,
models augmented by lumped masses on springs (augmented.py), static solves, rendering (render.py)."""
