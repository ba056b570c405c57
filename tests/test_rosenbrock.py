"""The shared Rosenbrock W-method (:mod:`probedyn.schemes.rosenbrock`) on the Prothero-Robinson problem
``y' = lam (y - g(t)) + g'(t)``, ``g = sin``, whose solution from ``y(0) = g(0) + y0`` is
``g(t) + y0 exp(lam t)``: a stiff decay onto a smooth solution with the exact answer known."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from probedyn.schemes.rosenbrock import ros23, stable_identity


@njit(cache=True)
def _prothero_robinson(kern, ctx, t, y, f, J, Tt, want_j):
    lam = ctx[0]
    f[0] = lam * (y[0] - math.sin(t)) + math.cos(t)
    if want_j:
        J[0, 0] = lam
        Tt[0] = -lam * math.cos(t) - math.sin(t)
    return y[0]


stable_identity(_prothero_robinson, "tests")


def _run(lam, rtol, y0=0.0, T=2.0):
    ts, ys, F, n, rej = ros23(_prothero_robinson, None, (lam,), T, np.array([y0]), rtol, np.array([rtol]), 1e-6,
                              T / 20, 1_000_000)
    exact = np.sin(ts) + y0 * np.exp(lam * ts)
    return ts, ys[:, 0], F, n, exact


@pytest.mark.parametrize("lam", [-1.0, -1e3, -1e7])
def test_the_error_follows_the_tolerance_at_any_stiffness(lam):
    """The global error is at most the sum of the local errors the step control admits (each step's below
    ``atol + rtol |y| <= 2 rtol`` here; on the mild problem nothing damps them, on the stiff ones the decay does),
    and it falls with the tolerance as the method's order says (local error ~ h^3 with h ~ tol^(1/3): global
    error ~ tol^(2/3) or better), whatever the stiffness. The stiff problem takes under 2000 steps: a linearly
    implicit, L-stable method is limited by accuracy, not stability (an explicit one would need |lam| T / 2 = 1e7)."""
    errs, steps = [], []
    for rtol in (1e-4, 1e-6):
        ts, y, F, n, exact = _run(lam, rtol)
        assert n > 0 and ts[-1] == pytest.approx(2.0, rel=1e-12)
        assert np.array_equal(F, y)  # the recorded quantity is the system's return value at each accepted step
        errs.append(np.max(np.abs(y - exact)))
        steps.append(n)
    assert errs[0] < steps[0] * 2e-4 and errs[1] < steps[1] * 2e-6
    assert errs[0] / errs[1] > 100 ** (2 / 3) / 3  # 100x tighter tolerance: error down by ~21x or more
    assert steps[1] < 2000


def test_a_stiff_transient_decays_without_oscillation():
    """L-stability: an initial offset on a stiff mode (lam h ~ -1e4 after the first steps) is damped at once, not
    carried as a slowly decaying, sign-alternating error (as the trapezoidal rule would)."""
    ts, y, F, n, exact = _run(-1e7, 1e-6, y0=1.0)
    late = ts > 1e-5  # 100 time constants
    assert np.max(np.abs(y[late] - exact[late])) < 20e-6


_SCAN = """
from probedyn.schemes.ffm import FFM, line_scan_path
from probedyn.schemes.ffm_lattice2d import lattice2d_path
from probedyn.schemes.rosenbrock import ros23
ffm = FFM.from_preset("mica", "pt", {"U0": 5e-19, "a": 4e-10, "k_x": 8.0, "m_x": 2e-11, "c_x": 1e-5})
line_scan_path(ffm, [0.0, 4e-9, 0.0], speed=5e-6, rtol=1e-5, atol_rel=1e-5)
lattice2d_path(U0=5e-19, a=4e-10, theta=0.1, k_x=8.0, k_y=8.0, m=2e-11, c_x=1e-5, c_y=1e-5, turns=[0.0, 2e-9],
               speed=5e-6)
print(sum(ros23.stats.cache_hits.values()), sum(ros23.stats.cache_misses.values()))
"""


def test_a_new_process_finds_the_integrator_in_the_disk_cache(tmp_path):
    """The FFM systems and friction kernels have process-independent identities (``stable_identity``), so the
    second process to run a scan loads ``ros23``'s specialisations from numba's disk cache instead of compiling
    them (4 s each). Without those identities every process compiled and added an entry to the index, and past
    128 entries saving it failed with a ReferenceError (session 55)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # a cache of its own: no other test writes its index
    runs = [subprocess.run([sys.executable, "-c", _SCAN], capture_output=True, text=True, timeout=300, env=env)
            for _ in range(2)]
    for r in runs:
        assert r.returncode == 0, r.stderr[-2000:]
    hits, misses = map(int, runs[1].stdout.split())
    assert (hits, misses) == (2, 0)


def test_the_factored_solve_is_the_elimination_bit_for_bit():
    """``ros23`` factors ``W`` once per step and solves its three stages with that factorisation
    (:func:`lu_factor_small`, :func:`lu_solve_factored`); until session 65 each stage eliminated ``W`` again
    (:func:`lu_solve_small`). Each entry of the right-hand side receives the same operations in the same order, so
    the two agree bit for bit, on matrices that need row swaps (a zero or small pivot) as on diagonally dominant
    ones, and the integrations of the FFM models are those of before (measured: every sample of the three-scan
    example's residuals)."""
    from probedyn.schemes.rosenbrock import lu_factor_small, lu_solve_factored, lu_solve_small

    rng = np.random.default_rng(65)
    mats = [rng.normal(size=(n, n)) for n in (1, 2, 3, 4, 6) for _ in range(20)]
    mats += [np.array([[0.0, 1.0, 0.0], [-8e12, -1e7, -3.0], [1.0, 0.0, -1e3]]),  # an FFM W's pattern: swaps
             np.eye(4) - 1e-9 * rng.normal(size=(4, 4))]
    for A in mats:
        b = rng.normal(size=A.shape[0])
        M, piv = A.copy(), np.zeros(A.shape[0], np.int64)
        lu_factor_small(M, piv)
        x = b.copy()
        lu_solve_factored(M, piv, x)
        assert np.array_equal(x, lu_solve_small(A, b))
        assert np.allclose(A @ x, b, rtol=1e-8, atol=1e-8 * np.abs(A).max() * np.abs(x).max())


def test_the_output_grows_past_its_first_allocation_and_stops_at_max_steps():
    """The accepted steps are kept in arrays grown by doubling (from 1024 rows; not ``max_steps`` rows allocated
    on every call): a run of some 10^4 steps keeps every one, in order, and a run cut at ``max_steps`` returns
    ``n = -1`` with exactly ``max_steps + 1`` rows."""
    ts, y, F, n, exact = _run(-1.0, 1e-9, T=20.0)
    assert n > 3000 and len(ts) == n + 1 and np.all(np.diff(ts) > 0) and ts[-1] == pytest.approx(20.0, rel=1e-12)
    assert np.max(np.abs(y - exact)) < n * 2e-9
    ts2, ys2, F2, n2, _ = ros23(_prothero_robinson, None, (-1.0,), 20.0, np.array([0.0]), 1e-9, np.array([1e-9]),
                                1e-6, 1.0, 1500)
    assert n2 == -1 and len(ts2) == len(ys2) == len(F2) == 1501
    assert np.array_equal(ts2, ts[:1501]) and np.array_equal(ys2[:, 0], y[:1501])
