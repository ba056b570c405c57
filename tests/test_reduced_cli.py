"""``--probe`` on the scheme commands and ``probedyn reduced-probe``."""

from __future__ import annotations

import json
import math

import pytest

from probedyn.cli import main

FEM = ["--probe", "cantilever", "--probe-set", "tip_shape=pyramid", "--probe-set", "elements_through_thickness=1",
       "--probe-modes", "4"]


def _json(args, capsys):
    assert main([*args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_ffm_with_a_table_probe_is_the_preset(capsys):
    a = _json(["simulate", "ffm", "--preset", "vamwcnt", "--length", "4e-6"], capsys)
    b = _json(["simulate", "ffm", "--preset", "vamwcnt", "--length", "4e-6", "--probe", "table-2.2"], capsys)
    assert b["probe"]["source"] == "Table 2.2" and a["probe"] is None and a["probe_source"].startswith("Table 2.2")
    assert b["period_m"] == pytest.approx(a["period_m"], rel=1e-9) and b["k_x"] == a["k_x"]


def test_ffm_with_the_fem_probe(capsys):
    d = _json(["simulate", "ffm", "--preset", "vamwcnt", *FEM], capsys)
    p = d["probe"]
    assert p["source"] == "FEM" and p["mesh_key"] and p["dofs"] > 1000
    assert d["k_x"] == pytest.approx(p["scan"]["static_stiffness"], rel=1e-12)
    assert d["regime"] == "regular" and "scan_note" in d
    # the sawtooth period lies between the quasi-static (F_s - F_c)/k (critically damped probe)
    # and twice it (an undamped slip overshoots to 2 F_c - F_s)
    assert d["period_estimate_m"] < d["period_m"] < 2 * d["period_estimate_m"]


def test_contact_force_curve_with_the_probe(capsys):
    d = _json(["contact", "--model", "dmt", *FEM], capsys)
    fc = d["force_curve"]
    k = d["probe"]["normal"]["static_stiffness"]
    H, R = d["parameters"]["H_j"], d["parameters"]["R_m"]
    assert fc["k"] == pytest.approx(k) and fc["predicted_tail_jump_gap"] == pytest.approx((H * R / (3 * k)) ** (1 / 3))
    # k_n ~ 49 N/m: d* = 0.16 nm is inside the tail's end (zeta_0): no jump either way
    assert fc["predicted_tail_jump_gap"] < fc["tail_end_gap"] and fc["jump_in"] is None


def test_stickslip_u0_psi_from_the_probe(capsys):
    # Table 4.3 as the probe: U0 = 25 k a^2 / 4 pi^2 gives u0 = 25; x0 = a/4 gives psi = pi/2
    from probedyn.schemes.stickslip import TwoMassModel

    tm = TwoMassModel()
    d = _json(["stickslip", "equilibria", "--probe", "table-4.3", "--U0", repr(tm.U0_from_u0(25.0)),
               "--x0", repr(tm.a / 4)], capsys)
    assert d["u0"] == pytest.approx(25.0, rel=1e-9) and d["psi"] == pytest.approx(math.pi / 2, rel=1e-9)
    assert any(line.startswith("(4.7)  u0") for line in d["scaling"]["derivation"])
    assert main(["stickslip", "equilibria", "--probe", "table-4.3", "--U0", repr(tm.U0_from_u0(25.0))]) == 0
    assert "scaling of section 4.1.3" in capsys.readouterr().out


def test_reduced_probe_command(capsys, tmp_path):
    f = tmp_path / "p.json"
    d = _json(["reduced-probe", "cantilever", "--set", "tip_shape=pyramid", "--set", "elements_through_thickness=1",
               "--modes", "4", "--out", str(f)], capsys)
    assert f.exists() and (tmp_path / "p.ritz.npz").exists()
    back = _json(["reduced-probe", str(f)], capsys)
    assert back["static_compliance"] == d["static_compliance"]
    t = _json(["reduced-probe", "table-4.1"], capsys)
    assert t["provenance"]["source"] == "Table 4.1"


@pytest.mark.parametrize("args", [
    ["simulate", "ffm", "--probe-set", "length=1e-4"],
    ["stickslip", "equilibria", "--probe", "table-4.3"],
    ["simulate", "ffm", "--probe", "table-3.2"],
    ["reduced-probe", "table-2.1", "--q", "10"],
])
def test_bad_probe_input_exits_2(args, capsys):
    assert main(args) == 2
    assert "probedyn: error:" in capsys.readouterr().err


@pytest.mark.slow
def test_push_with_a_table_probe_is_the_preset(capsys):
    a = _json(["simulate", "push"], capsys)
    b = _json(["simulate", "push", "--probe", "table-4.1"], capsys)
    assert b["mean_step_m"] == pytest.approx(a["mean_step_m"], rel=1e-9) and b["probe"]["source"] == "Table 4.1"
