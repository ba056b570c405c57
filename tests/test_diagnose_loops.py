"""Mesoscale friction loops (:mod:`probedyn.diagnose.friction_loop`): the regime a record is diagnosed in,
the baseline's steady friction against an energy balance, the slope law against the tip's force balance,
and the diagnosis on independent truths (``tests/diagnose_truth_loops.py``: the force balance solved per
point, its own code path)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_truth_loops import _balance, _with_reversal, make_loop_case  # noqa: E402

from probedyn.core.errors import DataFormatError  # noqa: E402
from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import FrictionData, FrictionScan  # noqa: E402
from probedyn.diagnose.friction_loop import (FrictionLoopProblem, reversal_deficit, segment_slopes,  # noqa: E402
                                             slope_force, steady_friction)
from probedyn.diagnose.problems import make_problem  # noqa: E402


def _write(folder: Path, step: float, lattice: float | None, sampling: str = "interval-mean") -> Path:
    x = np.arange(64) * step
    f = 1e-9 * np.sin(np.arange(64))
    rows = [(1, xx, ff) for xx, ff in zip(x, f)] + [(1, xx, -ff) for xx, ff in zip(x[::-1], f[::-1])]
    (folder / "m.csv").write_text("scan,position_m,lateral_force_N\n" + "".join(f"{s},{a:.9e},{b:.9e}\n" for s, a, b in rows))
    lat = f"[sample]\nlattice = {lattice}\n" if lattice else ""
    (folder / "m.toml").write_text(f'[measurement]\nkind = "friction"\ndata = "m.csv"\nsampling = "{sampling}"\n'
                                   f"[lever]\nk_x = 20.0\n{lat}[[scans]]\nid = 1\nspeed = 1e-6\nload = 1e-8\n")
    return folder / "m.toml"


def test_the_sample_spacing_selects_the_regime_or_refuses_the_record(tmp_path):
    """Samples a quarter period apart or closer: stick-slip; interval means over >= 20 periods: a loop;
    in between, or point samples of an unresolved stick-slip (aliased): a one-line error naming both limits."""
    assert type(make_problem(_write(tmp_path, 100e-9, None))) is FrictionLoopProblem  # 200 periods per sample
    assert make_problem(_write(tmp_path, 0.05e-9, None)).data.regime == "stick-slip"
    with pytest.raises(DataFormatError, match="at most 0.25 period between samples.*at least 20"):
        make_problem(_write(tmp_path, 2e-9, None))  # 4 periods per sample
    with pytest.raises(DataFormatError, match="aliased"):
        make_problem(_write(tmp_path, 100e-9, None, sampling="point"))


def test_steady_friction_is_the_energy_released_per_slip_over_the_period():
    """Energy balance of the FFM's steady stick-slip at a low speed (the lever's damping drag c v is
    1e-6 of the friction): the mean lateral force times the period is the energy the tip loses in one
    slip, from the quasi-static instability ``x_c`` of the well to the next well's minimum ``x_a``
    (``E = -U0 cos(q x) + k (X - x)^2 / 2`` at ``X_c``). Tolerance 2 %: the slip overshoots at Q = 1 by
    less than that (measured 0.4 %) and the quasi-static branch is the low-speed limit."""
    k, a, N, u0 = 20.0, 0.5e-9, 10e-9, 0.3e-10  # U0 = 3e-19 J: eta = 4 pi^2 U0 / (k a^2) = 2.4
    data = FrictionData(path=Path("x"), kind="friction", meta={}, scans=[], k_x=k, lattice=a)
    F_k = steady_friction(data, u0, a, 1e-9, N)
    U0, q = u0 * N, 2 * math.pi / a
    F0 = q * U0
    xc = math.acos(-k / (q * F0)) / q
    Xc = xc + F0 * math.sin(q * xc) / k
    xx = np.linspace(xc + 1e-6 * a, xc + a, 200001)
    g = k * (Xc - xx) - F0 * np.sin(q * xx)
    xa = float(xx[np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0][0]])
    E = lambda x: -U0 * math.cos(q * x) + 0.5 * k * (Xc - x) ** 2  # noqa: E731
    assert F_k == pytest.approx((E(xc) - E(xa)) / a, rel=0.02)


def test_slope_law_is_the_force_balance_on_an_incline_and_nests_the_flat_loop():
    """``slope_force`` (Ogletree et al. 1996) against the tip's equilibrium solved as a linear system:
    exact without adhesion; ``c = 0`` is ``d F_k``; the loop's mean per unit slope is ``N`` to first order."""
    theta = np.linspace(-0.3, 0.3, 13)
    for d in (1.0, -1.0):
        ref = _balance(10e-9, 0.0, 0.4, d, theta)
        assert np.allclose(slope_force(0.4 * 10e-9, 10e-9, d, np.tan(theta)), ref, rtol=1e-12)
        assert np.allclose(slope_force(4e-9, 10e-9, d, np.tan(theta), c=0.0), d * 4e-9, rtol=1e-15)
    t = 1e-4
    mean = 0.5 * (slope_force(4e-9, 10e-9, 1.0, t) + slope_force(4e-9, 10e-9, -1.0, t))
    assert mean / t == pytest.approx(10e-9 * (1 + 0.4**2), rel=1e-3)


