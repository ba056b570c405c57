"""The source's generalised-bristle nano-friction model, eqs (2.7)–(2.12).

As printed::

    F_x   = sigma_0x z_x + F_vx(a) V_x                                            (2.7)
    z_x'  = max(V_i)_{i=x,y} - z_x ||V||_inf / g_x                                 (2.8)
    g_x   = [F_cx(a) + (F_sx(a) - F_cx(a)) exp(-((V_x + V_y) / 2 V_s)^2)] / sigma_0x (2.9)

and the same for y (2.10)–(2.12). How the print is read here:

* ``V = (V_x, V_y)`` is the **sliding velocity of the tip relative to the sample** (the text
  calls it "the scan velocity"; in the FFM model the tip is the only moving body, so it is the
  tip velocity ``(x', y')``, not the base speed). With the base velocity instead, the force
  would not depend on the tip's motion and no slip could occur.
* ``max(V_i)`` is read literally: the larger *signed* component (``vmax="literal"``,
  default). Consequence, stated in docs/friction.md: in 1D (V_y = 0) ``z' = max(V,0) - |V| z/g``,
  so for V < 0 the deflection only relaxes towards 0 — a backward scan has no friction
  plateau. ``vmax="magnitude"`` uses the component of largest magnitude with its sign; in 1D
  it is exactly the LuGre state equation (2.3) with the Stribeck argument V/(2 V_s), and it is
  odd under scan reversal.
* ``F_s(a)``, ``F_c(a)``, ``F_v(a)``: the lattice (jumping mechanism, 2.6) enters only through
  the values of the friction levels; they are constants for a given sample.
* There is no bristle damping ``sigma_1`` in (2.7) (unlike LuGre 2.5).
* F_c > F_s is rejected: the text defines F_s and F_c as the highest and the lowest values of
  the periodic friction curve.

This module provides the 1D reduction (V_y = 0) as the registry model ``bristle`` (numba
kernel, used by the FFM line scan) and the full 2D right-hand side with its analytic Jacobian
(:func:`bristle2d_eval`) used by the full FFM model (2.13)–(2.16).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from probedyn.core.errors import ParameterError
from probedyn.core.params import Param, ParamSet

from .base import FRICTION_MODELS, TABLE_2_1, BristleModel, positive_param


@njit(cache=True)
def bristle_kernel(p, x, v, z):
    """1D reduction (V_y = 0) of (2.7)-(2.9). p = (sigma0, F_s, F_c, V_s, F_v, literal)."""
    s0, Fs, Fc, Vs, Fv, literal = p[0], p[1], p[2], p[3], p[4], p[5]
    u = v / (2.0 * Vs)
    e = math.exp(-u * u)
    g = (Fc + (Fs - Fc) * e) / s0
    dg = -(Fs - Fc) * e * u / (Vs * s0)
    av = abs(v)
    sg = 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)
    if literal > 0.5:
        drive = v if v > 0 else 0.0
        ddrive = 1.0 if v > 0 else 0.0
    else:
        drive = v
        ddrive = 1.0
    zd = drive - av * z / g
    dzd_dv = ddrive - z * (sg / g - av * dg / (g * g))
    dzd_dz = -av / g
    return (s0 * z + Fv * v, zd, 0.0, Fv, s0, 0.0, dzd_dv, dzd_dz)


@FRICTION_MODELS.register
class GeneralisedBristle(BristleModel):
    key = "bristle"
    title = "generalised-bristle nano-friction model of the source (1D reduction, V_y = 0)"
    source = "(2.7)-(2.9) [(2.10)-(2.12) in 2D]"
    n_state = 1
    params = ParamSet([
        positive_param("sigma0", TABLE_2_1["sigma0_x"], "N/m", "bristle stiffness sigma_0x", "(2.7); Table 2.1",
                       hi=1e9),
        positive_param("F_s", TABLE_2_1["F_s_x"], "N", "static friction F_sx", "(2.9); Table 2.1", hi=1e-3),
        positive_param("F_c", TABLE_2_1["F_c_x"], "N", "kinetic friction F_cx", "(2.9); Table 2.1", hi=1e-3),
        positive_param("V_s", TABLE_2_1["V_s"], "m/s", "Stribeck velocity", "(2.9); Table 2.1", hi=1e3),
        Param("F_v", TABLE_2_1["F_v_x"], "N s/m", "viscous friction coefficient (departure 10: N s/m)", lo=0.0,
              hi=1.0, source="(2.7); Table 2.1"),
        Param("vmax", "literal", "", "reading of max(V_i) in (2.8): signed max or largest magnitude",
              kind=str, choices=("literal", "magnitude"), source="(2.8)"),
    ])
    packed = ("sigma0", "F_s", "F_c", "V_s", "F_v", "vmax")
    load_params = ("F_s", "F_c")
    kernel = staticmethod(bristle_kernel)

    def validate(self) -> None:
        if self.values["F_c"] > self.values["F_s"]:
            raise ParameterError(
                f"bristle model needs F_c <= F_s (kinetic <= static friction), got F_c = "
                f"{self.values['F_c']:g} N > F_s = {self.values['F_s']:g} N")

    def pack(self) -> np.ndarray:
        v = self.values
        return np.array([v["sigma0"], v["F_s"], v["F_c"], v["V_s"], v["F_v"],
                         1.0 if v["vmax"] == "literal" else 0.0])

    def steady_force(self, v):
        """Steady sliding (z' = 0) for V > 0: F = F_c + (F_s - F_c) exp(-(V/2V_s)^2) + F_v V."""
        v = np.asarray(v, float)
        p = self.values
        lvl = p["F_c"] + (p["F_s"] - p["F_c"]) * np.exp(-(v / (2 * p["V_s"])) ** 2)
        if p["vmax"] == "literal":
            return np.where(v > 0, lvl, 0.0) + p["F_v"] * v
        return np.sign(v) * lvl + p["F_v"] * v


@njit(cache=True)
def bristle2d_eval(p, vx, vy, zx, zy):
    """Full 2D model (2.7)-(2.12). p = (s0x, s0y, Fsx, Fsy, Fcx, Fcy, Vs, Fvx, Fvy, literal).

    Returns Fx, Fy, zx', zy' and the Jacobian J (4 x 4) of (Fx, Fy, zx', zy') with respect to
    (vx, vy, zx, zy). ||V||_inf = max(|vx|, |vy|); the Stribeck argument is (vx + vy)/(2 V_s).
    """
    s0x, s0y, Fsx, Fsy, Fcx, Fcy, Vs, Fvx, Fvy, literal = (p[0], p[1], p[2], p[3], p[4], p[5],
                                                           p[6], p[7], p[8], p[9])
    J = np.zeros((4, 4))
    u = (vx + vy) / (2.0 * Vs)
    e = math.exp(-u * u)
    du = 1.0 / (2.0 * Vs)  # du/dvx = du/dvy
    gx = (Fcx + (Fsx - Fcx) * e) / s0x
    gy = (Fcy + (Fsy - Fcy) * e) / s0y
    dgx = (Fsx - Fcx) * e * (-2.0 * u) * du / s0x
    dgy = (Fsy - Fcy) * e * (-2.0 * u) * du / s0y
    # drive = max(V_i)
    if literal > 0.5:
        if vx >= vy:
            drive, ddx, ddy = vx, 1.0, 0.0
        else:
            drive, ddx, ddy = vy, 0.0, 1.0
    else:
        if abs(vx) >= abs(vy):
            drive, ddx, ddy = vx, 1.0, 0.0
        else:
            drive, ddx, ddy = vy, 0.0, 1.0
    # infinity norm
    if abs(vx) >= abs(vy):
        ninf = abs(vx)
        dnx = 1.0 if vx > 0 else (-1.0 if vx < 0 else 0.0)
        dny = 0.0
    else:
        ninf = abs(vy)
        dnx = 0.0
        dny = 1.0 if vy > 0 else -1.0
    zxd = drive - zx * ninf / gx
    zyd = drive - zy * ninf / gy
    Fx = s0x * zx + Fvx * vx
    Fy = s0y * zy + Fvy * vy
    J[0, 0] = Fvx
    J[0, 2] = s0x
    J[1, 1] = Fvy
    J[1, 3] = s0y
    J[2, 0] = ddx - zx * (dnx / gx - ninf * dgx / (gx * gx))
    J[2, 1] = ddy - zx * (dny / gx - ninf * dgx / (gx * gx))
    J[2, 2] = -ninf / gx
    J[3, 0] = ddx - zy * (dnx / gy - ninf * dgy / (gy * gy))
    J[3, 1] = ddy - zy * (dny / gy - ninf * dgy / (gy * gy))
    J[3, 3] = -ninf / gy
    return Fx, Fy, zxd, zyd, J
