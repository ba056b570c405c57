"""Prandtl–Tomlinson: lattice period, the eta = 1 transition, quasi-static balance, 2D zigzag."""

import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes import ffm as F
from probedyn.schemes.friction.prandtl_tomlinson import (MICA_LATTICE, PrandtlTomlinson, lattice_sites,
                                                         pt2d_scan)
from probedyn.schemes.stickslip_analysis import analyze

A = MICA_LATTICE
K = 0.2  # Table 2.1 k_x


def _scan(eta, n=10, rtol=1e-5):
    U0 = eta * K * A * A / (4 * math.pi**2)
    ffm = F.FFM.from_preset("mica", "pt", {"U0": U0})
    return ffm, F.line_scan(ffm, n * A, rtol=rtol)


@pytest.mark.parametrize("eta", [1.5, 4.0])
def test_stick_slip_at_the_lattice_period(eta):
    """eta > 1: one slip per lattice site, period = a (the 1 % of the issue; the analysis grid
    spacing is 5e-4 a)."""
    _, r = _scan(eta)
    an = analyze(r.base, r.lateral_force)
    assert an["regime"] == "regular"
    assert an["n_slips"] >= 8
    assert an["period_m"] == pytest.approx(A, rel=0.01)


@pytest.mark.parametrize("eta", [0.5, 0.8])
def test_smooth_sliding_below_eta_one(eta):
    """eta < 1: a single energy minimum for every base position, continuous force; the
    steepest |dF/dX| over the median stays near the quasi-static value (1 + eta)/(1 - eta)
    (within a factor 1.5: the median is not exactly the loading slope) and far below the
    stick-slip threshold."""
    _, r = _scan(eta)
    an = analyze(r.base, r.lateral_force)
    assert an["regime"] == "smooth"
    qs = (1 + eta) / (1 - eta)
    assert qs / 1.5 < an["abruptness"] < 1.5 * qs


def test_smooth_sliding_matches_the_massless_reduced_model():
    """Independent check: with m_x -> 0 (singular perturbation; inertia m x'' ~ 1e-24 N at
    2 um/s) (2.13) becomes the first-order ODE c (V - x') + k (V t - x) = F0 sin(2 pi x / a),
    solved here by scipy Radau. The lateral forces agree to 1e-3 F0; the quasi-static curve
    without the dashpot term c_x V ~ 1.4e-14 N = 0.14 % F0 does not (so the test can fail)."""
    from scipy.integrate import solve_ivp

    eta = 0.6
    ffm, r = _scan(eta, n=4, rtol=1e-8)
    F0 = 2 * math.pi * ffm.friction.values["U0"] / A
    q = 2 * math.pi / A
    c, V = ffm.cantilever["c_x"], ffm.cantilever["V"]
    sol = solve_ivp(lambda t, x: V + (K * (V * t - x) - F0 * np.sin(q * x)) / c, (0, r.t[-1]), [0.0],
                    method="Radau", jac=lambda t, x: [[(-K - F0 * q * np.cos(q * x[0])) / c]],
                    rtol=1e-10, atol=1e-20, dense_output=True)
    x_red = sol.sol(r.t)[0]
    F_red = K * (r.base - x_red)
    assert np.max(np.abs(r.lateral_force - F_red)) < 1e-3 * F0
    xs = np.linspace(-A, 5 * A, 200001)
    x_static = np.interp(r.base, xs + F0 * np.sin(q * xs) / K, xs)
    assert np.max(np.abs(r.lateral_force - K * (r.base - x_static))) > 1e-3 * F0


def test_transition_is_at_eta_one():
    """Abruptness jumps across eta = 1: finite (1+eta)/(1-eta) below, sampling-limited above."""
    below = analyze(*(lambda r: (r.base, r.lateral_force))(_scan(0.9)[1]))
    above = analyze(*(lambda r: (r.base, r.lateral_force))(_scan(1.2)[1]))
    assert below["regime"] == "smooth" and above["regime"] == "regular"
    assert above["abruptness"] > 10 * below["abruptness"]


