"""The contact registry's cone and pyramid (schemes/contact/cone.py) against independent references:
Sneddon's integrals with the sphere-capped profile evaluated by quadrature, the sharp-cone and sharp-pyramid
closed forms, Sneddon's sphere below the cap edge (and Hertz while delta << R), and finite differences of the
closed-form derivatives."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from probedyn.core.errors import ParameterError
from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.contact.cone import BILODEAU_PYRAMID, blunted_cone_nd

ALPHA = math.radians(25.0)


def _sneddon_quadrature(a: float, R: float, alpha: float) -> tuple[float, float]:
    """delta(a) and P(a) / E* of the sphere-capped cone from Sneddon's integrals with the profile's slope
    f'(r) = r / sqrt(R^2 - r^2) (sphere, r <= R cos alpha) and cot(alpha) beyond, by quadrature (the
    substitution r = a sin t removes the endpoint singularity)."""
    b = R * math.cos(alpha)
    fp = lambda r: r / math.sqrt(R * R - r * r) if r <= b else 1.0 / math.tan(alpha)  # noqa: E731
    brk = [math.asin(b / a)] if b < a else None
    d = a * quad(lambda t: fp(a * math.sin(t)), 0.0, math.pi / 2, points=brk, epsabs=0, epsrel=1e-12)[0]
    P = 2.0 * quad(lambda t: (a * math.sin(t)) ** 2 * fp(a * math.sin(t)), 0.0, math.pi / 2, points=brk,
                   epsabs=0, epsrel=1e-12)[0]
    return d, P


def _sphere(a, R):
    """Sneddon's rigid sphere: delta = (a / 2) L, P / E* = (R^2 + a^2) L / 2 - a R, L = ln((R + a) / (R - a))."""
    L = np.log((R + a) / (R - a))
    return a / 2 * L, (R * R + a * a) * L / 2 - a * R


@pytest.mark.parametrize("alpha_deg", [18.0, 25.0, 60.0])
@pytest.mark.parametrize("a_over_b", [0.3, 0.9, 1.0, 1.7, 6.0, 40.0])
def test_closed_form_is_sneddons_integral(a_over_b, alpha_deg):
    alpha = math.radians(alpha_deg)
    A = a_over_b * math.cos(alpha)  # in units of R
    D, P, dD, dP = blunted_cone_nd(np.array([A]), alpha)
    d_q, P_q = _sneddon_quadrature(A, 1.0, alpha)
    assert D[0] == pytest.approx(d_q, rel=1e-9)  # quadrature to 1e-12; the closed form is exact
    assert P[0] == pytest.approx(P_q, rel=1e-9)
    h = 1e-6 * A  # central differences: truncation ~ h^2 f''' / 6, far below 1e-7 here
    Dp, Pp, _, _ = blunted_cone_nd(np.array([A + h]), alpha)
    Dm, Pm, _, _ = blunted_cone_nd(np.array([A - h]), alpha)
    if abs(a_over_b - 1.0) > 1e-3:  # the kink of f'' at the cap edge: D and P are C1 there, not C2
        assert dD[0] == pytest.approx((Dp - Dm)[0] / (2 * h), rel=1e-6)
        assert dP[0] == pytest.approx((Pp - Pm)[0] / (2 * h), rel=1e-6)


def test_limits_sphere_below_the_cap_and_sneddon_cone_far_beyond():
    R = 20e-9
    m = get_contact_model("cone", alpha=ALPHA, R_t=R, R_s=0.0, E_s=5e6)
    E = m.scales.E_star
    d_cap = _sphere(R * math.cos(ALPHA), R)[0]  # the sphere's penetration when its contact reaches R cos alpha
    assert m.describe()["cap_edge_depth_m"] == pytest.approx(d_cap, rel=1e-12)
    # Hertz while delta << R (the sphere's profile is the paraboloid's to O(r^4 / R^3))
    d = np.array([1e-4, 1e-3]) * R
    assert np.allclose(m.force(d), 4 / 3 * E * math.sqrt(R) * d**1.5, rtol=2e-3)
    # up to the cap edge: Sneddon's sphere
    a = np.array([0.2, 0.6, 0.99 * math.cos(ALPHA)]) * R
    delta, P = _sphere(a, R)
    assert np.allclose(m.force(delta), E * P, rtol=1e-6)
    # far beyond the cap the blunted cone tends to the sharp one: P / P_sharp - 1 = O(b / a), a ~ delta
    dd = np.array([1e3, 1e4]) * d_cap
    ratio = m.force(dd) / m.sharp_force(dd)
    assert abs(ratio[1] - 1) < abs(ratio[0] - 1) < 0.05
    assert abs(ratio[1] - 1) < 0.3 * abs(ratio[0] - 1)  # shrinking like (b/a)^1 (factor 10 per decade)
    assert np.all(m.force(np.array([-1e-9, 0.0])) == 0.0)
    # alpha -> 0: the cap reaches the sphere's equator, the sphere to any depth
    s = get_contact_model("cone", alpha=1e-3, R_t=R, R_s=0.0, E_s=5e6)
    delta, P = _sphere(0.9 * R, R)
    assert s.force(delta) == pytest.approx(E * P, rel=1e-6)


def test_pyramid_is_bilodeau_in_the_sharp_limit():
    R = 1e-10
    p = get_contact_model("pyramid", alpha=ALPHA, R_t=R, R_s=0.0, E_s=5e6)
    d = 2e-5  # 10^5 tip radii: the cap is negligible (relative O(1e-3))
    assert p.force(d) == pytest.approx(BILODEAU_PYRAMID * p.scales.E_star * math.tan(ALPHA) * d * d, rel=3e-3)


def test_cone_has_no_adhesion():
    with pytest.raises(ParameterError):
        get_contact_model("cone", W=0.1)
    m = get_contact_model("cone", alpha=ALPHA)
    assert m.pull_off_force() == 0.0
    assert m.force(1e-8, "loading") == m.force(1e-8, "unloading")
