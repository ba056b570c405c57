"""The modal command line on the default cantilever: JSON contract, files, errors."""

import json

import meshio
import pytest

from probedyn.cli import main

COARSE = ["--set", "elements_through_thickness=1"]


def run_json(capsys, args):
    assert main(args + ["--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_modes_json_contract_and_files(capsys, tmp_path):
    res = run_json(capsys, ["modes", "cantilever", "--n-modes", "4", "--out", str(tmp_path), *COARSE])
    assert res["dofs"] > 0 and len(res["modes"]) == 4
    fams = {"flapwise", "lateral", "torsion", "axial", "other"}
    assert all(m["family"] in fams for m in res["modes"])
    # ordering of the default 300x30x10 um beam: flapwise (t < w) below lateral
    assert res["modes"][0]["family"] == "flapwise" and res["modes"][1]["family"] == "lateral"
    f = [m["frequency_hz"] for m in res["modes"]]
    assert f == sorted(f)
    mesh = meshio.read(tmp_path / "modes.vtu")
    assert len([k for k in mesh.point_data if "mode" in k.lower()]) >= 4
    assert json.loads((tmp_path / "modes.json").read_text())["dofs"] == res["dofs"]


def test_compare_with_tip_mass_shows_both_forms_of_3_10(capsys):
    # m/(rho A L) = 1: the standard form is within ~1 % of the FEM, the printed one >10 % off
    m_beam = 2330 * 300e-6 * 30e-6 * 10e-6
    res = run_json(capsys, ["compare", "cantilever", "--n-modes", "2", "--set", f"tip_mass={m_beam}",
                            "--set", "poisson_ratio=0", *COARSE])
    first = [r for r in res["comparison"] if r["family"] == "flapwise" and r["order"] == 1]
    by = {("printed" if "printed" in r["formula"] else "standard"): r for r in first}
    assert abs(by["standard"]["rel_diff"]) < 0.01
    assert abs(by["printed"]["rel_diff"]) > 0.10


def test_reduce_first_mode_effective_mass_is_quarter_beam_mass(capsys):
    # Euler-Bernoulli: m_eff of mode 1 at the tip = rho A L / 4 (3D FEM within 2 % on a coarse mesh)
    res = run_json(capsys, ["reduce", "cantilever", "--n-modes", "2", "--q", "100", "--set", "poisson_ratio=0", *COARSE])
    m1 = res["lumped"][0]
    assert m1["family"] == "flapwise"
    m_beam = 2330 * 300e-6 * 30e-6 * 10e-6
    assert m1["mass"] == pytest.approx(m_beam / 4, rel=0.02)
    assert m1["stiffness"] == pytest.approx((2 * 3.141592653589793 * m1["frequency_hz"]) ** 2 * m1["mass"], rel=1e-9)
    st = res["static"]
    assert st["fem_n_per_m"] == pytest.approx(st["with_shear_correction"], rel=0.02)


def test_params_lists_units_and_defaults(capsys):
    res = run_json(capsys, ["params", "cantilever"])
    by = {p["name"]: p for p in res["parameters"]}
    for name in ("length", "width", "thickness", "material", "youngs_modulus", "poisson_ratio", "density", "tip_mass"):
        assert name in by
    assert by["length"]["unit"] == "m" and by["length"]["default"] == pytest.approx(300e-6)


def test_toml_probe_file(capsys, tmp_path):
    spec = tmp_path / "probe.toml"
    spec.write_text('probe = "cantilever"\nlength = 400e-6\nelements_through_thickness = 1\n')
    short = run_json(capsys, ["modes", "cantilever", "--n-modes", "1", *COARSE])
    long = run_json(capsys, ["modes", str(spec), "--n-modes", "1"])
    # f1 ~ 1/L^2 (Euler-Bernoulli); shear makes the short beam a little softer: within 1 %
    ratio = short["modes"][0]["frequency_hz"] / long["modes"][0]["frequency_hz"]
    assert ratio == pytest.approx((400 / 300) ** 2, rel=0.01)


@pytest.mark.parametrize("args,needle", [
    (["--set", "length=-1e-6"], "positive"),
    (["--set", "length=300"], "micrometres"),
    (["--set", "material=unobtainium"], "material"),
    (["--set", "colour=red"], "unknown parameter"),
    (["--set", "thickness=0"], "positive"),
])
def test_bad_input_is_one_line_error(capsys, args, needle):
    assert main(["modes", "cantilever", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("probedyn: error:") and needle in err[0]


def test_mesh_too_coarse_for_requested_modes(capsys):
    # one element layer (~30 elements along 300 um) cannot carry 100 modes (~50 half-waves):
    # refused before solving, with a hint
    assert main(["modes", "cantilever", "--n-modes", "100", "--set", "elements_through_thickness=1"]) == 2
    err = capsys.readouterr().err
    assert "probedyn: error:" in err and "coarse" in err


def test_bad_input_through_the_installed_entry_point():
    # once through a real process: exit code 2, one stderr line, no traceback
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "probedyn.cli", "modes", "cantilever", "--set", "length=300"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("probedyn: error:") and "Traceback" not in proc.stderr
