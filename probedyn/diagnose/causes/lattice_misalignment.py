"""The scan runs at an angle to the lattice rows: a two-dimensional (zigzag) stick-slip.

Starts. A scan at an angle theta to the rows of a lattice of period a crosses the rows along x
every a / cos(theta) of support travel: the baseline (theta = 0) fits that spacing with its own
period, ``a_ref = a / cos(theta)``, and the stick-slip shape (eta = 4 pi^2 U0 / (k a^2)) with its
corrugation. Every start of a misaligned model therefore keeps the x train where the baseline put
it, ``a = a_ref cos(theta)`` and ``u0 = u0_ref cos^2(theta)`` (same eta), and adds the y train;
started at the baseline's period instead, the x slips of a 10 degree start drift by 1.5 % of a
period per period and the fit stalls in another basin. The data-derived start reads the angle from
the same relation with the sample's declared lattice constant: ``cos(theta) = a_lattice / a_ref``.
"""

from __future__ import annotations

import math

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

#: declared start angles [deg] (the data-derived one is added by data_starts)
THETA_STARTS = (8.0, 20.0, 35.0)


def _aligned(ref: dict, theta_deg: float) -> dict:
    """A start at angle theta that keeps the baseline's x train (period along the scan and eta)."""
    c = math.cos(math.radians(theta_deg))
    out = {"theta_deg": float(theta_deg)}
    if "a" in ref:
        out["a"] = float(ref["a"]) * c
    if "u0" in ref:
        out["u0"] = float(ref["u0"]) * c * c
    return out


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
    params = (CauseParam("theta_deg", "deg", 0.0, 45.0, 0.0, "scan angle to the lattice rows", starts=THETA_STARTS),)

    def start_sets_from(self, ref: dict[str, float]) -> list[dict[str, float]]:
        """The declared angles, each with the baseline's x train kept (module docstring)."""
        return [_aligned(ref, t) for t in THETA_STARTS]

    def data_starts(self, problem, ref: dict) -> list[dict]:
        """The angle from the slip period along the scan (the fitted period of the model it
        extends) and the sample's declared lattice constant: ``cos(theta) = a_lattice / a_ref``
        (only where the period along the scan is the longer one: a shorter period is a scanner
        calibration, not an angle)."""
        a_ref = float(ref.get("a", getattr(problem, "a_slip", 0.0)))
        lat = float(getattr(problem.data, "lattice", 0.0) or 0.0)
        if not (a_ref > lat > 0):
            return []
        th = math.degrees(math.acos(lat / a_ref))
        lo, hi = self.params[0].lo, self.params[0].hi
        if not lo < th <= hi:
            return []
        return [_aligned(ref, th)]

    def effect(self, v, s):
        s.theta += math.radians(v["theta_deg"])
