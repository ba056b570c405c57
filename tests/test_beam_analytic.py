"""Analytic beam references (lumped/beam.py): limits, independent solutions, known constants."""

import math

import numpy as np
import pytest
import scipy.linalg as sla

from probedyn.core.errors import ParameterError
from probedyn.lumped import beam as B
from beam_reference import timoshenko_roots_transfer

SI = dict(E=169e9, nu=0.0, rho=2330.0)


def default_beam(**kw):
    p = dict(L=300e-6, w=30e-6, t=10e-6, **SI)
    p.update(kw)
    return B.RectBeam(**p)


def test_eb_roots_match_tabulated_and_asymptotic():
    # Tabulated clamped-free roots (Blevins, Formulas for natural frequency, table 8-1), 6 digits.
    r = B.eb_roots(6)
    assert np.allclose(r[:4], [1.875104, 4.694091, 7.854757, 10.995541], atol=2e-6)
    # asymptotically (2n-1) pi / 2 with an error ~ 2 e^{-bL}
    n = np.arange(1, 7)
    assert np.all(np.abs(r[2:] - (2 * n[2:] - 1) * math.pi / 2) < 3 * np.exp(-r[2:]))


def test_timoshenko_closed_form_equals_transfer_matrix():
    # Two independent evaluations: Huang's closed-form equation and expm of the Timoshenko ODEs.
    # Both are root solves to ~1e-14; 1e-9 leaves room for the expm rounding on high modes.
    for beam in (default_beam(), default_beam(nu=0.28), default_beam(t=40e-6)):
        for d in ("flapwise", "lateral"):
            a = B.timoshenko_roots(beam, d, 4)
            b = timoshenko_roots_transfer(beam, d, 4)
            assert np.allclose(a, b, rtol=1e-9), (d, a, b)


def test_timoshenko_tends_to_euler_bernoulli_quadratically():
    # Shear and rotary inertia lower the frequency by O((t/L)^2): the gap vanishes as t/L -> 0
    # and halving t/L divides it by 4 (within 2 %, the next term being O((t/L)^4)).
    gaps = []
    for t in (8e-6, 4e-6, 2e-6, 1e-6):
        beam = default_beam(t=t)
        eb = B.eb_frequencies(beam, "flapwise", 2)
        ti = B.timoshenko_frequencies(beam, "flapwise", 2)
        assert np.all(ti < eb)
        gaps.append(1 - ti / eb)
    gaps = np.array(gaps)
    ratio = gaps[:-1] / gaps[1:]
    assert np.allclose(ratio, 4.0, rtol=0.02), ratio
    assert gaps[-1, 0] < 1e-5


def test_timoshenko_shear_dominates_rotary_inertia():
    # To first order the Timoshenko gap is a sum of a rotary-inertia part ~ r^2 and a shear part
    # ~ s^2 = r^2 E/(kappa G) (= 2.4 r^2 for nu = 0). For a simply supported beam both have the
    # same coefficient, so the full gap would be 3.4x the rotary-only gap; for clamped-free the
    # coefficients differ by O(10 %), hence the band. Removing shear (kappa -> inf) isolates
    # the rotary-inertia part.
    beam = default_beam(t=20e-6)
    eb = B.eb_frequencies(beam, "flapwise", 1)[0]
    full = B.timoshenko_frequencies(beam, "flapwise", 1)[0]
    rot_only = B.timoshenko_frequencies(B.RectBeam(**{**beam.__dict__, "kappa": 1e12}), "flapwise", 1)[0]
    assert 2.9 < (eb - full) / (eb - rot_only) < 3.9


def test_cowper_kappa():
    assert B.cowper_kappa(0.0) == pytest.approx(5 / 6)
    assert B.cowper_kappa(0.3) == pytest.approx(13 / 15.3)


