"""The lateral-force calibration (torsional stiffness x sensitivity) is off by a factor."""

from __future__ import annotations

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

    def effect(self, v, s):
        s.gain *= v["g"]
