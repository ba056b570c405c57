"""Friction contrast between the phases of a heterogeneous surface, marked by its relief.

A blend, a patterned film or a contaminated surface has regions of different friction coefficient, and
in the usual case the regions also differ in height (the islands of one polymer stand above or sink below
the matrix of the other: the SBS/PMMA blend of ``examples/measurements/friction_loops_sbs_pmma``, where
the half loop falls where the surface rises, correlation -0.55 to -0.78 over its four lines). The
lateral-force image then shows the contrast in the **half loop** (trace minus retrace over 2) at the
positions of the relief, whereas the slope term of :mod:`.surface_slope` shows in the loop's **mean**: the
two are separated by the scan directions, not by a fit alone.

Model: the friction of every sample is ``F_k (1 + beta zeta(x))``, ``zeta`` the relief (the recorded mean
surface low-passed above its noise, each line's tilt removed) from its 2nd to its 98th percentile over
all lines as 0 .. 1: ``F_k`` is the friction of the lowest parts, ``(1 + beta) F_k`` that of the highest,
linear in between -- exact for two phases at two levels (islands on a matrix) and for any surface whose
friction changes linearly with its height. Nested: ``beta = 0`` is the uniform-friction loop. The same
contrast enters the slope law's friction term (:func:`probedyn.diagnose.friction_loop.slope_force`).
Assumptions: the phases differ in height (a contrast between regions at one level is invisible to it:
then the lateral image alone, not the topography, marks them), the load is the same on both phases
(adhesion differences act as a friction contrast here), one contrast for every line of the record.
Offered when the record has heights whose relief exceeds the surface's noise 8 times (``RELIEF_SNR``).
Applies to mesoscale loops (``regimes = ("loop",)``).
"""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class FrictionContrast(Cause):
    key = "friction-contrast"
    kind = "friction"
    regimes = ("loop",)
    title = "Friction contrast between surface phases that differ in height (a blend's islands and matrix)"
    source = ("friction F_k (1 + beta zeta(x)), zeta the recorded relief from its 2nd to its 98th percentile "
              "as 0 .. 1; phase contrast in lateral-force images: Overney et al. (1992) Nature 359, 133")
    description = ("The half loop (trace minus retrace) changes with the relief: the surface's phases have "
                   "different friction coefficients; beta is the highest parts' friction over the lowest's, minus 1.")
    needs = "a height_m column with relief above the height noise (islands, domains) on a mesoscale loop"
    requires = "a height_m column whose relief exceeds its noise (the phases' heights mark where each is)"
    changes = ("friction",)
    params = (CauseParam("contrast", "1", -0.95, 10.0, 0.0,
                         "friction of the highest parts over that of the lowest, minus 1", starts=(-0.5, 1.0)),)

    def constrain(self, problem):
        if getattr(problem, "relief", None) is None:
            return None
        return super().constrain(problem)

    def data_starts(self, problem, ref_values, ref_causes=()):
        """The contrast the reference fit's residual shows: its least-squares regression on
        ``d F_k zeta`` (the first-order change of the half loop)."""
        x = problem.direction * problem.friction_of(ref_values) * problem.relief
        return problem.residual_start("contrast", x, ref_values, ref_causes)

    def effect(self, v, s):
        s.contrast = v["contrast"]

    def derived(self, v, problem):
        b = v["contrast"]
        fk = abs(getattr(problem, "half_loop", 0.0))
        out = {"friction_ratio_high_to_low": 1.0 + b, "relief_range_m": float(problem.relief_range)}
        mean_z = float(np.mean(problem.relief))
        if fk > 0:  # the half loop is the friction at the record's mean relief
            low = fk / (1.0 + b * mean_z)
            out.update(friction_low_parts_N=low, friction_high_parts_N=low * (1.0 + b))
        return out
