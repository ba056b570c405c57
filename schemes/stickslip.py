"""The non-dimensional two-mass stick-slip model of nano-pushing (source section 4.1.3).

Physical model (eq 4.2, Fig 4.7): a probe tip (m1, k1, c1) is driven by the cantilever base
moving at speed V; the tip pushes a sample (m2) through a linearised contact (k2, c2); the
sample feels the substrate potential ``U = U0 cos(2 pi X / a)`` (eq 4.1), i.e. the force
``(2 pi U0 / a) sin(2 pi X_s / a)``.

Non-dimensional form (eqs 4.3-4.7), re-derived and checked term by term::

    t  = sqrt(k/m) T,   m = m1 m2/(m1+m2),   k = k1 k2/(k1+k2)                  (4.3, 4.5)
    y1 = (2 pi/a) X_t - v t,  y2 = (2 pi/a) X_s - v t,  v = (2 pi/a) sqrt(m/k) V   (4.6)
    (m1/m) y1'' = -2 z1 y1' - 2 z2 (y1' - y2') - (k1/k) y1 - (k2/k)(y1 - y2)
    (m2/m) y2'' = -2 z2 (y2' - y1') - (k2/k)(y2 - y1) + u0 sin(y2 + v t + psi)      (4.7)

with ``z_i = c_i / (2 sqrt(k m))`` and ``u0 = 4 pi^2 U0 / (k a^2)``; the state is
``x = [y1, y1', y2, y2']`` (eq 4.9).  ``psi`` is the phase of the substrate seen by the
sample at t = 0: for v = 0 it is the "quasi-statically varying phase" of eq 4.11.

Quasi-static equilibria (eqs 4.10-4.12): with v = 0 the rest states are
``y1 = k2/(k1+k2) X``, ``y2 = X`` with ``X = u0 sin(X + psi)``; eliminating y1 gives the reduced
potential ``W(X) = X^2/2 + u0 cos(X + psi)`` (the effective stiffness k1 k2/(k1+k2) is exactly k,
so the coefficient of X^2/2 is 1), whose curvature ``L(X) = 1 - u0 cos(X + psi)`` decides
stability (Lagrange-Dirichlet, eq 4.12).  The total energy
``E = (m1/m) y1'^2/2 + (m2/m) y2'^2/2 + (k1/k) y1^2/2 + (k2/k)(y1-y2)^2/2 + u0 cos(y2+psi)``
satisfies ``dE/dt = -2 z1 y1'^2 - 2 z2 (y1'-y2')^2 <= 0`` and ``E >= W(y2)``: once E is below
the reduced potential at both saddles bounding the sample's well, the sample can never leave
that well and converges to its node.  This is the rigorous "steady state reached" certificate
used by the basin computation (together with a tolerance on the distance to the node).

SOURCE-NOTES item 5: for u0 = 25, psi = 5 the equation gives 8 stable and 7 unstable
equilibria (the text says 16 nodes and 15 saddles); :func:`equilibria` reports what the
equation gives.

Integration: the tip mode is stiff compared with the sample (non-dimensional frequency
sqrt((k1+k2)/k / (m1/m)) ~ 95 for Table 4.3 against O(1-5) for the sample), so the bulk
kernels use classical RK4 with a fixed step below the RK4 stability limit of the tip mode
(|lambda dt| < 2.8), compiled with numba and run over all cells; reference solutions use
scipy's DOP853 with tight tolerances (``tests/stickslip_reference.py``, used by the tests and
benchmarks/basins.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset

# --------------------------------------------------------------------------------------
# Parameters (Table 4.3)
# --------------------------------------------------------------------------------------

_T43 = preset("table-4.3")

TABLE_4_3 = ParamSet(
    [
        Param("m1", _T43["m1"], "kg", "tip (probe) effective mass", lo=1e-16, hi=1e-6, positive=True, source="Table 4.3"),
        Param("m2", _T43["m2"], "kg", "sample mass", lo=1e-22, hi=1e-6, positive=True, source="Table 4.3"),
        Param("k1", _T43["k1"], "N/m", "probe stiffness", lo=1e-4, hi=1e4, positive=True, source="Table 4.3"),
        Param("k2", _T43["k2"], "N/m", "linearised tip-sample contact stiffness", lo=1e-9, hi=1e4, positive=True,
              source="Table 4.3"),
        Param("zeta1", _T43["zeta1"], "", "probe damping ratio c1/(2 sqrt(k m))", lo=0.0, hi=100.0,
              source="Table 4.3, eq 4.7"),
        Param("zeta2", _T43["zeta2"], "", "tip-sample damping ratio c2/(2 sqrt(k m))", lo=0.0, hi=100.0,
              source="Table 4.3, eq 4.7"),
        # The source gives no period for 4.1.3.  The text's own pairings (u0 = 25 <-> U0 ~ 1 eV,
        # V = 3 um/s .. 0.3 mm/s spanning quasi-static .. sliding) are consistent only with a
        # period of ~0.16 um for Table 4.3's k (see docs/stickslip.md); with an atomic period
        # (0.5 nm) u0 would be ~2e6 for 1 eV.  The default is that implied period (preset note).
        Param("a", _T43["a"], "m", "period of the sample-substrate potential (eq 4.1)", lo=1e-11, hi=1e-3,
              positive=True, source="eq 4.1, implied by 4.1.3.1"),
    ]
)


@dataclass(frozen=True)
class TwoMassModel:
    """Two-mass model of Fig 4.7 with its non-dimensional coefficients (eqs 4.5, 4.7).

    Defaults are Table 4.3 (:mod:`probedyn.core.presets`).  All attributes are SI; the derived
    properties are the dimensionless coefficients of eq 4.7.
    """

    m1: float = _T43["m1"]
    m2: float = _T43["m2"]
    k1: float = _T43["k1"]
    k2: float = _T43["k2"]
    zeta1: float = _T43["zeta1"]
    zeta2: float = _T43["zeta2"]
    a: float = _T43["a"]

    @classmethod
    def from_params(cls, overrides: dict[str, Any] | None = None) -> "TwoMassModel":
        return cls(**TABLE_4_3.resolve(overrides))

    def __post_init__(self) -> None:
        for name in ("m1", "m2", "k1", "k2", "a"):
            TABLE_4_3[name].coerce(getattr(self, name))
        for name in ("zeta1", "zeta2"):
            TABLE_4_3[name].coerce(getattr(self, name))

    # eq 4.5
    @property
    def m(self) -> float:
        return self.m1 * self.m2 / (self.m1 + self.m2)

    @property
    def k(self) -> float:
        return self.k1 * self.k2 / (self.k1 + self.k2)

    @property
    def time_scale(self) -> float:
        """sqrt(m/k) [s]: one unit of non-dimensional time (eq 4.3)."""
        return math.sqrt(self.m / self.k)

    @property
    def mu1(self) -> float:
        return self.m1 / self.m

    @property
    def mu2(self) -> float:
        return self.m2 / self.m

    @property
    def kappa1(self) -> float:
        return self.k1 / self.k

    @property
    def kappa2(self) -> float:
        return self.k2 / self.k

    def coefficients(self) -> np.ndarray:
        """[m1/m, m2/m, k1/k, k2/k, 2 zeta1, 2 zeta2] as used by the compiled kernels."""
        return np.array([self.mu1, self.mu2, self.kappa1, self.kappa2, 2 * self.zeta1, 2 * self.zeta2])

    def tip_frequency(self) -> float:
        """Non-dimensional frequency of the tip mode with the sample held: sqrt((k1+k2)/k / (m1/m))."""
        return math.sqrt((self.kappa1 + self.kappa2) / self.mu1)

    def max_stable_dt(self, u0: float) -> float:
        """Largest RK4 step kept below 70 % of the stability limit 2.83/omega_max."""
        w_sample = math.sqrt((self.kappa2 + abs(u0)) / self.mu2)
        return 0.7 * 2.83 / max(self.tip_frequency(), w_sample)

    # eq 4.6 and below eq 4.7
    def v_from_speed(self, V: float) -> float:
        """Non-dimensional speed v = (2 pi / a) sqrt(m/k) V for a base speed V [m/s]."""
        return 2 * math.pi / self.a * self.time_scale * V

    def speed_from_v(self, v: float) -> float:
        return v * self.a / (2 * math.pi * self.time_scale)

    def u0_from_U0(self, U0: float) -> float:
        """u0 = 4 pi^2 U0 / (k a^2) for a potential amplitude U0 [J]."""
        return 4 * math.pi**2 * U0 / (self.k * self.a**2)

    def U0_from_u0(self, u0: float) -> float:
        return u0 * self.k * self.a**2 / (4 * math.pi**2)

    # eq 4.7 as a first-order system (eq 4.8) for scipy
    def rhs(self, t: float, x: np.ndarray, u0: float, v: float, psi: float) -> np.ndarray:
        y1, p1, y2, p2 = x
        z1, z2 = 2 * self.zeta1, 2 * self.zeta2
        f1 = (-z1 * p1 - z2 * (p1 - p2) - self.kappa1 * y1 - self.kappa2 * (y1 - y2)) / self.mu1
        f2 = (-z2 * (p2 - p1) - self.kappa2 * (y2 - y1) + u0 * np.sin(y2 + v * t + psi)) / self.mu2
        return np.array([p1, f1, p2, f2])

    def jacobian(self, t: float, x: np.ndarray, u0: float, v: float, psi: float) -> np.ndarray:
        """Analytic Jacobian of :meth:`rhs` (for implicit integrators)."""
        z1, z2 = 2 * self.zeta1, 2 * self.zeta2
        c = u0 * math.cos(x[2] + v * t + psi)
        return np.array(
            [
                [0.0, 1.0, 0.0, 0.0],
                [-(self.kappa1 + self.kappa2) / self.mu1, -(z1 + z2) / self.mu1, self.kappa2 / self.mu1, z2 / self.mu1],
                [0.0, 0.0, 0.0, 1.0],
                [self.kappa2 / self.mu2, z2 / self.mu2, (-self.kappa2 + c) / self.mu2, -z2 / self.mu2],
            ]
        )

    def energy(self, x: np.ndarray, u0: float, psi: float) -> np.ndarray:
        """Total energy of the v = 0 system (the Lyapunov function of the quasi-static problem)."""
        y1, p1, y2, p2 = np.asarray(x, dtype=float)
        return (
            0.5 * self.mu1 * p1**2
            + 0.5 * self.mu2 * p2**2
            + 0.5 * self.kappa1 * y1**2
            + 0.5 * self.kappa2 * (y1 - y2) ** 2
            + u0 * np.cos(y2 + psi)
        )

    def quasi_static_state(self, X: float) -> np.ndarray:
        """Rest state of eq 4.10 for a sample coordinate X."""
        return np.array([self.k2 / (self.k1 + self.k2) * X, 0.0, X, 0.0])


DEFAULT_MODEL = TwoMassModel()


#: largest non-dimensional speed of the moving-base dynamics: the transient (t >= 300) is integrated
#: with 128 steps per forcing period 2 pi / v, i.e. ~6000 v steps per cell
V_MAX = 1e3
#: largest |psi| accepted: beyond, X + psi (|X| <= u0 <= 1e4) keeps fewer than ~6 significant digits of X
PSI_MAX = 1e6


def _check_u0_psi(u0: float, psi: float) -> None:
    if not (isinstance(u0, (int, float, np.floating, np.integer)) and math.isfinite(u0)):
        raise ParameterError(f"u0 must be a finite number, got {u0!r}")
    if u0 < 0:
        raise ParameterError(f"u0 must be >= 0 (it is 4 pi^2 U0/(k a^2)), got {u0:g}")
    if u0 > 1e4:
        raise ParameterError(f"u0 = {u0:g} is too large (more than ~3000 equilibria); use u0 <= 1e4")
    if not math.isfinite(psi):
        raise ParameterError(f"psi must be finite, got {psi!r}")
    if abs(psi) > PSI_MAX:
        raise ParameterError(f"psi = {psi:g} rad: a phase beyond +-{PSI_MAX:g} rad loses its value in floating point "
                             "(X + psi); give it modulo 2 pi")


# --------------------------------------------------------------------------------------
# Quasi-static equilibria (eqs 4.10-4.12)
# --------------------------------------------------------------------------------------


@dataclass
class Equilibria:
    """Solutions of X = u0 sin(X + psi) (eq 4.11) with their stability (eq 4.12)."""

    u0: float
    psi: float
    X: np.ndarray  # sorted roots
    L: np.ndarray  # 1 - u0 cos(X + psi)
    stable_mask: np.ndarray
    marginal_mask: np.ndarray  # |L| below tolerance (fold points): neither stable nor unstable
    W: np.ndarray = field(default=None)  # reduced potential at the roots

    @property
    def stable(self) -> np.ndarray:
        return self.X[self.stable_mask]

    @property
    def unstable(self) -> np.ndarray:
        return self.X[~self.stable_mask & ~self.marginal_mask]

    @property
    def n_stable(self) -> int:
        return int(self.stable_mask.sum())

    @property
    def n_unstable(self) -> int:
        return int((~self.stable_mask & ~self.marginal_mask).sum())

    def to_dict(self) -> dict[str, Any]:
        return {
            "u0": self.u0,
            "psi": self.psi,
            "stable": self.n_stable,
            "unstable": self.n_unstable,
            "marginal": int(self.marginal_mask.sum()),
            "stable_X": self.stable,
            "unstable_X": self.unstable,
            "stable_L": self.L[self.stable_mask],
            "unstable_L": self.L[~self.stable_mask & ~self.marginal_mask],
        }


def reduced_potential(X: np.ndarray, u0: float, psi: float) -> np.ndarray:
    """W(X) = X^2/2 + u0 cos(X + psi): the energy with the tip at its quasi-static position."""
    X = np.asarray(X, dtype=float)
    return 0.5 * X**2 + u0 * np.cos(X + psi)


def equilibria(u0: float, psi: float, tol: float = 1e-12) -> Equilibria:
    """All solutions of ``X = u0 sin(X + psi)`` (eq 4.11), sorted, with stability (eq 4.12).

    Method: ``g(X) = X - u0 sin(X + psi)`` has ``g' = 1 - u0 cos(X + psi)``, which vanishes
    only at ``X + psi = +-arccos(1/u0) + 2 pi n`` (u0 > 1).  Between consecutive critical
    points g is strictly monotone, so each interval holds at most one root, found by Brent's
    method; all roots lie in ``|X| <= u0``.  The count is therefore exact, not sampled.
    A root where ``|L| < sqrt(tol)`` (a fold, u0 cos = 1) is reported as marginal.
    """
    _check_u0_psi(u0, psi)
    u0 = float(u0)
    psi = float(psi)

    def g(X: float) -> float:
        return X - u0 * math.sin(X + psi)

    lo, hi = -u0 - 1e-9, u0 + 1e-9
    breaks = [lo]
    if u0 > 1.0:
        c = math.acos(1.0 / u0)
        nmin = math.floor((lo + psi - c) / (2 * math.pi)) - 1
        nmax = math.ceil((hi + psi + c) / (2 * math.pi)) + 1
        for n in range(nmin, nmax + 1):
            for s in (-c, c):
                xc = s + 2 * math.pi * n - psi
                if lo < xc < hi:
                    breaks.append(xc)
    breaks.append(hi)
    breaks = sorted(set(breaks))
    roots: list[float] = []
    for a_, b_ in zip(breaks[:-1], breaks[1:]):
        ga, gb = g(a_), g(b_)
        if ga == 0.0:
            roots.append(a_)
        elif ga * gb < 0:
            roots.append(brentq(g, a_, b_, xtol=1e-14, rtol=4 * np.finfo(float).eps))
    if g(breaks[-1]) == 0.0:
        roots.append(breaks[-1])
    # Tangential roots (g has a zero at a critical point without a sign change): the
    # critical point itself is a root when |g| vanishes there.
    for xc in breaks[1:-1]:
        if abs(g(xc)) < tol * max(1.0, u0) and not any(abs(xc - r) < 1e-7 for r in roots):
            roots.append(xc)
    X = np.array(sorted(roots))
    L = 1.0 - u0 * np.cos(X + psi)
    marginal = np.abs(L) < math.sqrt(tol) * max(1.0, u0)
    return Equilibria(u0, psi, X, L, (L > 0) & ~marginal, marginal, reduced_potential(X, u0, psi))


def well_table(eq: Equilibria) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Wells of the reduced potential: (node X, left saddle X, right saddle X, barrier energy).

    Well i contains node i; its boundaries are the neighbouring saddles (+-inf at the ends);
    the barrier is min(W(left saddle), W(right saddle)) (+inf for a single well).
    """
    if eq.marginal_mask.any():
        raise SolverError(
            f"u0 = {eq.u0:g}, psi = {eq.psi:g} is at a fold (a marginal equilibrium): basins are undefined; shift psi slightly"
        )
    nodes = eq.stable
    sad = eq.unstable
    if len(sad) != len(nodes) - 1:
        raise SolverError(f"expected one saddle between consecutive nodes, got {len(nodes)} nodes and {len(sad)} saddles")
    left = np.concatenate([[-np.inf], sad])
    right = np.concatenate([sad, [np.inf]])
    Wl = np.where(np.isfinite(left), reduced_potential(np.where(np.isfinite(left), left, 0.0), eq.u0, eq.psi), np.inf)
    Wr = np.where(np.isfinite(right), reduced_potential(np.where(np.isfinite(right), right, 0.0), eq.u0, eq.psi), np.inf)
    return nodes, left, right, np.minimum(Wl, Wr)


