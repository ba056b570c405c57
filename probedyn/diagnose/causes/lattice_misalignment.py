"""The scan runs at an angle to the lattice rows: a two-dimensional (zigzag) stick-slip."""

from __future__ import annotations

import math

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class LatticeMisalignment(Cause):
    key = "lattice-misalignment"
    kind = "friction"
    title = "2D zigzag from a scan misaligned with the lattice"
    source = ("separable square lattice -U0 [cos(2 pi x/a) + cos(2 pi y/a)] with an isotropic lever: x and y decouple "
              "into two FFM line scans at V cos(theta), V sin(theta); source 2.1.4.1 (Fig 2.7), 4.1.1")
    description = ("The tip sticks and slips along x and y alternately; the measured force along the scan is "
                   "cos(theta) F_x + sin(theta) F_y with periods a/cos(theta) and a/sin(theta).")
    needs = "a scan with several lattice periods"
    changes = ("lattice",)
    params = (CauseParam("theta_deg", "deg", 0.0, 45.0, 0.0, "scan angle to the lattice rows", starts=(8.0, 20.0, 35.0)),)

    def effect(self, v, s):
        s.theta += math.radians(v["theta_deg"])
