"""``probedyn contact`` and the contact report section."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from probedyn.cli import main


def _run_json(args, capsys):
    assert main(["contact", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("model,expected", [("dmt", -2.0), ("jkr", -1.5)])
def test_limits_from_the_command_line(model, expected, capsys):
    res = _run_json(["--model", model], capsys)
    assert res["pull_off_normalized"] == pytest.approx(expected, abs=1e-9)


def test_md_json_has_pull_off_curve_and_published_fit(capsys):
    res = _run_json(["--model", "md", "--lambda", "0.5"], capsys)
    assert res["lam"] == 0.5
    fit = res["pull_off_published_fit"]
    assert abs(fit["relative_difference"]) < 0.02
    c = res["curve"]
    n = len(c["penetration_normalized"])
    assert n > 100 and len(c["load_normalized_loading"]) == n
    # DMT-like lambda: no gaps; loading and unloading coincide but where Maugis' own non-contact branch holds the
    # retract (from its fold, the jump-out, to the end of the approach's free state D_free = -2 / (pi lam)), more
    # adhesive there
    assert all(v is not None for v in c["load_normalized_loading"])
    D = np.array(c["penetration_normalized"])
    lo, un = np.array(c["load_normalized_loading"]), np.array(c["load_normalized_unloading"])
    held = (D >= res["jump_out_penetration_normalized"]) & (D < -2 / (math.pi * 0.5))
    assert held.sum() >= 3 and np.all(un[held] < lo[held])
    assert lo[~held] == pytest.approx(un[~held], abs=1e-12)
    # dimensional pull-off = normalised * pi W R
    p = res["parameters"]
    assert res["pull_off_n"] == pytest.approx(res["pull_off_normalized"] * math.pi * p["W_j_m2"] * p["R_m"], rel=1e-12)


def test_out_folder_gets_json_and_plot(tmp_path, capsys):
    assert main(["contact", "--model", "md", "--lambda", "3", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "contact.json").stat().st_size > 1000
    assert (tmp_path / "contact_md.png").stat().st_size > 10000
    out = capsys.readouterr().out
    assert "pull-off" in out


@pytest.mark.parametrize("args", [["--lambda", "-1"], ["--model", "hertz"], ["--set", "E_t=-3"],
                                  ["--set", "nu_s=0.9"], ["--set", "nonsense=1"]])
def test_bad_input_is_a_one_line_error(args):
    proc = subprocess.run([sys.executable, "-m", "probedyn.cli", "contact", *args],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("probedyn: error:"), proc.stderr


def test_fig_2_19_and_pull_off_table(tmp_path):
    from probedyn.report.contact import plot_fig_2_19
    from probedyn.schemes.contact.carpick import pull_off_table

    path = plot_fig_2_19(tmp_path / "fig.png")
    assert path.stat().st_size > 20000
    rows = pull_off_table((1e-3, 0.3, 3.0, 1e3))
    assert rows[0]["pull_off"] == pytest.approx(-2.0, rel=0.01)
    assert rows[-1]["pull_off"] == pytest.approx(-1.5, rel=0.01)
    assert all(abs(r["rel_diff_pct"]) < 2 for r in rows)


@pytest.mark.slow
def test_report_section_quick(tmp_path):
    from probedyn.report.contact import section

    md = section(tmp_path, quick=True)
    assert "contact_fig_2_19.png" in md and "coupling_fig_2_22.png" in md
    assert (tmp_path / "contact_fig_2_19.png").exists() and (tmp_path / "coupling_fig_2_22.png").exists()
    assert "Verdict" in md


def test_model_help_lists_every_registry_law():
    """``--model``'s help is built from the contact registry, so a law added as one file is offered."""
    from probedyn.schemes.contact import list_models

    proc = subprocess.run([sys.executable, "-m", "probedyn.cli", "contact", "--help"], capture_output=True, text=True,
                          timeout=120, env={**__import__("os").environ, "COLUMNS": "400"})
    assert proc.returncode == 0
    text = " ".join(proc.stdout.split())
    for key in list_models():
        assert f"{key} (" in text, key


@pytest.mark.parametrize("model", ["cone", "pyramid"])
def test_non_adhesive_law_prints_only_what_it_defines(model, capsys, tmp_path):
    """A law without attraction has no W, lambda, pull-off, jump-out or Maugis units: the command prints none
    of them; the load at the cap edge (contact radius R cos alpha) is Sneddon's rigid sphere's there (the cap is
    the sphere of the tip radius up to its edge; Briscoe et al.), an independent check of the number printed."""
    from probedyn.schemes.contact import CONTACT_MODELS

    adhesive = {c.key: c.adhesive for c in CONTACT_MODELS}
    assert adhesive == {"cone": False, "pyramid": False, "dmt": True, "jkr": True, "md": True, "md-vdw": True}
    res = _run_json(["--model", model, "--set", "alpha=0.5"], capsys)
    assert res["adhesive"] is False
    for key in ("lam", "pull_off_n", "pull_off_normalized", "jump_out_load_normalized", "contact_transition",
                "pull_off_published_fit"):
        assert key not in res
    p = res["parameters"]
    E, R, d = p["E_star_pa"], p["R_m"], p["cap_edge_depth_m"]
    a = R * math.cos(p["equivalent_cone_half_angle_rad"])  # the cap's edge
    L = math.log((R + a) / (R - a))
    assert d == pytest.approx(a / 2 * L, rel=1e-12)  # the sphere's penetration at that contact radius
    assert res["cap_edge_load_n"] == pytest.approx(E * ((R * R + a * a) * L / 2 - a * R), rel=1e-6)
    assert main(["contact", "--model", model, "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out.lower()
    assert "pull-off force" not in out and "lambda" not in out and "jump-out:" not in out
    assert "no pull-off" in out and "cap edge" in out
    assert (tmp_path / f"contact_{model}.png").stat().st_size > 10000
