"""Offset and linear drift of the lateral-force signal (photodiode zero, thermal drift)."""

from __future__ import annotations

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
    params = (CauseParam("offset", "N", -1.0, 1.0, 0.0, "offset"), CauseParam("drift", "N", -1.0, 1.0, 0.0, "drift over the longest scan"))

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        F = 5.0 * problem.data.k_x * problem.a_est
        return ForceOffsetDrift((CauseParam("offset", "N", -F, F, 0.0, "offset"),
                                 CauseParam("drift", "N", -F, F, 0.0, "drift over the longest scan")))

    def effect(self, v, s):
        s.offset += v["offset"]
        s.drift += v["drift"]

    def derived(self, v, problem):
        t = getattr(problem, "t_ref", 0.0)
        return {"drift_rate_N_per_s": v["drift"] / t} if t > 0 else {}