def test_slopes_come_from_the_mean_of_trace_and_retrace_heights():
    """The feedback's lag shifts the trace's heights forward and the retrace's back: their mean at each
    position cancels the shift to first order (a ramp's slope exactly)."""
    x = np.linspace(0, 1e-6, 50)
    h = 0.02 * x
    pos = np.concatenate([x, x[::-1]])
    hgt = np.concatenate([np.roll(h, 2), np.roll(h[::-1], 2)])  # each direction's heights lag two samples
    hgt[:2], hgt[50:52] = h[:2], h[::-1][:2]
    d = np.concatenate([np.ones(50), -np.ones(50)])
    s = FrictionScan(1, 1e-6, 1e-8, pos, np.zeros(100), np.arange(100.0), d, hgt)
    t = segment_slopes(s)
    assert np.allclose(t[5:45], 0.02, rtol=1e-9)


@pytest.mark.parametrize("seed", [7000, 7004])
def test_a_hidden_slope_coupling_is_named_and_its_calibration_factor_recovered(tmp_path, seed):
    """On the independent truth the slope coupling is found first and the calibration factor derived
    from it recovers the truth's ``g`` within 10 % (the issue's bound; the model is first order in the
    slope and takes the adhesion as zero, the truth's adhesion is up to half the load)."""
    path, truth = make_loop_case(tmp_path, seed, "surface-slope")
    res = diagnose(make_problem(path))
    assert res["findings"] and res["findings"][0]["cause"] == "surface-slope", res["verdict"]
    assert res["findings"][0]["derived"]["lateral_calibration_factor"] == pytest.approx(truth["g"], rel=0.10)


@pytest.mark.parametrize("seed", [7001, 7003])
def test_a_flat_surface_claims_no_slope_coupling(tmp_path, seed):
    path, truth = make_loop_case(tmp_path, seed, None)
    prob = make_problem(path)
    # a flat surface has no relief above its noise: no phase coordinate, the contrast is not offered
    assert prob.relief is None and "friction-contrast" in prob.describe()["causes_not_offered"]
    res = diagnose(prob)
    assert res["findings"] == [], res["findings"]


