"""Correct-cause, false-discovery and parameter-recovery rates of the diagnosis of mesoscale friction
loops (:mod:`probedyn.diagnose.friction_loop`) on seeded independent truths.

Usage: ``python benchmarks/diagnose_rates_loops.py N_EFFECT N_NULL OUT.json`` (resumable: the cases in
OUT.json are skipped; the file is rewritten after every case).

Truth: ``tests/diagnose_truth_loops.py`` (the tip's force balance on the incline solved per point,
Coulomb friction, islands of a second phase, lateral calibration factor 0.7-1.4 in half the cases,
friction contrast in half, feedback lag 0-2 samples, adhesion up to half the load). Hidden effect:
``surface-slope`` (seeds 7000 + 2 i), with the islands' friction contrast a second effect where the case
draws one (session 22: ``friction-contrast`` is a cause; a first finding among the case's effects is right,
``slope_first`` counts the earlier criterion); noise-only: a flat surface tilted by up to 1 % (seeds 7001 + 2 i).
Reported as the other rate studies: correct cause first, false discoveries (any finding on a null),
the median ``|g_fit - g| / g`` (the calibration factor derived from the coupling,
:func:`probedyn.diagnose.causes.surface_slope.calibration_factor`, against the truth's), every miss with its class, CPU time per case.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from diagnose_truth_loops import make_loop_case  # noqa: E402

from probedyn.core.io import write_json  # noqa: E402
from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.problems import make_problem  # noqa: E402


def _cpu() -> float:
    a = resource.getrusage(resource.RUSAGE_SELF)
    b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


def run_case(folder: Path, seed: int, effect: str | None) -> dict:
    path, truth = make_loop_case(folder, seed, effect)
    c0 = _cpu()
    res = diagnose(make_problem(path))
    f = res["findings"]
    row = {"seed": seed, "effect": effect, "truth": truth, "verdict": res["verdict"],
           "findings": [x["cause"] for x in f], "baseline_p": res["baseline"]["p_value"], "cpu_s": _cpu() - c0,
           "noise": {k: v for k, v in res["method"]["noise"].items() if k in ("model", "rho", "baseline_estimate")}}
    # the truth's effects: the slope coupling on every hidden case, and (session 22) the islands' friction
    # contrast where the case draws one (half of them): a first finding among them is right
    contrast = effect is not None and truth["contrast"] != 1.0
    row["truth_effects"] = ([effect] + (["friction-contrast"] if contrast else [])) if effect else []
    if effect and f:
        row["correct_first"] = f[0]["cause"] in row["truth_effects"]
        row["slope_first"] = f[0]["cause"] == effect  # the sessions-18-21 criterion
        fs = next((x for x in f if x["cause"] == effect), None)
        if row["correct_first"] and fs is not None:
            g = fs["derived"]["lateral_calibration_factor"]
            row["fitted"] = g
            row["c_slope"] = fs["parameters"]["c_slope"]["value"]
            row["recovery_error"] = abs(g - truth["g"]) / truth["g"]
            # uncertainty calibration: g's error in units of its jackknife sigma over the lines, and of the
            # Jacobian's sigma of c carried to g (g ~ c for a small apparent friction coefficient)
            pc = fs["parameters"]["c_slope"]
            sg = (fs.get("derived_sigma_jackknife") or {}).get("lateral_calibration_factor")
            s_jac = pc.get("sigma_jacobian", pc.get("sigma"))
            if sg:
                row["z_jackknife"] = (g - truth["g"]) / sg
            if s_jac:
                row["z_jacobian"] = (g - truth["g"]) / (s_jac * g / max(row["c_slope"], 1e-12))
        fc = next((x for x in f if x["cause"] == "friction-contrast"), None)
        if fc is not None and contrast:
            ratio = fc["derived"]["friction_ratio_high_to_low"]
            row["contrast_fitted"] = ratio
            row["contrast_error"] = abs(ratio - truth["contrast"]) / truth["contrast"]
    elif effect:
        row["correct_first"] = row["slope_first"] = False
    if effect:
        row["contrast_claimed"] = "friction-contrast" in row["findings"]
    return row


def _gate(row: dict) -> bool:
    """Whether the baseline's residuals alone would have been whitened (before the best candidate's)."""
    return bool(((row.get("noise") or {}).get("baseline_estimate") or {}).get("rho", 0.0) > 0.0)


def _coverage(z: list[float]) -> dict | None:
    if not z:
        return None
    a = np.abs(np.asarray(z, float))
    return {"n": int(len(a)), "within_1_sigma": float(np.mean(a < 1)), "within_2_sigma": float(np.mean(a < 2)),
            "median_abs_z": float(np.median(a))}


def summary(rows: list[dict]) -> dict:
    eff = [r for r in rows if r["effect"]]
    nul = [r for r in rows if not r["effect"]]
    errs = [r["recovery_error"] for r in eff if "recovery_error" in r]
    return {"n_hidden": len(eff), "n_null": len(nul),
            "correct_first": sum(r["correct_first"] for r in eff),
            "correct_first_rate": (sum(r["correct_first"] for r in eff) / len(eff)) if eff else None,
            "slope_first": sum(r.get("slope_first", r["correct_first"]) for r in eff),
            # the friction contrast (session 22): claimed on the cases that draw one, and on those that do not
            "contrast": {"cases": sum("friction-contrast" in r.get("truth_effects", ()) for r in eff),
                         "claimed": sum(r.get("contrast_claimed", False) for r in eff
                                        if "friction-contrast" in r.get("truth_effects", ())),
                         "claimed_without": sum(r.get("contrast_claimed", False) for r in eff
                                                if "friction-contrast" not in r.get("truth_effects", ())),
                         "without": sum("friction-contrast" not in r.get("truth_effects", ()) for r in eff),
                         "median_ratio_error": float(np.median([r["contrast_error"] for r in eff if "contrast_error" in r]))
                         if any("contrast_error" in r for r in eff) else None},
            "false_discoveries": sum(bool(r["findings"]) for r in nul),
            "false_discovery_rate": (sum(bool(r["findings"]) for r in nul) / len(nul)) if nul else None,
            "median_recovery_error": float(np.median(errs)) if errs else None,
            "max_recovery_error": float(np.max(errs)) if errs else None,
            # fraction of the correct findings whose g lies within 1 and 2 of its sigma (Gaussian: 0.68, 0.95)
            "coverage_jackknife": _coverage([r["z_jackknife"] for r in eff if "z_jackknife" in r]),
            "coverage_jacobian": _coverage([r["z_jacobian"] for r in eff if "z_jacobian" in r]),
            "misses": [{"seed": r["seed"], "class": ("no finding (baseline p = %.3g)" % r["baseline_p"]) if not r["findings"]
                        else f"wrong cause first: {r['findings'][0]}", "verdict": r["verdict"]}
                       for r in eff if not r["correct_first"]],
            "false_discovery_cases": [{"seed": r["seed"], "findings": r["findings"]} for r in nul if r["findings"]],
            "verdicts": {v: sum(r["verdict"] == v for r in rows) for v in sorted({r["verdict"] for r in rows})},
            "whitened": {"hidden": sum((r.get("noise") or {}).get("model") == "AR(1)" for r in rows if r["effect"]),
                         "null": sum((r.get("noise") or {}).get("model") == "AR(1)" for r in rows if not r["effect"]),
                         "baseline_gate_hidden": sum(_gate(r) for r in rows if r["effect"]),
                         "baseline_gate_null": sum(_gate(r) for r in rows if not r["effect"])},
            "median_cpu_s": float(np.median([r["cpu_s"] for r in rows])) if rows else None}


def main(n_eff: int, n_null: int, out: Path) -> dict:
    data = json.loads(out.read_text()) if out.exists() else {"rows": []}
    done = {r["seed"] for r in data["rows"]}
    todo = [(7000 + 2 * i, "surface-slope") for i in range(n_eff)] + [(7001 + 2 * i, None) for i in range(n_null)]
    with tempfile.TemporaryDirectory() as tmp:
        for seed, eff in todo:
            if seed in done:
                continue
            row = run_case(Path(tmp), seed, eff)
            data["rows"].append(row)
            data["summary"] = summary(data["rows"])
            data["machine"] = {"cpus": os.cpu_count()}
            write_json(out, data)
            print(seed, eff, row["verdict"], row["findings"], f"{row.get('fitted', float('nan')):.3f}",
                  f"g {row['truth']['g']:.3f}", f"{row['cpu_s']:.1f} s", flush=True)
    return data["summary"]


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: diagnose_rates_loops.py N_EFFECT N_NULL OUT.json")
    print(json.dumps(main(int(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3])), indent=1, default=float))
