"""Modal diagnosis of levers carrying a meshed tip: false discoveries on noise-only data and the
hidden-effect catalog (issue 11, class 1: "cantilever with or without tip").

Usage: ``python benchmarks/diagnose_rates_tip.py N_EFFECT N_NULL OUT.json [LEVERS]`` (resumable
like ``benchmarks/diagnose_rates.py``; LEVERS e.g. ``BC``, default ``ABC``).

Cases: hidden effects 11000 + i (the modal catalog cycling, levers in turn), noise-only 15000 + i
(levers in turn, every fourth declared in air). Each case's tip is drawn from its own generator
(seed + 10^6): a pyramid or a cone, height 5-15 um, half-angle 15-25 deg, declared in the sidecar's
[probe] (``tip_shape``, ``tip_height``, ``tip_half_angle``). Truth (``tests/diagnose_truth.py``,
``tip=``): probedyn's 3D FEM of the tipped lever on P2 tetrahedra with 4 layers through the
thickness (the diagnosis: 3), the effect built into the mesh or the matrices as for the untipped
cases (a thickness error re-meshes a thicker lever carrying the same tip), cached under
``~/.cache/probedyn-truths/modal_tip.json``. Reported as in ``diagnose_rates.py``.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_rates import CODE, add_outcome, run_cases, summarize  # noqa: E402
from diagnose_truth import LEVERS, MODAL_EFFECTS, make_modal_case  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.modal import ModalProblem  # noqa: E402

_BASES: dict = {}


def draw_tip(seed: int) -> dict:
    rng = np.random.default_rng(seed + 10**6)
    return {"shape": str(rng.choice(["pyramid", "cone"])), "height": float(rng.uniform(5e-6, 15e-6)),
            "half_angle": float(math.radians(rng.uniform(15.0, 25.0)))}


def tip_cases(n_effect: int, n_null: int, levers: str = "ABC") -> list[dict]:
    out = []
    for i in range(n_effect):
        out.append({"seed": 11000 + i, "effect": MODAL_EFFECTS[i % len(MODAL_EFFECTS)],
                    "lever": levers[i % len(levers)], "truth_kind": "fem", "tip": draw_tip(11000 + i)})
    for i in range(n_null):
        out.append({"seed": 15000 + i, "effect": None, "lever": levers[i % len(levers)], "truth_kind": "fem",
                    "declared_medium": "air" if i % 4 == 1 else "vacuum", "tip": draw_tip(15000 + i)})
    return out


def run_case(folder, case) -> dict:
    seed, effect, lever, tip = case["seed"], case["effect"], case["lever"], case["tip"]
    t0, c0 = time.perf_counter(), time.process_time()
    path, truth = make_modal_case(Path(folder), seed, effect, lever, declared_medium=case.get("declared_medium", "vacuum"),
                                  tip=tip)
    t_truth, c_truth = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    key = (lever, json.dumps(tip, sort_keys=True))
    prob = ModalProblem(read_measurement(path), bases=_BASES.get(key))
    _BASES.setdefault(key, prob.bases)
    res = diagnose(prob)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    b = prob.reference_baseline
    row = {"code": CODE, "seed": seed, "effect": effect, "lever": lever, "tip": tip, "truth_kind": "fem",
           "truth": truth["params"], "declared_medium": case.get("declared_medium"), "verdict": res["verdict"],
           "findings": [f["cause"] for f in res["findings"]], "runtime_s": dt, "cpu_s": dc,
           "truth_runtime_s": t_truth, "truth_cpu_s": c_truth, "baseline_p": res["baseline"]["p_value"],
           "fem_dofs": b.model.dofs, "floor": prob.mf_floor,
           "disc_rel": [float(x) for x in prob.disc / prob.data.freq]}
    return add_outcome(row, res, effect, truth)


def study(n_effect: int, n_null: int, out: str, levers: str = "ABC") -> dict:
    outp = Path(out)
    rows = json.loads(outp.read_text())["rows"] if outp.exists() else []
    cases = tip_cases(n_effect, n_null, levers)
    eff = [c for c in cases if c["effect"]]
    nul = [c for c in cases if not c["effect"]]
    mixed = []
    for i in range(max(len(eff), len(nul))):
        mixed += nul[i:i + 1] + eff[i:i + 1]
    return run_cases(mixed, rows, outp, run_case, ("seed", "effect", "lever", "verdict", "findings",
                                                   "recovery_error", "cpu_s", "truth_cpu_s", "fem_dofs"))


if __name__ == "__main__":
    n_eff, n_null = int(sys.argv[1]), int(sys.argv[2])
    out = sys.argv[3] if len(sys.argv) > 3 else "benchmarks/results/diagnose_rates_tip.json"
    print(json.dumps(study(n_eff, n_null, out, sys.argv[4] if len(sys.argv) > 4 else "ABC"), indent=1, default=float))
