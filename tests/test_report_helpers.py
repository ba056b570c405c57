"""Helpers of the report layer and the library functions moved out of the commands (issue 9):
exact or limit-case checks, no FEM (fast)."""

import math

import numpy as np
import pytest

from probedyn.lumped.holder_sweep import lumped_holder_sweep, pair_by_family
from probedyn.lumped.smart import SmartLumpedModel
from probedyn.report._tables import cell, markdown_table
from probedyn.report.smart_probes import _reference_orders, _tracks
from probedyn.schemes.contact.carpick import cos_fit_pull_off


def _lumped(kt=(0.1, 10.0)):
    J = np.diag([1.6e-7, 1.6e-7])
    K2 = np.diag([96.0, 10.8])
    lm = SmartLumpedModel(["y", "z"], J, K2, np.zeros((2, 2)), 5e-8, np.array(kt, float))
    return lm, lm.to_dict()


def test_holder_sweep_reproduces_the_model_and_its_rigid_limit():
    lm, d = _lumped((3.0, 3.0))
    sw = lumped_holder_sweep(d, [3.0, 3.0], ("y", "z"), n=1)
    np.testing.assert_allclose(sw["f"][0], lm.modes()[0], rtol=1e-12)
    # k_t -> infinity: the tip moves with the holder, body mode with the added mass m
    sw = lumped_holder_sweep(d, [1e9, 1e9], ("y", "z"), n=1)
    rigid = sorted(math.sqrt(d["K2"][i][i] / (d["J"][i][i] + d["m"])) / (2 * math.pi) for i in range(2))
    np.testing.assert_allclose(sw["f"][0][:2], rigid, rtol=1e-6)


def test_holder_sweep_keeps_unswept_springs():
    lm, d = _lumped((0.1, 10.0))
    sw = lumped_holder_sweep(d, [0.1, 0.1], ("y",), n=1)  # y at its own value, z untouched
    np.testing.assert_allclose(sw["f"][0], lm.modes()[0], rtol=1e-12)


def test_pair_by_family_never_divides_different_families():
    a = [("flapwise", 100.0), ("lateral", 300.0), ("torsion", 2000.0), ("axial", 4000.0)]
    b = [("flapwise", 200.0), ("lateral", 600.0), ("torsion", 4000.0), ("flapwise", 5000.0)]
    rows = pair_by_family(a, b)
    for r in rows:
        if r["ratio"] is not None:
            assert r["f_b"] / r["f_a"] == r["ratio"]
    assert [(r["family"], r["order"], r["ratio"]) for r in rows] == [
        ("flapwise", 1, 2.0), ("lateral", 1, 2.0), ("torsion", 1, 2.0), ("axial", 1, None), ("flapwise", 2, None)]


def test_degenerate_pair_is_one_track_and_one_analytic_order():
    rows = [{"k_t": k, "mode": i, "frequency_hz": f, "direction": d}
            for k in (1.0, 100.0)
            for i, f, d in ((1, 700.0 * k, "lateral"), (2, 700.0 * k, "lateral"), (3, 701.0 * k, "axial"))]
    tracks = _tracks(rows, [1.0, 100.0])
    assert [t for t, _ in tracks] == [[1, 2], [3]]
    assert "degenerate lateral pair" in tracks[0][1]
    refs = [{"direction": "lateral", "formula": "f", "value_hz": v} for v in (5.0, 5.0, 9.0, 9.0)]
    assert [r["n"] for r in _reference_orders(refs)] == ["1", "1 (pair)", "2", "2 (pair)"]


def test_frequency_cells_use_one_format():
    assert cell(1298.31, "hz") == "1.2983 kHz"
    assert cell(44905.49, "hz6") == "44.9055 kHz"
    assert cell(None, "hz") == "–"
    md = markdown_table([{"f": 711.74}], [("f", "f", "hz")])
    assert md.splitlines()[-1] == "| 711.74 Hz |"


def test_cos_fit_limits():
    # the COS fit gives the DMT pull-off -2 pi W R exactly at lambda = 0; as lambda -> inf its
    # alpha tends to 1/1.02, not 1, so it reaches JKR's -1.5 within its stated ~1 % accuracy
    assert cos_fit_pull_off(0.0) == pytest.approx(-2.0, abs=1e-12)
    assert cos_fit_pull_off(float("inf")) == pytest.approx(-1.5, rel=0.01)