# --------------------------------------------------------------------------------------
# Compiled kernels
# --------------------------------------------------------------------------------------

# Module-level numba kernels (cached on disk; compiled on first call in each process).


@numba.njit(cache=True, nogil=True, fastmath=False)
def deriv(y1, p1, y2, p2, t, u0, v, psi, c):
    mu1, mu2, ka1, ka2, z1, z2 = c[0], c[1], c[2], c[3], c[4], c[5]
    f1 = (-z1 * p1 - z2 * (p1 - p2) - ka1 * y1 - ka2 * (y1 - y2)) / mu1
    f2 = (-z2 * (p2 - p1) - ka2 * (y2 - y1) + u0 * math.sin(y2 + v * t + psi)) / mu2
    return p1, f1, p2, f2

@numba.njit(cache=True, nogil=True)
def rk4(y1, p1, y2, p2, t, dt, u0, v, psi, c):
    a1, b1, c1, d1 = deriv(y1, p1, y2, p2, t, u0, v, psi, c)
    h = 0.5 * dt
    a2, b2, c2, d2 = deriv(y1 + h * a1, p1 + h * b1, y2 + h * c1, p2 + h * d1, t + h, u0, v, psi, c)
    a3, b3, c3, d3 = deriv(y1 + h * a2, p1 + h * b2, y2 + h * c2, p2 + h * d2, t + h, u0, v, psi, c)
    a4, b4, c4, d4 = deriv(y1 + dt * a3, p1 + dt * b3, y2 + dt * c3, p2 + dt * d3, t + dt, u0, v, psi, c)
    s = dt / 6.0
    return (
        y1 + s * (a1 + 2 * a2 + 2 * a3 + a4),
        p1 + s * (b1 + 2 * b2 + 2 * b3 + b4),
        y2 + s * (c1 + 2 * c2 + 2 * c3 + c4),
        p2 + s * (d1 + 2 * d2 + 2 * d3 + d4),
    )

