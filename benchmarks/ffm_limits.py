"""Where the FFM kernel's time goes, and what bounds its ratio over LSODA (issue 15, item 5).

The same 1D line scan (Table 2.1, mica, bristle friction, V = 2 um/s) as ``benchmarks/ffm.py``,
72 nm (first slip at 64.75 nm + sawtooth), all in this process:

* the fast integrator (``schemes.ffm.line_scan``: numba Rosenbrock 2(3), analytic Jacobian):
  accepted and rejected steps, wall time per step, and how the steps split between the
  **stick** phases (tip velocity below 10 V) and the **slips** (the transient after each slip:
  the tip rings at the cantilever's frequency with Q ~ 1/(2 zeta), every ring resolved);
* plain LSODA without a Jacobian (scipy, python right-hand side) at the same tolerances:
  right-hand-side calls, wall time per call;
* the reference (Radau with the analytic Jacobian, rtol 1e-8) for the errors of both.

The ratio LSODA/fast = (LSODA calls x python cost per call) / (fast steps x compiled cost per
step): printed factor by factor, so the bound is visible (fewer steps cannot come from a
better step-size control if the slip transients need them; see the printed step shares).

Run:  .venv/bin/python benchmarks/ffm_limits.py
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ffm import scipy_scan  # noqa: E402

from probedyn.schemes import ffm as F  # noqa: E402


def main() -> int:
    ffm = F.FFM.from_preset("mica")
    dF = ffm.friction.values["F_s"] - ffm.friction.values["F_c"]
    k, V, m = ffm.cantilever["k_x"], ffm.cantilever["V"], ffm.cantilever["m_x"]
    F.warm_up()
    atol = F._atol(ffm, 1e-7)
    length = 72e-9
    out: dict = {"length_m": length}
    t0 = time.perf_counter()
    ref = scipy_scan(ffm, length, "Radau", 1e-8, atol * 1e-2)
    out["reference"] = {"wall_s": time.perf_counter() - t0, "nfev": int(ref.nfev), "njev": int(ref.njev)}
    grid = np.linspace(0, length / V, 20001)
    F_ref = k * (V * grid - ref.sol(grid)[0])

    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        r = F.line_scan(ffm, length)
        best = min(best, time.perf_counter() - t0)
    Fx = np.interp(V * grid, r.base, r.lateral_force)
    slip = np.abs(r.v) > 10 * V
    n = r.n_steps
    h = np.diff(r.t)
    out["fast"] = {"wall_s": best, "steps": n, "rejected": r.n_rejected, "us_per_step": 1e6 * best / max(n, 1),
                   "steps_in_slips": int(slip[1:].sum()), "share_in_slips": float(slip[1:].mean()),
                   "scan_share_in_slips": float(h[slip[1:]].sum() / h.sum()),
                   "h_min_s": float(h.min()), "h_max_s": float(h.max()),
                   "period_s": float(2 * np.pi * np.sqrt(m / k)),
                   "max_err": float(np.max(np.abs(Fx - F_ref)) / dF)}

    t0 = time.perf_counter()
    ls = scipy_scan(ffm, length, "LSODA", 1e-5, atol, jac=False, limit=300.0)
    t_ls = time.perf_counter() - t0
    F_ls = k * (V * grid - ls.sol(grid)[0])
    out["lsoda"] = {"wall_s": t_ls, "nfev": int(ls.nfev), "njev": int(ls.njev), "steps": int(ls.t.size - 1),
                    "us_per_call": 1e6 * t_ls / max(int(ls.nfev), 1), "max_err": float(np.max(np.abs(F_ls - F_ref)) / dF)}
    f, L = out["fast"], out["lsoda"]
    out["ratio"] = L["wall_s"] / f["wall_s"]
    print(f"FFM 72 nm scan (mica, bristle), errors in F_s - F_c; wall times best of 5 (fast) / 1 (LSODA)")
    print(f"  fast:  {f['steps']} steps ({f['rejected']} rejected), {f['wall_s'] * 1e3:.2f} ms, "
          f"{f['us_per_step']:.2f} us/step; {100 * f['share_in_slips']:.0f} % of the steps in slips covering "
          f"{100 * f['scan_share_in_slips']:.1f} % of the time; h {f['h_min_s']:.2e}..{f['h_max_s']:.2e} s "
          f"(cantilever period {f['period_s']:.2e} s); max error {f['max_err']:.1e}")
    print(f"  LSODA: {L['steps']} steps, {L['nfev']} rhs calls ({L['njev']} finite-difference Jacobians), "
          f"{L['wall_s']:.2f} s, {L['us_per_call']:.1f} us/call; max error {L['max_err']:.1e}")
    print(f"  ratio LSODA / fast = {out['ratio']:.1f} = steps {L['steps'] / f['steps']:.2f} x "
          f"(rhs calls per step {L['nfev'] / max(L['steps'], 1):.2f} x us/call {L['us_per_call']:.1f}) / "
          f"(us/step {f['us_per_step']:.2f})")
    if len(sys.argv) > 1:
        Path(sys.argv[1]).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
