"""Clamp compliance: the clamp face rests on an elastic foundation instead of being rigid.

One physical support model: normal and tangential springs per unit area of the clamp face
(a glue layer, the chip's overhang, a soft holder). For the rectangular root of a lever of
thickness t and width w this is, in beam terms, a root rotational stiffness per unit clamp width
``k_n t^3 / 12`` and a root translational stiffness per unit width ``k_t t`` for flapwise bending,
and -- the same support -- ``k_n t w^3 / 12`` and ``k_t w t`` for lateral bending (``k_t I_p`` for
twist). A finite but stiff clamp therefore lowers flapwise and lateral modes in a fixed ratio,
which a point mass or an anisotropy cannot imitate. A lever bonded to its chip over an overlap is the other
support of the catalog (``bonded-overlap``, an alternative: one support at a time).

Parameters: the dimensionless compliances ``c_rot = E / (L k_n)`` (root rotation compliance in
units of the beam's L / EI per unit width) and ``c_trans = E t^2 / (12 L^3 k_t)`` (root translation
in units of L^3 / EI per unit width); 0 = rigid (the baseline).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ClampCompliance(Cause):
    key = "clamp-compliance"
    kind = "modal"
    title = "Clamp / base compliance (elastic foundation of the clamp face)"
    source = ("Winkler foundation on the clamp face; beam limit: EI w'' = k_r w', EI w''' = -k_t w at the root, "
              "rigid clamp (eq 2.40) for k -> infinity")
    description = ("Normal and tangential springs per unit area of the clamp face instead of a rigid clamp: lowers "
                   "the low modes more than the high ones, flapwise and lateral alike.")
    needs = "two or more bending modes (one mode cannot tell it from a stiffness error)"
    changes = ("clamp",)
    alternative = "clamp support"  # the clamp face on a foundation or the lever bonded over an overlap: one at a time
    params = (
        CauseParam("c_rot", "1 (E / (L k_n))", 0.0, 3.0, 0.0, "root rotation compliance per unit width, in L/EI",
                   starts=(0.01, 0.1)),
        CauseParam("c_trans", "1 (E t^2 / (12 L^3 k_t))", 0.0, 3.0, 0.0,
                   "root translation compliance per unit width, in L^3/EI", starts=(0.003, 0.03)),
    )

    def effect(self, v, s):
        s.clamp = (v["c_rot"], v["c_trans"])

    def derived(self, v, problem):
        b = problem.reference_baseline
        kn, kt = b.clamp_stiffness(max(v["c_rot"], 1e-300), max(v["c_trans"], 1e-300))
        return {"k_normal_per_area_N_per_m3": kn, "k_tangential_per_area_N_per_m3": kt,
                "k_rot_per_width_flapwise_N": kn * b.t**3 / 12.0, "k_trans_per_width_flapwise_N_per_m2": kt * b.t,
                "k_rot_flapwise_Nm_per_rad": kn * b.w * b.t**3 / 12.0, "k_trans_flapwise_N_per_m": kt * b.w * b.t,
                "k_rot_lateral_Nm_per_rad": kn * b.t * b.w**3 / 12.0}