@numba.njit(cache=True, nogil=True)
def basins(x0, u0, psi, c, dt, tmax, nodes, left, right, barrier, tol, margin, out_label, out_x, out_t):
    """Integrate each initial state (v = 0) until the energy certificate traps it in a
    well AND it is within tol of that well's node; label = well index (-1: not settled)."""
    n = x0.shape[0]
    nw = nodes.shape[0]
    nmax = int(tmax / dt) + 1
    for i in range(n):
        y1, p1, y2, p2 = x0[i, 0], x0[i, 1], x0[i, 2], x0[i, 3]
        lab = -1
        t = 0.0
        for step in range(nmax):
            # which well holds y2 (wells are sorted intervals)
            w = 0
            while w < nw - 1 and y2 > right[w]:
                w += 1
            E = (
                0.5 * c[0] * p1 * p1 + 0.5 * c[1] * p2 * p2 + 0.5 * c[2] * y1 * y1
                + 0.5 * c[3] * (y1 - y2) * (y1 - y2) + u0 * math.cos(y2 + psi)
            )
            if E < barrier[w] - margin and abs(y2 - nodes[w]) < tol and abs(p2) < tol:
                lab = w
                break
            y1, p1, y2, p2 = rk4(y1, p1, y2, p2, t, dt, u0, 0.0, psi, c)
            t += dt
        out_label[i] = lab
        out_x[i, 0], out_x[i, 1], out_x[i, 2], out_x[i, 3] = y1, p1, y2, p2
        out_t[i] = t

