"""Truth models that generate measurements with a hidden effect (tests only; never imported by probedyn).

The modal truth is *independent* of probedyn's reduced FE beam: exact Euler-Bernoulli
solutions by transfer matrices (matrix exponential of the first-order form of
EI w'''' - P w'' = rho A omega^2 w), with root springs, an interior point mass (jump
EI [w'''] = m omega^2 w) and axial force, the free-end condition EI w''' = P w' - m omega^2 w,
St-Venant torsion in closed form, and fluid loading by its own copy of Sader's hydrodynamic
function applied to the uniform beam exactly (omega_f = omega_v / sqrt(1 + T Gamma_r(omega_f)),
Q = (1/T + Gamma_r) / Gamma_i). Frequencies get Gaussian noise of the relative size written
into the sidecar; the hidden effect and its parameters are returned to the test only.

The friction truth tracks the quasi-static Prandtl-Tomlinson tip position *point by point*
(damped Newton from the previous equilibrium, a jump when the well disappears: descent to the
next minimum), instead of probedyn's closed-form branch inversion, and adds the effect,
then white force noise.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq
from scipy.special import kve

# ----------------------------------------------------------------- modal
PROBE = dict(length=200e-6, width=30e-6, thickness=2e-6, E=169e9, rho=2330.0, nu=0.28)
MODES = [("flap", 1), ("flap", 2), ("flap", 3), ("flap", 4), ("lateral", 1), ("torsion", 1)]
MODAL_EFFECTS = ["clamp-compliance", "point-mass", "thickness-error", "width-error", "length-error",
                 "anisotropy", "fluid-loading", "axial-prestress"]


def _gamma(omega, b, rho_f, eta_f):
    re = rho_f * omega * b * b / (4 * eta_f)
    s = np.sqrt(1j * re)
    gc = 1 + 4j * kve(1, -1j * s) / (s * kve(0, -1j * s))
    t = math.log10(re)
    om_r = (0.91324 - 0.48274 * t + 0.46842 * t**2 - 0.12886 * t**3 + 0.044055 * t**4 - 0.0035117 * t**5 + 0.00069085 * t**6) / (
        1 - 0.56964 * t + 0.48690 * t**2 - 0.13444 * t**3 + 0.045155 * t**4 - 0.0035862 * t**5 + 0.00069085 * t**6)
    om_i = (-0.024134 - 0.029256 * t + 0.016294 * t**2 - 0.00010961 * t**3 + 0.000064577 * t**4 - 0.000044510 * t**5) / (
        1 - 0.59702 * t + 0.55182 * t**2 - 0.18357 * t**3 + 0.079156 * t**4 - 0.014369 * t**5 + 0.0028361 * t**6)
    g = (om_r + 1j * om_i) * gc
    return g.real, abs(g.imag)


def tm_det(beta, kr=math.inf, kt=math.inf, mu=0.0, xm=1.0, p=0.0):
    """Frequency determinant of a uniform EB beam, x in [0, 1], Lambda = beta^4."""
    lam = beta**4
    A = np.array([[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [lam, 0, p, 0]], float)
    if math.isinf(kr) and math.isinf(kt):
        Y0 = np.array([[0, 0], [0, 0], [1, 0], [0, 1]], float)
    elif math.isinf(kt):  # w(0) = 0; unknowns w'(0) and the root shear
        Y0 = np.array([[0, 0], [1, 0], [kr, 0], [p, 1]], float)
    elif math.isinf(kr):  # w'(0) = 0; unknowns w(0) and the root moment
        Y0 = np.array([[1, 0], [0, 0], [0, 1], [-kt, 0]], float)
    else:
        Y0 = np.array([[1, 0], [0, 1], [0, kr], [-kt, p]], float)
    if mu and xm < 1.0:
        Jm = np.eye(4); Jm[3, 0] += mu * lam
        Y = expm(A * (1 - xm)) @ Jm @ expm(A * xm) @ Y0
        tipmu = 0.0
    else:
        Y = expm(A) @ Y0
        tipmu = mu
    # end: w'' = 0 ; w''' - p w' + mu Lambda w = 0
    row2 = Y[2]
    row3 = Y[3] - p * Y[1] + tipmu * lam * Y[0]
    return row2[0] * row3[1] - row2[1] * row3[0]


def tm_roots(n, **kw):
    """First n beta roots (non-dimensional, beta^4 = rho A omega^2 L^4 / EI)."""
    grid = np.arange(0.3, 4.0 * n + 6, 0.01)
    vals = np.array([tm_det(b, **kw) for b in grid])
    roots = []
    for i in range(len(grid) - 1):
        if vals[i] == 0 or vals[i] * vals[i + 1] < 0:
            roots.append(brentq(lambda b: tm_det(b, **kw), grid[i], grid[i + 1], xtol=1e-13))
            if len(roots) == n:
                break
    return np.array(roots)


def torsion_J(w, t):
    a, b = max(w, t), min(w, t)
    r = b / a
    return a * b**3 * (1 / 3 - 0.21 * r * (1 - r**4 / 12))


def modal_truth(effect, params, probe=PROBE, modes=MODES, Q_int=2e4):
    """Exact frequencies [Hz] and Q of the listed modes of the probe carrying ``effect``."""
    L, w, t, E, rho, nu = (probe[k] for k in ("length", "width", "thickness", "E", "rho", "nu"))
    kr = kt = math.inf; mu = 0.0; xm = 1.0; p_nd = 0.0; rho_f = 0.0; eta_f = 1.8e-5; Eb = E
    EI0 = E * w * t**3 / 12
    if effect == "clamp-compliance":
        kr = params["kappa_r"]; kt = params.get("kappa_t", math.inf)
    elif effect == "point-mass":
        mu, xm = params["mu"], params["xi"]
    elif effect == "thickness-error":
        t = t * params["t_ratio"]
    elif effect == "width-error":
        w = w * params["w_ratio"]
    elif effect == "length-error":
        L = L * params["L_ratio"]
    elif effect == "anisotropy":
        Eb = E * params["e_ratio"]
    elif effect == "fluid-loading":
        rho_f, eta_f = params["rho_f"], params["eta_f"]
    elif effect == "axial-prestress":
        p_nd = params["p"]
    elif effect is not None:
        raise ValueError(effect)
    A = w * t
    m_nom = probe["rho"] * probe["width"] * probe["thickness"] * probe["length"]
    out_f, out_q = [], []
    for fam, order in modes:
        if fam == "torsion":
            G = E / (2 * (1 + nu))
            Ip = w * t * (w * w + t * t) / 12
            f = (2 * order - 1) / (4 * L) * math.sqrt(G * torsion_J(w, t) / (rho * Ip))
            out_f.append(f); out_q.append(Q_int); continue
        EI = Eb * (w * t**3 if fam == "flap" else t * w**3) / 12
        # nondimensionalise the nominal-scaled quantities with this family's EI and actual L
        kw = dict(kr=kr * EI0 / probe["length"] * L / EI if math.isfinite(kr) else math.inf,
                  kt=kt * EI0 / probe["length"] ** 3 * L**3 / EI if math.isfinite(kt) else math.inf,
                  mu=mu * m_nom / (rho * A * L), xm=xm, p=p_nd * EI0 / probe["length"] ** 2 * L**2 / EI)
        beta = tm_roots(order, **kw)[order - 1]
        om = beta**2 * math.sqrt(EI / (rho * A * L**4))
        q = Q_int
        if fam == "flap" and rho_f > 0:
            T = math.pi * rho_f * w / (4 * rho * t)
            om_v = om
            om = brentq(lambda o: o - om_v / math.sqrt(1 + T * _gamma(o, w, rho_f, eta_f)[0]), om_v * 1e-3, om_v)
            gr, gi = _gamma(om, w, rho_f, eta_f)
            q = 1 / (1 / Q_int + 1 / ((1 / T + gr) / gi))
        out_f.append(om / (2 * math.pi)); out_q.append(q)
    return np.array(out_f), np.array(out_q)


def draw_modal_effect(effect, rng, strength=1.0):
    """A seeded random magnitude of the effect, in the catalog's parameters.

    The ranges span from about the detection limit (a few sigma of 1e-3 frequency noise on
    the most sensitive mode) to clearly visible effects; ``strength`` < 1 keeps only the upper
    part of each range (used by the fast default tests, which must not sit on the threshold).
    """
    sgn = rng.choice([-1.0, 1.0])
    u = 1.0 - strength * rng.uniform(0.0, 1.0)  # 0..1, biased to the strong end for strength < 1
    lerp = lambda a, b: a + (b - a) * (1.0 - u)  # noqa: E731  (strong end = b)
    if effect == "clamp-compliance":
        return {"kappa_r": float(10 ** lerp(math.log10(3000), math.log10(30)))}
    if effect == "point-mass":
        return {"mu": float(10 ** lerp(math.log10(0.003), math.log10(0.1))), "xi": float(rng.uniform(0.5, 1.0))}
    if effect == "thickness-error":
        return {"t_ratio": float(1 + sgn * lerp(0.002, 0.03))}
    if effect == "width-error":
        return {"w_ratio": float(1 + sgn * lerp(0.004, 0.05))}
    if effect == "length-error":
        return {"L_ratio": float(1 + sgn * lerp(0.001, 0.02))}
    if effect == "anisotropy":
        return {"e_ratio": float(1 + sgn * lerp(0.005, 0.1))}
    if effect == "fluid-loading":
        return {"rho_f": float(10 ** lerp(math.log10(0.3), 3)), "eta_f": float(10 ** rng.uniform(-5, -3))}
    if effect == "axial-prestress":
        return {"p": float(sgn * lerp(0.02, 1.0))}
    raise ValueError(effect)


def write_modal(folder: Path, name, f, q, modes=MODES, probe=PROBE, rel=1e-3, qrel=0.05, with_q=True, lengths=None, extra_probe=None):
    folder = Path(folder); folder.mkdir(parents=True, exist_ok=True)
    lines = ["family,order,frequency_Hz" + (",Q" if with_q else "") + (",length_m" if lengths is not None else "")]
    for k, (fam, o) in enumerate(modes):
        row = f"{fam},{o},{f[k]:.9g}"
        if with_q:
            row += f",{q[k]:.6g}" if fam == "flap" else ","
        if lengths is not None:
            row += f",{lengths[k]:.6g}"
        lines.append(row)
    (folder / f"{name}.csv").write_text("\n".join(lines) + "\n")
    pr = dict(probe, **(extra_probe or {}))
    side = [
        "[measurement]", 'kind = "modal"', f'data = "{name}.csv"', 'description = "generated"', "",
        "[probe]", *[f"{k} = {v!r}" for k, v in pr.items()], "",
        "[medium]", 'name = "vacuum"', "", "[noise]", f"frequency_rel = {rel!r}", f"Q_rel = {qrel!r}", "",
    ]
    (folder / f"{name}.toml").write_text("\n".join(side))
    return folder / f"{name}.toml"


def make_modal_case(folder, effect, seed, rel=1e-3, qrel=0.05, modes=MODES, with_q=True, strength=1.0):
    """Write a measurement carrying ``effect`` (None: null case); return (path, truth params)."""
    rng = np.random.default_rng(seed)
    params = draw_modal_effect(effect, rng, strength) if effect else {}
    f, q = modal_truth(effect, params, modes=modes)
    f = f * (1 + rel * rng.standard_normal(len(f)))
    q = q * np.exp(qrel * rng.standard_normal(len(q)))
    return write_modal(folder, f"meas_{seed}", f, q, modes=modes, rel=rel, qrel=qrel, with_q=with_q), params


# -------------------------------------------------------------- friction
FRICTION = dict(k_x=1.0, a=0.5e-9, mu_c=0.0637, sigma=5e-12, scan_len=5e-9, n_pts=100,
                speeds=(1e-8, 1e-6), loads=(2e-9, 4e-9))  # n_pts per direction
FRICTION_EFFECTS = ["velocity-log", "scanner-nonlinearity", "force-offset-drift", "lattice-misalignment",
                    "viscous-friction", "adhesion-load"]


_GX, _GW = np.polynomial.legendre.leggauss(8)


def track_pt(X, direction, F0, k, a, phi, slip_frac, boxcar=True):
    """Sequential quasi-static PT: the tip's well is carried point by point (explicit state).

    With ``boxcar`` each sample is the mean force over its sampling interval (midpoints to the
    neighbours within the segment), by 8-point Gauss-Legendre quadrature of the tracked force,
    the interval split at the slip position computed from the tracker's own state.
    """
    eta = 2 * math.pi * F0 / (k * a)  # = 4 pi^2 U0 / (k a^2): stability k + U'' > 0
    xc = a / (2 * math.pi) * math.acos(-1 / eta) if eta > 1 else a / 2
    xj = slip_frac * xc if eta > 1 else xc
    state = {"c": phi + round((X[0] - phi) / a) * a}  # centre of the current well

    def equilibrium(Xi, c):
        lo, hi = c - xc, c + xc  # stable branch of this well
        g = lambda x: k * (x - Xi) + F0 * math.sin(2 * math.pi * (x - phi) / a)  # noqa: E731
        if g(lo) > 0 or g(hi) < 0:
            return None
        return brentq(g, lo, hi, xtol=1e-18)

    def force(Xi, d):
        for _ in range(10):
            x = equilibrium(Xi, state["c"])
            if x is not None and d * (x - state["c"]) <= xj * (1 + 1e-12):
                return k * (Xi - x)
            state["c"] += d * a  # slip into the next well along the motion
        raise RuntimeError("tracker lost")

    def slip_X(d):  # support position at which the tip reaches the slip point of its well
        xs = state["c"] + d * xj
        return xs + (F0 / k) * math.sin(2 * math.pi * (xs - phi) / a)

    def integrate(x0, x1, d):  # mean force over [x0, x1] along the motion (x1 after x0)
        if x1 == x0:
            return force(x0, d)
        tot = 0.0
        pieces = [(x0, x1)]
        xs = slip_X(d)
        if d * (xs - x0) > 0 and d * (x1 - xs) > 0:
            pieces = [(x0, xs), (xs, x1)]
        for p0, p1 in pieces:
            pts = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * _GX
            vals = [force(q, d) for q in pts]
            tot += 0.5 * abs(p1 - p0) * float(np.dot(_GW, vals))
        return tot / abs(x1 - x0)

    out = np.empty(len(X))
    cuts = np.nonzero(np.diff(direction) != 0)[0] + 1
    starts = np.concatenate([[0], cuts]); ends = np.concatenate([cuts, [len(X)]])
    for s0, e0 in zip(starts, ends):
        d = 1.0 if direction[s0] > 0 else -1.0
        seg = X[s0:e0]
        for i in range(len(seg)):
            if not boxcar or len(seg) < 2:
                out[s0 + i] = force(seg[i], d); continue
            lo = seg[i] if i == 0 else 0.5 * (seg[i - 1] + seg[i])
            hi = seg[i] if i == len(seg) - 1 else 0.5 * (seg[i] + seg[i + 1])
            out[s0 + i] = integrate(lo, hi, d)
    return out


def friction_truth(effect, params, cfg=FRICTION, rng=None):
    """Scans (list of dicts) of the truth model carrying ``effect``; noise added when rng given."""
    k, a = cfg["k_x"], cfg["a"]
    L, n = cfg["scan_len"], cfg["n_pts"]
    v_max = max(cfg["speeds"])
    loads = cfg["loads"]
    n_mean = float(np.mean([ld for _ in cfg["speeds"] for ld in loads]))
    scans = []
    sid = 0
    for v in cfg["speeds"]:
        for N in loads:
            Xn = np.concatenate([np.linspace(0, L, n), np.linspace(L, 0, n)[1:]])
            dirs = np.concatenate([np.ones(n), -np.ones(n - 1)])
            t = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(Xn)))]) / v
            X = Xn.copy()
            if effect == "scanner-nonlinearity":
                X = Xn + params["bow"] * Xn * (L - Xn) / L
            F0 = cfg["mu_c"] * (N + (params["n_adh"] * n_mean if effect == "adhesion-load" else 0.0))
            slip = 1 + params["slip_b"] * math.log(v / v_max) if effect == "velocity-log" else 1.0
            phi = rng.uniform(0, a) if rng is not None else 0.1 * a
            if effect == "lattice-misalignment":
                th = math.radians(params["theta"])
                phy = rng.uniform(0, a) if rng is not None else 0.3 * a
                F = (math.cos(th) * track_pt(X * math.cos(th), dirs, F0, k, a, phi, slip)
                     + math.sin(th) * track_pt(X * math.sin(th), dirs, F0, k, a, phy, slip))
            else:
                F = track_pt(X, dirs, F0, k, a, phi, slip)
            if effect == "viscous-friction":
                F = F + params["visc"] * k * a * (v / v_max) * dirs
            if effect == "force-offset-drift":
                F = F + k * a * (params["offset"] + params["drift"] * (t - t.mean() * 0 - 0.5 * t[-1]) / t[-1])
            if rng is not None:
                F = F + cfg["sigma"] * rng.standard_normal(len(F))
            scans.append(dict(id=sid, speed=v, load=N, position=Xn, force=F, time=t))
            sid += 1
    return scans


def draw_friction_effect(effect, rng, strength=1.0):
    sgn = rng.choice([-1.0, 1.0])
    u = 1.0 - strength * rng.uniform(0.0, 1.0)
    lerp = lambda lo, hi: lo + (hi - lo) * (1.0 - u)  # noqa: E731
    if effect == "velocity-log":
        return {"slip_b": float(lerp(0.005, 0.08))}
    if effect == "scanner-nonlinearity":
        return {"bow": float(sgn * lerp(0.01, 0.1))}
    if effect == "force-offset-drift":
        return {"offset": float(sgn * lerp(0.01, 0.2)), "drift": float(rng.choice([-1, 1]) * lerp(0.0, 0.2))}
    if effect == "lattice-misalignment":
        return {"theta": float(lerp(3.0, 30.0))}
    if effect == "viscous-friction":
        return {"visc": float(lerp(0.01, 0.2))}
    if effect == "adhesion-load":
        return {"n_adh": float(lerp(0.05, 1.0))}
    raise ValueError(effect)


def write_friction(folder, name, scans, cfg=FRICTION, sigma_stated=True):
    folder = Path(folder); folder.mkdir(parents=True, exist_ok=True)
    lines = ["scan,position_m,lateral_force_N,time_s"]
    for s in scans:
        for x, f, t in zip(s["position"], s["force"], s["time"]):
            lines.append(f"{s['id']},{x:.9e},{f:.9e},{t:.9e}")
    (folder / f"{name}.csv").write_text("\n".join(lines) + "\n")
    side = ["[measurement]", 'kind = "friction"', f'data = "{name}.csv"', "", "[probe]", f"k_x = {cfg['k_x']!r}", "",
            "[sample]", f"lattice = {cfg['a']!r}", ""]
    if sigma_stated:
        side += ["[noise]", f"force = {cfg['sigma']!r}", ""]
    for s in scans:
        side += ["[[scans]]", f"id = {s['id']}", f"speed = {s['speed']!r}", f"load = {s['load']!r}", ""]
    (folder / f"{name}.toml").write_text("\n".join(side))
    return folder / f"{name}.toml"


def make_friction_case(folder, effect, seed, strength=1.0, cfg=FRICTION):
    rng = np.random.default_rng(10_000 + seed)
    params = draw_friction_effect(effect, rng, strength) if effect else {}
    scans = friction_truth(effect, params, cfg, rng)
    return write_friction(folder, f"scan_{seed}", scans, cfg), params
