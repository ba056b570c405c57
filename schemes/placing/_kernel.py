"""Compiled kernels of the release simulation (:mod:`.release`): the full Maugis-Dugdale force
with its hysteresis, the equations of motion with their analytic Jacobian, and a linearly
implicit Rosenbrock integrator (ode23s, Shampine & Reichelt 1997; L-stable, order 2(3)) with
event location for the contact transitions and the release / recapture decisions.

Scaled variables (see :mod:`.release`): lengths in the Maugis penetration unit ``l``, forces in
``pi W R``, masses in the sample mass ``M``, time in ``tau = sqrt(M l / (pi W R))``.

State ``z = [q_1..q_N, delta, q_1'..q_N', delta']``: ``q_n`` the tip-normalised probe modal
coordinates (tip height ``h = D + sum q_n``), ``delta = y - h`` the penetration of the sample
(position ``y``) into the tip. Contact state ``s``: 1 in contact (stable MD branch down to the
jump-out penetration ``D_min``), 0 out of contact (van der Waals tail up to the jump-in
penetration ``D0``).

Parameter vector ``par`` (float64):

==  ==============================================================
0   D     mean tip height above the substrate (gap budget)
1   F0    drive force amplitude on the tip
2   w     drive frequency
3   phi   drive phase
4   cc    contact damping coefficient (in contact only)
5   g     sample weight
6   S     substrate attraction coefficient ``S / (y - z0)^2``
7   z0    cut-off of the substrate law
8   Dmin  jump-out penetration (end of the stable branch)
9   D0    jump-in penetration (end of the tail)
10  tz    tail coefficient ``2 z0_bar^2``
11  tg    tail gap origin ``d0 + D0``
12  du    spline step in ``u = sqrt(delta - Dmin)``
13  hlow  lowest tip height (escape check)
14  gm    margin below ``hlow`` before the escape check applies
15  Vb    potential energy at the barrier (escape check)
16  yb    barrier height
17  Tend  end of the attached phase (no separation by then: attached)
18  Tfly  extra time allowed after a separation
==  ==============================================================
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NPAR = 19


@njit(cache=True)
def md_force(delta, s, par, Pn, dPn):
    """Contact force ``P`` (positive repulsive) and ``dP/ddelta`` in contact state ``s``."""
    Dmin = par[8]
    if s == 1:
        x = delta - Dmin
        if x < 0.0:
            x = 0.0
        u = math.sqrt(x)
        du = par[12]
        n = Pn.shape[0]
        j = int(u / du)
        if j >= n - 1:
            # linear extrapolation in u beyond the table (not reached in practice)
            j = n - 2
            P = Pn[n - 1] + dPn[n - 1] * (u - du * (n - 1))
            dPdu = dPn[n - 1]
        else:
            t = (u - j * du) / du
            p0, p1 = Pn[j], Pn[j + 1]
            m0, m1 = dPn[j] * du, dPn[j + 1] * du
            t2 = t * t
            t3 = t2 * t
            P = (2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * m1
            dPdu = ((6 * t2 - 6 * t) * p0 + (3 * t2 - 4 * t + 1) * m0 + (-6 * t2 + 6 * t) * p1
                    + (3 * t2 - 2 * t) * m1) / du
        uu = u if u > 1e-9 else 1e-9
        return P, dPdu / (2.0 * uu)
    gap = par[11] - delta
    if gap < 1e-9:
        gap = 1e-9
    P = -par[10] / (gap * gap)
    return P, -2.0 * par[10] / (gap * gap * gap)


@njit(cache=True)
def tail_potential(delta, par):
    """Potential of the tail force on the sample, ``int P d delta = -2 z0^2 / gap``."""
    gap = par[11] - delta
    return -par[10] / gap


@njit(cache=True)
def rhs_jac(t, z, s, par, mm, kk, cn, Pn, dPn, f, J, Tt, want_jac):
    """``f = dz/dt``; with ``want_jac`` also ``J = df/dz`` and ``Tt = df/dt``. Returns the
    contact force (with damping) on the tip."""
    N = mm.shape[0]
    n = 2 * (N + 1)
    delta = z[N]
    ddelta = z[2 * N + 1]
    P, dP = md_force(delta, s, par, Pn, dPn)
    cc = par[4] if s == 1 else 0.0
    Fc = P + cc * ddelta
    y = par[0] + delta
    for i in range(N):
        y += z[i]
    gy = y - par[7]
    if gy < 1e-9:
        gy = 1e-9
    Fsub = -par[6] / (gy * gy)
    dFsub = 2.0 * par[6] / (gy * gy * gy)
    wt = par[2] * t + par[3]
    Fd = par[1] * math.sin(wt)
    dFd = par[1] * par[2] * math.cos(wt)
    yddot = -Fc - par[5] + Fsub
    sq = 0.0
    for i in range(N):
        qdd = (Fd + Fc - cn[i] * z[N + 1 + i] - kk[i] * z[i]) / mm[i]
        f[i] = z[N + 1 + i]
        f[N + 1 + i] = qdd
        sq += qdd
    f[N] = ddelta
    f[2 * N + 1] = yddot - sq
    if want_jac:
        for a in range(n):
            Tt[a] = 0.0
            for b in range(n):
                J[a, b] = 0.0
        st = 0.0
        for i in range(N):
            J[i, N + 1 + i] = 1.0
            J[N + 1 + i, i] = -kk[i] / mm[i]
            J[N + 1 + i, N + 1 + i] = -cn[i] / mm[i]
            J[N + 1 + i, N] = dP / mm[i]
            J[N + 1 + i, 2 * N + 1] = cc / mm[i]
            Tt[N + 1 + i] = dFd / mm[i]
            st += dFd / mm[i]
        J[N, 2 * N + 1] = 1.0
        r = 2 * N + 1
        # y'' part
        for i in range(N):
            J[r, i] = dFsub
        J[r, N] = -dP + dFsub
        J[r, 2 * N + 1] = -cc
        # minus sum of q'' rows
        for i in range(N):
            for b in range(n):
                J[r, b] -= J[N + 1 + i, b]
        Tt[r] = -st
    return Fc


@njit(cache=True)
def _lu(A, piv):
    n = A.shape[0]
    for i in range(n):
        p = i
        best = abs(A[i, i])
        for r in range(i + 1, n):
            if abs(A[r, i]) > best:
                best = abs(A[r, i])
                p = r
        piv[i] = p
        if p != i:
            for c in range(n):
                tmp = A[i, c]
                A[i, c] = A[p, c]
                A[p, c] = tmp
        d = A[i, i]
        if d == 0.0:
            d = 1e-300
            A[i, i] = d
        for r in range(i + 1, n):
            A[r, i] /= d
            fct = A[r, i]
            for c in range(i + 1, n):
                A[r, c] -= fct * A[i, c]


@njit(cache=True)
def _lus(A, piv, b):
    n = A.shape[0]
    x = b.copy()
    for i in range(n):
        p = piv[i]
        if p != i:
            tmp = x[i]
            x[i] = x[p]
            x[p] = tmp
    for i in range(n):
        for c in range(i):
            x[i] -= A[i, c] * x[c]
    for i in range(n - 1, -1, -1):
        for c in range(i + 1, n):
            x[i] -= A[i, c] * x[c]
        x[i] /= A[i, i]
    return x


@njit(cache=True)
def _energy(z, par, N):
    y = par[0] + z[N]
    v = z[2 * N + 1]
    for i in range(N):
        y += z[i]
        v += z[N + 1 + i]
    hl = par[13]
    Vp = tail_potential(y - hl, par)
    Vs = -par[6] / (y - par[7])
    return 0.5 * v * v + Vp + Vs + par[5] * y, y, v


@njit(cache=True)
def simulate(z0, s0, par, mm, kk, cn, Pn, dPn, rtol, atol, h0, hmax, max_steps, record, max_rec):
    """Integrate from ``z0`` (contact state ``s0``) until a decision.

    Returns ``(outcome, t, z, s, t_sep, n_steps, n_rej, min_P, Iy, Xy, ts, zs, ss, Fs, n_rec)``;
    ``Iy`` is the impulse of the tip's force on the sample after the separation (per unit
    sample mass: a velocity) and ``Xy`` its time integral (a length): times ``tan(theta)``
    they give the lateral velocity and displacement a tilted tip imparts (:mod:`.landing`).
    Outcomes: 0 attached (no separation by ``Tend``), 1 recaptured (contact re-formed after a
    separation), 2 released (after a separation, below the tip's lowest point by ``gm`` with
    enough energy to cross the barrier, or below the barrier), 3 undecided (``Tend + Tfly``
    after the separation), -1 too many steps."""
    N = mm.shape[0]
    n = 2 * (N + 1)
    d = 1.0 / (2.0 + math.sqrt(2.0))
    e32 = 6.0 + math.sqrt(2.0)
    f0 = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    J = np.empty((n, n))
    Tt = np.empty(n)
    W = np.empty((n, n))
    piv = np.empty(n, dtype=np.int64)
    ts = np.empty(max_rec if record else 1)
    zs = np.empty((max_rec if record else 1, n))
    ss = np.empty(max_rec if record else 1, dtype=np.int64)
    Fs = np.empty(max_rec if record else 1)
    n_rec = 0
    z = z0.copy()
    s = s0
    t = 0.0
    Fc = rhs_jac(t, z, s, par, mm, kk, cn, Pn, dPn, f0, J, Tt, True)
    min_P = Fc
    if record:
        ts[0] = t
        zs[0] = z
        ss[0] = s
        Fs[0] = Fc
        n_rec = 1
    h = h0
    t_sep = -1.0
    n_acc = 0
    n_rej = 0
    Tend = par[17]
    outcome = -1
    Iy = 0.0
    Xy = 0.0
    while True:
        if n_acc + n_rej >= max_steps:
            outcome = -1
            break
        T_lim = Tend if t_sep < 0 else t_sep + par[18]
        if t >= T_lim:
            outcome = 0 if t_sep < 0 else 3
            break
        if t + h > T_lim:
            h = T_lim - t
        # one ode23s step
        for a in range(n):
            for b in range(n):
                W[a, b] = -h * d * J[a, b]
            W[a, a] += 1.0
        _lu(W, piv)
        k1 = _lus(W, piv, f0 + h * d * Tt)
        ym = z + 0.5 * h * k1
        rhs_jac(t + 0.5 * h, ym, s, par, mm, kk, cn, Pn, dPn, f1, J, Tt, False)
        k2 = _lus(W, piv, f1 - k1) + k1
        yn = z + h * k2
        rhs_jac(t + h, yn, s, par, mm, kk, cn, Pn, dPn, f2, J, Tt, False)
        # J, Tt were not overwritten (want_jac False); rebuild the stage-3 right-hand side
        k3 = _lus(W, piv, f2 - e32 * (k2 - f1) - 2.0 * (k1 - f0) + h * d * Tt)
        err = 0.0
        for a in range(n):
            sc = atol[a] + rtol * max(abs(z[a]), abs(yn[a]))
            e = h / 6.0 * (k1[a] - 2.0 * k2[a] + k3[a]) / sc
            if abs(e) > err:
                err = abs(e)
        if not (err <= 1.0) and h > 1e-14:
            n_rej += 1
            if err != err:
                h *= 0.1
            else:
                h *= max(0.1, 0.8 * err ** (-1.0 / 3.0))
            continue
        # event: contact transition inside the step?
        dl_new = yn[N]
        thr = par[8] if s == 1 else par[9]
        crossed = (dl_new < thr) if s == 1 else (dl_new > thr)
        if crossed:
            dl_old = z[N]
            gap_new = abs(dl_new - thr)
            if gap_new > 1e-7 * (1.0 + abs(thr)) and h > 1e-14:
                theta = (dl_old - thr) / (dl_old - dl_new)
                if theta < 0.02:
                    theta = 0.02
                if theta > 0.999:
                    theta = 0.999
                h = h * theta * (1.0 + 1e-7)
                n_rej += 1
                continue
        t = t + h
        z = yn
        n_acc += 1
        Fc_old = Fc
        s_old = s
        if crossed:
            if s == 1:
                s = 0
                if t_sep < 0:
                    t_sep = t
            else:
                s = 1
                outcome = 1
        Fc = rhs_jac(t, z, s, par, mm, kk, cn, Pn, dPn, f0, J, Tt, True)
        if s_old == 0 and s == 0:
            I_old = Iy
            Iy += -0.5 * (Fc_old + Fc) * h
            Xy += 0.5 * (I_old + Iy) * h
        elif t_sep >= 0:
            Xy += Iy * h
        if s == 1 and Fc < min_P:
            min_P = Fc
        if record and n_rec < max_rec:
            ts[n_rec] = t
            zs[n_rec] = z
            ss[n_rec] = s
            Fs[n_rec] = Fc
            n_rec += 1
        if outcome == 1:
            break
        if s == 0 and t_sep >= 0:
            E, y, v = _energy(z, par, N)
            if y < par[16] and v < 0:
                outcome = 2
                break
            if y < par[13] - par[14] and v < 0 and E > par[15]:
                outcome = 2
                break
        fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.8 * err ** (-1.0 / 3.0)))
        h = min(h * fac, hmax)
        if crossed:
            h = max(h * 1e-3, 1e-9)
    return (outcome, t, z, s, t_sep, n_acc, n_rej, min_P, Iy, Xy, ts[:n_rec], zs[:n_rec], ss[:n_rec], Fs[:n_rec],
            n_rec)
