"""Correct-cause, false-discovery and parameter-recovery rates of the spectrum diagnosis, through the
full modal cause ranking.

Usage: ``python benchmarks/diagnose_rates_spectra.py N_EFFECT N_NULL [OUT.json]`` (default 50 50
``benchmarks/results/diagnose_rates_spectra_causes.json``). Resumable: the cases already in OUT.json
are kept and skipped; the file is rewritten atomically after every case. ``--truths-only``
precomputes the FEM truths into the cache (``~/.cache/probedyn-truths/spectra``, keyed by lever,
effect, parameters and the truth code) without diagnosing.

Cases (``tests/diagnose_truth_spectra.spectrum_cases``): seeds 3000 + i with the modal catalog's
effects cycling (point mass, clamp compliance, thickness / width / length / modulus error, axial
prestress, fluid loading = air not declared), levers A (300 x 30 x 10 um), B (100 x 40 x 10, short
and wide), C (150 x 20 x 10) every 8, a quarter declared in air; nulls 7000 + i on the levers in
turn, every third triple from the Timoshenko beam, every fourth declared in air.
Truth (tests/diagnose_truth_spectra.py, independent of the diagnosis): the thermal PSD of the modes
of probedyn's FEM on the finer truth mesh with the effect built into the mesh or the matrices (the
modal study's builders), equipartition areas at an off-axis detector spot, Sader air loading, one
internal loss factor (Q 200-1000), white + 1/f background, 0-2 spurs, Gamma periodogram scatter.
Diagnosis: ``spectrum_problem`` (peaks identified against the nominal FEM) then the modal engine.

Detectability (the criterion of every data kind, ``diagnose_rates.detectability``): the baseline's
chi-square on the **noise-free** spectrum's identified peaks (the expected PSD, no periodogram scatter,
the same declared averages) against the omnibus threshold, and the expected cause's noise-free gain
against the targeted test's; a case below both is reported below detectability, and the correct-first
rate is given over all cases, over the detectable ones and over the identifiable ones (no rival cause
within twice the evidence margin of the expected one's noise-free chi-square). ``python benchmarks/diagnose_rates_spectra.py
detect OUT.json`` adds the criterion to rows computed without it.

Reported: correct cause first (the first finding), correct within the reported confounded group,
false discoveries on the nulls (any finding) by truth kind, the median |fit - truth| / |truth - null|
of the effect's main parameter when the cause is right, the peaks identified, every miss with its
class, run times (wall and CPU; the machine was shared).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from diagnose_rates import MAIN, add_detectability, detectability_summary, miss_class, signals  # noqa: E402
from diagnose_truth_spectra import make_spectrum_case, spectrum_cases, spectrum_fem_truth  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.spectrum import spectrum_problem  # noqa: E402

OUT = ROOT / "benchmarks" / "results" / "diagnose_rates_spectra_causes.json"
_BASES: dict = {}
try:
    CODE = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                          cwd=ROOT).stdout.strip() or None
except OSError:
    CODE = None


def run_case(folder, case: dict) -> dict:
    seed, effect, lever = case["seed"], case["effect"], case["lever"]
    t0, c0 = time.perf_counter(), time.process_time()
    path, truth = make_spectrum_case(Path(folder), seed, effect, lever, truth_kind=case["truth_kind"],
                                     declared_medium=case["declared_medium"])
    t_truth, c_truth = time.perf_counter() - t0, time.process_time() - c0
    det = detectability(folder, case) if effect else None
    t0, c0 = time.perf_counter(), time.process_time()
    row = {"code": CODE, "seed": seed, "effect": effect, "lever": lever, "truth_kind": case["truth_kind"],
           "detectability": det,
           "declared_medium": case["declared_medium"], "truth": truth["params"],
           "truth_modes": [(m["family"], m["order"], m["f"]) for m in truth["modes"]], "spurs_Hz": truth["spurs_Hz"],
           "averages": truth["averages"], "Q_int": truth["Q_int"], "truth_cpu_s": c_truth}
    try:
        prob = spectrum_problem(read_measurement(path), base=_BASES.get(lever))
    except Exception as e:  # a spectrum the identification refuses is a miss (or a correct null), recorded
        row.update(verdict=f"error: {e}", findings=[], peaks=[], runtime_s=time.perf_counter() - t0,
                   cpu_s=time.process_time() - c0)
        return _score(row, effect, truth)
    _BASES.setdefault(lever, prob.identification_baseline)  # the fit's baseline: refined from it per case
    row["peaks"] = [{"f0_Hz": p["f0_Hz"], "Q": p["Q"], "accepted": p["accepted"], "family": p["family"],
                     "order": p["order"], "reasons": p["reasons"]} for p in prob.peaks["peaks"]]
    res = diagnose(prob)
    row.update(verdict=res["verdict"], findings=[f["cause"] for f in res["findings"]],
               runtime_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0,
               baseline_p=res["baseline"]["p_value"])
    if res["findings"]:
        f0 = res["findings"][0]
        row.update(first=f0["cause"], group=[f0["cause"], *f0.get("confounded_with", [])],
                   fitted={k: v.get("value") for k, v in f0["parameters"].items()})
    return _score(row, effect, truth)


def detectability(folder, case: dict) -> dict:
    """The effect's noise-free signals and thresholds (module docstring)."""
    path, _ = make_spectrum_case(Path(folder), case["seed"], case["effect"], case["lever"], truth_kind=case["truth_kind"],
                                 declared_medium=case["declared_medium"], noise_free=True, name=f"clean_{case['seed']}")
    try:
        prob = spectrum_problem(read_measurement(path), base=_BASES.get(case["lever"]))
    except Exception as e:  # noqa: BLE001 -- no peak identified on the noise-free record: nothing to detect
        return {"detectable": False, "signal_chi2": 0.0, "threshold": 0.0, "error": str(e)}
    return signals(prob, case["effect"])


