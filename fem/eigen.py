"""Sparse symmetric factorisation and shift-invert eigen-solution ``K phi = omega^2 M phi``.

The shift-invert operator ``(K - sigma M)^-1`` is factorised once with MKL PARDISO (``mtype =
2`` real SPD when ``K - sigma M`` is positive definite, i.e. for ``sigma`` below the lowest
eigenvalue, else ``mtype = -2`` real symmetric indefinite) and used by one of two eigen-solvers:

* ``method="block"`` (default below :data:`MIXED_MIN_DOFS`): a **block shift-invert Lanczos** (block Krylov) method in the
  M-inner product, :func:`block_eigsh`.  It applies the factorisation to a block of ``b``
  right-hand sides at once (PARDISO streams the factor from memory once per block, so a
  block of 6 costs about 3.5 single solves), builds the Krylov space ``[V, OP V, OP^2 V, ...]``
  (``OP = (K - sigma M)^-1 M``), M-orthonormalised block by block (two passes of classical
  Gram-Schmidt), takes the Ritz pairs of OP on it after every block solve (no product with K:
  the projections are built from the kept ``M Q``, ``OP Q`` and ``M OP Q``) and stops as soon
  as every wanted pair's eigenvalue error bound (Kato-Temple: ``(rho/theta)^2 theta/gap``) is
  below :data:`ETOL` and its eigenvector angle bound ``rho/gap`` below :data:`VTOL` (a caller
  that needs the vectors at the round-off floor, the Ritz reduction, passes ``tol=TO_FLOOR``);
  after ``steps + 1`` blocks it restarts from the best Ritz vectors.
* ``method="arpack"``: ARPACK (``scipy.sparse.linalg.eigsh(..., OPinv=...)``) in shift-invert
  mode, one right-hand side per step (the reference; the benchmark compares the two).
* ``method="mixed"`` (``"auto"``, the default, chooses it from :data:`MIXED_MIN_DOFS` free DOFs
  with sigma = 0 and PARDISO): a single-precision factor of K (half the
  factor's memory traffic) used only as the preconditioner of a block Davidson method whose
  Rayleigh-Ritz projections and residuals use the double K and M, :func:`mixed_eigsh`; same
  stopping bounds for the pencil (``||r||_{M^-1}`` by CG on M); falls back to the double factor
  and the block solver if it does not converge.  Measured at 265k DOFs in docs/fem.md
  ("Session 7"): 60 instead of 48 vectors, float32 numeric factorisation ~0.65x the double one.

Without pypardiso the fallback is scipy's SuperLU (``splu``), which is two orders of magnitude
slower for 3D problems (benchmarks/modal.py measures both).

PARDISO is called through ctypes directly (the MKL library handle of pypardiso): the 1-based
int32 index arrays of the upper triangle are made once per factorisation, not per solve (a
pypardiso ``solve`` converts them every call: ~40 ms per solve at 265k DOFs), and there is no
matrix copy or hash.  Settings (:data:`PARDISO_OPTIONS`, each measured in benchmarks/modal.py at
265k and 540k DOFs, docs/fem.md): ordering ``iparm[1]`` (0 minimum degree, 2 METIS, 3 parallel
METIS), ``iparm[23]`` parallel factorisation algorithm (0 classic, 1 two-level), ``iparm[24]``
forward/backward substitution (0 sequential, 2 parallel), ``iparm[27]`` single-precision
factors (float32 matrix and factor; each solve then refined against the double matrix in
double precision until its backward error is at the double level, :func:`_pardiso`),
``iparm[36]`` matrix format (0 CSR, -80 VBSR: rows of >= 80 % equal pattern merged into
blocks, the default), ``iparm[59]`` in-core (0) or out-of-core (2).

Factorisation reuse: inside ``with reuse_factorizations():`` a matrix already factorised in that
block (same shape, pattern and values: a BLAKE2 digest of its CSR arrays) is not factorised
again; studies that change only the mass (holder density) or repeat a model use it.

Threads: on few shared cores, OpenBLAS's spinning threads (ARPACK's dense steps use it)
compete with MKL's; ``OPENBLAS_NUM_THREADS=1`` set before numpy is imported made the ARPACK
loop 3-5x faster at 23k DOFs on the 2-core test machine (probedyn/__init__.py sets it).
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from probedyn.core.errors import SolverError
from probedyn.fem.kernels import csr_matmat_rows as _csr_matmat_rows
from probedyn.fem.kernels import upper_triangle as _upper_triangle

SOLVERS = ("auto", "pardiso", "superlu")
METHODS = ("auto", "block", "arpack", "mixed")
#: method="auto": the mixed-precision solver from this many DOFs (sigma = 0, PARDISO), else the block
#: solver; at 265k DOFs the float32 factor saves ~6 of ~34 CPU s end to end (docs/fem.md "Session 7"),
#: below ~100k the factorisation is too small a share for the extra vectors to pay
MIXED_MIN_DOFS = 150_000
#: block solver: accept a stagnating shift-invert residual below this (round-off floor reached)
FLOOR_OK = 1e-5
#: block solver: bound on the relative eigenvalue error of every returned pair (block_eigsh)
ETOL = 1e-11
#: block solver: bound on the angle error of every returned eigenvector (block_eigsh)
VTOL = 1e-6
#: a residual tolerance below the round-off floor: ``tol=TO_FLOOR`` iterates until the residuals stop falling
TO_FLOOR = 1e-12
#: block solver: projected residuals are trusted while every bound is above this (their floor: ~1e-8 theta_1)
PROJECTED_OK = 1e-6

#: PARDISO settings (module docstring); ``factorize(..., options=...)`` overrides per call
PARDISO_OPTIONS: dict[str, int] = {
    "ordering": 3,        # iparm[1]: parallel (OpenMP) nested-dissection (METIS)
    "factor_algorithm": 0,  # iparm[23]: classic parallel factorisation
    "parallel_solve": 0,  # iparm[24]: sequential forward/backward substitution
    "single": 0,          # iparm[27]: 1 = single-precision factors
    "refinement": 0,      # iparm[7]: max iterative refinement steps (0 = automatic)
    "ooc": 0,             # iparm[59]: 0 in-core, 2 out-of-core
    "vbsr": -80,          # iparm[36]: 0 CSR; -t = variable block rows (VBSR): rows of >= t % equal pattern merged
}


def _import_pypardiso():
    """``import pypardiso`` with MKL's runtime library named for it where it lies in the environment's own
    ``lib`` (pip's ``mkl`` wheel): without ``PYPARDISO_MKL_RT``, and where ``ctypes.util.find_library`` does
    not see the venv, pypardiso globs the whole environment recursively for it, once at import and once per
    solver object (~0.2-0.35 s each, measured in ``benchmarks/diagnose_modal.py``'s profile)."""
    import glob
    import os
    import sys

    if "PYPARDISO_MKL_RT" not in os.environ:
        for pattern in ("lib/libmkl_rt.so*", "lib64/libmkl_rt.so*", "lib/libmkl_rt*.dylib", "Library/bin/mkl_rt*.dll"):
            hits = sorted(glob.glob(os.path.join(sys.prefix, pattern)), key=len)
            if hits:
                os.environ["PYPARDISO_MKL_RT"] = hits[0]
                break
    import pypardiso

    return pypardiso


def have_pardiso() -> bool:
    # pypardiso is imported where it is used, not at module level: it is the optional fast
    # backend (SuperLU is the fallback when MKL is missing) and importing it loads MKL (~0.6 s).
    try:
        _import_pypardiso()
    except Exception:
        return False
    return True


@dataclass
class Factorization:
    """A factorised sparse symmetric matrix: ``solve(b)`` for b of shape (n,) or (n, k)."""

    solve: Callable[[np.ndarray], np.ndarray]
    backend: str
    seconds: float
    release: Callable[[], None] = field(default=lambda: None)
    info: dict[str, Any] = field(default_factory=dict)
    #: single-precision factors only: the float32 solve WITHOUT refinement (an approximate
    #: inverse, relative error ~0.1 at 265k DOFs), the preconditioner of :func:`mixed_eigsh`
    approximate: Callable[[np.ndarray], np.ndarray] | None = None


# ---------------------------------------------------------------------------------------------
# factorisation reuse
# ---------------------------------------------------------------------------------------------

_REUSE: list[dict] = []  # stack of {digest: Factorization} while reuse_factorizations() is active


def matrix_digest(A: sp.csr_matrix) -> str:
    """BLAKE2 digest of a CSR matrix (shape, pattern and values)."""
    h = hashlib.blake2b(digest_size=20)
    h.update(np.asarray(A.shape, dtype=np.int64).tobytes())
    for arr in (A.indptr, A.indices, A.data):
        h.update(np.ascontiguousarray(arr).view(np.uint8))
    return h.hexdigest()


@contextlib.contextmanager
def reuse_factorizations() -> Iterator[dict]:
    """Within this block, a matrix factorised once (same shape, pattern and values) is not
    factorised again; all its factorisations are released at the end.  Yields the cache
    (digest -> Factorization; ``Factorization.info["reused"]`` counts the reuses)."""
    cache: dict = {}
    _REUSE.append(cache)
    try:
        yield cache
    finally:
        _REUSE.remove(cache)
        for f in cache.values():
            f.info.get("_release", lambda: None)()


def factorize(A: sp.spmatrix, spd: bool = True, solver: str = "auto", options: dict | None = None,
              analysis: Analysis | None = None) -> Factorization:
    """Factorise symmetric ``A`` with PARDISO (``solver='pardiso'`` or 'auto' when available)
    or SuperLU.  ``spd`` selects PARDISO's SPD type 2 (else symmetric indefinite -2); if the
    SPD factorisation fails (a zero or negative pivot), the indefinite type is tried.
    ``options``: PARDISO settings overriding :data:`PARDISO_OPTIONS`.  ``analysis``: an
    :class:`Analysis` of ``A``'s predicted pattern started earlier (used if it fits; always
    released)."""
    try:
        return _factorize(A, spd, solver, options, analysis)
    finally:
        if analysis is not None:
            analysis.release()


def _factorize(A, spd, solver, options, analysis) -> Factorization:
    if solver not in SOLVERS:
        raise SolverError(f"unknown linear solver '{solver}' (known: {', '.join(SOLVERS)})")
    A = sp.csr_matrix(A, dtype=float)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
        A.sort_indices()
    key = None
    if _REUSE:
        key = (matrix_digest(A), bool(spd), solver, tuple(sorted((options or {}).items())))
        hit = _REUSE[-1].get(key)
        if hit is not None:
            hit.info["reused"] = hit.info.get("reused", 0) + 1
            return Factorization(hit.solve, hit.backend, 0.0, lambda: None, hit.info, hit.approximate)
    t0 = time.perf_counter()
    if solver in ("auto", "pardiso") and have_pardiso():
        last: Exception | None = None
        for mtype in ((2, -2) if spd else (-2,)):
            try:
                f = _pardiso(A, mtype, {**PARDISO_OPTIONS, **(options or {})}, analysis if mtype == 2 else None)
                f.seconds = time.perf_counter() - t0
                break
            except Exception as exc:  # zero pivot in SPD mode, PARDISO error codes
                last = exc
        else:
            raise SolverError(f"PARDISO factorisation failed: {str(last).splitlines()[0]}")
    elif solver == "pardiso":
        raise SolverError("pypardiso is not installed (pip install pypardiso), use solver='superlu'")
    else:
        try:
            lu = spla.splu(A.tocsc())
        except RuntimeError as exc:
            raise SolverError(f"SuperLU factorisation failed ({exc}): the matrix is singular; is the model clamped?") from None
        f = Factorization(lu.solve, "superlu", time.perf_counter() - t0)
    if key is not None:
        f.info["_release"] = f.release
        _REUSE[-1][key] = f
        return Factorization(f.solve, f.backend, f.seconds, lambda: None, f.info, f.approximate)
    return f


# ---------------------------------------------------------------------------------------------
# PARDISO through ctypes
# ---------------------------------------------------------------------------------------------

_MKL: list = []


def _mkl_pardiso():
    """The ``pardiso`` entry of MKL (found once by pypardiso, whose library search costs ~0.7 s)."""
    if not _MKL:
        _MKL.append(_import_pypardiso().PyPardisoSolver(mtype=2)._mkl_pardiso)
    return _MKL[0]


class PardisoError(RuntimeError):
    pass


_PARDISO_ERRORS = {-1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
                   -4: "zero pivot, numerical factorisation or iterative refinement problem",
                   -5: "unclassified (internal) error", -6: "reordering failed", -7: "diagonal matrix is singular",
                   -8: "32-bit integer overflow", -9: "not enough memory for out-of-core",
                   -10: "error opening out-of-core files", -11: "read/write error with out-of-core files"}


class _Pardiso:
    """One PARDISO handle with its matrix (upper triangle, 1-based int32 indices kept)."""

    def __init__(self, upper: tuple[np.ndarray, np.ndarray, np.ndarray], mtype: int, opts: dict) -> None:
        self.fn = _mkl_pardiso()
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        ip = self.iparm
        ip[0] = 1  # user-supplied values
        ip[1] = int(opts["ordering"])
        ip[7] = int(opts["refinement"])
        ip[9] = 13 if mtype == 11 else 8  # pivot perturbation 1e-8 (indefinite only)
        ip[10] = 0
        ip[12] = 0
        ip[17] = -1  # report nnz of the factors in iparm[17]
        ip[18] = -1  # report factorisation MFLOPS in iparm[18]
        ip[23] = int(opts["factor_algorithm"])
        ip[24] = int(opts["parallel_solve"])
        ip[27] = int(opts["single"])
        ip[34] = 0  # one-based indexing
        ip[36] = int(opts.get("vbsr", 0))
        ip[59] = int(opts["ooc"])
        self.mtype = int(mtype)
        self.ia, self.ja, data = upper  # 1-based int32 CSR of the upper triangle
        self.n = self.ia.size - 1
        self.data = np.ascontiguousarray(data, dtype=np.float64)
        if opts["single"]:
            # PARDISO's mixed-precision mode reads the matrix values in single precision
            self.data32 = self.data.astype(np.float32)
        self.perm = np.zeros(0, dtype=np.int32)
        self.single = bool(opts["single"])

    def call(self, phase: int, b: np.ndarray | None = None) -> np.ndarray | None:
        nrhs = 1 if b is None or b.ndim == 1 else b.shape[1]
        if b is None:
            b = np.zeros(self.n)
            x = np.zeros(self.n)
        else:
            x = np.zeros_like(b, order="F")
        err = ctypes.c_int32(0)
        i32 = ctypes.POINTER(ctypes.c_int32)
        dp = ctypes.c_void_p
        a = self.data32 if self.single else self.data
        if self.single and b.dtype != np.float32:
            b32 = np.asfortranarray(b, dtype=np.float32)
            x32 = np.zeros_like(b32, order="F")
        else:
            b32, x32 = b, x
        self.fn(self.pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(ctypes.c_int32(1)),
                ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(self.mtype)),
                ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(self.n)),
                a.ctypes.data_as(dp), self.ia.ctypes.data_as(i32), self.ja.ctypes.data_as(i32),
                self.perm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(nrhs)),
                self.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(0)),
                b32.ctypes.data_as(dp), x32.ctypes.data_as(dp), ctypes.byref(err))
        if err.value != 0:
            raise PardisoError(f"PARDISO error {err.value}: {_PARDISO_ERRORS.get(err.value, 'unknown')}")
        if x32 is not x:
            x[...] = x32
        return x

    def free(self) -> None:
        if self.pt.any():
            try:
                self.call(-1)
            except PardisoError:
                pass
            self.pt[:] = 0


