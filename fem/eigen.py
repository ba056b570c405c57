"""Sparse symmetric factorisation and shift-invert eigen-solution ``K phi = omega^2 M phi``.

The shift-invert operator ``(K - sigma M)^-1`` is factorised once with MKL PARDISO
(pypardiso; ``mtype = 2`` real SPD when ``K - sigma M`` is positive definite, i.e. for
``sigma`` below the lowest eigenvalue, else ``mtype = -2`` real symmetric indefinite), and
handed to ARPACK (``scipy.sparse.linalg.eigsh(K, k, M, sigma, OPinv=...)``).  Without
pypardiso the fallback is scipy's SuperLU (``splu``), which is two orders of magnitude slower
for 3D problems (benchmarks/modal.py measures both).

Only the upper triangle is passed to PARDISO for symmetric types, as MKL requires.

Threads: on few shared cores, OpenBLAS's spinning threads (ARPACK's dense steps use it)
compete with MKL's; ``OPENBLAS_NUM_THREADS=1`` set before numpy is imported made the ARPACK
loop 3-5x faster at 23k DOFs on the 2-core test machine (benchmarks/modal.py sets it).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from probedyn.core.errors import SolverError

SOLVERS = ("auto", "pardiso", "superlu")


def have_pardiso() -> bool:
    # pypardiso is imported where it is used, not at module level: it is the optional fast
    # backend (SuperLU is the fallback when MKL is missing) and importing it loads MKL (~0.6 s).
    try:
        import pypardiso  # noqa: F401
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


def factorize(A: sp.spmatrix, spd: bool = True, solver: str = "auto") -> Factorization:
    """Factorise symmetric ``A`` with PARDISO (``solver='pardiso'`` or 'auto' when available)
    or SuperLU.  ``spd`` selects PARDISO's SPD type 2 (else symmetric indefinite -2); if the
    SPD factorisation fails (a zero or negative pivot), the indefinite type is tried."""
    if solver not in SOLVERS:
        raise SolverError(f"unknown linear solver '{solver}' (known: {', '.join(SOLVERS)})")
    A = sp.csr_matrix(A, dtype=float)
    t0 = time.perf_counter()
    if solver in ("auto", "pardiso") and have_pardiso():
        for mtype in ((2, -2) if spd else (-2,)):
            try:
                f = _pardiso(A, mtype)
                f.seconds = time.perf_counter() - t0
                return f
            except Exception as exc:  # PyPardisoError on non-SPD input etc.
                last = exc
        raise SolverError(f"PARDISO factorisation failed: {str(last).splitlines()[0]}")
    if solver == "pardiso":
        raise SolverError("pypardiso is not installed (pip install pypardiso), use solver='superlu'")
    try:
        lu = spla.splu(A.tocsc())
    except RuntimeError as exc:
        raise SolverError(f"SuperLU factorisation failed ({exc}): the matrix is singular; is the model clamped?") from None
    return Factorization(lu.solve, "superlu", time.perf_counter() - t0)


_POOL: dict[int, list] = {}


def _pardiso_instance(mtype: int):
    """A PyPardisoSolver from a small pool (creating one costs ~0.7 s: pypardiso searches the
    file system for the MKL library); returned to the pool by ``Factorization.release``."""
    import pypardiso

    pool = _POOL.setdefault(mtype, [])
    return pool.pop() if pool else pypardiso.PyPardisoSolver(mtype=mtype)


def _pardiso(A: sp.csr_matrix, mtype: int) -> Factorization:
    U = sp.triu(A, format="csr")
    U.sort_indices()
    ps = _pardiso_instance(mtype)
    ps.set_iparm(1, 1)  # user-supplied iparm
    ps.set_iparm(2, 3)  # parallel (OpenMP) nested-dissection ordering
    ps.factorize(U)
    if mtype == 2 and ps.get_iparm(30) != 0:
        raise SolverError("zero or negative pivot in SPD factorisation")
    n = A.shape[0]

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        shape = b.shape
        # PARDISO reads a block of right-hand sides column by column: Fortran order
        bb = np.asfortranarray(b.reshape(n, -1))
        ps.set_phase(33)  # solve only, with the stored factors (skip pypardiso's re-hash)
        x = ps._call_pardiso(U, bb)
        return np.ascontiguousarray(x).reshape(shape)

    def release() -> None:
        ps.free_memory(everything=True)
        ps.factorized_A = sp.csr_matrix((0, 0))
        _POOL.setdefault(mtype, []).append(ps)

    return Factorization(solve, f"pardiso(mtype={mtype})", 0.0, release)


@dataclass
class EigenResult:
    eigenvalues: np.ndarray  # omega^2 [rad^2/s^2], ascending
    vectors: np.ndarray  # (n, k), M-orthonormal
    backend: str
    factor_s: float
    solve_s: float
    n_opinv: int


def shift_invert_eigsh(
    K: sp.spmatrix,
    M: sp.spmatrix,
    n_modes: int,
    sigma: float | None = None,
    solver: str = "auto",
    tol: float = 0.0,
) -> EigenResult:
    """Lowest ``n_modes`` eigenpairs of ``K phi = lambda M phi`` nearest ``sigma``.

    ``sigma`` [rad^2/s^2]: shift; default ``-1e-12 * mean(diag K)/mean(diag M)`` (slightly below
    zero, so ``K - sigma M`` is SPD also for a free-floating model; a constrained model passes
    ``sigma = 0``).  Raises
    :class:`SolverError` for too few DOFs (fewer than 10 per requested mode), ARPACK
    non-convergence, or non-finite / negative eigenvalues.
    """
    n = K.shape[0]
    if n_modes < 1:
        raise SolverError(f"n_modes must be at least 1, got {n_modes}")
    if n < 10 * n_modes:
        raise SolverError(
            f"mesh too coarse for {n_modes} modes: {n} free DOFs (need at least {10 * n_modes}); refine the mesh"
        )
    dK, dM = K.diagonal(), M.diagonal()
    if sigma is None:
        # slightly below zero: |sigma| must stay well below the first elastic eigenvalue,
        # which can be ~1e-9 of diag(K)/diag(M) for a long beam with small elements
        sigma = -1e-12 * float(np.mean(np.abs(dK)) / np.mean(np.abs(dM)))
    A = (K - sigma * M).tocsr()
    fac = factorize(A, spd=sigma <= 0, solver=solver)
    count = [0]

    def matvec(x):
        count[0] += 1
        return fac.solve(x)

    op = spla.LinearOperator((n, n), matvec=matvec, dtype=float)
    t0 = time.perf_counter()
    rng = np.random.default_rng(12345)
    v0 = rng.standard_normal(n)
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
    finally:
        fac.release()
    solve_s = time.perf_counter() - t0
    order = np.argsort(w)
    w, V = w[order][:n_modes], V[:, order][:, :n_modes]
    if not np.all(np.isfinite(w)):
        raise SolverError("eigen-solver returned non-finite eigenvalues")
    scale = float(np.max(np.abs(w))) if w.size else 1.0
    if np.any(w < -1e-8 * scale):
        raise SolverError(
            f"negative eigenvalue {w.min():.3g} (rad/s)^2: the stiffness is not positive semi-definite"
        )
    w = np.maximum(w, 0.0)
    return EigenResult(w, V, fac.backend, fac.seconds, solve_s, count[0])
