"""Offset and linear drift of the lateral-force signal (photodiode zero, thermal drift)."""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ForceOffsetDrift(Cause):
    key = "force-offset-drift"
    kind = "friction"
    title = "Lateral-force offset and drift"
    source = "measurement chain: F_meas = F + o + d (t - t_mid) / T_ref (one rate d / T_ref for every scan)"
    description = ("A constant offset and a drift of the lateral-force signal linear in time (one rate: a faster scan drifts "
                   "less; on one clock through the record the scans' zeros differ by the drift between them): trace "
                   "and retrace no longer symmetric about zero.")
    needs = "trace and retrace"
    changes = ("detector",)
    #: stick-slip records and friction loops alike: an image line's lateral channel drifts as a line scan's does
    regimes = ("stick-slip", "loop")
    params = (CauseParam("offset", "N", -1.0, 1.0, 0.0, "offset"), CauseParam("drift", "N", -1.0, 1.0, 0.0, "drift over the longest scan"))

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        if any(p.name == "offset" for p in getattr(problem, "base_params", ())):
            # a friction loop's baseline carries the channel's zero already (friction_loop): the drift alone,
            # bounded by five times the record's span. Only on one clock through the record: within a line
            # (trace, then retrace) a drift is a friction changing linearly along the line -- as a friction
            # contrast or a slope can be -- and only the lines' zeros differing by the drift between them
            # separate it (own loop truth 7018, no time column: a drift of half the friction imitated the
            # blend's friction contrast as the second finding)
            if getattr(problem, "drift_clock", "record") != "record":
                return None
            F = 5.0 * max(float(np.ptp(problem.force)), 10.0 * problem.sigma)
            return ForceOffsetDrift((CauseParam("drift", "N", -F, F, 0.0, "drift over the longest scan"),),
                                    note="friction loop: the baseline's offset is the channel's zero; the drift alone")
        F = 5.0 * problem.data.k_x * problem.a_est
        return ForceOffsetDrift((CauseParam("offset", "N", -F, F, 0.0, "offset"),
                                 CauseParam("drift", "N", -F, F, 0.0, "drift over the longest scan")))

    def effect(self, v, s):
        if any(p.name == "offset" for p in self.params):
            s.offset += v["offset"]
        s.drift += v["drift"]

    def derived(self, v, problem):
        t = getattr(problem, "t_ref", 0.0)
        return {"drift_rate_N_per_s": v["drift"] / t} if t > 0 else {}