@pytest.mark.parametrize("seed", [7022, 7064])
def test_a_friction_contrast_between_phases_is_named_and_its_ratio_recovered(tmp_path, seed):
    """Islands whose friction coefficient is 1.15 (7022) or 1.28 (7064) times the matrix's: the contrast is
    claimed beside the slope coupling, and the ratio of the highest parts' friction to the lowest's
    recovers the truth's within 10 % (the model is exact on the plateaus; the edges are low-passed and the
    heights lag the lateral force by up to two samples), the calibration factor within 10 % as above."""
    path, truth = make_loop_case(tmp_path, seed, "surface-slope")
    res = diagnose(make_problem(path))
    found = {f["cause"]: f for f in res["findings"]}
    assert set(found) == {"friction-contrast", "surface-slope"}, res["findings"]
    ratio = found["friction-contrast"]["derived"]["friction_ratio_high_to_low"]
    assert ratio == pytest.approx(truth["contrast"], rel=0.10)
    assert found["surface-slope"]["derived"]["lateral_calibration_factor"] == pytest.approx(truth["g"], rel=0.10)


def test_no_friction_contrast_where_the_phases_share_one_friction(tmp_path):
    """Islands of one friction coefficient (seed 7002: relief 5-60 nm, contrast 1): the contrast cause is
    offered (the relief marks phases) but not claimed; the slope coupling is."""
    path, truth = make_loop_case(tmp_path, 7002, "surface-slope")
    assert truth["contrast"] == 1.0
    prob = make_problem(path)
    assert "friction-contrast" in [c.key for c in prob.causes]
    res = diagnose(prob)
    assert [f["cause"] for f in res["findings"]] == ["surface-slope"]


def test_jackknife_replicate_is_the_record_without_that_line(tmp_path):
    """The finding's uncertainty over the image lines (delete-one jackknife, Efron & Stein 1981): each replicate
    equals the slope coupling fitted to the record written again without that line (a new problem from a new
    file: its own noise estimate, slopes and starts), and the reported sigma is the jackknife's
    sqrt((m - 1)/m sum (c_i - mean)^2) wherever it exceeds the Jacobian's."""
    from probedyn.diagnose.engine import Fitter

    path, _ = make_loop_case(tmp_path, 7000, "surface-slope")
    res = diagnose(make_problem(path))
    f = res["findings"][0]
    reps = [r["c_slope"] for r in f["replicates"]]
    prob = make_problem(path)
    ids = [s.id for s in prob.data.scans]
    assert len(reps) == len(ids) >= 3
    m = len(reps)
    sd = math.sqrt((m - 1) / m * float(np.sum((np.asarray(reps) - np.mean(reps)) ** 2)))
    p = f["parameters"]["c_slope"]
    assert p["sigma_jackknife"] == pytest.approx(sd, rel=1e-12)
    if "sigma_jacobian" in p:  # the jackknife replaced a smaller Jacobian sigma
        assert p["sigma"] == pytest.approx(sd, rel=1e-12) and sd > p["sigma_jacobian"]
    else:
        assert p["sigma"] >= sd
    csv = path.with_suffix(".csv")
    lines = csv.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [ln for ln in lines if ln.startswith("scan")]
    col = head[-1].split(",").index("scan")
    for i in (0, m - 1):
        sub = tmp_path / f"without_{ids[i]}"
        sub.mkdir()
        rows = [ln for ln in lines if ln and not ln.startswith("#") and not ln.startswith("scan")
                and int(float(ln.split(",")[col])) != ids[i]]
        (sub / csv.name).write_text("\n".join(head + rows) + "\n")
        (sub / path.name).write_text(path.read_text())
        q = make_problem(sub / path.name)
        F = Fitter(q)
        fit = F.nested(F.baseline(), tuple(c for c in q.causes if c.key == "surface-slope"))
        assert fit.values["c_slope"] == pytest.approx(reps[i], rel=2e-3)


# -- scans at several loads ------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [6001, 6002])
def test_a_coulomb_loop_at_two_loads_is_the_baseline(tmp_path, seed):
    """Scans at L and 2 L of a Coulomb truth without adhesion (flat surface): the baseline carries the FFM's
    friction at the reference load to each load by Amontons' law, so nothing is left to explain (before
    session 25 the PT's own load law, U0 = u0 N, left these 'unexplained': chi^2 2402 on 2048 samples for
    6001; its friction grows 1.6-2.2 times, not 2, from one load to twice it)."""
    path, truth = make_loop_case(tmp_path, seed, None, load_factors=(1.0, 2.0), adhesion_ratio=0.0)
    res = diagnose(make_problem(path))
    assert res["verdict"] == "no-significant-discrepancy" and res["findings"] == [], res["verdict"]


