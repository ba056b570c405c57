"""The stiff integrator of the FFM line-scan models: a linearly implicit Rosenbrock W-method of order 2(3).

One step of ``y' = f(t, y)`` (Shampine & Reichelt 1997, the method of MATLAB's ode23s; L-stable), with
``W = I - h d J``, ``d = 1 / (2 + sqrt 2)``, ``J = df/dy`` and ``T = df/dt`` at the step's start::

    W k1 = f(t, y) + h d T
    W (k2 - k1) = f(t + h/2, y + h k1 / 2) - k1
    y_new = y + h k2
    W k3 = f(t + h, y_new) - e32 (k2 - f1) - 2 (k1 - f0) + h d T,   e32 = 6 + sqrt 2

and the embedded error estimate ``h (k1 - 2 k2 + k3) / 6`` scaled by ``atol + rtol |y|`` (max norm). A step is
accepted below 1 (or at a step below 1e-22 s, where round-off decides) and the next step is scaled by
``0.8 err^(-1/3)`` within [0.2, 5] (after a rejection within [0.1, 1]). The Jacobian is evaluated once per
accepted step, analytically, by the model (a W-method stays of order 2 with an approximate J).

Each model is one ``system(kern, ctx, t, y, f, J, Tt, want_j)``, numba-compiled: it writes ``f(t, y)`` into
``f`` and, if ``want_j``, ``df/dy`` into ``J`` and ``df/dt`` into ``Tt``, and returns the force it records at
this state. ``kern`` is the friction model's numba kernel (or None) and ``ctx`` a tuple of the model's
parameters; numba compiles (and caches on disk) one specialisation per system and kernel, so a new model
runs at the speed of the built-in ones.

The on-disk cache keys a specialisation by the identities of the dispatchers it receives, and numba names a
dispatcher by a random UUID, new in every process. Every system and kernel passed here is therefore given a
stable identity (:func:`stable_identity`); without one the cache never hits. Until session 55 the systems had
none, and ``ros23`` was compiled again in every process that ran an FFM scan (4 s). Each process also added an
entry to the index. numba keeps only the last 128 dispatchers it rebuilt from an index alive, so once the
index named more systems than that, saving it failed in every process that had to compile: ``ReferenceError:
underlying object has vanished``, a traceback from ``probedyn diagnose`` (blind friction f22).

Users: :mod:`probedyn.schemes.ffm` (one mode, any friction model),
:mod:`probedyn.schemes.ffm_modal` (N modes), :mod:`probedyn.schemes.ffm_lattice2d` (two lateral springs
over a square lattice). The nano-placing release (:mod:`probedyn.schemes.placing._kernel`) keeps a variant of
its own: it locates contact transitions inside a step and factorises ``W`` once per step.
"""

from __future__ import annotations

import hashlib
import inspect
import math
from typing import Any

import numpy as np
from numba import njit


def stable_identity(fn: Any, owner: str) -> None:
    """Give a numba dispatcher passed to a cached function (a system of :func:`ros23`, a friction kernel) an
    identity that is the same in every process, so that numba's on-disk cache finds the specialisation again.
    The identity is the owner, the function's module and name and its source hash, so a changed function gets a
    new identity and a cached integrator never runs an old formula. Uses numba's ``_set_uuid`` (its
    ``_MemoMixin``); on a numba without it the integrator still runs, only compiled again in every process."""
    try:
        if getattr(fn, "_MemoMixin__uuid", None) is not None:
            return
        src = inspect.getsource(fn.py_func)
        digest = hashlib.sha1(src.encode()).hexdigest()[:16]
        fn._set_uuid(f"probedyn:{owner}:{fn.py_func.__module__}.{fn.py_func.__qualname__}:{digest}")
    except (AttributeError, OSError, TypeError, AssertionError):  # pragma: no cover - other numba
        pass


