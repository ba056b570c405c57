"""Blind contact mechanics + lever equilibrium for synthetic AFM force curves.

Conventions
-----------
delta : indentation (m), > 0 in contact; -delta is the far-field separation beyond first touch.
P     : tip-sample force (N), > 0 repulsive (lever pushed away from sample), < 0 attractive.
z     : piezo position (m), increasing towards the sample; z_rel = z - z_c, z_c the piezo position
        at which the undeflected tip touches the undeformed surface.
Lever : deflection d = P / k (positive = bent away from sample); tip position z - d, so
        delta = z_rel - d  <=>  z_rel = delta + P/k.

Each contact law is returned as an ordered equilibrium path (delta_i, P_i) from far away
(delta = -L, P = 0) to deep indentation.  Along the path z_rel_i = delta_i + P_i/k; a path
segment is stable on the lever iff z_rel increases along it (dz/ds > 0 <=> dP/dD < k, D the
separation).  The quasi-static simulation follows the stable branch and jumps (at constant z)
when the branch ends.
"""
import numpy as np
from scipy.optimize import brentq


def estar(E_s, nu_s, E_t, nu_t):
    inv = (1 - nu_s ** 2) / E_s
    if E_t is not None:
        inv += (1 - nu_t ** 2) / E_t
    return 1.0 / inv


def hertz_force(delta, R, Es):
    d = np.clip(delta, 0, None)
    return 4.0 / 3.0 * Es * np.sqrt(R) * d ** 1.5


def hertz_delta(P, R, Es):
    return (3.0 * P / (4.0 * Es * np.sqrt(R))) ** (2.0 / 3.0)


def _far(L, d_end, n=400):
    return np.linspace(-L, d_end, n)


# ---------------------------------------------------------------- Hertz
def path_hertz(R, Es, delta_max, L):
    d_nc = _far(L, 0.0, 400)[:-1]
    d_c = delta_max * np.linspace(0, 1, 6000) ** 1.5
    delta = np.concatenate([d_nc, d_c])
    P = hertz_force(delta, R, Es)
    return dict(delta=delta, P=P, branch=np.r_[np.zeros(d_nc.size), np.ones(d_c.size)])


# ---------------------------------------------------------------- DMT + vdW tail
def path_dmt(R, Es, W, D0, delta_max, L):
    """DMT: in contact P = Hertz - 2 pi W R; outside, sphere-flat vdW -H R / (6 (s + D0)^2)
    with H = 12 pi W D0^2 (so the force is continuous, -2 pi W R, at touch s = 0)."""
    H = 12 * np.pi * W * D0 ** 2
    s = np.concatenate([np.linspace(L, 20e-9, 300)[:-1] if L > 20e-9 else np.empty(0),
                        np.geomspace(min(L, 20e-9), 1e-14, 6000), [0.0]])
    d_nc = -s
    P_nc = -H * R / (6 * (s + D0) ** 2)
    d_c = delta_max * np.linspace(0, 1, 6000)[1:] ** 1.5
    P_c = hertz_force(d_c, R, Es) - 2 * np.pi * W * R
    return dict(delta=np.r_[d_nc, d_c], P=np.r_[P_nc, P_c], H=H,
                branch=np.r_[np.zeros(d_nc.size), np.ones(d_c.size)])


# ---------------------------------------------------------------- JKR
def jkr_state(a, R, Es, W):
    delta = a ** 2 / R - np.sqrt(2 * np.pi * W * a / Es)
    P = 4 * Es * a ** 3 / (3 * R) - np.sqrt(8 * np.pi * W * Es * a ** 3)
    return delta, P


def path_jkr(R, Es, W, P_max, L):
    """No force outside contact; in contact both branches of the JKR curve, parametrised by a."""
    f = lambda a: jkr_state(a, R, Es, W)[1] - P_max
    a_hi = (3 * R * (P_max + 10 * np.pi * W * R) / (4 * Es)) ** (1 / 3) + (np.pi * W * R ** 2 / Es) ** (1 / 3)
    while f(a_hi) < 0:
        a_hi *= 1.5
    a_max = brentq(f, (9 * np.pi * W * R ** 2 / (8 * Es)) ** (1 / 3), a_hi, xtol=1e-16)
    a = np.r_[0.0, np.geomspace(a_max * 1e-7, a_max * 0.05, 3000)[:-1], np.linspace(a_max * 0.05, a_max * 1.02, 8000)]
    d_c, P_c = jkr_state(a, R, Es, W)
    d_nc = _far(L, 0.0, 400)[:-1]
    return dict(delta=np.r_[d_nc, d_c], P=np.r_[np.zeros(d_nc.size), P_c],
                branch=np.r_[np.zeros(d_nc.size), np.ones(d_c.size)])


# ---------------------------------------------------------------- Maugis-Dugdale
def _s_minus_atan(s):
    s = np.asarray(s, float)
    out = s - np.arctan(s)
    small = s < 1e-2
    ss = s[small]
    out[small] = ss ** 3 / 3 - ss ** 5 / 5 + ss ** 7 / 7
    return out


def md_eq1(s, A, lam):
    """Maugis' energy-balance equation (Johnson & Greenwood 1997), m = c/a = sqrt(1+s^2)."""
    s = np.atleast_1d(np.asarray(s, float))
    m = np.sqrt(1 + s ** 2)
    at = np.arctan(s)
    t1 = _s_minus_atan(s) + s ** 2 * at                      # s + (m^2-2) atan s
    t2 = s * at - s ** 2 / (1 + m)                           # s atan s - m + 1
    return (lam * A ** 2 / 2 * t1 + 4 * lam ** 2 * A / 3 * t2)[0]


