"""Viscoelastic indentation: a rigid axisymmetric indenter on a linear viscoelastic half-space
(Lee & Radok 1960 while the contact grows, Ting 1966 while it shrinks), with the lever as a spring.

Not a registry law (:class:`~.base.ContactModel` is a force-penetration curve); the force here
depends on the **history** of the indentation, so it is evaluated along a time record.

Law
---
An elastic, frictionless, non-adhesive indenter whose elastic force is ``P_e = E* g(delta)``
(sphere: ``g = (4/3) sqrt(R) delta^(3/2)``, Hertz; sharp cone: ``g = (2/pi) tan(alpha) delta^2``,
Sneddon) on a half-space with the relaxation modulus (in the reduced-modulus form, the Poisson ratio
constant) of the **standard linear solid**

    E(t) = E_inf (1 + s exp(-t / tau)),   s = E_0 / E_inf - 1 >= 0   (relaxation strength).

While the contact radius grows (Lee & Radok 1960)::

    P(t) = int_0^t E(t - u) d g(delta(u)) / E_inf ... = E_inf [g(delta(t)) + s H(t)],
    H(t) = int_0^t exp(-(t - u) / tau) d g(delta(u)).

After the largest contact (Ting 1966, one maximum of the contact radius) the contact radius at t is
the one of the earlier time ``t1(t) <= t_m`` with

    int_{t1}^{t} E(t - u) d delta(u) = 0,                                     (Ting's condition)

and the force is ``P(t) = int_0^{t1} E(t - u) d g(delta(u)) = E_inf [g(delta(t1)) + s e^{-(t - t1)/tau} H(t1)]``.
The contact is lost when ``t1`` reaches the first touch: the surface under the tip then still lies
below its undeformed level (it recovers with the delay tau), so the tip leaves it **before** the
approach's contact point -- no adhesion is involved. ``s = 0`` is exactly the elastic law with
``E* = E_inf``; ``tau -> 0`` gives ``E_inf`` (relaxed), ``tau -> infinity`` gives ``E_0 = (1 + s) E_inf``.

Numerics (exponential kernel: **recursive convolution**): ``delta`` and ``g`` piecewise linear in
time between samples, so over a step ``dt``
``H_n = a H_{n-1} + phi (g_n - g_{n-1})`` with ``a = e^{-dt/tau}``, ``phi = tau (1 - a) / dt`` (exact for
that interpolation); the same for ``G(t) = int_0^t e^{-(t-u)/tau} d delta`` (Ting's condition reads
``delta(t) - delta(t1) + s (G(t) - e^{-(t - t1)/tau} G(t1)) = 0``, linear in ``delta(t)``). The lever
(stiffness k, piezo ``z_rel = z - z_c``): ``delta + P / k = z_rel`` at every sample, a monotone scalar
equation per step (Newton in ``delta`` while loading; while unloading a search for ``t1`` over the
loading history: bisection over the samples, then regula falsi inside the interval). Cost
**O(n log n)** for n samples (O(n) while loading); compiled (numba).

Assumptions: linear viscoelasticity (small strains), one relaxation time, constant Poisson ratio,
no adhesion, one maximum of the contact radius per record (approach, then retract; a later
re-loading beyond the maximum continues Lee-Radok from the stored history, an approximation).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["power_law", "sls_lever_curve", "sls_indentation_force", "lee_radok_constant_rate"]


def power_law(shape: str, R: float = 0.0, alpha: float = 0.0) -> tuple[float, float]:
    """``(c, m)`` of the elastic law ``P_e = E* c delta^m`` of a sphere (Hertz, radius R) or a sharp cone
    (Sneddon, half-angle alpha [rad])."""
    if shape == "sphere":
        return 4.0 / 3.0 * math.sqrt(R), 1.5
    if shape == "cone":
        return 2.0 / math.pi * math.tan(alpha), 2.0
    raise ValueError(f"unknown indenter shape {shape!r} (sphere, cone)")


def _decay(dt, tau):
    """``(a, phi)``: e^{-dt/tau} and tau (1 - a) / dt (-> 1 for dt << tau)."""
    x = dt / tau
    a = math.exp(-x)
    phi = -math.expm1(-x) / x if x > 1e-12 else 1.0 - 0.5 * x
    return a, phi


def _kernel(t, zr, k, c, m, E_inf, s, tau):
    n = t.shape[0]
    F = np.zeros(n)
    # loading history (contact growing): time, delta, g, H, G at each loading sample
    Th = np.empty(n + 1)
    Dh = np.empty(n + 1)
    Gh = np.empty(n + 1)
    Hh = np.empty(n + 1)
    GGh = np.empty(n + 1)
    nh = 0
    inv_k = 0.0 if k == math.inf else 1.0 / k
    d_prev = zr[0] if zr[0] < 0.0 else 0.0  # the first sample is taken out of contact or at touch
    g_prev = 0.0
    H = 0.0
    G = 0.0
    lost = False
    # the first sample: out of contact if zr <= 0; else a step into contact at t0 (loaded instantly)
    for i in range(n):
        if i == 0:
            dt = 0.0
            a, phi = 1.0, 1.0
        else:
            dt = t[i] - t[i - 1]
            a, phi = _decay(dt, tau)
        y = zr[i]
        if lost:
            F[i] = 0.0
            d_prev = y
            continue
        # --- try a Lee-Radok (loading) step: delta + E_inf [(1 + s phi) c delta^m + s (a H - phi g_prev)] / k = y
        c0 = E_inf * s * (a * H - phi * g_prev) * inv_k
        c1 = E_inf * (1.0 + s * phi) * c * inv_k
        yy = y - c0
        dmax_hist = Dh[nh - 1] if nh > 0 else 0.0
        if yy <= 0.0 and nh == 0:  # out of contact before the first touch
            F[i] = 0.0
            d_prev = y
            continue
        if k == math.inf:
            dl = y
        else:
            if yy <= 0.0:
                dl = yy
            else:
                d = min(yy, (yy / c1) ** (1.0 / m)) if c1 > 0 else yy
                for _ in range(60):
                    f = d + c1 * d**m - yy
                    fp = 1.0 + c1 * m * d ** (m - 1.0)
                    dn = d - f / fp
                    if dn <= 0.0:
                        dn = 0.5 * d
                    if abs(dn - d) <= 1e-15 * max(d, 1e-300):
                        d = dn
                        break
                    d = dn
                dl = d
        if dl >= dmax_hist:  # the contact grows: Lee-Radok
            dp = dl if dl > 0.0 else 0.0
            if nh == 0:  # the touch: a history node of zero contact at the step's start (delta+ linear in the step)
                Th[0] = t[i - 1] if i > 0 else t[i]
                Dh[0] = 0.0
                Gh[0] = 0.0
                Hh[0] = 0.0
                GGh[0] = 0.0
                nh = 1
                d_prev = 0.0
            gp = c * dp**m
            H = a * H + phi * (gp - g_prev)
            G = a * G + phi * (dp - (d_prev if d_prev > 0.0 else 0.0))
            F[i] = E_inf * (gp + s * H)
            Th[nh] = t[i]
            Dh[nh] = dp
            Gh[nh] = gp
            Hh[nh] = H
            GGh[nh] = G
            nh += 1
            d_prev = dp
            g_prev = gp
            continue
        # --- the contact shrinks: Ting. Unknown t1 on the loading history, parametrised by u in [0, nh-1]
        # h(u) = delta_n(u) + P_n(u) / k - y, increasing in u
        ti = t[i]
        # h at node j
        lo = 0
        hi = nh - 1
        h_lo = _ting_h(0, 0.0, Th, Dh, Gh, Hh, GGh, ti, a, phi, G, d_prev, s, tau, E_inf, inv_k, y, k)
        if h_lo >= 0.0:  # even at zero contact radius the tip is above the surface: contact lost
            lost = True
            F[i] = 0.0
            d_prev = y
            continue
        h_hi = _ting_h(hi, 0.0, Th, Dh, Gh, Hh, GGh, ti, a, phi, G, d_prev, s, tau, E_inf, inv_k, y, k)
        if h_hi < 0.0:  # (not reached: dl >= dmax_hist above) -- keep the largest contact
            lo = hi
        else:
            while hi - lo > 1:
                mid = (lo + hi) // 2
                hm = _ting_h(mid, 0.0, Th, Dh, Gh, Hh, GGh, ti, a, phi, G, d_prev, s, tau, E_inf, inv_k, y, k)
                if hm < 0.0:
                    lo = mid
                    h_lo = hm
                else:
                    hi = mid
                    h_hi = hm
        # regula falsi (Illinois) for theta in [0, 1] inside interval [lo, lo + 1]
        th = 0.0
        if hi > lo:
            x0, x1 = 0.0, 1.0
            f0, f1 = h_lo, h_hi
            side = 0
            for _ in range(60):
                th = (x0 * f1 - x1 * f0) / (f1 - f0) if f1 != f0 else 0.5 * (x0 + x1)
                fm = _ting_h(lo, th, Th, Dh, Gh, Hh, GGh, ti, a, phi, G, d_prev, s, tau, E_inf, inv_k, y, k)
                if fm == 0.0 or x1 - x0 < 1e-13:
                    break
                if fm < 0.0:
                    x0, f0 = th, fm
                    if side == -1:
                        f1 *= 0.5
                    side = -1
                else:
                    x1, f1 = th, fm
                    if side == 1:
                        f0 *= 0.5
                    side = 1
        dn, P = _ting_state(lo, th, Th, Dh, Gh, Hh, GGh, ti, a, phi, G, d_prev, s, tau, E_inf)
        G = a * G + phi * (dn - d_prev)
        F[i] = P
        d_prev = dn
    return F


def _ting_state(j, th, Th, Dh, Gh, Hh, GGh, ti, a, phi, G_prev, d_prev, s, tau, E_inf):
    """Surface displacement under the tip at ti and the force, for t1 = T[j] + th (T[j+1] - T[j])."""
    if th > 0.0:
        dtj = Th[j + 1] - Th[j]
        at, pt = _decay(th * dtj, tau)
        d1 = Dh[j] + th * (Dh[j + 1] - Dh[j])
        g1 = Gh[j] + th * (Gh[j + 1] - Gh[j])
        H1 = at * Hh[j] + pt * (g1 - Gh[j])
        G1 = at * GGh[j] + pt * (d1 - Dh[j])
        t1 = Th[j] + th * dtj
    else:
        d1, g1, H1, G1, t1 = Dh[j], Gh[j], Hh[j], GGh[j], Th[j]
    e = math.exp(-(ti - t1) / tau)
    dn = (d1 + s * (e * G1 - a * G_prev + phi * d_prev)) / (1.0 + s * phi)
    P = E_inf * (g1 + s * e * H1)
    return dn, P


def _ting_h(j, th, Th, Dh, Gh, Hh, GGh, ti, a, phi, G_prev, d_prev, s, tau, E_inf, inv_k, y, k):
    dn, P = _ting_state(j, th, Th, Dh, Gh, Hh, GGh, ti, a, phi, G_prev, d_prev, s, tau, E_inf)
    return dn + P * inv_k - y


_JIT: dict = {}


def _compiled():
    """The kernels compiled with numba on first use (cached on disk): the contact registry's discovery imports
    this module, and listing the registry (CLI help) should not import numba."""
    if not _JIT:
        from numba import njit

        g = globals()
        for name in ("_decay", "_ting_state", "_ting_h", "_kernel"):  # callees first: numba binds globals
            g[name] = njit(cache=True)(g[name])
        _JIT["kernel"] = g["_kernel"]
    return _JIT["kernel"]


def sls_lever_curve(t, z_rel, k: float, c: float, m: float, E_inf: float, strength: float, tau: float) -> np.ndarray:
    """Force [N] on a lever of stiffness ``k`` [N/m] (``math.inf``: the indentation is prescribed,
    ``delta = z_rel``) along a record in **time order** ``t`` [s] with piezo positions ``z_rel`` [m] (towards
    the sample, 0 at the undeformed surface), over the SLS half-space ``E_inf (1 + s e^{-t/tau})`` indented by
    ``P_e = E* c delta^m`` (:func:`power_law`). ``strength = 0`` is the elastic law with ``E* = E_inf``."""
    t = np.ascontiguousarray(t, dtype=float)
    z = np.ascontiguousarray(z_rel, dtype=float)
    if t.shape != z.shape or t.ndim != 1:
        raise ValueError("t and z_rel must be 1-D arrays of one length")
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        raise ValueError("times must increase")
    if not (strength >= 0 and tau > 0 and E_inf > 0 and k > 0):
        raise ValueError("need strength >= 0, tau > 0, E_inf > 0, k > 0")
    return _compiled()(t, z, float(k), float(c), float(m), float(E_inf), float(strength), float(tau))


def sls_indentation_force(t, delta, c: float, m: float, E_inf: float, strength: float, tau: float) -> np.ndarray:
    """Force [N] for a prescribed indentation history ``delta(t)`` (displacement control; Ting's
    contact loss included: the force is 0 once the surface has separated from the indenter)."""
    return sls_lever_curve(t, delta, math.inf, c, m, E_inf, strength, tau)


def lee_radok_constant_rate(t, v: float, c: float, E_inf: float, strength: float, tau: float):
    """Closed form of Lee-Radok for a sphere (m = 3/2) pushed at the constant rate ``v`` from t = 0:
    ``P = E_inf c v^{3/2} [t^{3/2} + (3/2) s tau^{3/2} (x - D(x))]``, ``x = sqrt(t / tau)``, D Dawson's
    integral (``int_0^t e^{-(t-u)/tau} sqrt(u) du = tau^{3/2} (x - D(x))``)."""
    from scipy.special import dawsn

    t = np.asarray(t, float)
    x = np.sqrt(t / tau)
    return E_inf * c * v**1.5 * (t**1.5 + 1.5 * strength * tau**1.5 * (x - dawsn(x)))
