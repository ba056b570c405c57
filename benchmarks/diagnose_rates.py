"""Correct-cause, false-discovery and parameter-recovery rates of the modal diagnosis on seeded cases.

Usage: ``python benchmarks/diagnose_rates.py N_PER_EFFECT N_NULL [OUT.json] [LEVER] [SKIP_SEEDS]``.

Truth (tests/diagnose_truth.py, independent of the diagnosis): probedyn's 3D FEM on a finer
mesh (3 instead of 2 elements through the thickness) with the hidden effect built into the
mesh or the matrices (a point mass on a mesh vertex, lumped springs on the clamp-face nodes,
a re-meshed thicker/wider/longer lever, another modulus, a geometric stiffness assembled in
the test module, Sader fluid loading by the test module's own hydrodynamic function), plus
noise (1e-3 relative on six frequencies, 5 % on Q where given). Null cases: the same FEM truth
without effect (noise seeds vary) and a Timoshenko beam (``probedyn.lumped.beam``, five
bending modes) without effect. Seeds: effects 1000 + i, FEM nulls 5000 + i, Timoshenko nulls
7000 + i. The nominal FEM baseline of the lever is built once and shared by the cases (it is
the same probe FEM every case would build).

Reported: correct cause first (the first finding, or the first of its confounded group), the
false-discovery rate on the nulls (any finding), the median |fit - truth| / |truth - null| of
the effect's main parameter when the cause is right, every miss with its class, run times.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from diagnose_truth import LEVERS, MODAL_EFFECTS, make_modal_case  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.modal import ModalProblem  # noqa: E402

MAIN = {"point-mass": ("mass", 0.0), "clamp-compliance": ("c_rot", 0.0), "thickness-error": ("t_ratio", 1.0),
        "width-error": ("w_ratio", 1.0), "length-error": ("dL", 0.0), "modulus-error": ("e_ratio", 1.0),
        "axial-prestress": ("sigma", 0.0), "fluid-loading": ("rho_f", 0.0)}
_BASES: dict = {}


def _problem(path: Path, lever: str) -> ModalProblem:
    meas = read_measurement(path)
    prob = ModalProblem(meas, bases=_BASES.get(lever))
    _BASES.setdefault(lever, prob.bases)
    return prob


def run_case(folder, seed, effect, lever, truth_kind="fem"):
    path, truth = make_modal_case(Path(folder), seed, effect, lever, truth_kind=truth_kind)
    t0 = time.perf_counter()
    res = diagnose(_problem(path, lever))
    dt = time.perf_counter() - t0
    row = {"seed": seed, "effect": effect, "lever": lever, "truth_kind": truth_kind, "truth": truth["params"],
           "verdict": res["verdict"], "findings": [f["cause"] for f in res["findings"]], "runtime_s": dt,
           "baseline_p": res["baseline"]["p_value"]}
    if res["findings"]:
        f0 = res["findings"][0]
        group = [f0["cause"], *f0.get("confounded_with", [])]
        row.update(first=f0["cause"], group=group)
        if effect:
            row["correct_first"] = f0["cause"] == effect
            row["correct_in_group"] = effect in group
            if effect in group and effect in MAIN:
                name, null = MAIN[effect]
                fit = res["final"]["parameters"].get(name) if f0["cause"] == effect else None
                if fit is not None:
                    row["recovery_error"] = abs(fit - truth["params"][name]) / abs(truth["params"][name] - null)
    return row


def summarize(rows):
    eff = [r for r in rows if r["effect"]]
    nul = [r for r in rows if not r["effect"]]
    rec = [r["recovery_error"] for r in eff if "recovery_error" in r]
    misses = [{k: r.get(k) for k in ("seed", "effect", "verdict", "findings", "group")} for r in eff
              if not r.get("correct_first")]
    return {
        "n_effect": len(eff), "n_null": len(nul),
        "correct_first": float(np.mean([bool(r.get("correct_first")) for r in eff])) if eff else None,
        "correct_in_confounded_group": float(np.mean([bool(r.get("correct_in_group")) for r in eff])) if eff else None,
        "false_discovery_fem_nulls": float(np.mean([bool(r["findings"]) for r in nul if r["truth_kind"] == "fem"]))
        if any(r["truth_kind"] == "fem" for r in nul) else None,
        "false_discovery_timoshenko_nulls": float(np.mean([bool(r["findings"]) for r in nul
                                                           if r["truth_kind"] == "timoshenko"]))
        if any(r["truth_kind"] == "timoshenko" for r in nul) else None,
        "median_recovery_error": float(np.median(rec)) if rec else None,
        "n_recovered": len(rec),
        "runtime_median_s": float(np.median([r["runtime_s"] for r in rows])) if rows else None,
        "misses": misses,
        "null_findings": [{k: r.get(k) for k in ("seed", "truth_kind", "verdict", "findings")} for r in nul if r["findings"]],
    }


def study(n_per_effect: int, n_null: int, out: str | None = None, lever: str = "C", skip=()):
    rows = []
    cases = [(1000 + i * len(MODAL_EFFECTS) + j, e, "fem") for i in range(n_per_effect) for j, e in enumerate(MODAL_EFFECTS)]
    nulls = [c for i in range(n_null) for c in ((5000 + i, None, "fem"), (7000 + i, None, "timoshenko"))]
    # interleaved (effect, null, effect, null, ...) so that a run cut short still measures both rates
    mixed = []
    for i in range(max(len(cases), len(nulls))):
        mixed += cases[i:i + 1] + nulls[i:i + 1]
    cases = [c for c in mixed if c[0] not in skip]
    with tempfile.TemporaryDirectory() as d:
        for seed, eff, tk in cases:
            rows.append(run_case(d, seed, eff, lever, tk))
            print(json.dumps({k: rows[-1].get(k) for k in ("seed", "effect", "truth_kind", "verdict", "findings",
                                                           "recovery_error", "runtime_s")}, default=float), flush=True)
            if out:
                Path(out).write_text(json.dumps({"summary": summarize(rows), "rows": rows}, indent=1, default=float))
    return summarize(rows)


if __name__ == "__main__":
    n_eff, n_null = int(sys.argv[1]), int(sys.argv[2])
    out = sys.argv[3] if len(sys.argv) > 3 else None
    lever = sys.argv[4] if len(sys.argv) > 4 else "C"
    skip = tuple(int(x) for x in sys.argv[5].split(",")) if len(sys.argv) > 5 else ()
    assert lever in LEVERS
    print(json.dumps(study(n_eff, n_null, out, lever, skip), indent=1, default=float))
