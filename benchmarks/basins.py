"""Benchmark: a 256 x 256 basin of attraction of the two-mass stick-slip model (Fig 4.9).

Measures, in one process:

1. the compiled (numba) kernel over all cells at once, single thread;
2. the same grid through the sweep engine (Dask LocalCluster, 2 workers; threads, and with
   ``--processes`` also as processes), including cluster start-up and NetCDF I/O;
3. the reference: a loop of per-cell ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-8,
   atol 1e-10, to t = 150, i.e. 6x the longest settling time observed) on a random subset.

Prints the time per cell of both, the speed-up ratio, and the agreement (same node reached,
distance of the reference's end state to that node) on the subset.

    .venv/bin/python benchmarks/basins.py [--grid 256] [--subset 16] [--u0 20] [--processes]
"""

from __future__ import annotations

import argparse
import sys
import json
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=256)
    ap.add_argument("--subset", type=int, default=16)
    ap.add_argument("--u0", type=float, default=20.0)
    ap.add_argument("--psi", type=float, default=5.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--processes", action="store_true", help="also time the engine with process workers")
    args = ap.parse_args()

    from probedyn.schemes import stickslip as ss
    from probedyn.schemes.sweep import axis, run_sweep

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from stickslip_reference import basin_reference  # the scipy DOP853 reference (not library code)

    u0, psi, n = args.u0, args.psi, args.grid
    (a3, b3), (a4, b4) = ss.default_basin_window(u0)
    x3 = axis("x3_0", a3, b3, n)
    x4 = axis("x4_0", a4, b4, n)
    X3, X4 = np.meshgrid(x3, x4)

    ss.basin_labels(np.zeros(1), np.zeros(1), u0, psi)  # load the compiled kernel (not timed)
    t0 = time.perf_counter()
    vec = ss.basin_labels(X3, X4, u0, psi)
    t_vec = time.perf_counter() - t0

    rows = [("compiled kernel, 1 thread, in process", t_vec)]
    with tempfile.TemporaryDirectory() as td:
        modes = [False] + ([True] if args.processes else [])
        for proc in modes:
            t0 = time.perf_counter()
            r = run_sweep(ss.basin_cell, {"x4_0": x4, "x3_0": x3}, fixed={"u0": u0, "psi": psi},
                          out=Path(td) / f"b{int(proc)}.nc", workers=args.workers, processes=proc, progress=False)
            t_eng = time.perf_counter() - t0
            same = np.array_equal(r.dataset["label"].values, vec["label"])
            rows.append((f"sweep engine, {args.workers} {'process' if proc else 'thread'} workers (incl. start-up, NetCDF)", t_eng))
            if not same:
                raise SystemExit("engine result differs from the in-process kernel")

    rng = np.random.default_rng(2026)
    pick = rng.choice(X3.size, size=args.subset, replace=False)
    t0 = time.perf_counter()
    refs = [basin_reference(X3.flat[i], X4.flat[i], u0, psi, t_end=150.0, rtol=1e-8, atol=1e-10) for i in pick]
    t_ref = time.perf_counter() - t0
    lab_ref = np.array([r["label"] for r in refs])
    lab_vec = vec["label"].ravel()[pick]
    agree = float(np.mean(lab_ref == lab_vec))
    dist = max(r["dist"] for r in refs)
    per_vec = t_vec / X3.size
    per_ref = t_ref / args.subset
    res = {
        "u0": u0, "psi": psi, "grid": n, "cells": int(X3.size),
        "t_kernel_s": t_vec, "t_engine_s": {name: t for name, t in rows[1:]},
        "unsettled": int((vec["label"] < 0).sum()),
        "subset": args.subset, "t_solve_ivp_subset_s": t_ref,
        "per_cell_kernel_s": per_vec, "per_cell_solve_ivp_s": per_ref,
        "speedup_per_cell": per_ref / per_vec,
        "estimated_solve_ivp_full_grid_s": per_ref * X3.size,
        "label_agreement": agree, "max_ref_distance_to_node": dist,
    }
    print(f"basin of attraction u0 = {u0:g}, psi = {psi:g}, {n} x {n} = {X3.size} cells")
    for name, t in rows:
        print(f"  {name:62s} {t:8.2f} s")
    print(f"  per-cell solve_ivp (DOP853) loop on {args.subset} cells: {t_ref:8.2f} s "
          f"({per_ref * 1e3:.0f} ms/cell; full grid would take ~{per_ref * X3.size / 3600:.1f} h)")
    print(f"  ratio (time per cell, solve_ivp loop / compiled kernel): {per_ref / per_vec:,.0f}")
    print(f"  agreement on the subset: {100 * agree:.1f} % same node; reference end state within "
          f"{dist:.1e} of that node")
    print(json.dumps(res))


if __name__ == "__main__":
    main()
