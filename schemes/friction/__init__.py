"""Friction model registry (one module per model)."""