@numba.njit(cache=True, nogil=True)
def attractor(x0, u0, v, psi, c, dt, n_trans, n_rec, n_sub, out_strobe, out_stats):
    """Integrate with the base moving (v > 0): n_trans steps of transient, then n_rec
    steps recorded.  n_sub steps make one forcing period 2 pi / v.  Per trajectory:
    strobe samples of (y2, y2') once per period, and statistics over the record:
    [min y2, max y2, mean y2, min y2', max y2', mean u0 sin(y2+vt+psi), dissipated energy,
     mean y1]."""
    n = x0.shape[0]
    n_strobe = out_strobe.shape[1]
    for i in range(n):
        y1, p1, y2, p2 = x0[i, 0], x0[i, 1], x0[i, 2], x0[i, 3]
        t = 0.0
        for s in range(n_trans):
            y1, p1, y2, p2 = rk4(y1, p1, y2, p2, t, dt, u0, v, psi, c)
            t = (s + 1) * dt
        mn, mx, sm = y2, y2, 0.0
        vmn, vmx = p2, p2
        fs = 0.0
        diss = 0.0
        sy1 = 0.0
        k = 0
        for s in range(n_rec):
            if s % n_sub == 0 and k < n_strobe:
                out_strobe[i, k, 0] = y2
                out_strobe[i, k, 1] = p2
                k += 1
            # trapezoid-free rectangle sums (the record spans whole periods, so the
            # rectangle rule is spectrally accurate for the periodic integrands)
            sm += y2
            sy1 += y1
            fs += u0 * math.sin(y2 + v * t + psi)
            diss += c[4] * p1 * p1 + c[5] * (p1 - p2) * (p1 - p2)
            y1, p1, y2, p2 = rk4(y1, p1, y2, p2, t, dt, u0, v, psi, c)
            t = (n_trans + s + 1) * dt
            if y2 < mn:
                mn = y2
            if y2 > mx:
                mx = y2
            if p2 < vmn:
                vmn = p2
            if p2 > vmx:
                vmx = p2
        out_stats[i, 0] = mn
        out_stats[i, 1] = mx
        out_stats[i, 2] = sm / n_rec
        out_stats[i, 3] = vmn
        out_stats[i, 4] = vmx
        out_stats[i, 5] = fs / n_rec
        out_stats[i, 6] = diss * dt
        out_stats[i, 7] = sy1 / n_rec

@numba.njit(cache=True, nogil=True)
def trajectory_kernel(x0, u0, v, psi, c, dt, nsteps, every, out):
    y1, p1, y2, p2 = x0[0], x0[1], x0[2], x0[3]
    t = 0.0
    k = 0
    for s in range(nsteps + 1):
        if s % every == 0 and k < out.shape[0]:
            out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4] = t, y1, p1, y2, p2
            k += 1
        if s == nsteps:
            break
        y1, p1, y2, p2 = rk4(y1, p1, y2, p2, t, dt, u0, v, psi, c)
        t = (s + 1) * dt



