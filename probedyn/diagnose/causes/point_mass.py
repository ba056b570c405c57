"""An added point mass at an unknown position along the beam (tip, particle, sensor, glue)."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class PointMass(Cause):
    key = "point-mass"
    kind = "modal"
    title = "Added point mass at an unknown position"
    source = "FEM point mass m A(x)^T A(x) (fem/model.py PointMass); eq 3.10 (corrected, SOURCE-NOTES 1) for x = L"
    description = ("A concentrated mass m at x = xi L on the line through the clamp-face centroid parallel to the "
                   "beam axis; lowers each mode by its modal displacement at xi squared.")
    needs = "two or more bending modes to locate it (one mode: mass and position are degenerate)"
    changes = ("mass",)
    params = (
        CauseParam("mass", "kg", 0.0, 1.0, 0.0, "added mass (bounds: 0 to 3 probe masses)"),
        CauseParam("xi", "1 (x / L)", 0.0, 1.0, 1.0, "position along the beam from the clamp",
                   starts=(0.75, 0.5)),
    )

    def constrain(self, problem):
        if super().constrain(problem) is None or not problem.supports("mass"):
            return None
        m = problem.probe_mass
        return PointMass((CauseParam("mass", "kg", 0.0, 3.0 * m, 0.0, "added mass (0 to 3 probe masses)",
                                     starts=(0.03 * m, 0.3 * m)), self.params[1]))

    def start_sets(self):
        m = self.params[0].hi / 3.0  # the probe mass
        return [{"mass": 0.03 * m, "xi": 1.0}, {"mass": 0.03 * m, "xi": 0.6}, {"mass": 0.3 * m, "xi": 1.0},
                {"mass": 0.3 * m, "xi": 0.6}, {"mass": 0.03 * m, "xi": 0.3}]

    def effect(self, v, s):
        s.masses = [*s.masses, (v["xi"], v["mass"])]

    def derived(self, v, problem):
        return {"mass_kg": v["mass"], "mass_ratio": v["mass"] / problem.probe_mass,
                "position_m": v["xi"] * problem.reference_baseline.L}
