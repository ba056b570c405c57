"""Prandtl-Tomlinson (PT) friction: the tip in a periodic substrate potential.

1D:        U = -U0 cos(2 pi x / a)
square:    U = -U0 [cos(2 pi x / a) + cos(2 pi y / a)]
hexagonal: U = -(U0/2) [2 cos(2 pi x/a) cos(2 pi y/(sqrt3 a)) + cos(4 pi y/(sqrt3 a))]
(normalised so that the barrier along the x lattice axis is 2 U0 and the curvature at a
minimum along x is 4 pi^2 U0 / a^2 in all three cases).  The friction force on the tip is
F = load * grad U + gamma V (``gamma`` a viscous coupling to the substrate).  With a lateral
spring k the quasi-static path has jumps (stick-slip) iff eta = 4 pi^2 U0 / (k a^2) > 1.
The lattice period *emerges* here: one slip per lattice site for 1 < eta < ~4.6 (overdamped).
Thermal noise is added by :mod:`probedyn.schemes.ffm` (Langevin force, fixed seed).
"""

from __future__ import annotations

import numpy as np

from probedyn.params import Param, ParamSet

from .base import FrictionModel

S3 = np.sqrt(3.0)


class PrandtlTomlinson(FrictionModel):
    name = "pt"
    equations = "PT (section 2.1.2.1, 4.1)"
    n_state = 0
    dim = 2
    params = ParamSet([
        Param("U0", 5.5e-21, "J", "corrugation amplitude (barrier 2 U0)", positive=True),
        Param("a", 0.519e-9, "m", "lattice constant (mica, Table 4.2)", positive=True, hi=1e-6, source="Table 4.2"),
        Param("lattice", "1d", "", "substrate lattice", kind=str, choices=("1d", "square", "hex")),
        Param("gamma", 0.0, "N s/m", "viscous coupling to the substrate", lo=0.0),
    ])

    def potential(self, X):
        p = self.p
        q = 2 * np.pi / p["a"]
        x, y = X[0], X[1]
        if p["lattice"] == "1d":
            return -p["U0"] * np.cos(q * x)
        if p["lattice"] == "square":
            return -p["U0"] * (np.cos(q * x) + np.cos(q * y))
        return -0.5 * p["U0"] * (2 * np.cos(q * x) * np.cos(q * y / S3) + np.cos(2 * q * y / S3))

    def _grad_hess(self, X):
        p = self.p
        U0, q = p["U0"], 2 * np.pi / p["a"]
        x, y = X[0], X[1]
        G = np.zeros(2)
        H = np.zeros((2, 2))
        if p["lattice"] in ("1d", "square"):
            G[0] = U0 * q * np.sin(q * x)
            H[0, 0] = U0 * q * q * np.cos(q * x)
            if p["lattice"] == "square":
                G[1] = U0 * q * np.sin(q * y)
                H[1, 1] = U0 * q * q * np.cos(q * y)
        else:
            r = q / S3
            cx, sx, cy, sy = np.cos(q * x), np.sin(q * x), np.cos(r * y), np.sin(r * y)
            c2, s2 = np.cos(2 * r * y), np.sin(2 * r * y)
            G[0] = U0 * q * sx * cy
            G[1] = U0 * (r * cx * sy + r * s2)
            H[0, 0] = U0 * q * q * cx * cy
            H[0, 1] = H[1, 0] = -U0 * q * r * sx * sy
            H[1, 1] = U0 * (r * r * cx * cy + 2 * r * r * c2)
        return G, H

    def force(self, X, V, Z, load=1.0):
        G, _ = self._grad_hess(X)
        return load * G + self.p["gamma"] * np.asarray(V)

    def jacobian(self, X, V, Z, load=1.0):
        _, H = self._grad_hess(X)
        e = np.zeros((2, 0))
        return load * H, self.p["gamma"] * np.eye(2), e, np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 0))

    def eta(self, k: float) -> float:
        """Tomlinson parameter 4 pi^2 U0 / (k a^2)."""
        return 4 * np.pi ** 2 * self.p["U0"] / (k * self.p["a"] ** 2)

    def steady_force(self, v, load=1.0):
        return self.p["gamma"] * v

    def force_scale(self):
        return 2 * np.pi * self.p["U0"] / self.p["a"]

    def damping(self):
        return self.p["gamma"]
