"""Vibrational nano-placing (section 4.2): every phase against an independent reference.

Tolerances come from the physics: limit cases of the frequency equation (machine precision),
the FEM discretisation error of a one-layer P2 beam (0.1 % on the first three flapwise modes,
the issue's 0.5 % bar), the fold-passage law of a slow approach (delay ~ v^(2/3) plus a snap
term ~ v), the amplitude nonlinearity of a linearised response (~A/s), and integrator
tolerances. Long studies (full FEM re-solves over the beta range, the 64 x 64 map) are in
tests/test_placing_slow.py.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.lumped import beam as bm
from probedyn.schemes.placing import capture as cap
from probedyn.schemes.placing import landing as ld
from probedyn.schemes.placing import multi as mu
from probedyn.schemes.placing import release as rel
from probedyn.schemes.placing.approach import Approach
from probedyn.schemes.placing.probe import (EQUIV_MASS_RATIO, SILICON_RHO, TABLE, PlacingProbe,
                                            mass_plausibility, table_beam_geometry)


@pytest.fixture(scope="module")
def table_probe():
    return PlacingProbe.table()


@pytest.fixture(scope="module")
def beam_probe():
    g = table_beam_geometry()
    return PlacingProbe.from_beam(bm.RectBeam(g["length"], g["width"], g["thickness"], 169e9, 0.28, 2330.0))


@pytest.fixture(scope="module")
def fem_probe():
    """The Table 4.4 cantilever's FEM (13.8k DOFs) reduced to 8 modes + static shapes."""
    from probedyn.probes.placing import placing_probe

    return placing_probe("fem")


@pytest.fixture(scope="module")
def tables():
    return rel._tables(float(TABLE["lambda"]))


# ------------------------------------------------------------------ probe, Table 4.4 (SOURCE-NOTES 10)


def test_table_beam_has_the_table_stiffness_and_mass_ratio(beam_probe):
    g = table_beam_geometry()
    assert beam_probe.k == pytest.approx(float(TABLE["k"]), rel=1e-12)
    mp = mass_plausibility(beam_probe)
    m_eq = EQUIV_MASS_RATIO * SILICON_RHO * g["width"] * g["thickness"] * g["length"]
    assert mp["m_equivalent_geometric_kg"] == pytest.approx(m_eq, rel=1e-9)
    assert mp["ratio_equivalent_to_table"] == pytest.approx(m_eq / float(TABLE["m"]), rel=1e-9)
    assert mp["ratio_equivalent_to_table"] > 100  # the table's m is far too light (SOURCE-NOTES 10)
    # the table mass rescales frequencies by sqrt(m_geo/m_table) and leaves statics alone
    tab = beam_probe.with_mass_source("table")
    assert tab.m == pytest.approx(float(TABLE["m"]), rel=1e-12)
    assert tab.k == beam_probe.k
    assert tab.f1 / beam_probe.f1 == pytest.approx(math.sqrt(beam_probe.m / tab.m), rel=1e-12)


def test_table_probe_alone_has_no_geometric_mass(table_probe):
    with pytest.raises(ParameterError):
        table_probe.with_mass_source("geometric")


# ------------------------------------------------------------------ approach (4.13-4.21)


def test_jump_into_contact_force_balance_and_slow_approach(table_probe):
    ap = Approach.from_probe(table_probe)
    js = ap.jump_in()
    s_star = (ap.H * ap.R / (3 * ap.k)) ** (1 / 3)
    assert js["s_star_m"] == pytest.approx(s_star, rel=1e-14)
    assert js["z0_star_m"] == pytest.approx(ap.zeta0 + 1.5 * s_star, rel=1e-14)
    # at the fold the gradient of the force equals the stiffness and k* = 0
    assert float(ap.force_gradient(js["z0_star_m"], js["w_star_m"])) == pytest.approx(ap.k, rel=1e-12)
    lin = ap.linearised(js["z0_star_m"] * (1 + 1e-9))
    assert abs(lin["k_star_n_per_m"]) < 1e-3 * ap.k
    sims = [ap.simulate_approach(v) for v in (1e-5, 1e-6)]
    d = [s["delay_m"] for s in sims]
    assert 0 < d[1] < d[0]  # the simulated jump comes later and converges to z0*
    assert d[1] < 0.01 * js["z0_star_m"]
    # fold passage (~v^(2/3)) plus the snap after it (~v): apparent exponent between 2/3 and 1
    expo = math.log(d[0] / d[1]) / math.log(10.0)
    assert 0.6 < expo < 1.0


