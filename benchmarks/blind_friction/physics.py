"""Own physics for the blind friction generator (session 46, written blind from docs only).

Prandtl-Tomlinson tip with inertia and thermal noise, integrated by a BAOAB Langevin splitting
(Leimkuhler-Matthews), compiled with numba.  Conventions:

  corrugation  U(x) = -(U0/2) cos(2 pi x / a)          (U0 = peak-to-peak barrier)
  eta          = 2 pi^2 U0 / (k a^2)                   (stick-slip for eta > 1)
  equation     m x'' = -U'(x) + k (X_true - x) + c (X_true' - x') - gamma x' + xi(t)
               <xi(t) xi(t')> = 2 (c + gamma) kB T delta(t - t')
  lateral force (what the lever's torsion shows)  F = k (X_true - x)

X_true is the support's true position; the recorded one X_rec moves uniformly in time, and
X_true = X_rec + bow (X_rec - Xb0)(Xb1 - X_rec)/(Xb1 - Xb0) (scanner bow, zero unless hidden).

2-D version (lattice misalignment): U = -(U0/2)[cos(q x') + cos(q y')], (x', y') the lattice frame
rotated by theta from the scan frame (x along the scan), lever springs k_x (scan) and k_y
(transverse, support fixed at Y0), damping c_x, c_y, one tip mass.
"""
import math

import numpy as np
from numba import njit

KB = 1.380649e-23


@njit(cache=True)
def seed_rng(s):
    np.random.seed(s)


@njit(cache=True)
def run_1d(x, v, t0, Xstart, dirn, V, n_samp, n_sub, dt, m, k, c, gam, U0, a, kT,
           bow, Xb0, Xb1, point, out_f, out_t, ev_X, ev_t, ev_n, nw):
    """Integrate one support sweep. Returns (x, v, t, n_events, nw).

    out_f[j]: interval mean (point=0) or centre-time value (point=1) of k (X_true - x).
    Events: entry of the tip into a new well (|x - n a| < 0.2 a, n != current well)."""
    q = 2.0 * math.pi / a
    A = 0.5 * U0 * q
    G = c + gam
    e1 = math.exp(-G * dt / m)
    sd = math.sqrt(kT / m * (1.0 - e1 * e1)) if kT > 0 else 0.0
    Lb = Xb1 - Xb0
    t = t0
    ne = 0
    # initial force
    Xr = Xstart
    Xt = Xr + bow * (Xr - Xb0) * (Xb1 - Xr) / Lb
    Vt = dirn * V * (1.0 + bow * (Xb0 + Xb1 - 2.0 * Xr) / Lb)
    F = -A * math.sin(q * x) + k * (Xt - x) + c * Vt
    half = n_sub // 2
    for j in range(n_samp):
        acc = 0.0
        for i in range(n_sub):
            v += 0.5 * dt * F / m
            x += 0.5 * dt * v
            if sd > 0.0:
                v = e1 * v + sd * np.random.standard_normal()
            else:
                v = e1 * v
            x += 0.5 * dt * v
            t += dt
            Xr = Xstart + dirn * V * (t - t0)
            Xt = Xr + bow * (Xr - Xb0) * (Xb1 - Xr) / Lb
            Vt = dirn * V * (1.0 + bow * (Xb0 + Xb1 - 2.0 * Xr) / Lb)
            F = -A * math.sin(q * x) + k * (Xt - x) + c * Vt
            v += 0.5 * dt * F / m
            lat = k * (Xt - x)
            acc += lat
            if point == 1 and i == half:
                out_f[j] = lat
            # well tracking
            nn = math.floor(x / a + 0.5)
            if nn != nw and abs(x - nn * a) < 0.2 * a:
                if ne < ev_X.shape[0]:
                    ev_X[ne] = Xt
                    ev_t[ne] = t
                    ev_n[ne] = nn
                ne += 1
                nw = nn
        if point == 0:
            out_f[j] = acc / n_sub
        out_t[j] = t - 0.5 * n_sub * dt
    return x, v, t, ne, nw


