"""Scanner creep / nonlinearity: the real support position bows away from the nominal one."""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ScannerNonlinearity(Cause):
    key = "scanner-nonlinearity"
    kind = "friction"
    title = "Scanner nonlinearity / creep"
    source = "quadratic piezo nonlinearity, exact at the calibrated ends: X = X_nom + c (X - X0)(X1 - X)/(X1 - X0)"
    description = "The stick-slip period drifts along the scan (the support moves faster in the middle than the nominal calibration says)."
    needs = "a scan with several lattice periods"
    changes = ("scanner",)
    params = (CauseParam("bow", "1", -0.4, 0.4, 0.0, "bow coefficient c (largest error c L / 4 mid-scan)", starts=(-0.1, 0.1)),)

    def effect(self, v, s):
        s.bow += v["bow"]