def md_contact(A, lam):
    """Dimensionless contact state: returns (P_bar, Delta_bar, m)."""
    g = lambda s: md_eq1(s, A, lam) - 1.0
    hi = 1.0
    while g(hi) < 0:
        hi *= 2
    s = brentq(g, 0.0, hi, xtol=1e-15, rtol=1e-14)
    m = np.sqrt(1 + s * s)
    at = np.arctan(s)
    P = A ** 3 - lam * A ** 2 * (s + m ** 2 * at)
    D = A ** 2 - 4.0 / 3.0 * A * lam * s
    return P, D, m


def md_scales(R, Es, W):
    K = 4 * Es / 3
    return dict(K=K, a=(np.pi * W * R ** 2 / K) ** (1 / 3), P=np.pi * W * R,
                d=(np.pi ** 2 * W ** 2 * R / K ** 2) ** (1 / 3))


def md_sigma0(R, Es, W, lam):
    K = 4 * Es / 3
    return lam / 2 * (np.pi * W * K ** 2 / R) ** (1 / 3)


def path_md(R, Es, W, lam, P_max, L, nA=4000):
    sc = md_scales(R, Es, W)
    s0 = md_sigma0(R, Es, W, lam)
    h0 = W / s0
    # non-contact Dugdale branch: cohesive zone radius c where the gap reaches h0, centre gap h >= 0
    bq = (2 - 4 / np.pi) * s0 / Es
    c_on = (-bq + np.sqrt(bq ** 2 + 4 * h0 / (2 * R))) / (2 / (2 * R))
    c = np.r_[0.0, np.geomspace(c_on * 1e-6, c_on, 3000)]
    d_dug = c ** 2 / (2 * R) - 4 * s0 * c / (np.pi * Es) - h0
    P_dug = -np.pi * s0 * c ** 2
    # contact branch
    Amax = 1.0
    while md_contact(Amax, lam)[0] * sc['P'] < P_max:
        Amax *= 1.3
    A_small = 1e-5
    A = np.r_[np.geomspace(A_small, 0.05 * Amax, 1200)[:-1], np.linspace(0.05 * Amax, Amax, nA)]
    st = np.array([md_contact(x, lam) for x in A])
    d_c = st[:, 1] * sc['d']
    P_c = st[:, 0] * sc['P']
    d_nc = _far(L, -h0, 400)[:-1]
    if L <= h0:
        d_nc = np.array([-h0 - 1e-9])
    delta = np.r_[d_nc, d_dug, d_c]
    P = np.r_[np.zeros(d_nc.size), P_dug, P_c]
    return dict(delta=delta, P=P, h0=h0, sigma0=s0, c_on=c_on,
                branch=np.r_[np.zeros(d_nc.size), 0.5 * np.ones(c.size), np.ones(A.size)],
                join=(d_dug[-1], P_dug[-1], d_c[0], P_c[0]))


# ---------------------------------------------------------------- lever quasi-statics
def simulate(path, k, z_app, z_ret):
    """Quasi-static lever on the equilibrium path.  z_app increasing, z_ret decreasing (relative
    to z_c).  Returns dict with delta, P for both segments and the list of jumps."""
    dl, P = path['delta'], path['P']
    z = dl + P / k
    n = z.size
    stable = np.diff(z) > 0
    jumps = []

    def interp(i, zt):
        t = (zt - z[i]) / (z[i + 1] - z[i])
        return dl[i] + t * (dl[i + 1] - dl[i]), P[i] + t * (P[i + 1] - P[i])

    out_a = np.empty((len(z_app), 2))
    i = 0
    while not (stable[i] and z[i] <= z_app[0] <= z[i + 1]):
        i += 1
    for q, zt in enumerate(z_app):
        while True:
            if stable[i]:
                if z[i + 1] >= zt:
                    break
                if i + 1 < n - 1 and stable[i + 1]:
                    i += 1
                    continue
                # fold at node i+1: jump forward at constant z
                j = i + 1
                while j < n - 1 and not (stable[j] and z[j] <= zt <= z[j + 1]):
                    j += 1
                if j >= n - 1:
                    raise RuntimeError('approach ran off the path')
                before = (dl[i + 1], P[i + 1])
                jumps.append(dict(kind='snap-in', z_rel=float(z[i + 1]), delta_from=float(before[0]),
                                  P_from=float(before[1]), delta_to=float(interp(j, z[i + 1])[0]),
                                  P_to=float(interp(j, z[i + 1])[1])))
                i = j
                break
            else:
                i += 1
        out_a[q] = interp(i, zt)
    out_r = np.empty((len(z_ret), 2))
    while not (stable[i] and z[i] <= z_ret[0] <= z[i + 1]):
        i += 1 if z[i + 1] < z_ret[0] else -1
    for q, zt in enumerate(z_ret):
        while True:
            if stable[i]:
                if z[i] <= zt:
                    break
                if i - 1 >= 0 and stable[i - 1]:
                    i -= 1
                    continue
                j = i - 1
                while j >= 0 and not (stable[j] and z[j] <= zt <= z[j + 1]):
                    j -= 1
                if j < 0:
                    raise RuntimeError('retract ran off the path')
                jumps.append(dict(kind='pull-off', z_rel=float(z[i]), delta_from=float(dl[i]),
                                  P_from=float(P[i]), delta_to=float(interp(j, z[i])[0]),
                                  P_to=float(interp(j, z[i])[1])))
                i = j
                break
            else:
                i -= 1
        out_r[q] = interp(i, zt)
    return dict(delta_a=out_a[:, 0], P_a=out_a[:, 1], delta_r=out_r[:, 0], P_r=out_r[:, 1], jumps=jumps,
                z_path=z, stable=stable)
