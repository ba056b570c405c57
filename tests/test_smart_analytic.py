"""Analytic references of the smart probes (lumped/smart_analytic.py): limit cases and
independent evaluations, no FEM."""

import math

import numpy as np
import pytest

from probedyn.core.errors import GeometryError
from probedyn.lumped.beam import tip_mass_roots
from probedyn.lumped.smart_analytic import (
    DuoBimorphBeam, EccentricSection, Piezotube, end_body_frequencies, rayleigh_end_mass_frequency,
    rigid_body_properties, tip_mass_beam_frequencies,
)

B = DuoBimorphBeam(300e-6, 30e-6, 10e-6, 7800.0, 16.5e-12)


def test_corrected_318_is_dimensionally_the_beam_formula():
    # (3.18) corrected: sqrt(h^2/(12 rho s11)) must equal sqrt(EI/(rho A)) with EI = w h^3/(12 s11)
    for d, EI in (("z", B.w * B.h**3 / 12 / B.s11), ("y", B.h * B.w**3 / 12 / B.s11)):
        assert B.omega_scale(d) == pytest.approx(math.sqrt(EI / (B.rho * B.A)), rel=1e-14)


def test_no_end_mass_gives_clamped_free_roots():
    # lambda_1 L = 1.87510407 (1 + cos cosh = 0), to the digits of the classical root
    f = B.frequencies("z", 0.0, 2)
    x = np.sqrt(2 * math.pi * f / B.omega_scale("z")) * B.L
    assert x[0] == pytest.approx(1.87510407, rel=1e-7)
    assert x[1] == pytest.approx(4.69409113, rel=1e-7)


def test_heavy_end_mass_limit_is_spring_mass():
    # mu = m/(rho A L) = 1e4: Rayleigh k/(m + 33/140 m_b) is exact to O(1/mu^2)
    m = 1e4 * B.mass
    f = B.frequencies("y", m, 1)[0]
    assert f == pytest.approx(B.rayleigh_frequency("y", m), rel=1e-6)


def test_source_notes_item1_numbers():
    # departure 1: for m/(rho A L) = 1 the FE beam gives bL = 1.248, the printed form 1.423
    assert tip_mass_roots(1.0, 1, "standard")[0] == pytest.approx(1.248, abs=1e-3)
    assert tip_mass_roots(1.0, 1, "printed")[0] == pytest.approx(1.423, abs=1e-3)


def test_thin_wall_vs_exact_annulus():
    t = Piezotube(0.5e-3, 0.3e-3, 5e-3, 7800.0, 16.5e-12)
    wall, R = t.Re - t.Ri, t.R_mean
    assert t.I(True) / t.I(False) == pytest.approx(1 + wall**2 / (4 * R**2), rel=1e-13)
    f_ex, f_th = t.lateral_frequencies(0.0, 1, True)[0], t.lateral_frequencies(0.0, 1, False)[0]
    assert f_ex / f_th == pytest.approx(math.sqrt(1 + wall**2 / (4 * R**2)), rel=1e-12)


def test_axial_with_holder_mass_limits_and_equation():
    t = Piezotube(0.5e-3, 0.45e-3, 5e-3, 7800.0, 16.5e-12)
    a = t.bar_speed
    # m_h -> 0: quarter-wave rod
    f0 = t.axial_frequencies(1e-12 * t.mass, 2)
    assert f0 * 2 * math.pi * t.L / a == pytest.approx([math.pi / 2, 3 * math.pi / 2], rel=1e-6)
    # m_h -> inf: spring (A / (s11 L)) with mass m_h + m_rod / 3
    m = 1e4 * t.mass
    k = t.A / (t.s11 * t.L)
    assert t.axial_frequencies(m, 1)[0] == pytest.approx(math.sqrt(k / (m + t.mass / 3)) / (2 * math.pi), rel=1e-6)
    # the roots satisfy beta tan beta = rho A L / m_h
    m = 2e-5
    beta = t.axial_frequencies(m, 3) * 2 * math.pi * t.L / a
    assert beta * np.tan(beta) == pytest.approx(np.full(3, t.mass / m), rel=1e-9)


