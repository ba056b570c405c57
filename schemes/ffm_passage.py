"""The noisy saddle-node passage of an overdamped FFM tip: where a stick-slip slip comes when the instability is near.

A tip dragged through the Prandtl-Tomlinson potential loses its well at the support position ``X_c`` (the
saddle-node, where ``k + U''`` vanishes at the inflection ``x_c``). Near it the force on the tip is, to lowest order
in ``y = x - x_c`` and the support's advance ``V (t - t_c)`` (motion in +x),

    gamma dy/dt = k V (t - t_c) + b y^2 + xi(t),    b = -U'''(x_c) / 2 = q^3 U0 sin(q x_c) / 2,

with ``<xi xi'> = 2 gamma k_B T delta`` (``gamma`` the tip's whole damping, lever and substrate; overdamped: the
inertial time ``m / gamma`` far below the passage's). In the units ``t* = (gamma^2 / (k V b))^(1/3)`` and
``y* = gamma / (b t*)`` it is one equation for every lever, scan speed and corrugation,

    dz/ds = z^2 + s + sqrt(2 theta) w(s),     theta = k_B T b / (gamma k V),

(the normal form of the saddle-node with a drifting parameter; Berglund & Gentz, *Noise-induced phenomena in
slow-fast dynamical systems*, 2006, ch. 4). Without noise the tip leaves at ``s = 2.2`` (the Riccati equation's
blow-up, the Airy function's first zero 2.338, less the last ``1/z``): the integrator's saddle-node delay of the
athermal path, ``2.2 V t*`` of support travel past ``X_c``. With noise it leaves earlier and with a spread: at
``theta = 1.8`` the median by 0.96 t* (blind friction set 2's g16, a tip on a viscous substrate at 295 K, 1.5 um/s:
0.095 of a period earlier than the athermal slip, where its generator's Langevin tip slipped 0.084 earlier,
10-90 % spreads 0.30 and 0.24 of a period). Kramers' rate with a constant attempt frequency on the quasi-static
barrier stops at ``X_c``, which holds no barrier; it cannot give this, and where the passage is slow (large
``gamma``, fast scans) the slips came a tenth of a period late and too sharp (docs/diagnose.md 9.57).

:func:`escape_hazard` is the cumulative hazard ``H(s) = -ln S(s)`` of leaving by ``s`` (``z`` past
:data:`ESCAPE_Z`), from the Smoluchowski equation of the normal form solved on a grid (:func:`escape_survival`),
tabulated in ``theta`` and interpolated in ``ln theta``. Far before the instability (``theta`` large) the normal
form's cubic barrier ``(4/3) |s|^(3/2)`` is no longer the potential's: there the friction model keeps Kramers' rate
on the whole barrier and takes the larger of the two rates (:mod:`probedyn.diagnose.friction`, which reads this module).

:func:`overdamped_falls` is the FFM tip's equation of motion (:mod:`.ffm`) in its overdamped limit, the reduced form
the friction diagnosis integrates each slip point's fall with (its inertial time below a tenth of the passage's,
:func:`bottleneck_scales`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit
from scipy.constants import k as K_B

__all__ = ["ESCAPE_Z", "THETA_RANGE", "bottleneck_scales", "deterministic_escape", "escape_hazard",
           "escape_survival", "fall_substeps", "overdamped_falls"]

#: where the tip counts as gone (units ``y*``): far down the drift-dominated side, where the rest of the fall takes
#: ``1 / z`` and no longer depends on the noise. The friction model uses the *difference* between the noisy and the
#: deterministic passage to the same level (the integrator carries the fall itself); between 3 and 12 it moves the
#: median's difference by 0.02 at theta = 1.8, each alone by 0.23 (tests/test_diagnose_bottleneck.py)
ESCAPE_Z = 6.0
#: the noise strengths tabulated (:func:`escape_hazard`): below, the passage is the deterministic one (the spread
#: below 0.1 t*); above, the slip comes where the cubic normal form no longer holds, and Kramers' rate on the whole
#: barrier is the model
THETA_RANGE = (0.03, 100.0)
#: table points per decade of ``theta``: the median interpolated midway between two within 0.05 t* of a direct solution
#: there, or 2.5 % of its distance from the saddle-node at large theta (tests/test_diagnose_bottleneck.py)
THETA_PER_DECADE = 10
#: the hazard's grid: steps of ``S_STEP`` up to ``S_END`` (units ``t*``), where every tip has gone (S below 1e-3 at
#: theta up to 100)
S_END = 6.0
S_STEP = 0.01
#: Runge-Kutta steps per output step of :func:`overdamped_falls` beyond which the friction model leaves the passage out
#: (the tip relaxes in its well a thousand times faster than the support moves a step: g16's scans take 1-7)
FALL_MAX_SUBSTEPS = 1000
#: the passage's width ``y*`` in units of ``1 / q`` beyond which the cubic expansion about the inflection no longer
#: holds (g16's scans, where the normal form reproduced the generator's slips, are at 0.15-0.46; a tip ten times as
#: damped as the lever on 0.5 nm, own seed 2001 at 300 K, at 0.6-1.3: its passage is the integrator's alone)
NORMAL_FORM_WIDTH = 0.6
#: the inertial time over the passage's, ``m / (gamma t*)``, below which the tip is overdamped there
#: (:func:`bottleneck_scales`)
OVERDAMPED = 0.1


@njit(cache=True)
def _bernoulli(x):
    """``x / (exp(x) - 1)`` (the Scharfetter-Gummel weight), by its series near 0."""
    if abs(x) < 1e-6:
        return 1.0 - 0.5 * x
    return x / math.expm1(x)


@njit(cache=True)
def _survival_kernel(theta, z_abs, s0, s_end, ds_near, dz):
    """Smoluchowski equation of the normal form ``dz = (z^2 + s) ds + sqrt(2 theta) dW`` on ``[z_lo, z_abs]``:
    Scharfetter-Gummel fluxes (exact for a locally constant drift at any Peclet number), implicit Euler in ``s``
    (steps ``ds_near`` for ``s > -4``, growing as ``sqrt(|s|)`` before), reflecting at ``z_lo``, absorbing at
    ``z_abs``; started in the well's Boltzmann distribution at ``s0``. Returns the steps ``s`` and the survival."""
    zw = -math.sqrt(-s0)
    sd = math.sqrt(theta / (2.0 * math.sqrt(-s0)))
    z_lo = zw - 10.0 * sd - 2.0
    n = int((z_abs - z_lo) / dz) + 1
    z = np.empty(n)
    P = np.empty(n)
    vmin = 1e300
    for i in range(n):
        z[i] = z_lo + i * dz
        v = -(z[i] ** 3 / 3.0 + s0 * z[i])
        if v < vmin and z[i] < -zw:
            vmin = v
    tot = 0.0
    for i in range(n):
        if z[i] < -zw:  # the well, up to its saddle
            P[i] = math.exp(-(-(z[i] ** 3 / 3.0 + s0 * z[i]) - vmin) / theta)
        else:
            P[i] = 0.0
        tot += P[i]
    for i in range(n):
        P[i] /= tot * dz
    m = 1
    s = s0
    while s < s_end:
        m += 1
        s += ds_near * (math.sqrt(-s) if s < -4.0 else 1.0)
    out_s = np.empty(m)
    out_S = np.empty(m)
    out_s[0] = s0
    out_S[0] = 1.0
    a = np.empty(n)
    b = np.empty(n)
    c = np.empty(n)
    Bm = np.empty(n)
    Bp = np.empty(n)
    s = s0
    for j in range(1, m):
        ds = ds_near * (math.sqrt(-s) if s < -4.0 else 1.0)
        s += ds
        r = theta / (dz * dz) * ds
        for i in range(n):  # the face i + 1/2; flux theta/dz (Bm_i P_i - Bp_i P_{i+1}), P_n = 0 (absorbed)
            zf = z[i] + 0.5 * dz
            w = (zf * zf + s) * dz / theta
            Bm[i] = _bernoulli(-w)
            Bp[i] = _bernoulli(w)
        for i in range(n):
            b[i] = 1.0 + r * Bm[i] + (r * Bp[i - 1] if i > 0 else 0.0)
            a[i] = -r * Bm[i - 1] if i > 0 else 0.0  # sub-diagonal (row i, column i - 1)
            c[i] = -r * Bp[i] if i < n - 1 else 0.0  # super-diagonal
        # Thomas algorithm (diagonally dominant: the M-matrix of an upwinded flux)
        for i in range(1, n):
            f = a[i] / b[i - 1]
            b[i] -= f * c[i - 1]
            P[i] -= f * P[i - 1]
        P[n - 1] /= b[n - 1]
        for i in range(n - 2, -1, -1):
            P[i] = (P[i] - c[i] * P[i + 1]) / b[i]
        tot = 0.0
        for i in range(n):
            tot += P[i]
        out_s[j] = s
        out_S[j] = tot * dz
    return out_s, out_S