def test_linearised_response_in_the_time_domain(table_probe):
    ap = Approach.from_probe(table_probe)
    z0 = 1.5 * ap.jump_in()["z0_star_m"]
    lin = ap.linearised(z0)
    F0 = 1e-4 * lin["k_star_n_per_m"] * lin["s_eq_m"]
    sim = ap.simulate_forced(z0, lin["omega_n_rad_s"], F0)
    r = ap.response(z0, lin["omega_n_rad_s"])
    # nonlinearity ~ A / s_eq ~ 1e-4 / (2 zeta) ~ 5e-4
    assert sim["amplitude_m"] == pytest.approx(F0 * float(r["compliance_m_per_n"]), rel=2e-3)
    assert sim["phase_rad"] == pytest.approx(float(r["phase_rad"]), abs=2e-3)


def test_frequency_shift_small_amplitude_limit_and_exact_orbit(table_probe):
    ap = Approach.from_probe(table_probe)
    z0 = 1.3 * ap.jump_in()["z0_star_m"]
    small = ap.shift_small_amplitude(z0)
    f0 = ap.omega0 / (2 * math.pi)
    A = 1e-12
    # A -> 0: the exact orbit period and Giessibl's sqrt form reduce to (4.21), the first-order
    # Giessibl formula to -f0 k_ts / (2k)
    assert ap.shift_exact(z0, A) == pytest.approx(small, rel=1e-5)
    assert ap.shift_giessibl(z0, A, form="sqrt") == pytest.approx(small, rel=1e-5)
    kts = float(ap.force_gradient(z0, ap.equilibria(z0)["w_stable_m"]))
    assert ap.shift_giessibl(z0, A) == pytest.approx(-f0 * kts / (2 * ap.k), rel=1e-5)
    # two independent evaluations of a finite-amplitude orbit: quadrature vs DOP853
    for A in (0.1e-9, 0.3e-9):
        assert ap.shift_simulated(z0, A) == pytest.approx(ap.shift_exact(z0, A), rel=1e-6)
    # an amplitude that reaches the barrier has no orbit: the dynamic jump
    assert math.isnan(ap.shift_exact(1.02 * ap.jump_in()["z0_star_m"], 1e-9))


# ------------------------------------------------------------------ capture (4.22-4.41)


def test_capture_equation_limits():
    assert np.allclose(cap.capture_roots(0, 0, 4), bm.eb_roots(4), rtol=1e-12)
    for mass in (0.2, 1.0, 5.0):  # tip mass: (3.10) in the standard form (SOURCE-NOTES 1)
        assert np.allclose(cap.capture_roots(0, mass, 3), bm.tip_mass_roots(mass, 3, "standard"), rtol=1e-10)
    assert np.allclose(cap.capture_roots(math.inf, 0, 3), cap.CLAMPED_PINNED[:3], rtol=1e-12)
    # K -> infinity approaches the pinned end like 1/K
    for K in (1e4, 1e6):
        assert abs(cap.capture_roots(K, 0, 1)[0] / cap.CLAMPED_PINNED[0] - 1) < 10.0 / K
    # hanging sample far below its contact resonance = a rigid tip mass (first order in w^2/w_c^2)
    K, m_ = 1e8, 0.5
    x = cap.capture_roots(K, m_, 2, end="hanging")
    assert np.allclose(x, bm.tip_mass_roots(m_, 2), rtol=1e-6)


def test_an_attached_mass_lowers_the_frequency_the_printed_sign_raises_it():
    for K in (0.0, 3.0, 300.0):
        mus = np.linspace(0, 2, 9)
        corr = [cap.capture_roots(K, m_, 1)[0] for m_ in mus]
        prin = [cap.capture_roots(K, m_, 1, form="printed")[0] for m_ in mus]
        assert np.all(np.diff(corr) < 0)
        assert np.all(np.diff(prin) > 0)


def test_capture_forced_response_static_limit(beam_probe):
    c = cap.Capture.from_probe(beam_probe, 0.0, 0.0)
    u = c.forced_response(np.array([beam_probe.L]), [0.0], F0=1.0, n=12)
    # modal truncation error of the static tip compliance ~ sum_{n>12} 1/(bL)^4 ~ 1e-5
    assert u[0, 0].real == pytest.approx(beam_probe.L**3 / (3 * beam_probe.EI), rel=1e-4)


