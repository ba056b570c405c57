"""Adhesion of the tip to the sample, after the contact registry (probedyn.schemes.contact).

Three causes, one per contact law of the registry: DMT (Hertz offset by the adhesion, with the
van der Waals tail ``-2 pi W R zeta_0^2 / D^2`` that pulls the tip into contact where its gradient
exceeds the lever's stiffness; the tail's range ``zeta_0`` is fitted, from the registry's Table 4.4
value 0.375 nm: it is no universal constant -- Israelachvili's "universal" cut-off 0.165 nm, an
interatomic spacing, or longer for a rough tip -- and it sets the snap-in, since the Hamaker
constant is ``H = 12 pi W zeta_0^2``), JKR (adhesion inside the contact only: a jump into contact and a
hysteresis), and Maugis-Dugdale with its transition parameter lambda fitted (DMT for lambda -> 0,
JKR for lambda -> infinity). Each replaces the baseline's Hertz contact by the registry model
with the fitted work of adhesion W.
"""

from __future__ import annotations

from probedyn.core.presets import preset
from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

_W = CauseParam("W", "J/m^2", 0.0, 2.0, 0.0, "work of adhesion", starts=(0.003, 0.03, 0.3))
#: the range of the DMT tail: null value the registry's (Table 4.4), bounds 0.15-2 nm: from just below
#: Israelachvili's contact separation D0 = 0.165 nm (the one cut-off that gives most solids' surface energies
#: from their Hamaker constants, Intermolecular and Surface Forces, 3rd ed., 13.6; no van der Waals contact
#: is closer) to the nanometre asperities of a rough tip; irrelevant where W = 0. A shorter tail is not
#: physics: it only lets the DMT jump mimic JKR's (docs/diagnose.md 9.12).
_Z0 = CauseParam("z0", "m", 0.15e-9, 2e-9, preset("table-4.4")["zeta0"],
                 "range zeta_0 of the van der Waals tail (H = 12 pi W zeta_0^2)", scale="log", starts=(0.165e-9, 1e-9))


class _Adhesion(Cause):
    kind = "force"
    changes = ("adhesion",)
    alternative = "contact law"  # one law at a time: DMT, JKR and Maugis-Dugdale are alternatives
    contact = ""

    def effect(self, v, s):
        s.contact = self.contact
        s.W = v["W"]

    def derived(self, v, problem):
        import math

        R = problem.data.tip_radius
        return {"dmt_pull_off_N": 2 * math.pi * v["W"] * R, "jkr_pull_off_N": 1.5 * math.pi * v["W"] * R}


@CAUSES.register
class AdhesionDMT(_Adhesion):
    key = "adhesion-dmt"
    title = "Adhesion, DMT (with the van der Waals tail: jump to contact where its gradient exceeds k)"
    source = "contact registry 'dmt': eqs 2.20-2.21; pull-off 2 pi W R"
    description = ("Hertz contact offset by -2 pi W R plus the -H R / (6 D^2) tail outside contact (H = 12 pi W zeta_0^2, "
                   "zeta_0 fitted): snap-in and pull-off without hysteresis of the contact law.")
    needs = "the retract below the baseline (pull-off), or a snap-in on the approach (for zeta_0)"
    params = (_W, _Z0)
    contact = "dmt"

    def effect(self, v, s):
        super().effect(v, s)
        s.z0 = v.get("z0", _Z0.null)

    def derived(self, v, problem):
        """With the Hamaker constant, the jump to contact: the lever of stiffness k becomes unstable in the tail
        ``-H R / (6 d^2)`` where its gradient ``H R / (3 d^3)`` reaches k, at ``d* = (H R / (3 k))^(1/3)``
        (schemes.contact.force_curve); below the tail's end gap zeta_0 the approach reaches the contact without a
        jump (reported as 0)."""
        import math

        from probedyn.schemes.contact.force_curve import tail_jump_gap

        z0 = v.get("z0", _Z0.null)
        H = 12 * math.pi * v["W"] * z0**2
        d_star = tail_jump_gap(H, problem.state(v, (self,)).R, problem.data.k) if H > 0 else 0.0
        return {**super().derived(v, problem), "hamaker_J": H, "snap_in_gap_m": d_star if d_star > z0 else 0.0}


@CAUSES.register
class AdhesionJKR(_Adhesion):
    key = "adhesion-jkr"
    title = "Adhesion, JKR (short-range, with contact hysteresis)"
    source = "contact registry 'jkr': Johnson, Kendall & Roberts (1971); pull-off 3/2 pi W R (load control)"
    description = "Adhesion acting inside the contact only: the contact forms with a jump and breaks late (neck), so approach and retract differ."
    needs = "approach and retract (the hysteresis)"
    params = (_W,)
    contact = "jkr"


@CAUSES.register
class AdhesionMD(_Adhesion):
    key = "adhesion-md"
    title = "Adhesion, Maugis-Dugdale (transition parameter lambda fitted)"
    source = "contact registry 'md': eqs 2.24-2.35 (SOURCE-NOTES 3); lambda = 2.06 / z0 (W^2 R / (pi K^2))^(1/3)"
    description = "The DMT-JKR transition: a Dugdale attraction of range fixed by lambda; lambda -> 0 is DMT, large lambda JKR."
    needs = "a resolved pull-off and the shape of the retract near it"
    params = (_W, CauseParam("lam", "1", 0.05, 10.0, 1.0, "Maugis transition parameter", scale="log", starts=(0.2, 3.0)))
    contact = "md"
    #: the causes it contains as limits of lambda (JKR: lambda -> infinity, DMT: lambda -> 0); the engine
    #: fits them from this cause's optimum too, and prefers them within the evidence margin (parsimony)
    limits = ("adhesion-jkr", "adhesion-dmt")

    def start_sets(self):
        return [{"W": 0.03, "lam": 5.0}, {"W": 0.03, "lam": 0.3}, {"W": 0.3, "lam": 1.0}, {"W": 0.003, "lam": 1.0}]

    def effect(self, v, s):
        super().effect(v, s)
        s.lam = v["lam"]

    def derived(self, v, problem):
        """With the pull-offs, the Dugdale range ``h0 = W / sigma_0 = 2 / (pi lam)`` Maugis length units of the
        registry law the fit evaluates: Maugis' own non-contact branch (departure 47) lets the approach jump to
        contact where the gap reaches h0, whatever the lever's stiffness."""
        from probedyn.diagnose.forcecurve import _interaction
        from probedyn.schemes.contact.maugis_dugdale import dugdale_range

        law = _interaction(problem.state(v, (self,)), problem.E_t, problem.nu_t)[2]
        return {**super().derived(v, problem), "snap_in_gap_m": dugdale_range(v["lam"]) * law.scales.d_unit}
