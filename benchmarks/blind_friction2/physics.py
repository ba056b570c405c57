"""Independent friction physics for the blind_friction2 test-data generator.

Written only from docs/diagnose.md sec. 1 (formats) and sec. 3 (catalog); nothing of probedyn is
imported or read.  numpy / scipy / numba only.

Atomic stick-slip (Prandtl-Tomlinson with inertia and a Langevin bath)
------------------------------------------------------------------------
    m x'' = -dU/dx + k (X(t) - x) + c (X'(t) - x') - gamma_s x' + R(t)
    U(x)  = -(U0/2) cos(2 pi x / a)         (U0 peak-to-peak, eta = 2 pi^2 U0 / (k a^2))
    <R(t) R(t')> = 2 (c + gamma_s) kB T delta(t - t')
The lever damping c acts on the velocity relative to the support (docs sec. 1, [lever]); the
optional gamma_s is a viscous tip-substrate friction (relative to the sample: the catalog's
`viscous-friction`).  The recorded lateral force is the lever's spring force k (X - x), positive where
the lever is bent back against the trace's motion.

Integrator ("exact-OU splitting", Strang):  half kick of the lattice force  ->  exact stochastic flow of
the *linear* part (spring to the moving support + both dampings + thermal force) over dt  ->  half kick.
The linear part is an Ornstein-Uhlenbeck process for the deviation from its steady sliding solution
x_p = X(t) - gamma_s V / k, v_p = V (X linear within a step; the support path is piecewise linear, a
change of V at a turn only changes the variables between steps).  Its propagator expm(A dt) and its
noise covariance Sigma_dt = Sigma_eq - P Sigma_eq P^T (Sigma_eq = diag(kBT/k, kBT/m)) are exact for any
dt, so:
  * equipartition in a harmonic well is exact at any dt and any damping (checked: <k x^2>/kBT = 1 for
    Q = 0.05, 1, 20; see checks.py);
  * weak damping: for Q -> infinity it reduces to a symplectic Strang split (kick-rotate-kick), energy
    conserving to O(dt^2) (checked: the Boltzmann distribution of the lever force in the full lattice
    potential at Q = 20);
  * strong damping: a velocity kick dv = dt F/(2m) relaxes inside the OU flow and displaces the tip by
    m dv / (c+gamma_s) = dt F / (2 (c+gamma_s)); two half kicks give x += dt F/(c+gamma_s): the correct
    overdamped (Smoluchowski) drift, with the exact OU diffusion kBT/(c+gamma_s) (checked: the T = 0
    mobility in a tilted washboard against the analytic sqrt(F^2 - Fc^2)/gamma, and the free diffusion
    coefficient; checks.py).  BAOAB, by contrast, diffuses with kBT dt/(2m) in that limit, and plain
    Euler-Maruyama is unstable there, which is why neither was used.

2D (lattice misalignment): a square lattice U = -(U0/2)[cos(2 pi xi/a) + cos(2 pi zeta/a)] with the
lattice axes (xi, zeta) rotated by theta from the scan axis x; the tip on two lever springs, k_x along the
scan and k_y = ky_ratio k_x across it (the support fixed in y), each with its own damping relative to the
support (c_y chosen so that Q_y = Q_x with the same mass m).  The same split, per axis.

Mesoscale friction loops: a quasi-static spring-block (the lever k_x in series with a contact stiffness
k_c) on a surface of height h(x) with local Coulomb friction mu(x) (N + N_adh): Ogletree et al. (1996)
force balance on the local slope t = dh/dx,
    uphill sliding   L_+ = N (t + mu_eff) / (1 - mu_eff t),   downhill  L_- = N (t - mu_eff) / (1 + mu_eff t),
mu_eff = mu (N + N_adh)/N.  The tip sticks until the lever force reaches the threshold of the current
direction (so every reversal is a stick ramp of slope k_eff), and slides quasi-statically otherwise.  On
top, the unresolved atomic stick-slip: a sawtooth of the lattice period with thermally jittered slip
points (zero mean per period), plus the tip's interval-averaged thermal force noise sqrt(2 kBT c/tau).
Samples are interval means over >= 20 lattice periods.
"""
import math

