"""Thickness, width and length of the probe differ from the nominal ones.

Each is an exact affine stretch of the probe's mesh along its axis (``fem_terms``: the P2
stiffness of the stretched mesh is a sum of six projected matrices with known scale factors).
The free-length error is an *offset* ``dL`` of the clamp edge (the same for every length of a
length sweep), the others are ratios. Every frequency is monotone in each of these single
parameters, so the nested fit starts only from the null (no extra starts).
"""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ThicknessError(Cause):
    key = "thickness-error"
    kind = "modal"
    title = "Thickness differs from nominal"
    source = "affine stretch of the FEM mesh through the thickness; beam limit f_flap ~ t (eq 2.41)"
    description = "Actual thickness t = ratio t_nom: flapwise and torsional modes scale with t, lateral ones hardly."
    needs = "a lateral or torsional mode besides the flapwise ones (flapwise alone: same as a modulus error)"
    changes = ("thickness",)
    params = (CauseParam("t_ratio", "1", 0.6, 1.6, 1.0, "t / t_nominal"),)

    def effect(self, v, s):
        s.scale = np.array(s.scale, float)
        s.scale[s.axes["thickness"]] *= v["t_ratio"]


@CAUSES.register
class WidthError(Cause):
    key = "width-error"
    kind = "modal"
    title = "Width differs from nominal"
    source = "affine stretch of the FEM mesh across the width; beam limit f_lat ~ w"
    description = "Actual width w = ratio w_nom: lateral modes scale with w, torsion falls, flapwise hardly changes in vacuum."
    needs = "a lateral or torsional mode (or fluid loading, which depends on w)"
    changes = ("width",)
    params = (CauseParam("w_ratio", "1", 0.6, 1.6, 1.0, "w / w_nominal"),)

    def effect(self, v, s):
        s.scale = np.array(s.scale, float)
        s.scale[s.axes["width"]] *= v["w_ratio"]


@CAUSES.register
class LengthError(Cause):
    key = "length-error"
    kind = "modal"
    title = "Free length differs from nominal (clamp edge offset)"
    source = "affine stretch of the FEM mesh along the beam axis; beam limit f_bend ~ 1/L^2, f_tors ~ 1/L"
    description = ("The clamp edge sits dL further out (dL > 0: longer) than declared: bending modes ~ 1/L^2, "
                   "torsion ~ 1/L; in a length sweep the same dL for every length.")
    needs = "a torsional mode besides bending modes, or a length sweep"
    changes = ("length",)
    params = (CauseParam("dL", "m", -1.0, 1.0, 0.0, "offset of the clamp edge (bounds: 30 % of the shortest length)"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        Lmin = problem.shortest_length
        return LengthError((CauseParam("dL", "m", -0.3 * Lmin, 0.3 * Lmin, 0.0, "free length minus nominal"),))

    def effect(self, v, s):
        s.scale = np.array(s.scale, float)
        s.scale[s.axes["length"]] *= (s.length + v["dL"]) / s.length
