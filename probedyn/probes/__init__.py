"""Registry of probes: each ties a parametric geometry (meshes/) to materials, point masses and
springs (fem/) and to its analytic references (lumped/)."""