import numpy as np
from numba import njit
from scipy.linalg import expm

KB = 1.380649e-23


# ----------------------------------------------------------------------------------------------
# linear-part propagator
# ----------------------------------------------------------------------------------------------
def ou_propagator(k, m, ctot, T, dt):
    """Exact propagator P (2x2) and Cholesky factor Lc of the noise covariance of the linear part
    u' = w, w' = -(k/m) u - (ctot/m) w + sqrt(2 ctot kB T)/m xi, over dt."""
    A = np.array([[0.0, 1.0], [-k / m, -ctot / m]])
    P = expm(A * dt)
    if T > 0:
        S_eq = np.diag([KB * T / k, KB * T / m])
        S = S_eq - P @ S_eq @ P.T
        S = 0.5 * (S + S.T)
        # Cholesky (2x2, semidefinite safe)
        l11 = math.sqrt(max(S[0, 0], 0.0))
        l21 = S[1, 0] / l11 if l11 > 0 else 0.0
        l22 = math.sqrt(max(S[1, 1] - l21 * l21, 0.0))
        Lc = np.array([[l11, 0.0], [l21, l22]])
    else:
        Lc = np.zeros((2, 2))
    return P, Lc


@njit(cache=True)
def nb_seed(s):
    np.random.seed(s)


# ----------------------------------------------------------------------------------------------
# 1D PT Langevin over a piecewise-linear support path
# ----------------------------------------------------------------------------------------------
@njit(cache=True)
def _run_1d(x, v, seg_X0, seg_V, seg_nsamp, n_per, dt, P, Lc, k, m, ctot, gam_s,
            U0, a, bow_c, bow_X0, bow_X1, F_ext,
            out_mean, out_point, out_t, ev_X, ev_F, ev_dir, ev_seg, ev_j, max_ev):
    """Run the segments in order.  Segment s: nominal support X_rec = seg_X0[s] + seg_V[s] * t for
    seg_nsamp[s] * n_per steps.  The true support is the bowed map of X_rec.  For each sample interval
    (n_per steps) store the mean lever force and the lever force at its end (point sample) and the time.
    Slip events: the tip crossing x = (j +- 0.6) a out of well j (just past the bare lattice's barrier
    top, a 0.1 a hysteresis against thermal recrossing), storing the true support position then and the
    running max (or min) of the lever force since the previous event (the stick phase's peak)."""
    kick_c = 2.0 * math.pi / a
    fmax = math.pi * U0 / a
    isamp = 0
    t = 0.0
    nev = 0
    j = int(math.floor(x / a + 0.5))
    runmax = -1e300
    runmin = 1e300
    for s in range(seg_X0.shape[0]):
        Vn = seg_V[s]
        for ismp in range(seg_nsamp[s]):
            acc = 0.0
            for st in range(n_per):
                tl0 = (ismp * n_per + st) * dt
                tl1 = tl0 + dt
                Xr0 = seg_X0[s] + Vn * tl0
                Xr1 = seg_X0[s] + Vn * tl1
                Lb = bow_X1 - bow_X0
                if bow_c != 0.0:
                    X0t = Xr0 + bow_c * (Xr0 - bow_X0) * (bow_X1 - Xr0) / Lb
                    X1t = Xr1 + bow_c * (Xr1 - bow_X0) * (bow_X1 - Xr1) / Lb
                else:
                    X0t = Xr0
                    X1t = Xr1
                Vs = (X1t - X0t) / dt
                # half kick
                F = -fmax * math.sin(kick_c * x) + F_ext
                v += 0.5 * dt * F / m
                # exact OU flow of the linear part
                d = gam_s * Vs / k
                u = x - (X0t - d)
                w = v - Vs
                r1 = np.random.standard_normal()
                r2 = np.random.standard_normal()
                un = P[0, 0] * u + P[0, 1] * w + Lc[0, 0] * r1
                wn = P[1, 0] * u + P[1, 1] * w + Lc[1, 0] * r1 + Lc[1, 1] * r2
                x = un + (X1t - d)
                v = wn + Vs
                F = -fmax * math.sin(kick_c * x) + F_ext
                v += 0.5 * dt * F / m
                fl = k * (X1t - x)
                acc += fl
                if fl > runmax:
                    runmax = fl
                if fl < runmin:
                    runmin = fl
                # slip events with hysteresis
                q = x / a - j
                if q > 0.6 or q < -0.6:
                    jn = int(math.floor(x / a + 0.5))
                    if nev < max_ev:
                        ev_X[nev] = X1t
                        if jn > j:
                            ev_F[nev] = runmax
                            ev_dir[nev] = 1
                        else:
                            ev_F[nev] = runmin
                            ev_dir[nev] = -1
                        ev_seg[nev] = s
                        ev_j[nev] = j
                        nev += 1
                    j = jn
                    runmax = -1e300
                    runmin = 1e300
            out_mean[isamp] = acc / n_per
            out_point[isamp] = k * (X1t - x)
            t += n_per * dt
            out_t[isamp] = t
            isamp += 1
    return x, v, nev


