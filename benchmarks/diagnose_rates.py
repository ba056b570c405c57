"""Correct-cause, false-discovery and parameter-recovery rates of the modal diagnosis on seeded cases.

Usage: ``python benchmarks/diagnose_rates.py N_EFFECT N_NULL OUT.json [--static REL]`` (resumable: the
cases already in OUT.json are kept and skipped; the file is rewritten atomically after every case).
``--static REL``: the FEM-truth cases also declare a measured static spring constant (end load) with
relative noise REL (``tests/diagnose_truth.static_truth``: the truth FEM's own static solve); the
Timoshenko nulls stay frequency-only.

Cases: ``tests/diagnose_cases.py`` (seeds 1000 + i with the effects cycling and the levers A
(long), B (short and wide: shear matters), C (narrow) cycling every 8; nulls 5000 + i on the
levers in turn, every third from the Timoshenko beam, every fourth declared in air).
Truth (tests/diagnose_truth.py, independent of the diagnosis): probedyn's 3D FEM on a finer,
unstretched mesh (4 layers of 20-node hexahedra instead of the diagnosis' 3 stretched), solved
directly, with the hidden effect built into the mesh or the matrices (a point mass on a mesh
vertex, springs on the clamp face (a consistent foundation on the truth's mesh), a re-meshed thicker/wider/longer lever, another
modulus, a geometric stiffness assembled in the test module, Sader fluid loading by the test
module's own hydrodynamic function), plus noise (1e-3 relative on six frequencies, 5 % on Q where
given); Timoshenko nulls: ``probedyn.lumped.beam`` (four flapwise + one lateral mode). The nominal
FEM baseline of each lever is built once and shared by its cases (the same probe FEM every case
would build).

Reported: correct cause first (the first finding), the false-discovery rate on the nulls (any
finding) by truth kind, the median |fit - truth| / |truth - null| of the effect's main parameter
when the cause is right, every miss with its class, run times (wall and CPU).

Detectability (the criterion of every data kind, as ``diagnose_rates_curves.signal_chi2``): the
effect's *signal* is the chi-square the diagnosis' baseline leaves on the **noise-free** record (the
same case without its noise draws, the same stated noise), against the omnibus test's threshold
``chi2_dof(1 - alpha) - dof`` (the signal at which the noisy test fires with even odds); a modal
problem also has the targeted route (a cause's likelihood-ratio test at alpha / N), so the expected
cause's noise-free gain ``chi2_base - chi2_cause`` against ``chi2_k(1 - alpha / N) - k`` counts too. A case
below both is reported *below detectability* (with its signals) and left out of the correct-first
rate over the detectable cases; the rate over all cases is reported beside it. Identifiability (as
``diagnose_rates_curves.identifiability``): every catalog cause is fitted, nested in the baseline, to
the noise-free record; if a rival's chi-square is within twice the evidence margin (2 ln 10 = 4.6) of
the expected cause's, no amount of such data can name the expected cause rather than that rival (the
diagnosis should say *confounded*): the correct-first rate is also given over the identifiable cases.
``python benchmarks/diagnose_rates.py detect OUT.json`` adds the criterion to rows computed without it.
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

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from diagnose_cases import modal_cases  # noqa: E402
from diagnose_truth import make_modal_case  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.modal import ModalProblem  # noqa: E402

MAIN = {"point-mass": ("mass", 0.0), "clamp-compliance": ("c_rot", 0.0), "thickness-error": ("t_ratio", 1.0),
        "width-error": ("w_ratio", 1.0), "length-error": ("dL", 0.0), "modulus-error": ("e_ratio", 1.0),
        "axial-prestress": ("sigma", 0.0), "fluid-loading": ("rho_f", 0.0), "crystal-anisotropy": ("a_crystal", 0.0),
        "bonded-overlap": ("lam_n", 1e-4)}
_BASES: dict = {}
STATIC_REL: float | None = None  # --static
try:  # the commit the rows were computed with (a resumed study may mix commits: each row says which)
    CODE = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parent).stdout.strip() or None
except OSError:
    CODE = None


def _problem(path: Path, lever: str) -> ModalProblem:
    meas = read_measurement(path)
    prob = ModalProblem(meas, bases=_BASES.get(lever))
    _BASES.setdefault(lever, prob.bases)
    return prob


def run_case(folder, case):
    seed, effect, lever, truth_kind = case["seed"], case["effect"], case["lever"], case["truth_kind"]
    t0, c0 = time.perf_counter(), time.process_time()
    static = STATIC_REL if truth_kind == "fem" else None
    path, truth = make_modal_case(Path(folder), seed, effect, lever, truth_kind=truth_kind,
                                  declared_medium=case.get("declared_medium", "vacuum"), static_rel=static)
    t_truth, c_truth = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    res = diagnose(_problem(path, lever))
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    det = detectability(folder, case) if effect else None
    row = {"code": CODE, "seed": seed, "effect": effect, "lever": lever, "truth_kind": truth_kind, "truth": truth["params"],
           "detectability": det,
           "declared_medium": case.get("declared_medium"), "static_rel": static, "verdict": res["verdict"],
           "findings": [f["cause"] for f in res["findings"]], "runtime_s": dt, "cpu_s": dc,
           "truth_runtime_s": t_truth, "truth_cpu_s": c_truth, "baseline_p": res["baseline"]["p_value"]}
    return add_outcome(row, res, effect, truth)


def detectability(folder, case: dict) -> dict:
    """The effect's noise-free signals and thresholds (module docstring, *Detectability*)."""
    seed, effect, lever = case["seed"], case["effect"], case["lever"]
    static = case.get("static_rel", STATIC_REL if case["truth_kind"] == "fem" else None)
    path, _ = make_modal_case(Path(folder), seed, effect, lever, truth_kind=case["truth_kind"],
                              declared_medium=case.get("declared_medium", "vacuum"), static_rel=static,
                              noise_free=True, name=f"clean_{seed}")
    return signals(_problem(path, lever), effect)


