"""Contact registry, DMT (2.20), JKR, and the dimensional interface shared by all models.

Independent references: eq 2.20 written out directly, the JKR (1971) formulas in terms of E*,
Hertz without adhesion, finite differences of the force for the stiffness, and the round trip
load -> contact -> force.
"""

import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes.contact import COMMON_PARAMS, get_contact_model, list_models


def test_registry_lists_the_models():
    assert set(list_models()) == {"dmt", "jkr", "md", "md-vdw", "cone", "pyramid"}
    assert get_contact_model("Maugis-Dugdale").name == "md"
    for name in list_models():
        m = get_contact_model(name)
        assert m.equations and m.title
    # every parameter declares a unit (dimensionless ones use "")
    assert all(p.unit is not None and p.doc for p in COMMON_PARAMS)


def test_derived_quantities_follow_2_21_and_2_24():
    m = get_contact_model("md", E_t=170e9, nu_t=0.28, E_s=60e9, nu_s=0.25, R_t=20e-9, R_s=0.0,
                          W=0.2, z0=0.3e-9)
    s = m.scales
    E_star = 1 / ((1 - 0.28**2) / 170e9 + (1 - 0.25**2) / 60e9)
    assert s.E_star == pytest.approx(E_star, rel=1e-14)
    assert s.R == 20e-9  # flat sample
    assert s.lam == pytest.approx(2.06 / 0.3e-9 * (0.2**2 * 20e-9 / (math.pi * (4 / 3 * E_star) ** 2)) ** (1 / 3))
    # zeta_0 in Maugis units is 2.06 / (pi lam) (used by the tail)
    assert s.z0_bar == pytest.approx(2.06 / (math.pi * s.lam), rel=1e-12)
    # lam given -> W such that (2.24) returns lam
    m2 = get_contact_model("md", lam=0.7)
    assert m2.scales.lam == 0.7
    from probedyn.schemes.contact.base import lam_from
    assert lam_from(m2.scales.W, m2.scales.R, m2.scales.K, m2.scales.z0) == pytest.approx(0.7, rel=1e-12)


def test_dmt_force_is_eq_2_20():
    m = get_contact_model("dmt")
    s = m.scales
    d = np.linspace(-3e-9, 2e-9, 101)  # penetration; separation x - (Rs + Rt) = z0 - d
    sep = s.z0 - d
    direct = np.where(sep >= s.z0, -s.H * s.R / (6 * sep**2),
                      -s.H * s.R / (6 * s.z0**2) + 4 * s.E_star * math.sqrt(s.R) * np.maximum(s.z0 - sep, 0) ** 1.5 / 3)
    assert np.allclose(m.force(d), direct, rtol=1e-12, atol=1e-24)


def test_jkr_radius_and_force_are_the_1971_formulas():
    m = get_contact_model("jkr")
    s = m.scales
    a = np.linspace(0.2, 3.0, 30) * s.a_unit
    # JKR in E*: delta = a^2/R - sqrt(2 pi W a / E*), P = 4 E* a^3 / (3R) - sqrt(8 pi W E* a^3)
    delta = a * a / s.R - np.sqrt(2 * math.pi * s.W * a / s.E_star)
    P = 4 * s.E_star * a**3 / (3 * s.R) - np.sqrt(8 * math.pi * s.W * s.E_star * a**3)
    stable = a >= s.a_unit * 6 ** (-1 / 3)
    st = m.state(delta[stable], "unloading")
    assert np.allclose(st["radius"], a[stable], rtol=1e-9)
    assert np.allclose(st["force"], P[stable], rtol=1e-9, atol=1e-12 * s.P_unit)
    un = m.state(delta[~stable], "unstable")
    assert np.allclose(un["radius"], a[~stable], rtol=1e-9)
    # no force out of contact on approach (JKR assumption)
    assert np.all(m.force(np.array([-1e-9, -1e-10]), "loading") == 0)