@njit(cache=True)
def run_2d(x, y, vx, vy, t0, Xstart, Y0, dirn, V, n_samp, n_sub, dt, m, kx, ky, cx, cy,
           U0, a, theta, phx, phy, kT, point, out_f, out_t):
    q = 2.0 * math.pi / a
    A = 0.5 * U0 * q
    ct = math.cos(theta)
    st = math.sin(theta)
    ex = math.exp(-cx * dt / m)
    ey = math.exp(-cy * dt / m)
    sdx = math.sqrt(kT / m * (1.0 - ex * ex)) if kT > 0 else 0.0
    sdy = math.sqrt(kT / m * (1.0 - ey * ey)) if kT > 0 else 0.0
    t = t0
    Xt = Xstart
    # lattice frame: xp = ct x + st y, yp = -st x + ct y
    xp = ct * x + st * y + phx
    yp = -st * x + ct * y + phy
    gxp = A * math.sin(q * xp)
    gyp = A * math.sin(q * yp)
    Fx = -(gxp * ct - gyp * st) + kx * (Xt - x) + cx * dirn * V
    Fy = -(gxp * st + gyp * ct) + ky * (Y0 - y)
    half = n_sub // 2
    for j in range(n_samp):
        acc = 0.0
        for i in range(n_sub):
            vx += 0.5 * dt * Fx / m
            vy += 0.5 * dt * Fy / m
            x += 0.5 * dt * vx
            y += 0.5 * dt * vy
            if sdx > 0.0:
                vx = ex * vx + sdx * np.random.standard_normal()
                vy = ey * vy + sdy * np.random.standard_normal()
            else:
                vx = ex * vx
                vy = ey * vy
            x += 0.5 * dt * vx
            y += 0.5 * dt * vy
            t += dt
            Xt = Xstart + dirn * V * (t - t0)
            xp = ct * x + st * y + phx
            yp = -st * x + ct * y + phy
            gxp = A * math.sin(q * xp)
            gyp = A * math.sin(q * yp)
            Fx = -(gxp * ct - gyp * st) + kx * (Xt - x) + cx * dirn * V
            Fy = -(gxp * st + gyp * ct) + ky * (Y0 - y)
            vx += 0.5 * dt * Fx / m
            vy += 0.5 * dt * Fy / m
            lat = kx * (Xt - x)
            acc += lat
            if point == 1 and i == half:
                out_f[j] = lat
        if point == 0:
            out_f[j] = acc / n_sub
        out_t[j] = t - 0.5 * n_sub * dt
    return x, y, vx, vy, t


# ----------------------------------------------------------------------------------------------
# quasi-static PT landscape (1-D)

def eta_of(U0, k, a):
    return 2.0 * math.pi ** 2 * U0 / (k * a * a)


def critical_force(U0, k, a):
    """Quasi-static (athermal) peak lateral force k a sqrt(eta^2-1)/(2 pi) and spinodal support X*."""
    eta = eta_of(U0, k, a)
    if eta <= 1:
        return 0.0, None
    phis = math.acos(-1.0 / eta)
    F = math.pi * U0 / a * math.sin(phis)
    return F, a * phis / (2 * math.pi) + F / k


def forward_barrier(Xrel, U0, k, a):
    """Barrier (J) from the well whose minimum tends to x = 0 to the forward saddle, for support
    positions Xrel (array); NaN where the well does not exist. Vectorised bisection on the phase."""
    eta = eta_of(U0, k, a)
    phis = math.acos(-1.0 / eta)
    Xrel = np.asarray(Xrel, float)

    def g(phi):
        return math.pi * U0 / a * np.sin(phi) - k * (Xrel - a * phi / (2 * math.pi))

    def bisect(lo, hi, increasing):
        lo = np.full_like(Xrel, lo)
        hi = np.full_like(Xrel, hi)
        for _ in range(70):
            mid = 0.5 * (lo + hi)
            gm = g(mid)
            up = (gm < 0) if increasing else (gm > 0)
            lo = np.where(up, mid, lo)
            hi = np.where(up, hi, mid)
        return 0.5 * (lo + hi)

    pmin = bisect(-phis, phis, True)
    pmax = bisect(phis, 2 * math.pi - phis, False)

    def E(phi):
        xx = a * phi / (2 * math.pi)
        return -0.5 * U0 * np.cos(phi) + 0.5 * k * (Xrel - xx) ** 2

    dE = E(pmax) - E(pmin)
    ok = (g(np.full_like(Xrel, -phis)) < 0) & (g(np.full_like(Xrel, phis)) > 0)
    dE = np.where(ok, dE, np.nan)
    return dE, pmin, pmax


def kramers_prefactor(Xrel, U0, k, a, m, G):
    """Kramers (moderate damping, Grote-Hynes/Kramers) rate prefactor at support Xrel:
    omega_w/(2 pi) * (sqrt(G'^2/4 + omega_b^2) - G'/2)/omega_b, G' = G/m."""
    dE, pmin, pmax = forward_barrier(np.atleast_1d(Xrel), U0, k, a)
    q = 2 * math.pi / a
    kw = 0.5 * U0 * q * q * np.cos(pmin) + k
    kb = -(0.5 * U0 * q * q * np.cos(pmax) + k)
    ww = np.sqrt(kw / m)
    wb = np.sqrt(kb / m)
    g = G / m
    return ww / (2 * math.pi) * (np.sqrt(g * g / 4 + wb * wb) - g / 2) / wb