def escape_survival(theta: float, z_abs: float = ESCAPE_Z, s_end: float = S_END, fine: float = 1.0):
    """The probability ``S(s)`` that a tip in the normal form's well at noise ``theta`` has not passed ``z_abs`` by
    ``s`` (units ``t*``; module docstring). Started where the well's barrier ``(4/3) |s0|^(3/2)`` is 15 theta
    (at least ``s0 = -6``), in its Boltzmann distribution. ``fine`` divides the grid's steps (a convergence check).
    Returns ``(s, S)``."""
    if not (theta > 0 and math.isfinite(theta)):
        raise ValueError(f"theta must be positive and finite, got {theta!r}")
    s0 = -max(6.0, (15.0 * 0.75 * theta) ** (2.0 / 3.0))
    dz = min(0.04, theta / 12.0) / fine
    return _survival_kernel(float(theta), float(z_abs), s0, float(s_end), 0.01 / fine, dz)


@functools.lru_cache(maxsize=None)
def deterministic_escape(z_abs: float = ESCAPE_Z) -> float:
    """``s`` at which the noiseless normal form ``dz/ds = z^2 + s``, started in its well long before, passes
    ``z_abs`` (2.338, the Airy function's first zero, less about ``1 / z_abs``)."""
    from scipy.integrate import solve_ivp

    s0 = -40.0
    hit = lambda s, z: z[0] - z_abs  # noqa: E731
    hit.terminal = True
    sol = solve_ivp(lambda s, z: [z[0] * z[0] + s], (s0, 10.0), [-math.sqrt(-s0)], events=hit, rtol=1e-10,
                    atol=1e-12, max_step=0.01)
    return float(sol.t_events[0][0])