@pytest.mark.parametrize("seed,ratio", [(7002, 0.29), (7005, 0.40)])
def test_an_adhesion_load_is_found_from_two_loads(tmp_path, seed, ratio):
    """Derjaguin's friction mu (L + A) at L and 2 L: adhesion-load first, and its N_adh (the half loop's
    intercept on the load axis) within 10 % of the truth's A (the statistical error is ~1-2 %: 512-2048
    samples of 1-5 % noise on two levels)."""
    path, truth = make_loop_case(tmp_path, seed, "adhesion-load", load_factors=(1.0, 2.0), adhesion_ratio=ratio)
    res = diagnose(make_problem(path))
    assert res["findings"] and res["findings"][0]["cause"] == "adhesion-load", res["findings"]
    assert res["findings"][0]["parameters"]["n_adh"]["value"] == pytest.approx(truth["A"], rel=0.10)


@pytest.mark.parametrize("seed", [6011, 6013])
def test_a_drifting_lateral_channel_is_found_on_image_lines(tmp_path, seed):
    """The lateral channel's zero drifting linearly in time through three image lines (trace, retrace, next
    line on one clock). The loop baseline carries a constant zero only; before session 47 the drift cause was
    offered to stick-slip records alone, and a blind generator's loop with a drift (f22, session 46) read
    *unexplained* with no cause tried. Now force-offset-drift is first, its drift over one scan within 3.4 of
    its stated sigmas of the truth (two-sided 1 % over the cases, Bonferroni over 2), and the same lines without
    the drift read as no discrepancy."""
    path, truth = make_loop_case(tmp_path, seed, None, load_factors=(1.0, 1.0, 1.0), drift_rate=1e-10)
    res = diagnose(make_problem(path))
    assert res["findings"] and res["findings"][0]["cause"] == "force-offset-drift", res["findings"]
    d = res["findings"][0]["parameters"]["drift"]
    assert abs(d["value"] - truth["params"]["drift"]) < 3.4 * d["sigma"], (d, truth["params"])
    path0, _ = make_loop_case(tmp_path / "null", seed, None, load_factors=(1.0, 1.0, 1.0))
    res0 = diagnose(make_problem(path0))
    assert res0["findings"] == [], res0["findings"]


def test_the_corrugation_starts_reach_the_recorded_friction(tmp_path):
    """The PT's mean friction is a sawtooth in U0 (it drops where the slips skip one more well): the fit's
    extra starts (:meth:`FrictionLoopProblem._level_crossings`) sit on rising stretches where the FFM gives
    the recorded half loop, within the interpolation's error between the 96 tabulated corrugations (the
    stretch is smooth: a few per cent per grid step)."""
    path, _ = make_loop_case(tmp_path, 7001, "adhesion-load", load_factors=(1.0, 2.0), adhesion_ratio=0.9)
    prob = make_problem(path)
    assert prob.u_crossings
    v = float(np.median(prob.speeds))
    for u in prob.u_crossings:
        assert prob.friction_at(u, v, prob.N_ref) == pytest.approx(abs(prob.half_loop), rel=0.02)
    # a single load: the reference load is that load and the baseline is the FFM there, as before
    path1, _ = make_loop_case(tmp_path, 7001, None)
    p1 = make_problem(path1)
    s = p1.data.scans[0]
    assert p1.N_ref == s.load and p1.friction_at(1e-10, s.speed, s.load) == steady_friction(p1.data, 1e-10, p1.data.lattice, s.speed, s.load)