@njit(cache=True)
def _run_2d(x, y, vx, vy, seg_X0, seg_V, seg_nsamp, n_per, dt, Px, Lx, Py, Ly, kx, ky, m,
            U0, a, cth, sth, Y0, out_mean, out_point, out_t):
    """2D square lattice at angle theta; support moves along x only (y support fixed at Y0)."""
    q = 2.0 * math.pi / a
    f = math.pi * U0 / a
    isamp = 0
    t = 0.0
    for s in range(seg_X0.shape[0]):
        Vn = seg_V[s]
        for ismp in range(seg_nsamp[s]):
            acc = 0.0
            for st in range(n_per):
                tl0 = (ismp * n_per + st) * dt
                X0t = seg_X0[s] + Vn * tl0
                X1t = X0t + Vn * dt
                xi = cth * x + sth * y
                ze = -sth * x + cth * y
                Fxi = -f * math.sin(q * xi)
                Fze = -f * math.sin(q * ze)
                Fx = cth * Fxi - sth * Fze
                Fy = sth * Fxi + cth * Fze
                vx += 0.5 * dt * Fx / m
                vy += 0.5 * dt * Fy / m
                u = x - X0t
                w = vx - Vn
                r1 = np.random.standard_normal()
                r2 = np.random.standard_normal()
                un = Px[0, 0] * u + Px[0, 1] * w + Lx[0, 0] * r1
                wn = Px[1, 0] * u + Px[1, 1] * w + Lx[1, 0] * r1 + Lx[1, 1] * r2
                x = un + X1t
                vx = wn + Vn
                u = y - Y0
                w = vy
                r1 = np.random.standard_normal()
                r2 = np.random.standard_normal()
                un = Py[0, 0] * u + Py[0, 1] * w + Ly[0, 0] * r1
                wn = Py[1, 0] * u + Py[1, 1] * w + Ly[1, 0] * r1 + Ly[1, 1] * r2
                y = un + Y0
                vy = wn
                xi = cth * x + sth * y
                ze = -sth * x + cth * y
                Fxi = -f * math.sin(q * xi)
                Fze = -f * math.sin(q * ze)
                Fx = cth * Fxi - sth * Fze
                Fy = sth * Fxi + cth * Fze
                vx += 0.5 * dt * Fx / m
                vy += 0.5 * dt * Fy / m
                acc += kx * (X1t - x)
            out_mean[isamp] = acc / n_per
            out_point[isamp] = kx * (X1t - x)
            t += n_per * dt
            out_t[isamp] = t
            isamp += 1
    return x, y, vx, vy


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------
def eta_of(U0, k, a):
    return 2 * math.pi ** 2 * U0 / (k * a * a)


def U0_of(eta, k, a):
    return eta * k * a * a / (2 * math.pi ** 2)


def pt_threshold(U0, k, a):
    """Quasi-static athermal PT peak force: (pi U0/a) sqrt(1 - 1/eta^2) (eta > 1)."""
    eta = eta_of(U0, k, a)
    return math.pi * U0 / a * math.sqrt(max(0.0, 1 - 1 / eta ** 2))


