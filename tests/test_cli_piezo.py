"""``probedyn actuate`` and ``probedyn modes --electrodes`` (coarse meshes)."""

from __future__ import annotations

import json

import pytest

from probedyn.cli import main

COARSE = ["--set", "element_size=400e-6", "--set", "holder=point", "--set", "tip=none"]


def test_actuate_pattern_json_and_files(capsys, tmp_path):
    assert main(["actuate", "piezotube", *COARSE, "--pattern", "V_z", "--volts", "10", "--json",
                 "--out", str(tmp_path)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["voltages"] == {e: 10.0 for e in ("electrode_yp", "electrode_zp", "electrode_ym", "electrode_zm")}
    ux, uy, uz = r["tip_displacement_m"]
    assert ux > 0 and abs(uy) < 1e-6 * ux and abs(uz) < 1e-6 * ux  # +V outside: the tube extends
    assert (tmp_path / "actuate.vtu").stat().st_size > 1000
    assert json.loads((tmp_path / "actuate.json").read_text())["pattern"] == "V_z"


def test_actuate_electrodes_with_one_voltage_each(capsys):
    assert main(["actuate", "piezotube", *COARSE, "--electrode", "electrode_zp", "--electrode", "electrode_zm",
                 "--volts", "-1", "--volts", "1", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["tip_displacement_m"][2] > 0


@pytest.mark.parametrize("args,msg", [
    (["actuate", "piezotube", "--electrode", "electrode_foo"], "unknown electrode 'electrode_foo'"),
    (["actuate", "piezotube", "--set", "material=pzt-5h-iso", "--pattern", "V_x"], "no piezoelectric constants"),
    (["actuate", "cantilever", "--pattern", "V_x"], "no piezoelectric actuation"),
    (["actuate", "piezotube", "--pattern", "V_w"], "unknown drive pattern"),
    (["modes", "piezotube", "--electrodes", "sideways"], "--electrodes must be short, open or both"),
])
def test_bad_input_one_line_exit_2(capsys, args, msg):
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("probedyn: error:") and msg in err[0]


def test_modes_short_runs(capsys):
    assert main(["modes", "piezotube", *COARSE, "--electrodes", "short", "--n-modes", "2", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["electrodes"] == "short" and len(r["modes"]) == 2 and r["modes"][0]["frequency_hz"] > 0


@pytest.mark.slow
def test_modes_short_and_open_give_keff(capsys):
    assert main(["modes", "piezotube", *COARSE, "--electrodes", "both", "--n-modes", "3", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    lat = [r for r in rows if r["family"] in ("lateral", "flapwise")]
    assert lat and all(r["f_oc_hz"] > r["f_sc_hz"] and 0.02 < r["k_eff2"] < 0.2 for r in lat)
