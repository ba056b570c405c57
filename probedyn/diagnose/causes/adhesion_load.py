"""Friction proportional to the total load N + N_adh (adhesion or a capillary meniscus)."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class AdhesionLoad(Cause):
    key = "adhesion-load"
    kind = "friction"
    title = "Load dependence through adhesion (or a capillary meniscus)"
    source = "Derjaguin's law, section 2.2.4 (adhesion-friction coupling); registry load_params (U0 ~ load)"
    description = "The corrugation follows the total load N + N_adh instead of N: friction is finite at zero load."
    needs = "scans at two or more normal loads"
    changes = ("adhesion",)
    params = (CauseParam("n_adh", "N", -1.0, 1.0, 0.0, "adhesion load"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        lo, hi = float(problem.loads.min()), float(problem.loads.max())
        return AdhesionLoad((CauseParam("n_adh", "N", -0.9 * lo, 20.0 * hi, 0.0, "adhesion load",
                                        starts=(0.5 * hi, 3.0 * hi)),))

    def effect(self, v, s):
        s.n_adh += v["n_adh"]
