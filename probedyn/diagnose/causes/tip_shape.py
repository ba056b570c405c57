"""The tip is a cone or pyramid, not a sphere: deep indentations follow delta^2, not delta^1.5.

The contact registry's ``cone`` law (:mod:`probedyn.schemes.contact.cone`: Sneddon's cone blunted by
a spherical cap of the declared tip radius R, tangent at the contact radius ``b = R cos(alpha)``, as a real
rounded apex and Briscoe et al. 1994) replaces the baseline's Hertz sphere. Nested: the null value
``alpha = 0`` is the baseline's Hertz sphere itself; a small half-angle is Sneddon's exact sphere to about the
depth R, which Hertz equals while ``delta << R``. The cone shows once the contact radius passes b, beyond the
penetration ``(b / 2) ln((R + b) / (R - b))`` (R = 20 nm, alpha = 25 deg: 27 nm; 18 deg: 35 nm), so the cause
is identifiable on deep indentations of soft samples. With the sample modulus free, a sharp cone fixes only
``E* tan(alpha)``; alpha itself is read from where the branch turns from delta^1.5 to delta^2 and needs the
tip radius. Until session 34 the cap was a paraboloid tangent at ``R cot(alpha)`` (a cap 3 R wide at 18 deg):
an independent generator's sphere-capped tip read as a smaller sphere (blind force curve c03).
"""

from __future__ import annotations

import math

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class TipShape(Cause):
    key = "tip-shape"
    kind = "force"
    title = "Tip shape: cone / pyramid (Sneddon, Bilodeau) instead of a sphere"
    source = ("contact registry 'cone': Sneddon (1965) P = (2/pi) E* tan(alpha) delta^2 for a sharp cone, blunted by "
              "a paraboloid cap of the tip radius (Briscoe et al. 1994); Bilodeau (1992) pyramid as the equivalent cone")
    description = ("The contact branch of a deep indentation grows as delta^2 (cone or pyramid flanks) instead of "
                   "Hertz's delta^1.5 once the contact radius exceeds the rounded apex, R cot(alpha).")
    needs = "an indentation deeper than the tip's rounded apex, ~R (soft samples, large loads)"
    changes = ("tip_shape",)
    params = (CauseParam("alpha", "deg", 0.0, 80.0, 0.0, "cone half-angle (axis to flank)", starts=(15.0, 30.0, 50.0)),)

    def effect(self, v, s):
        s.alpha = math.radians(v["alpha"])

    def derived(self, v, problem):
        a = math.radians(v["alpha"])
        if a <= 0:
            return {}
        from probedyn.schemes.contact.cone import BluntedPyramid

        R = problem.data.tip_radius
        b = R * math.cos(a)
        return {"pyramid_face_half_angle_deg": math.degrees(math.atan(math.tan(a) / BluntedPyramid.cone_factor)),
                "cap_edge_depth_m": 0.5 * b * math.log((R + b) / (R - b)), "cap_edge_radius_m": b}
