"""Analytic beam references, FEM-vs-formula comparison (compare.py) and reductions of FEM modes to
lumped models (reduce.py, smart.py)."""