def test_capture_equation_against_the_fem_ritz_model(fem_probe):
    """(4.38) with the probe's FEM EI and rho A vs the FEM-mode Ritz model with static shapes at
    the tip (a spring and a mass there are exact in the static limit); one-layer P2 FEM within
    0.5 % for the first three flapwise modes (tests/test_placing_slow.py: full FEM re-solves)."""
    from probedyn.schemes.placing.studies import capture_study

    res = capture_study(fem_probe, K_values=(0.0, 30.0, 3000.0), mu_values=(0.0, 1.0), basis=fem_probe.ritz)
    assert res["check"] and res["check_max_abs_rel"] < 5e-3
    assert res["check_bL_range"][1] > 7.0


def test_md_linearisation_and_piecewise_linear_orders(tables):
    c = tables.contact
    lin = cap.md_linearisation(c, 0.0)
    h = 1e-3 * c.scales.d_unit
    d = lin["penetration_m"]
    k_num = (c.force(d + h, "unloading") - c.force(d - h, "unloading")) / (2 * h)
    assert lin["k1_n_per_m"] == pytest.approx(k_num, rel=1e-5)  # central difference O(h^2)
    assert lin["k0_n"] == pytest.approx(-lin["k1_n_per_m"] * d, rel=1e-12)
    ref = cap._pl_reference(c, None, 801)
    ns = [8, 16, 32, 64]
    orders = {sp: cap.convergence_order(ns, [cap.piecewise_linear_error(c, n, sp, reference=ref)["max_error_n"]
                                             for n in ns]) for sp in ("uniform", "graded")}
    assert 0.4 < orders["uniform"] < 0.65  # square-root end: N^-1/2
    assert 1.8 < orders["graded"] < 2.2  # graded nodes restore N^-2


# ------------------------------------------------------------------ release (4.42)


def test_kernel_tables_reproduce_the_registry(tables):
    c = tables.contact
    D = np.linspace(tables.Dmin + 1e-3, 8.0, 50)
    P, k = tables.force(D, 1)
    st = c.nd_state(D, "stable")
    assert np.allclose(P, st["P"], rtol=0, atol=1e-7)
    assert np.allclose(k, st["k"], rtol=1e-4)
    Dt = np.linspace(tables.D0 - 5.0, tables.D0, 20)
    Pt, _ = tables.force(Dt, 0)
    assert np.allclose(Pt, c.nd_tail(Dt)[0], rtol=1e-12)


def test_table_point_cannot_release_a_nanoscale_sample(table_probe, tables):
    st = rel.setup_release(table_probe, tables=tables)
    r = rel.simulate(st)
    assert r.outcome == "attached"
    assert st.meta["inertial_force_n"] < 1e-8 * abs(st.meta["F_pull_off_n"])


def test_release_threshold_against_the_pull_off_force(table_probe, tables):
    A, w = 0.5e-6, 1e8
    M_th = abs(tables.pull_off_force) / (w**2 * A)  # quasi-static: omega / omega_c = 0.07
    codes = {}
    for f in (0.9, 1.2, 3.0):
        st = rel.setup_release(table_probe, M=f * M_th, A=A, omega=w, tables=tables)
        r = rel.simulate(st)
        codes[f] = r.code
        if r.code == 0:  # attached: the tension never exceeded the pull-off force
            assert r.max_tension_n <= abs(tables.pull_off_force) * (1 + 1e-3)
    assert codes[0.9] == 0 and codes[3.0] == 2 and codes[1.2] in (1, 2)


def test_release_kernel_against_solve_ivp(table_probe, tables):
    for M, A, w in ((2e-18, 0.5e-6, 1e8), (2e-18, 0.5e-6, 6.9e7), (2e-18, 3e-9, 1.5e9)):
        st = rel.setup_release(table_probe, M=M, A=A, omega=w, tables=tables)
        a = rel.simulate(st)
        b = rel.simulate_scipy(st, method="LSODA")
        assert a.outcome == b.outcome
        assert a.t_separation_s == pytest.approx(b.t_separation_s, rel=1e-3)


def test_escape_criterion_the_released_sample_does_not_come_back(table_probe, tables):
    # release height 100 um so that the sample flies 20 periods (50 um) without reaching the substrate
    st = rel.setup_release(table_probe, M=2e-18, A=0.5e-6, omega=1e8, D=100e-6, tables=tables, n_fly=20)
    assert rel.simulate(st).outcome == "released"
    st.par[15], st.par[16] = math.inf, -math.inf  # no release decision: integrate on
    r = rel.simulate(st)
    assert r.outcome == "undecided"  # never recaptured within 20 periods
    assert r.sample_velocity_m_s < 0 and r.sample_height_m < st.meta["tip_lowest_m"] - 10e-6


