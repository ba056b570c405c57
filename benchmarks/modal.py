"""Benchmark of the modal pipeline: first 10 modes of the default silicon cantilever vs DOFs.

For each mesh (P2 tetrahedra, element size t/n for n = 1.5 ... 6.5, about 12k to 580k DOFs) a
fresh subprocess meshes, assembles (K and M separately, the vectorised path of
``probedyn.fem.elasticity``), factorises ``K - sigma M`` with PARDISO and runs ARPACK for 10
modes; its peak resident memory (``ru_maxrss``) is the peak of that model alone.

Reference computations in the same run:

* SuperLU (scipy's default ``splu``) vs PARDISO on the same shift-invert matrix at a moderate
  size (h = t/3, ~70k DOFs) (same frequencies required to 1e-9), reported as a time ratio;
* scikit-fem's generic ``BilinearForm`` assembly vs the vectorised assembly at the same size;
* the largest model that fits in 24 GiB, from a power-law fit of peak memory vs DOFs over the
  three largest runs (an extrapolation when the largest run is below that).

Usage::

    .venv/bin/python benchmarks/modal.py            # full table (~10 min on 2 cores)
    .venv/bin/python benchmarks/modal.py --quick    # two small sizes, for a smoke test

The printed table is what ``benchmarks/results/modal.txt`` holds.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

T = 10e-6
N_MODES = 10


def one(divisor: float, superlu: bool = False, skfem_assembly: bool = False) -> dict:
    """Mesh + assemble + solve one size in this process; returns timings and memory."""
    from probedyn.probes import get_probe

    probe = get_probe("cantilever")[0]
    values = probe.resolve({"element_size": T / divisor, "elements_through_thickness": 1})
    t0 = time.perf_counter()
    model = probe.build(values)
    mesh_s = time.perf_counter() - t0
    model.assemble()
    res = model.modes(N_MODES)
    out = {
        "divisor": divisor, "dofs": res.dofs, "elements": int(model.mesh.t.shape[1]),
        "mesh_s": mesh_s,
        "assemble_K_s": res.timings["assemble_K_s"], "assemble_M_s": res.timings["assemble_M_s"],
        "factor_s": res.timings["factor_s"], "arpack_s": res.timings["arpack_s"],
        "postprocess_s": res.timings["postprocess_s"], "n_opinv": res.timings["n_opinv"],
        "solver": res.solver, "f1_hz": res.modes[0].frequency_hz,
        "families": res.families(),
    }
    K, M = model.assemble()
    free = model.free_dofs
    out["nnz_K"] = int(K[free][:, free].nnz)
    if superlu:
        from probedyn.fem.eigen import shift_invert_eigsh

        t = time.perf_counter()
        r2 = shift_invert_eigsh(K[free][:, free].tocsr(), M[free][:, free].tocsr(), N_MODES, solver="superlu")
        out["superlu_factor_s"] = r2.factor_s
        out["superlu_total_s"] = time.perf_counter() - t
        out["pardiso_total_s"] = res.timings["factor_s"] + res.timings["arpack_s"]
        f_sl = np.sqrt(r2.eigenvalues) / (2 * np.pi)
        out["superlu_max_rel_diff"] = float(np.max(np.abs(f_sl / res.frequencies_hz - 1)))
    if skfem_assembly:
        from probedyn.fem import elasticity as el

        t = time.perf_counter()
        Kref = el.assemble_stiffness_skfem(model.mesh, model.elem_region, model.materials, model.orientations)
        out["skfem_assemble_K_s"] = time.perf_counter() - t
        out["skfem_vs_fast_max_rel"] = float(abs(Kref - model._Kel).max() / abs(model._Kel).max())
    out["peak_rss_gib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    return out


def run_sub(divisor: float, **flags) -> dict:
    cmd = [sys.executable, __file__, "--one", str(divisor)]
    for k, v in flags.items():
        if v:
            cmd.append("--" + k.replace("_", "-"))
    # one OpenBLAS thread: ARPACK's small dense steps otherwise spin against MKL's threads
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise SystemExit(f"benchmark size t/{divisor} failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--superlu", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--skfem-assembly", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--quick", action="store_true", help="two small sizes only")
    ap.add_argument("--out", default=None, help="also write the table to this file")
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(one(a.one, a.superlu, a.skfem_assembly)))
        return

    import tempfile

    os.environ.setdefault("PROBEDYN_CACHE", tempfile.mkdtemp(prefix="probedyn-bench-"))
    divisors = [1.5, 2.0] if a.quick else [1.5, 2.0, 3.0, 4.0, 5.0, 6.5]
    lines = []

    def say(s: str = "") -> None:
        print(s, flush=True)
        lines.append(s)

    say(f"probedyn benchmarks/modal.py — first {N_MODES} modes of the default cantilever "
        f"(300 x 30 x 10 um, silicon), P2 tetrahedra")
    say(f"machine: {os.cpu_count()} logical CPUs; each size in a fresh process; times in s, memory = peak RSS")
    say("")
    hdr = (f"{'h':>6} {'DOFs':>8} {'tets':>7} {'mesh':>6} {'asm K':>6} {'asm M':>6} {'factor':>7} "
           f"{'ARPACK':>7} {'total':>7} {'peak GiB':>8} {'f1 [Hz]':>10}  solver")
    say(hdr)
    rows = []
    for d in divisors:
        r = run_sub(d)
        rows.append(r)
        tot = r["assemble_K_s"] + r["assemble_M_s"] + r["factor_s"] + r["arpack_s"]
        say(f"{'t/' + format(d, 'g'):>6} {r['dofs']:>8d} {r['elements']:>7d} {r['mesh_s']:>6.1f} "
            f"{r['assemble_K_s']:>6.2f} {r['assemble_M_s']:>6.2f} {r['factor_s']:>7.2f} {r['arpack_s']:>7.2f} "
            f"{tot:>7.2f} {r['peak_rss_gib']:>8.2f} {r['f1_hz']:>10.1f}  {r['solver']}")
    say("")
    # scaling fits over the larger half of the runs
    big = rows[-3:] if len(rows) >= 3 else rows
    n = np.array([r["dofs"] for r in big], float)
    mem = np.array([r["peak_rss_gib"] for r in big])
    tsol = np.array([r["factor_s"] + r["arpack_s"] for r in big])
    tasm = np.array([r["assemble_K_s"] + r["assemble_M_s"] for r in big])
    if len(big) >= 2:
        pm = np.polyfit(np.log(n), np.log(mem), 1)
        ps = np.polyfit(np.log(n), np.log(tsol), 1)
        pa = np.polyfit(np.log(n), np.log(tasm), 1)
        n24 = float(np.exp((np.log(24.0) - pm[1]) / pm[0]))
        t24 = float(np.exp(np.polyval(ps, np.log(n24))))
        say(f"scaling over the {len(big)} largest runs: peak memory ~ DOFs^{pm[0]:.2f}, "
            f"solve time ~ DOFs^{ps[0]:.2f}, assembly ~ DOFs^{pa[0]:.2f}")
        say(f"largest model in 24 GiB (extrapolated): ~{n24 / 1e6:.2f} M DOFs, 10 modes in ~{t24:.0f} s "
            f"(solve only, 2 cores)")
        say("")
    # reference comparisons at a moderate size
    ref_div = 2.0 if a.quick else 3.0
    ref = run_sub(ref_div, superlu=True)
    asm = run_sub(2.0, skfem_assembly=True)
    say(f"reference at {ref['dofs']} DOFs (h = t/{ref_div:g}):")
    say(f"  factorisation: SuperLU {ref['superlu_factor_s']:.2f} s vs PARDISO {ref['factor_s']:.2f} s "
        f"-> ratio {ref['superlu_factor_s'] / ref['factor_s']:.1f}x")
    say(f"  10-mode solve: SuperLU {ref['superlu_total_s']:.2f} s vs PARDISO {ref['pardiso_total_s']:.2f} s "
        f"-> ratio {ref['superlu_total_s'] / ref['pardiso_total_s']:.1f}x; "
        f"max relative frequency difference {ref['superlu_max_rel_diff']:.1e}")
    say(f"  stiffness assembly at {asm['dofs']} DOFs: scikit-fem BilinearForm {asm['skfem_assemble_K_s']:.2f} s vs "
        f"vectorised {asm['assemble_K_s']:.2f} s -> ratio {asm['skfem_assemble_K_s'] / asm['assemble_K_s']:.1f}x "
        f"(max relative entry difference {asm['skfem_vs_fast_max_rel']:.1e})")
    if a.out:
        from probedyn.core.io import write_text

        write_text(a.out, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
