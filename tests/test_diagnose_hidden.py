"""Hidden-effect tests: measurements from a richer truth model carrying one catalog effect.

The generator (tests/diagnose_truth.py) is independent of probedyn's models: exact transfer-
matrix beams and a sequential Prandtl-Tomlinson tracker. The measurement file holds only what
an experimentalist would have (nominal spec, measured values, stated noise); the truth stays here.

Tolerances (stated once):
* parameter recovery: |fit - truth| <= max(0.25 |truth - neutral|, 3 sigma_fit) (25 % of the
  effect size, or three standard errors where the data constrain it less, e.g. a light
  fluid's density against its viscosity). The
  default cases use the strong half of each range (baseline misfit >~ 10 sigma), where the
  noise alone limits the effect size to ~10 %; the rest is left for parameter correlation
  (point mass: mass vs position) -- the slow study reports the full distribution.
* held-out gain: the held-out RMS must drop by a factor >= 2 (a correct cause brings it
  from >~ 3 sigma to ~1 sigma).
* null cases: with alpha = 0.01 and a Bonferroni-corrected LR test a null case claims a
  cause with probability < 1 %; fixed seeds keep the default run deterministic.
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from diagnose_truth import (MODAL_EFFECTS, make_friction_case, make_modal_case, modal_truth,  # noqa: E402
                            write_modal)

from probedyn.diagnose.engine import diagnose  # noqa: E402

MAIN = {"clamp-compliance": ("kappa_r", None), "point-mass": ("mu", 0.0), "thickness-error": ("t_ratio", 1.0),
        "width-error": ("w_ratio", 1.0), "length-error": ("L_ratio", 1.0), "anisotropy": ("e_ratio", 1.0),
        "fluid-loading": ("rho_f", 0.0), "axial-prestress": ("p", 0.0), "velocity-log": ("slip_b", 0.0),
        "force-offset-drift": ("offset", 0.0), "adhesion-load": ("n_adh", 0.0)}


def _check_found(res, effect, truth):
    assert res["verdict"] in ("explained", "partly-explained"), res["summary"]
    f0 = res["findings"][0]
    assert f0["cause"] == effect, res["summary"]
    assert f0["status"] == "identified"
    name, neutral = MAIN[effect]
    fit, t = f0["parameters"][name]["value"], truth[name]
    sd = f0["parameters"][name]["sigma"]
    if neutral is None:  # a compliance: compare 1/kappa
        assert abs(1 / fit - 1 / t) <= max(0.25 / t, 3 * sd / fit**2), (fit, t, sd)
    else:
        assert abs(fit - t) <= max(0.25 * abs(t - neutral), 3 * sd), (fit, t, sd)
    g = f0["gain"]
    assert g["residual_rms_after"] < g["residual_rms_before"]
    assert g["heldout_rms_before"] / g["heldout_rms_after"] >= 2.0, g
    # the truth never appears in the measurement file
    text = Path(res["measurement"]).read_text() + Path(res["measurement"]).with_suffix(".csv").read_text()
    assert effect not in text and "truth" not in text


@pytest.mark.parametrize("effect", MODAL_EFFECTS)
def test_modal_hidden_effect_named_first(effect, tmp_path):
    seed = 100 + MODAL_EFFECTS.index(effect)
    path, truth = make_modal_case(tmp_path, effect, seed, strength=0.5)
    res = diagnose(path)
    _check_found(res, effect, truth)
    from probedyn.core.io import dumps

    json.loads(dumps(res))  # JSON-able through the project encoder


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_modal_null_claims_nothing(seed, tmp_path):
    path, _ = make_modal_case(tmp_path, None, seed)
    res = diagnose(path)
    # nothing is claimed; the chi-square test alone may flag ~1 % of null cases ("unexplained")
    assert res["findings"] == [] and res["verdict"] in ("no-significant-discrepancy", "unexplained"), res["summary"]


def test_confounded_tip_mass_vs_thickness_with_one_mode(tmp_path):
    """One flapwise mode: a tip mass and a thickness error both fit exactly -> confounded, not guessed."""
    f, q = modal_truth("point-mass", {"mu": 0.04, "xi": 1.0}, modes=[("flap", 1)])
    path = write_modal(tmp_path, "one", f * (1 + 3e-4), q, modes=[("flap", 1)], with_q=False)
    res = diagnose(path)
    assert res["confounded"], res["summary"]
    group = res["confounded"][0]["causes"]
    assert "point-mass" in group and "thickness-error" in group
    assert res["findings"][0]["status"] == "confounded"
    gm = res["confounded"][0]["group_measurement"]
    # the recommended measurements must separate tip mass from thickness by > 3 sigma (1e-3 noise)
    sep = [abs(m["predictions"]["point-mass"] - m["predictions"]["thickness-error"]) / (1e-3 * m["predictions"]["point-mass"])
           for m in gm["measurements"]]
    assert max(sep) > 3.0
    # and with a second flapwise mode the two are told apart: the truth (point mass) wins
    f2, q2 = modal_truth("point-mass", {"mu": 0.04, "xi": 1.0}, modes=[("flap", 1), ("flap", 2)])
    path2 = write_modal(tmp_path, "two", f2 * (1 + 3e-4), q2, modes=[("flap", 1), ("flap", 2)], with_q=False)
    res2 = diagnose(path2)
    tops = [res2["findings"][0]["cause"]] + res2["findings"][0]["confounded_with"]
    assert "point-mass" in tops and "thickness-error" not in tops, res2["summary"]


@pytest.mark.parametrize("effect", ["force-offset-drift"])
def test_friction_hidden_effect_named_first(effect, tmp_path):
    path, truth = make_friction_case(tmp_path, effect, 3, strength=0.5)
    res = diagnose(path)
    _check_found(res, effect, truth)


def test_friction_null_claims_nothing(tmp_path):
    path, _ = make_friction_case(tmp_path, None, 4)
    res = diagnose(path)
    assert res["findings"] == [] and res["verdict"] == "no-significant-discrepancy", res["summary"]


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["modal", "friction"])
def test_rates_over_seeded_cases(kind, tmp_path):
    """>= 50 hidden-effect and >= 50 null cases per data kind (full magnitude ranges)."""
    from diagnose_rates import study

    s = study(kind, 54 if kind == "friction" else 56, 50, tmp_path / "rates.json")
    print(json.dumps(s, indent=1))
    # thresholds: effects are drawn down to ~the detection limit, so not every one is found;
    # the false-discovery rate is bounded by alpha = 1 % per case (+ binomial scatter on 50).
    assert s["detection_rate"] >= 0.8
    assert s["correct_among_detected"] >= 0.8
    assert s["false_discovery_rate"] <= 0.06
