"""The contact registry's cone and pyramid (schemes/contact/cone.py) against independent references:
Sneddon's integrals evaluated by quadrature, the sharp-cone and sharp-pyramid closed forms, Hertz
below the cap edge, and finite differences of the closed-form derivatives."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from probedyn.core.errors import ParameterError
from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.contact.cone import BILODEAU_PYRAMID, blunted_cone_nd

ALPHA = math.radians(25.0)


def _sneddon_quadrature(a: float, R: float, alpha: float) -> tuple[float, float]:
    """delta(a) and P(a) / E* of the paraboloid-capped cone from Sneddon's integrals, by quadrature
    (substitution r = a sin t removes the endpoint singularity)."""
    b = R / math.tan(alpha)
    fp = lambda r: r / R if r <= b else 1.0 / math.tan(alpha)  # noqa: E731
    brk = [math.asin(b / a)] if b < a else None
    d = a * quad(lambda t: fp(a * math.sin(t)), 0.0, math.pi / 2, points=brk, epsabs=0, epsrel=1e-12)[0]
    P = 2.0 * quad(lambda t: (a * math.sin(t)) ** 2 * fp(a * math.sin(t)), 0.0, math.pi / 2, points=brk,
                   epsabs=0, epsrel=1e-12)[0]
    return d, P


@pytest.mark.parametrize("a_over_b", [0.3, 1.0, 1.7, 6.0, 40.0])
def test_closed_form_is_sneddons_integral(a_over_b):
    cot = 1.0 / math.tan(ALPHA)
    A = a_over_b * cot  # in units of R
    D, P, dD, dP = blunted_cone_nd(np.array([A]), cot)
    d_q, P_q = _sneddon_quadrature(A, 1.0, ALPHA)
    assert D[0] == pytest.approx(d_q, rel=1e-9)  # quadrature to 1e-12; the closed form is exact
    assert P[0] == pytest.approx(P_q, rel=1e-9)
    h = 1e-6 * A  # central differences: truncation ~ h^2 f''' / 6, far below 1e-7 here
    Dp, Pp, _, _ = blunted_cone_nd(np.array([A + h]), cot)
    Dm, Pm, _, _ = blunted_cone_nd(np.array([A - h]), cot)
    if abs(A - cot) > 2 * h:  # the kink of f'' at the cap edge: D and P are C1 there, not C2
        assert dD[0] == pytest.approx((Dp - Dm)[0] / (2 * h), rel=1e-6)
        assert dP[0] == pytest.approx((Pp - Pm)[0] / (2 * h), rel=1e-6)


def test_limits_hertz_below_the_cap_and_sneddon_cone_far_beyond():
    R = 20e-9
    m = get_contact_model("cone", alpha=ALPHA, R_t=R, R_s=0.0, E_s=5e6)
    E = m.scales.E_star
    d_cap = R / math.tan(ALPHA) ** 2  # the cap edge depth b^2 / R
    d = np.array([0.01, 0.5, 0.99]) * d_cap
    assert np.allclose(m.force(d), 4 / 3 * E * math.sqrt(R) * d**1.5, rtol=1e-10)
    # far beyond the cap the blunted cone tends to the sharp one: P / P_sharp - 1 = O(b / a), a ~ delta
    dd = np.array([1e3, 1e4]) * d_cap
    ratio = m.force(dd) / m.sharp_force(dd)
    assert abs(ratio[1] - 1) < abs(ratio[0] - 1) < 0.05
    assert abs(ratio[1] - 1) < 0.3 * abs(ratio[0] - 1)  # shrinking like (b/a)^1 (factor 10 per decade)
    assert np.all(m.force(np.array([-1e-9, 0.0])) == 0.0)


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
