"""``probedyn simulate ffm`` and the friction report section."""

import json

import pytest

from probedyn.cli import main


def _json(args, capsys):
    assert main(["simulate", "ffm", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_json_has_the_required_fields(capsys):
    d = _json(["--preset", "mica"], capsys)
    for key in ("static_friction_n", "kinetic_friction_n", "period_m", "regime"):
        assert key in d
    # the source's 10 nm scan never reaches F_s / k_x = 65 nm: no slip (SOURCE-NOTES 12);
    # the command says so and extends the scan to measure the regular stick-slip
    assert d["preset_scan"]["regime"] == "presliding" and d["preset_scan"]["n_slips"] == 0
    assert d["preset_scan"]["scan_length_m"] == pytest.approx(10e-9)
    assert d["regime"] == "regular"
    F_s, F_c, k = 12.95e-9, 12.45e-9, 0.2  # Table 2.1
    # quasi-static sawtooth: peaks at F_s, valleys near F_c, period (F_s - F_c)/k_x;
    # overdamped slips stop within a few % of the sawtooth amplitude of F_c
    assert d["static_friction_n"] == pytest.approx(F_s, rel=1e-3)
    assert abs(d["kinetic_friction_n"] - F_c) < 0.05 * (F_s - F_c)
    assert d["period_m"] == pytest.approx((F_s - F_c) / k, rel=0.05)
    assert d["first_slip_estimate_m"] == pytest.approx(12.95e-9 / 0.2)


def test_long_scan_with_set_and_model(capsys, tmp_path):
    d = _json(["--preset", "mica", "--length", "9e-8", "--model", "lugre", "--set", "sigma1=0",
               "--out", str(tmp_path)], capsys)
    assert d["regime"] == "regular" and d["model"] == "lugre"
    assert abs(d["static_friction_n"] - 12.95e-9) < 0.05 * 0.5e-9
    assert (tmp_path / "ffm_mica_lugre.png").exists()
    assert json.loads((tmp_path / "ffm_mica_lugre.json").read_text())["regime"] == "regular"


def test_human_output(capsys):
    assert main(["simulate", "ffm", "--preset", "vamwcnt", "--length", "2e-6"]) == 0
    out = capsys.readouterr().out
    assert "regime: regular" in out and "static friction" in out


@pytest.mark.parametrize("args,msg", [
    (["--set", "k_x=-0.1"], "k_x"), (["--set", "F_c=2e-8"], "F_c <= F_s"),
    (["--preset", "gold"], "preset"), (["--model", "dahl"], "friction model"), (["--set", "m_x=-1"], "m_x"),
])
def test_bad_input_is_a_one_line_error(args, msg, capsys):
    assert main(["simulate", "ffm", *args]) == 2
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err


@pytest.mark.slow
def test_report_section(tmp_path):
    from probedyn.report.friction import section

    md = section(tmp_path, quick=True)
    assert "friction_mica.png" in md and (tmp_path / "friction_pt2d.png").exists()