def signals(prob, effect: str) -> dict:
    """The baseline's chi-square on a noise-free problem ``prob`` against the omnibus threshold, and the
    expected cause's gain against the targeted test's (where the problem has that route)."""
    from scipy.stats import chi2 as chi2_dist

    from probedyn.diagnose.engine import ALPHA, EVIDENCE_MARGIN, Fitter, lr_threshold

    F = Fitter(prob)
    try:
        base = F.baseline()
        out = {"signal_chi2": float(base.chi2), "threshold": float(chi2_dist.ppf(1 - ALPHA, base.dof)) - base.dof}
        det = out["signal_chi2"] >= out["threshold"]
        cause = [c for c in prob.causes if c.key == effect]
        if not cause:
            out["detectable"] = bool(det)
            return out
        # every catalog cause nested in the baseline on the noise-free record, as the diagnosis fits them
        chi = {c.key: float(f.chi2) for c, f in zip(prob.causes, F.map_nested([(base, (c,), None) for c in prob.causes]))}
        if getattr(prob, "model_error_in_likelihood", False):
            k = len(cause[0].params)
            out["targeted_signal"] = float(base.chi2) - chi[effect]
            out["targeted_threshold"] = lr_threshold(k, len(prob.causes)) - k
            det = det or out["targeted_signal"] >= out["targeted_threshold"]
        out["detectable"] = bool(det)
        # identifiability (as diagnose_rates_curves.identifiability): a rival whose noise-free chi-square is
        # within twice the evidence margin of the expected cause's cannot be told from it by such data
        rivals = {k: v for k, v in chi.items() if k != effect}
        if rivals:
            rival = min(rivals, key=rivals.get)
            out.update(rival=rival, rival_gap_chi2=rivals[rival] - chi[effect],
                       identifiable=bool(rivals[rival] - chi[effect] >= 2 * EVIDENCE_MARGIN))
        return out
    finally:
        F.close_pool()


