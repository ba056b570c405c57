"""Benchmark of the coupled piezoelectric solves on both smart probes' default meshes.

For each probe (duo-bimorph, piezotube; default parameters and meshes) in one process:

* DOFs: mechanical unknowns (free displacement + lumped tip) and potential unknowns;
* one static actuation (drive pattern V_z) with the two solvers of :mod:`probedyn.fem.piezo`:
  ``indefinite`` (PARDISO symmetric indefinite, mtype -2, on the whole scaled system) and
  ``schur`` (static condensation of the potential: PCG on K_uu + K_ur K_rr^-1 K_ur^T with the
  factorised K_uu), the time ratio and the largest relative difference of the displacement;
* one modal solve (6 modes, electrodes shorted) with both solvers: time ratio and frequency
  difference;
* the mechanical-only SPD factorisation of K_uu as the reference time of the same process
  (all times are given as ratios to it, because the machine is shared).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/piezo.py [--quick]

``--quick`` uses coarse meshes (a smoke test).  The printed table is what
``benchmarks/results/piezo.txt`` holds.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from probedyn.fem.eigen import factorize  # noqa: E402
from probedyn.probes.piezo import piezo_model  # noqa: E402


def run(name: str, overrides: dict) -> dict:
    t0 = time.perf_counter()
    probe, values, pm, setup = piezo_model(name, overrides)
    K, M, free, n_extra = pm.mechanical_system()
    pm.blocks()
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    f = factorize(K, spd=True)
    t_spd = time.perf_counter() - t0
    f.release()
    pat = setup.pattern(None, "V_z")
    out = {"probe": name, "mech_dofs": int(K.shape[0]), "phi_nodes": pm.n_phi, "build_s": t_build, "spd_factor_s": t_spd}
    res = {}
    for solver in ("indefinite", "schur"):
        t0 = time.perf_counter()
        r = pm.static(pat, solver=solver)
        res[solver] = r
        out[f"static_{solver}_s"] = time.perf_counter() - t0
        out["coupled_dofs"] = r.dofs
        if solver == "schur":
            out["cg_iterations"] = r.timings.get("cg_iterations")
    out["static_max_rel_diff"] = float(np.abs(res["indefinite"].u - res["schur"].u).max()
                                       / np.abs(res["indefinite"].u).max())
    fr = {}
    for solver in ("indefinite", "schur"):
        t0 = time.perf_counter()
        m = pm.modes(6, "short", solver=solver)
        out[f"modal_{solver}_s"] = time.perf_counter() - t0
        out[f"modal_{solver}_opinv"] = m.timings.get("n_opinv")
        fr[solver] = m.frequencies_hz
    out["modal_max_rel_diff"] = float(np.max(np.abs(fr["indefinite"] - fr["schur"]) / fr["indefinite"]))
    out["frequencies_hz"] = fr["indefinite"].tolist()
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    cases = [("duo-bimorph", {"element_size": 15e-6} if a.quick else {}),
             ("piezotube", {"element_size": 400e-6} if a.quick else {})]
    print("coupled piezo solves, default meshes (ratios to the SPD factorisation of K_uu in the same process)")
    for name, ov in cases:
        o = run(name, ov)
        ref = o["spd_factor_s"]
        print(f"\n{name}: {o['mech_dofs']} mechanical + {o['coupled_dofs'] - o['mech_dofs']} potential unknowns "
              f"= {o['coupled_dofs']} (build {o['build_s']:.2f} s)")
        print(f"  SPD factorisation of K_uu            {ref:8.2f} s   (1.00)")
        print(f"  static, indefinite (mtype -2)        {o['static_indefinite_s']:8.2f} s   "
              f"({o['static_indefinite_s'] / ref:.2f})")
        print(f"  static, Schur PCG ({o['cg_iterations']:.0f} it)           {o['static_schur_s']:8.2f} s   "
              f"({o['static_schur_s'] / ref:.2f})   max rel diff {o['static_max_rel_diff']:.1e}")
        print(f"  6 modes, indefinite ({o['modal_indefinite_opinv']:.0f} solves)     {o['modal_indefinite_s']:8.2f} s   "
              f"({o['modal_indefinite_s'] / ref:.2f})")
        print(f"  6 modes, Schur PCG ({o['modal_schur_opinv']:.0f} solves)      {o['modal_schur_s']:8.2f} s   "
              f"({o['modal_schur_s'] / ref:.2f})   max rel diff {o['modal_max_rel_diff']:.1e}")
        print("  frequencies [Hz]: " + ", ".join(f"{x:.6g}" for x in o["frequencies_hz"]))


if __name__ == "__main__":
    main()
