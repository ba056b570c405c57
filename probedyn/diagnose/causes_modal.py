"""Modal causes: extensions of the reduced beam model (:mod:`probedyn.diagnose.beam`).

Each ``apply`` edits the *state* the modal model is evaluated from:
``t``, ``w``, ``L`` (ratios to the nominal thickness, width, length), ``e_bend`` (ratio of the
axial Young's modulus used in bending to the nominal E), ``k_rot``/``k_trans`` (root springs in
units of EI_flap / L_nom and EI_flap / L_nom^3 of the nominal beam), ``masses`` (list of
(point mass / nominal beam mass, position x / L)), ``p`` (axial force in units of
EI_flap / L_nom^2), ``rho_f``/``eta_f`` (fluid). Non-dimensionalising by the *nominal* beam keeps
the parameters of one physical clamp or sensor the same across a length sweep.

Stated assumptions (each also in docs/diagnose.md): the clamp springs act on both bending
families (an isotropic clamp) but not on torsion; the point mass loads the bending families
(its rotary inertia about the beam axis is neglected in torsion); fluid loading acts on the
flapwise family only (lateral motion is edge-on and torsion needs Green & Sader's torsional
function); axial prestress acts on both bending families.
"""

from __future__ import annotations

import math

from probedyn.diagnose.causes import Cause, CauseParam, register


@register
class ClampCompliance(Cause):
    id = "clamp-compliance"
    kind = "modal"
    title = "Clamp / base compliance"
    description = ("Root rotational and translational springs instead of a rigid clamp "
                   "(glue layer, chip overhang, soft base). Lowers the low modes more than the high ones.")
    needs = "two or more bending modes (one mode cannot tell it from a stiffness error)"
    source = "beam boundary condition EI w'' = k_r w', EI w''' = -k_t w at x = 0 (limit: eq 2.40 for k -> inf)"
    params = (
        CauseParam("kappa_r", "1 (k_r L/EI)", 0.3, 1e4, (30.0, 3.0), "root rotational stiffness k_r L_nom / EI_flap", scale="log", neutral=math.inf),
        CauseParam("kappa_t", "1 (k_t L^3/EI)", 3.0, 1e8, (1e5,), "root translational stiffness k_t L_nom^3 / EI_flap", scale="log", neutral=math.inf, secondary=True, hold=1e8),
    )

    def apply(self, v, s):
        s["k_rot"] = v["kappa_r"]
        s["k_trans"] = v["kappa_t"]

    def derived(self, v, problem):
        ei = problem.nominal_EI_flap
        L = problem.props.length
        return {"k_rot_Nm_per_rad": v["kappa_r"] * ei / L, "k_trans_N_per_m": v["kappa_t"] * ei / L**3}


@register
class PointMass(Cause):
    id = "point-mass"
    kind = "modal"
    title = "Added point mass at an unknown position"
    description = ("A concentrated mass (tip, adsorbed particle, sensor) at x = xi L; lowers each mode by "
                   "its modal displacement at xi squared.")
    needs = "two or more bending modes to locate it (one mode: mass and position are degenerate)"
    source = "corrected eq 3.10 for xi = 1 (SOURCE-NOTES item 1); Rayleigh-Ritz eqs 4.45-4.55 in general"
    params = (
        CauseParam("mu", "1 (m / rho A L)", 0.0, 5.0, (0.05,), "added mass / nominal beam mass", neutral=0.0),
        CauseParam("xi", "1 (x / L)", 0.05, 1.0, (1.0, 0.75, 0.5), "position along the beam", neutral=1.0, secondary=True, hold=1.0),
    )

    def apply(self, v, s):
        s["masses"] = [*s.get("masses", []), (v["mu"], v["xi"])]

    def derived(self, v, problem):
        p = problem.props
        return {"mass_kg": v["mu"] * p.rho * p.area * p.length, "position_m": v["xi"] * p.length}


class _Ratio(Cause):
    kind = "modal"
    key = ""

    def apply(self, v, s):
        s[self.key] = s.get(self.key, 1.0) * v[self.params[0].name]


