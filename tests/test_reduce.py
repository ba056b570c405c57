"""lumped.reduce: eqs 3.1-3.3 generalised to FEM modes, checked against beam limits."""

import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.lumped import beam as bm
from probedyn.lumped.reduce import reduce_mode, reduce_modes


@pytest.fixture(scope="module")
def solved():
    from probedyn.probes import get_probe

    p, _ = get_probe("cantilever")
    values = p.resolve({"poisson_ratio": 0.0, "elements_through_thickness": 2})
    return p, values, p.build(values).modes(4)


def _first(result, family):
    return next(m for m in result.modes if m.family == family)


def test_effective_mass_first_flapwise_is_quarter_beam_mass(solved):
    # Euler-Bernoulli: m_eff(tip) = rho A L / 4 exactly (int phi^2 = L, phi(L) = 2). The 3D mode
    # differs by shear and rotary-inertia terms ~ (t/L)^2 (bL)^2 ~ 1e-3 and by the P2 eigenvector
    # error (~1e-4 on this mesh); 1 % bounds both with margin.
    p, values, result = solved
    b = p.beam(values)
    lm = reduce_mode(result, _first(result, "flapwise"))
    assert lm.direction == "z"
    assert lm.mass == pytest.approx(0.25 * b.mass, rel=0.01)
    # k_eff = omega^2 m_eff (3.3); for mode 1 this is (1.8751^4 / 12) / (1/3) = 1.0302 x 3EI/L^3
    assert lm.stiffness == pytest.approx(lm.omega**2 * lm.mass, rel=1e-12)
    k_ratio = bm.eb_roots(1)[0] ** 4 / 12.0
    assert lm.stiffness / bm.static_tip_stiffness(b, shear=False) == pytest.approx(k_ratio, rel=0.01)


def test_lateral_mode_refers_to_y(solved):
    # lateral: same quarter-mass limit; shear/rotary terms ~ (w/L)^2 (bL)^2 ~ 1e-2 -> 3 % bound
    p, values, result = solved
    lm = reduce_mode(result, _first(result, "lateral"))
    assert lm.direction == "y"
    assert lm.mass == pytest.approx(0.25 * p.beam(values).mass, rel=0.03)


def test_quality_factor_damping(solved):
    _, _, result = solved
    for lm in reduce_modes(result, Q=50.0):
        if math.isfinite(lm.mass):
            assert lm.damping == pytest.approx(math.sqrt(lm.stiffness * lm.mass) / 50.0)
            assert lm.damping_ratio == pytest.approx(1 / 100.0)
            assert lm.quality_factor == pytest.approx(50.0)


def test_mu_damping_is_eq_3_2(solved):
    # (3.2)/(3.1): c / M = mu / (rho A) for a beam without point masses.
    p, values, result = solved
    b = p.beam(values)
    mu = 1e-3
    lm = reduce_mode(result, _first(result, "flapwise"), mu=mu, mass_per_length=b.mass_per_length)
    assert lm.damping / lm.mass == pytest.approx(mu / b.mass_per_length, rel=1e-12)


def test_mu_damping_excludes_tip_mass():
    # With a tip mass the distributed damping acts on the beam only: c = (mu/(rho A)) x
    # (phi^T M_beam phi / phi_tip^2). M_beam is assembled independently from the same mesh
    # without the point mass.
    from probedyn.probes import get_probe

    p, _ = get_probe("cantilever")
    v0 = p.resolve({"poisson_ratio": 0.0, "elements_through_thickness": 2})
    b = p.beam(v0)
    values = p.resolve({"poisson_ratio": 0.0, "elements_through_thickness": 2, "tip_mass": b.mass})
    result = p.build(values).modes(1)
    _, M_beam = p.build(v0).assemble()
    m = result.modes[0]
    phi = np.asarray(m.shape)
    expected = float(phi @ (M_beam @ phi)) / m.tip_displacement[2] ** 2
    mu = 2e-3
    lm = reduce_mode(result, m, mu=mu, mass_per_length=b.mass_per_length)
    assert lm.damping == pytest.approx(mu / b.mass_per_length * expected, rel=1e-6)
    assert lm.mass > 1.5 * expected  # the tip mass dominates m_eff


def test_bad_damping_input(solved):
    _, _, result = solved
    m = result.modes[0]
    with pytest.raises(ParameterError):
        reduce_mode(result, m, mu=1.0, Q=10.0)
    with pytest.raises(ParameterError):
        reduce_mode(result, m, Q=0.0)
    with pytest.raises(ParameterError):
        reduce_mode(result, m, mu=1.0)  # no rho A