def test_torsion_constant_series_limits():
    # Square: J = 0.1406 a^4 (Timoshenko & Goodier table, 4 digits); thin strip -> a b^3 / 3.
    assert B.torsion_constant_rect(1.0, 1.0) == pytest.approx(0.1406, abs=1e-4)
    assert B.torsion_constant_rect(2.0, 1.0) == pytest.approx(0.229 * 2, rel=2e-3)
    assert B.torsion_constant_rect(100.0, 1.0) / (100 / 3) == pytest.approx(1 - 0.630 / 100, abs=1e-4)


def test_torsion_constant_against_prandtl_fem():
    # Independent: Prandtl stress function laplace(phi) = -2, phi = 0 on the boundary, J = 2 int phi,
    # P2 triangles on the 3:1 section. P2 energy error ~ h^4 on a smooth solution (the corner
    # singularities are mild for the stress function), so 4 refinements agree to < 1e-3.
    import skfem
    from skfem.helpers import dot, grad

    a, b = 3.0, 1.0
    m = skfem.MeshTri.init_tensor(np.linspace(0, a, 13), np.linspace(0, b, 5)).refined(3)
    basis = skfem.Basis(m, skfem.ElementTriP2())

    @skfem.BilinearForm
    def lap(u, v, w):
        return dot(grad(u), grad(v))

    @skfem.LinearForm
    def rhs(v, w):
        return 2.0 * v

    A = lap.assemble(basis)
    f = rhs.assemble(basis)
    phi = skfem.solve(*skfem.condense(A, f, D=basis.get_dofs()))
    J_fem = 2.0 * f @ phi / 2.0  # int phi dA = (1/2) f . phi since f = int 2 v
    assert B.torsion_constant_rect(a, b) == pytest.approx(J_fem, rel=1e-3)


def test_static_stiffness_shear_correction():
    beam = default_beam()
    I = beam.w * beam.t**3 / 12
    assert B.static_tip_stiffness(beam, shear=False) == pytest.approx(3 * beam.E * I / beam.L**3, rel=1e-14)
    ks = B.static_tip_stiffness(beam)
    # series compliance: k_eb / k = 1 + 3 EI / (kappa G A L^2)
    corr = 3 * beam.E * I / (beam.k_shear * beam.G * beam.A * beam.L**2)
    assert B.static_tip_stiffness(beam, shear=False) / ks == pytest.approx(1 + corr, rel=1e-14)


def test_axial_and_torsion_formulas():
    beam = default_beam()
    fa = B.axial_frequencies(beam, 2)
    assert fa[0] == pytest.approx(math.sqrt(beam.E / beam.rho) / (4 * beam.L))
    assert fa[1] / fa[0] == pytest.approx(3.0)
    ft = B.torsion_frequencies(beam, 2)
    assert ft[1] / ft[0] == pytest.approx(3.0)


# ---------------------------------------------------------------------------- tip mass (3.10)


def test_tip_mass_zero_mass_is_clamped_free():
    for form in ("standard", "printed"):
        r = B.tip_mass_roots(0.0, 3, form)
        assert np.allclose(r, B.eb_roots(3), rtol=1e-12)
        r = B.tip_mass_roots(1e-9, 1, form)
        assert r[0] == pytest.approx(1.8751, abs=1e-4)


def test_tip_mass_heavy_mass_is_spring_mass():
    # m >> rho A L: the beam is a massless spring 3EI/L^3 carrying m; the beam mass adds 33/140
    # of itself (Rayleigh), a relative correction 33/140/ratio on omega^2.
    beam = default_beam()
    for ratio in (1e3, 1e5):
        m = ratio * beam.mass
        f = B.tip_mass_frequencies(beam, "flapwise", m, 1)[0]
        k = B.static_tip_stiffness(beam, shear=False)
        f_sm = math.sqrt(k / m) / (2 * math.pi)
        f_rayleigh = math.sqrt(k / (m + 33 / 140 * beam.mass)) / (2 * math.pi)
        assert f < f_sm
        assert f == pytest.approx(f_rayleigh, rel=1e-3 / ratio)
        assert f == pytest.approx(f_sm, rel=0.15 / ratio)