def choose_dt(k, m, U0, a, c, gam_s, n_per_period=60, ky=None):
    """dt = 1/n_per_period of the fastest period, sqrt((k + max lattice curvature)/m).  In the strongly
    damped case dt is then far below the lattice relaxation time (c+gamma)/(k + curvature), which is what
    the kick split needs there (dt/tau = (2 pi/n) Q sqrt(1+eta) for gamma = 0)."""
    curv = 2 * math.pi ** 2 * U0 / (a * a)
    kk = k if ky is None else max(k, ky)
    if ky is not None:
        curv *= 2.0
    w = math.sqrt((kk + curv) / m)
    return 2 * math.pi / w / n_per_period


def simulate_atomic_scan(p, speed, X0, L, n_samp, rng_seed, pre_periods=3.0, ky_ratio=None,
                         theta=0.0, with_retrace=True, dt_max=None):
    """One scan: pre-roll backwards into X0 (so the trace starts at a reversal), trace X0 -> X0+L with
    n_samp samples, then (optionally) retrace.  p: dict with k, m, c, gam_s, U0, a, T, bow.
    Returns dict with per-sample mean and point force (noise free), sample times (from the scan's start
    of the trace), the nominal interval-centre and point positions, directions, and slip events."""
    k, m, c, gs, U0, a, T = p["k"], p["m"], p["c"], p.get("gam_s", 0.0), p["U0"], p["a"], p["T"]
    bow = p.get("bow", 0.0)
    ctot = c + gs
    tau_s = (L / n_samp) / speed
    if dt_max is None:
        dt_max = choose_dt(k, m, U0, a, c, gs, ky=None if ky_ratio is None else ky_ratio * k)
    n_per = max(1, int(math.ceil(tau_s / dt_max)))
    dt = tau_s / n_per
    Lpre = pre_periods * a
    npre = int(math.ceil(Lpre / (L / n_samp)))
    Lpre = npre * L / n_samp
    segX0 = [X0 + Lpre, X0]
    segV = [-speed, speed]
    segN = [npre, n_samp]
    if with_retrace:
        segX0.append(X0 + L)
        segV.append(-speed)
        segN.append(n_samp)
    segX0 = np.array(segX0)
    segV = np.array(segV)
    segN = np.array(segN, dtype=np.int64)
    ntot = int(segN.sum())
    out_mean = np.zeros(ntot)
    out_point = np.zeros(ntot)
    out_t = np.zeros(ntot)
    nb_seed(int(rng_seed) % (2 ** 31))
    rng = np.random.default_rng(rng_seed)
    if ky_ratio is None:
        P, Lc = ou_propagator(k, m, ctot, T, dt)
        # start: equilibrium of the stick branch at the pre-roll start (retrace direction), thermal v
        Xs = X0 + Lpre
        x = Xs + pt_threshold(U0, k, a) * 0.5 / k  # somewhere on the backward stick branch
        x = _relax(x, Xs, k, U0, a)
        v = -speed + (math.sqrt(KB * T / m) * rng.standard_normal() if T > 0 else 0.0)
        max_ev = int(4 * (Lpre + 2 * L) / a + 100)
        ev_X = np.zeros(max_ev)
        ev_F = np.zeros(max_ev)
        ev_dir = np.zeros(max_ev, dtype=np.int64)
        ev_seg = np.zeros(max_ev, dtype=np.int64)
        ev_j = np.zeros(max_ev, dtype=np.int64)
        b0, b1 = X0, X0 + L
        _, _, nev = _run_1d(x, v, segX0, segV, segN, n_per, dt, P, Lc, k, m, ctot, gs, U0, a,
                            bow, b0, b1, 0.0, out_mean, out_point, out_t, ev_X, ev_F, ev_dir, ev_seg,
                            ev_j, max_ev)
        events = dict(X=ev_X[:nev], F=ev_F[:nev], dir=ev_dir[:nev], seg=ev_seg[:nev], j=ev_j[:nev])
    else:
        ky = ky_ratio * k
        cy = c * math.sqrt(ky / k)  # same mass and same Q along y
        Px, Lx = ou_propagator(k, m, c, T, dt)
        Py, Ly = ou_propagator(ky, m, cy, T, dt)
        Y0 = rng.uniform(0, a)
        x, y = _relax2d(X0 + Lpre, Y0, k, ky, U0, a, theta)
        vx = -speed
        vy = 0.0
        _run_2d(x, y, vx, vy, segX0, segV, segN, n_per, dt, Px, Lx, Py, Ly, k, ky, m, U0, a,
                math.cos(theta), math.sin(theta), Y0, out_mean, out_point, out_t)
        events = None
    # bookkeeping of the recorded (nominal) positions
    dX = L / n_samp
    cen = []
    pts = []
    dirs = []
    tstart = []
    for s in range(len(segX0)):
        i = np.arange(segN[s])
        cen.append(segX0[s] + segV[s] / speed * (i + 0.5) * dX)
        pts.append(segX0[s] + segV[s] / speed * (i + 1.0) * dX)
        dirs.append(np.full(segN[s], int(np.sign(segV[s]))))
    cen = np.concatenate(cen)
    pts = np.concatenate(pts)
    dirs = np.concatenate(dirs)
    keep = np.arange(ntot) >= npre
    t_trace0 = npre * tau_s
    return dict(mean=out_mean[keep], point=out_point[keep], t_end=out_t[keep] - t_trace0,
                centre=cen[keep], ptpos=pts[keep], dir=dirs[keep], tau_s=tau_s, dt=dt, n_per=n_per,
                events=events, point_pre=out_point[npre - 1], nsteps=ntot * n_per)