@njit(cache=True)
def lu_solve_small(A, b):
    """Solve A x = b for a small dense matrix (Gaussian elimination, partial pivoting); compiled. The Rosenbrock step
    solved each stage with it until session 65; now the reference that :func:`lu_factor_small` and
    :func:`lu_solve_factored` reproduce bit for bit (``tests/test_rosenbrock.py``, ``benchmarks/rosenbrock_stages.py``)."""
    n = A.shape[0]
    M = A.copy()
    x = b.copy()
    for i in range(n):
        piv = i
        best = abs(M[i, i])
        for r in range(i + 1, n):
            if abs(M[r, i]) > best:
                best = abs(M[r, i])
                piv = r
        if piv != i:
            for cc in range(n):
                tmp = M[i, cc]
                M[i, cc] = M[piv, cc]
                M[piv, cc] = tmp
            tmp = x[i]
            x[i] = x[piv]
            x[piv] = tmp
        for r in range(i + 1, n):
            fct = M[r, i] / M[i, i]
            for cc in range(i, n):
                M[r, cc] -= fct * M[i, cc]
            x[r] -= fct * x[i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for cc in range(i + 1, n):
            s -= M[i, cc] * x[cc]
        x[i] = s / M[i, i]
    return x


@njit(cache=True)
def lu_factor_small(M, piv):
    """Factor the small dense matrix ``M`` in place (Gaussian elimination, partial pivoting, LAPACK's layout: the
    multipliers below the diagonal, whole rows swapped, ``piv[i]`` the row swapped with row ``i``). The
    arithmetic is :func:`lu_solve_small`'s, so :func:`lu_solve_factored` gives its result bit for bit."""
    n = M.shape[0]
    for i in range(n):
        p = i
        best = abs(M[i, i])
        for r in range(i + 1, n):
            if abs(M[r, i]) > best:
                best = abs(M[r, i])
                p = r
        piv[i] = p
        if p != i:
            for cc in range(n):
                tmp = M[i, cc]
                M[i, cc] = M[p, cc]
                M[p, cc] = tmp
        for r in range(i + 1, n):
            fct = M[r, i] / M[i, i]
            for cc in range(i + 1, n):
                M[r, cc] -= fct * M[i, cc]
            M[r, i] = fct


@njit(cache=True)
def lu_solve_factored(M, piv, x):
    """Solve in place ``A x = b`` (``x`` holds ``b``) with ``M, piv`` from :func:`lu_factor_small`: the row swaps,
    then forward substitution with the stored multipliers (each entry receives the same operations, in the same
    order, as in :func:`lu_solve_small`), then back substitution."""
    n = M.shape[0]
    for i in range(n):
        p = piv[i]
        if p != i:
            tmp = x[i]
            x[i] = x[p]
            x[p] = tmp
    for i in range(n):
        for r in range(i + 1, n):
            x[r] -= M[r, i] * x[i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for cc in range(i + 1, n):
            s -= M[i, cc] * x[cc]
        x[i] = s / M[i, i]


@njit(cache=True)
def ros23(system, kern, ctx, T, y0, rtol, atol, h0, hmax, max_steps):
    """Integrate ``system`` (module docstring) from ``y0`` at ``t = 0`` to ``T`` [s], first step ``h0``, steps at
    most ``hmax``; ``atol`` per state. Returns ``(t, y, F, n_steps, n_rejected)`` on the accepted steps (``F``
    the force ``system`` records); ``n_steps`` is -1 if ``max_steps`` were taken before ``T``.

    ``W`` is factored once per step and the three stages solved with that factorisation; the stages and the
    output (grown by doubling, not allocated for ``max_steps`` at once) live in buffers allocated once per call.
    Until session 65 every stage eliminated ``W`` again and every vector expression allocated an array (some 25
    per step): the same arithmetic, bit for bit (``tests/test_rosenbrock.py``), 2-3 times slower."""
    d = 1.0 / (2.0 + math.sqrt(2.0))
    e32 = 6.0 + math.sqrt(2.0)
    n = y0.shape[0]
    cap = min(max_steps + 1, 1024)
    ts = np.empty(cap)
    ys = np.empty((cap, n))
    Fs = np.empty(cap)
    y = y0.copy()
    yn = np.empty(n)
    ym = np.empty(n)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    t = 0.0
    f0 = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    J = np.empty((n, n))
    W = np.empty((n, n))
    piv = np.empty(n, np.int64)
    Tt = np.zeros(n)
    Fr = system(kern, ctx, t, y, f0, J, Tt, True)
    ts[0] = 0.0
    ys[0] = y
    Fs[0] = Fr
    h = h0
    i = 0
    n_rej = 0
    while t < T:
        if i >= max_steps:
            return ts[: i + 1], ys[: i + 1], Fs[: i + 1], -1, n_rej
        if t + h > T:
            h = T - t
        hd = h * d
        for a in range(n):
            for b in range(n):
                W[a, b] = -h * d * J[a, b]
            W[a, a] += 1.0
        lu_factor_small(W, piv)
        for a in range(n):
            k1[a] = f0[a] + hd * Tt[a]
        lu_solve_factored(W, piv, k1)
        hh = 0.5 * h
        for a in range(n):
            ym[a] = y[a] + hh * k1[a]
        system(kern, ctx, t + 0.5 * h, ym, f1, J, Tt, False)
        for a in range(n):
            k2[a] = f1[a] - k1[a]
        lu_solve_factored(W, piv, k2)
        for a in range(n):
            k2[a] = k2[a] + k1[a]
            yn[a] = y[a] + h * k2[a]
        system(kern, ctx, t + h, yn, f2, J, Tt, False)
        for a in range(n):
            k3[a] = f2[a] - e32 * (k2[a] - f1[a]) - 2.0 * (k1[a] - f0[a]) + hd * Tt[a]
        lu_solve_factored(W, piv, k3)
        err = 0.0
        for a in range(n):
            sc = atol[a] + rtol * max(abs(y[a]), abs(yn[a]))
            e = h / 6.0 * (k1[a] - 2.0 * k2[a] + k3[a]) / sc
            err = max(err, abs(e))
        if err <= 1.0 or h < 1e-22:
            t = t + h
            for a in range(n):
                y[a] = yn[a]
            Fr = system(kern, ctx, t, y, f0, J, Tt, True)
            i += 1
            if i >= ts.shape[0]:  # grow the output by doubling
                cap = min(2 * ts.shape[0], max_steps + 1)
                ts2 = np.empty(cap)
                ys2 = np.empty((cap, n))
                Fs2 = np.empty(cap)
                ts2[:i] = ts[:i]
                ys2[:i] = ys[:i]
                Fs2[:i] = Fs[:i]
                ts, ys, Fs = ts2, ys2, Fs2
            ts[i] = t
            ys[i] = y
            Fs[i] = Fr
            fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * err ** (-1.0 / 3.0)))
            h = min(h * fac, hmax)
        else:
            n_rej += 1
            h = h * max(0.1, 0.8 * err ** (-1.0 / 3.0))
    return ts[: i + 1], ys[: i + 1], Fs[: i + 1], i, n_rej


__all__ = ["lu_factor_small", "lu_solve_factored", "lu_solve_small", "ros23", "stable_identity"]
