"""LuGre friction model, eqs 2.3-2.5 of the source (Canudas de Wit et al. 1995).

    dz/dt = v - z |v| / g(v)                                  (2.3)
    g(v)  = [F_c + (F_s - F_c) exp(-(v/V_s)^2)] / sigma0      (2.4)
    F     = sigma0 z + sigma1 dz/dt + F_v v                    (2.5)

1D (x only). ``F_s >= F_c > 0`` is required (the Stribeck curve decreases from the static to
the kinetic level).  Friction levels scale with the normal-load factor ``load``.
Steady sliding: z = g(v) sign(v), F = sigma0 g(v) sign(v) + F_v v.
"""

from __future__ import annotations

import numpy as np

from probedyn.params import Param, ParamSet

from .base import FrictionModel, require


class LuGre(FrictionModel):
    name = "lugre"
    equations = "2.3-2.5"
    n_state = 1
    dim = 1
    params = ParamSet([
        Param("sigma0", 1e4, "N/m", "bristle stiffness", positive=True, source="2.5"),
        Param("sigma1", 0.0, "N s/m", "bristle damping", lo=0.0, source="2.5"),
        Param("F_s", 12.95e-9, "N", "static friction", positive=True, source="2.4"),
        Param("F_c", 12.45e-9, "N", "Coulomb (kinetic) friction", positive=True, source="2.4"),
        Param("F_v", 1e-7, "N s/m", "viscous friction coefficient", lo=0.0, source="2.5"),
        Param("V_s", 1e-5, "m/s", "Stribeck velocity", positive=True, source="2.4"),
    ])

    def validate(self) -> None:
        p = self.p
        require(p["F_c"] <= p["F_s"], f"lugre: F_c = {p['F_c']:g} N exceeds F_s = {p['F_s']:g} N (the Stribeck curve must fall from F_s to F_c)")

    def _g(self, v, load):
        p = self.p
        e = np.exp(-(v / p["V_s"]) ** 2)
        g = load * (p["F_c"] + (p["F_s"] - p["F_c"]) * e) / p["sigma0"]
        dg = load * (p["F_s"] - p["F_c"]) * e * (-2.0 * v / p["V_s"] ** 2) / p["sigma0"]
        return g, dg

    def rates(self, X, V, Z, load=1.0):
        v = V[0]
        g, _ = self._g(v, load)
        return np.array([v - Z[0] * abs(v) / g])

    def force(self, X, V, Z, load=1.0):
        p = self.p
        zd = self.rates(X, V, Z, load)[0]
        return np.array([p["sigma0"] * Z[0] + p["sigma1"] * zd + p["F_v"] * V[0], 0.0])

    def jacobian(self, X, V, Z, load=1.0):
        p = self.p
        v, z = V[0], Z[0]
        g, dg = self._g(v, load)
        s = np.sign(v)
        dzd_dz = -abs(v) / g
        dzd_dv = 1.0 - z * (s / g - abs(v) * dg / g ** 2)
        dFx = np.zeros((2, 2))
        dFv = np.zeros((2, 2))
        dFv[0, 0] = p["sigma1"] * dzd_dv + p["F_v"]
        dFz = np.zeros((2, 1))
        dFz[0, 0] = p["sigma0"] + p["sigma1"] * dzd_dz
        dZv = np.zeros((1, 2))
        dZv[0, 0] = dzd_dv
        return dFx, dFv, dFz, np.zeros((1, 2)), dZv, np.array([[dzd_dz]])

    def steady_force(self, v, load=1.0):
        g, _ = self._g(v, load)
        return self.p["sigma0"] * g * np.sign(v) + self.p["F_v"] * v

    def length_scales(self):
        return np.array([self.p["F_s"] / self.p["sigma0"]])

    def force_scale(self):
        return self.p["F_s"]

    def damping(self):
        return self.p["F_v"] + self.p["sigma1"]