def test_tip_mass_source_notes_values():
    # departure 1: m/(rho A L) = 1 -> printed form 1.423, standard form 1.248.
    assert B.tip_mass_roots(1.0, 1, "printed")[0] == pytest.approx(1.423, abs=5e-4)
    assert B.tip_mass_roots(1.0, 1, "standard")[0] == pytest.approx(1.248, abs=5e-4)
    # printed form, heavy mass: tan x = tanh x (a pinned tip), not a spring-mass system
    assert B.tip_mass_roots(1e8, 1, "printed")[0] == pytest.approx(3.926602, abs=1e-5)


def _hermite_beam_tip_mass(n_el, ratio, n_modes):
    """Independent reference: cubic Hermite beam elements (EI = rho A = L = 1) + tip point mass."""
    h = 1.0 / n_el
    ke = np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                   [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]) / h**3
    me = h / 420 * np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                             [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    nd = 2 * (n_el + 1)
    K = np.zeros((nd, nd))
    M = np.zeros((nd, nd))
    for e in range(n_el):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += ke
        M[s, s] += me
    M[-2, -2] += ratio
    w2 = sla.eigh(K[2:, 2:], M[2:, 2:], eigvals_only=True)[:n_modes]
    return w2 ** 0.25  # lambda L with L = 1


@pytest.mark.parametrize("ratio", [0.2, 1.0, 5.0])
def test_tip_mass_standard_form_matches_beam_fe(ratio):
    # Hermite elements converge as h^4 in frequency; 60 elements -> < 1e-7 on the first 3 roots.
    fe = _hermite_beam_tip_mass(60, ratio, 3)
    std = B.tip_mass_roots(ratio, 3, "standard")
    printed = B.tip_mass_roots(ratio, 3, "printed")
    assert np.allclose(std, fe, rtol=1e-6)
    assert abs(printed[0] / fe[0] - 1) > 0.05  # the printed form is visibly wrong


# ---------------------------------------------------------------------------- Rayleigh (2.46)


def test_rayleigh_quotient_exact_modes():
    # On an exact mode the quotient is the eigenvalue; the quintic spline on 200 samples is
    # accurate to ~h^4 in Y'' -> 1e-6 relative is a loose bound.
    L = 2.0
    x = np.linspace(0, L, 200)
    for bL in B.eb_roots(3):
        w2 = B.rayleigh_quotient(x, B.eb_mode_shape(x, bL, L), 3.0, 1.5)
        assert w2 == pytest.approx(bL**4 / L**4 * 3.0 / 1.5, rel=1e-6)


def test_rayleigh_quotient_static_shape_upper_bound():
    # Static end-load shape x^2 (3L - x): exact quotient 140/11 EI/(m L^4) > 1.8751^4.
    x = np.random.default_rng(0).uniform(0, 1, 300)
    x = np.concatenate([[0.0, 1.0], x])
    w2 = B.rayleigh_quotient(x, x**2 * (3 - x), 1.0, 1.0)
    assert w2 == pytest.approx(140 / 11, rel=1e-9)
    assert w2 > B.eb_roots(1)[0] ** 4


def test_eb_mode_tip_effective_mass_is_quarter():
    # int phi^2 dx = L and |phi(L)| = 2 for every clamped-free mode -> m_eff(tip) = rho A L / 4.
    from scipy.integrate import quad

    for bL in B.eb_roots(4):
        I = quad(lambda s: B.eb_mode_shape(s, bL, 1.0) ** 2, 0, 1, limit=200)[0]
        assert I / B.eb_mode_shape(1.0, bL, 1.0) ** 2 == pytest.approx(0.25, rel=1e-9)


def test_bad_beam_input():
    with pytest.raises(ParameterError):
        default_beam(L=0.0)
    with pytest.raises(ParameterError):
        default_beam(nu=0.5)
    with pytest.raises(ParameterError):
        B.tip_mass_roots(-1.0, 1)