# --------------------------------------------------------------------------------------
# Basins of attraction (quasi-static, v = 0; Fig 4.9)
# --------------------------------------------------------------------------------------


def initial_states(x3: np.ndarray, x4: np.ndarray, model: TwoMassModel = DEFAULT_MODEL) -> np.ndarray:
    """Initial 4-states for sample initial conditions (x3, x4): the tip at its quasi-static
    position k2/(k1+k2) x3 (eq 4.10) and at rest."""
    x3 = np.asarray(x3, dtype=float).ravel()
    x4 = np.asarray(x4, dtype=float).ravel()
    x0 = np.zeros((x3.size, 4))
    x0[:, 0] = model.k2 / (model.k1 + model.k2) * x3
    x0[:, 2] = x3
    x0[:, 3] = x4
    return x0


def basin_labels(
    x3_0: np.ndarray,
    x4_0: np.ndarray,
    u0: float,
    psi: float,
    model: TwoMassModel = DEFAULT_MODEL,
    dt: float | None = None,
    tmax: float = 3000.0,
    tol: float = 1e-4,
) -> dict[str, np.ndarray]:
    """Steady state reached from each sample initial condition (x3_0[i], x4_0[i]), v = 0.

    Each cell is integrated (compiled RK4, all cells in one call) until (a) its energy is
    below the barrier of the well holding the sample (so it can never leave it, see the
    module docstring) and (b) |x3 - node| < tol and |x4| < tol.  Returns ``label`` (index of
    the node in increasing X; -1 if not settled by ``tmax``), ``x3_final`` (the node X of the
    label, NaN if unsettled), ``x3_end`` (integrated x3 at stop), ``t_settle``.
    """
    _check_u0_psi(u0, psi)
    eq = equilibria(u0, psi)
    nodes, left, right, barrier = well_table(eq)
    if dt is None:
        dt = min(0.02, model.max_stable_dt(u0))
    x3_0 = np.asarray(x3_0, dtype=float)
    x4_0 = np.asarray(x4_0, dtype=float)
    shape = np.broadcast_shapes(x3_0.shape, x4_0.shape)
    x3b, x4b = np.broadcast_to(x3_0, shape), np.broadcast_to(x4_0, shape)
    if not (np.all(np.isfinite(x3b)) and np.all(np.isfinite(x4b))):
        raise ParameterError("basin initial conditions must be finite")
    x0 = initial_states(x3b, x4b, model)
    n = x0.shape[0]
    lab = np.empty(n, dtype=np.int64)
    xe = np.empty((n, 4))
    te = np.empty(n)
    # Energy margin: RK4's energy error per step is O((omega dt)^5) relative; 1e-9 (1+u0)
    # keeps the certificate conservative without delaying it measurably.
    margin = 1e-9 * (1.0 + u0)
    basins(
        x0, float(u0), float(psi), model.coefficients(), float(dt), float(tmax),
        nodes, left, right, barrier, float(tol), margin, lab, xe, te,
    )
    xf = np.where(lab >= 0, nodes[np.clip(lab, 0, None)], np.nan)
    return {
        "label": lab.reshape(shape),
        "x3_final": xf.reshape(shape),
        "x3_end": xe[:, 2].reshape(shape),
        "t_settle": te.reshape(shape),
    }


def basin_cell(x3_0, x4_0, u0: float, psi: float, dt: float | None = None, tmax: float = 3000.0, tol: float = 1e-4, **model_params):
    """Sweep-engine entry point (see :mod:`probedyn.schemes.sweep`): vectorised over cells."""
    model = TwoMassModel.from_params(model_params) if model_params else DEFAULT_MODEL
    r = basin_labels(x3_0, x4_0, u0, psi, model=model, dt=dt, tmax=tmax, tol=tol)
    return {"label": r["label"].astype(np.int32), "x3_final": r["x3_final"], "t_settle": r["t_settle"]}


