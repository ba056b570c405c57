"""False discoveries and correct causes of the force-curve diagnosis when the noise is correlated.

Usage: ``python benchmarks/diagnose_noise_correlation.py N_NULL N_HIDDEN RHO OUT.json [--unstated]`` (resumable:
the JSON is rewritten after every case and cases already in it are skipped).

Truth: the force-curve generator of ``benchmarks/diagnose_rates_curves.py`` (``tests/diagnose_truth_curves.py``,
noise-only seeds 6000 + i, hidden effects 2000 + i cycling through ``CURVE_EFFECTS``) with its white noise
replaced by AR(1) noise of the same marginal sigma and lag-one correlation ``RHO`` (one chain over the
approach and the retract, as recorded); the sidecar states the marginal sigma, as a user who measured the
noise's standard deviation would, or (``--unstated``) states no noise, as most instrument exports: the
diagnosis then estimates it from the record's own scatter. Each case is diagnosed twice in the same process: with the samples taken
as independent (``noise_model="white"``, the diagnosis before session 19) and with the default
(``"auto"``: AR(1) whitening where the stated noise's high-frequency part, or without a stated noise the
first against the second differences of the best nested candidate's residuals, and the residuals' lag-one
correlation show it, :mod:`probedyn.diagnose.noise`). Reported: false discoveries on the nulls,
correct cause first on the hidden cases (over all cases: no detectability rule is applied here), the
correlation the diagnosis estimated, CPU time.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from diagnose_truth_curves import CURVE_EFFECTS, EXPECTED, make_curve_case  # noqa: E402

from probedyn.diagnose.engine import run  # noqa: E402


def run_case(folder: Path, seed: int, effect: str | None, rho: float, stated: bool = True) -> dict:
    path, truth = make_curve_case(folder, seed, effect, noise_rho=rho, state_noise=stated)
    truth.pop("force_clean")
    row = {"seed": seed, "effect": effect, "rho_true": rho, "noise_stated": stated}
    for model in ("white", "auto"):
        c0 = time.process_time()
        res = run(path, noise_model=model)
        f = [x["cause"] for x in res["findings"]]
        out = {"findings": f, "verdict": res["verdict"], "baseline_p": res["baseline"]["p_value"],
               "noise": {k: v for k, v in res["method"]["noise"].items() if k in ("model", "rho", "rho_scatter", "rho_lag1", "innovation_sd")},
               "cpu_s": time.process_time() - c0}
        if effect:
            out["correct_first"] = bool(f) and f[0] == EXPECTED[effect][0]
        row[model] = out
    return row


def summary(rows: list[dict]) -> dict:
    out = {}
    nul = [r for r in rows if not r["effect"]]
    hid = [r for r in rows if r["effect"]]
    for model in ("white", "auto"):
        out[model] = {
            "nulls": len(nul), "false_discoveries": sum(bool(r[model]["findings"]) for r in nul),
            "false_discovery_cases": [{"seed": r["seed"], "findings": r[model]["findings"]} for r in nul if r[model]["findings"]],
            "hidden": len(hid), "correct_first": sum(r[model]["correct_first"] for r in hid),
            "misses": [{"seed": r["seed"], "effect": r["effect"], "findings": r[model]["findings"]}
                       for r in hid if not r[model]["correct_first"]],
            "cpu_s_total": sum(r[model]["cpu_s"] for r in rows)}
    rhos = [r["auto"]["noise"].get("rho", 0.0) for r in rows]
    out["auto"]["rho_estimated_median"] = sorted(rhos)[len(rhos) // 2] if rhos else None
    out["auto"]["whitened_cases"] = sum(r["auto"]["noise"].get("model") == "AR(1)" for r in rows)
    return out


def main(n_null: int, n_hidden: int, rho: float, out: Path, stated: bool = True) -> dict:
    data = json.loads(out.read_text()) if out.exists() else {"rho": rho, "noise_stated": stated, "rows": []}
    if data.get("noise_stated", True) != stated:
        raise SystemExit(f"{out} holds a run with noise_stated = {data.get('noise_stated', True)}")
    done = {r["seed"] for r in data["rows"]}
    todo = []
    for i in range(max(n_null, n_hidden)):  # interleaved: a partial run is balanced
        if i < n_hidden:
            todo.append((2000 + i, CURVE_EFFECTS[i % len(CURVE_EFFECTS)]))
        if i < n_null:
            todo.append((6000 + i, None))
    with tempfile.TemporaryDirectory() as tmp:
        for seed, eff in todo:
            if seed in done:
                continue
            row = run_case(Path(tmp), seed, eff, rho, stated)
            data["rows"].append(row)
            data["summary"] = summary(data["rows"])
            part = out.with_suffix(".part")
            part.write_text(json.dumps(data, indent=1))
            os.replace(part, out)
            print(seed, eff, "white:", row["white"]["findings"], "auto:", row["auto"]["findings"],
                  f"rho {row['auto']['noise'].get('rho', 0):.2f}", flush=True)
    return data


if __name__ == "__main__":
    a = [x for x in sys.argv[1:] if x != "--unstated"]
    res = main(int(a[0]), int(a[1]), float(a[2]), Path(a[3]), stated="--unstated" not in sys.argv[1:])
    print(json.dumps(res["summary"], indent=1))
