"""Nano-pushing: Radau with the analytic Jacobian vs. Radau with scipy's finite-difference Jacobian.

Prints wall times, their ratio and the agreement of the results (mean step, sticking points).
Run: .venv/bin/python benchmarks/push_jacobian.py
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from probedyn.schemes import pushing as P


def run_fd(model, travel):
    """Same integration as pushing.simulate (1D) but without the analytic Jacobian."""
    idx = np.array(P.IX)

    def f(t, yy):
        full = np.zeros(P.NS)
        full[idx] = yy
        return model.rhs(t, full)[idx]

    p = model.p
    atol = np.array([1e-14, 1e-9, 1e-14, 1e-9, 1e-17, 1e-9])
    t0 = time.perf_counter()
    sol = solve_ivp(f, (0, travel / p["V"]), model.initial_state()[idx], method="Radau", rtol=p["rtol"],
                    atol=atol, max_step=0.05 * p["a"] / p["V"])
    wall = time.perf_counter() - t0
    full = np.zeros((P.NS, sol.t.size))
    full[idx] = sol.y
    return P.PushResult(sol.t, full, model, wall, sol.nfev)


def main() -> None:
    for sub in ("mica", "hopg"):
        m = P.make_model(sub, {})
        travel = 8e-9
        ra = P.simulate(m, travel, n_out=10**9)
        rf = run_fd(m, travel)
        a_an, a_fd = P.analyse(ra), P.analyse(rf)
        print(f"{sub}: analytic Jacobian {ra.wall_time:.2f} s ({ra.nfev} f-evals), finite-difference "
              f"{rf.wall_time:.2f} s ({rf.nfev} f-evals); speed-up {rf.wall_time / ra.wall_time:.2f}x; "
              f"mean step {a_an['mean_step_m']:.5e} vs {a_fd['mean_step_m']:.5e} m "
              f"(rel. diff {abs(a_an['mean_step_m'] / a_fd['mean_step_m'] - 1):.1e})")


if __name__ == "__main__":
    main()
