"""Run time of one modal diagnosis (6 modes + 4 Q) on the FEM baseline, split into its stages.

Prints, measured in this process (wall and CPU time, ``time.process_time``: on a shared machine
the CPU time is the reproducible number): building the FEM baseline (probe FEM, discretisation
estimate, the 1D-3D beam gaps of the model-form floor), the whole diagnosis with that baseline reused (Ritz reduction,
nested fits, cross-validation, FEM re-solve of the final model), and their ratio.

Usage: python benchmarks/diagnose_modal.py
"""

from __future__ import annotations

import time
from pathlib import Path

from probedyn.diagnose.engine import diagnose
from probedyn.diagnose.formats import read_measurement
from probedyn.diagnose.modal import ModalProblem

EX = Path(__file__).resolve().parents[1] / "examples" / "measurements" / "afm_cantilever_modes.toml"


def main() -> None:
    meas = read_measurement(EX)
    t0, c0 = time.perf_counter(), time.process_time()
    prob = ModalProblem(meas)
    t_base, c_base = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    res = diagnose(ModalProblem(meas, bases=prob.bases))
    t_diag, c_diag = time.perf_counter() - t0, time.process_time() - c0
    fem = res["method"]["model"]["fems"][0]
    print(f"FEM baseline ({fem.get('fem_dofs', '?')} DOFs, thickness stretch {fem.get('thickness_stretch', 1):.2f}): "
          f"{t_base:.1f} s wall, {c_base:.1f} s CPU")
    print(f"diagnosis with the baseline reused: {t_diag:.1f} s wall, {c_diag:.1f} s CPU "
          f"({res['model_evaluations']} model evaluations; "
          f"verdict {res['verdict']})")
    print(f"total: {t_base + t_diag:.1f} s wall, {c_base + c_diag:.1f} s CPU; "
          f"ratio diagnosis / baseline build (wall): {t_diag / t_base:.1f}")


if __name__ == "__main__":
    main()
