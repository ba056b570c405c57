"""Run time of one modal diagnosis (6 modes) against the cost of the models it could have used.

Prints, measured in this process:
* one evaluation of the reduced 1D FE beam (three families, six modes);
* one full diagnosis of examples/measurements/afm_cantilever_modes (baseline, 8 causes, LOO CV);
* one 3D FEM modal solve of the same cantilever (probes/cantilever.py), if available;
* the ratios, and what the diagnosis would cost if every model evaluation were a 3D solve.

Usage: python benchmarks/diagnose_modal.py [--no-fem]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from probedyn.diagnose.engine import diagnose, make_problem

EX = Path(__file__).resolve().parents[1] / "examples" / "measurements" / "afm_cantilever_modes.toml"


def main() -> None:
    prob = make_problem(EX)
    n = 200
    t0 = time.perf_counter()
    for _ in range(n):
        prob._cache.clear()
        prob.residuals({"Q_int": 2e4})
    t_eval = (time.perf_counter() - t0) / n
    runs = []
    for _ in range(3):
        t0 = time.perf_counter()
        res = diagnose(make_problem(EX))
        runs.append(time.perf_counter() - t0)
    t_diag = min(runs)
    print(f"reduced beam evaluation (3 families, 6 modes): {t_eval * 1e3:.2f} ms")
    print(f"one diagnosis, 6 modes: {t_diag:.2f} s (best of 3; {res['model_evaluations']} model evaluations; "
          f"verdict {res['verdict']}, first cause {res['findings'][0]['cause'] if res['findings'] else '-'})")
    print(f"ratio diagnosis / one evaluation: {t_diag / t_eval:.0f}")
    if "--no-fem" in sys.argv:
        return
    try:
        from probedyn.probes import get_probe

        probe, _ = get_probe("cantilever")
        t0 = time.perf_counter()
        probe.modes({"length": 200e-6, "width": 30e-6, "thickness": 2e-6, "elements_through_thickness": 1}, n_modes=6)
        t_fem = time.perf_counter() - t0
    except Exception as exc:  # the FEM belongs to another part of the project
        print(f"3D FEM not run: {exc}")
        return
    print(f"one 3D FEM modal solve (coarsest mesh, incl. meshing): {t_fem:.2f} s")
    print(f"ratio 3D solve / reduced evaluation: {t_fem / t_eval:.0f}")
    print(f"the same diagnosis on 3D re-solves would take ~{res['model_evaluations'] * t_fem / 3600:.1f} h "
          f"(ratio {res['model_evaluations'] * t_fem / t_diag:.0f})")


if __name__ == "__main__":
    main()