def _coulomb_loop(folder: Path, k_x: float, speed: float, load: float, mu: float, sigma: float, seed: int = 3) -> Path:
    """Trace and retrace of two flat image lines with Coulomb friction ``mu load``, an offset and white noise."""
    rng = np.random.default_rng(seed)
    n, length = 200, 5e-6
    x = (np.arange(n) + 0.5) * length / n
    rows, t = [], 0.0
    for sid in (1, 2):
        for d, xs in ((1.0, x), (-1.0, x[::-1])):
            for xx in xs:
                rows.append((sid, xx, 3e-10 + d * mu * load + rng.normal(0.0, sigma), t))
                t += length / n / speed
    (folder / "c.csv").write_text("scan,position_m,lateral_force_N,time_s\n"
                                  + "".join(f"{s},{a:.9e},{b:.9e},{c:.9e}\n" for s, a, b, c in rows))
    scans = "".join(f"[[scans]]\nid = {i}\nspeed = {speed}\nload = {load}\n" for i in (1, 2))
    (folder / "c.toml").write_text(f'[measurement]\nkind = "friction"\ndata = "c.csv"\nsampling = "interval-mean"\n'
                                   f"[lever]\nk_x = {k_x}\n[sample]\nlattice = 4.8e-10\n[noise]\nforce = {sigma}\n"
                                   + scans)
    return folder / "c.toml"


def test_a_friction_below_the_stick_slip_threshold_s_sliding_friction_is_reachable(tmp_path):
    """A stiff lever (k_x 100 N/m) on a fast line (3.4 um/s) with a small Coulomb friction (0.2 nN): the FFM's
    damped sliding over a corrugation at the stick-slip threshold eta = 1 already gives 0.66 nN (the lever's
    default damping, Q_x = 1 at 100 kHz), so with its corrugation bounded there the baseline stalled at the
    bound (a blind generator's nulls, session 30: chi^2 5.6e7 on 1960 samples, or a friction contrast claimed).
    The bound is lowered until the FFM's friction falls below a tenth of the recorded level; the record is
    then the baseline (its chi^2 test passes at the engine's alpha), with the half loop reproduced."""
    path = _coulomb_loop(tmp_path, 100.0, 3.4e-6, 3e-9, 0.07, 3e-12)
    prob = make_problem(path)
    u_eta1 = prob.data.k_x * prob.data.lattice**2 / (4 * math.pi**2) / prob.N_ref
    assert prob.friction_at(u_eta1, 3.4e-6, prob.N_ref) > 3.0 * abs(prob.half_loop)  # the stalled case
    assert prob.base_params[0].lo < u_eta1
    assert prob.friction_at(prob.base_params[0].lo, 3.4e-6, prob.N_ref) <= 0.1 * abs(prob.half_loop)
    res = diagnose(prob)
    assert res["findings"] == [] and res["verdict"] == "no-significant-discrepancy", res["verdict"]
    assert res["baseline"]["p_value"] > 1e-3


def test_a_loop_recorded_one_way_is_refused_in_one_line(tmp_path):
    """Interval means of the trace alone: the friction (half the trace-retrace difference) cannot be told from
    the lateral channel's zero, so the record is refused with a one-line error (session 30: it was fitted,
    the offset's bounds could not reach the level, chi^2 6e5 and a slope coupling at its bound claimed)."""
    path = _coulomb_loop(tmp_path, 20.0, 1e-6, 1e-8, 0.3, 1e-11)
    csv = path.with_suffix(".csv")
    head, *rows = csv.read_text().splitlines(keepends=True)
    xs = [float(r.split(",")[1]) for r in rows]
    fwd = [r for i, r in enumerate(rows) if i == 0 or xs[i] > xs[i - 1]]  # the trace runs up
    csv.write_text(head + "".join(fwd))
    with pytest.raises(DataFormatError, match="one way only.*trace and its retrace"):
        make_problem(path)


