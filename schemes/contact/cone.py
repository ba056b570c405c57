"""Conical and pyramidal tips (Sneddon 1965; Bilodeau 1992), blunted by the tip radius: no adhesion.

A sharp AFM tip is a cone or a pyramid whose apex is rounded; once the contact radius exceeds the
rounded cap, the force grows as ``delta^2`` (cone) instead of Hertz's ``delta^1.5`` (sphere). Deep
indentations of soft samples (cells, gels, polymers: hundreds of nm) are in that regime.

**Sneddon's solution for an axisymmetric punch** (Sneddon, Int. J. Eng. Sci. 3 (1965) 47, eqs 5.6
and 5.8 with the profile ``f(r)``, ``f(0) = 0``, on an elastic half-space of reduced modulus E*
(2.21), frictionless)::

    delta(a) = a  int_0^a f'(r) / sqrt(a^2 - r^2) dr
    P(a)     = 2 E*  int_0^a r^2 f'(r) / sqrt(a^2 - r^2) dr

**Blunted cone** (half-angle ``alpha`` between the axis and the flank): a spherical cap of the tip radius R,
``f(r) = R - sqrt(R^2 - r^2)``, tangent to the cone at ``b = R cos(alpha)`` (its height there ``R (1 - sin alpha)``), the
cone ``f(b) + (r - b) cot(alpha)`` beyond (the profile and its slope continuous; the contact reaches the
cap's edge at the penetration ``(b / 2) ln((R + b) / (R - b))``): the geometry of Briscoe,
Sebastian & Adams, J. Phys. D 27 (1994) 1156, and of a real rounded apex. For ``a <= b`` the integrals give the
sphere (Sneddon 1965; ``L = ln((R + a) / (R - a))``)::

    delta(a) = (a / 2) L,   P(a) = E* [ (R^2 + a^2) L / 2 - a R ]

(Hertz, ``delta = a^2 / R``, ``P = 4 E* a^3 / (3 R)``, for ``a << R``); for ``a > b`` (``s = sqrt(a^2 - b^2)``,
``Lam = ln((R + a) / (R sin(alpha) + s))``)::

    delta(a) = a Lam + a cot(alpha) arccos(b / a)
    P(a)     = E* [ (R^2 + a^2) Lam + R s sin(alpha) - a R + cot(alpha) (a^2 arccos(b / a) + b s) ]

(derived here from Sneddon's integrals with that profile; at ``a = b`` they join the sphere's). Until session 34
the cap was the paraboloid ``r^2 / (2 R)`` tangent at ``R cot(alpha)``: the same apex curvature, but for a sharp
tip a cap many radii wide (3.1 R at 18 deg) where the sphere meets the cone at 0.95 R -- an independent
generator's sphere-capped 18 deg tip, indented 10 R deep, was read as a smaller sphere.

Limits (tests/test_contact_cone.py): ``R -> 0`` is Sneddon's sharp cone ``P = (2 / pi) E* tan(alpha)
delta^2``, ``delta = (pi / 2) a cot(alpha)``; ``alpha -> 0`` (``b -> R``) is the sphere to any depth, and Hertz
while ``delta << R``; the closed forms are checked against a quadrature of the two integrals.

**Pyramid** (four-sided, ``alpha`` the half-angle between the axis and a face): Bilodeau's
(J. Appl. Mech. 59 (1992) 519) sharp-pyramid law ``P = 0.7453 E* tan(alpha) delta^2``, implemented
as the equivalent cone ``tan(alpha_c) = (pi / 2) 0.7453 tan(alpha)`` (the sharp law exactly; the
blunted pyramid's cap is the sphere tangent to that cone -- an approximation of the rounded apex, as in
Rico et al., Phys. Rev. E 72 (2005) 021914).

Normalisation used by :class:`~.base.ContactModel`: lengths in units of R (``A = a / R``,
``D = delta / R``) and loads in units of ``E* R^2``; there is no tail (no force out of contact)
and no adhesion (``W`` must be 0).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.core.params import Param, ParamSet

from .base import COMMON_PARAMS, CONTACT_MODELS, ContactModel, ContactScales, _as_array

#: Bilodeau (1992): sharp four-sided pyramid, ``P = BILODEAU_PYRAMID E* tan(alpha) delta^2``
BILODEAU_PYRAMID = 0.7453
#: smallest half-angle [rad]: the cap then ends at b = R cos(alpha), 5e-9 R short of the sphere's equator
ALPHA_MIN = 1e-4

_GEOMETRY = [p for p in COMMON_PARAMS if p.name in ("E_t", "nu_t", "E_s", "nu_s", "R_t", "R_s")]


def blunted_cone_nd(A, alpha: float):
    """``(D, P, dD/dA, dP/dA)`` of the sphere-capped cone of half-angle ``alpha`` in units of R and ``E* R^2`` at
    the normalised contact radius ``A = a / R`` (module docstring)."""
    A = np.atleast_1d(np.asarray(A, dtype=float))
    sa, B = math.sin(alpha), math.cos(alpha)  # b / R
    cot_a = B / sa
    cap = A <= B
    D = np.zeros_like(A)
    P = np.zeros_like(A)
    dD = np.zeros_like(A)
    dP = np.zeros_like(A)
    if np.any(cap):
        a = A[cap]
        L = np.log1p(a) - np.log1p(-a)  # ln((1 + a) / (1 - a))
        D[cap] = 0.5 * a * L
        P[cap] = 0.5 * (1.0 + a * a) * L - a
        dD[cap] = 0.5 * L + a / (1.0 - a * a)
        dP[cap] = a * L + 2.0 * a * a / (1.0 - a * a)
    if np.any(~cap):
        a = A[~cap]
        s = np.sqrt(np.maximum(a * a - B * B, 1e-300))
        lam = np.log((1.0 + a) / (sa + s))
        ac = np.arccos(np.clip(B / a, -1.0, 1.0))
        D[~cap] = a * lam + a * cot_a * ac
        P[~cap] = (1.0 + a * a) * lam + s * sa - a + cot_a * (a * a * ac + B * s)
        dlam = 1.0 / (1.0 + a) - (a / s) / (sa + s)
        dac = B / (a * s)
        dD[~cap] = lam + a * dlam + cot_a * (ac + a * dac)
        dP[~cap] = 2.0 * a * lam + (1.0 + a * a) * dlam + sa * a / s - 1.0 + cot_a * (2.0 * a * ac + a * a * dac
                                                                                    + B * a / s)
    return D, P, dD, dP


class _Tip(ContactModel):
    """A non-adhesive axisymmetric tip of revolution through :func:`blunted_cone_nd`."""

    #: tan(alpha_cone) / tan(alpha) of the equivalent cone
    cone_factor: ClassVar[float] = 1.0
    adhesive: ClassVar[bool] = False

    def __init__(self, **overrides: Any) -> None:
        for name in ("W", "H", "lam", "z0"):
            if overrides.get(name):
                raise ParameterError(f"contact model '{self.key}' has no adhesion: '{name}' is not a parameter "
                                     "(adhesion with a conical tip is not implemented)")
            overrides.pop(name, None)
        self.values = self.params.resolve(overrides)
        alpha = float(self.values["alpha"])
        if not 0.0 < alpha < math.pi / 2:
            raise ParameterError(f"half-angle alpha must be in (0, pi/2) rad, got {alpha}")
        v = self.values
        E_star = 1.0 / ((1 - v["nu_t"] ** 2) / v["E_t"] + (1 - v["nu_s"] ** 2) / v["E_s"])
        R = v["R_t"] if not v["R_s"] else 1.0 / (1.0 / v["R_t"] + 1.0 / v["R_s"])
        self.alpha_cone = math.atan(self.cone_factor * math.tan(alpha))
        # lengths in R, loads in E* R^2 (W = 0: no Maugis units)
        self.scales = ContactScales(E_star=E_star, K=4.0 / 3.0 * E_star, R=R, W=0.0, H=0.0, z0=0.0, lam=0.0,
                                    a_unit=R, P_unit=E_star * R * R, d_unit=R)
        self._table_cache = {}

    @property
    def lam(self) -> float:
        return 0.0

    def nd_curve(self, A):
        return blunted_cone_nd(A, self.alpha_cone)

    def nd_key(self) -> tuple:
        """The normalised curve depends on the equivalent cone's half-angle alone (a cache key for its
        polylines, to 12 digits)."""
        return (self.key, float(f"{self.alpha_cone:.12g}"))

    def nd_endpoint(self):
        return 0.0, 0.0

    def nd_tail(self, D, branch="loading"):
        D = np.asarray(D, dtype=float)
        return np.zeros_like(D), np.zeros_like(D)

    def state(self, delta, branch="loading") -> dict[str, Any]:
        d, scalar = _as_array(delta)
        s = self.scales
        st = self.nd_state(d / s.d_unit, branch if branch != "unstable" else "loading")
        res = dict(force=np.asarray(st["P"]) * s.P_unit, radius=np.asarray(st["A"]) * s.a_unit,
                   stiffness=np.asarray(st["k"]) * s.P_unit / s.d_unit, contact=np.asarray(st["contact"]) & (d > 0))
        res["force"] = np.where(d > 0, res["force"], 0.0)
        res["radius"] = np.where(d > 0, res["radius"], 0.0)
        res["stiffness"] = np.where(d > 0, res["stiffness"], 0.0)
        if scalar:
            res = {k: (v[0].item() if hasattr(v[0], "item") else v[0]) for k, v in res.items()}
        return res

    def sharp_force(self, delta):
        """The sharp-tip law (R -> 0): Sneddon's cone or Bilodeau's pyramid, ``c E* tan(alpha) delta^2``."""
        d = np.maximum(np.asarray(delta, dtype=float), 0.0)
        return 2.0 / math.pi * self.scales.E_star * math.tan(self.alpha_cone) * d * d

    def describe(self) -> dict[str, Any]:
        s = self.scales
        return dict(model=self.key, title=self.title, equations=self.source, E_star_pa=s.E_star, R_m=s.R,
                    alpha_rad=float(self.values["alpha"]), equivalent_cone_half_angle_rad=self.alpha_cone,
                    cap_edge_radius_m=s.R * math.cos(self.alpha_cone), cap_edge_depth_m=s.R * self.cap_edge_depth)

    @property
    def cap_edge_depth(self) -> float:
        """The penetration [in R] at which the contact reaches the cap's edge ``b = R cos(alpha)``: the sphere's
        ``(b / 2) ln((R + b) / (R - b))`` (``b^2 / R`` for a small cap), twice its geometric height there."""
        return float(blunted_cone_nd(np.array([math.cos(self.alpha_cone)]), self.alpha_cone)[0][0])


_ALPHA = Param("alpha", math.radians(20.0), "rad", "half-angle between the tip axis and its flank (cone) or face "
               "(pyramid)", lo=ALPHA_MIN, hi=math.pi / 2 - ALPHA_MIN, positive=True, source="Sneddon (1965); Bilodeau (1992)")


@CONTACT_MODELS.register
class BluntedCone(_Tip):
    """Cone of half-angle alpha with a spherical cap of the tip radius (Sneddon; Briscoe et al.)."""

    key: ClassVar[str] = "cone"
    title: ClassVar[str] = "Sneddon cone, blunted by the tip radius (no adhesion)"
    source: ClassVar[str] = ("Sneddon (1965) axisymmetric punch; sharp cone P = (2/pi) E* tan(alpha) delta^2; "
                             "spherical cap: Briscoe et al. (1994)")
    params: ClassVar[ParamSet] = ParamSet(_GEOMETRY + [_ALPHA])


@CONTACT_MODELS.register
class BluntedPyramid(_Tip):
    """Four-sided pyramid (face half-angle alpha) as Bilodeau's equivalent cone, blunted by the tip radius."""

    key: ClassVar[str] = "pyramid"
    title: ClassVar[str] = "Bilodeau pyramid, blunted by the tip radius (no adhesion)"
    source: ClassVar[str] = ("Bilodeau (1992) four-sided pyramid P = 0.7453 E* tan(alpha) delta^2 as the equivalent "
                             "Sneddon cone; spherical cap as the cone's")
    params: ClassVar[ParamSet] = ParamSet(_GEOMETRY + [_ALPHA])
    cone_factor: ClassVar[float] = math.pi / 2.0 * BILODEAU_PYRAMID
