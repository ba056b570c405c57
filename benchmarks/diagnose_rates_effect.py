"""Does the modal diagnosis find one hidden effect, on levers of several shapes? (one effect per study)

Usage: ``python benchmarks/diagnose_rates_effect.py EFFECT N OUT.json`` (resumable, as
``benchmarks/diagnose_rates.py``). Effects and their seeds: ``crystal-anisotropy`` (9000 + i;
``benchmarks/diagnose_rates_crystal.py``), ``bonded-overlap`` (9500 + i).

Truth (tests/diagnose_truth.py, probedyn's FEM with the effect built into the mesh or the matrices, 4 layers of
20-node hexahedra, solved directly) plus 1e-3 frequency noise on the six modes (flapwise 1-4, lateral 1, torsion
1): ``crystal-anisotropy`` meshes the cubic ``silicon-110`` and declares the catalog's isotropic silicon;
``bonded-overlap`` meshes the lever on through an overlap of ``lo L`` (elements of t/4 along it since session 43)
whose bottom face rests on springs (normal ``k_n``, tangential ``k_t`` per area, a consistent foundation since session 43; a thin isotropic bond, ``k_t / k_n = (1 - 2 nu) / (2 (1 -
nu))``, nu in [0.3, 0.45]) and leaves its end free -- not the cause's beam segment on the clamp face. Levers cycle
through A (300 x 30 x 10 um), B (100 x 40 x 10), C (150 x 20 x 10) and three more geometries.

Reported: the first finding is the effect (correct first), it is in the first finding's confounded group, and
the error of its main parameter (``a_crystal`` against 1; ``lam_n``).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import diagnose_rates as dr  # noqa: E402
from diagnose_truth import make_modal_case  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.modal import ModalProblem  # noqa: E402

LEVERS = ["A", "B", "C",
          {"length": 200e-6, "width": 35e-6, "thickness": 7e-6},
          {"length": 150e-6, "width": 50e-6, "thickness": 8e-6},
          {"length": 250e-6, "width": 40e-6, "thickness": 6e-6}]
SEEDS = {"crystal-anisotropy": 9000, "bonded-overlap": 9500}
_BASES: dict = {}


def run_case(folder, case):
    seed, lever, effect = case["seed"], case["lever"], case["effect"]
    key = lever if isinstance(lever, str) else json.dumps(lever, sort_keys=True)
    t0, c0 = time.perf_counter(), time.process_time()
    path, truth = make_modal_case(Path(folder), seed, effect, lever)
    t_truth, c_truth = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    prob = ModalProblem(read_measurement(path), bases=_BASES.get(key))
    _BASES.setdefault(key, prob.bases)
    res = diagnose(prob)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    row = {"code": dr.CODE, "seed": seed, "effect": effect, "lever": lever, "truth_kind": "fem",
           "truth": truth["params"], "verdict": res["verdict"], "findings": [f["cause"] for f in res["findings"]],
           "candidates": [{"cause": c["cause"], "chi2": c.get("chi2"), "evidence": c.get("evidence")}
                          for c in res["candidates"][:3]],
           "fitted": res["findings"][0]["parameters"] if res["findings"] else None,
           "runtime_s": dt, "cpu_s": dc, "truth_runtime_s": t_truth, "truth_cpu_s": c_truth,
           "baseline_p": res["baseline"]["p_value"]}
    return dr.add_outcome(row, res, effect, truth)


def study(effect: str, n: int, out: str) -> dict:
    outp = Path(out)
    rows = json.loads(outp.read_text())["rows"] if outp.exists() else []
    cases = [{"seed": SEEDS[effect] + i, "lever": LEVERS[i % len(LEVERS)], "effect": effect} for i in range(n)]
    return dr.run_cases(cases, rows, outp, run_case, ("seed", "lever", "verdict", "findings", "group",
                                                      "recovery_error", "runtime_s"))


if __name__ == "__main__":
    eff, n = sys.argv[1], int(sys.argv[2])
    out = sys.argv[3] if len(sys.argv) > 3 else f"benchmarks/results/diagnose_rates_{eff}.json"
    print(json.dumps(study(eff, n, out), indent=1, default=float))