def test_the_reversal_deficit_is_the_stick_ramp_averaged_over_each_interval():
    """The lever's force after a reversal rises at k through the height h and then slides: each interval's mean
    deficit against quadrature of the ramp on a fine grid (ramp shorter than, equal to and longer than an
    interval), the long-interval limit ``h^2 / (2 k Delta)``, and no deficit without a height."""
    k, h = 8.0, 14.4e-9  # 2 x 7.2 nN on an 8 N/m lever: a 1.8 nm ramp (blind f10's highest load)
    for delta in (39e-9, 1.8e-9, 0.7e-9):
        ua = np.arange(6) * delta
        ub = ua + delta
        u = (np.arange(600_000) + 0.5) / 100_000 * delta  # six intervals, 1e5 points each
        ref = np.maximum(h - k * u, 0.0).reshape(6, -1).mean(axis=1)
        got = reversal_deficit(np.full(6, h), k, ua, ub)
        assert np.allclose(got, ref, rtol=1e-6, atol=1e-9 * h)
    assert reversal_deficit(h, k, 0.0, 39e-9) == pytest.approx(h * h / (2 * k * 39e-9), rel=1e-12)
    assert reversal_deficit(0.0, k, 0.0, 39e-9) == 0.0
    assert reversal_deficit(-h, k, 0.0, 39e-9) == 0.0  # a force already past the other friction: no stick


def test_the_truth_s_reversal_stick_is_the_ramp_the_model_averages():
    """The truth generator's reversal (its own fine grid, the sliding force interpolated between its sub-points)
    and the model's closed form agree on a flat surface, trace and retrace, ramp shorter and longer than an
    interval."""
    k, n, dx = 5.0, 12, 10e-9
    for F in (9e-9, 45e-9):  # ramps of 3.6 and 18 nm
        sub_fwd, sub_back = np.full((n, 8), F), np.full((n, 8), -F)
        ua = np.arange(n) * dx
        model = F - reversal_deficit(np.full(n, 2 * F), k, ua, ua + dx)
        assert np.allclose(_with_reversal(sub_fwd, sub_back, 1.0, k, dx), model, rtol=0, atol=1e-5 * F)
        assert np.allclose(_with_reversal(sub_back, sub_fwd, -1.0, k, dx), -model[::-1], rtol=0, atol=1e-5 * F)


def test_a_loop_whose_reversals_stand_above_the_noise_is_the_baseline(tmp_path):
    """A flat Coulomb loop whose first interval means fall ~9 sigma short of the sliding
    friction at every reversal (the truth's stick ramp): no discrepancy. Read as ``d F_k`` throughout, as
    before session 55, the same record was *unexplained* (chi^2 1.19 per sample)."""
    path, truth = make_loop_case(tmp_path, 1, None)
    L = 2 * truth["mu"] * (truth["L"] + truth["A"]) / truth["k_x"]
    p = make_problem(path)
    x = p.data.scans[0].position
    dx = float(np.ptp(x)) / (truth["n"] - 1)
    deficit = truth["g"] * (2 * truth["mu"] * (truth["L"] + truth["A"])) * L / (2 * dx)
    assert deficit > 5 * truth["sigma"]  # the test can fail: the reversals are far outside the noise
    res = diagnose(p)
    assert res["verdict"] == "no-significant-discrepancy" and not res["findings"]


# ---- session 68: the level at one speed, the contact's stiffness at the reversals -------------------------------


def _chaotic_lever(path: Path, k_x: float, half_loop: float, eta: float = 12.0, f0: float = 250e3, Q: float = 8.0):
    """Rewrite a loop record's sidecar so that its lever and lattice put the FFM's PT, at the recorded friction, at
    ``eta`` on an underdamped lever (``Q``): blind friction set 2's g06 (eta 10-14, Q_x 8). The lattice follows from
    the PT's peak force ``F0 = eta k a / (2 pi)`` of the order of the friction."""
    a = 2 * math.pi * half_loop / (eta * k_x)
    m = k_x / (2 * math.pi * f0) ** 2
    c = math.sqrt(m * k_x) / Q
    txt = path.read_text().replace(f"[lever]\nk_x = {k_x:.6g}\n",
                                   f"[lever]\nk_x = {k_x:.6g}\nm_x = {m!r}\nc_x = {c!r}\n[sample]\nlattice = {a!r}\n")
    path.write_text(txt)
    return a


