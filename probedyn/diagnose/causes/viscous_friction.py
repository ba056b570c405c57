"""A viscous friction term (the registry PT model's gamma: F = F0 sin(2 pi x / a) + gamma x')."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

#: the claimed coefficient's profile sweep (``CauseParam.sweep_relative``: steps of this fraction of its value). With a
#: declared temperature's activation in the baseline the misfit is rugged along gamma: more viscous drag trades against
#: fewer activated slips (a lower attempt frequency), and the local fit stops in the first basin (blind g02, 10 K:
#: gamma 2.0e-5 with -2 ln L 3490, where the profile falls step by step to 2782 at the generator's 3.0e-5;
#: docs/diagnose.md 9.60)
SWEEP_FRACTION = 0.1


@CAUSES.register
class ViscousFriction(Cause):
    key = "viscous-friction"
    kind = "friction"
    title = "Viscous friction term"
    source = "friction registry 'pt' parameter gamma (F = F0 sin + gamma v); source eqs 2.7, 2.10 (F_nu v)"
    description = "A friction force proportional to the sliding speed: the friction loop widens linearly with speed."
    needs = "scans at two or more speeds"
    changes = ()
    params = (CauseParam("gamma", "N s/m", 0.0, 1.0, 0.0, "viscous coefficient (bounds: 10 x the lever force at the fastest speed)",
                         sweep=SWEEP_FRACTION, sweep_claimed=True, sweep_relative=True),)

    def constrain(self, problem):
        g_hi = 10.0 * problem.data.k_x * problem.a_est / problem.v_max
        # the catalog's parameter (its unit, null and sweep) with the record's bound and starts
        return ViscousFriction((replace(self.params[0], hi=g_hi, doc="viscous coefficient",
                                        starts=(1e-3 * g_hi, 1e-2 * g_hi)),))

    def data_starts(self, problem, ref: dict) -> list[dict]:
        """From the recorded loop: the peak force of scans at one load and different speeds grows by
        gamma (V2 - V1)."""
        L = problem.loop
        out = []
        for i in range(len(L.peak)):
            for j in range(len(L.peak)):
                if problem.loads[i] == problem.loads[j] and problem.speeds[j] > problem.speeds[i]:
                    g = (L.peak[j] - L.peak[i]) / (problem.speeds[j] - problem.speeds[i])
                    if g > 0:
                        out.append(g)
        return [{"gamma": float(np.median(out))}] if out else []

    def effect(self, v, s):
        s.gamma += v["gamma"]

    def derived(self, v, problem):
        return {"force_at_fastest_speed_N": v["gamma"] * problem.v_max}
