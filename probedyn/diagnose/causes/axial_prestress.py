"""A uniform axial prestress of the lever (geometric stiffness)."""

from __future__ import annotations

import math

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class AxialPrestress(Cause):
    key = "axial-prestress"
    kind = "modal"
    title = "Axial prestress (geometric stiffness)"
    source = ("K_G = sigma int (d_x u).(d_x v) dV (second-order work of a uniaxial stress); beam limit "
              "EI w'''' - P w'' = rho A omega^2 w")
    description = ("A uniform axial stress sigma (tension > 0; e.g. a tip held against a surface, a thermally "
                   "strained mount) adds the geometric stiffness: raises the low bending modes most.")
    needs = "two or more bending modes"
    changes = ("stress",)
    params = (CauseParam("sigma", "Pa", -1.0, 1.0, 0.0, "axial stress (bounds from the buckling stress)"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        b = problem.reference_baseline
        # Euler buckling of a clamped-free column: sigma_cr = pi^2 E t^2 / (48 L^2)
        s_cr = math.pi**2 * b.E_ref * b.t**2 / (48.0 * b.L**2)
        return AxialPrestress((CauseParam("sigma", "Pa", -0.9 * s_cr, 30.0 * s_cr, 0.0,
                                          "axial stress (compression down to 0.9 of the buckling stress)"),))

    def effect(self, v, s):
        s.axial_stress += v["sigma"]

    def derived(self, v, problem):
        b = problem.reference_baseline
        return {"axial_force_N": v["sigma"] * b.w * b.t}
