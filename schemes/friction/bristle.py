"""The source's generalised-bristle nano-friction model, eqs 2.7-2.12.

    F_x = sigma0x z_x + F_vx V_x                                          (2.7)
    dz_x/dt = max(V_i) - z_x ||V||_inf / g_x                              (2.8)
    g_x = [F_cx + (F_sx - F_cx) exp(-((V_x + V_y) / 2 V_s)^2)] / sigma0x  (2.9)
and the same in y (2.10-2.12).

Interpretation of the print (documented in docs/friction.md):

* ``max(V_i)`` taken literally (``vmax_rule = "literal"``) is not odd in V: for a backward
  scan (V_x < 0, V_y = 0) it is 0, so the bristle relaxes to zero and friction vanishes
  instead of reversing. The default ``vmax_rule = "dominant"`` uses the signed velocity
  component of largest magnitude; for V_y = 0 this is V_x, i.e. exactly LuGre (2.3) with
  sigma1 = 0. For forward scans (V_x >= 0 > V_y or V_y = 0) both rules coincide.
* ``||V||_inf = max(|V_x|, |V_y|)``; the Stribeck exponent uses the signed mean
  (V_x + V_y)/2 as printed, so along x alone the effective Stribeck velocity is 2 V_s.
* F_nu is a viscous coefficient in N s/m (SOURCE-NOTES item 9; Table 2.1 prints N).
* ``F_c <= F_s`` is required in each direction (the exponential must fall to F_c).
* The lattice dependence F(a) of (2.6) enters only through the values of F_s, F_c, F_nu:
  the model contains no length that sets a stick-slip period (see docs/friction.md).
Friction levels scale with the normal-load factor ``load``.
"""

from __future__ import annotations

import numpy as np

from probedyn.params import Param, ParamSet

from .base import FrictionModel, require


class Bristle(FrictionModel):
    name = "bristle"
    equations = "2.7-2.12"
    n_state = 2
    dim = 2
    params = ParamSet([
        Param("sigma0x", 1e4, "N/m", "bristle stiffness x", positive=True, source="2.7, Table 2.1"),
        Param("sigma0y", 1e4, "N/m", "bristle stiffness y", positive=True, source="2.10, Table 2.1"),
        Param("F_sx", 12.95e-9, "N", "static friction x", positive=True, source="2.9, Table 2.1"),
        Param("F_sy", 12.95e-9, "N", "static friction y", positive=True, source="2.12, Table 2.1"),
        Param("F_cx", 12.45e-9, "N", "kinetic friction x", positive=True, source="2.9, Table 2.1"),
        Param("F_cy", 12.45e-9, "N", "kinetic friction y", positive=True, source="2.12, Table 2.1"),
        Param("F_vx", 1e-7, "N s/m", "viscous friction x (N s/m, SOURCE-NOTES 9)", lo=0.0, source="2.7"),
        Param("F_vy", 1e-7, "N s/m", "viscous friction y (N s/m, SOURCE-NOTES 9)", lo=0.0, source="2.10"),
        Param("V_s", 1e-5, "m/s", "Stribeck velocity", positive=True, source="2.9"),
        Param("vmax_rule", "dominant", "", "reading of max(V_i) in 2.8/2.11", kind=str,
              choices=("dominant", "literal")),
    ])

    def validate(self):
        p = self.p
        for a in "xy":
            require(p[f"F_c{a}"] <= p[f"F_s{a}"],
                    f"bristle: F_c{a} = {p[f'F_c{a}']:g} N exceeds F_s{a} = {p[f'F_s{a}']:g} N (the model forbids F_c > F_s)")

    def _vmax(self, V):
        """max(V_i) and its gradient w.r.t. (V_x, V_y)."""
        if self.p["vmax_rule"] == "literal":
            return (V[0], np.array([1.0, 0.0])) if V[0] >= V[1] else (V[1], np.array([0.0, 1.0]))
        return (V[0], np.array([1.0, 0.0])) if abs(V[0]) >= abs(V[1]) else (V[1], np.array([0.0, 1.0]))

    def _ninf(self, V):
        if abs(V[0]) >= abs(V[1]):
            return abs(V[0]), np.array([np.sign(V[0]), 0.0])
        return abs(V[1]), np.array([0.0, np.sign(V[1])])

    def _g(self, V, load):
        p = self.p
        u = (V[0] + V[1]) / (2.0 * p["V_s"])
        e = np.exp(-u * u)
        de = e * (-2.0 * u) / (2.0 * p["V_s"])  # d e / d V_x = d e / d V_y
        g = np.empty(2)
        dg = np.empty(2)
        for i, a in enumerate("xy"):
            g[i] = load * (p[f"F_c{a}"] + (p[f"F_s{a}"] - p[f"F_c{a}"]) * e) / p[f"sigma0{a}"]
            dg[i] = load * (p[f"F_s{a}"] - p[f"F_c{a}"]) * de / p[f"sigma0{a}"]
        return g, dg

    def rates(self, X, V, Z, load=1.0):
        vm, _ = self._vmax(V)
        n, _ = self._ninf(V)
        g, _ = self._g(V, load)
        return vm - Z * n / g

    def force(self, X, V, Z, load=1.0):
        p = self.p
        return np.array([p["sigma0x"] * Z[0] + p["F_vx"] * V[0], p["sigma0y"] * Z[1] + p["F_vy"] * V[1]])

    def jacobian(self, X, V, Z, load=1.0):
        p = self.p
        vm, dvm = self._vmax(V)
        n, dn = self._ninf(V)
        g, dg = self._g(V, load)
        dZv = np.empty((2, 2))
        for i in range(2):
            # d/dV [vm - z n / g] ; dg/dVx = dg/dVy = dg[i]
            dZv[i] = dvm - Z[i] * (dn / g[i] - n * dg[i] / g[i] ** 2 * np.ones(2))
        dZz = np.diag(-n / g)
        dFv = np.diag([p["F_vx"], p["F_vy"]])
        dFz = np.diag([p["sigma0x"], p["sigma0y"]])
        return np.zeros((2, 2)), dFv, dFz, np.zeros((2, 2)), dZv, dZz

    def steady_force(self, v, load=1.0):
        g, _ = self._g(np.array([v, 0.0]), load)
        return self.p["sigma0x"] * g[0] * np.sign(v) + self.p["F_vx"] * v

    def length_scales(self):
        p = self.p
        return np.array([p["F_sx"] / p["sigma0x"], p["F_sy"] / p["sigma0y"]])

    def force_scale(self):
        return self.p["F_sx"]

    def damping(self):
        return self.p["F_vx"]
