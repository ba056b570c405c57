"""The piezo's position on the retract differs from the recorded one (hysteresis or creep of the scanner).

A piezo scanner driven open-loop (or read by its drive signal rather than a position sensor) does not
return along the same path: at the same recorded z the tip is displaced by ``dz`` on the retract
relative to the approach (hysteresis of the ceramic, creep during the ramp's turn). In contact this
shifts the retract's force by the contact branch's slope times ``dz``; out of contact it changes
nothing, which separates it from a drift of the deflection in time (``deflection-drift``: a force offset
everywhere) and from the baseline tilt (linear in z on both segments). One constant offset over the
retract (the first-order model of the loop near the turning point, where the contact is).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class PiezoHysteresis(Cause):
    key = "piezo-hysteresis"
    kind = "force"
    title = "Piezo hysteresis / creep: the retract's true piezo position offset from the recorded one"
    source = "measurement chain: z_true = z_recorded + dz on the retract (open-loop scanner hysteresis, creep)"
    description = ("Approach and retract contact branches displaced along z by a constant dz at the same recorded "
                   "piezo position, with identical non-contact baselines.")
    needs = "approach and retract in contact (the branch's slope turns dz into force)"
    changes = ("scanner",)
    params = (CauseParam("dz", "m", -1e-6, 1e-6, 0.0, "retract piezo offset"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        h = 0.1 * problem.span  # at most a tenth of the ramp
        return PiezoHysteresis((CauseParam("dz", "m", -h, h, 0.0, "retract piezo offset",
                                           starts=(-0.01 * problem.span, 0.01 * problem.span)),))

    def effect(self, v, s):
        s.z_shift += v["dz"]
