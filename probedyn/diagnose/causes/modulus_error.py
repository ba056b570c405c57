"""The material's elastic constants differ from the declared ones (all scaled alike)."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ModulusError(Cause):
    key = "modulus-error"
    kind = "modal"
    title = "Elastic modulus differs from nominal (or density: only E/rho is seen)"
    source = "C -> ratio C in every region: every frequency ~ sqrt(ratio)"
    description = ("All elastic constants scaled by one ratio (alloy, doping, porosity, temperature; an error of "
                   "the density shows the same way): every mode scales by sqrt(ratio).")
    needs = "modes of two families, or a declared geometry (a uniform scale is also a thickness/length pattern)"
    changes = ("modulus",)
    params = (CauseParam("e_ratio", "1", 0.4, 2.5, 1.0, "E / E_nominal"),)  # monotone: the null start suffices

    def effect(self, v, s):
        s.E_factor *= v["e_ratio"]
