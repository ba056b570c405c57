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
  shift-invert Lanczos of ``probedyn.fem.eigen`` (a block of 6 right-hand sides per solve for
  10 modes; its error-bound history is printed), same frequencies required to 1e-8.

"End to end" for probedyn = mesh + assembly + free-DOF extraction (since session 5) +
factorisation + block solve; since session 6 PARDISO's analysis runs beside the assembly (as in
``ElasticModel.modes``; ``--no-overlap``: after it) and the extra measurements (assembly again,
numpy assembly, ARPACK, PARDISO settings) come after the end-to-end phases.

Part 2, accuracy per second: the default mesh (hex-s2, graded) against P2 tetrahedra, with the
errors of all 10 frequencies against the converged values (Richardson, docs/fem.md).

Part 3, the peer (optional, ``--ngsolve PYTHON``: an interpreter with ``ngsolve``, e.g.
/work/ngsolve-venv/bin/python; never a probedyn dependency): NGSolve on the same geometry and
element order at matched DOFs, end to end (mesh + assembly + factorisation + 10 modes) with
sparse Cholesky + ARPACK shift-invert and with PINVIT (``benchmarks/ngsolve_peer.py``), and
the time for the first ten modes within 0.1 % of converged in both codes.

Usage::

    .venv/bin/python benchmarks/modal.py --quick                      # two small sizes
    # session 4 (benchmarks/results/modal-s4*.txt): matched DOFs, two runs per code, min taken
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s4-265k.txt
    .venv/bin/python benchmarks/modal.py --match 6.35:1.35e-6 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s4-510k.txt
    # session 5 (benchmarks/results/modal-s5-*.txt; end to end now includes the free-DOF extraction)
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s5-265k.txt
    .venv/bin/python benchmarks/modal.py --match 6.35:1.35e-6 --variants-at 0 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s5-509k.txt
    # session 6 (PARDISO's analysis beside the assembly, the default): the quiet peer run, and the
    # A/B of the overlap (--no-overlap: the session-5 order, analysis after the assembly)
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s6-265k-quiet.txt
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --no-overlap --out benchmarks/results/modal-s6-265k-quiet-nooverlap.txt

    # session 7 (from 150k free DOFs the default is the float32 factor + mixed_eigsh, as in
    # ElasticModel.modes): the quiet peer run, and the A/B with the session-6 double path
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s7-265k-quiet.txt
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --double --out benchmarks/results/modal-s7-265k-quiet-double.txt

    # session 8 (threaded sparse / tall products in the eigen-solvers, compiled CSR conversions;
    # the mixed path's total now counts the mixed solver's own time): the quiet peer run, the
    # A/B with the double path, and the A/B of the threads (NUMBA_NUM_THREADS=1: scipy's products)
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s8-265k-quiet.txt
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \\
        --double --out benchmarks/results/modal-s8-265k-quiet-double.txt
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 \\
        --no-accuracy --out benchmarks/results/modal-s8-265k-quiet-1thread.txt

    # session 9 (gmsh's HXT mesher above meshes._gmsh.HXT_MIN_TETS predicted tetrahedra: ~9 %
    # fewer tetrahedra at one size, so t/5.2 (265,278 DOFs) now matches maxh 2.045 um (268,128);
    # t/5 gives 242,877): the quiet peer run, and the same with NUMBA_NUM_THREADS=1
    .venv/bin/python benchmarks/modal.py --match 5.2:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s9-265k-quiet.txt
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/modal.py --match 5.2:2.045e-6 --repeat 2 --variants-at 0 \
        --no-accuracy --out benchmarks/results/modal-s9-265k-quiet-1thread.txt
    .venv/bin/python benchmarks/modal.py --match 6.6:1.35e-6 --variants-at 0 --no-accuracy \
        --ngsolve /work/ngsolve-venv/bin/python --out benchmarks/results/modal-s9-509k-quiet.txt
    # the mesher A/B (session 8's Delaunay mesh at its own matched size, same code otherwise)
    .venv/bin/python benchmarks/modal.py --match 5:2.045e-6 --repeat 2 --variants-at 0 --no-accuracy \
        --delaunay --out benchmarks/results/modal-s9-265k-quiet-delaunay.txt

