"""Independent reference for lumped/beam.py (not library code): the Timoshenko clamped-free
frequencies from the Timoshenko ODEs by a transfer matrix (``expm``), against Huang's closed-form
equation of :func:`probedyn.lumped.beam.timoshenko_roots` (no shared algebra)."""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

from probedyn.lumped.beam import RectBeam, _scan_roots, _timo_params


def timoshenko_roots_transfer(beam: RectBeam, direction: str, n: int) -> np.ndarray:
    """Independent evaluation of :func:`probedyn.lumped.beam.timoshenko_roots` from the Timoshenko ODEs themselves.

    State ``y = [w, w', psi, psi']`` with
    ``kGA (w'' - psi') + rho A omega^2 w = 0`` and ``EI psi'' + kGA (w' - psi) + rho I omega^2 psi = 0``;
    ``y(L) = expm(A L) y(0)``. Clamped: ``w(0) = psi(0) = 0``; free: moment ``EI psi'(L) = 0`` and
    shear ``kGA (w'(L) - psi(L)) = 0``. Roots of the 2x2 determinant. Used as a cross-check of
    the closed-form equation (no shared algebra).
    """
    I = beam.I(direction)
    EI, kGA, rA, rI, L = beam.E * I, beam.k_shear * beam.G * beam.A, beam.rho * beam.A, beam.rho * I, beam.L
    scale = beam.omega_scale(direction)

    def det(x: float) -> float:
        om2 = (x * x * scale) ** 2
        Amat = np.array(
            [
                [0.0, 1.0, 0.0, 0.0],  # w' = w'
                [-rA * om2 / kGA, 0.0, 0.0, 1.0],  # w'' = psi' - rho A omega^2 / kGA w
                [0.0, 0.0, 0.0, 1.0],  # psi' = psi'
                [0.0, -kGA / EI, (kGA - rI * om2) / EI, 0.0],  # psi'' = -(kGA/EI)(w' - psi) - rho I omega^2/EI psi
            ]
        )
        T = expm(Amat * L)
        # unknowns at the clamp: w'(0) (column 1) and psi'(0) (column 3)
        m = np.array([[T[3, 1], T[3, 3]], [T[1, 1] - T[2, 1], T[1, 3] - T[2, 3]]])
        m = m / np.abs(m).max(axis=1, keepdims=True)  # row scaling: zeros unchanged
        return float(np.linalg.det(m))

    r2, s2 = _timo_params(beam, direction)
    x_max = (1.0 / math.sqrt(r2 * s2)) ** 0.5 * (1 - 1e-9)
    return _scan_roots(det, 0.3, 0.02, n, x_max) ** 2
