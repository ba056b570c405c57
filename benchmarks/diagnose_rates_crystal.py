"""Does the modal diagnosis find a lever that is single-crystal silicon, declared as isotropic silicon?

Usage: ``python benchmarks/diagnose_rates_crystal.py N OUT.json`` (resumable, as
``benchmarks/diagnose_rates.py``).

Truth (tests/diagnose_truth.py): probedyn's FEM of the lever meshed with the **cubic** material
``silicon-110`` (C11, C12, C44 of Hopcroft et al. 2010 rotated to the lever's axes, x || [110]),
4 layers of 20-node hexahedra, solved directly -- not the cause's interpolated stiffness -- plus
1e-3 frequency noise on the six modes (flapwise 1-4, lateral 1, torsion 1); the sidecar declares the
catalog's isotropic "silicon" (E = 169 GPa, nu = 0.28). Levers cycle through A (300 x 30 x 10 um),
B (100 x 40 x 10), C (narrow) and three more geometries; seeds 9000 + i (noise, Q).

Reported: the first finding is ``crystal-anisotropy`` (correct first), it is in the first finding's
confounded group, and the fitted fraction ``a_crystal`` against the truth's 1.
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
_BASES: dict = {}


def run_case(folder, case):
    seed, lever = case["seed"], case["lever"]
    key = lever if isinstance(lever, str) else json.dumps(lever, sort_keys=True)
    t0, c0 = time.perf_counter(), time.process_time()
    path, truth = make_modal_case(Path(folder), seed, "crystal-anisotropy", lever)
    t_truth, c_truth = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    prob = ModalProblem(read_measurement(path), bases=_BASES.get(key))
    _BASES.setdefault(key, prob.bases)
    res = diagnose(prob)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    row = {"code": dr.CODE, "seed": seed, "effect": "crystal-anisotropy", "lever": lever, "truth_kind": "fem",
           "truth": truth["params"], "verdict": res["verdict"], "findings": [f["cause"] for f in res["findings"]],
           "candidates": [{"cause": c["cause"], "chi2": c.get("chi2"), "evidence": c.get("evidence")}
                          for c in res["candidates"][:3]],
           "runtime_s": dt, "cpu_s": dc, "truth_runtime_s": t_truth, "truth_cpu_s": c_truth,
           "baseline_p": res["baseline"]["p_value"]}
    return dr.add_outcome(row, res, "crystal-anisotropy", truth)


def study(n: int, out: str) -> dict:
    outp = Path(out)
    rows = json.loads(outp.read_text())["rows"] if outp.exists() else []
    cases = [{"seed": 9000 + i, "lever": LEVERS[i % len(LEVERS)]} for i in range(n)]
    return dr.run_cases(cases, rows, outp, run_case, ("seed", "lever", "verdict", "findings", "group",
                                                      "recovery_error", "runtime_s"))


if __name__ == "__main__":
    n = int(sys.argv[1])
    out = sys.argv[2] if len(sys.argv) > 2 else "benchmarks/results/diagnose_rates_crystal.json"
    print(json.dumps(study(n, out), indent=1, default=float))
