"""Benchmark: the shared Rosenbrock integrator's step (session 65) against the step as it was, in this process.

Until session 65 ``schemes.rosenbrock.ros23`` eliminated ``W`` once per stage (three times per step,
``lu_solve_small``), allocated some 25 small arrays per step (every vector expression) and allocated its output
for ``max_steps`` rows on every call (2e6 x 5 doubles, 80 MB, for the diagnosis' FFM paths). Now ``W`` is factored
once per step (``lu_factor_small``, ``lu_solve_factored``), the stages live in buffers allocated once per call and
the output grows by doubling. The arithmetic is the same, bit for bit: this script checks that every output array
is identical before it times anything.

The old step is kept here (``ros23_as_before``, a copy of the session-64 code) as the reference. Cases, each a
model the diagnosis integrates (``probedyn.diagnose.friction``):

* the 1D Prandtl-Tomlinson path of the three-scan example's slow scan (trace and retrace, k = 1 N/m, m = 1e-12 kg,
  Q = 1, a = 0.5 nm, eta ~ 5.4, V = 23 nm/s, the diagnosis' tolerances 1e-5, steps at most half a sample);
* the same with the diagnosis' ``max_steps`` (2e6), where the old step also paid the output allocation;
* the 2D misaligned lattice (``schemes.ffm_lattice2d``, k_y = 2.5 k_x, 10 degrees; four states);
* the source's bristle line scan (Table 2.1, 72 nm; ``schemes.ffm.line_scan``'s defaults).

Run:  .venv/bin/python benchmarks/rosenbrock_stages.py   (about 20 s; prints one line per case and a JSON record)
"""

from __future__ import annotations

import json
import math
import time

import numpy as np
from numba import njit

from probedyn.schemes import ffm as FFM_MOD
from probedyn.schemes import ffm_lattice2d as L2D
from probedyn.schemes.rosenbrock import lu_solve_small, ros23


@njit
def ros23_as_before(system, kern, ctx, T, y0, rtol, atol, h0, hmax, max_steps):
    """``ros23`` as it was until session 64 (the reference of this benchmark)."""
    d = 1.0 / (2.0 + math.sqrt(2.0))
    e32 = 6.0 + math.sqrt(2.0)
    n = y0.shape[0]
    ts = np.empty(max_steps + 1)
    ys = np.empty((max_steps + 1, n))
    Fs = np.empty(max_steps + 1)
    y = y0.copy()
    t = 0.0
    f0 = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    J = np.empty((n, n))
    W = np.empty((n, n))
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
        for a in range(n):
            for b in range(n):
                W[a, b] = -h * d * J[a, b]
            W[a, a] += 1.0
        k1 = lu_solve_small(W, f0 + h * d * Tt)
        ym = y + 0.5 * h * k1
        system(kern, ctx, t + 0.5 * h, ym, f1, J, Tt, False)
        k2 = lu_solve_small(W, f1 - k1) + k1
        yn = y + h * k2
        system(kern, ctx, t + h, yn, f2, J, Tt, False)
        k3 = lu_solve_small(W, f2 - e32 * (k2 - f1) - 2.0 * (k1 - f0) + h * d * Tt)
        err = 0.0
        for a in range(n):
            sc = atol[a] + rtol * max(abs(y[a]), abs(yn[a]))
            e = h / 6.0 * (k1[a] - 2.0 * k2[a] + k3[a]) / sc
            err = max(err, abs(e))
        if err <= 1.0 or h < 1e-22:
            t = t + h
            y = yn
            Fr = system(kern, ctx, t, y, f0, J, Tt, True)
            i += 1
            ts[i] = t
            ys[i] = y
            Fs[i] = Fr
            fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * err ** (-1.0 / 3.0)))
            h = min(h * fac, hmax)
        else:
            n_rej += 1
            h = h * max(0.1, 0.8 * err ** (-1.0 / 3.0))
    return ts[: i + 1], ys[: i + 1], Fs[: i + 1], i, n_rej