def test_outcome_map_sweep_writes_netcdf(table_probe, tmp_path):
    grid = {"omega": np.array([2.5e3, 1e8]), "A": np.array([0.5e-6])}
    res = rel.outcome_map(table_probe, grid, fixed={"M": 2e-18}, out=tmp_path / "m.nc", workers=1,
                          processes=False, chunk_size=1)
    assert (tmp_path / "m.nc").exists()
    o = res.dataset["outcome"].values.ravel()
    direct = rel.release_cells(2e-18, 0.5e-6, grid["omega"], 5e-6, rel.probe_spec(table_probe))["outcome"]
    assert list(o) == list(direct) == [0, 2]


# ------------------------------------------------------------------ landing (4.43-4.44)


def test_force_laws_and_what_dominates():
    H, R1, R2 = 1e-19, 50e-9, 160e-9
    for s in (1e-10, 1e-9):  # Hamaker -> Derjaguin for s << R, to O(s/R)
        assert ld.sphere_sphere_force(s, H, R1, R2, "hamaker") == pytest.approx(
            ld.sphere_sphere_force(s, H, R1, R2), rel=5 * s / R1)
        assert ld.sphere_flat_force(s, H, R2, "hamaker") == pytest.approx(ld.sphere_flat_force(s, H, R2), rel=5 * s / R2)
    s = 5e-6  # far away: sphere-flat ~ 2 H R^3 / (3 s^4)
    assert ld.sphere_flat_force(s, H, R2, "hamaker") == pytest.approx(2 * H * R2**3 / (3 * s**4), rel=5 * R2 / s)
    # gravity beats the substrate's pull beyond ~2 um with the full law, only beyond ~13 um with Derjaguin
    assert 1e-6 < ld.gravity_crossover(law="hamaker") < 3e-6
    assert ld.gravity_crossover(law="derjaguin") > 10e-6
    assert ld.tilt_angle(0.5e-6, 2e-3) == pytest.approx(math.atan(2.5e-4), rel=1e-15)


def test_flight_without_tilt_lands_straight_and_ballistically():
    fl = ld.Flight.table(law="hamaker")
    r = fl.fly(4.5e-6, -40.0)
    assert r["status"] == "landed" and r["R_L_m"] == 0.0
    assert r["t_flight_s"] == pytest.approx(4.5e-6 / 40.0, rel=1e-3)  # vdW and gravity change v by < 1e-3


def test_landing_radius_scales_with_the_tilt(table_probe, tables):
    st = rel.setup_release(table_probe, M=2e-18, A=0.5e-6, omega=1e8, tables=tables)
    r = rel.simulate(st)
    a, b = ld.land(r, tilt="amplitude"), ld.land(r, tilt="slope")
    assert a.R_L > 0 and b.R_L > a.R_L
    assert b.R_L / a.R_L == pytest.approx(math.tan(b.theta) / math.tan(a.theta), rel=1e-3)


# ------------------------------------------------------------------ several samples (4.45-4.55)


def test_printed_two_term_matrices_equal_the_legendre_basis(beam_probe):
    L = beam_probe.L
    ms = [(0.5 * L, 0.1 * beam_probe.beam_mass), (L, 0.2 * beam_probe.beam_mass)]
    K, M = mu.printed_matrices(beam_probe.EI, beam_probe.rhoA, L, ms)
    w = mu.PolynomialRitz.from_probe(beam_probe, 2).solve(ms)["omega"]
    assert np.allclose(mu.matrices_frequencies(K, M), w, rtol=1e-10)


def test_exact_beam_with_masses_and_ritz_convergence(beam_probe):
    L, EI, rA = beam_probe.L, beam_probe.EI, beam_probe.rhoA
    scale = math.sqrt(EI / (rA * L**4))
    assert np.allclose(mu.exact_frequencies(L, EI, rA, [(L, rA * L)], 3) / scale, bm.tip_mass_roots(1.0, 3) ** 2,
                       rtol=1e-10)
    ms = [(0.5 * L, 0.3 * rA * L), (L, 0.3 * rA * L)]
    ex = mu.exact_frequencies(L, EI, rA, ms, 3)
    errs = {n: mu.PolynomialRitz(L, EI, rA, n).solve(ms)["omega"][:3] / ex - 1 for n in (6, 8, 16)}
    for n, e in errs.items():
        assert np.all(e > -1e-10)  # Rayleigh-Ritz is an upper bound
    # the mass at L/2 puts a jump in the shear: algebraic convergence, faster than n^-2
    assert np.all(errs[8] / errs[16] > 4.0)


