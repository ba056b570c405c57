"""Topographic crosstalk in a friction loop: the load's component along a sloped surface.

On a surface of local slope ``t = tan theta = dh/dx`` the vertical load ``L`` the feedback holds has a
component along the surface, and the friction acts along the incline: the force balance of the tip
(load, adhesion ``A`` along the surface normal, the contact's repulsion and its friction ``mu`` times
that repulsion) gives the horizontal force ``F = [L t + d mu (L + A / cos theta)] / (1 - d mu t)`` in
scan direction ``d`` (Ogletree, Carpick & Salmeron 1996, Rev. Sci. Instrum. 67, 3298, eqs 2-3, the basis
of the wedge calibration). Trace and retrace differ by about ``2 mu (L + A)`` (the friction) and their
mean follows the slope, ``~ L t`` -- the adhesion cancels from it (the normal adhesion is balanced by
part of the repulsion): the loop's offset images dh/dx with the load alone. Fitted as a coupling ``c``
of the slope the instrument recorded (``height_m``) in ``F = (c N t + d F_k) / (1 - d (F_k / N) c t)``
(nested: ``c = 0`` is the flat-surface loop ``d F_k``), whose loop mean is ``c N t (1 + mu_a^2)`` to first
order in t, ``mu_a = F_k / N`` the apparent friction coefficient. The truth's loop mean is
``g L t (1 + mu^2 (1 + A / L))`` with ``g`` the factor by which the declared lateral calibration is off and
``g mu (L + A) = F_k``: without adhesion ``g + mu_a^2 / g = c (1 + mu_a^2)``, whose root near ``c`` is the
**calibration factor** reported (``c = g`` when ``g = 1``). With an adhesion load ``A`` fitted as well
(the adhesion-load cause, scans at two or more loads: the half loop's intercept is ``g mu A``) the model's
loop mean is ``c N t (1 + Y)`` with ``Y = F_k^2 / (N (N + A))`` and the truth's ``g N t (1 + Y / g^2)``:
``g`` is the root near ``c`` of ``g^2 - c (1 + Y) g + Y = 0`` (``Y = mu_a^2`` without adhesion; ignoring
an adhesion that is there biases ``g`` by about ``-mu_a^2 A / ((L + A) (g - mu_a^2 / g))``).
The friction coefficient is then ``F_k / (g (N + A))``.
Applies to mesoscale loops (``regimes = ("loop",)``).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class SurfaceSlope(Cause):
    key = "surface-slope"
    kind = "friction"
    regimes = ("loop",)
    title = "Topographic crosstalk: the load's component along the sloped surface in the lateral force"
    source = ("Ogletree, Carpick & Salmeron (1996) Rev. Sci. Instrum. 67, 3298, eqs 2-3: "
              "F = N (c t + d mu) / (1 - d mu c t), t = dh/dx the recorded slope, d the scan direction")
    description = ("The mean of trace and retrace follows the surface slope (the loop's offset images dh/dx); "
                   "c = 1 with a correct lateral calibration, c = g (the calibration's error factor) otherwise.")
    needs = "a height_m column (the topography recorded with the lateral force) on a mesoscale loop"
    requires = "a height_m column (the topography the instrument recorded with the lateral force)"
    changes = ("topography",)
    params = (CauseParam("c_slope", "1", 0.0, 5.0, 0.0, "slope coupling (1: the load's full component)",
                         starts=(1.0,)),)

    def constrain(self, problem):
        if getattr(problem, "slopes", None) is None or not np.ptp(problem.slopes) > 0:
            return None
        return super().constrain(problem)

    def data_starts(self, problem, ref_values, ref_causes=()):
        """The coupling the reference fit's residual shows: its least-squares regression on ``N t``
        (the first-order slope term)."""
        return problem.residual_start("c_slope", problem.load_of * problem.slopes, ref_values, ref_causes)

    def effect(self, v, s):
        s.slope_c = v["c_slope"]

    def derived(self, v, problem):
        c = v["c_slope"]
        A = float(v.get("n_adh", 0.0))  # the adhesion load, where the adhesion-load cause is in the model
        fk = abs(getattr(problem, "half_loop", 0.0))
        N = float(np.mean(problem.loads))
        out = {}
        if c > 0 and N > 0 and N + A > 0:
            g = calibration_factor(c, fk / math.sqrt(N * (N + A)))
            out["lateral_calibration_factor"] = g
            out["friction_coefficient" if "n_adh" in v else "friction_coefficient_if_no_adhesion"] = fk / (g * (N + A))
            out["friction_N_calibrated"] = fk / g
        return out


def calibration_factor(c: float, mu_a: float) -> float:
    """The lateral calibration factor ``g`` from the fitted coupling ``c`` and the apparent friction
    coefficient ``mu_a = F_k / N`` (no adhesion; with an adhesion load ``A``, ``mu_a = F_k / sqrt(N (N + A))``):
    the root near ``c`` of ``g^2 - c (1 + mu_a^2) g + mu_a^2 = 0``
    (the larger root; ``c (1 + mu_a^2)`` where the discriminant is negative, i.e. ``c < 2 mu_a / (1 + mu_a^2)``)."""
    b = c * (1.0 + mu_a**2)
    disc = b * b - 4.0 * mu_a**2
    return 0.5 * (b + math.sqrt(disc)) if disc >= 0 else 0.5 * b
