"""The tip radius differs from the declared one (a blunted or contaminated tip)."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class TipRadiusError(Cause):
    key = "tip-radius-error"
    kind = "force"
    title = "Tip radius differs from nominal"
    source = "Hertz P ~ E* R^1/2 delta^3/2; pull-off ~ W R (contact registry)"
    description = ("The actual radius R = ratio R_nom: the contact stiffens as sqrt(R) -- separable from the sample "
                   "modulus only when the modulus is declared, or through the adhesion (pull-off ~ W R).")
    needs = "a declared sample modulus ([sample] E), or adhesion"
    changes = ("tip_radius",)
    params = (CauseParam("r_ratio", "1", 0.1, 10.0, 1.0, "R / R_nominal", scale="log", starts=(0.5, 2.0)),)

    def effect(self, v, s):
        s.R *= v["r_ratio"]

    def derived(self, v, problem):
        return {"tip_radius_m": v["r_ratio"] * problem.data.tip_radius}