def _relax(x, X, k, U0, a, it=200):
    """Newton relaxation to a local minimum of U + k/2 (x-X)^2 (damped)."""
    for _ in range(it):
        g = math.pi * U0 / a * math.sin(2 * math.pi * x / a) - k * (X - x)
        h = 2 * math.pi ** 2 * U0 / a ** 2 * math.cos(2 * math.pi * x / a) + k
        step = g / h if h > 0 else g / k * 0.2
        step = max(min(step, 0.05 * a), -0.05 * a)
        x -= step
        if abs(step) < 1e-9 * a:
            break
    return x


def _relax2d(X, Y, kx, ky, U0, a, th, it=4000):
    c, s = math.cos(th), math.sin(th)
    x, y = X, Y
    f = math.pi * U0 / a
    q = 2 * math.pi / a
    lr = 0.2 / (max(kx, ky) + 2 * f * q)
    for _ in range(it):
        xi = c * x + s * y
        ze = -s * x + c * y
        Fxi = -f * math.sin(q * xi)
        Fze = -f * math.sin(q * ze)
        gx = -(c * Fxi - s * Fze) - kx * (X - x)
        gy = -(s * Fxi + c * Fze) - ky * (Y - y)
        x -= lr * gx
        y -= lr * gy
    return x, y


# ----------------------------------------------------------------------------------------------
# quasi-static PT barrier and the effective activation prefactor
# ----------------------------------------------------------------------------------------------
def pt_barrier_branch(U0, k, a, n=4000):
    """Forward stick branch of the well at x ~ 0: support X from the branch's zero force to the spinodal.
    Returns X, F = k (X - x_min), dE (barrier to the forward saddle), curvatures at min and saddle."""
    eta = eta_of(U0, k, a)
    q = 2 * math.pi / a
    phic = math.acos(-1 / eta)
    xc = phic / q
    Xc = xc + math.pi * U0 / a * math.sin(phic) / k
    xm = np.linspace(0, xc, n)[:-1]
    Xg = xm + math.pi * U0 / a * np.sin(q * xm) / k
    E = lambda x, X: -(U0 / 2) * np.cos(q * x) + 0.5 * k * (x - X) ** 2
    # saddle: the other root of U'(x) = k (X - x) in (xc, a/2 + ...): Newton from the far side
    xs = np.full_like(xm, 0.5 * a + 0.0)
    xs = np.maximum(xs, xc)
    for _ in range(200):
        g = math.pi * U0 / a * np.sin(q * xs) - k * (Xg - xs)
        h = 2 * math.pi ** 2 * U0 / a ** 2 * np.cos(q * xs) + k
        h = np.where(h < -1e-12 * k, h, -1e-12 * k)
        xs = xs - g / h
        xs = np.clip(xs, xc, a)
    dE = E(xs, Xg) - E(xm, Xg)
    km = 2 * math.pi ** 2 * U0 / a ** 2 * np.cos(q * xm) + k
    ks = 2 * math.pi ** 2 * U0 / a ** 2 * np.cos(q * xs) + k
    return dict(X=Xg, F=k * (Xg - xm), dE=np.maximum(dE, 0), km=km, ks=ks, Xc=Xc)


