"""Parametric gmsh geometries of the probes (plain cantilever, duo-bimorph, piezotube)."""