The NGSolve venv (never a probedyn dependency): ``python3 -m venv /work/ngsolve-venv &&
/work/ngsolve-venv/bin/pip install ngsolve scipy``.  Matching DOFs: Netgen's DOF count is not
smooth in maxh (``ngsolve_peer.py --count --maxh H`` meshes only and prints the DOFs; measured
values in ``ngsolve_peer.MEASURED_P2``): maxh 2.045 um gives 268,128 DOFs for probedyn's
264,588 (t/5 with gmsh's Delaunay, up to session 8; 265,278 at t/5.2 with HXT from session 9), and 1.35 um 509,886 (1.34 um jumps to 1,089,375), so the "540k" size is
matched at 509k with probedyn's t/6.35 (508,824; HXT from session 9: t/6.6, 509,802).

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
    ("VBSR (iparm[36]=-80), ordering 3 (parallel METIS), classic [default]", {}),
    ("CSR (iparm[36]=0) [previous default]", {"vbsr": 0}),
    ("VBSR, ordering 2 (METIS)", {"ordering": 2}),
    ("VBSR, ordering 0 (minimum degree)", {"ordering": 0}),
    ("CSR, two-level parallel factorisation (iparm[23]=1)", {"vbsr": 0, "factor_algorithm": 1}),
    ("VBSR, two-level parallel factorisation (iparm[23]=1)", {"factor_algorithm": 1}),
    ("VBSR, parallel forward/backward (iparm[24]=2)", {"parallel_solve": 2}),
    ("float32 factor (iparm[27]=1) + refinement in double", {"single": 1}),
    ("CSR, out-of-core (iparm[59]=2)", {"vbsr": 0, "ooc": 2}),
]
#: above 400k DOFs only these (each factorisation takes minutes on the shared machine)
LARGE_VARIANTS = ("CSR (iparm[36]=0) [previous default]", "float32 factor (iparm[27]=1) + refinement in double")


def clock() -> tuple[float, float]:
    """(wall, CPU of this process incl. all its threads) [s]."""
    return time.perf_counter(), time.process_time()


def since(c0: tuple[float, float]) -> tuple[float, float]:
    return time.perf_counter() - c0[0], time.process_time() - c0[1]


