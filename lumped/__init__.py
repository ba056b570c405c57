"""Analytic beam references and automatic reduction of FEM modes to lumped models."""