def median_slip_force(br, f0, T, V):
    """Quasi-static activated slip: hazard f0 exp(-dE/kT) along X = V t; the force at H = ln 2."""
    r = f0 * np.exp(-br["dE"] / (KB * T))
    H = np.concatenate([[0], np.cumsum(0.5 * (r[1:] + r[:-1]) * np.diff(br["X"]))]) / V
    if H[-1] < math.log(2):
        return br["F"][-1]
    return float(np.interp(math.log(2), H, br["F"]))


def fit_log10_f0(br, T, speeds, medF):
    """log10 f0 so that the model median slip forces match the simulated ones (least squares in F)."""
    grid = np.linspace(3, 16, 521)
    best = None
    for lg in grid:
        r = sum((median_slip_force(br, 10 ** lg, T, V) - F) ** 2 for V, F in zip(speeds, medF))
        if best is None or r < best[0]:
            best = (r, lg)
    return best[1]


def kramers_f0(br, F, m, ctot):
    """Kramers (moderate-to-strong damping) prefactor at the stick-branch point of force F."""
    i = int(np.argmin(np.abs(br["F"] - F)))
    wa = math.sqrt(max(br["km"][i], 0) / m)
    wb = math.sqrt(max(-br["ks"][i], 0) / m)
    G = ctot / m
    if wb == 0:
        return float("nan")
    return wa / (2 * math.pi) * (math.sqrt(G * G / 4 + wb * wb) - G / 2) / wb


# ----------------------------------------------------------------------------------------------
# mesoscale friction loop (quasi-static spring-block)
@njit(cache=True)
def _interp_u(x, x0, dx, arr):
    s = (x - x0) / dx
    i = int(math.floor(s))
    if i < 0:
        return arr[0]
    if i >= arr.shape[0] - 1:
        return arr[arr.shape[0] - 1]
    f = s - i
    return arr[i] * (1 - f) + arr[i + 1] * f


@njit(cache=True)
def _qs_block(Xs, keff, g0, gdx, Lp_g, Lm_g):
    """Quasi-static stick / slide of the contact point x under the lever (keff) driven at Xs: stick while
    Lm(x) <= keff (X - x) <= Lp(x), else slide to keff (X - x) = Lp(x) (forward) or Lm(x) (backward)."""
    n = Xs.shape[0]
    F = np.empty(n)
    xt = np.empty(n)
    x = Xs[0] - _interp_u(Xs[0], g0, gdx, Lm_g) / keff
    for i in range(n):
        X = Xs[i]
        Lf = keff * (X - x)
        if Lf > _interp_u(x, g0, gdx, Lp_g):
            for _ in range(8):
                x = X - _interp_u(x, g0, gdx, Lp_g) / keff
        elif Lf < _interp_u(x, g0, gdx, Lm_g):
            for _ in range(8):
                x = X - _interp_u(x, g0, gdx, Lm_g) / keff
        F[i] = keff * (X - x)
        xt[i] = x
    return F, xt
