"""probedyn.studies.reduced: geometry matters (predicted from the reduced stiffness, confirmed by
simulation) and higher modes.  The full studies are slow; the default test runs two geometries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probedyn.schemes.ffm import FFM
from probedyn.studies import reduced as st

_FV = FFM.from_preset("vamwcnt").friction.values
G0 = _FV["F_s"] / _FV["sigma0"]


def _check_ffm_rows(rows, rel):
    # The one-mode FFM model with the same damping ratio (Q = 100 for every geometry) and the same
    # friction: the sawtooth scales with the spring, so period * k_scan / (F_s - F_c) is the same
    # overshoot factor for every geometry (to the bristle's share of the compliance, k/sigma0 ~ 1e-3,
    # and the sampling of the trace: `rel`); the amplitude is the underdamped slip's
    # (F_s - F_c)(1 + exp(-pi zeta / sqrt(1 - zeta^2))) for a constant kinetic friction; the
    # bristle's Stribeck rise while the slip turns round (|v| < V_s over a fraction ~V_s/v_max
    # <= 0.05 of the slip, v_max = (F_s - F_c)/sqrt(k m)) takes up to ~2 % of the overshoot.
    factors = []
    for r in rows:
        f = r["ffm_vamwcnt"]
        assert f["regime"] == "regular"
        factors.append(f["period_m"] / f["predicted_period_m"])
        assert f["amplitude_n"] == pytest.approx(f["predicted_amplitude_n"], rel=0.02)
        # first slip: F_s / k plus the bristle's pre-sliding creep g0 ln(1/(1 - z/g0)), g0 = F_s/sigma0
        # (0.5 pm for Table 2.2), a few g0 before the instability: bound 10 g0
        assert abs(f["first_slip_m"] - f["predicted_first_slip_m"]) < 10 * G0
    factors = np.array(factors)
    assert np.ptp(factors) / factors.mean() < rel
    # ... and the period does change with the geometry: it follows 1 / k_scan
    k = np.array([r["k_scan"] for r in rows])
    P = np.array([r["ffm_vamwcnt"]["period_m"] for r in rows])
    if np.ptp(k) / k.mean() > 0.03:
        assert np.corrcoef(P, 1 / k)[0, 1] > 0.99


def _check_contact_rows(rows):
    for r in rows:
        c = r["contact"]
        assert c["jump_in"] == c["predicted_jump"]
        if c["jump_in"]:
            assert c["jump_in_gap_m"] == pytest.approx(c["predicted_gap_m"], rel=0.005)


def test_geometry_two_variants():
    rows = st.geometry_study((("base", None), ("tip_height", 20e-6)))
    # a taller tip: longer lever for the torsion -> softer scan spring; the normal spring barely moves
    assert rows[1]["k_scan"] < rows[0]["k_scan"]
    assert rows[1]["k_normal"] == pytest.approx(rows[0]["k_normal"], rel=0.05)
    _check_ffm_rows(rows, rel=0.02)
    _check_contact_rows(rows)
    for r in rows:  # pushing: the ~3 N/m Hertz contact dominates the series stiffness
        assert r["pushing"]["k_series"] < 3.5


@pytest.mark.slow
def test_geometry_full_study():
    rows = st.geometry_study()
    _check_ffm_rows(rows, rel=0.03)
    _check_contact_rows(rows)
    by = {(r["variant"], r["value"]): r for r in rows}
    base = by[("base", None)]
    # beam scalings of the reduced stiffness: normal ~ t^3 / L^3
    thin = by[("thickness", 5e-6)]
    assert thin["k_normal"] / base["k_normal"] == pytest.approx(0.5**3, rel=0.1)
    long_ = by[("length", 400e-6)]
    assert long_["k_normal"] / base["k_normal"] == pytest.approx((300 / 400) ** 3, rel=0.1)
    # the transition speed of pushing moves by < 1 % over the whole family (contact-dominated)
    V = np.array([r["pushing"]["predicted_transition_m_s"] for r in rows])
    assert np.ptp(V) / V.mean() < 0.01


@pytest.mark.slow
def test_pushing_step_with_the_fem_probe():
    # the step predicted from the reduced stiffness (one lattice constant, slip (F_s-F_c)/k_s < a)
    # confirmed by the pushing simulation with the FEM-reduced tip (stiffness, mass, damping)
    from probedyn.probes.reduce import reduce_probe
    from probedyn.schemes import pushing as pu

    rp = reduce_probe("cantilever", dict(st.FFM_CANTILEVER, **st.COARSE), n_modes=4, Q=st.STUDY_Q)
    o = rp.lumped("scan")
    pred = st.pushing_prediction(o.stiffness)
    _, an = pu.push("mica", probe=dict(k=o.stiffness, m=o.mass, damping=o.damping))
    assert an["regime"] == "stick-slip"
    assert an["mean_step_m"] == pytest.approx(pred["predicted_step_m"], rel=0.02)


@pytest.mark.slow
def test_higher_modes_converge():
    hm = st.higher_modes_study(speeds=(2e-6,), n_list=(None, 1, 2, 4), reference=6)
    err = {r["n_modes"]: abs(r["rel_diff"]["period_m"]) for r in hm["runs"]}
    # modal superposition converges: each added scan mode reduces the period error, 4 modes are
    # within 1 % of 6; the amplitude is set by the static residual (within 1 % from N = 1)
    assert err[4] < err[2] < err[1]
    assert err[4] < 0.01
    amp = {r["n_modes"]: abs(r["rel_diff"]["amplitude_n"]) for r in hm["runs"]}
    assert amp[1] < 0.01
    # the first scan mode left out rings with a fraction r_next of the dominant mode's velocity
    # after a slip: r_next falls with N, and so does the error
    r_next = {r["n_modes"]: r["next_mode_velocity_ratio"] for r in hm["runs"] if r["n_modes"] in (1, 2, 4)}
    assert r_next[4] < r_next[2] < r_next[1] < 0.5
    assert all(math.isfinite(r["slip_time_s"]) for r in hm["runs"])


@pytest.mark.slow
def test_report_section_quick(tmp_path):
    from probedyn.report.reduced import section

    md = section(tmp_path, True)
    assert "reduced-ffm-table-vs-fem.png" in md and (tmp_path / "reduced-ffm-table-vs-fem.png").stat().st_size > 10_000
    for needle in ("Springs and masses at the apex", "Modal truncation", "Geometry matters", "Higher modes"):
        assert needle in md
