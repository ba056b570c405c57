"""Offset and linear drift of the lateral-force signal (photodiode zero, thermal drift)."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ForceOffsetDrift(Cause):
    key = "force-offset-drift"
    kind = "friction"
    title = "Lateral-force offset and drift"
    source = "measurement chain: F_meas = F + o + d (t - t_mid) / T_scan"
    description = "A constant offset and a linear drift in time of the lateral-force signal: trace and retrace no longer symmetric about zero."
    needs = "trace and retrace"
    changes = ("detector",)
    params = (CauseParam("offset", "N", -1.0, 1.0, 0.0, "offset"), CauseParam("drift", "N", -1.0, 1.0, 0.0, "drift over one scan"))

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        F = 5.0 * problem.data.k_x * problem.a_est
        return ForceOffsetDrift((CauseParam("offset", "N", -F, F, 0.0, "offset"),
                                 CauseParam("drift", "N", -F, F, 0.0, "drift over one scan")))

    def effect(self, v, s):
        s.offset += v["offset"]
        s.drift += v["drift"]