# ----------------------------------------------------------------------------------------------
def friction_loop_scan(p, X0, L, n_samp, speed, height_fn, mu_fn, rng, fine=None):
    """p: k_x, k_c, N, N_adh, a, T, c, saw (sawtooth p-p as a fraction of F_k), jitter.
    height_fn(x) true topography [m]; mu_fn(x) local friction coefficient.  Returns trace then retrace
    interval means of the lever force (noise free, with the atomic sawtooth and the tip's thermal
    force averaged), the interval-mean true height under the tip, and nominal centres."""
    kx, kc, N, Nad, a = p["k_x"], p["k_c"], p["N"], p["N_adh"], p["a"]
    keff = kx * kc / (kx + kc)
    dX = L / n_samp
    if fine is None:
        fine = max(20, int(math.ceil(dX / (a / 10))))
    h = dX / fine
    # path: pre-roll backward over 2 intervals, trace, retrace
    npre = 2 * fine
    Xs = np.concatenate([X0 + h * np.arange(npre, 0, -1), X0 + h * np.arange(0, n_samp * fine + 1),
                         X0 + L - h * np.arange(1, n_samp * fine + 1)])
    # position of the sample bins on the fine path
    ntr = n_samp * fine
    # thresholds tabulated on a uniform grid of tip positions (the loop itself in numba)
    tgrid = np.linspace(X0 - 0.2 * L - 1e-7, X0 + 1.2 * L + 1e-7, 200001)
    hg = height_fn(tgrid)
    t = np.gradient(hg, tgrid)
    mu = mu_fn(tgrid) * (N + Nad) / N
    Lp_g = N * (t + mu) / (1 - mu * t)
    Lm_g = N * (t - mu) / (1 + mu * t)
    F, xt = _qs_block(Xs, keff, tgrid[0], tgrid[1] - tgrid[0], Lp_g, Lm_g)
    # atomic sawtooth on the sliding parts (zero mean per slip period, jittered slip points)
    Fk = mu_fn(xt) * (N + Nad)
    saw = np.zeros_like(F)
    dxt = np.diff(xt, prepend=xt[0])
    sliding = np.abs(dxt) > 0.2 * h
    # slip points along the tip path: a lattice with thermal jitter
    nper = int(L / a) + 50
    jit = p["jitter"] * a * rng.standard_normal(nper)
    edges = X0 - 20 * a + a * np.arange(nper) + jit
    edges.sort()
    idx = np.searchsorted(edges, xt) - 1
    idx = np.clip(idx, 0, nper - 2)
    frac = (xt - edges[idx]) / (edges[idx + 1] - edges[idx])
    frac = np.clip(frac, 0, 1)
    direc = np.sign(np.diff(Xs, prepend=Xs[0] - h))
    saw = np.where(sliding, p["saw"] * Fk * (np.where(direc > 0, frac, 1 - frac) - 0.5) * direc, 0.0)
    Ftot = F + saw
    # bins: trace samples are fine points npre+1 .. npre+ntr (the interval from X0+(i)dX to (i+1)dX)
    tr = Ftot[npre + 1: npre + 1 + ntr].reshape(n_samp, fine).mean(1)
    re = Ftot[npre + 1 + ntr:].reshape(n_samp, fine).mean(1)
    htr = height_fn(xt[npre + 1: npre + 1 + ntr]).reshape(n_samp, fine).mean(1)
    hre = height_fn(xt[npre + 1 + ntr:]).reshape(n_samp, fine).mean(1)
    tau = dX / speed
    th = math.sqrt(2 * KB * p["T"] * p["c"] / tau) if p["T"] > 0 else 0.0
    mean = np.concatenate([tr, re]) + th * rng.standard_normal(2 * n_samp)
    hh = np.concatenate([htr, hre])
    i = np.arange(n_samp)
    centre = np.concatenate([X0 + (i + 0.5) * dX, X0 + L - (i + 0.5) * dX])
    dirs = np.concatenate([np.ones(n_samp, int), -np.ones(n_samp, int)])
    tt = np.concatenate([(i + 1) * tau, L / speed + (i + 1) * tau])
    return dict(mean=mean, height=hh, centre=centre, dir=dirs, t_end=tt, tau_s=tau,
                Fk_trace=float(np.median(tr)), Fk_retrace=float(np.median(re)), th_sigma=th)
