"""The rarefied gas of the modal diagnosis (:mod:`probedyn.diagnose.hydrodynamics`): the free-molecular damping of a
plate checked against the momentum fluxes integrated over the Maxwell distribution, and the slip interpolation's
limits."""

from __future__ import annotations

import math

import pytest
from scipy.constants import N_A, R, k
from scipy.integrate import quad

from probedyn.diagnose.hydrodynamics import M_AIR, free_molecular_damping, rarefied_factor


def _normal_drag_by_quadrature(p, T, M, v):
    """Net force per unit area on a plate moving at ``v`` normal to itself through a gas at rest: the struck
    molecules' momentum flux, integrated over the 1D Maxwell distribution of the normal velocity, plus that of the
    same number re-emitted diffusely (half-Maxwellian flux at the plate's temperature, moving with the plate), on
    the face ahead minus the face behind."""
    m = M / N_A
    n = p / (k * T)
    s = math.sqrt(k * T / m)
    g = lambda u: math.exp(-0.5 * (u / s) ** 2) / (math.sqrt(2 * math.pi) * s)  # noqa: E731
    re = m * math.sqrt(math.pi * k * T / (2 * m))  # momentum per re-emitted molecule (flux-weighted mean)
    ahead_p = n * m * quad(lambda u: (u - v) ** 2 * g(u), -12 * s, v, epsabs=0, epsrel=1e-13)[0]
    ahead_n = n * quad(lambda u: (v - u) * g(u), -12 * s, v, epsabs=0, epsrel=1e-13)[0]
    behind_p = n * m * quad(lambda u: (u - v) ** 2 * g(u), v, 12 * s, epsabs=0, epsrel=1e-13)[0]
    behind_n = n * quad(lambda u: (u - v) * g(u), v, 12 * s, epsabs=0, epsrel=1e-13)[0]
    return (ahead_p + ahead_n * re) - (behind_p + behind_n * re)


@pytest.mark.parametrize("p,T", [(60.0, 295.0), (1.0, 77.0)])
def test_the_free_molecular_damping_is_the_maxwellian_momentum_flux(p, T):
    """``b_n`` is the quadrature's drag over the speed at v = 0.1 m/s (1e-4 of the thermal speed: the linear
    term), within 1e-6; ``b_t`` is the struck molecules' number flux ``n c_bar / 4`` times the molecular mass; both
    proportional to the pressure. Specular reflection would give 8 / (4 + pi) times ``b_n``."""
    v = 0.1
    b_n, b_t = free_molecular_damping(p, T, M_AIR)
    assert b_n == pytest.approx(_normal_drag_by_quadrature(p, T, M_AIR, v) / v, rel=1e-6)
    m = M_AIR / N_A
    c_bar = math.sqrt(8 * k * T / (math.pi * m))
    assert b_t == pytest.approx(p / (k * T) * c_bar / 4 * m, rel=1e-12)
    assert free_molecular_damping(2 * p, T)[0] == pytest.approx(2 * b_n, rel=1e-14)
    # a plate's Q in it (Q = omega rho t / b_n) against Christian's specular formula (pi/2)^(3/2) rho t f sqrt(RT/M)/p
    rho_t, f = 2330.0 * 2e-6, 1e5
    q_specular = (math.pi / 2) ** 1.5 * rho_t * f * math.sqrt(R * T / M_AIR) / p
    assert 2 * math.pi * f * rho_t / b_n == pytest.approx(q_specular * 8 / (4 + math.pi), rel=1e-12)


def test_the_slip_interpolation_has_both_limits():
    """``rarefied_factor(c_fm, c_cont)``: 1 for a continuum (c_fm infinite), the damping's harmonic sum
    ``c_cont * factor = 1 / (1 / c_fm + 1 / c_cont)`` between, -> c_fm / c_cont when rarefied."""
    assert rarefied_factor(math.inf, 3.0) == 1.0
    for c_fm, c_cont in ((1e-6, 1.0), (1.0, 1.0), (50.0, 1.0)):
        assert c_cont * rarefied_factor(c_fm, c_cont) == pytest.approx(1 / (1 / c_fm + 1 / c_cont), rel=1e-14)
    assert rarefied_factor(1e-6, 1.0) == pytest.approx(1e-6, rel=1e-5)