def test_eccentric_section_against_grid_integration():
    Re, Ri, dy, dz = 1.0, 0.8, 0.06, 0.03
    sec = EccentricSection(Re, Ri, dy, dz)
    w, v = sec.second_moments()
    n = 2001
    y, z = np.meshgrid(np.linspace(-Re, Re, n), np.linspace(-Re, Re, n), indexing="ij")
    inside = (y**2 + z**2 <= Re**2) & ((y - dy) ** 2 + (z - dz) ** 2 > Ri**2)
    dA = (2 * Re / (n - 1)) ** 2
    A = inside.sum() * dA
    cy, cz = (y[inside].sum() * dA / A, z[inside].sum() * dA / A)
    Y, Z = y[inside] - cy, z[inside] - cz
    J = np.array([[np.sum(Y * Y), np.sum(Y * Z)], [np.sum(Y * Z), np.sum(Z * Z)]]) * dA
    wg = np.linalg.eigvalsh(J)
    # grid quadrature of a disc boundary: relative error ~ h / R = 1e-3
    assert wg == pytest.approx(w, rel=3e-3)
    assert sec.lower_mode_angle_deg() == pytest.approx(math.degrees(math.atan2(dz, dy)), abs=1e-9)
    assert abs(abs(v[:, 0] @ np.array([dy, dz]) / math.hypot(dy, dz)) - 1) < 1e-12


def test_end_body_exact_static_limit():
    # massless beam + rigid body (J = 0) at offset e: omega^2 = 1 / (m * delta), with the
    # exact load-point compliance delta = (L^3/3 + e L^2 + e^2 L) / EI
    EI, L, m, e = 2.0, 1.5, 3.0, 0.4
    f = end_body_frequencies(EI, 1e-12, L, m, e, 0.0)[0]
    delta = (L**3 / 3 + e * L**2 + e * e * L) / EI
    assert f == pytest.approx(math.sqrt(1 / (m * delta)) / (2 * math.pi), rel=1e-9)
    # e = J = 0: the transcendental tip-mass equation (heavy mass: the one-element mass is exact)
    f1 = end_body_frequencies(EI, 1.0, L, 100.0)[0]
    assert f1 == pytest.approx(tip_mass_beam_frequencies(EI, 1.0, L, 100.0, 1)[0], rel=1e-4)


def test_rigid_body_properties_of_a_box():
    from skfem import MeshTet

    a, b, c = 2.0, 1.0, 0.5
    m = MeshTet.init_tensor(np.linspace(0, a, 3), np.linspace(0, b, 4), np.linspace(0, c, 2))
    mass, com, J = rigid_body_properties(m.p, m.t, np.full(m.t.shape[1], 3.0))
    M = 3.0 * a * b * c
    assert mass == pytest.approx(M, rel=1e-13)
    assert com == pytest.approx([a / 2, b / 2, c / 2], rel=1e-13)
    assert np.diag(J) == pytest.approx([M * (b * b + c * c) / 12, M * (a * a + c * c) / 12, M * (a * a + b * b) / 12], rel=1e-12)
    assert np.abs(J - np.diag(np.diag(J))).max() < 1e-12 * M


def test_rayleigh_estimate_textbook_error_without_mass():
    # the 33/140 estimate is 1.5 % high for a bare cantilever (1.8810^2 vs 1.8751^2 ... in omega: +0.6 %)
    f_r = rayleigh_end_mass_frequency(1.0, 1.0, 1.0, 0.0)
    f_e = tip_mass_beam_frequencies(1.0, 1.0, 1.0, 0.0, 1)[0]
    assert f_r / f_e - 1 == pytest.approx(math.sqrt(3 / (33 / 140)) / 1.87510407**2 - 1, rel=1e-6)
    assert 0 < f_r / f_e - 1 < 0.02


def test_bad_tube_raises():
    with pytest.raises(GeometryError):
        Piezotube(0.5e-3, 0.5e-3, 5e-3, 7800.0, 16.5e-12)


def test_end_body_mode_referred_to_a_point():
    """Heavy end mass at the end (e = J = 0): the first mode is the static cubic, so the
    referred mass is m + 33/140 m_beam and the stiffness 3 EI / L^3 (to O(m_beam/m));
    referring to a point x_ref beyond the end scales M by (w / (w + x_ref theta))^2 with
    theta = 3 w / (2 L) for the static shape."""
    from probedyn.lumped.smart_analytic import end_body_first_mode_at

    EI, rA, L, m = 2.0, 1.0, 1.0, 1e4
    M, k = end_body_first_mode_at(EI, rA, L, m, 0.0, 0.0, 0.0)
    assert M == pytest.approx(m + 33 / 140 * rA * L, rel=1e-6)
    assert k == pytest.approx(3 * EI / L**3, rel=1e-4)
    M2, k2 = end_body_first_mode_at(EI, rA, L, m, 0.0, 0.0, 0.2)
    assert M2 / M == pytest.approx(1 / (1 + 0.2 * 1.5 / L) ** 2, rel=1e-4)
    assert k2 / M2 == pytest.approx(k / M, rel=1e-12)  # same frequency
