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