def add_outcome(row: dict, res: dict, effect: str | None, truth: dict) -> dict:
    """``row`` with the diagnosis' first finding and its group, and for a hidden effect whether it
    is first / in the group and the relative error of its main parameter (:data:`MAIN`)."""
    if res["findings"]:
        f0 = res["findings"][0]
        group = [f0["cause"], *f0.get("confounded_with", [])]
        row.update(first=f0["cause"], group=group)
    if effect:
        row["correct_first"] = bool(res["findings"]) and res["findings"][0]["cause"] == effect
        row["correct_in_group"] = effect in row.get("group", [])
        if row["correct_first"] and effect in MAIN:
            name, null = MAIN[effect]
            fit = res["findings"][0]["parameters"].get(name, {}).get("value")
            if fit is not None:
                row["recovery_error"] = abs(fit - truth["params"][name]) / abs(truth["params"][name] - null)
    return row


def detectable(r: dict) -> bool:
    """A row without the criterion counts as detectable."""
    return not r.get("detectability") or r["detectability"]["detectable"]


def identifiable(r: dict) -> bool:
    """A detectable row whose expected cause no rival matches on the noise-free record (without the criterion: yes)."""
    return detectable(r) and (not r.get("detectability") or r["detectability"].get("identifiable", True))


def detectability_summary(eff: list[dict]) -> dict:
    """The correct-first rates over the detectable and the identifiable hidden-effect rows ``eff`` (None while a
    row lacks the criterion) and the rows below detectability."""
    det = [r for r in eff if detectable(r)]
    ident = [r for r in det if identifiable(r)]
    complete = bool(eff) and all(r.get("detectability") for r in eff)
    return {
        "n_detectable": len(det) if complete else None,
        "correct_first_of_detectable": float(np.mean([bool(r.get("correct_first")) for r in det]))
        if complete and det else None,
        "below_detectability": [{**{k: r.get(k) for k in ("seed", "effect", "lever", "truth", "verdict", "findings")},
                                 **r["detectability"]} for r in eff if not detectable(r)],
        "n_identifiable": len(ident) if complete else None,
        "correct_first_of_identifiable": float(np.mean([bool(r.get("correct_first")) for r in ident]))
        if complete and ident else None,
    }


def add_detectability(out, detect=None, summarize_rows=None) -> dict:
    """The detectability and identifiability criteria added to the hidden-effect rows of ``out`` that lack them,
    by ``detect(folder, row)`` (default: the modal study's), the summary by ``summarize_rows``; rewritten atomically."""
    detect, summarize_rows = detect or detectability, summarize_rows or summarize
    outp = Path(out)
    rows = json.loads(outp.read_text())["rows"]
    with tempfile.TemporaryDirectory() as d:
        for r in rows:
            if r["effect"] and "identifiable" not in (r.get("detectability") or {}):
                r["detectability"] = detect(d, r)
                print(json.dumps({"seed": r["seed"], "effect": r["effect"], **r["detectability"]}), flush=True)
    tmp = outp.with_suffix(".tmp")
    tmp.write_text(json.dumps({"summary": summarize_rows(rows), "rows": rows}, indent=1, default=float))
    os.replace(tmp, outp)
    return summarize_rows(rows)


def miss_class(r) -> str:
    """The class of a miss: below detectability, no discrepancy found, a cause claimed but confounded, or
    another cause first."""
    if not detectable(r):
        d = r["detectability"]
        return (f"below detectability (noise-free signal chi2 {d['signal_chi2']:.3g} < {d['threshold']:.3g}"
                + (f", targeted {d['targeted_signal']:.3g} < {d['targeted_threshold']:.3g}" if "targeted_signal" in d
                   else "") + ")")
    if not identifiable(r):
        d = r["detectability"]
        return (f"not identifiable (rival {d['rival']} within {d['rival_gap_chi2']:.2g} of chi2 on the noise-free "
                f"record): " + (f"{r['findings'][0]} first" if r["findings"] else r["verdict"]))
    if not r["findings"]:
        return "not detected (" + r["verdict"] + ")"
    if r.get("correct_in_group"):
        return "confounded (right cause in the group)"
    return "wrong cause first: " + r["findings"][0]


