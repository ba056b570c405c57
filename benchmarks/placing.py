"""Benchmark: the release simulation of vibrational nano-placing (eq 4.42, full Maugis-Dugdale
contact) -- the compiled integrator against plain ``scipy.integrate.solve_ivp`` -- and a 64 x 64
outcome map on Dask with two worker processes.

* one run, four regimes (Table 4.4's point: attached over three kHz periods; omega = 1e8 rad/s:
  released; 6.9e7 rad/s: recaptured; 1.5e9 rad/s near the contact resonance): the numba ode23s
  kernel of :mod:`probedyn.schemes.placing._kernel` (analytic Jacobian, event location) against
  ``solve_ivp`` (Radau and BDF with the same analytic Jacobian, LSODA) on the same right-hand side
  (the compiled one, called from Python), same tolerances (rtol = atol = 1e-6 in the scaled
  variables), restarted at every contact transition with terminal events. Median of repeats,
  all in this process; outcomes and separation times are compared.
* the 64 x 64 map omega = 1e6-1e10 rad/s x A = 0.1 nm-2 um at M = 2e-18 kg
  (:func:`probedyn.schemes.placing.release.outcome_map`): wall time on a LocalCluster with two
  single-threaded worker processes (includes starting the cluster and loading the compiled
  kernels in each worker), CPU per cell; NetCDF and a picture under ``--out``.
* per-cell time of the map with solve_ivp (LSODA, the fastest plain one) on a random sample of
  48 cells of the same grid, against the kernel on the same cells.

The machine is shared (2 cores, up to 8 agents): compare the ratios, not the absolute times.

Run:  .venv/bin/python benchmarks/placing.py [--out DIR] [--n 64]
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import statistics
import time
from pathlib import Path

import numpy as np

print = functools.partial(print, flush=True)  # noqa: A001


def _median_time(fn, repeat):
    ts = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), out


def main() -> None:
    from probedyn.schemes.placing import release as rel
    from probedyn.schemes.placing.probe import TABLE, PlacingProbe

    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    ap.add_argument("--n", type=int, default=64)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    probe = PlacingProbe.table()
    tabs = rel._tables(float(TABLE["lambda"]))
    rel.simulate(rel.setup_release(probe, tables=tabs))  # compile / load the kernel
    cases = [("Table 4.4 point (attached)", dict()), ("omega 1e8, A 0.5 um (released)", dict(A=0.5e-6, omega=1e8)),
             ("omega 6.9e7, A 0.5 um (recaptured)", dict(A=0.5e-6, omega=6.9e7)),
             ("omega 1.5e9, A 3 nm (resonant release)", dict(A=3e-9, omega=1.5e9))]
    single = []
    for name, kw in cases:
        st = rel.setup_release(probe, tables=tabs, **kw)
        tk, rk = _median_time(lambda: rel.simulate(st), 7)
        row = {"case": name, "outcome": rk.outcome, "kernel_s": tk, "kernel_steps": rk.n_steps,
               "t_sep_kernel_s": rk.t_separation_s}
        for method in ("Radau", "BDF", "LSODA"):
            ts, rs = _median_time(lambda: rel.simulate_scipy(st, method=method), 3)
            row[f"{method}_s"] = ts
            row[f"{method}_ratio"] = ts / tk
            row[f"{method}_outcome"] = rs.outcome
            row[f"{method}_t_sep_rel_diff"] = (rs.t_separation_s / rk.t_separation_s - 1
                                               if math.isfinite(rk.t_separation_s) else None)
        single.append(row)
        print(f"{name}: {rk.outcome}, kernel {tk * 1e3:.2f} ms ({rk.n_steps} steps); "
              + ", ".join(f"{m} {row[m + '_s'] * 1e3:.1f} ms (x{row[m + '_ratio']:.0f}, {row[m + '_outcome']})"
                          for m in ("Radau", "BDF", "LSODA")))
    # the map on Dask
    n = int(args.n)
    om = np.geomspace(1e6, 1e10, n)
    A = np.geomspace(1e-10, 2e-6, n)
    nc = args.out / f"placing_map_omega_A_{n}x{n}.nc"
    t0 = time.perf_counter()
    res = rel.outcome_map(probe, {"omega": om, "A": A}, fixed={"M": float(TABLE["M1"])}, out=nc, workers=2,
                          processes=True, chunk_size=max(64, n * n // 16), restart=True)
    wall = time.perf_counter() - t0
    ds = res.dataset
    cpu = ds["cpu_s"].values
    counts = {v: int((ds["outcome"].values == k).sum()) for k, v in rel.OUTCOMES.items()}
    print(f"{n}x{n} map on Dask (2 worker processes): {wall:.1f} s wall, CPU per cell median "
          f"{np.median(cpu) * 1e3:.2f} ms, mean {np.mean(cpu) * 1e3:.2f} ms; {counts}")
    # per-cell: kernel vs LSODA on a random sample of the same grid
    rng = np.random.default_rng(0)
    idx = rng.choice(n * n, 48, replace=False)
    tk_cells, ts_cells, agree = [], [], 0
    for i in idx:
        w, a = om[i // n], A[i % n]
        st = rel.setup_release(probe, M=float(TABLE["M1"]), A=float(a), omega=float(w), tables=tabs)
        t0 = time.perf_counter()
        rk = rel.simulate(st)
        tk_cells.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        rs = rel.simulate_scipy(st, method="LSODA")
        ts_cells.append(time.perf_counter() - t0)
        agree += rk.code == rs.code
    per_cell = {"kernel_mean_s": float(np.mean(tk_cells)), "lsoda_mean_s": float(np.mean(ts_cells)),
                "ratio_of_means": float(np.mean(ts_cells) / np.mean(tk_cells)),
                "median_ratio": float(np.median(np.array(ts_cells) / np.array(tk_cells))),
                "outcomes_agree": f"{agree}/{len(idx)}"}
    print(f"per cell (48 random cells): kernel {per_cell['kernel_mean_s'] * 1e3:.2f} ms, LSODA "
          f"{per_cell['lsoda_mean_s'] * 1e3:.1f} ms (x{per_cell['ratio_of_means']:.0f}); outcomes agree {per_cell['outcomes_agree']}")
    out = {"single_runs": single, "map": {"n": n, "wall_s": wall, "cpu_per_cell_median_s": float(np.median(cpu)),
                                          "cpu_per_cell_mean_s": float(np.mean(cpu)), "counts": counts, "netcdf": str(nc)},
           "per_cell_vs_solve_ivp": per_cell, "note": "shared 2-core machine: ratios in one process are the result"}
    (args.out / "placing.json").write_text(json.dumps(out, indent=2, default=float))
    try:
        from probedyn.report.placing import plot_release_map

        tb = rel._tables(float(TABLE["lambda"]))
        m = {"axes": ["omega", "A"], "x": om, "y": A, "fixed": {"M": float(TABLE["M1"])},
             "outcome": ds["outcome"].transpose("omega", "A").values}
        plot_release_map(m, args.out / f"placing_map_omega_A_{n}x{n}.png",
                         f"release outcome, M = 2e-18 kg ({n} x {n}, Dask)", tb.pull_off_force, tb.k1_bar * tb.P / tb.l)
    except ImportError as exc:  # the report package arrives with the CLI restructuring
        print(f"(no picture: {exc})")


if __name__ == "__main__":
    main()
