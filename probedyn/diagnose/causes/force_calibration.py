"""The lateral-force calibration (torsional stiffness x sensitivity) is off by a factor."""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ForceCalibration(Cause):
    key = "force-calibration"
    kind = "friction"
    title = "Lateral-force calibration factor"
    source = "measurement chain: F_meas = g F (lateral sensitivity and torsional stiffness of the lever)"
    description = ("The recorded force is g times the true one: the stick slope is g k_x instead of the declared "
                   "k_x, while the slip amplitude and period keep the lattice's.")
    needs = "stick-slip with resolved stick branches"
    changes = ("detector",)
    params = (CauseParam("g", "1", 0.2, 5.0, 1.0, "measured / true lateral force", starts=(0.7, 1.4)),)

    def data_starts(self, problem, ref: dict) -> list[dict]:
        """From the recorded loop: a factor g scales the peak force and the slip drop alike, so their
        ratio gives eta (the corrugation in units of k a^2) and then the peak gives g (quasi-static PT,
        :func:`probedyn.diagnose.friction.loop_estimate`); the corrugation per unit load goes with it
        (the baseline's has absorbed the factor)."""
        L = problem.loop
        st = {"g": float(np.median(L.g))}
        if "n_adh" not in ref and "load_share" not in ref:
            Neff = problem.effective_loads() if hasattr(problem, "effective_loads") else problem.loads
            st["u0"] = float(np.median(L.U0 / np.maximum(Neff, 1e-30)))
        return [st]

    def effect(self, v, s):
        s.gain *= v["g"]
