"""The scan runs at an angle to the lattice rows: a two-dimensional (zigzag) stick-slip.

The lever holds the tip with k_x along the scan and k_y = ky_ratio k_x across it. For k_y = k_x (the null of
ky_ratio) the lattice axes decouple into two 1D FFM scans ("trains") at V cos(theta) and V sin(theta); otherwise
the lever couples them and the tip moves in 2D (:mod:`probedyn.schemes.ffm_lattice2d`): on a lever much
stiffer across the scan the tip keeps to the scan line and slips in the potential along it, not in the zigzag.
A declared ``[lever] k_y`` fixes the ratio.

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
#: bounds of k_y / k_x: a rectangular lever scanned across its axis has ~0.65 (bending through the tip height
#: against torsion), one scanned along it the inverse; a soft contact or tip in series lowers both
KY_RATIO_BOUNDS = (0.1, 100.0)
#: start values of k_y / k_x besides the isotropic lever (1, the null): a lever stiffer across the scan
KY_STARTS = (10.0,)
#: the grid of (angle [deg], k_y / k_x) the problem ranks by the whole model's chi-square (:meth:`ridge_starts`):
#: on a lever stiffer across the scan the chi-square's basin is narrow in both (an own truth at 12 deg and 8:
#: chi^2 x 5 at 6 or 11, x 4 at 11 or 13 deg), and the isotropic starts do not reach it; 0.65 is the usual
#: scan across a rectangular lever's axis (:data:`KY_RATIO_BOUNDS`; own case 2012 at 0.66: angle 37 % off
#: without it, 0.5 % with it, docs/diagnose.md section 9.37)
RIDGE_THETAS = (8.0, 12.0, 17.0, 24.0, 33.0)
RIDGE_KY = (0.65, 3.0, 10.0)
#: the angle's profile sweep step [deg] (engine Fitter.swept), run once the cause is claimed (``sweep_claimed``:
#: every held point is a 2D scan fit of 1-5 s). On an anisotropic lever the free fit stalls on the (angle, k_y / k_x)
#: valley's wall: own 2005 (26.81 deg, k_y / k_x 3) stopped at 25.13 deg with chi^2 586 000, where the angle held at
#: 25.63, 26.13, 26.63 deg gives 467 000, 305 000, 167 000 (docs/diagnose.md 9.42-9.43)
SWEEP_DEG = 0.5
#: the stiffness ratio's sweep step [log10] (claimed only, after the angle's): the chi^2 is rugged at about 5 % in
#: k_y / k_x (a slip landing in another well across the scan). Own 2047 (20.12 deg, k_y / k_x 3.57): swept in the
#: angle alone the fit ends at 20.22 deg and 3.31 with chi^2 34 000 (a free fit from the truth reaches 4 000);
#: swept in both, 20.12 deg and 3.62 with chi^2 5 900 (docs/diagnose.md 9.43)
SWEEP_KY_DEX = 0.02


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
    source = ("separable square lattice -U0 [cos(2 pi x/a) + cos(2 pi y/a)]; the lever's springs k_x along the scan "
              "and k_y across it, as the source's 2D FFM model (2.13)-(2.14) with c_y = c_x (Table 2.1); for k_y = k_x "
              "x and y decouple into two FFM line scans at V cos(theta), V sin(theta); source 2.1.4.1 (Fig 2.7), 4.1.1")
    description = ("The tip sticks and slips along x and y alternately; the measured force along the scan is "
                   "cos(theta) F_x + sin(theta) F_y with periods a/cos(theta) and a/sin(theta).")
    needs = "a scan with several lattice periods"
    changes = ("lattice",)
    params = (CauseParam("theta_deg", "deg", 0.0, 45.0, 0.0, "scan angle to the lattice rows", starts=THETA_STARTS,
                         sweep=SWEEP_DEG, sweep_claimed=True),
              CauseParam("ky_ratio", "1", KY_RATIO_BOUNDS[0], KY_RATIO_BOUNDS[1], 1.0,
                         "the lever's lateral stiffness across the scan over k_x", scale="log", starts=KY_STARTS,
                         sweep=SWEEP_KY_DEX, sweep_claimed=True))

    def constrain(self, problem):
        """A declared ``[lever] k_y`` fixes the stiffness across the scan: only the angle is fitted."""
        base = super().constrain(problem)
        if base is None or not getattr(getattr(problem, "data", None), "k_y", None):
            return base
        return type(self)(params=self.params[:1], note="k_y as declared")

    def start_sets_from(self, ref: dict[str, float]) -> list[dict[str, float]]:
        """The declared angles on an isotropic lever, then the middle one on a lever stiffer across the scan,
        each with the baseline's x train kept (module docstring)."""
        out = [_aligned(ref, t) for t in THETA_STARTS]
        if self._free_ky():
            out += [{**_aligned(ref, THETA_STARTS[1]), "ky_ratio": r} for r in KY_STARTS]
        return out

    def _free_ky(self) -> bool:
        return any(p.name == "ky_ratio" for p in self.params)

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
        out = [_aligned(ref, th)]
        return out + ([{**out[0], "ky_ratio": r} for r in KY_STARTS] if self._free_ky() else [])

    def ridge_starts(self, problem, ref: dict) -> list[dict]:
        """A grid of angles (:data:`RIDGE_THETAS` and the data-derived one) and stiffness ratios across the scan
        (:data:`RIDGE_KY`), each keeping the baseline's x train, for the problem to rank by the whole model's
        chi-square; where ``k_y`` is declared, the angles alone (none on a declared isotropic lever: the declared
        starts reach the trains' basins)."""
        thetas = list(RIDGE_THETAS) + [st["theta_deg"] for st in self.data_starts(problem, ref)[:1]]
        if self._free_ky():
            return [{**_aligned(ref, t), "ky_ratio": r} for t in thetas for r in RIDGE_KY]
        data = getattr(problem, "data", None)
        if data is not None and getattr(data, "k_y", None) and data.k_y != data.k_x:
            return [_aligned(ref, t) for t in thetas]
        return []

    def effect(self, v, s):
        s.theta += math.radians(v["theta_deg"])
        if "ky_ratio" in v:
            s.ky_ratio = float(v["ky_ratio"])