def rss() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def one(divisor: float, variants: bool = True, numpy_asm: bool = True, arpack: bool = True,
        overlap: bool = True, mixed: bool | None = None) -> dict:
    """Mesh + assemble + solve one tetrahedral size in this process (wall and CPU times).

    ``overlap`` (default, as ``ElasticModel.modes``): PARDISO's analysis of the free stiffness'
    pattern starts before the assembly and runs beside it; the extra measurements (compiled
    and numpy assembly again, ARPACK, PARDISO settings) come after the end-to-end phases.
    ``mixed`` (None: as ``ElasticModel.modes``, ``eigen.auto_method`` by the free DOFs): the
    end-to-end eigen-solve is ``mixed_eigsh`` on a single-precision factor (its analysis beside
    the assembly, as the double one); the double factor and the block solver then run after it,
    for the frequencies' difference and the extra measurements."""
    sys.path.insert(0, str(HERE))
    import _numpy_assembly as old

    from probedyn.fem import eigen as E
    from probedyn.fem import elasticity as el
    from probedyn.probes import get_probe

    probe = get_probe("cantilever")[0]
    values = probe.resolve({"element_size": T / divisor, "elements_through_thickness": 1, "element": "tet-p2"})
    out: dict = {"divisor": divisor, "load_start": os.getloadavg()[0]}
    c0 = clock()
    model = probe.build(values)
    out["mesh_s"], out["mesh_cpu_s"] = since(c0)
    out["elements"] = int(model.mesh.t.shape[1])
    c0 = clock()
    if mixed is None:
        mixed = E.auto_method(int(model.free_dofs.size), 0.0) == "mixed"
    fopts = {"single": 1} if mixed else None
    analysis = model.start_analysis(fopts) if overlap else None
    K_full, M_full = model.assemble()
    # includes the numba pattern and the first-call overhead (and starting the analysis)
    out["assemble_s"], out["assemble_cpu_s"] = since(c0)
    out["overlap"] = overlap
    c0 = clock()
    K, M = model.free_matrices()  # the clamped DOFs eliminated (part of every modal solve)
    out["free_s"], out["free_cpu_s"] = since(c0)
    out["dofs"] = int(K.shape[0])
    out["nnz_K"] = int(K.nnz)
    # ---- eigen-solvers on one factorisation ---------------------------------------------------
    c0 = clock()
    fac = E.factorize(K, analysis=analysis, options=fopts)
    out["factor_s"], out["factor_cpu_s"] = since(c0)
    out["factor_nnz"] = fac.info.get("factor_nnz")
    out["analysis_s"] = fac.info.get("analysis_s")
    out["numeric_s"] = fac.info.get("numeric_s")
    out["analysis_overlapped"] = fac.info.get("analysis_overlapped")
    out["method"] = "mixed" if mixed else "block"
    if mixed:
        try:
            c0 = clock()
            w, V, n_solved, info = E.mixed_eigsh(K, M, N_MODES, fac.approximate)
            out["block_s"], out["block_cpu_s"] = since(c0)
        finally:
            fac.release()
        out["mixed_f_hz"] = (np.sqrt(w) / (2 * np.pi)).tolist()
        out["mixed_vectors"], out["mixed_history"] = n_solved, info["history"]
        out["mixed_error_bound"] = float(np.max(info["error_bounds"]))
        fac = E.factorize(K)  # the double factor for the comparison and the extra measurements (not timed)
    # the double block solver: the end-to-end eigen-solve of the block path; after the mixed one,
    # only its comparison (up to session 7 its time replaced the mixed solver's in the end-to-end
    # total of the mixed path: block_s was overwritten; fixed in session 8)
    try:
        c0 = clock()
        w, V, n_solved, info = E.block_eigsh(K, M, N_MODES, 0.0, fac)
        t_block = since(c0)
    except BaseException:
        fac.release()
        raise
    if mixed:
        out["block_double_s"], out["block_double_cpu_s"] = t_block
        out["mixed_vs_block_max_rel"] = float(np.max(np.abs(np.array(out["mixed_f_hz"]) / (np.sqrt(w) / (2 * np.pi))
                                                            - 1)))
    else:
        out["block_s"], out["block_cpu_s"] = t_block
    out["probedyn_total_s"] = out["mesh_s"] + out["assemble_s"] + out["free_s"] + out["factor_s"] + out["block_s"]
    out["probedyn_total_cpu_s"] = (out["mesh_cpu_s"] + out["assemble_cpu_s"] + out["free_cpu_s"] + out["factor_cpu_s"]
                                   + out["block_cpu_s"])
    # ---- extra measurements (after the end-to-end phases) ---------------------------------------
    try:
        out["block_vectors"] = n_solved
        out["block_size"] = info["block"]
        out["block_history"] = info.get("history")
        out["block_error_bound"] = float(np.max(info["error_bounds"]))
        out["block_residual"] = float(np.max(info["residuals"]))
        f_block = np.sqrt(w) / (2 * np.pi)
        out["f_hz"] = f_block.tolist()
        n = K.shape[0]
        if arpack:
            import scipy.sparse.linalg as spla

            cnt = [0]

            def mv(x):
                cnt[0] += 1
                return fac.solve(x)

            k_int = N_MODES + max(3, N_MODES // 2)
            c0 = clock()
            wa, _ = spla.eigsh(K, k=k_int, M=M, sigma=0.0,
                               OPinv=spla.LinearOperator((n, n), matvec=mv, dtype=float), which="LM",
                               v0=np.random.default_rng(12345).standard_normal(n), ncv=max(2 * k_int + 1, 20))
            out["arpack_s"], out["arpack_cpu_s"] = since(c0)
            out["arpack_solves"] = cnt[0]
            f_arp = np.sort(np.sqrt(wa) / (2 * np.pi))[:N_MODES]
            out["block_vs_arpack_max_rel"] = float(np.max(np.abs(f_block / f_arp - 1)))
        B = np.random.default_rng(1).standard_normal((n, 15))
        c0 = clock()
        X_ref = fac.solve(B)
        out["block15_solve_s"], out["block15_solve_cpu_s"] = since(c0)
        c0 = clock()
        fac.solve(B[:, 0])
        out["single_solve_s"], out["single_solve_cpu_s"] = since(c0)
    finally:
        fac.release()
    out["peak_rss_gib_solve"] = rss()
    # ---- assembly: compiled again and the numpy path (after the factor is released: memory) ----
    t0 = time.perf_counter()
    Kc = el.assemble_stiffness(model.mesh, model.elem_region, model.materials, model.orientations,
                               basis=model.basis)
    t1 = time.perf_counter()
    Mc = el.assemble_mass(model.mesh, model.elem_density, basis=model.basis)
    t2 = time.perf_counter()
    out.update(compiled_K_s=t1 - t0, compiled_M_s=t2 - t1)
    if numpy_asm:
        t0 = time.perf_counter()
        Ko = old.assemble_stiffness_numpy(model.mesh, model.elem_region, model.materials, model.orientations)
        t1 = time.perf_counter()
        Mo = old.assemble_mass_numpy(model.mesh, model.elem_density)
        t2 = time.perf_counter()
        out.update(numpy_K_s=t1 - t0, numpy_M_s=t2 - t1,
                   K_max_rel_diff=float(abs(Ko - Kc).max() / abs(Ko).max()),
                   M_max_rel_diff=float(abs(Mo - Mc).max() / abs(Mo).max()))
        del Ko, Mo
    del Kc, Mc
    # ---- PARDISO settings ------------------------------------------------------------------------
    if variants:
        rows = []
        for name, opts in PARDISO_VARIANTS:
            if K.shape[0] > 400e3 and name not in LARGE_VARIANTS:
                continue
            if opts.get("ooc") and K.shape[0] > 100e3:
                rows.append({"name": name, "options": opts, "error": "skipped above 100k DOFs (16x slower at 12k)"})
                continue
            try:
                c0 = clock()
                f = E.factorize(K, options=opts)
                fw, fc = since(c0)
                c0 = clock()
                X = f.solve(B)
                ts, tsc = since(c0)
                err = float(np.abs(X - X_ref).max() / np.abs(X_ref).max())
                rows.append({"name": name, "options": opts, "factor_s": fw, "factor_cpu_s": fc,
                             "analysis_s": f.info["analysis_s"], "numeric_s": f.info["numeric_s"],
                             "block15_solve_s": ts, "block15_solve_cpu_s": tsc, "solution_rel_err": err,
                             "factor_nnz": f.info.get("factor_nnz"), "sweeps": f.info.get("refinement_sweeps")})
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
    import tempfile

    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    # a fresh cache for every run: a repeated size must mesh again, not read the previous run's mesh
    env["PROBEDYN_CACHE"] = tempfile.mkdtemp(prefix="probedyn-bench-")
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


def checkpoint(path: str | None, data: dict) -> None:
    if path:
        from probedyn.core.io import write_json

        write_json(str(Path(path).with_suffix(".json")), data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--no-variants", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--lean", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--hex", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--no-overlap", action="store_true",
                    help="PARDISO's analysis after the assembly (the session-5 order), not beside it")
    ap.add_argument("--mixed", action="store_true",
                    help="end to end with a single-precision factor and fem.eigen.mixed_eigsh at every size "
                         "(default: as ElasticModel.modes, from eigen.MIXED_MIN_DOFS free DOFs)")
    ap.add_argument("--delaunay", action="store_true",
                    help="gmsh's Delaunay 3D mesher at every size (up to session 8; from session 9 meshes above "
                         "meshes._gmsh.HXT_MIN_TETS predicted tetrahedra use HXT): the mesher A/B, e.g. with "
                         "--match 5:2.045e-6")
    ap.add_argument("--double", action="store_true",
                    help="end to end with the double factor and the block solver at every size (the session-6 path)")
    ap.add_argument("--quick", action="store_true", help="two small sizes only")
    ap.add_argument("--sizes", default=None, help="divisors n of h = t/n (default 1.5,2,3,4,5,6.5)")
    ap.add_argument("--match", default=None,
                    help="divisor:maxh pairs (e.g. 5:2.045e-6,6.35:1.35e-6): the Netgen maxh matching each size's "
                         "DOFs (find it with ngsolve_peer.py --count); default: ngsolve_peer.maxh_for(DOFs)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per size and code (fresh processes; min taken)")
    ap.add_argument("--variants-at", default=None,
                    help="divisors at which the PARDISO settings are measured (default: every size)")
    ap.add_argument("--no-accuracy", action="store_true", help="skip part 2 (accuracy per second)")
    ap.add_argument("--ngsolve", default=None, help="python interpreter with ngsolve (peer column)")
    ap.add_argument("--out", default=None, help="also write the table to this file (and .json beside it)")
    a = ap.parse_args()
    if a.delaunay:
        import probedyn.meshes._gmsh as gm

        gm.HXT_MIN_TETS = float("inf")
    if a.one is not None:
        print(json.dumps(one(a.one, not a.no_variants, numpy_asm=not a.lean, arpack=not a.lean,
                             overlap=not a.no_overlap, mixed=True if a.mixed else (False if a.double else None))))
        return
    if a.hex:
        print(json.dumps(hex_default()))
        return

    import tempfile

    os.environ.setdefault("PROBEDYN_CACHE", tempfile.mkdtemp(prefix="probedyn-bench-"))
    match = dict((float(k), v) for k, v in (x.split(":") for x in a.match.split(","))) if a.match else {}
    divisors = [1.5, 2.0] if a.quick else (
        [float(x) for x in a.sizes.split(",")] if a.sizes else (sorted(match) or [1.5, 2, 3, 4, 5, 6.5]))
    variants_at = divisors if a.variants_at is None else [float(x) for x in a.variants_at.split(",")]
    lines: list[str] = []
    data: dict = {"load_start": os.getloadavg(), "cpus": os.cpu_count()}

    def say(s: str = "") -> None:
        print(s, flush=True)
        lines.append(s)

    say(f"probedyn benchmarks/modal.py — first {N_MODES} modes of the default cantilever (300 x 30 x 10 um, silicon)")
    say(f"machine: {os.cpu_count()} logical CPUs, SHARED with other jobs (load average at start "
        f"{os.getloadavg()[0]:.1f}); each run in a fresh process, {a.repeat} run(s) per size and code, min taken; "
        f"times in s (wall, and CPU of the process = all its threads), memory = peak RSS")
    rows = []
    for d in divisors:
        runs, peers = [], []
        for rep in range(a.repeat):
            first = rep == 0
            args = ["--one", str(d)] + ([] if (first and d in variants_at) else ["--no-variants"])
            r = run_sub(args + ([] if first else ["--lean"]) + (["--no-overlap"] if a.no_overlap else [])
                        + (["--delaunay"] if a.delaunay else [])
                        + (["--mixed"] if a.mixed else []) + (["--double"] if a.double else []))
            runs.append(r)
            data.setdefault("runs", []).append(r)
            checkpoint(a.out, data)
            if a.ngsolve:
                gargs = (["--maxh", str(match[d])] if d in match else ["--dofs", str(r["dofs"])])
                gargs += ["--pinvit"] if (r["dofs"] < 100e3 and first) else []  # PINVIT: slow
                g = run_sub(gargs, a.ngsolve, str(HERE / "ngsolve_peer.py"))
                peers.append(g)
                data.setdefault("peer_runs", []).append(g)
                checkpoint(a.out, data)
        r = dict(runs[0])
        for k in ("probedyn_total_s", "probedyn_total_cpu_s"):
            r[k + "_runs"] = [x[k] for x in runs]
            r[k] = min(r[k + "_runs"])
        if peers:
            g = dict(peers[0])
            for k in ("total_s", "total_cpu_s"):
                g[k + "_runs"] = [x[k] for x in peers]
                g[k] = min(g[k + "_runs"])
            r["ngsolve"] = g
        rows.append(r)
    data["rows"] = rows
    checkpoint(a.out, data)
    say("")
    say("1. P2 tetrahedra, one run per size (the first): phases, assembly compiled vs numpy, block Lanczos vs ARPACK")
    say(f"{'h':>7} {'DOFs':>8} {'mesh':>6} {'asm cmp':>8} {'asm np':>7} {'ratio':>6} {'factor':>7} {'ARPACK':>7} "
        f"{'(solves)':>8} {'block':>6} {'(vecs)':>6} {'ratio':>6} {'|df/f|':>8} {'GiB':>5}")
    for r in rows:
        asm_c = r["compiled_K_s"] + r["compiled_M_s"]
        asm_n = r["numpy_K_s"] + r["numpy_M_s"]
        say(f"{'t/' + format(r['divisor'], 'g'):>7} {r['dofs']:>8d} {r['mesh_s']:>6.1f} {asm_c:>8.2f} {asm_n:>7.2f} "
            f"{asm_n / asm_c:>6.1f} {r['factor_s']:>7.2f} {r['arpack_s']:>7.2f} {r['arpack_solves']:>8d} "
            f"{r['block_s']:>6.2f} {r['block_vectors']:>6d} {r['arpack_s'] / r['block_s']:>6.2f} "
            f"{r['block_vs_arpack_max_rel']:>8.1e} {r['peak_rss_gib']:>5.2f}")
        say(f"{'':>7} CPU s: mesh {r['mesh_cpu_s']:.1f}, assembly {r['assemble_cpu_s']:.1f}, free DOFs "
            f"{r['free_cpu_s']:.2f}, factor {r['factor_cpu_s']:.1f}, {r.get('method', 'block')} {r['block_cpu_s']:.1f} (b = {r['block_size']}), "
            f"ARPACK {r['arpack_cpu_s']:.1f}")
        if r.get("numeric_s") is not None:
            say(f"{'':>7} PARDISO: analysis {r['analysis_s']:.2f} s "
                f"({'beside the assembly' if r.get('analysis_overlapped') else 'after the assembly'}), "
                f"numeric {r['numeric_s']:.2f} s, factor nnz {r['factor_nnz']} (VBSR units)")
        say(f"{'':>7} block solver: largest eigenvalue error bound {r['block_error_bound']:.1e}, residual "
            f"{r['block_residual']:.1e}; (vectors, bound) per Rayleigh-Ritz step: "
            + ", ".join(f"({h[0]}, {h[1]:.0e})" for h in r["block_history"]))
        if r.get("method") == "mixed":
            say(f"{'':>7} end to end with the float32 factor + mixed_eigsh: {r['mixed_vectors']} vectors, bound "
                f"{r['mixed_error_bound']:.1e}, frequencies vs the double block solver {r['mixed_vs_block_max_rel']:.1e} "
                f"(double block solver afterwards: {r['block_double_s']:.1f}/{r['block_double_cpu_s']:.1f} s)")
    say("")
    say("PARDISO settings (same K; factorisation, one 15-column block solve; solution error vs the default; "
        "wall / CPU s):")
    for r in rows:
        if not r.get("pardiso"):
            continue
        say(f"  {r['dofs']} DOFs:")
        for v in r["pardiso"]:
            if "error" in v:
                say(f"    {v['name']:<62} error: {v['error']}")
            else:
                sw = f" ({v['sweeps']} refinement sweeps)" if v.get("sweeps") else ""
                say(f"    {v['name']:<62} factor {v['factor_s']:6.1f}/{v['factor_cpu_s']:5.1f} (analysis "
                    f"{v['analysis_s']:5.1f}) solve15 {v['block15_solve_s']:6.2f}/{v['block15_solve_cpu_s']:5.2f}  "
                    f"err {v['solution_rel_err']:.1e}{sw}")
    if a.ngsolve:
        say("")
        say("NGSolve peer (same geometry, P2, matched DOFs; mesh + assembly + factorisation + 10 modes; "
            "min of the runs, wall and CPU s):")
        for r in rows:
            g = r["ngsolve"]
            pin = f", PINVIT {g['pinvit_s']:.1f} s (|df/f| {g['pinvit_max_rel_diff']:.0e})" if "pinvit_s" in g else ""
            fdiff = float(np.max(np.abs(np.array(g["f_hz"]) / np.array(r["f_hz"]) - 1)))
            say(f"  probedyn {r['dofs']} DOFs vs NGSolve {g['dofs']} DOFs (maxh {g['maxh']:.4g} m; DOFs "
                f"{100 * (g['dofs'] / r['dofs'] - 1):+.1f} %; max |f_ng/f_pd - 1| {fdiff:.1e})")
            say(f"    NGSolve  mesh {g['mesh_s']:.1f}/{g['mesh_cpu_s']:.1f}, assembly {g['assemble_s']:.1f}/"
                f"{g['assemble_cpu_s']:.1f}, Cholesky {g['factor_s']:.1f}/{g['factor_cpu_s']:.1f}, ARPACK "
                f"{g['arpack_s']:.1f}/{g['arpack_cpu_s']:.1f} ({g['n_opinv']} solves) -> total runs "
                f"{', '.join(format(x, '.1f') for x in g['total_s_runs'])} s wall, "
                f"{', '.join(format(x, '.1f') for x in g['total_cpu_s_runs'])} s CPU{pin}")
            say(f"    probedyn mesh {r['mesh_s']:.1f}/{r['mesh_cpu_s']:.1f}, assembly {r['assemble_s']:.1f}/"
                f"{r['assemble_cpu_s']:.1f}, free DOFs {r['free_s']:.1f}/{r['free_cpu_s']:.1f}, PARDISO {r['factor_s']:.1f}/{r['factor_cpu_s']:.1f}, "
                f"{r.get('method', 'block')} "
                f"{r['block_s']:.1f}/{r['block_cpu_s']:.1f} -> total runs "
                f"{', '.join(format(x, '.1f') for x in r['probedyn_total_s_runs'])} s wall, "
                f"{', '.join(format(x, '.1f') for x in r['probedyn_total_cpu_s_runs'])} s CPU")
            say(f"    ratio probedyn/NGSolve (min/min): wall {r['probedyn_total_s'] / g['total_s']:.2f}, CPU "
                f"{r['probedyn_total_cpu_s'] / g['total_cpu_s']:.2f}")
    if not a.no_accuracy:
        say("")
        say("2. accuracy per second: all 10 frequencies within 0.1 % of converged")
        h = run_sub(["--hex"])
        data["hex_default"] = h
        say(f"  probedyn default (hex-s2, graded): {h['dofs']} DOFs, {h['total_s']:.2f} s end to end, max error "
            f"{100 * h['max_rel_err']:.3f} %")
        for r in rows:
            err = float(np.max(np.abs(np.array(r["f_hz"]) / np.array(CONVERGED_HZ) - 1)))
            r["max_rel_err"] = err
            say(f"  P2 tetrahedra t/{r['divisor']:g}: {r['dofs']} DOFs, {r['probedyn_total_s']:.1f} s, max error "
                f"{100 * err:.3f} %")
        if a.ngsolve:
            best = ngsolve_accuracy(a.ngsolve)
            data["ngsolve_accuracy"] = best
            if best:
                say(f"  NGSolve cheapest within 0.1 %: P{best['order']}, maxh {best['maxh']:.2g} m, {best['dofs']} "
                    f"DOFs, {best['total_s']:.1f} s (max error {100 * best['max_rel_err']:.3f} %) -> "
                    f"probedyn/NGSolve {h['total_s'] / best['total_s']:.2f}")
    data["load_end"] = os.getloadavg()
    say("")
    say(f"load average at the end {os.getloadavg()[0]:.1f}")
    if a.out:
        from probedyn.core.io import write_text

        write_text(a.out, "\n".join(lines) + "\n")
        checkpoint(a.out, data)


if __name__ == "__main__":
    main()