def default_basin_window(u0: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """Default initial-condition window: x3(0) in +-1.5 max(u0, 1), x4(0) in +-max(u0, 1)."""
    s = max(float(u0), 1.0)
    return (-1.5 * s, 1.5 * s), (-s, s)


# --------------------------------------------------------------------------------------
# Dynamics with the base moving (v > 0): attractors, limit cycles, branches, regime map
# --------------------------------------------------------------------------------------

STAT_NAMES = ["x3_min", "x3_max", "x3_mean", "x4_min", "x4_max", "friction_mean", "dissipated", "y1_mean"]


@dataclass
class AttractorSettings:
    """Integration settings for the periodic steady states (documented in docs/stickslip.md)."""

    steps_per_period: int = 256  # RK4 steps per forcing period 2 pi / v (capped by stability)
    t_transient: float = 300.0  # transient discarded (tip mode decays at ~0.1 per unit time)
    min_transient_periods: int = 3
    record_periods: int = 4  # record length (periodic orbits up to period 4 are resolved)


def attractor_stats(
    u0: np.ndarray | float,
    v: np.ndarray | float,
    x3_0: np.ndarray | float = 0.0,
    x4_0: np.ndarray | float = 0.0,
    psi: float = 0.0,
    model: TwoMassModel = DEFAULT_MODEL,
    settings: AttractorSettings | None = None,
) -> dict[str, np.ndarray]:
    """Periodic steady state of eq 4.7 for each (u0, v, x3_0, x4_0) (broadcast together).

    The forcing ``u0 sin(y2 + v t + psi)`` has period ``T = 2 pi / v``; steps are chosen as an
    integer number per period (so the record spans whole periods and the strobe samples are
    at identical forcing phase), at most 0.02 and below the RK4 stability limit.  The
    transient is ``max(t_transient, min_transient_periods T)``.  Returns the STAT_NAMES
    arrays, ``strobe_x3``/``strobe_x4`` (one sample per period) and ``w_min``/``w_max``: the
    extremes of the sample's LAB velocity ``x4 + v``.
    """
    s = settings or AttractorSettings()
    u0a, va, x3a, x4a = np.broadcast_arrays(*(np.asarray(q, dtype=float) for q in (u0, v, x3_0, x4_0)))
    shape = u0a.shape
    u0f, vf, x3f, x4f = (q.ravel() for q in (u0a, va, x3a, x4a))
    if np.any(~np.isfinite(vf)) or np.any(vf <= 0):
        raise ParameterError("speed v must be positive and finite for the moving-base dynamics (use basins for v = 0)")
    if np.any(vf > V_MAX):
        raise ParameterError(f"speed v = {vf.max():g} is beyond {V_MAX:g}: the transient alone would take about "
                             f"6000 v integration steps per cell (give v <= {V_MAX:g})")
    if np.any(~np.isfinite(u0f)) or np.any(u0f < 0):
        raise ParameterError("u0 must be finite and >= 0")
    n = u0f.size
    stats = np.empty((n, len(STAT_NAMES)))
    strobe = np.full((n, s.record_periods, 2), np.nan)
    c = model.coefficients()
    kern = attractor
    x0 = initial_states(x3f, x4f, model)
    # group cells by speed (dt depends on v only through the period and on u0 through stability)
    for vv in np.unique(vf):
        sel = np.nonzero(vf == vv)[0]
        T = 2 * math.pi / vv
        dt_max = min(0.02, min(model.max_stable_dt(float(u)) for u in np.unique(u0f[sel])))
        n_sub = max(s.steps_per_period, int(math.ceil(T / dt_max)))
        dt = T / n_sub
        n_trans_periods = max(s.min_transient_periods, int(math.ceil(s.t_transient / T)))
        # u0 differs per cell: run the kernel per distinct u0 within this speed
        for uu in np.unique(u0f[sel]):
            sub = sel[u0f[sel] == uu]
            st2 = np.empty((sub.size, len(STAT_NAMES)))
            sb2 = np.full((sub.size, s.record_periods, 2), np.nan)
            kern(np.ascontiguousarray(x0[sub]), float(uu), float(vv), float(psi), c, dt,
                 n_trans_periods * n_sub, s.record_periods * n_sub, n_sub, sb2, st2)
            stats[sub] = st2
            strobe[sub] = sb2
    out = {name: stats[:, j].reshape(shape) for j, name in enumerate(STAT_NAMES)}
    out["dissipated"] = out["dissipated"] / s.record_periods  # per forcing period
    out["strobe_x3"] = strobe[:, :, 0].reshape(shape + (s.record_periods,))
    out["strobe_x4"] = strobe[:, :, 1].reshape(shape + (s.record_periods,))
    out["w_min"] = out["x4_min"] + va
    out["w_max"] = out["x4_max"] + va
    return out


def trajectory(x0: np.ndarray, u0: float, v: float, psi: float, t_end: float, model: TwoMassModel = DEFAULT_MODEL,
               dt: float | None = None, n_out: int = 2000) -> np.ndarray:
    """One trajectory (compiled RK4) sampled at about n_out points: columns t, y1, y1', y2, y2'."""
    if dt is None:
        dt = min(0.02, model.max_stable_dt(u0))
        if v > 0:
            dt = min(dt, 2 * math.pi / v / 256)
    nsteps = int(math.ceil(t_end / dt))
    every = max(1, nsteps // n_out)
    out = np.full((nsteps // every + 1, 5), np.nan)
    trajectory_kernel(np.asarray(x0, dtype=float), float(u0), float(v), float(psi), model.coefficients(), float(dt), nsteps, every, out)
    return out[~np.isnan(out[:, 0])]


def phase_portrait(u0: float, psi: float = 5.0, v: float = 0.0, n_ic: int = 24, t_end: float = 60.0,
                   model: TwoMassModel = DEFAULT_MODEL, window: tuple | None = None) -> dict[str, Any]:
    """Sample phase-plane (x3, x4) trajectories from initial conditions on the window's
    border and its mid-line (as in Figs 4.8 and 4.10); with the equilibria for v = 0."""
    _check_u0_psi(u0, psi)
    (x3lo, x3hi), (x4lo, x4hi) = window or default_basin_window(u0)
    k = max(2, n_ic // 3)
    ics = [(x, x4hi) for x in np.linspace(x3lo, x3hi, k)] + [(x, x4lo) for x in np.linspace(x3lo, x3hi, k)]
    ics += [(x, 0.0) for x in np.linspace(x3lo, x3hi, n_ic - 2 * k)]
    trajs = []
    for x3, x4 in ics:
        x0 = initial_states(np.array([x3]), np.array([x4]), model)[0]
        trajs.append(trajectory(x0, u0, v, psi, t_end, model))
    out: dict[str, Any] = {"u0": u0, "psi": psi, "v": v, "trajectories": trajs}
    if v == 0:
        out["equilibria"] = equilibria(u0, psi)
    return out


def limit_cycles(u0: float, v_values: np.ndarray, model: TwoMassModel = DEFAULT_MODEL,
                 settings: AttractorSettings | None = None, psi: float = 0.0) -> dict[str, np.ndarray]:
    """Limit cycle of the sample for each speed (Figs 4.10-4.11), started at rest at x3 = 0.

    Amplitude = half the x3 range over the cycle, centre = its time-averaged x3 (the mean
    sample-base separation, eq 4.6), plus the x4 range and mean friction; the orbit itself is
    returned sampled over the last forcing periods (``orbits``: list of (t, x3, x4) arrays).
    """
    v_values = np.asarray(v_values, dtype=float)
    st = attractor_stats(u0, v_values, 0.0, 0.0, psi=psi, model=model, settings=settings)
    s = settings or AttractorSettings()
    orbits = []
    for v in v_values:
        T = 2 * math.pi / v
        t_tr = max(s.t_transient, s.min_transient_periods * T)
        nper = 2
        tr = trajectory(np.zeros(4), u0, v, psi, t_tr + nper * T, model, n_out=20000)
        orbits.append(tr[tr[:, 0] >= t_tr][:, [0, 3, 4]])
    return {
        "v": v_values,
        "amplitude": 0.5 * (st["x3_max"] - st["x3_min"]),
        "centre": st["x3_mean"],
        "x4_amplitude": 0.5 * (st["x4_max"] - st["x4_min"]),
        "friction_mean": st["friction_mean"],
        "dissipated": st["dissipated"],
        "y1_mean": st["y1_mean"],
        "w_min": st["w_min"],
        "w_max": st["w_max"],
        "orbits": orbits,
    }


def linear_response_amplitude(u0: float, v: float, model: TwoMassModel = DEFAULT_MODEL) -> float:
    """High-speed limit: amplitude of y2 for the linear system forced by u0 sin(v t) on the
    sample (y2 small, so sin(y2 + vt) ~ sin(vt)).  Exact 2-DOF transfer function."""
    c = model.coefficients()
    mu1, mu2, ka1, ka2, z1, z2 = c
    w = v
    K = np.array([[ka1 + ka2, -ka2], [-ka2, ka2]], dtype=complex)
    C = np.array([[z1 + z2, -z2], [-z2, z2]], dtype=complex)
    M = np.diag([mu1, mu2]).astype(complex)
    Z = K + 1j * w * C - w**2 * M
    h = np.linalg.solve(Z, np.array([0.0, u0], dtype=complex))
    return float(abs(h[1]))


# regime classification thresholds (docs/stickslip.md): the sample "sticks" when its lab
# velocity falls below STICK_FRACTION v.  In the quasi-static limit the lab velocity on a
# stable branch is v / (1 - u0 cos(X + psi)) >= v / (1 + u0), so STICK_FRACTION = 1/2 puts
# the quasi-static boundary exactly at the fold criterion u0 = 1.  "Steady sliding": no
# stick and a lab-velocity modulation (w_max - w_min)/v below SLIDING_MODULATION.
STICK_FRACTION = 0.5
SLIDING_MODULATION = 0.2
REGIMES = {
    0: "no stick-slip",
    1: "stick-slip",
    2: "coexisting regimes",
    3: "steady sliding",
    4: "irregular stick-slip",
}


def strobe_period(sb: np.ndarray, tol: float, p_max: int | None = None) -> int:
    """Smallest p (in forcing periods) with sb[k + p] == sb[k] (within tol) over the whole
    record; 0 if none up to p_max (default: half the record), i.e. not (yet) periodic."""
    n = sb.shape[0]
    p_max = p_max or n // 2
    for p in range(1, p_max + 1):
        if np.all(np.abs(sb[p:] - sb[:-p]) < tol):
            return p
    return 0


def _distinct(strobes: list[np.ndarray], tol: float) -> int:
    """Number of distinct periodic attractors: two trajectories share one when their strobe
    sets (one point per forcing period) coincide within tol as sets."""
    reps: list[np.ndarray] = []
    for pts in strobes:
        found = False
        for r in reps:
            d = np.abs(pts[:, None, :] - r[None, :, :]).max(axis=2)
            if d.min(axis=1).max() < tol and d.min(axis=0).max() < tol:
                found = True
                break
        if not found:
            reps.append(pts)
    return len(reps)


def regime_cell(u0, v, n_ic: int = 6, psi: float = 0.0, steps_per_period: int = 128,
                t_transient: float = 300.0, transient_periods: int = 8, record_periods: int = 8,
                confirm_factor: float = 10.0, **model_params) -> dict[str, np.ndarray]:
    """Sweep-engine entry point: classify the steady dynamics at each (u0[i], v[i]) (Fig 4.13).

    ``n_ic`` trajectories start at rest at x3(0) evenly spread over [-u0-pi, u0+pi] (the
    range of the quasi-static equilibria).  After a transient of max(t_transient,
    transient_periods T) each is recorded for ``record_periods`` forcing periods
    T = 2 pi / v.  A trajectory is periodic with period p if its stroboscopic samples
    repeat after p periods (p <= record_periods/2).  Classification (codes in REGIMES):

    * 2 "coexisting regimes": >= 2 distinct periodic attractors;
    * 4 "irregular stick-slip": a trajectory is not periodic (chaotic, quasi-periodic or a
      transient longer than the window) and no second periodic attractor was found;
    * otherwise one attractor: 1 "stick-slip" if the sample's lab speed x4 + v drops below
      STICK_FRACTION v, else 3 "steady sliding" if the lab-speed modulation is below
      SLIDING_MODULATION v, else 0 "no stick-slip" (smooth, corrugated motion).

    Cells classified 2 or 4 are re-run with a transient ``confirm_factor`` times longer
    (long transients near period-doubling transitions otherwise look like extra attractors);
    the confirmed class is returned.

    Also returns the number of distinct periodic attractors, the period of the attractor
    reached from x3(0) = 0 (0 = irregular), the extreme lab-speed ratios and its mean friction.
    """
    if isinstance(n_ic, bool) or int(n_ic) != n_ic or n_ic < 1:
        raise ParameterError(f"n_ic (initial conditions per cell) must be a positive integer, got {n_ic!r}")
    out = _regime_pass(u0, v, n_ic, psi, steps_per_period, t_transient, transient_periods, record_periods,
                       model_params)
    redo = np.nonzero((out["regime"] == 2) | (out["regime"] == 4))[0]
    if redo.size and confirm_factor > 1:
        u0a, va = (np.broadcast_arrays(np.atleast_1d(np.asarray(u0, float)), np.atleast_1d(np.asarray(v, float))))
        again = _regime_pass(u0a.ravel()[redo], va.ravel()[redo], n_ic, psi, steps_per_period,
                             t_transient * confirm_factor, int(transient_periods * confirm_factor), record_periods,
                             model_params)
        for k in out:
            out[k][redo] = again[k]
    return out


def _regime_pass(u0, v, n_ic, psi, steps_per_period, t_transient, transient_periods, record_periods,
                 model_params) -> dict[str, np.ndarray]:
    model = TwoMassModel.from_params(model_params) if model_params else DEFAULT_MODEL
    u0 = np.atleast_1d(np.asarray(u0, dtype=float))
    v = np.atleast_1d(np.asarray(v, dtype=float))
    u0, v = (q.ravel() for q in np.broadcast_arrays(u0, v))
    n = u0.size
    frac = np.linspace(-1.0, 1.0, n_ic) if n_ic > 1 else np.zeros(1)
    x3_0 = (u0[:, None] + math.pi) * frac[None, :]
    settings = AttractorSettings(steps_per_period=steps_per_period, t_transient=t_transient,
                                 min_transient_periods=transient_periods, record_periods=record_periods)
    st = attractor_stats(np.repeat(u0[:, None], n_ic, axis=1), np.repeat(v[:, None], n_ic, axis=1), x3_0, 0.0,
                         psi=psi, model=model, settings=settings)
    regime = np.empty(n, dtype=np.int32)
    n_att = np.empty(n, dtype=np.int32)
    period = np.empty(n, dtype=np.int32)
    mid = n_ic // 2
    for i in range(n):
        # tolerance: 1e-3 of the excursion scale (1 + u0); the RK4 error of the sample motion
        # at <= 0.02 per step is orders of magnitude smaller.
        tol = 1e-3 * (1.0 + u0[i])
        sbs = [np.stack([st["strobe_x3"][i, j], st["strobe_x4"][i, j]], axis=-1) for j in range(n_ic)]
        per = [strobe_period(sb, tol) for sb in sbs]
        periodic = [sb for sb, p in zip(sbs, per) if p > 0]
        n_att[i] = _distinct(periodic, tol)
        period[i] = per[mid]
        if n_att[i] > 1:
            regime[i] = 2
        elif len(periodic) < n_ic:
            regime[i] = 4
        elif np.any(st["w_min"][i] < STICK_FRACTION * v[i]):
            regime[i] = 1
        else:
            mod = (st["w_max"][i] - st["w_min"][i]).max() / v[i]
            regime[i] = 3 if mod < SLIDING_MODULATION else 0
    return {
        "regime": regime,
        "n_attractors": n_att,
        "period": period,
        "w_min_ratio": st["w_min"].min(axis=1) / v,
        "w_max_ratio": st["w_max"].max(axis=1) / v,
        "friction_mean": st["friction_mean"][:, mid],
    }


def steady_branches(u0_values: np.ndarray, v: float, n_ic: int = 12, psi: float = 5.0,
                    model: TwoMassModel = DEFAULT_MODEL, settings: AttractorSettings | None = None) -> dict[str, Any]:
    """Steady-state sample coordinates x3* vs u0 (Fig 4.12).

    v = 0 (quasi-static): the nodes of eq 4.11 at phase psi reached from a set of initial
    conditions (the stable equilibria, each confirmed by the basin integration).  v > 0:
    the x3 samples of the periodic attractors reached from ``n_ic`` rest states spread over
    |x3(0)| <= u0 + pi; a stick-slip cycle shows as a vertical spread (branch widening).
    Returns per u0 an array of x3* values (v = 0) or an (n_ic, 3) array of the attractors'
    (min, max, mean) x3 (v > 0).
    """
    u0_values = np.asarray(u0_values, dtype=float)
    out: list[np.ndarray] = []
    if v == 0:
        for u in u0_values:
            x3_0 = np.linspace(-(u + math.pi), u + math.pi, n_ic)
            r = basin_labels(x3_0, np.zeros_like(x3_0), u, psi, model=model)
            out.append(np.unique(r["x3_final"][r["label"] >= 0]))
    else:
        s = settings or AttractorSettings()
        frac = np.linspace(-1.0, 1.0, n_ic)
        U = np.repeat(u0_values[:, None], n_ic, axis=1)
        x3_0 = (U + math.pi) * frac[None, :]
        st = attractor_stats(U, v, x3_0, 0.0, psi=psi, model=model, settings=s)
        for i in range(u0_values.size):
            out.append(np.stack([st["x3_min"][i], st["x3_max"][i], st["x3_mean"][i]], axis=1))
    return {"u0": u0_values, "v": v, "x3": out}


def is_stick(u0: float, v: float, n_ic: int = 3, **kw) -> bool:
    """True when the steady motion at (u0, v) contains stick phases (regimes 1, 2, 4)."""
    return int(regime_cell(np.array([u0]), np.array([v]), n_ic=n_ic, **kw)["regime"][0]) in (1, 2, 4)


def stick_boundary(fixed: float, lo: float, hi: float, along: str = "v", rtol: float = 1e-2,
                   n_ic: int = 3, **kw) -> float:
    """Boundary of the stick-slip region found by bisection (Fig 4.13).

    ``along="v"``: at u0 = ``fixed``, the speed in [lo, hi] above which the motion no longer
    sticks (geometric bisection).  ``along="u0"``: at v = ``fixed``, the amplitude u0 in
    [lo, hi] above which stick-slip appears; in the quasi-static limit v -> 0 this tends to
    the fold criterion u0 = 1 (eq 4.12).  Requires the criterion to differ at the two ends.
    """
    if along not in ("v", "u0"):
        raise ParameterError(f"along must be 'v' or 'u0', got {along!r}")
    if not (0 < lo < hi):
        raise ParameterError(f"bisection bracket must satisfy 0 < lo < hi, got [{lo:g}, {hi:g}]")

    def f(x: float) -> bool:
        return is_stick(fixed, x, n_ic, **kw) if along == "v" else is_stick(x, fixed, n_ic, **kw)

    flo, fhi = f(lo), f(hi)
    if flo == fhi:
        raise SolverError(f"no stick-slip boundary in [{lo:g}, {hi:g}] along {along} (both ends {'stick' if flo else 'smooth'})")
    while hi / lo - 1 > rtol:
        mid = math.sqrt(lo * hi) if along == "v" else 0.5 * (lo + hi)
        if f(mid) == flo:
            lo = mid
        else:
            hi = mid
    return math.sqrt(lo * hi) if along == "v" else 0.5 * (lo + hi)
