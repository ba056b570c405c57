"""Benchmark of the modal pipeline: first 10 modes of the default silicon cantilever.

Part 1, P2 tetrahedra vs DOFs (element size t/n; each size in a fresh subprocess, whose peak
resident memory ``ru_maxrss`` is that model's alone), all ratios measured in that process on
the same matrices:

* assembly: the compiled kernels (``probedyn.fem.assembly``) vs the previous vectorised numpy
  path (``benchmarks/_numpy_assembly.py``), same K to round-off;
* PARDISO settings on ``K`` (sigma = 0): ordering ``iparm[1]`` 0/2/3, two-level parallel
  factorisation ``iparm[23] = 1``, parallel forward/backward ``iparm[24] = 2``, single
  precision ``iparm[27] = 1`` (its solution error against the double factor is reported),
  out-of-core ``iparm[59] = 2``; factorisation time and the time of one 15-column block solve;
* eigen-solvers on one factorisation: ARPACK (one right-hand side per step) vs the block
  shift-invert Lanczos of ``probedyn.fem.eigen`` (15 right-hand sides per solve), same
  frequencies required to 1e-8.

Part 2, accuracy per second: the default mesh (hex-s2, graded) against P2 tetrahedra, with the
errors of all 10 frequencies against the converged values (Richardson, docs/fem.md).

Part 3, the peer (optional, ``--ngsolve PYTHON``: an interpreter with ``ngsolve``, e.g.
/work/ngsolve-venv/bin/python; never a probedyn dependency): NGSolve on the same geometry and
element order at matched DOFs, end to end (mesh + assembly + factorisation + 10 modes) with
sparse Cholesky + ARPACK shift-invert and with PINVIT (``benchmarks/ngsolve_peer.py``), and
the time for the first ten modes within 0.1 % of converged in both codes.

Usage::

    .venv/bin/python benchmarks/modal.py --quick                      # two small sizes
    .venv/bin/python benchmarks/modal.py --sizes 3,5,6.5 --ngsolve /work/ngsolve-venv/bin/python \\
        --out benchmarks/results/modal.txt                              # 68k, 265k, 540k DOFs

265k DOFs need ~3 GiB, 540k ~7 GiB per process (check ``free -g``); the times depend on the
load of the machine: compare the ratios of one run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

T = 10e-6
N_MODES = 10
HERE = Path(__file__).resolve().parent
#: converged frequencies [Hz] of the default cantilever (tests/test_fem_hex.py, docs/fem.md)
CONVERGED_HZ = [153352.5, 455917.3, 956135.0, 2535545.0, 2656705.0, 2736002.0, 5150153.0, 7107932.0, 7209704.0,
                7627202.0]

PARDISO_VARIANTS = [
    ("ordering 3 (parallel METIS), classic, sequential solve [default]", {}),
    ("ordering 2 (METIS)", {"ordering": 2}),
    ("ordering 0 (minimum degree)", {"ordering": 0}),
    ("two-level parallel factorisation (iparm[23]=1)", {"factor_algorithm": 1}),
    ("parallel forward/backward (iparm[24]=2)", {"parallel_solve": 2}),
    ("single precision factors (iparm[27]=1)", {"single": 1}),
    ("out-of-core (iparm[59]=2)", {"ooc": 2}),
]


def rss() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def one(divisor: float, variants: bool = True) -> dict:
    """Mesh + assemble + solve one tetrahedral size in this process."""
    sys.path.insert(0, str(HERE))
    import _numpy_assembly as old

    from probedyn.fem import eigen as E
    from probedyn.fem import elasticity as el
    from probedyn.probes import get_probe

    probe = get_probe("cantilever")[0]
    values = probe.resolve({"element_size": T / divisor, "elements_through_thickness": 1, "element": "tet-p2"})
    t0 = time.perf_counter()
    model = probe.build(values)
    mesh_s = time.perf_counter() - t0
    out: dict = {"divisor": divisor, "elements": int(model.mesh.t.shape[1]), "mesh_s": mesh_s}
    t0 = time.perf_counter()
    K_full, M_full = model.assemble()
    out["assemble_s"] = time.perf_counter() - t0  # includes the numba pattern and the first-call overhead
    t0 = time.perf_counter()
    Kc = el.assemble_stiffness(model.mesh, model.elem_region, model.materials, model.orientations,
                               basis=model.basis)
    t1 = time.perf_counter()
    Mc = el.assemble_mass(model.mesh, model.elem_density, basis=model.basis)
    t2 = time.perf_counter()
    out.update(compiled_K_s=t1 - t0, compiled_M_s=t2 - t1)
    t0 = time.perf_counter()
    Ko = old.assemble_stiffness_numpy(model.mesh, model.elem_region, model.materials, model.orientations)
    t1 = time.perf_counter()
    Mo = old.assemble_mass_numpy(model.mesh, model.elem_density)
    t2 = time.perf_counter()
    out.update(numpy_K_s=t1 - t0, numpy_M_s=t2 - t1,
               K_max_rel_diff=float(abs(Ko - Kc).max() / abs(Ko).max()),
               M_max_rel_diff=float(abs(Mo - Mc).max() / abs(Mo).max()))
    del Ko, Mo, Kc, Mc
    K, M = model.free_matrices()
    out["dofs"] = int(K.shape[0])
    out["nnz_K"] = int(K.nnz)
    # ---- eigen-solvers on one factorisation ---------------------------------------------------
    fac = E.factorize(K)
    out["factor_s"] = fac.seconds
    out["factor_nnz"] = fac.info.get("factor_nnz")
    try:
        t0 = time.perf_counter()
        w, V, n_solved, info = E.block_eigsh(K, M, N_MODES, 0.0, fac)
        out["block_s"] = time.perf_counter() - t0
        out["block_vectors"] = n_solved
        f_block = np.sqrt(w) / (2 * np.pi)
        import scipy.sparse.linalg as spla

        cnt = [0]

        def mv(x):
            cnt[0] += 1
            return fac.solve(x)

        n = K.shape[0]
        k_int = N_MODES + max(3, N_MODES // 2)
        t0 = time.perf_counter()
        wa, _ = spla.eigsh(K, k=k_int, M=M, sigma=0.0, OPinv=spla.LinearOperator((n, n), matvec=mv, dtype=float),
                           which="LM", v0=np.random.default_rng(12345).standard_normal(n), ncv=max(2 * k_int + 1, 20))
        out["arpack_s"] = time.perf_counter() - t0
        out["arpack_solves"] = cnt[0]
        f_arp = np.sort(np.sqrt(wa) / (2 * np.pi))[:N_MODES]
        out["block_vs_arpack_max_rel"] = float(np.max(np.abs(f_block / f_arp - 1)))
        out["f_hz"] = f_arp.tolist()
        B = np.random.default_rng(1).standard_normal((n, 15))
        t0 = time.perf_counter()
        X_ref = fac.solve(B)
        out["block15_solve_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        fac.solve(B[:, 0])
        out["single_solve_s"] = time.perf_counter() - t0
    finally:
        fac.release()
    out["peak_rss_gib_solve"] = rss()
    # ---- PARDISO settings ------------------------------------------------------------------------
    if variants:
        rows = []
        for name, opts in PARDISO_VARIANTS:
            if opts.get("ooc") and K.shape[0] > 100e3:
                rows.append({"name": name, "options": opts, "error": "skipped above 100k DOFs (16x slower at 12k)"})
                continue
            try:
                f = E.factorize(K, options=opts)
                t0 = time.perf_counter()
                X = f.solve(B)
                ts = time.perf_counter() - t0
                err = float(np.abs(X - X_ref).max() / np.abs(X_ref).max())
                rows.append({"name": name, "options": opts, "factor_s": f.seconds, "analysis_s": f.info["analysis_s"],
                             "numeric_s": f.info["numeric_s"], "block15_solve_s": ts, "solution_rel_err": err,
                             "factor_nnz": f.info.get("factor_nnz")})
                f.release()
            except Exception as exc:  # a setting MKL refuses: report it
                rows.append({"name": name, "options": opts, "error": str(exc).splitlines()[0]})
        out["pardiso"] = rows
    out["peak_rss_gib"] = rss()
    return out


def hex_default() -> dict:
    """The default (hex-s2) cantilever: time end to end and the errors against converged."""
    from probedyn.probes import get_probe

    p = get_probe("cantilever")[0]
    t0 = time.perf_counter()
    v = p.resolve({})
    model = p.build(v)
    res = model.modes(N_MODES)
    tot = time.perf_counter() - t0
    f = res.frequencies_hz
    return {"dofs": res.dofs, "total_s": tot, "assemble_s": res.timings.get("assemble_s"),
            "factor_s": res.timings.get("factor_s"), "eigen_s": res.timings.get("arpack_s"),
            "max_rel_err": float(np.max(np.abs(f / np.array(CONVERGED_HZ) - 1))), "f_hz": f.tolist()}


def run_sub(args: list[str], python: str | None = None, script: str | None = None) -> dict:
    cmd = [python or sys.executable, script or __file__, *args]
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise SystemExit(f"benchmark step {args} failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def ngsolve_accuracy(python: str) -> dict | None:
    """NGSolve's cheapest run with all 10 frequencies within 0.1 % of converged: P2, P3 on
    increasingly fine meshes (stop at the first that meets it)."""
    script = str(HERE / "ngsolve_peer.py")
    best = None
    for order in (2, 3):
        for maxh in (10e-6, 7e-6, 5e-6, 3.5e-6, 2.5e-6):
            r = run_sub(["--maxh", str(maxh), "--order", str(order)], python, script)
            err = float(np.max(np.abs(np.array(r["f_hz"]) / np.array(CONVERGED_HZ) - 1)))
            r["max_rel_err"] = err
            if err < 1e-3:
                if best is None or r["total_s"] < best["total_s"]:
                    best = r
                break
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--no-variants", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--hex", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--quick", action="store_true", help="two small sizes only")
    ap.add_argument("--sizes", default=None, help="divisors n of h = t/n (default 1.5,2,3,4,5,6.5)")
    ap.add_argument("--variants-at", default=None,
                    help="divisors at which the PARDISO settings are measured (default: every size)")
    ap.add_argument("--ngsolve", default=None, help="python interpreter with ngsolve (peer column)")
    ap.add_argument("--out", default=None, help="also write the table to this file (and .json beside it)")
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(one(a.one, not a.no_variants)))
        return
    if a.hex:
        print(json.dumps(hex_default()))
        return

    import tempfile

    os.environ.setdefault("PROBEDYN_CACHE", tempfile.mkdtemp(prefix="probedyn-bench-"))
    divisors = [1.5, 2.0] if a.quick else [float(x) for x in (a.sizes or "1.5,2,3,4,5,6.5").split(",")]
    variants_at = divisors if a.variants_at is None else [float(x) for x in a.variants_at.split(",")]
    lines: list[str] = []
    data: dict = {"load_start": os.getloadavg(), "cpus": os.cpu_count()}

    def say(s: str = "") -> None:
        print(s, flush=True)
        lines.append(s)

    say(f"probedyn benchmarks/modal.py — first {N_MODES} modes of the default cantilever (300 x 30 x 10 um, silicon)")
    say(f"machine: {os.cpu_count()} logical CPUs, load average at start {os.getloadavg()[0]:.1f}; each size in a fresh "
        f"process; times in s, memory = peak RSS")
    say("")
    say("1. P2 tetrahedra: compiled vs numpy assembly, block Lanczos vs ARPACK on one PARDISO factorisation")
    say(f"{'h':>6} {'DOFs':>8} {'mesh':>6} {'asm cmp':>8} {'asm np':>7} {'ratio':>6} {'factor':>7} {'ARPACK':>7} "
        f"{'(solves)':>8} {'block':>6} {'(vecs)':>6} {'ratio':>6} {'|df/f|':>8} {'GiB':>5} {'ng total':>8} {'pd/ng':>6}")
    rows = []
    for d in divisors:
        # PARDISO settings only at the --variants-at sizes (seven factorisations each: minutes at 265k+)
        r = run_sub(["--one", str(d)] + ([] if d in variants_at else ["--no-variants"]))
        asm_c = r["compiled_K_s"] + r["compiled_M_s"]
        asm_n = r["numpy_K_s"] + r["numpy_M_s"]
        r["probedyn_total_s"] = r["mesh_s"] + r["assemble_s"] + r["factor_s"] + r["block_s"]
        ng = ""
        ratio_ng = ""
        if a.ngsolve:
            args = ["--dofs", str(r["dofs"])] + (["--pinvit"] if r["dofs"] < 100e3 else [])  # PINVIT: slow
            g = run_sub(args, a.ngsolve, str(HERE / "ngsolve_peer.py"))
            r["ngsolve"] = g
            ng = f"{g['total_s']:8.1f}"
            ratio_ng = f"{r['probedyn_total_s'] / g['total_s']:6.2f}"
        rows.append(r)
        say(f"{'t/' + format(d, 'g'):>6} {r['dofs']:>8d} {r['mesh_s']:>6.1f} {asm_c:>8.2f} {asm_n:>7.2f} "
            f"{asm_n / asm_c:>6.1f} {r['factor_s']:>7.2f} {r['arpack_s']:>7.2f} {r['arpack_solves']:>8d} "
            f"{r['block_s']:>6.2f} {r['block_vectors']:>6d} {r['arpack_s'] / r['block_s']:>6.2f} "
            f"{r['block_vs_arpack_max_rel']:>8.1e} {r['peak_rss_gib']:>5.2f} {ng:>8} {ratio_ng:>6}")
    say("")
    say("PARDISO settings (same K, factorisation and one 15-column block solve; solution error vs the default):")
    for r in rows:
        say(f"  {r['dofs']} DOFs:")
        for v in r.get("pardiso", []):
            if "error" in v:
                say(f"    {v['name']:<66} error: {v['error']}")
            else:
                say(f"    {v['name']:<66} factor {v['factor_s']:7.2f} s (analysis {v['analysis_s']:.2f}) "
                    f"solve15 {v['block15_solve_s']:6.3f} s  err {v['solution_rel_err']:.1e}")
    if a.ngsolve:
        say("")
        say("NGSolve peer (same geometry, P2, matched DOFs; mesh + assembly + Cholesky + 10 modes):")
        for r in rows:
            g = r["ngsolve"]
            pin = f", PINVIT {g['pinvit_s']:.1f} s (|df/f| {g['pinvit_max_rel_diff']:.0e})" if "pinvit_s" in g else ""
            say(f"  {g['dofs']} DOFs: mesh {g['mesh_s']:.1f} s, assembly {g['assemble_s']:.1f} s, Cholesky "
                f"{g['factor_s']:.1f} s, ARPACK {g['arpack_s']:.1f} s -> total {g['total_s']:.1f} s{pin}; probedyn "
                f"{r['probedyn_total_s']:.1f} s -> ratio {r['probedyn_total_s'] / g['total_s']:.2f}")
    say("")
    say("2. accuracy per second: all 10 frequencies within 0.1 % of converged")
    h = run_sub(["--hex"])
    data["hex_default"] = h
    say(f"  probedyn default (hex-s2, graded): {h['dofs']} DOFs, {h['total_s']:.2f} s end to end, max error "
        f"{100 * h['max_rel_err']:.3f} %")
    for r in rows:
        err = float(np.max(np.abs(np.array(r["f_hz"]) / np.array(CONVERGED_HZ) - 1)))
        r["max_rel_err"] = err
        say(f"  P2 tetrahedra t/{r['divisor']:g}: {r['dofs']} DOFs, {r['probedyn_total_s']:.1f} s, max error {100 * err:.3f} %")
    if a.ngsolve:
        best = ngsolve_accuracy(a.ngsolve)
        data["ngsolve_accuracy"] = best
        if best:
            say(f"  NGSolve cheapest within 0.1 %: P{best['order']}, maxh {best['maxh']:.2g} m, {best['dofs']} DOFs, "
                f"{best['total_s']:.1f} s (max error {100 * best['max_rel_err']:.3f} %) -> probedyn/NGSolve "
                f"{h['total_s'] / best['total_s']:.2f}")
    data["rows"] = rows
    data["load_end"] = os.getloadavg()
    say("")
    say(f"load average at the end {os.getloadavg()[0]:.1f}")
    if a.out:
        from probedyn.core.io import write_json, write_text

        write_text(a.out, "\n".join(lines) + "\n")
        write_json(str(Path(a.out).with_suffix(".json")), data)


if __name__ == "__main__":
    main()