def _theta_nodes() -> np.ndarray:
    """The tabulated ``ln theta`` (:data:`THETA_RANGE`, :data:`THETA_PER_DECADE`)."""
    lo, hi = THETA_RANGE
    return np.linspace(math.log(lo), math.log(hi), int(round(THETA_PER_DECADE * math.log10(hi / lo))) + 1)


@functools.lru_cache(maxsize=None)
def _node(i: int) -> tuple[np.ndarray, np.ndarray]:
    """The cumulative hazard ``-ln S`` at the ``i``-th tabulated ``theta`` on the steps of :data:`S_STEP` from its
    start to :data:`S_END` (computed when first needed, 0.02-0.2 s, kept for the process)."""
    th = float(math.exp(_theta_nodes()[i]))
    ss, S = escape_survival(th)
    s = np.arange(ss[0], S_END + 0.5 * S_STEP, S_STEP)
    H = np.interp(s, ss, -np.log(np.maximum(S, 1e-300)))
    s.setflags(write=False)
    H.setflags(write=False)
    return s, H


def escape_hazard(theta: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The cumulative hazard ``H(s)`` of the noisy passage at ``theta`` (units ``t*``, 0 at the saddle-node): the
    two tabulated neighbours' on the earlier start's grid, linear in ``ln theta`` between them (monotone in ``s`` as
    each is). None outside :data:`THETA_RANGE`. Returns ``(s, H)``."""
    if not (THETA_RANGE[0] <= theta <= THETA_RANGE[1]):
        return None
    lt = _theta_nodes()
    x = math.log(theta)
    i = min(max(int(np.searchsorted(lt, x, side="right")) - 1, 0), len(lt) - 2)
    w = (x - lt[i]) / (lt[i + 1] - lt[i])
    (s0, H0), (s1, H1) = _node(i), _node(i + 1)
    # the same step and end: the longer grid is the earlier start's (the larger theta's); before its own start the
    # other's hazard is nil (its well's barrier there is 15 theta)
    s, n0, n1 = (s1, len(s0), len(s1)) if len(s1) >= len(s0) else (s0, len(s0), len(s1))
    H = np.zeros(len(s))
    H[len(s) - n0:] += (1.0 - w) * H0
    H[len(s) - n1:] += w * H1
    return s, H


def bottleneck_scales(U0: float, a: float, k: float, V: float, gamma: float, m: float, T: float) -> dict | None:
    """The normal form's scales for a Prandtl-Tomlinson tip (``U = -U0 cos(2 pi x / a)``) on a lever ``k`` dragged
    at ``V``, damping ``gamma`` (lever and substrate) and mass ``m``, at ``T``: ``t_star`` [s], ``theta``, ``b``
    [N/m^2], ``inertia`` (``m / (gamma t*)``), ``width`` (``q y*``). None where there is no instability (eta <= 1), no
    noise or no motion, where the tip is not overdamped at the passage (``inertia`` above :data:`OVERDAMPED`: its
    inertia then carries it through the bottleneck, and the slip is the hazard's and the integrator's) or where the
    passage is as wide as the lattice's curvature (``width`` above :data:`NORMAL_FORM_WIDTH`)."""
    q = 2.0 * math.pi / a
    eta = q * q * U0 / k
    if not (eta > 1.0 and T > 0 and V > 0 and gamma > 0 and k > 0):
        return None
    b = 0.5 * q**3 * U0 * math.sqrt(1.0 - 1.0 / (eta * eta))
    t_star = (gamma * gamma / (k * V * b)) ** (1.0 / 3.0)
    inertia = m / (gamma * t_star)
    width = q * gamma / (b * t_star)  # q y*
    if inertia > OVERDAMPED or width > NORMAL_FORM_WIDTH:
        return None
    return {"t_star": t_star, "theta": K_B * T * b / (gamma * k * V), "b": b, "inertia": inertia, "width": width}


@njit(cache=True)
def _fall_kernel(X0, x0, V, k, F0, q, gamma, h, n_out, n_sub, x_land):
    """Overdamped tip ``gamma dx/dt = k (X - x) - F0 sin(q x)`` with the support ``X = X0 + V t``, from ``x0`` at
    ``X0``: the tip's position at the support steps ``X0 + i h`` (``i = 0 .. n_out - 1``), classical Runge-Kutta with
    ``n_sub`` steps between outputs until the tip, past ``x_land``, moves at less than twice the support's speed (it
    has landed and sticks), then one linearised backward-Euler step per output (the stick's slow drift; stable at any
    step, where the explicit steps would have to resolve the well's fast relaxation all along)."""
    out = np.empty(n_out)
    x = x0
    out[0] = x
    dt = h / V / n_sub
    X = X0
    landed = False
    for i in range(1, n_out):
        if not landed and x > x_land and abs(k * (X - x) - F0 * math.sin(q * x)) < 2.0 * gamma * V:
            landed = True
        if landed:
            X += h
            f = (k * (X - x) - F0 * math.sin(q * x)) / gamma
            x += (h / V) * f / (1.0 + (h / V) * (k + F0 * q * math.cos(q * x)) / gamma)
            out[i] = x
            continue
        for _ in range(n_sub):
            k1 = (k * (X - x) - F0 * math.sin(q * x)) / gamma
            k2 = (k * (X + 0.5 * V * dt - x - 0.5 * dt * k1) - F0 * math.sin(q * (x + 0.5 * dt * k1))) / gamma
            k3 = (k * (X + 0.5 * V * dt - x - 0.5 * dt * k2) - F0 * math.sin(q * (x + 0.5 * dt * k2))) / gamma
            k4 = (k * (X + V * dt - x - dt * k3) - F0 * math.sin(q * (x + dt * k3))) / gamma
            x += dt * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
            X += V * dt
        out[i] = x
    return out


def fall_substeps(V: float, k: float, U0: float, a: float, gamma: float, h: float) -> int:
    """Runge-Kutta steps per output step ``h`` of :func:`overdamped_falls`: a step of 0.4 of the fastest relaxation
    time ``gamma / (k + q^2 U0)`` (the classical Runge-Kutta's stability ends at 2.8)."""
    q = 2.0 * math.pi / a
    return max(1, int(math.ceil((h / V) / (0.4 * gamma / (k + q * q * U0)))))


def overdamped_falls(X0: np.ndarray, x0: float, V: float, k: float, U0: float, a: float, gamma: float, h: float,
                     n_out: int) -> np.ndarray:
    """The tip's positions after it passes ``x0`` (a lattice maximum) at each support position ``X0`` (one row per
    start), at the support steps ``h`` [m], for a Prandtl-Tomlinson tip (``U = -U0 cos(2 pi x / a)``) on a lever
    ``k`` dragged at ``V`` with damping ``gamma``, overdamped (inertia neglected: :func:`bottleneck_scales`); classical
    Runge-Kutta, :func:`fall_substeps` steps per output step, until the tip sticks in the next well (a quarter period
    past ``x0``, moving at less than twice the support's speed), then linearised backward Euler."""
    q = 2.0 * math.pi / a
    n_sub = fall_substeps(V, k, U0, a, gamma, h)
    return np.array([_fall_kernel(float(X), float(x0), float(V), float(k), float(q * U0), q, float(gamma), float(h),
                                  int(n_out), n_sub, float(x0) + 0.25 * a) for X in np.asarray(X0, float)])