def test_no_adhesion_reduces_every_model_to_hertz():
    for name in list_models():
        m = get_contact_model(name, W=0.0)
        s = m.scales
        d = np.linspace(-1e-9, 2e-9, 31)
        F = m.force(d)
        assert np.allclose(F, s.K * math.sqrt(s.R) * np.maximum(d, 0) ** 1.5, rtol=1e-14)
        assert m.pull_off_force() == 0.0


@pytest.mark.parametrize("name,lam", [("dmt", None), ("jkr", None), ("md", 0.3), ("md", 2.0)])
def test_stiffness_is_the_derivative_of_the_force(name, lam):
    kw = {} if lam is None else dict(lam=lam)
    m = get_contact_model(name, **kw)
    s = m.scales
    d = np.linspace(0.2, 3.0, 15) * s.d_unit
    h = 1e-6 * s.d_unit
    fd = (m.force(d + h, "unloading") - m.force(d - h, "unloading")) / (2 * h)
    # central difference error O(h^2) relative ~ 1e-12, rounding ~1e-16/1e-6
    assert np.allclose(m.stiffness(d, "unloading"), fd, rtol=1e-6)


@pytest.mark.parametrize("name", ["dmt", "jkr", "md"])
def test_at_load_round_trip(name):
    m = get_contact_model(name)
    po = m.pull_off_force()
    loads = np.array([0.99 * po, 0.5 * po, 0.0, 1e-9, 1e-7])
    st = m.at_load(loads)
    F = m.force(st["penetration"], "unloading")
    assert np.allclose(F, loads, rtol=1e-9, atol=1e-12 * abs(po))
    # contact radius grows with load on the stable branch
    assert np.all(np.diff(st["radius"]) > 0)


def test_scalar_in_scalar_out():
    m = get_contact_model("md")
    F = m.force(0.0)
    assert isinstance(F, float)
    st = m.state(1e-10)
    assert isinstance(st["radius"], float) and isinstance(st["contact"], bool)


@pytest.mark.parametrize("bad", [dict(nu_s=0.6), dict(E_t=0.0), dict(R_t=-5e-9), dict(lam=-1.0),
                                 dict(z0=-1e-10), dict(W=float("inf")), dict(bogus=1.0)])
def test_every_model_rejects_non_physical_parameters(bad):
    for name in list_models():
        with pytest.raises(ParameterError):
            get_contact_model(name, **bad)


@pytest.mark.parametrize("name,lam", [("dmt", None), ("jkr", None), ("md", 0.3), ("md", 3.0)])
@pytest.mark.parametrize("branch", ["loading", "unloading"])
def test_interpolant_matches_the_exact_solver(name, lam, branch):
    # cubic spline in u = sqrt(D - D_edge) with 400 nodes on u in [0, ~4.6]: h ~ 0.012,
    # error ~ h^4 |P''''| ~ 1e-8 of pi W R; tolerance 1e-6 leaves room for the edge node
    kw = {} if lam is None else dict(lam=lam)
    m = get_contact_model(name, **kw)
    s = m.scales
    f = m.interpolant(branch)
    d = np.linspace(-3.0, 19.0, 997) * s.d_unit
    F, k = f(d)
    exact = m.state(d, branch)
    assert np.allclose(F, exact["force"], rtol=0, atol=1e-6 * s.P_unit)
    # the stiffness: same, away from the vertical tangent at the jump-out point
    ok = np.isfinite(exact["stiffness"]) & (np.abs(exact["stiffness"]) < 50 * s.P_unit / s.d_unit)
    assert np.allclose(k[ok], exact["stiffness"][ok], rtol=1e-4, atol=1e-5 * s.P_unit / s.d_unit)
    # scalar call for ODE right-hand sides
    F0, k0 = f(0.5 * s.d_unit)
    assert isinstance(F0, float) and F0 == pytest.approx(m.force(0.5 * s.d_unit, branch), abs=1e-6 * s.P_unit)


def test_w_and_lambda_together_are_ambiguous():
    with pytest.raises(ParameterError):
        get_contact_model("md", W=0.1, lam=1.0)