def test_from_eta_and_eta_roundtrip():
    m = PrandtlTomlinson.from_eta(2.5, K)
    assert m.eta(K) == pytest.approx(2.5)
    with pytest.raises(ParameterError):
        PrandtlTomlinson.from_eta(-1.0, K)
    with pytest.raises(ParameterError):
        PrandtlTomlinson(a=-1e-10)


@pytest.mark.parametrize("lattice", ["square", "hex"])
def test_2d_on_axis_scan_stays_on_the_axis_with_site_to_site_slips(lattice):
    """Scanning along a1 through a row of sites: y stays 0 (symmetry), the tip sticks near
    lattice sites and advances by a per slip."""
    r = pt2d_scan(lattice, eta=4.0, angle_deg=0.0, length=8 * A, zeta=1.0)  # no ringing after slips
    assert np.max(np.abs(r.tip[1])) < 1e-6 * A
    an = analyze(r.scan_distance, r.force[0])
    assert an["period_m"] == pytest.approx(A, rel=0.01)


def test_2d_zigzag_off_the_lattice_axis():
    """Scanning 15 deg off a1 on the hexagonal lattice: the tip dwells at lattice sites (the
    potential minima) and hops between rows, a zigzag around the scan line: it visits sites of
    at least two rows, never strays more than a from the scan line, and most of the time sits
    within 0.25 a of a site."""
    ang = 15.0
    r = pt2d_scan("hex", eta=4.0, angle_deg=ang, length=12 * A)
    sites = lattice_sites("hex", A, (-2 * A, 14 * A), (-3 * A, 6 * A))
    d = np.min(np.hypot(r.tip[0][:, None] - sites[:, 0][None], r.tip[1][:, None] - sites[:, 1][None]), axis=1)
    assert np.mean(d < 0.25 * A) > 0.7
    rows = np.unique(np.round(r.tip[1][d < 0.25 * A] / (math.sqrt(3) / 2 * A)))
    assert rows.size >= 2
    th = math.radians(ang)
    perp = -r.tip[0] * math.sin(th) + r.tip[1] * math.cos(th)
    assert np.max(np.abs(perp)) < A
    # the zigzag: the perpendicular offset changes sign along the scan
    assert perp.min() < -0.1 * A and perp.max() > 0.1 * A


def test_thermal_noise_is_reproducible_and_lowers_the_slip_force():
    """Langevin force with a fixed seed: same seed -> same trace; at 300 K thermal activation
    lets the tip slip before the athermal instability, so the mean peak force is lower
    (thermolubricity; eta = 2, U0 ~ 8e-21 J = 2 k_B T)."""
    kw = dict(lattice="square", eta=2.0, angle_deg=0.0, length=6 * A)
    r1 = pt2d_scan(temperature=300.0, seed=3, **kw)
    r2 = pt2d_scan(temperature=300.0, seed=3, **kw)
    assert np.array_equal(r1.force, r2.force)
    r0 = pt2d_scan(temperature=0.0, **kw)
    p0 = analyze(r0.scan_distance, r0.force[0])["static_friction_n"]
    n = 200  # smooth the thermal trace before finding peaks
    f1 = np.convolve(r1.force[0], np.ones(n) / n, mode="same")
    p1 = analyze(r1.scan_distance[n:-n], f1[n:-n], noise=None)["static_friction_n"]
    assert p1 < p0


def test_pt2d_rejects_bad_input():
    with pytest.raises(ParameterError, match="lattice"):
        pt2d_scan("kagome")
    with pytest.raises(ParameterError, match="eta"):
        pt2d_scan("hex", eta=-1)
    with pytest.raises(ParameterError, match="temperature"):
        pt2d_scan("hex", temperature=-5)