def _pt_case(max_steps: int):
    """The example's slow scan as one segment of the diagnosis' PT path (trace: 8 periods after a 2-period roll)."""
    a, k, m, V = 5e-10, 1.0, 1e-12, 2.318870427908512e-08
    U0 = 5.443 * k * a * a / (4 * math.pi**2)
    c = math.sqrt(m * k)  # Q = 1
    fm = FFM_MOD.FFM.from_preset("mica", "pt", {"U0": U0, "a": a, "k_x": k, "m_x": m, "c_x": c, "V": V}).friction
    T = 10 * a / V
    dX = a / 40  # the record's sample spacing; the step at most half of it
    atol = np.array([1e-5 * (2 * math.pi / a) * U0 / k, 100 * V, 1e-5])
    ctx = (fm.pack(), m, c, k, V, 0.0)
    return FFM_MOD._system, fm.kernel, ctx, T, np.zeros(3), 1e-5, atol, 1e-3 * math.sqrt(m / k), 0.5 * dX / V, max_steps


def _lattice_case():
    a, kx, m, V, th = 5e-10, 1.0, 1e-12, 2.318870427908512e-08, math.radians(10.0)
    U0 = 5.443 * kx * a * a / (4 * math.pi**2)
    q = 2 * math.pi / a
    c = math.sqrt(m * kx)
    p = np.array([U0, q, math.cos(th), math.sin(th), 0.0, 0.0, m, c, c, kx, 2.5 * kx, 0.0])
    T = 10 * a / V
    atol = np.array([1e-5 * q * U0 / kx] * 2 + [100 * V] * 2)
    return L2D._system, None, (p, V, 0.0), T, np.zeros(4), 1e-5, atol, 1e-3 * math.sqrt(m / (2.5 * kx)), \
        0.5 * a / 40 / V, 200_000


def _bristle_case():
    ffm = FFM_MOD.FFM.from_preset("mica", "bristle")
    cp, fm = ffm.cantilever, ffm.friction
    m, c, k, V = cp["m_x"], cp["c_x"], cp["k_x"], cp["V"]
    T = 72e-9 / V
    return (FFM_MOD._system, fm.kernel, (fm.pack(), m, c, k, V, 0.0), T, np.zeros(3), 1e-5,
            FFM_MOD._atol(ffm, 1e-7), 1e-3 * math.sqrt(m / k), T / 50.0, 5_000_000)


def _time(fn, args, repeat: int) -> float:
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn(*args)
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    cases = [("PT path, example slow scan (max_steps 2e5)", _pt_case(200_000)),
             ("PT path, example slow scan (max_steps 2e6, the diagnosis')", _pt_case(2_000_000)),
             ("2D misaligned lattice (k_y = 2.5 k_x, 10 deg)", _lattice_case()),
             ("bristle line scan, Table 2.1, 72 nm", _bristle_case())]
    rows = []
    for name, args in cases:
        new, old = ros23(*args), ros23_as_before(*args)  # compiled here, outside the timing
        assert new[3] == old[3] and new[4] == old[4]
        for x, y in zip(new[:3], old[:3]):
            assert np.array_equal(x, y), name  # the same arithmetic, bit for bit
        t_new, t_old = _time(ros23, args, 7), _time(ros23_as_before, args, 7)
        steps = int(new[3]) + int(new[4])
        rows.append(dict(case=name, steps=int(new[3]), rejected=int(new[4]), old_s=t_old, new_s=t_new,
                         ratio=t_old / t_new, new_us_per_step=1e6 * t_new / steps))
        print(f"{name:62s} steps {new[3]:6d} (+{new[4]} rejected)  before {1e3 * t_old:7.2f} ms  "
              f"now {1e3 * t_new:7.2f} ms  ratio {t_old / t_new:4.2f}  ({1e6 * t_new / steps:.3f} us per step)")
    print(json.dumps({"benchmark": "rosenbrock_stages", "rows": rows}))


if __name__ == "__main__":
    main()
