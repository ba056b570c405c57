"""Measured data: formats, baseline calibration, residual analysis and a catalog of named model extensions."""
