"""Adhesion–friction coupling (section 2.2.4): the contact -> friction link, the stick-slip
measures, and the claim of the source checked with FFM scans."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes.coupling import CouplingSetup, contact_at, scan_metrics

sys.path.insert(0, str(Path(__file__).parent))
from ffm_reference import MICA_LATTICE, MICA_X, pt_scan, reference_scan  # noqa: E402  (independent solvers)


def test_no_adhesion_gives_hertz_and_unit_scale():
    c = contact_at(0.0, CouplingSetup())
    assert c["W"] == 0 and c["pull_off"] == 0
    assert c["radius"] == pytest.approx(c["radius_hertz"], rel=1e-12)
    assert c["scale"] == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("law", ["area", "load"])
def test_friction_scale_grows_with_adhesion(law):
    s = CouplingSetup(law=law, lams=(0.0, 0.1, 0.3, 1.0, 3.0))
    rows = [contact_at(l, s) for l in s.lams]
    assert np.all(np.diff([r["W"] for r in rows]) > 0)
    assert np.all(np.diff([-r["pull_off"] for r in rows]) > 0)
    assert np.all(np.diff([r["scale"] for r in rows]) > 0)


def test_area_law_matches_jkr_contact_radius_at_large_lambda():
    # lam = 300: MD is JKR to O(1/lam^2); JKR radius under load L:
    # a^3 = R/K (L + 3 pi W R + sqrt(6 pi W R L + (3 pi W R)^2))
    from probedyn.schemes.contact import MaugisDugdale

    s = CouplingSetup()
    c = contact_at(300.0, s)
    sc = MaugisDugdale(lam=300.0, **s.contact).scales
    q = 3 * math.pi * sc.W * sc.R
    a3 = sc.R / sc.K * (s.load + q + math.sqrt(2 * q * s.load + q * q))
    assert c["radius"] == pytest.approx(a3 ** (1 / 3), rel=1e-3)


def test_load_law_is_derjaguin_two_term():
    s = CouplingSetup(law="load")
    c = contact_at(1.0, s)
    assert c["scale"] == pytest.approx(1.0 - c["pull_off"] / s.load, rel=1e-14)


def test_scan_metrics_on_an_exact_sawtooth():
    # ramp 0 -> Fs over x1, then a sawtooth Fc -> Fs with period p (instant slips)
    Fs, Fc, x1, p = 13e-9, 12e-9, 65e-9, 5e-9
    x = np.linspace(0, x1 + 8.5 * p, 200001)
    dx = x[1] - x[0]
    F = np.where(x < x1, Fs * x / x1, Fc + (Fs - Fc) * (((x - x1) / p) % 1.0))
    F[x >= x1] = np.where(((x[x >= x1] - x1) / p) % 1.0 < 1e-12, Fc, F[x >= x1])
    m = scan_metrics(x, F)
    assert m["first_stick_m"] == pytest.approx(x1, abs=2 * dx)
    assert m["period_m"] == pytest.approx(p, abs=2 * dx)
    assert m["peak_n"] == pytest.approx(Fs, rel=1e-3)
    assert m["valley_n"] == pytest.approx(Fc, rel=1e-3)
    # mean over whole periods of a linear sawtooth is (Fs + Fc)/2; 8.5 periods -> the half
    # period at the end biases it by at most (Fs - Fc) / (2 * 8.5)
    assert abs(m["mean_friction_n"] - 0.5 * (Fs + Fc)) < (Fs - Fc) / 17
    assert m["n_slips"] == 9


def test_scan_metrics_smooth_sliding_has_no_slips():
    x = np.linspace(0, 1e-7, 1000)
    F = 1e-9 * (1 - np.exp(-x / 1e-8))
    m = scan_metrics(x, F)
    assert m["n_slips"] == 0 and math.isnan(m["period_m"])


@pytest.mark.parametrize("kw", [dict(load=-1e-9), dict(speed=0.0), dict(law="magic"), dict(lams=(0.1, -1.0))])
def test_bad_setup_raises(kw):
    with pytest.raises(ParameterError):
        CouplingSetup(**kw).validate()


# ---------------------------------------------------------------- FFM scans
def test_reference_scan_mica_levels_and_first_stick():
    # 1D reduction of 2.13-2.15 with 2.7-2.9 (docs/source-departures.md item 11): the spring force rises with
    # slope ~k_x until friction reaches F_s, so the first slip comes after F_s / k_x = 64.75 nm;
    # then a sawtooth between ~F_c and ~F_s. Stribeck at V/(2 V_s) = 0.1 lowers the peak by
    # (F_s - F_c)(1 - e^-0.01) = 0.005 nN (0.04 %); the tolerances are a few times that.
    Fs, Fc, k = MICA_X["Fs"], MICA_X["Fc"], MICA_X["k"]
    r = reference_scan(Fs / k + 4 * (Fs - Fc) / k, n_out=3000)
    m = scan_metrics(r["base"], r["spring_force"])
    dx = r["base"][1] - r["base"][0]
    assert m["first_stick_m"] == pytest.approx(Fs / k, abs=0.002 * Fs / k + 2 * dx)
    assert m["peak_n"] == pytest.approx(Fs, rel=2e-3)
    assert m["valley_n"] == pytest.approx(Fc, rel=2e-3)
    # during a stick the spring force climbs from the valley to the peak at slope ~k_x:
    # period = (peak - valley) / k_x within the sampling resolution
    assert m["period_m"] == pytest.approx((m["peak_n"] - m["valley_n"]) / k, abs=3 * dx)


def test_friction_scale_rescales_lengths_in_the_bristle_model():
    # inertia and damping are negligible on the stick time scale, so multiplying F_s and F_c
    # by f multiplies the first stick and the period by f (to the sampling resolution)
    Fs, Fc, k = MICA_X["Fs"], MICA_X["Fc"], MICA_X["k"]
    L = Fs / k + 3 * (Fs - Fc) / k
    out = []
    for f in (1.0, 2.5):
        r = reference_scan(L * f, scale=f, n_out=2000)
        out.append(scan_metrics(r["base"], r["spring_force"]))
    dx = L / 2000
    assert out[1]["first_stick_m"] == pytest.approx(2.5 * out[0]["first_stick_m"], abs=2.5 * 2 * dx)
    assert out[1]["period_m"] == pytest.approx(2.5 * out[0]["period_m"], abs=2.5 * 3 * dx)


def test_prandtl_tomlinson_period_is_the_lattice_when_critically_damped():
    # eta > 1: stick-slip; with critical damping each slip ends in the next well, so the
    # period is the lattice constant. Sampling: 6000 points over ~16 a -> 0.3 % of a per sample;
    # 1 % tolerance (the PT criterion).
    a = MICA_LATTICE

    for eta in (3.0, 45.0):
        r = pt_scan(eta, eta * a / (2 * math.pi) + 10 * a, zeta=1.0)
        m = scan_metrics(r["base"], r["spring_force"])
        assert m["period_m"] == pytest.approx(a, rel=0.01)
        # the first slip needs the spring to reach the maximum lateral force 2 pi U0 / a
        # = eta k a / (2 pi) (for eta >> 1 the tip barely moves before it): first stick ~ eta a / 2 pi
        if eta > 10:
            assert m["first_stick_m"] == pytest.approx(eta * a / (2 * math.pi), rel=0.05)


def test_prandtl_tomlinson_underdamped_skips_sites_at_high_eta():
    # underdamped (zeta = 0.1), eta = 45: the tip overshoots several wells per slip; the period
    # is then an integer multiple (> 1) of the lattice constant
    a = MICA_LATTICE

    r = pt_scan(45.0, 45 * a / (2 * math.pi) + 55 * a, zeta=0.1)
    m = scan_metrics(r["base"], r["spring_force"])
    ratio = m["period_m"] / a
    assert ratio > 1.5
    assert ratio == pytest.approx(round(ratio), abs=0.02)


# ---------------------------------------------------------------- the project's FFM vs the references
@pytest.mark.parametrize("f", [1.0, 4.0])
def test_project_ffm_agrees_with_the_independent_reference_scan(f):
    # same ODE (2.7-2.9, 2.13, 2.15), two integrators (numba Rosenbrock 2(3) vs scipy BDF) with
    # relative tolerances 1e-5 / 1e-7: levels agree to ~1e-5, slip positions to the sampling
    from probedyn.schemes.coupling import ffm_scan

    L = f * (MICA_X["Fs"] / MICA_X["k"] + 4 * (MICA_X["Fs"] - MICA_X["Fc"]) / MICA_X["k"])
    s = ffm_scan(L, 2e-6, f, n_out=3000)
    a = scan_metrics(s["base"], s["spring_force"])
    r = reference_scan(L, scale=f, n_out=3000)
    b = scan_metrics(r["base"], r["spring_force"])
    dx = L / 3000
    assert a["first_stick_m"] == pytest.approx(b["first_stick_m"], abs=2 * dx)
    assert a["period_m"] == pytest.approx(b["period_m"], abs=2 * dx)
    for key in ("mean_friction_n", "peak_n", "valley_n"):
        assert a[key] == pytest.approx(b[key], rel=1e-4)


def test_project_pt_agrees_with_the_independent_pt_scan():
    from probedyn.schemes.coupling import ffm_pt_scan

    a = MICA_LATTICE

    L = 14 * a / (2 * math.pi) + 15 * a
    s = ffm_pt_scan(14.0, L, zeta=0.1)
    m1 = scan_metrics(s["base"], s["spring_force"])
    r = pt_scan(14.0, L, zeta=0.1)
    m2 = scan_metrics(r["base"], r["spring_force"])
    assert m1["period_m"] == pytest.approx(m2["period_m"], rel=1e-3)
    assert m1["first_stick_m"] == pytest.approx(m2["first_stick_m"], rel=1e-3)


def test_claim_first_stick_and_period_grow_with_adhesion_as_a_rescaling():
    # the study itself on three lambdas: both lengths grow; lengths / f constant within the
    # sampling of the period (4000 points over ~first stick + 12 periods: < 2 %)
    from probedyn.schemes.coupling import run, verdict

    res = run(CouplingSetup(lams=(0.0, 0.3, 1.0), n_periods=4))
    v = verdict(res["rows"])
    assert v["first_stick_increases"] and v["period_increases"]
    assert v["first_over_scale_spread"] < 0.01
    assert v["period_over_scale_spread"] < 0.02
