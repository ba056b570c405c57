"""Drift of the deflection signal in time during a force curve (thermal drift of the optical lever)."""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class DeflectionDrift(Cause):
    key = "deflection-drift"
    kind = "force"
    title = "Deflection drift in time (force-curve baseline)"
    source = "measurement chain: F_meas = F + b0 + b1 z + d (t - t_mid) / T (T: the recording's duration)"
    description = ("A linear drift in time of the deflection signal. A tilt of the baseline is linear in the piezo "
                   "position z and is calibrated by the baseline; a drift is linear in time, so it shifts approach "
                   "and retract in opposite senses relative to z (the baseline hysteresis far from the sample).")
    needs = "approach and retract far from the sample (their baselines differ by the drift)"
    changes = ("detector",)
    params = (CauseParam("drift", "N", -1.0, 1.0, 0.0, "force drift over the recording"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        Fs = float(max(problem.data.force.max() - problem.data.force.min(), 10 * problem.sigma))
        return DeflectionDrift((CauseParam("drift", "N", -Fs, Fs, 0.0, "force drift over the recording"),))

    def effect(self, v, s):
        s.drift += v["drift"]

    def derived(self, v, problem):
        return {"drift_N_per_s": v["drift"] / float(np.ptp(problem.data.time))} if problem.data.time is not None else {}
