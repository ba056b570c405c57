"""LuGre friction model, eqs (2.3)–(2.5) of the source (Canudas de Wit et al. 1995).

    dz/dt = V - z |V| / g(V)                                        (2.3)
    g(V)  = [F_c + (F_s - F_c) exp(-(V/V_s)^2)] / sigma_0           (2.4)
    F     = sigma_0 z + sigma_1 dz/dt + F_v V                        (2.5)

``V`` is the sliding velocity of the tip relative to the sample, ``z`` the mean bristle
deflection [m]. Steady sliding (dz/dt = 0): ``F = sign(V) [F_c + (F_s - F_c) exp(-(V/V_s)^2)]
+ F_v V`` (the Stribeck curve). At rest and for small displacements (pre-sliding) the model is a
spring of stiffness ``sigma_0``. The print is dimensionally consistent; it is used as printed.
F_s < F_c (velocity strengthening) is admissible in LuGre; F_s, F_c must be positive so that
g > 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from probedyn.core.params import Param, ParamSet

from .base import FRICTION_MODELS, TABLE_2_1, BristleModel, positive_param


@njit(cache=True)
def lugre_kernel(p, x, v, z):
    s0, s1, Fs, Fc, Vs, Fv = p[0], p[1], p[2], p[3], p[4], p[5]
    u = v / Vs
    e = math.exp(-u * u)
    g = (Fc + (Fs - Fc) * e) / s0
    dg = (Fs - Fc) * e * (-2.0 * u / Vs) / s0
    av = abs(v)
    sg = 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)
    zd = v - av * z / g
    dzd_dv = 1.0 - z * (sg / g - av * dg / (g * g))
    dzd_dz = -av / g
    F = s0 * z + s1 * zd + Fv * v
    return (F, zd, 0.0, s1 * dzd_dv + Fv, s0 + s1 * dzd_dz, 0.0, dzd_dv, dzd_dz)


@FRICTION_MODELS.register
class LuGre(BristleModel):
    key = "lugre"
    title = "LuGre bristle friction with Stribeck effect"
    source = "(2.3)-(2.5)"
    n_state = 1
    params = ParamSet([
        positive_param("sigma0", TABLE_2_1["sigma0_x"], "N/m", "bristle stiffness sigma_0", "(2.4), (2.5); Table 2.1",
                       hi=1e9),
        Param("sigma1", 0.0, "N s/m", "bristle damping sigma_1", lo=0.0, hi=1.0, source="(2.5)"),
        positive_param("F_s", TABLE_2_1["F_s_x"], "N", "static friction", "(2.4); Table 2.1", hi=1e-3),
        positive_param("F_c", TABLE_2_1["F_c_x"], "N", "kinetic (Coulomb) friction", "(2.4); Table 2.1", hi=1e-3),
        positive_param("V_s", TABLE_2_1["V_s"], "m/s", "Stribeck velocity", "(2.4); Table 2.1", hi=1e3),
        Param("F_v", TABLE_2_1["F_v_x"], "N s/m", "viscous friction coefficient (departure 10: N s/m)", lo=0.0,
              hi=1.0, source="(2.5); Table 2.1"),
    ])
    packed = ("sigma0", "sigma1", "F_s", "F_c", "V_s", "F_v")
    load_params = ("F_s", "F_c")
    kernel = staticmethod(lugre_kernel)

    def steady_force(self, v):
        v = np.asarray(v, float)
        p = self.values
        return np.sign(v) * (p["F_c"] + (p["F_s"] - p["F_c"]) * np.exp(-(v / p["V_s"]) ** 2)) + p["F_v"] * v
