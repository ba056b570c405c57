"""Closed-loop simulation of path tracking: plant + controller + substrate + amplifier + sensor.

The closed loop is linear except for two optional terms, so it is integrated by an
**exponential integrator** that is exact for the linear part whatever its stiffness (the tube's
axial mode at 45 kHz, the eps -> 0 family of section 3.5.3)::

    X' = A_cl X + F(t) + N(X, t),    X = [q; q'; xi]

* ``A_cl = A + Bu Kx`` (+ the PID integrator), ``F(t) = Bu (w(t) + Kx S nu(t))`` + the
  integrator's ``n - r``: reference terms and sensor noise ``nu = (n, n')`` on the measured tip;
* ``N(X, t) = Bu (sat(u) - u) + Bf F_sub(q1)``: amplifier saturation at ``+-v_max`` and the
  substrate force (:mod:`.disturbance`).

Scheme (Cox-Matthews ETD2RK with a first-order hold on F): with ``Phi = e^(A h)``,
``P1 = h phi1(A h)``, ``P2 = h phi2(A h)`` (one augmented matrix exponential, Van Loan):

    a       = Phi X_k + P1 (F_k + N_k) + P2 (F_k+1 - F_k)
    X_k+1   = a + P2 (N(a, t_k+1) - N_k)

For ``N = 0`` it is exact for piecewise-linear F; for a smooth F the first-order hold errs by at
most ``h^2 max|F''| / 8`` (the bound the tests use); with N it is second order. The step only
has to resolve the inputs (path, noise band, lattice crossings ``v / a``), not the plant's
modes. A numba kernel runs the loop. :func:`simulate_ivp` solves the same ODE with
``scipy.integrate.solve_ivp`` (optionally with the analytic Jacobian ``A_cl + dN/dX``) for
cross-checks and the benchmark.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
from numba import njit
from scipy.integrate import solve_ivp

from probedyn.core.errors import ParameterError, SolverError
from probedyn.schemes.tracking import inversion
from probedyn.schemes.tracking.controllers import Law
from probedyn.schemes.tracking.disturbance import PeriodicSurface
from probedyn.schemes.tracking.paths import Path
from probedyn.schemes.tracking.plants import MechanicalPlant


# ---------------------------------------------------------------------------------------------
# sensor noise
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SensorNoise:
    """Band-limited Gaussian noise on the measured tip position: RMS ``rms`` [m] per axis, flat
    spectrum up to ``bandwidth_hz``, seed ``seed``. Synthesised by FFT on a uniform grid as a sum
    of equal-amplitude random-phase sinusoids at the grid's Fourier frequencies below the band
    (so its RMS over the record is exactly ``rms``), with its exact derivative n'(t) (spectral);
    between grid points it is interpolated linearly."""

    rms: float
    bandwidth_hz: float = 10e3
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rms) and 0 <= self.rms < 1e-6):
            raise ParameterError(f"sensor noise RMS must be in [0, 1 um), got {self.rms:g} m")
        if not (math.isfinite(self.bandwidth_hz) and self.bandwidth_hz > 0):
            raise ParameterError("sensor noise bandwidth must be positive")

    def realise(self, duration: float, n_axes: int, h: float):
        """A function nu(t) -> (n, 2 n_axes) = (n, n') on [0, duration], synthesised on a grid of
        step ``h``."""
        N = int(math.ceil(duration / h)) + 1
        rng = np.random.default_rng(self.seed)
        f = np.fft.rfftfreq(N, h)
        band = (f > 0) & (f <= self.bandwidth_hz)
        nb = int(band.sum())
        if nb == 0:
            raise ParameterError("sensor noise: the band holds no frequency of the record (too short?)")
        ph = rng.uniform(0, 2 * math.pi, size=(nb, n_axes))
        amp = self.rms * math.sqrt(2.0 / nb)
        Z = np.zeros((f.size, n_axes), dtype=complex)
        Z[band] = amp * np.exp(1j * ph) * (N / 2)
        n = np.fft.irfft(Z, n=N, axis=0)
        dn = np.fft.irfft(Z * (2j * math.pi * f)[:, None], n=N, axis=0)
        tg = np.arange(N) * h
        vals = np.hstack([n, dn])

        def nu(t: np.ndarray) -> np.ndarray:
            t = np.atleast_1d(t)
            return np.stack([np.interp(t, tg, vals[:, j]) for j in range(vals.shape[1])], axis=1)

        return nu

    def describe(self) -> dict[str, Any]:
        return {"rms_m": self.rms, "bandwidth_hz": self.bandwidth_hz, "seed": self.seed}


# ---------------------------------------------------------------------------------------------
# the closed loop
# ---------------------------------------------------------------------------------------------


class ClosedLoop:
    """Plant + law + substrate + saturation + noise, with the forcing F(t) for a path."""

    def __init__(self, plant: MechanicalPlant, law: Law, path: Path, surface: PeriodicSurface | None = None,
                 v_max: float | None = None, noise: SensorNoise | None = None) -> None:
        self.plant, self.law, self.path, self.surface, self.noise = plant, law, path, surface, noise
        if v_max is not None and not (math.isfinite(v_max) and v_max > 0):
            raise ParameterError(f"voltage limit must be positive, got {v_max:g} V")
        self.v_max = v_max
        A, Bu, Bf, _ = plant.state_space()
        n2, m, d = A.shape[0], Bu.shape[1], len(plant.outputs)
        if law.Kx.shape != (m, n2):
            raise ParameterError(f"controller gains {law.Kx.shape} do not fit the plant ({m}, {n2})")
        self.ni = d if law.Ki is not None else 0
        nX = n2 + self.ni
        self.nX, self.n2, self.d, self.m = nX, n2, d, m
        Ku = np.zeros((m, nX))
        Ku[:, :n2] = law.Kx
        if self.ni:
            Ku[:, n2:] = law.Ki
        Acl = np.zeros((nX, nX))
        Acl[:n2, :n2] = A
        Bu_cl = np.zeros((nX, m))
        Bu_cl[:n2] = Bu
        Acl += Bu_cl @ Ku
        if self.ni:
            Acl[n2:, :n2] = np.hstack([plant.Cq, np.zeros((d, plant.n))])
        self.A, self.Bu, self.Ku = Acl, Bu_cl, Ku
        Bf_cl = np.zeros((nX, Bf.shape[1]))
        Bf_cl[:n2] = Bf
        self.Bf = Bf_cl
        # measured state = x + S nu (noise on tip position and velocity)
        S = np.zeros((n2, 2 * d))
        S[:plant.n, :d] = np.linalg.pinv(plant.Cq)
        S[plant.n:, d:] = np.linalg.pinv(plant.Cq)
        self.S = S
        # substrate axes among the plant outputs (-1: the tip does not move along it)
        if surface is not None:
            self.sub_idx = [plant.outputs.index(a) if a in plant.outputs else -1 for a in surface.axes]
        else:
            self.sub_idx = [-1, -1]
        self._nu = None
        self.noise_step = None

    def set_noise_grid(self, t_end: float, h: float) -> None:
        """Synthesise the sensor noise on the simulation grid (step h up to t_end)."""
        if self.noise is not None and self.noise.rms > 0:
            self._nu = self.noise.realise(t_end, self.d, h)
            self.noise_step = h

    # -- exogenous terms --------------------------------------------------------------------
    def reference(self, t: np.ndarray) -> np.ndarray:
        R = self.path.derivatives(t)
        return inversion.path_on_outputs(self.plant, R)

    def exogenous(self, t: np.ndarray, R: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F (n, nX), w_u (n, m): the part of u that is not Ku X, R)."""
        if R is None:
            R = self.reference(t)
        w = self.law.w(R, t)
        wu = np.array(w, dtype=float)
        nu = self._nu(t) if self._nu is not None else None
        if nu is not None:
            wu = wu + nu @ (self.law.Kx @ self.S).T
        F = wu @ self.Bu.T
        if self.ni:
            F[:, self.n2:] += -R[0] + (nu[:, :self.d] if nu is not None else 0.0)
        return F, wu, R

    # -- nonlinear terms --------------------------------------------------------------------
    def nonlinear(self, X: np.ndarray, wu: np.ndarray) -> np.ndarray:
        out = np.zeros_like(X)
        if self.v_max is not None:
            u = self.Ku @ X + wu
            out += self.Bu @ (np.clip(u, -self.v_max, self.v_max) - u)
        if self.surface is not None:
            f = self.surface.force(self._sub_pos(X))
            out += self.Bf @ self._sub_force(f)
        return out

    def _sub_pos(self, X: np.ndarray) -> np.ndarray:
        return np.array([X[i] if i >= 0 else 0.0 for i in self.sub_idx])

    def _sub_force(self, f: np.ndarray) -> np.ndarray:
        g = np.zeros(self.d)
        for j, i in enumerate(self.sub_idx):
            if i >= 0:
                g[i] += f[j]
        return g

    def jacobian(self, X: np.ndarray, wu: np.ndarray) -> np.ndarray:
        J = self.A.copy()
        if self.v_max is not None:
            u = self.Ku @ X + wu
            sat = (np.abs(u) > self.v_max).astype(float)
            J -= self.Bu @ (sat[:, None] * self.Ku)
        if self.surface is not None:
            Jf = self.surface.jacobian(self._sub_pos(X))
            P = np.zeros((2, self.nX))
            for j, i in enumerate(self.sub_idx):
                if i >= 0:
                    P[j, i] = 1.0
            E = np.zeros((self.d, 2))
            for j, i in enumerate(self.sub_idx):
                if i >= 0:
                    E[i, j] = 1.0
            J += self.Bf @ E @ Jf @ P
        return J

    def initial_state(self, F0: np.ndarray) -> np.ndarray:
        """Equilibrium of the linear closed loop with the forcing held at its t = 0 value."""
        try:
            return -np.linalg.solve(self.A, F0)
        except np.linalg.LinAlgError:
            raise SolverError("the closed loop has no equilibrium at t = 0 (singular A)") from None


# ---------------------------------------------------------------------------------------------
# exponential integrator
# ---------------------------------------------------------------------------------------------


def phi_matrices(A: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e^(Ah), h phi1(Ah), h phi2(Ah)) from one augmented exponential (Van Loan)."""
    n = A.shape[0]
    Z = np.zeros((3 * n, 3 * n))
    Z[:n, :n] = A * h
    Z[:n, n:2 * n] = np.eye(n) * h
    Z[n:2 * n, 2 * n:] = np.eye(n)
    E = sla.expm(Z)
    return E[:n, :n], E[:n, n:2 * n], E[:n, 2 * n:]


@njit(cache=True)
def _matvec(A, x, out):
    n, m = A.shape
    for i in range(n):
        acc = 0.0
        for j in range(m):
            acc += A[i, j] * x[j]
        out[i] = acc


@njit(cache=True)
def _nonlin(X, wu, Ku, Bu, vmax, Bf, sub_idx, p1, p2, kk, off0, off1, use_sat, use_sub, res, u, du, g, tmp):
    """res = N(X); u = applied voltages (saturated)."""
    nX = X.shape[0]
    m = Ku.shape[0]
    _matvec(Ku, X, u)
    for i in range(m):
        u[i] += wu[i]
    for i in range(nX):
        res[i] = 0.0
    if use_sat:
        for i in range(m):
            v = u[i]
            if v > vmax:
                du[i] = vmax - v
                u[i] = vmax
            elif v < -vmax:
                du[i] = -vmax - v
                u[i] = -vmax
            else:
                du[i] = 0.0
        _matvec(Bu, du, tmp)
        for i in range(nX):
            res[i] += tmp[i]
    if use_sub:
        px = X[sub_idx[0]] if sub_idx[0] >= 0 else 0.0
        py = X[sub_idx[1]] if sub_idx[1] >= 0 else 0.0
        xa = (px + off0) * kk
        ya = (py + off1) * kk
        fx = kk * np.sin(xa) * (p1 + p2 * np.cos(ya))
        fy = kk * np.sin(ya) * (p1 + p2 * np.cos(xa))
        for i in range(g.shape[0]):
            g[i] = 0.0
        if sub_idx[0] >= 0:
            g[sub_idx[0]] += fx
        if sub_idx[1] >= 0:
            g[sub_idx[1]] += fy
        _matvec(Bf, g, tmp)
        for i in range(nX):
            res[i] += tmp[i]


@njit(cache=True)
def _etd2_kernel(Phi, P1, P2, F, WU, X0, Ku, Bu, vmax, Bf, sub_idx, p1, p2, kk, off0, off1, use_sat, use_sub, stride):
    nX = X0.shape[0]
    m = Ku.shape[0]
    d = Bf.shape[1]
    nsteps = F.shape[0] - 1
    nout = nsteps // stride + 1
    out = np.empty((nout, nX))
    U = np.empty((nout, m))
    X = X0.copy()
    N = np.zeros(nX)
    Na = np.zeros(nX)
    a = np.zeros(nX)
    t1 = np.zeros(nX)
    t2 = np.zeros(nX)
    t3 = np.zeros(nX)
    tmp = np.zeros(nX)
    u = np.zeros(m)
    du = np.zeros(m)
    g = np.zeros(d)
    nl = use_sat or use_sub
    _nonlin(X, WU[0], Ku, Bu, vmax, Bf, sub_idx, p1, p2, kk, off0, off1, use_sat, use_sub, N, u, du, g, tmp)
    out[0] = X
    U[0] = u
    j = 1
    for k in range(nsteps):
        for i in range(nX):
            t2[i] = F[k, i] + N[i]
            t3[i] = F[k + 1, i] - F[k, i]
        _matvec(Phi, X, a)
        _matvec(P1, t2, t1)
        for i in range(nX):
            a[i] += t1[i]
        _matvec(P2, t3, t1)
        for i in range(nX):
            a[i] += t1[i]
        if nl:
            _nonlin(a, WU[k + 1], Ku, Bu, vmax, Bf, sub_idx, p1, p2, kk, off0, off1, use_sat, use_sub, Na, u, du, g, tmp)
            for i in range(nX):
                t3[i] = Na[i] - N[i]
            _matvec(P2, t3, t1)
            for i in range(nX):
                X[i] = a[i] + t1[i]
            _nonlin(X, WU[k + 1], Ku, Bu, vmax, Bf, sub_idx, p1, p2, kk, off0, off1, use_sat, use_sub, N, u, du, g, tmp)
        else:
            for i in range(nX):
                X[i] = a[i]
            _matvec(Ku, X, u)
            for i in range(m):
                u[i] += WU[k + 1, i]
        if (k + 1) % stride == 0:
            for i in range(nX):
                out[j, i] = X[i]
            for i in range(m):
                U[j, i] = u[i]
            j += 1
    return out, U


def _default_step(cl: ClosedLoop, t_end: float) -> float:
    h = t_end / 4000
    sp = cl.path.peak_speed()
    if cl.surface is not None and sp > 0:
        h = min(h, cl.surface.a / (25 * sp))  # >= 25 steps per lattice crossing
    if cl.noise is not None and cl.noise.rms > 0:
        h = min(h, 1.0 / (20 * cl.noise.bandwidth_hz))
    return h


@dataclass
class TrackingResult:
    """Time histories and error metrics of one tracking simulation (SI)."""

    t: np.ndarray
    r: np.ndarray
    y: np.ndarray
    u: np.ndarray
    q2: np.ndarray
    outputs: list[str]
    inputs: list[str]
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def e(self) -> np.ndarray:
        return self.y - self.r

    def metrics(self, transient: float | None = None) -> dict[str, Any]:
        """RMS and max error per axis (whole run and after ``transient`` s, default 5 % of the
        run), error relative to the path's extent, peak voltages."""
        e = self.e
        T = float(self.t[-1] - self.t[0])
        tt = 0.05 * T if transient is None else transient
        late = self.t >= self.t[0] + tt
        extent = float(np.max(np.abs(self.r))) or 1.0
        ax = {}
        for i, a in enumerate(self.outputs):
            ax[a] = {"rms_m": float(np.sqrt(np.mean(e[:, i] ** 2))), "max_m": float(np.max(np.abs(e[:, i]))),
                     "rms_after_transient_m": float(np.sqrt(np.mean(e[late, i] ** 2))),
                     "max_after_transient_m": float(np.max(np.abs(e[late, i])))}
        en = np.linalg.norm(e, axis=1)
        return {"axes": ax, "path_extent_m": extent, "transient_s": tt,
                "max_error_m": float(en.max()), "rms_error_m": float(np.sqrt(np.mean(en**2))),
                "max_error_after_transient_m": float(en[late].max()),
                "relative_max_error_after_transient": float(en[late].max() / extent),
                "voltage_peak_V": {n: float(np.max(np.abs(self.u[:, j]))) for j, n in enumerate(self.inputs)}}

    def to_dict(self) -> dict[str, Any]:
        return {"outputs": self.outputs, "inputs": self.inputs, "metrics": self.metrics(), "info": self.info}


def _unpack(cl: ClosedLoop, t: np.ndarray, X: np.ndarray, U: np.ndarray, R: np.ndarray, info: dict) -> TrackingResult:
    p = cl.plant
    q = X[:, :p.n]
    y = q @ p.Cq.T
    q2 = q[:, cl.d:2 * cl.d] if q.shape[1] >= 2 * cl.d else np.zeros_like(y)
    return TrackingResult(t, R[0], y, U, q2, list(p.outputs), list(p.inputs), info)


def simulate(plant: MechanicalPlant, law: Law, path: Path, *, surface: PeriodicSurface | None = None,
             v_max: float | None = None, noise: SensorNoise | None = None, h: float | None = None,
             t_end: float | None = None, stride: int | None = None, x0: np.ndarray | None = None,
             max_points: int = 20000) -> TrackingResult:
    """Simulate ``law`` driving ``plant`` along ``path`` with the exponential integrator
    (module docstring). ``h``: step [s] (default: resolves the path, the lattice crossings and
    the noise band); ``stride``: keep every stride-th step (default: at most ``max_points``)."""
    cl = ClosedLoop(plant, law, path, surface, v_max, noise)
    T = float(path.duration if t_end is None else t_end)
    if not (math.isfinite(T) and T > 0):
        raise ParameterError(f"simulation end time must be positive, got {T:g} s")
    hh = _default_step(cl, T) if h is None else float(h)
    nsteps = int(math.ceil(T / hh))
    if nsteps > 5e7:
        raise ParameterError(f"{nsteps} steps needed (h = {hh:g} s): shorten the path or lower its speed")
    hh = T / nsteps
    t = np.linspace(0.0, T, nsteps + 1)
    wall = time.perf_counter()
    cl.set_noise_grid(T, hh)
    F, wu, R = cl.exogenous(t)
    X0 = cl.initial_state(F[0]) if x0 is None else np.asarray(x0, dtype=float)
    Phi, P1, P2 = phi_matrices(cl.A, hh)
    st = max(1, nsteps // max_points) if stride is None else int(stride)
    s = surface
    c = np.ascontiguousarray
    X, U = _etd2_kernel(c(Phi), c(P1), c(P2), c(F), c(wu), c(X0, dtype=float), c(cl.Ku), c(cl.Bu),
                        float(v_max or 0.0), c(cl.Bf), np.array(cl.sub_idx, dtype=np.int64),
                        float(s.p1) if s else 0.0, float(s.p2) if s else 0.0, float(s.k) if s else 0.0,
                        float(s.offset[0]) if s else 0.0, float(s.offset[1]) if s else 0.0,
                        v_max is not None, s is not None, st)
    idx = np.arange(0, nsteps + 1, st)[:X.shape[0]]
    info = {"integrator": "ETD2 exponential (exact linear part, first-order hold)", "step_s": hh, "steps": nsteps,
            "wall_s": time.perf_counter() - wall, "controller": law.name, "controller_info": law.info,
            "plant": plant.provenance, "path": path.describe(), "v_max_V": v_max,
            "surface": surface.describe() if surface else None, "noise": noise.describe() if noise else None}
    Rk = R[:, idx]
    return _unpack(cl, t[idx], X, U, Rk, info)


def simulate_ivp(plant: MechanicalPlant, law: Law, path: Path, *, surface: PeriodicSurface | None = None,
                 v_max: float | None = None, method: str = "RK45", jac: bool = False, rtol: float = 1e-6,
                 atol: float | None = None, t_eval: np.ndarray | None = None, t_end: float | None = None) -> TrackingResult:
    """The same closed loop with ``scipy.integrate.solve_ivp`` (forcing evaluated exactly at every
    stage; ``jac=True`` passes the analytic Jacobian ``A_cl + dN/dX``). For cross-checks and the
    benchmark; sensor noise is not supported here."""
    if law.grid_only:
        raise ParameterError("solve_ivp needs a controller whose reference terms are defined at any time")
    cl = ClosedLoop(plant, law, path, surface, v_max, None)
    T = float(path.duration if t_end is None else t_end)
    F0, _, _ = cl.exogenous(np.array([0.0]))
    X0 = cl.initial_state(F0[0])
    scale = max(float(np.max(np.abs(X0))), path.extent())
    at = atol if atol is not None else rtol * 1e-3 * scale

    def rhs(t, X):
        F, wu, _ = cl.exogenous(np.array([t]))
        return cl.A @ X + F[0] + (cl.nonlinear(X, wu[0]) if (surface is not None or v_max is not None) else 0.0)

    def jacf(t, X):
        _, wu, _ = cl.exogenous(np.array([t]))
        return cl.jacobian(X, wu[0])

    wall = time.perf_counter()
    kw = {"jac": jacf} if jac and method in ("Radau", "BDF", "LSODA") else {}
    sol = solve_ivp(rhs, (0.0, T), X0, method=method, rtol=rtol, atol=at, t_eval=t_eval, **kw)
    if not sol.success:
        raise SolverError(f"solve_ivp ({method}) failed: {sol.message}")
    wall = time.perf_counter() - wall
    X = sol.y.T
    F, wu, R = cl.exogenous(sol.t)
    U = X @ cl.Ku.T + wu
    if v_max is not None:
        U = np.clip(U, -v_max, v_max)
    info = {"integrator": f"solve_ivp {method}" + (" + analytic Jacobian" if kw else ""), "rtol": rtol, "atol": at,
            "nfev": int(sol.nfev), "njev": int(getattr(sol, "njev", 0) or 0), "wall_s": wall, "controller": law.name}
    return _unpack(cl, sol.t, X, U, R, info)


# ---------------------------------------------------------------------------------------------
# frequency-domain steady state (the independent check of the simulator)
# ---------------------------------------------------------------------------------------------


def closed_loop_response(plant: MechanicalPlant, law: Law, omega: float, rhat: np.ndarray) -> np.ndarray:
    """Complex steady-state tip error ``e_hat`` for the reference ``r(t) = Re(rhat e^{i omega t})``
    (rhat (n_out,) complex) of the **linear** closed loop: the law's reference terms are linear
    in (r, r', ..., r''''), so ``w_hat = w(R_hat)`` with ``R_hat_k = (i omega)^k rhat``; then
    ``X_hat = (i omega I - A_cl)^-1 F_hat`` and ``e_hat = Cy X_hat - rhat``."""
    cl = ClosedLoop(plant, law, _Dummy(len(plant.outputs)))
    s = 1j * float(omega)
    R = np.array([[(s**k) * np.asarray(rhat, dtype=complex)] for k in range(5)])  # (5, 1, d)
    w = np.asarray(law.w(R, np.array([0.0])), dtype=complex)[0]
    F = cl.Bu @ w
    if cl.ni:
        F = F.astype(complex)
        F[cl.n2:] += -R[0, 0]
    X = np.linalg.solve(s * np.eye(cl.nX) - cl.A, F)
    y = np.hstack([plant.Cq, np.zeros((cl.d, plant.n))]) @ X[:cl.n2]
    return y - R[0, 0]


class _Dummy:
    """A placeholder path for building a closed loop without simulating it."""

    duration = 1.0
    smooth = True
    name = "none"

    def __init__(self, d: int) -> None:
        self.d = d

    def peak_speed(self) -> float:
        return 0.0

    def extent(self) -> float:
        return 0.0

    def describe(self) -> dict[str, Any]:
        return {"name": "none"}
