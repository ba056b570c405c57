"""FFM line-scan model (2.13)-(2.16): quasi-static limits, the sawtooth, presets, full 2D model."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes import ffm as F
from probedyn.schemes.stickslip_analysis import analyze


@pytest.fixture(scope="module")
def mica_long():
    return F.run_ffm("mica", length=90e-9)


def test_mica_regular_stick_slip_between_F_s_and_F_c(mica_long):
    """Quasi-static sawtooth (sigma0 >> k_x, slips far faster than the scan): the force peaks at
    F_s (the Stribeck factor at the creep speed k_x V / sigma0 ~ 4e-11 m/s is 1 - 1e-11) and falls
    to F_c (the sliding speed during a slip, ~(F_s - F_c)/F_v ~ 5 mm/s >> 2 V_s, removes the
    Stribeck excess). Tolerance: 5 % of F_s - F_c for the overshoot/undershoot of the
    damped slip, and the period (F_s - F_c)/k_x within 3 % (same budget)."""
    _, s = mica_long
    dF = s["F_s"] - s["F_c"]
    assert s["regime"] == "regular"
    assert s["n_slips"] >= 5
    assert abs(s["static_friction_n"] - s["F_s"]) < 0.05 * dF
    assert abs(s["kinetic_friction_n"] - s["F_c"]) < 0.05 * dF
    assert s["period_m"] == pytest.approx(dF / s["k_x"], rel=0.03)
    # first slip after F_s / k_x of base travel (+ the pre-sliding tip motion ~ F_s/sigma0 ~ pm)
    assert s["first_slip_m"] == pytest.approx(s["F_s"] / s["k_x"], rel=0.005)
    assert s["slip_fraction"] < 0.1


def test_source_scan_range_is_pure_presliding():
    """SOURCE-NOTES 12: 10 nm < F_s/k_x = 65 nm -> no slip; force = k_x X up to the series
    compliance of the bristle, k_x X / (1 + k_x / sigma0) (relative 2e-5)."""
    res, s = F.run_ffm("mica")
    assert s["regime"] == "presliding" and s["n_slips"] == 0
    k = s["k_x"]
    ref = F.presliding_force(F.FFM.from_preset("mica"), res.base)
    assert np.allclose(res.lateral_force, ref, rtol=1e-4, atol=1e-4 * k * 1e-9)
    assert s["max_force_n"] == pytest.approx(k * 10e-9, rel=1e-4)


def test_presliding_branch_with_a_compliant_bristle():
    """With sigma0 = 1 N/m the pre-sliding curvature is visible (g0 = F_s/sigma0 = 13 nm); the
    quasi-static closed form x = g0 ln(1/(1 - z/g0)) holds while V << V_s (V/V_s = 0.2 here
    enters the Stribeck factor as exp(-(V/2V_s)^2) ~ 1 - 0.01, bounding the difference)."""
    ffm = F.FFM.from_preset("mica", overrides={"sigma0": 1.0})
    res = F.line_scan(ffm, 40e-9)
    ref = F.presliding_force(ffm, res.base)
    ok = np.isfinite(ref) & (ref < 0.9 * 12.95e-9)
    assert ok.sum() > 10
    err = np.max(np.abs(res.lateral_force[ok] - ref[ok]))
    assert err < 0.01 * 12.95e-9


def test_against_an_independent_bdf_solution():
    """The Rosenbrock integrator against scipy BDF with a Jacobian (tests/ffm_reference.py,
    written independently): slip positions and levels agree to well below the sampling error of
    the analysis (1e-3 relative)."""
    sys.path.insert(0, str(Path(__file__).parent))
    from ffm_reference import reference_scan

    ref = reference_scan(75e-9, n_out=20000)
    ours = F.line_scan(F.FFM.from_preset("mica"), 75e-9)
    a1 = analyze(ref["base"], ref["spring_force"])
    a2 = analyze(ours.base, ours.lateral_force)
    assert a1["n_slips"] == a2["n_slips"] >= 3
    assert a2["first_slip_m"] == pytest.approx(a1["first_slip_m"], rel=1e-3)
    assert a2["static_friction_n"] == pytest.approx(a1["static_friction_n"], rel=1e-4)
    assert a2["kinetic_friction_n"] == pytest.approx(a1["kinetic_friction_n"], rel=1e-4)


def test_integrator_converges_with_tolerance():
    """Tightening rtol 1e-4 -> 1e-7 changes the force trace by less than 1e-3 (F_s - F_c)
    (outside the slips, whose position moves by tiny amounts): the default is converged."""
    ffm = F.FFM.from_preset("mica")
    r1 = F.line_scan(ffm, 70e-9, rtol=1e-4)
    r2 = F.line_scan(ffm, 70e-9, rtol=1e-7)
    b = np.linspace(0, 64e-9, 2000)  # before the first slip
    d = np.abs(np.interp(b, r1.base, r1.lateral_force) - np.interp(b, r2.base, r2.lateral_force))
    assert d.max() < 1e-3 * 0.5e-9
    a1, a2 = analyze(r1.base, r1.lateral_force), analyze(r2.base, r2.lateral_force)
    assert a1["first_slip_m"] == pytest.approx(a2["first_slip_m"], rel=1e-4)


def test_full_2d_model_agrees_with_1d_reduction():
    """(2.16) cancels F_y in (2.14); after the y-transient (c_y/k_y = 70 ns) V_y = 0 and the
    x-motion is the 1D model: forces agree to 1e-3 (F_s - F_c); y -> -F_cy/k_y."""
    ffm = F.FFM.from_preset("mica")
    full = F.line_scan_2d(ffm, 68e-9, n_out=1500)
    one = F.line_scan(ffm, 68e-9)
    d = np.abs(np.interp(full["base"], one.base, one.lateral_force) - full["lateral_force"])
    assert d.max() < 1e-3 * 0.5e-9
    assert full["y"][-1] == pytest.approx(-12.45e-9 / 0.1, rel=1e-6)


def test_vamwcnt_preset_is_regular_with_the_printed_table():
    """Table 2.2: first slip F_s/k_x = 1.5 um, period (F_s - F_c)/k_x = 0.9 um, abrupt slips."""
    _, s = F.run_ffm("vamwcnt", length=3.5e-6)
    assert s["regime"] == "regular"
    assert s["first_slip_m"] == pytest.approx(1.5e-6, rel=0.005)
    assert s["period_m"] == pytest.approx(0.9e-6, rel=0.03)


def test_alpha_sweep_goes_from_smooth_sliding_to_stick_slip():
    rows = F.alpha_sweep([10.0, 1e4], length=100e-9)
    assert rows[0]["regime"] == "smooth" and rows[1]["regime"] == "regular"
    assert rows[1]["alpha"] == pytest.approx(1e8 / 0.2)


def test_friction_scale_moves_the_first_slip_proportionally():
    _, s1 = F.run_ffm("mica", length=80e-9)
    _, s2 = F.run_ffm("mica", length=160e-9, friction_scale=2.0)
    assert s2["first_slip_m"] == pytest.approx(2 * s1["first_slip_m"], rel=1e-3)
    _, s3 = F.run_ffm("mica", length=160e-9, normal_load=2 * 141.75e-9)
    assert s3["first_slip_m"] == pytest.approx(s2["first_slip_m"], rel=1e-9)


@pytest.mark.parametrize("over,msg", [({"k_x": -0.2}, "k_x.*positive"), ({"m_x": 0.0}, "m_x.*positive"),
                                      ({"F_c": 2e-8}, "F_c <= F_s"), ({"F_cy": 2e-8}, "F_cy"),
                                      ({"bogus": 1}, "unknown parameter")])
def test_non_physical_setups_raise_parameter_errors(over, msg):
    with pytest.raises(ParameterError, match=msg):
        F.FFM.from_preset("mica", overrides=over)


def test_unknown_preset_and_model():
    with pytest.raises(ParameterError, match="preset"):
        F.FFM.from_preset("graphite")
    with pytest.raises(ParameterError, match="friction model"):
        F.FFM.from_preset("mica", model="dahl")


def test_lugre_model_in_the_ffm():
    """LuGre (2.3)-(2.5) with the mica levels also gives the sawtooth between F_s and F_c
    (its Stribeck argument V/V_s differs from the bristle model's V/(2V_s): same limits)."""
    _, s = F.run_ffm("mica", model="lugre", length=80e-9)
    assert s["regime"] == "regular"
    assert abs(s["static_friction_n"] - s["F_s"]) < 0.05 * (s["F_s"] - s["F_c"])