@register
class ThicknessError(_Ratio):
    id = "thickness-error"
    title = "Thickness differs from nominal"
    description = "Actual thickness t = ratio * t_nom: flapwise and torsional frequencies scale with t, lateral ones do not."
    needs = "a lateral or torsional mode besides the flapwise ones (flapwise alone: same as E or length error)"
    source = "f_flap ~ t / L^2 sqrt(E / rho) (eq 2.41)"
    key = "t"
    params = (CauseParam("t_ratio", "1", 0.5, 1.5, (1.0,), "t / t_nominal", neutral=1.0),)


@register
class WidthError(_Ratio):
    id = "width-error"
    title = "Width differs from nominal"
    description = "Actual width w = ratio * w_nom: lateral frequencies scale with w, torsional ~ 1/w, flapwise unchanged in vacuum."
    needs = "a lateral or torsional mode (or fluid loading, which depends on w)"
    source = "EI_lat = E t w^3 / 12; Roark torsion constant"
    key = "w"
    params = (CauseParam("w_ratio", "1", 0.5, 1.5, (1.0,), "w / w_nominal", neutral=1.0),)


@register
class LengthError(_Ratio):
    id = "length-error"
    title = "Free length differs from nominal"
    description = "Actual free length L = ratio * L_nom (clamp position): bending ~ 1/L^2, torsion ~ 1/L."
    needs = "a torsional mode besides bending modes"
    source = "eq 2.41"
    key = "L"
    params = (CauseParam("L_ratio", "1", 0.7, 1.3, (1.0,), "L / L_nominal", neutral=1.0),)


@register
class Anisotropy(_Ratio):
    id = "anisotropy"
    title = "Material anisotropy / crystal orientation"
    description = ("The Young's modulus along the beam axis differs from the isotropic value the spec assumed "
                   "(e.g. Si along <100>: 130 GPa vs <110>: 169 GPa, ratio 0.77); bending scales with sqrt(ratio), "
                   "torsion (shear modulus) does not.")
    needs = "a torsional mode besides bending modes"
    source = "effective E per direction: 1/E(n) = s_ijkl n_i n_j n_k n_l"
    key = "e_bend"
    params = (CauseParam("e_ratio", "1", 0.5, 1.6, (1.0,), "E_axial / E_nominal", neutral=1.0),)


@register
class FluidLoading(Cause):
    id = "fluid-loading"
    kind = "modal"
    title = "Fluid loading (air or liquid)"
    description = ("Added mass and damping of a surrounding fluid by Sader's hydrodynamic function for a thin "
                   "rectangular beam: lowers frequencies by 1/sqrt(1 + T Gamma_r) and sets a mode-dependent Q.")
    needs = "Q values, or several flapwise modes (Gamma depends on frequency)"
    source = "J. E. Sader, J. Appl. Phys. 84, 64 (1998), eqs 17, 20, 21, 25"
    params = (
        CauseParam("rho_f", "kg/m^3", 0.05, 3000.0, (1.2, 1000.0), "fluid density", scale="log", neutral=0.0),
        CauseParam("eta_f", "Pa s", 3e-6, 1e-2, (1.8e-5, 1e-3), "fluid dynamic viscosity", scale="log", neutral=1.8e-5, secondary=True, hold=1.8e-5),
    )


@register
class AxialPrestress(Cause):
    id = "axial-prestress"
    kind = "modal"
    title = "Axial prestress"
    description = ("An axial force P (tension > 0, e.g. residual stress of a coating or a constrained tip) "
                   "adds geometric stiffness P int w'^2: raises the low modes most.")
    needs = "two or more bending modes"
    source = "EI w'''' - P w'' = rho A omega^2 w"
    params = (CauseParam("p", "1 (P L^2/EI)", -2.2, 30.0, (0.0,), "axial force P L_nom^2 / EI_flap", neutral=0.0),)


    def derived(self, v, problem):
        return {"axial_force_N": v["p"] * problem.nominal_EI_flap / problem.props.length**2}
