"""A lever bonded to its chip over an overlap: the bond under the overlap is compliant.

The lever does not end at a rigid wall: it continues behind the chip edge for a length ``L_o`` and is
held there by a thin bond (glue, an oxide, a clamped contact) with a normal stiffness ``k_n`` and a shear
stiffness ``k_t`` per unit area (:mod:`probedyn.diagnose.overlap`: the bonded segment as a beam on the
bond, tied to the clamp face of the 3D FEM). The normal bond holds flapwise bending and twist, the shear
bond lateral bending: a thin isotropic layer has ``k_t / k_n = (1 - 2 nu) / (2 (1 - nu))`` (0.29 at
nu = 0.3, 0.09 at 0.45), so lateral modes drop more than flapwise ones (1.4x the flapwise drop at nu = 0.3,
1.9x at 0.45, 3.2x at 0.49 on a 300 x 30 x 10 um lever), and every flapwise mode drops alike (a stiff bond acts as a clamp ``1/beta`` further back) -- where a support at the clamp
face (``clamp-compliance``) lowers flapwise mode 1 most and the lateral modes least.

Parameters: the bond lengths ``lam_n``, ``lam_t`` = ``1 / (beta L)`` with ``beta^4 = 3 k / (E t^3)``
(the Winkler length of the lever's flapwise section on the normal / shear bond over the free length; to
first order the flapwise modes drop by ``2 lam_n``), and the overlap ``L_o / L``, which matters only
when the bond is soft (``lam >~ L_o / (3 L)``). Both lengths at their lower bound: a rigid bond (the
baseline's rigid clamp at the chip edge).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam
from probedyn.diagnose.modal_model import LAMBDA_MIN


@CAUSES.register
class BondedOverlap(Cause):
    key = "bonded-overlap"
    kind = "modal"
    title = "Lever bonded to its chip over an overlap (compliant bond)"
    source = ("Euler-Bernoulli segment on a two-parameter bond (Hetenyi 1946, Beams on Elastic Foundation), "
              "tied to the FEM's clamp face; rigid bond = rigid clamp (eq 2.40)")
    description = ("The lever continues behind the chip edge on a compliant bond (normal and shear stiffness per "
                   "area): every flapwise mode drops alike, the lateral modes more.")
    needs = "flapwise and lateral (or torsion) modes: the bond holds them by its normal and its shear stiffness"
    changes = ("clamp",)
    alternative = "clamp support"  # the clamp face on a foundation or the lever bonded over an overlap: one at a time
    params = (
        CauseParam("lam_n", "1 (1 / (beta_n L))", LAMBDA_MIN, 1.0, LAMBDA_MIN,
                   "normal bond's Winkler length over the free length", scale="log"),
        CauseParam("lam_t", "1 (1 / (beta_t L))", LAMBDA_MIN, 1.0, LAMBDA_MIN,
                   "shear bond's Winkler length over the free length", scale="log"),
        CauseParam("lo", "1 (L_o / L)", 0.02, 1.0, 0.3, "bonded overlap over the free length"),
    )

    def constrain(self, problem):
        if super().constrain(problem) is None or not problem.supports("overlap"):
            return None
        return self

    def start_sets(self):
        # a stiff, a medium and a soft bond, the shear bond softer as a glue layer's is (lam_t / lam_n = 1.4-2.7 for
        # nu = 0.3-0.45); three starts: the spectra's labelling screen fits every cause on every labelling
        return [{"lam_n": n, "lam_t": 2.0 * n, "lo": 0.3} for n in (0.01, 0.03, 0.1)]

    def effect(self, v, s):
        s.overlap = (v["lam_n"], v["lam_t"], v["lo"])

    def derived(self, v, problem):
        b = problem.reference_baseline
        kn, kt = b.overlap_stiffness(v["lam_n"], v["lam_t"])
        return {"k_normal_per_area_N_per_m3": kn, "k_shear_per_area_N_per_m3": kt, "shear_over_normal": kt / kn,
                "overlap_m": v["lo"] * b.L, "winkler_length_normal_m": v["lam_n"] * b.L,
                "winkler_length_shear_m": v["lam_t"] * b.L}