class Analysis:
    """PARDISO's analysis (phase 11: fill-reducing ordering and symbolic factorisation) of a
    pattern known before the matrix values, run in a background thread.

    Phase 11 of an SPD matrix needs only the pattern (``ia``, ``ja``); a model knows the pattern
    of its free stiffness from the mesh (:func:`probedyn.fem.kernels.free_upper_pattern`)
    before the element kernels compute a value, so the ordering runs while the matrices are
    assembled (the ctypes call releases the GIL).  :func:`factorize` (``analysis=...``) takes the
    analysed handle only if the matrix's upper triangle has exactly this pattern (else, e.g.
    after springs added entries, it is released and the matrix analysed as usual): the
    factorisation is the one the plain path computes (single precision included: analysed with
    ``options={"single": 1}`` the handle fits a single-precision factorisation)."""

    def __init__(self, ia: np.ndarray, ja: np.ndarray, options: dict | None = None) -> None:
        self.opts = {**PARDISO_OPTIONS, **(options or {})}
        # the pattern compared in take() is a copy: the arrays handed to PARDISO are not read while
        # phase 11 runs (MKL was seen to hold them 0-based mid-call: a reader got ia - 1)
        self.ia, self.ja = ia.copy(), ja.copy()
        self.ps: _Pardiso | None = _Pardiso((ia, ja, np.zeros(ja.size)), 2, self.opts)
        self.error: Exception | None = None
        self.seconds = float("nan")
        self._thread = threading.Thread(target=self._run, name="pardiso-analysis", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        t0 = time.perf_counter()
        try:
            self.ps.call(11)
        except Exception as exc:  # reported by take(): the matrix is then analysed as usual
            self.error = exc
        self.seconds = time.perf_counter() - t0

    def take(self, upper: tuple[np.ndarray, np.ndarray, np.ndarray], mtype: int, opts: dict) -> "_Pardiso | None":
        """The analysed handle holding ``upper``'s values if it fits (same pattern, SPD type,
        settings), else None (and the handle is released).  Waits for the analysis."""
        t0 = time.perf_counter()
        self._thread.join()
        self.waited = time.perf_counter() - t0
        ps, self.ps = self.ps, None
        if ps is None:
            return None
        ia, ja, data = upper
        if (self.error is None and mtype == 2 and opts == self.opts and ia.size == self.ia.size
                and ja.size == self.ja.size and np.array_equal(ia, self.ia) and np.array_equal(ja, self.ja)):
            ps.data = np.ascontiguousarray(data, dtype=np.float64)
            if ps.single:
                ps.data32 = ps.data.astype(np.float32)
            return ps
        ps.free()
        return None

    def release(self) -> None:
        """Free the handle if :func:`factorize` did not take it."""
        self._thread.join()
        if self.ps is not None:
            self.ps.free()
            self.ps = None


def _pardiso(A: sp.csr_matrix, mtype: int, opts: dict, analysis: Analysis | None = None) -> Factorization:
    """PARDISO factorisation of ``A``.  With ``opts["single"]`` the factor is single precision
    (``iparm[27] = 1``: matrix, right-hand sides and factor all float32; symmetric diagonal
    scaling made it worse for hex-s2, 5.6 vs 0.16 error with SuperLU float32, so none), and every
    solve is refined in double precision: ``x += S^-1 (b - A x)``
    until the normwise backward error ``||b - A x||_1 / (||A||_1 ||x||_1)`` is below 32 eps64 (a
    double-precision solve), stops falling by 2x for three sweeps (the round-off floor) or after
    ``opts["refinement"]`` sweeps (default 40).  A
    float32 solve alone is NOT accurate for these matrices: cond(K) ~ 1.5e9 already at 12k DOFs
    (cantilever, P2), so cond * eps32 >> 1 and its error is ~0.1-0.4 (SuperLU in float32 gives the
    same; benchmarks/modal.py); each refinement sweep contracts the error by about that factor
    on small models (7.5k-12k DOFs: 10-15 sweeps) and the refinement stalls (SolverError) on
    the 265k and 509k P2 cantilevers (benchmarks/results/modal-s4.txt)."""
    single = bool(opts["single"])
    # A is canonical (sorted rows, no duplicates: factorize); its upper triangle in one compiled pass
    if A.nnz >= 2**31 - 1:
        raise SolverError(f"matrix too large for PARDISO's 32-bit indices ({A.nnz} non-zeros)")
    upper = _upper_triangle(A.indptr, A.indices, A.data)
    ps = analysis.take(upper, mtype, opts) if analysis is not None else None
    t0 = time.perf_counter()
    if ps is None:
        ps = _Pardiso(upper, mtype, opts)
        ps.call(11)
        analysis_s = time.perf_counter() - t0
    else:  # analysed in the background while the matrix was assembled
        analysis_s = analysis.seconds
    t1 = time.perf_counter()
    try:
        ps.call(22)
    except PardisoError:
        ps.free()
        raise
    t2 = time.perf_counter()
    if mtype == 2 and ps.iparm[29] != 0:
        ps.free()
        raise SolverError("zero or negative pivot in SPD factorisation")
    n = A.shape[0]
    norm_A = float(abs(A).sum(axis=0).max()) if single else 1.0
    info = {"analysis_s": analysis_s, "numeric_s": t2 - t1, "factor_nnz": int(ps.iparm[17]),
            "mflops": int(ps.iparm[18]), "options": dict(opts),
            "analysis_overlapped": t1 - t0 < analysis_s}

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        shape = b.shape
        # PARDISO reads a block of right-hand sides column by column: Fortran order
        bb = np.asfortranarray(b.reshape(n, -1))
        if not single:
            x = ps.call(33, bb)
            return np.ascontiguousarray(x).reshape(shape)
        x = ps.call(33, bb)
        max_sweeps = int(opts["refinement"]) or 40
        sweeps, best, stall = 0, np.inf, 0
        while sweeps < max_sweeps:
            r = bb - A @ x
            # normwise backward error of x: at a small multiple of eps64 it is a double-precision solve
            be = float(np.max(np.abs(r).sum(axis=0) / (norm_A * np.maximum(np.abs(x).sum(axis=0), 1e-300))))
            if be <= 32 * np.finfo(float).eps:
                break
            stall = stall + 1 if be > 0.5 * best else 0
            if stall >= 3:  # round-off floor of the double residual
                break
            best = min(best, be)
            x += ps.call(33, np.asfortranarray(r))
            sweeps += 1
        info["refinement_sweeps"] = sweeps
        info["backward_error"] = be
        if be > 1e3 * np.finfo(float).eps and sweeps < max_sweeps:
            # stalled far from double precision: the float32 factor is too inaccurate (cond * eps32 >~ 1)
            raise SolverError(f"mixed-precision refinement stalled at backward error {be:.1e} after {sweeps} "
                              "sweeps: the single-precision factor is too inaccurate for this matrix (use single=0)")
        return np.ascontiguousarray(x).reshape(shape)

    def approximate(b: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(ps.call(33, np.asfortranarray(np.asarray(b, dtype=float).reshape(n, -1)))
                                    ).reshape(np.shape(b))

    return Factorization(solve, f"pardiso(mtype={mtype}{', single+refinement' if single else ''})", 0.0, ps.free,
                         info, approximate if single else None)


# ---------------------------------------------------------------------------------------------
# eigen-solvers
# ---------------------------------------------------------------------------------------------

@dataclass
class EigenResult:
    eigenvalues: np.ndarray  # omega^2 [rad^2/s^2], ascending
    vectors: np.ndarray  # (n, k), M-orthonormal
    backend: str
    factor_s: float
    solve_s: float
    n_opinv: int
    method: str = "arpack"
    info: dict[str, Any] = field(default_factory=dict)


def _m_orthonormalize(W: np.ndarray, MW: np.ndarray, drop: float = 1e-10,
                      max_cols: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """M-orthonormal basis of span(W) given ``MW = M W`` (directions whose relative Gram
    eigenvalue is below ``drop`` are dropped); returns (W', M W')."""
    if W.shape[1] == 0:
        return W, MW
    G = W.T @ MW
    G = 0.5 * (G + G.T)
    g, V = np.linalg.eigh(G)
    keep = g > drop * max(float(g.max()), 1e-300)
    if max_cols is not None and keep.sum() > max_cols:  # the max_cols strongest directions
        keep &= g >= np.sort(g)[-max_cols]
    C = V[:, keep] / np.sqrt(g[keep])
    return W @ C, MW @ C


def block_eigsh(K: sp.spmatrix, M: sp.spmatrix, n_modes: int, sigma: float, fac: Factorization,
                block: int | None = None, steps: int | None = None, rtol: float | None = None,
                etol: float = ETOL, vtol: float = VTOL, max_cycles: int = 10,
                seed: int = 12345) -> tuple[np.ndarray, np.ndarray, int, dict]:
    """The ``n_modes`` eigenpairs of ``K x = lambda M x`` nearest ``sigma`` by block shift-invert
    Lanczos with ``fac`` = factorisation of ``K - sigma M`` (module docstring).

    Method (Ericsson & Ruhe 1980; the block form of Grimes, Lewis & Simon, SIAM J. Matrix Anal.
    Appl. 15 (1994) 228, with full re-orthogonalisation): ``OP = (K - sigma M)^-1 M`` is
    self-adjoint in the M-inner product, with eigenvalues ``theta = 1 / (lambda - sigma)``.  The
    basis ``Q`` of the block Krylov space ``[V, OP V, OP^2 V, ...]`` (``V = OP R``, R random:
    one smoothing solve) is M-orthonormal (two passes of classical Gram-Schmidt); for every block
    ``Q_j`` the code keeps ``M Q_j``, the image ``OP Q_j`` (one block solve) and ``M OP Q_j`` (one
    product with M; ``M W`` of the next block is one more product with M: as a combination of
    kept columns it would inherit the orthogonalisation's cancellation, eps / residual), ``K``
    is never applied, and the Rayleigh-Ritz matrix ``H = Q^T M OP Q`` and ``G = (OP Q)^T M OP Q``
    grow by one block column per solve.  Ritz pairs ``(theta, x = Q y)`` of ``H``; their
    residuals ``rho = ||OP x - theta x||_M`` follow from ``rho^2 = y^T G y - theta^2`` (exact
    arithmetic; its round-off floor is ~1e-8 theta_1, so once every bound below is under
    :data:`PROJECTED_OK` they are recomputed from the columns: ``r = OP Q y - theta Q y``,
    ``rho^2 = r^T M r`` with ``M r`` from the kept ``M Q``, ``M OP Q``).  The eigenvalues
    returned are ``sigma + 1/theta`` (as ARPACK's); Rayleigh quotients of K would weigh the
    vectors' residual components along high modes by ``lambda_j / lambda_i``.

    **Stopping rule** (Parlett, The Symmetric Eigenvalue Problem, thm 11.7.1 / Kato-Temple; and
    for the vectors thm 11.7.1's companion, ``sin angle <= rho / gap``): for a Ritz pair with
    residual ``rho`` there is an eigenvalue of OP within ``rho^2 / gap`` of theta, ``gap`` = the
    distance from theta to the rest of the spectrum (estimated by the nearest other Ritz value,
    wanted or not), so the relative error of ``lambda - sigma = 1/theta`` is at most
    ``(rho / theta)^2 * theta / gap`` and the angle of x to its eigenvector at most
    ``(rho / theta) * theta / gap``.  The iteration stops at the first solve after which, for
    every wanted pair, the first is below ``etol`` (default :data:`ETOL` = 1e-11: frequencies to
    ~5e-12, far below the 1e-8 at which callers compare them), the second below ``vtol``
    (:data:`VTOL` = 1e-6: mode shapes to six digits) and, when ``rtol`` is given,
    ``rho / theta < rtol`` (``rtol=TO_FLOOR``: to the round-off floor, for callers that take the
    vectors as exact eigenvectors), or when the largest relative residual stops halving below
    :data:`FLOOR_OK` (the round-off floor of double precision).  The solves' own round-off
    (backward error eps ||K||) moves theta by ~1e-9 relative at 265k DOFs, ARPACK's alike.

    ``block`` right-hand sides per solve (default ``max(4, n_modes // 2 + 1)``: 6 for 10 modes;
    blocks of at least the largest eigenvalue multiplicity wanted), ``steps + 1`` blocks (default
    about ``6 (n_modes + 2) / block``, 6 to 12) before a thick restart from the
    ``max(block, n_modes + 2)`` best Ritz vectors.  Returns (eigenvalues ascending, M-orthonormal
    vectors, number of vectors solved, info: ``residuals`` rho/theta and ``error_bounds`` of
    the returned pairs, ``history`` (vectors solved, largest bound) per Rayleigh-Ritz step)."""
    n = K.shape[0]
    b = int(block or max(4, n_modes // 2 + 1))
    b = max(1, min(b, n // 3))
    keep_r = max(b, n_modes + 2)  # Ritz vectors kept at a thick restart
    max_blocks = max(2, int(steps) + 1) if steps else max(6, min(12, -(-6 * (n_modes + 2) // b)))
    cap = max(max_blocks * b, keep_r + 2 * b, n_modes + 2 * b)
    Qb, MQb, OQb, MOQb = (np.empty((n, cap), order="F") for _ in range(4))
    H, G = np.zeros((cap, cap)), np.zeros((cap, cap))
    rng = np.random.default_rng(seed)
    W = fac.solve(matmat(M, rng.standard_normal((n, b))))  # one smoothing solve: a start rich in low modes
    W, MW = _m_orthonormalize(W, matmat(M, W))
    m = 0
    n_solved = b
    info: dict[str, Any] = {"block": b, "steps": max_blocks - 1, "cycles": 1, "restarts": 0, "history": []}
    last = 0  # first column of the last block appended

    def append(W: np.ndarray, MW: np.ndarray, OW: np.ndarray | None = None, MOW: np.ndarray | None = None) -> None:
        nonlocal m, n_solved, last
        k = W.shape[1]
        last = m
        sl = slice(m, m + k)
        Qb[:, sl], MQb[:, sl] = W, MW
        if OW is None:
            OQb[:, sl] = fac.solve(MW)
            n_solved += k
            MOQb[:, sl] = matmat(M, OQb[:, sl])
        else:
            OQb[:, sl], MOQb[:, sl] = OW, MOW
        H[: m + k, sl] = MQb[:, : m + k].T @ OQb[:, sl]
        G[: m + k, sl] = OQb[:, : m + k].T @ MOQb[:, sl]
        H[sl, :m], G[sl, :m] = H[:m, sl].T, G[:m, sl].T
        m += k

    def next_block(src: slice, max_cols: int | None) -> tuple[np.ndarray, np.ndarray]:
        """OP of the columns ``src`` M-orthogonalised against the basis (CGS2), and M of it."""
        W = OQb[:, src].copy()
        Qa, MQa = Qb[:, :m], MQb[:, :m]
        for _pass in range(2):  # classical Gram-Schmidt, twice (M-inner product)
            W -= Qa @ (MQa.T @ W)
        # M W explicitly: as a combination M OP Q_src - M Q C it would carry the cancellation of
        # the orthogonalisation (relative error eps / residual once the Ritz pairs converge)
        return _m_orthonormalize(W, matmat(M, W), max_cols=max_cols)

    append(W, MW)
    prev = None
    for _it in range(max_cycles * max_blocks):
        if m < n_modes + 1:  # too few basis vectors for the wanted pairs yet (block < n_modes)
            W, MW = next_block(slice(last, m), None)
            if W.shape[1] == 0:
                raise SolverError("block eigen-solver: Krylov space exhausted before n_modes vectors")
            append(W, MW)
            continue
        Hm = H[:m, :m]
        th, Y = np.linalg.eigh(0.5 * (Hm + Hm.T))
        order = np.argsort(-np.abs(th))  # largest |theta| = lambda nearest sigma
        th, Y = th[order], Y[:, order]
        Yw = Y[:, :n_modes]
        Gm = G[:m, :m]
        rho2 = np.einsum("ij,ij->j", Yw, (0.5 * (Gm + Gm.T)) @ Yw) - th[:n_modes] ** 2
        res = np.sqrt(np.abs(rho2)) / np.abs(th[:n_modes])
        # gap of each wanted theta to the nearest other Ritz value (the unwanted ones included)
        gap = np.array([np.min(np.abs(np.delete(th, i) - th[i])) for i in range(n_modes)])
        rel_gap = np.abs(th[:n_modes]) / np.maximum(gap, 1e-300)
        bound = res ** 2 * rel_gap
        explicit = bound.max() < PROJECTED_OK
        if explicit:  # near convergence: residuals from the columns (the projection's floor is ~1e-8 theta_1)
            R = OQb[:, :m] @ Yw - Qb[:, :m] @ (Yw * th[:n_modes])
            MR = MOQb[:, :m] @ Yw - MQb[:, :m] @ (Yw * th[:n_modes])
            res = np.sqrt(np.abs(np.einsum("ij,ij->j", R, MR))) / np.abs(th[:n_modes])
            bound = res ** 2 * rel_gap
        info["residuals"], info["error_bounds"] = res, bound
        info["history"].append((n_solved, float(bound.max()), float(res.max())))
        if np.all(bound < etol) and np.all(res * rel_gap < vtol) and (rtol is None or np.all(res < rtol)):
            break
        # round-off floor: a residual that no longer falls (by 2x per solve) is as good as it gets
        # in double precision; below FLOOR_OK the eigenvalues are still accurate to ~1e-10
        if explicit and prev is not None and res.max() > 0.5 * prev and res.max() < FLOOR_OK:
            info["floor"] = True
            break
        prev = float(res.max()) if explicit else None
        if m + b > cap:  # thick restart from the best Ritz vectors (their images known: no solve)
            if info["cycles"] >= max_cycles:
                raise SolverError(f"block eigen-solver did not converge (largest residual {res.max():.1e} after "
                                  f"{max_cycles} cycles)")
            Yk = Y[:, :keep_r]
            keep = [Qb[:, :m] @ Yk, MQb[:, :m] @ Yk, OQb[:, :m] @ Yk, MOQb[:, :m] @ Yk]
            m = 0
            append(*keep)
            info["cycles"] += 1
            info["restarts"] += 1
            src = slice(0, m)  # the kept vectors' residual directions span (about) one block
        else:
            src = slice(last, m)
        W, MW = next_block(src, b)
        if W.shape[1] == 0:  # invariant subspace: nothing new to add
            break
        append(W, MW)
    else:
        raise SolverError(f"block eigen-solver did not converge (largest residual {res.max():.1e})")
    # the eigenvalues are sigma + 1/theta (as ARPACK's): theta carries the Kato-Temple bound above.
    # Rayleigh quotients of K would not be better: K weighs the vectors' residual components along
    # high modes by lambda_j / lambda_i (measured: 5e-9 off for a 1-mode solve stopped at
    # rho / theta = 1.3e-6, whose theta was within 1e-11 of ARPACK's)
    X = Qb[:, :m] @ Yw
    w = sigma + 1.0 / th[:n_modes]
    o = np.argsort(w)
    info["residuals"], info["error_bounds"] = info["residuals"][o], info["error_bounds"][o]
    return w[o], X[:, o], n_solved, info


#: :func:`matmat` / :func:`rows_matmul`: products with fewer multiply-adds stay serial (scipy /
#: numpy).  A thread start costs ~0.1 ms, but on a loaded machine a second thread only adds CPU
#: (docs/fem.md "Session 8"), so only the large models where the eigen phase's products take
#: seconds (from ~60k DOFs: K x 6 columns ~20M multiply-adds) use threads; the default probes'
#: solves (~14k DOFs) and the test suite keep the serial path
MATMAT_MIN_WORK = 20_000_000


def matmat_threads() -> int:
    """Threads of :func:`matmat`: numba's thread count (``NUMBA_NUM_THREADS``, the number of
    CPUs unless set; the report's workers set 1), as for every compiled kernel."""
    import numba

    return max(1, int(numba.config.NUMBA_NUM_THREADS))


def matmat(A: sp.spmatrix, X: np.ndarray, threads: int | None = None) -> np.ndarray:
    """``A @ X`` for a CSR matrix and a dense block X (n, k), its rows split between threads.

    The same sums as scipy's ``csr_matvecs`` (every entry accumulated over its row's non-zeros in
    stored order), so the result is bit for bit scipy's (tests/test_fem_threads.py); rows are cut
    at equal shares of the non-zeros.  The threads are plain Python threads running a compiled
    kernel that releases the GIL (:func:`probedyn.fem.kernels.csr_matmat_rows`), started per
    call: no numba threading layer (its default, workqueue, aborts on concurrent launches from
    several threads; OpenMP's GNU runtime beside MKL's is not fork-safe), no pool to be left
    broken in a forked child.  Anything but a float64 CSR matrix times a float64 2-D block, or a
    small product, goes to scipy."""
    nt = matmat_threads() if threads is None else int(threads)
    if (nt < 2 or not sp.isspmatrix_csr(A) or A.dtype != np.float64 or getattr(X, "ndim", 0) != 2
            or np.asarray(X).dtype != np.float64 or A.nnz * X.shape[1] < MATMAT_MIN_WORK):
        return A @ X
    n = A.shape[0]
    Xc = np.ascontiguousarray(X)
    Y = np.zeros((n, Xc.shape[1]))
    cuts = np.searchsorted(A.indptr, np.linspace(0, A.nnz, nt + 1)[1:-1]).tolist()
    bounds = list(zip([0] + cuts, cuts + [n]))
    in_threads(lambda r0, r1: _csr_matmat_rows(A.indptr, A.indices, A.data, Xc, Y, r0, r1), bounds)
    return Y


def rows_matmul(A: np.ndarray, B: np.ndarray, threads: int | None = None) -> np.ndarray:
    """``A @ B`` for a tall dense A (n, m) and a small B (m, k), its rows split between threads
    as :func:`matmat` (numpy releases the GIL inside BLAS; OpenBLAS itself keeps one thread,
    ``probedyn/__init__.py``, so no spinning BLAS threads compete with MKL's between calls).
    Each row's products are BLAS's own for that row: the result equals ``A @ B``
    (tests/test_fem_threads.py).  Small products (``n m k`` below :data:`MATMAT_MIN_WORK`) and
    single-thread settings call numpy once."""
    nt = matmat_threads() if threads is None else int(threads)
    n = A.shape[0]
    if nt < 2 or B.ndim != 2 or n * A.shape[1] * B.shape[1] < MATMAT_MIN_WORK:
        return A @ B
    Y = np.empty((n, B.shape[1]), dtype=np.result_type(A, B))
    cuts = np.linspace(0, n, nt + 1).astype(int).tolist()
    bounds = list(zip(cuts[:-1], cuts[1:]))
    in_threads(lambda r0, r1: np.matmul(A[r0:r1], B, out=Y[r0:r1]), bounds)
    return Y


def in_threads(fn: Callable[..., Any], bounds: list[tuple]) -> None:
    """``fn(*b)`` for every argument tuple b (a row range, or a task): the first in this thread,
    the others in new threads (started per call, joined before returning; an exception in any is
    raised here).  For compiled kernels that release the GIL."""
    errors: list[BaseException] = []

    def part(*args: Any) -> None:
        try:
            fn(*args)
        except BaseException as exc:  # pragma: no cover - re-raised below
            errors.append(exc)

    workers = [threading.Thread(target=part, args=b, daemon=True) for b in bounds[1:]]
    for w in workers:
        w.start()
    part(*bounds[0])
    for w in workers:
        w.join()
    if errors:  # pragma: no cover
        raise errors[0]


#: mixed solver: Jacobi-preconditioned CG on M to this relative residual for ``r^T M^-1 r``
MINV_RTOL = 1e-2


def _minv_norms(M: sp.spmatrix, R: np.ndarray, dinv: np.ndarray, rtol: float = MINV_RTOL,
                max_iter: int = 200) -> np.ndarray:
    """``r^T M^-1 r`` for every column r of R by Jacobi-preconditioned conjugate gradients on M.

    The consistent mass matrix is well conditioned after diagonal scaling, independently of the
    element size (Wathen, IMA J. Numer. Anal. 7 (1987) 449: the spectrum of ``D^-1 M`` lies in the
    range of the element ones), so CG converges in a mesh-independent number of steps (~10 at
    1e-2, 265k P2 DOFs).  CG's iterate x_k gives ``r^T x_k``, which increases monotonically to
    ``r^T M^-1 r``; the remainder is ``s^T M^-1 s`` (s = r - M x_k, Galerkin orthogonality), at
    most ``rtol^2 ||r||^2_{D^-1} / mu_min(D^-1 M)``, and is added with the smallest Ritz value of
    CG's own Lanczos matrix as mu_min (an upper estimate of mu_min: the added term is an
    estimate, ~1e-3 of the result; the error bounds it enters are quadratic in the residual and
    the solver stops with them 1e2-1e4 below their tolerances, tests/test_eigen_stopping.py)."""
    X = np.zeros_like(R)
    S = R.copy()
    Z = S * dinv[:, None]
    P = Z.copy()
    rz = np.einsum("ij,ij->j", S, Z)
    rz0 = rz.copy()
    alphas, betas = [], []
    for _k in range(max_iter):
        MP = matmat(M, P)
        a = rz / np.einsum("ij,ij->j", P, MP)
        X += P * a
        S -= MP * a
        Z = S * dinv[:, None]
        rz1 = np.einsum("ij,ij->j", S, Z)
        alphas.append(a)
        if np.all(rz1 <= rtol ** 2 * rz0):
            break
        beta = rz1 / rz
        betas.append(beta)
        P = Z + P * beta
        rz = rz1
    else:
        raise SolverError("M^-1 norm: CG on the mass matrix did not converge (is M positive definite?)")
    # mu_min of D^-1 M estimated from CG's Lanczos tridiagonal (smallest over the columns)
    k = len(alphas)
    A_ = np.array(alphas)
    B_ = np.array(betas) if betas else np.zeros((0, R.shape[1]))
    mu = np.inf
    for j in range(R.shape[1]):
        d = 1.0 / A_[:, j]
        d[1:] += B_[:, j] / A_[:-1, j]
        e = np.sqrt(np.abs(B_[:, j])) / A_[:-1, j]
        T = np.diag(d) + np.diag(e, 1) + np.diag(e, -1) if k > 1 else np.array([[d[0]]])
        mu = min(mu, float(np.linalg.eigvalsh(T)[0]))
    return np.einsum("ij,ij->j", R, X) + rz1 / max(mu, 1e-300)


def mixed_eigsh(K: sp.spmatrix, M: sp.spmatrix, n_modes: int, precondition: Callable[[np.ndarray], np.ndarray],
                block: int | None = None, etol: float = ETOL, vtol: float = VTOL, max_vectors: int | None = None,
                seed: int = 12345) -> tuple[np.ndarray, np.ndarray, int, dict]:
    """The ``n_modes`` lowest eigenpairs of ``K x = lambda M x`` by a block Davidson method
    whose preconditioner ``precondition(R) ~ K^-1 R`` may be inexact (a single-precision
    factor of K: :attr:`Factorization.approximate`) and whose Rayleigh-Ritz projections and
    residuals use the exact double-precision K and M.

    Why it is exact although the solves are not: the basis Q (M-orthonormal) is only a search
    space; the Ritz pairs ``(theta, x = Q y)`` of ``Q^T K Q`` are Rayleigh-Ritz approximations
    of the pencil ``(K, M)`` itself, and the stopping test uses their TRUE residuals
    ``r = K x - theta M x`` (K Q is kept: one sparse product per new block).  With an exact
    preconditioner the space is the shift-invert Krylov space of :func:`block_eigsh`
    (``K^-1 r = x - theta K^-1 M x``); a float32 factor (cond(K) ~1e9: each solve ~10 % off)
    only slows the convergence (265k DOFs: 60 vectors instead of 48).

    **Stopping rule** (Kato-Temple for the pencil, Parlett thm 11.7.1 in the M-inner product):
    for an M-normalised Ritz vector x with residual r there is an eigenvalue lambda with
    ``|lambda - theta| <= ||r||^2_{M^-1} / gap`` (gap = distance of theta to the rest of the
    spectrum, estimated by the nearest other Ritz value, as :func:`block_eigsh`) and the angle
    of x to its eigenvector is at most ``||r||_{M^-1} / gap``.  The iteration stops when for
    every wanted pair the relative eigenvalue bound ``||r||^2_{M^-1} / (gap theta)`` is below
    ``etol`` and the angle bound below ``vtol``.  ``||r||_{M^-1}`` is ``sqrt(r^T D^-1 r)``
    scaled by the ratio measured at the last CG evaluation while the bounds are large, and
    computed by CG on M (:func:`_minv_norms`) before the solver stops.  The eigenvalues
    returned are the Rayleigh quotients theta (upper bounds of the eigenvalues, Courant-Fischer).

    Expansion: each step applies the preconditioner to the residuals of the ``block`` least
    converged of the ``max(block, n_modes)`` lowest Ritz pairs (the first steps, while the space
    has fewer than ``n_modes + 1`` vectors: to ``M W`` of the last block, a Krylov start).
    No restart: at most ``max_vectors`` (default 16 blocks) basis vectors, else SolverError (the
    caller falls back to the double-precision path).  Returns (eigenvalues ascending,
    M-orthonormal vectors, number of vectors solved, info with ``residuals`` (||r||_{M^-1} /
    theta), ``error_bounds`` and ``history``)."""
    n = K.shape[0]
    b = int(block or max(4, n_modes // 2 + 1))
    b = max(1, min(b, n // 3))
    cap = int(max_vectors or 16 * b)
    cap = max(cap, n_modes + 2 * b)
    Q, MQ, KQ = (np.empty((n, cap), order="F") for _ in range(3))
    A = np.zeros((cap, cap))
    dinv = 1.0 / M.diagonal()
    if not np.all(dinv > 0):
        raise SolverError("mixed eigen-solver: the mass matrix has a non-positive diagonal")
    rng = np.random.default_rng(seed)
    W = precondition(matmat(M, rng.standard_normal((n, b))))
    n_solved = b
    m = 0
    ratio = None  # ||r||^2_{M^-1} / ||r||^2_{D^-1} of the wanted pairs at the last CG evaluation
    info: dict[str, Any] = {"block": b, "history": [], "cg_evaluations": 0}
    nx = max(b, n_modes)
    while True:
        for _pass in range(2):  # classical Gram-Schmidt, twice (M-inner product)
            if m:
                W = W - rows_matmul(Q[:, :m], MQ[:, :m].T @ W)
        W, MW = _m_orthonormalize(W, matmat(M, W))
        k = W.shape[1]
        if k == 0:
            raise SolverError("mixed eigen-solver: the search space stopped growing")
        if m + k > cap:
            raise SolverError(f"mixed eigen-solver did not converge within {cap} vectors")
        sl = slice(m, m + k)
        Q[:, sl], MQ[:, sl], KQ[:, sl] = W, MW, matmat(K, W)
        A[: m + k, sl] = Q[:, : m + k].T @ KQ[:, sl]
        A[sl, :m] = A[:m, sl].T
        m += k
        if m < n_modes + 1:
            W = precondition(MW)
            n_solved += k
            continue
        th, Y = np.linalg.eigh(0.5 * (A[:m, :m] + A[:m, :m].T))
        nxm = min(nx, m)
        Yx = Y[:, :nxm]
        R = rows_matmul(KQ[:, :m], Yx) - rows_matmul(MQ[:, :m], Yx * th[:nxm])
        d2 = np.einsum("ij,ij->j", R, R * dinv[:, None])  # ||r||^2_{D^-1}
        gap = np.array([np.min(np.abs(np.delete(th, i) - th[i])) for i in range(n_modes)])
        rel_gap = np.abs(th[:n_modes]) / np.maximum(gap, 1e-300)
        th_w = np.abs(th[:n_modes])

        def bounds(r2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            res = np.sqrt(r2) / th_w  # ||r||_{M^-1} / theta
            return res ** 2 * rel_gap, res * rel_gap

        est = d2[:n_modes] * (ratio if ratio is not None else 1.0)
        eb, ang = bounds(est)
        certified = False
        if np.all(eb < etol) and np.all(ang < vtol):  # converged by the estimate: the M^-1 norms by CG
            r2 = _minv_norms(M, R[:, :n_modes], dinv)
            info["cg_evaluations"] += 1
            ratio = r2 / np.maximum(d2[:n_modes], 1e-300)
            eb, ang = bounds(r2)
            certified = True
        info["history"].append((n_solved, float(eb.max()), float(ang.max())))
        info["residuals"], info["error_bounds"] = np.sqrt(eb / rel_gap), eb
        if certified and np.all(eb < etol) and np.all(ang < vtol):
            break
        pick = np.argsort(-d2)[:b]  # the least converged of the lowest nx pairs
        W = precondition(np.asfortranarray(R[:, pick]))
        n_solved += W.shape[1]
    X = rows_matmul(Q[:, :m], Y[:, :n_modes])
    return th[:n_modes].copy(), X, n_solved, info


def auto_method(n: int, sigma: float | None, tol: float = 0.0, solver: str = "auto") -> str:
    """The eigen-solver ``method="auto"`` runs for ``n`` free DOFs: "mixed" for a positive definite
    K (sigma = 0) with PARDISO from :data:`MIXED_MIN_DOFS` DOFs when no residual tolerance is asked
    (``tol``: the vectors to the round-off floor need the double factor), else "block"."""
    if (n >= MIXED_MIN_DOFS and sigma == 0 and tol == 0 and solver in ("auto", "pardiso") and have_pardiso()):
        return "mixed"
    return "block"


def shift_invert_eigsh(
    K: sp.spmatrix,
    M: sp.spmatrix,
    n_modes: int,
    sigma: float | None = None,
    solver: str = "auto",
    tol: float = 0.0,
    method: str = "auto",
    options: dict | None = None,
    analysis: Analysis | None = None,
) -> EigenResult:
    """Lowest ``n_modes`` eigenpairs of ``K phi = lambda M phi`` nearest ``sigma``.

    ``sigma`` [rad^2/s^2]: shift; default ``-1e-12 * mean(diag K)/mean(diag M)`` (slightly below
    zero, so ``K - sigma M`` is SPD also for a free-floating model; a constrained model passes
    ``sigma = 0``).  ``method``: "auto" (:func:`auto_method`), "block" (block shift-invert
    Lanczos), "arpack" or "mixed" (module docstring; "mixed" needs sigma = 0, PARDISO and
    ``tol = 0``, else it is "block"; pass it an ``analysis`` started with ``options={"single": 1}``); ``options``: PARDISO settings; ``analysis``: PARDISO's analysis of the pattern
    of ``K`` started before assembly (:class:`Analysis`, used for ``sigma = 0``).  Raises :class:`SolverError` for too few DOFs
    (fewer than 10 per requested mode), non-convergence, or non-finite / negative eigenvalues.
    """
    n = K.shape[0]
    if n_modes < 1:
        raise SolverError(f"n_modes must be at least 1, got {n_modes}")
    if n < 10 * n_modes:
        raise SolverError(
            f"mesh too coarse for {n_modes} modes: {n} free DOFs (need at least {10 * n_modes}); refine the mesh"
        )
    if method not in METHODS:
        raise SolverError(f"unknown eigen-solver method '{method}' (known: {', '.join(METHODS)})")
    K = sp.csr_matrix(K)
    M = sp.csr_matrix(M)
    dK, dM = K.diagonal(), M.diagonal()
    if sigma is None:
        # slightly below zero: |sigma| must stay well below the first elastic eigenvalue,
        # which can be ~1e-9 of diag(K)/diag(M) for a long beam with small elements
        sigma = -1e-12 * float(np.mean(np.abs(dK)) / np.mean(np.abs(dM)))
    A = K if sigma == 0 else (K - sigma * M).tocsr()  # sigma = 0: K itself (a reusable factorisation)
    if method == "auto":
        method = auto_method(n, sigma, tol, solver)
    mixed_failed = None
    if method == "mixed":
        # a single-precision factor of K as the preconditioner of mixed_eigsh (exact K, M projections);
        # K must be positive definite (sigma = 0, a clamped model) and the backend PARDISO
        if sigma == 0 and tol == 0 and solver in ("auto", "pardiso") and have_pardiso():
            fac = factorize(A, solver=solver, options={**(options or {}), "single": 1}, analysis=analysis)
            analysis = None  # taken or released by factorize
            t0 = time.perf_counter()
            try:
                if fac.approximate is None:
                    raise SolverError("no single-precision solve")
                w, V, count, binfo = mixed_eigsh(K, M, n_modes, fac.approximate)
            except SolverError as exc:  # fall back to the double-precision factor and block Lanczos
                mixed_failed = str(exc)
            else:
                info = {**fac.info, **binfo}
                info.pop("_release", None)
                return _checked(EigenResult(w, V, fac.backend + "+mixed", fac.seconds, time.perf_counter() - t0,
                                            count, "mixed", info))
            finally:
                fac.release()
        method = "block"
    fac = factorize(A, spd=sigma <= 0, solver=solver, options=options, analysis=analysis if sigma == 0 else None)
    t0 = time.perf_counter()
    info: dict[str, Any] = dict(fac.info)
    info.pop("_release", None)
    if mixed_failed is not None:
        info["mixed_failed"] = mixed_failed
    # a shift below zero is for free-floating models: their rigid-body modes have enormous
    # theta = 1 / (lambda - sigma), whose round-off swamps the block solver's residual test of
    # the elastic modes; ARPACK's implicit restarts handle them (and any non-convergence)
    use_block = method == "block" and sigma >= 0
    try:
        if use_block:
            try:
                w, V, count, binfo = block_eigsh(K, M, n_modes, sigma, fac, rtol=tol if tol > 0 else None)
                info.update(binfo)
            except SolverError as exc:
                info["block_failed"] = str(exc)
                use_block = False
        if not use_block:
            count_l = [0]

            def matvec(x):
                count_l[0] += 1
                return fac.solve(x)

            op = spla.LinearOperator((n, n), matvec=matvec, dtype=float)
            v0 = np.random.default_rng(12345).standard_normal(n)
            # Ask ARPACK for a few more pairs than needed: a larger Krylov space captures multiple
            # eigenvalues (rigid-body modes, the degenerate bending pairs of a tube) reliably.
            k_int = min(n - 2, n_modes + max(3, n_modes // 2))
            try:
                w, V = spla.eigsh(K, k=k_int, M=M, sigma=sigma, OPinv=op, which="LM", tol=tol, v0=v0,
                                  ncv=min(n - 1, max(2 * k_int + 1, 20)))
            except spla.ArpackNoConvergence as exc:
                raise SolverError(f"eigen-solver did not converge ({len(exc.eigenvalues)} of {n_modes} modes)") from None
            except (spla.ArpackError, ValueError, RuntimeError) as exc:
                raise SolverError(f"eigen-solver failed: {str(exc).splitlines()[0]}") from None
            order = np.argsort(w)
            w, V = w[order][:n_modes], V[:, order][:, :n_modes]
            count = count_l[0]
    finally:
        fac.release()
    solve_s = time.perf_counter() - t0
    return _checked(EigenResult(w, V, fac.backend, fac.seconds, solve_s, count, "block" if use_block else "arpack",
                                info))


def _checked(r: EigenResult) -> EigenResult:
    """Eigenpairs sorted ascending; SolverError for non-finite or negative eigenvalues."""
    order = np.argsort(r.eigenvalues)
    w, V = r.eigenvalues[order], r.vectors[:, order]
    if not np.all(np.isfinite(w)):
        raise SolverError("eigen-solver returned non-finite eigenvalues")
    scale = float(np.max(np.abs(w))) if w.size else 1.0
    if np.any(w < -1e-8 * scale):
        raise SolverError(
            f"negative eigenvalue {w.min():.3g} (rad/s)^2: the stiffness is not positive semi-definite"
        )
    r.eigenvalues, r.vectors = np.maximum(w, 0.0), V
    return r
