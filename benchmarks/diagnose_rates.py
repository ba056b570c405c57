"""Detection, correct-cause and false-discovery rates of ``probedyn diagnose`` on seeded cases.

Usage: ``python benchmarks/diagnose_rates.py KIND N_EFFECT N_NULL [OUT.json [START]]`` with KIND modal or
friction. Each hidden-effect case draws one catalog effect (cycling through the effects) with a
seeded random magnitude over the full range of tests/diagnose_truth.py (from about the
detection limit up), generates the measurement with the independent truth model plus noise,
and runs the diagnosis. Reported:

* detection rate: verdict is not "no-significant-discrepancy" and something is claimed;
* correct-cause rate: the first finding (or, if confounded, the first of its group) is the effect;
* parameter recovery: |fit - truth| / |truth - neutral| of the effect's main parameter;
* held-out gain: heldout_rms_before / heldout_rms_after of the first finding;
* false-discovery rate over null cases (noise only): fraction with any finding;
* the run time of each diagnosis.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from diagnose_truth import (FRICTION_EFFECTS, MODAL_EFFECTS, make_friction_case,  # noqa: E402
                            make_modal_case)

from probedyn.diagnose.engine import diagnose  # noqa: E402

MAIN = {"clamp-compliance": ("kappa_r", None), "point-mass": ("mu", 0.0), "thickness-error": ("t_ratio", 1.0),
        "width-error": ("w_ratio", 1.0), "length-error": ("L_ratio", 1.0), "anisotropy": ("e_ratio", 1.0),
        "fluid-loading": ("rho_f", 0.0), "axial-prestress": ("p", 0.0), "velocity-log": ("slip_b", 0.0),
        "scanner-nonlinearity": ("bow", 0.0), "force-offset-drift": ("offset", 0.0),
        "lattice-misalignment": ("theta", 0.0), "viscous-friction": ("visc", 0.0), "adhesion-load": ("n_adh", 0.0)}


def recovery_error(effect, truth, finding):
    name, neutral = MAIN[effect]
    fit = finding["parameters"][name]["value"]
    t = truth[name]
    if neutral is None:  # clamp stiffness: compliance 1/kappa is the effect size
        return abs(1 / fit - 1 / t) / (1 / t)
    return abs(fit - t) / abs(t - neutral)


def run_case(kind, effect, seed, folder, strength=1.0):
    mk = make_modal_case if kind == "modal" else make_friction_case
    path, truth = mk(folder, effect, seed, strength=strength)
    t0 = time.perf_counter()
    res = diagnose(path)
    dt = time.perf_counter() - t0
    out = {"effect": effect, "seed": seed, "truth": truth, "verdict": res["verdict"], "runtime_s": dt,
           "findings": [f["cause"] for f in res["findings"]], "confounded": res["confounded"]}
    if effect and res["findings"]:
        f0 = res["findings"][0]
        group = [f0["cause"], *f0.get("confounded_with", [])]
        out["first"] = f0["cause"]
        out["correct"] = f0["cause"] == effect
        out["correct_in_group"] = effect in group
        if f0["cause"] == effect:
            out["recovery_error"] = recovery_error(effect, truth, f0)
            g = f0["gain"]
            if g["heldout_rms_before"] and g["heldout_rms_after"]:
                out["heldout_gain"] = g["heldout_rms_before"] / g["heldout_rms_after"]
    out["detected"] = bool(res["findings"])
    return out


def study(kind, n_effect, n_null, out=None, start=0):
    effects = MODAL_EFFECTS if kind == "modal" else FRICTION_EFFECTS
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for i in range(start, start + n_effect):
            rows.append(run_case(kind, effects[i % len(effects)], 1000 + i, d))
            if out:
                Path(out).write_text(json.dumps({"rows": rows}, indent=1, default=float))
        for i in range(start, start + n_null):
            rows.append(run_case(kind, None, 5000 + i, d))
            if out:
                Path(out).write_text(json.dumps({"rows": rows}, indent=1, default=float))
    return summarize(kind, rows, out)


def summarize(kind, rows, out=None):
    eff = [r for r in rows if r["effect"]]
    null = [r for r in rows if not r["effect"]]
    rec = [r["recovery_error"] for r in eff if "recovery_error" in r]
    gains = [r["heldout_gain"] for r in eff if "heldout_gain" in r]
    per = {}
    for e in dict.fromkeys(r["effect"] for r in eff):
        sub = [r for r in eff if r["effect"] == e]
        er = [r["recovery_error"] for r in sub if "recovery_error" in r]
        per[e] = {"n": len(sub), "detected": sum(r["detected"] for r in sub),
                  "correct_first": sum(r.get("correct", False) for r in sub),
                  "median_recovery_error": float(np.median(er)) if er else None}
    s = {
        "kind": kind, "n_effect": len(eff), "n_null": len(null),
        "detection_rate": float(np.mean([r["detected"] for r in eff])) if eff else None,
        "correct_cause_rate": float(np.mean([r.get("correct", False) for r in eff])) if eff else None,
        "correct_among_detected": float(np.mean([r.get("correct", False) for r in eff if r["detected"]])) if any(r["detected"] for r in eff) else None,
        "correct_or_confounded_group": float(np.mean([r.get("correct_in_group", False) for r in eff])) if eff else None,
        "false_discovery_rate": float(np.mean([r["detected"] for r in null])) if null else None,
        "recovery_error_median": float(np.median(rec)) if rec else None,
        "recovery_error_p90": float(np.percentile(rec, 90)) if rec else None,
        "heldout_gain_median": float(np.median(gains)) if gains else None,
        "runtime_median_s": float(np.median([r["runtime_s"] for r in rows])),
        "per_effect": per,
    }
    if out:
        Path(out).write_text(json.dumps({"summary": s, "rows": rows}, indent=1, default=float))
    return s


if __name__ == "__main__":
    kind, ne, nn = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    out = sys.argv[4] if len(sys.argv) > 4 else None
    start = int(sys.argv[5]) if len(sys.argv) > 5 else 0
    print(json.dumps(study(kind, ne, nn, out, start), indent=1))