def summarize(rows):
    eff = [r for r in rows if r["effect"]]
    nul = [r for r in rows if not r["effect"]]
    rec = [r["recovery_error"] for r in eff if "recovery_error" in r]
    misses = [{**{k: r.get(k) for k in ("seed", "effect", "lever", "truth", "verdict", "findings", "group")},
               "class": miss_class(r)} for r in eff if not r.get("correct_first")]
    return {
        "n_effect": len(eff), "n_null": len(nul),
        "correct_first": float(np.mean([bool(r.get("correct_first")) for r in eff])) if eff else None,
        **detectability_summary(eff),
        "correct_in_confounded_group": float(np.mean([bool(r.get("correct_in_group")) for r in eff])) if eff else None,
        "false_discovery_fem_nulls": float(np.mean([bool(r["findings"]) for r in nul if r["truth_kind"] == "fem"]))
        if any(r["truth_kind"] == "fem" for r in nul) else None,
        "false_discovery_timoshenko_nulls": float(np.mean([bool(r["findings"]) for r in nul
                                                           if r["truth_kind"] == "timoshenko"]))
        if any(r["truth_kind"] == "timoshenko" for r in nul) else None,
        "median_recovery_error": float(np.median(rec)) if rec else None,
        "n_recovered": len(rec),
        "runtime_median_s": float(np.median([r["runtime_s"] for r in rows])) if rows else None,
        "cpu_median_s": float(np.median([r["cpu_s"] for r in rows])) if rows else None,
        "truth_cpu_median_s": float(np.median([r["truth_cpu_s"] for r in rows])) if rows else None,
        "by_effect": {e: {"n": sum(r["effect"] == e for r in eff),
                          "correct_first": sum(bool(r.get("correct_first")) for r in eff if r["effect"] == e)}
                      for e in sorted({r["effect"] for r in eff})},
        "machine": "2 cores shared with 5 other agents (wall times 3-10x idle; CPU times are per process)",
        "misses": misses,
        "null_findings": [{k: r.get(k) for k in ("seed", "truth_kind", "verdict", "findings")} for r in nul if r["findings"]],
    }


def study(n_effect: int, n_null: int, out: str):
    outp = Path(out)
    rows = json.loads(outp.read_text())["rows"] if outp.exists() else []
    cases = modal_cases(n_effect, n_null)
    eff = [c for c in cases if c["effect"]]
    nul = [c for c in cases if not c["effect"]]
    mixed = []  # interleaved (effect, null, ...) so that a run cut short still measures both rates
    for i in range(max(len(eff), len(nul))):
        mixed += eff[i:i + 1] + nul[i:i + 1]
    return run_cases(mixed, rows, outp, run_case, ("seed", "effect", "lever", "truth_kind", "verdict", "findings",
                                                   "recovery_error", "runtime_s", "cpu_s"))


def run_cases(mixed: list, rows: list, outp: Path, run, keys: tuple) -> dict:
    """Run the cases of ``mixed`` not yet in ``rows`` with ``run(folder, case)``, printing ``keys`` of
    each row and rewriting ``outp`` atomically after every case (resumable); the summary."""
    done = {r["seed"] for r in rows}
    with tempfile.TemporaryDirectory() as d:
        for case in mixed:
            if case["seed"] in done:
                continue
            rows.append(run(d, case))
            print(json.dumps({k: rows[-1].get(k) for k in keys}, default=float), flush=True)
            tmp = outp.with_suffix(".tmp")
            tmp.write_text(json.dumps({"summary": summarize(rows), "rows": rows}, indent=1, default=float))
            os.replace(tmp, outp)
    return summarize(rows)


if __name__ == "__main__":
    args = list(sys.argv[1:])
    if args and args[0] == "detect":
        print(json.dumps(add_detectability(args[1]), indent=1, default=float))
        sys.exit(0)
    if "--static" in args:
        i = args.index("--static")
        STATIC_REL = float(args[i + 1])
        del args[i:i + 2]
    n_eff, n_null = int(args[0]), int(args[1])
    out = args[2] if len(args) > 2 else "benchmarks/diagnose_rates_modal.json"
    print(json.dumps(study(n_eff, n_null, out), indent=1, default=float))