def _score(row: dict, effect, truth) -> dict:
    acc = {(p["family"], p["order"]) for p in row.get("peaks", []) if p["accepted"]}
    row["identified"] = sorted(acc)
    if effect:
        row["correct_first"] = row.get("first") == effect
        row["correct_in_group"] = effect in row.get("group", [])
        if row["correct_first"] and effect in MAIN:
            name, null = MAIN[effect]
            fit = row["fitted"].get(name)
            if fit is not None:
                row["recovery_error"] = abs(fit - truth["params"][name]) / abs(truth["params"][name] - null)
    return row


def summarize(rows: list[dict]) -> dict:
    eff = [r for r in rows if r["effect"]]
    nul = [r for r in rows if not r["effect"]]
    rec = [r["recovery_error"] for r in eff if "recovery_error" in r]

    def fd(kind):
        rr = [r for r in nul if r["truth_kind"] == kind]
        return {"n": len(rr), "false": sum(bool(r["findings"]) for r in rr)} if rr else None

    return {
        "n_effect": len(eff), "n_null": len(nul),
        "correct_first": float(np.mean([bool(r.get("correct_first")) for r in eff])) if eff else None,
        **detectability_summary(eff),
        "correct_in_confounded_group": float(np.mean([bool(r.get("correct_in_group")) for r in eff])) if eff else None,
        "false_discovery": float(np.mean([bool(r["findings"]) for r in nul])) if nul else None,
        "false_discovery_fem_nulls": fd("fem"), "false_discovery_timoshenko_nulls": fd("timoshenko"),
        "median_recovery_error": float(np.median(rec)) if rec else None, "n_recovered": len(rec),
        "by_effect": {e: {"n": sum(r["effect"] == e for r in eff),
                          "correct_first": sum(bool(r.get("correct_first")) for r in eff if r["effect"] == e),
                          "median_recovery_error": float(np.median([r["recovery_error"] for r in eff
                                                                    if r["effect"] == e and "recovery_error" in r]))
                          if any(r["effect"] == e and "recovery_error" in r for r in eff) else None}
                      for e in sorted({r["effect"] for r in eff})},
        "misses": [{**{k: r.get(k) for k in ("seed", "effect", "lever", "declared_medium", "truth", "verdict",
                                             "findings", "group", "identified")}, "class": miss_class(r)}
                   for r in eff if not r.get("correct_first")],
        "null_findings": [{k: r.get(k) for k in ("seed", "lever", "truth_kind", "declared_medium", "verdict", "findings",
                                                 "identified")} for r in nul if r["findings"]],
        "runtime_median_s": float(np.median([r["runtime_s"] for r in rows])) if rows else None,
        "cpu_median_s": float(np.median([r["cpu_s"] for r in rows])) if rows else None,
        "machine": "2 cores shared with 5 other agents (wall times 3-6x idle; CPU times are per process)",
    }


def study(n_effect: int, n_null: int, out: Path, seeds: set[int] | None = None) -> dict:
    rows = json.loads(out.read_text())["rows"] if out.exists() else []
    done = {r["seed"] for r in rows}
    cases = spectrum_cases(n_effect, n_null)
    eff = [c for c in cases if c["effect"]]
    nul = [c for c in cases if not c["effect"]]
    mixed = [x for i in range(max(len(eff), len(nul))) for x in eff[i:i + 1] + nul[i:i + 1]]
    with tempfile.TemporaryDirectory() as d:
        for case in mixed:
            if case["seed"] in done or (seeds and case["seed"] not in seeds):
                continue
            rows.append(run_case(d, case))
            r = rows[-1]
            print(json.dumps({k: r.get(k) for k in ("seed", "effect", "lever", "truth_kind", "declared_medium", "verdict",
                                                    "findings", "identified", "recovery_error", "cpu_s")},
                             default=float), flush=True)
            out.parent.mkdir(parents=True, exist_ok=True)
            tmp = out.with_suffix(".tmp")
            tmp.write_text(json.dumps({"summary": summarize(rows), "rows": rows}, indent=1, default=float))
            os.replace(tmp, out)
    return summarize(rows)


def truths_only(n_effect: int, n_null: int) -> None:
    from diagnose_truth import draw_modal_effect

    for c in spectrum_cases(n_effect, n_null):
        if c["truth_kind"] != "fem":
            continue
        rng = np.random.default_rng(c["seed"])
        params = draw_modal_effect(c["effect"], c["lever"], rng) if c["effect"] else {}
        t0 = time.process_time()
        spectrum_fem_truth(c["lever"], c["effect"], params)
        print(c["seed"], c["effect"], c["lever"], f"{time.process_time() - t0:.1f} s cpu", flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["detect"]:
        print(json.dumps(add_detectability(Path(sys.argv[2]), detectability, summarize), indent=1, default=float))
        sys.exit(0)
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    n_eff = int(args[0]) if args else 50
    n_null = int(args[1]) if len(args) > 1 else 50
    if "--truths-only" in sys.argv:
        truths_only(n_eff, n_null)
    else:
        out = Path(args[2]) if len(args) > 2 else OUT
        seeds = {int(s) for s in os.environ.get("SEEDS", "").split(",") if s}
        print(json.dumps(study(n_eff, n_null, out, seeds or None), indent=1, default=float))