def test_a_loop_at_one_speed_fits_its_level_where_the_ffm_friction_jumps_with_the_corrugation(tmp_path):
    """At one speed the FFM sets nothing but the friction level, and the level is the baseline's parameter
    (``F_ref``). Where the PT's slips skip wells on an underdamped lever its mean friction is no smooth function of
    the corrugation: here it jumps by more than 5 % between corrugations 0.1 % apart, so a fit in ``u0`` could not
    reach a level inside a jump (blind g06, session 67: chi^2 2209 on 766 for a null). On a noise-only Coulomb
    truth with such a lever, its noise 0.7 % of the friction (g06's), the baseline now fits to the noise: chi^2
    within 4 standard deviations of its dof, no finding (fitted in ``u0``, measured: chi^2 1977 on 1534,
    "unexplained")."""
    _, tr = make_loop_case(tmp_path / "draw", 7006, None)
    level = tr["g"] * tr["mu"] * (tr["L"] + tr["A"])
    path, tr = make_loop_case(tmp_path, 7006, None, overrides=dict(sigma=0.007 * level))
    a = _chaotic_lever(path, tr["k_x"], level)
    prob = make_problem(path)
    assert prob.level_param and prob.data.lattice == pytest.approx(a)
    v = float(prob.speeds[0])
    assert prob.u_crossings
    u = prob.u_crossings[0]
    Fk = np.array([prob.friction_at(u * (1.0 + x), v, prob.N_ref) for x in np.linspace(-0.01, 0.01, 21)])
    assert np.max(np.abs(np.diff(Fk)) / Fk[:-1]) > 0.05, Fk / Fk[10]
    res = diagnose(prob)
    b = res["baseline"]
    assert abs(b["chi2"] - b["dof"]) < 4 * math.sqrt(2 * b["dof"]), (b["chi2"], b["dof"])
    assert not res["findings"] and res["verdict"] == "no-significant-discrepancy", res["verdict"]


@pytest.mark.parametrize("k_contact", [None, 20.0])
def test_a_contact_stiffness_in_series_is_read_from_the_reversals(tmp_path, k_contact):
    """A soft lever (1.2 N/m) on 16 nm pixels: the stick after each reversal spans a third of a pixel or more, above
    the 15 pN noise. With a contact of 20 N/m in series (blind g12's spring-block: 20 N/m behind 1.2 N/m) the stick
    rises at 1.13 N/m, not 1.2; the baseline takes the contact's stiffness on as a term (every contact has one) and
    reads it within 10 % (the term's gain, ~2000 in chi^2, puts the compliance's relative standard error near
    1/sqrt(2000) = 2.2 %: 4 of them are 9 %). With a rigid contact the term is not taken. Both records are nulls
    and nothing is claimed."""
    path, tr = make_loop_case(tmp_path, 7000, None, contact_stiffness=k_contact,
                              overrides=dict(k_x=1.2, length=4e-6, n=256, sigma=15e-12))
    assert tr["g"] == 1.0  # (a calibration factor g scales the recorded stick slope too: g k_stick)
    res = diagnose(make_problem(path))
    t = {x["term"]: x for x in res["baseline"]["declared_terms"]}["contact-stiffness"]
    assert not res["findings"] and res["verdict"] == "no-significant-discrepancy", res["verdict"]
    if k_contact is None:
        assert not t["taken"], t
    else:
        assert t["taken"], t
        assert t["derived"]["k_contact_N_per_m"] == pytest.approx(k_contact, rel=0.10)