def test_fem_mode_ritz_with_two_masses(fem_probe):
    L = fem_probe.L
    mb = fem_probe.beam_mass
    ms = [(0.5 * L, 0.1 * mb), (L, 0.1 * mb)]
    om = mu.ritz_flapwise(fem_probe.ritz, ms, 3)
    ex = mu.exact_frequencies(L, fem_probe.EI, fem_probe.rhoA, ms, 3)
    # FEM (one P2 layer, EI from its own static stiffness) against Euler-Bernoulli: < 0.2 %
    assert np.all(np.abs(om / ex - 1) < 2e-3)
    modes_only = mu.ritz_flapwise(fem_probe.ritz.leading(fem_probe.ritz.n_modes), ms, 3)
    assert np.all(modes_only >= om * (1 - 1e-12))  # the static shapes can only lower the Ritz values


def test_identifiability_one_frequency_cannot_fix_two_unknowns(beam_probe):
    rows = mu.identifiability(beam_probe, M=[0.01 * beam_probe.beam_mass] * 2, n_modes_list=(1, 2, 4))
    by = {(r["unknowns"], r["n_frequencies"]): r for r in rows}
    for u in ("l1+l2", "M1+M2", "l1+M1"):
        assert not by[(u, 1)]["identifiable"] and by[(u, 2)]["identifiable"]
    assert not by[("l1+l2+M1+M2", 2)]["identifiable"] and by[("l1+l2+M1+M2", 4)]["identifiable"]


def test_inverse_positions_from_two_frequencies(beam_probe):
    L, EI, rA = beam_probe.L, beam_probe.EI, beam_probe.rhoA
    Mh = 0.01 * rA * L
    f0 = mu.exact_frequencies(L, EI, rA, [], 2)
    f = mu.exact_frequencies(L, EI, rA, [(0.5 * L, Mh), (L, Mh)], 2)
    res = mu.solve_inverse(beam_probe, f / f0 - 1, ["l1", "l2"], {"M1": Mh, "M2": Mh}, sigma=1e-7, starts=6)
    assert res["swap_symmetric"] and res["unique"]
    est = res["distinct"][0]["estimate"]
    pos = sorted([est["l1"], est["l2"]])
    # Ritz (12 polynomials) vs the exact beam: model error ~1e-5 of the shift, well inside 1e-3 L
    assert pos == pytest.approx([0.5 * L, L], abs=1e-3 * L)


def test_selective_release_thresholds_agree_with_the_release_runs(beam_probe, tables):
    L = beam_probe.L
    ms = [(0.5 * L, 1e-13), (L, 1e-13)]
    w = 0.8 * beam_probe.omega1
    thr = mu.release_thresholds(beam_probe, ms, [w], "base")[0]
    assert thr[1] < thr[0]  # below the first mode the tip moves more: sample 2 goes first
    T = np.abs(mu.local_response(beam_probe, ms, [w], "base"))[0]
    for Y, expect in ((math.sqrt(thr[0] * thr[1]), ("attached", "released")), (1.5 * thr[0], ("released", "released"))):
        got = []
        for k, (l, Mk) in enumerate(ms):
            st = rel.setup_release(mu.probe_at(beam_probe, l, ms), M=Mk, A=float(Y * T[k]), omega=w,
                                   tables=tables, D=max(50e-6, 10 * float(Y * T.max())))
            got.append(rel.simulate(st).outcome)
        assert tuple(got) == expect


# ------------------------------------------------------------------ command line


def test_cli_release_json_and_bad_input(capsys):
    from probedyn.cli import main

    assert main(["place", "release", "table-4.4", "--mass-source", "table", "--json"]) in (0, None)
    assert json.loads(capsys.readouterr().out)["outcome"] == "attached"
    assert main(["place", "release", "table-4.4", "--mass-source", "table", "--omega", "-5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "omega must be positive" in err[0]


def test_cli_release_writes_json_and_figure(tmp_path, capsys):
    from probedyn.cli import main

    out = tmp_path / "rel"
    assert main(["place", "release", "table-4.4", "--mass-source", "table", "--omega", "1e8", "--amplitude", "5e-7",
                 "--out", str(out)]) in (0, None)
    assert "released" in capsys.readouterr().out
    assert json.loads((out / "place_release.json").read_text())["outcome"] == "released"
    assert (out / "place_release.png").stat().st_size > 10_000
