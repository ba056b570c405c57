"""Controllers of the two-body probe (source section 3.5.3, eqs 3.46-3.54), checked and corrected.

Every controller is designed on a **model** plant (its blocks D, C1, K1, J, C2, K2, Gamma) and
returns a linear law applied to the measured plant state ``x = [q1, q2, q1', q2']``::

    u = w(t) + Kx x_meas + Ki xi,     xi' = y_meas - r      (xi only for the PID)

with ``w(t)`` the reference terms (feedforward minus feedback on the reference state).

Singular-perturbation model, checked step by step (docs/tracking.md; SOURCE-NOTES 15):
with ``z = K1 (q2 - q1)`` eq 3.37 (plus the body damping C2 probedyn keeps) is, exactly,

    D q1'' + C1 q1' = z                                                    (3.47a)
    J K1^-1 z'' + C2 K1^-1 z' + (K1 + K2) K1^-1 z = Gamma u - K2 q1 - C2 q1' - J q1''   (3.47b)

For diagonal (commuting) matrices and ``K_i = K_i* / eps^2`` (3.46), (3.47b) is the printed
``eps^2 J z'' + (K1* + K2*) z = K1* (Gamma u - K2 q1 - J q1'')`` **with q1'' (the print has
q1')**. At eps = 0 (no z'', z' terms): ``z_bar = K* (Gamma u - K2 q1 - C2 q1' - J q1'')`` with
``K* = K1 (K1 + K2)^-1`` (the print's ``(K1* + K2*)^-1 K1*`` is the same matrix only when they
commute), and the slow model (3.49, exact as printed once q1'' is used, plus C2):

    (D + K* J) q1'' + (C1 + K* C2) q1' + K* K2 q1 = K* Gamma u.

* :class:`OpenLoop`: ``u = inverse(model, r)``: quasi-static or exact dynamic (:mod:`.inversion`).
* :class:`SlowControl` (3.54): ``u_s = Gamma^-1 K*^-1 [ -Kp (q1 - r) - Kd (q1' - r') + ff ]``.
  **Sign**: the printed ``+Kp (q1 - q_d)`` is positive feedback for positive-definite gains;
  probedyn uses ``-Kp``. **Feedforward** ``ff = M_s r'' + C_s r' + K_s r`` (the slow model's
  inverse): without it (``feedforward=False``, the law as printed) the tip stops short by
  ``(K_s + Kp)^-1 K_s r`` - the slow model has the stiffness ``K_s = K* K2`` that a rigid robot
  arm (the source's refs 112-114, where 3.50-3.54 come from) does not have. Gains
  (:func:`slow_gains`): ``Kp = kappa K_s`` (kappa >= 0: the feedback adds stiffness, never
  cancels the plant's) and ``Kd`` giving the slow error dynamics
  ``M_s e'' + (C_s + Kd) e' + (K_s + Kp) e = 0`` the damping ratio ``zeta_s``.
* :class:`CompositeControl` (3.50-3.54): ``u = u_s + u_f``, ``u_f = K_v (q1' - q2')`` with
  ``Gamma K_v = C_f``, the damping added to the relative coordinate ``w = q2 - q1``:
  ``J w'' + (C2 + C_f) w' + (K1 + K2) w = ...``. The printed (3.52)
  ``K_v = eps^-1 Gamma^-1 K1*^-1 C*`` has units V s/N, not V s/m; substituting it in (3.47) does
  not give (3.53). The law that gives (3.53) is ``K_v = eps^-1 Gamma^-1 C*`` (diagonal case),
  i.e. ``C_f = C* / eps``. probedyn sets ``C_f`` to ``zeta_f`` times the critical damping of the
  boundary layer ``J eta'' + C_f eta' + (K1 + K2) eta = 0`` (3.57).
* :class:`PID`: a plain per-axis PID on the tip error (no model feedforward, no Gamma^-1
  decoupling), tuned on each axis's slow model for the same bandwidth: the three closed-loop
  poles at ``(s + omega_s)(s^2 + 2 zeta_s omega_s s + omega_s^2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.linalg as sla

from probedyn.core.errors import ParameterError
from probedyn.schemes.tracking import inversion
from probedyn.schemes.tracking.plants import MechanicalPlant


@dataclass
class Law:
    """``u = w(R) + Kx x_meas + Ki xi``; ``xi' = y_meas - r`` when ``Ki`` is not None.
    ``w``: callable on the path derivatives (5, n, n_out) (and the time grid) -> (n, n_in)."""

    name: str
    Kx: np.ndarray
    Ki: np.ndarray | None
    w: Callable[[np.ndarray, np.ndarray], np.ndarray]
    info: dict[str, Any] = field(default_factory=dict)
    grid_only: bool = False  # w can only be evaluated on a uniform grid (FFT inverse)


def slow_model(b: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Slow reduced-order model (3.49, corrected): K*, M_s, C_s, K_s, B_s = K* Gamma."""
    Ks = b["K1"] + b["K2"]
    Kstar = b["K1"] @ np.linalg.inv(Ks)
    return {"Kstar": Kstar, "M": b["D"] + Kstar @ b["J"], "C": b["C1"] + Kstar @ b["C2"], "K": Kstar @ b["K2"],
            "B": Kstar @ b["Gamma"]}


def critical_damping(M: np.ndarray, K: np.ndarray) -> np.ndarray:
    """``2 M^1/2 (M^-1/2 K M^-1/2)^1/2 M^1/2``: the damping matrix that makes every mode of
    (M, K) critically damped."""
    Mh = sla.sqrtm(M).real
    Mhi = np.linalg.inv(Mh)
    return 2 * Mh @ sla.sqrtm(Mhi @ K @ Mhi).real @ Mh


def _blocks(model: MechanicalPlant) -> dict[str, np.ndarray]:
    if not model.blocks or "Gamma" not in model.blocks:
        raise ParameterError("this controller is designed on the two-body model (3.37)")
    return model.blocks


def natural_slow_hz(model: MechanicalPlant) -> np.ndarray:
    """Natural frequencies [Hz] of the slow model (3.49) without control."""
    s = slow_model(_blocks(model))
    lam = sla.eigh(s["K"] if np.allclose(s["K"], s["K"].T) else 0.5 * (s["K"] + s["K"].T),
                   0.5 * (s["M"] + s["M"].T), eigvals_only=True)
    return np.sqrt(np.maximum(lam, 0)) / (2 * math.pi)


@dataclass
class OpenLoop:
    """Open loop: the voltages of an inverse of the model (quasi-static or dynamic)."""

    inverse: str = "dynamic"
    name: str = "open"

    def design(self, model: MechanicalPlant) -> Law:
        n, m = 2 * model.n, model.B.shape[1]
        if self.inverse == "quasi-static":
            w = lambda R, t: inversion.quasi_static(model, R[0])  # noqa: E731
            return Law("open (quasi-static inverse)", np.zeros((m, n)), None, w, {"inverse": "quasi-static"})
        if self.inverse != "dynamic":
            raise ParameterError(f"inverse must be 'quasi-static' or 'dynamic', got {self.inverse!r}")
        if model.blocks and "Gamma" in model.blocks:
            w = lambda R, t: inversion.two_body_inverse(model, R)[0]  # noqa: E731
            return Law("open (dynamic inverse)", np.zeros((m, n)), None, w, {"inverse": "dynamic, exact two-body"})
        w = lambda R, t: inversion.fft_inverse(model, t, R[0], R[1])  # noqa: E731
        return Law("open (dynamic inverse)", np.zeros((m, n)), None, w, {"inverse": "dynamic, frequency domain"},
                   grid_only=True)


def slow_gains(model: MechanicalPlant, stiffness_ratio: float, zeta: float):
    """Slow-loop gains: ``Kp = kappa K_s`` (feedback adds ``kappa`` times the slow model's own
    stiffness) and ``Kd`` so that each axis of ``M_s e'' + (C_s + Kd) e' + (K_s + Kp) e = 0`` has
    damping ratio ``zeta``: ``Kd = 2 zeta sqrt((1 + kappa) K_s M_s) - C_s`` (matrix square root).
    The slow closed-loop natural frequencies are ``sqrt(1 + kappa)`` times the slow model's."""
    if not (math.isfinite(stiffness_ratio) and stiffness_ratio >= 0):
        raise ParameterError(f"stiffness ratio must be >= 0, got {stiffness_ratio:g}")
    if not (math.isfinite(zeta) and zeta >= 0):
        raise ParameterError(f"damping ratio must be >= 0, got {zeta:g}")
    b = _blocks(model)
    s = slow_model(b)
    Kp = stiffness_ratio * s["K"]
    Kd = zeta * critical_damping(s["M"], s["K"] + Kp) - s["C"]
    Pre = np.linalg.inv(b["Gamma"]) @ np.linalg.inv(s["Kstar"])  # Gamma^-1 K*^-1
    bw = np.sqrt(np.maximum(np.diag(s["K"] + Kp) / np.diag(s["M"]), 0.0)) / (2 * math.pi)
    return s, Kp, Kd, Pre, bw


@dataclass
class SlowControl:
    """Slow control only (3.54), sign corrected, with the slow model's feedforward (module
    docstring). ``stiffness_ratio`` kappa and ``zeta`` set the slow loop (:func:`slow_gains`)."""

    stiffness_ratio: float = 0.2
    zeta: float = 0.7
    feedforward: bool = True
    name: str = "slow"

    def design(self, model: MechanicalPlant) -> Law:
        s, Kp, Kd, Pre, bw = slow_gains(model, self.stiffness_ratio, self.zeta)
        d = Kp.shape[0]
        Kx = np.zeros((Pre.shape[0], 4 * d))
        Kx[:, :d] = -Pre @ Kp
        Kx[:, 2 * d:3 * d] = -Pre @ Kd
        ff = self.feedforward

        def w(R, t):
            r, r1, r2 = R[0], R[1], R[2]
            v = r @ Kp.T + r1 @ Kd.T
            if ff:
                v = v + r2 @ s["M"].T + r1 @ s["C"].T + r @ s["K"].T
            return v @ Pre.T

        info = {"stiffness_ratio": self.stiffness_ratio, "zeta": self.zeta, "feedforward": ff,
                "bandwidth_hz": bw, "Kp": Kp, "Kd": Kd, "Kstar": s["Kstar"],
                "slow_natural_hz": natural_slow_hz(model)}
        return Law("slow (3.54)" + ("" if ff else ", as printed: no feedforward"), Kx, None, w, info)


@dataclass
class CompositeControl:
    """Composite control u = u_s + u_f (3.50-3.54, corrected; module docstring)."""

    stiffness_ratio: float = 0.2
    zeta: float = 0.7
    zeta_fast: float = 0.7
    feedforward: bool = True
    name: str = "composite"

    def design(self, model: MechanicalPlant) -> Law:
        slow = SlowControl(self.stiffness_ratio, self.zeta, self.feedforward).design(model)
        b = _blocks(model)
        if not (math.isfinite(self.zeta_fast) and self.zeta_fast >= 0):
            raise ParameterError(f"fast damping ratio must be >= 0, got {self.zeta_fast:g}")
        Cf = self.zeta_fast * critical_damping(b["J"], b["K1"] + b["K2"])
        Kv = np.linalg.solve(b["Gamma"], Cf)
        d = b["K1"].shape[0]
        Kx = slow.Kx.copy()
        Kx[:, 2 * d:3 * d] += Kv
        Kx[:, 3 * d:] -= Kv
        info = {**slow.info, "zeta_fast": self.zeta_fast, "C_f": Cf, "K_v": Kv}
        return Law("composite (3.50-3.54)", Kx, None, slow.w, info)


@dataclass
class PID:
    """Plain per-axis PID on the tip error (no model feedforward, no Gamma^-1 decoupling), tuned
    on each axis's slow model for the bandwidth of the slow loop with the same ``stiffness_ratio``
    (``omega_b = sqrt(1 + kappa) omega_0``): closed-loop poles of the slow model at
    ``(s + omega_b)(s^2 + 2 zeta omega_b s + omega_b^2)``. ``gain`` multiplies all three gains
    (detuning: the loop gain falls uniformly, the low-frequency crossover with it)."""

    stiffness_ratio: float = 0.2
    zeta: float = 0.7
    gain: float = 1.0
    name: str = "pid"

    def design(self, model: MechanicalPlant) -> Law:
        b = _blocks(model)
        s, _, _, _, bw = slow_gains(model, self.stiffness_ratio, self.zeta)
        if not (math.isfinite(self.gain) and self.gain > 0):
            raise ParameterError(f"PID gain factor must be positive, got {self.gain:g}")
        ws = 2 * math.pi * bw
        d = b["K1"].shape[0]
        M, C, K, Bs = (np.diag(s[k]) for k in ("M", "C", "K", "B"))
        kd = self.gain * np.maximum(((2 * self.zeta + 1) * ws * M - C) / Bs, 0.0)
        kp = self.gain * np.maximum(((1 + 2 * self.zeta) * ws**2 * M - K) / Bs, 0.0)
        ki = self.gain * ws**3 * M / Bs
        Kx = np.zeros((d, 4 * d))
        Kx[:, :d] = -np.diag(kp)
        Kx[:, 2 * d:3 * d] = -np.diag(kd)
        Ki = -np.diag(ki)

        def w(R, t):
            return R[0] * kp + R[1] * kd

        # low-frequency crossover of the integral action on the slow model: ki b / (K + kp b)
        f_i = ki * Bs / (K + kp * Bs) / (2 * math.pi)
        return Law("PID", Kx, Ki, w, {"bandwidth_hz": bw if self.gain == 1 else f_i, "design_bandwidth_hz": bw,
                                      "integral_crossover_hz": f_i, "gain": self.gain, "zeta": self.zeta,
                                      "kp_V_per_m": kp, "ki_V_per_m_s": ki, "kd_V_s_per_m": kd})


def closed_loop_matrix(plant: MechanicalPlant, law: Law) -> np.ndarray:
    """State matrix of the linear closed loop (plant states, then the PID integrators)."""
    A, Bu, _, _ = plant.state_space()
    n2, d = A.shape[0], len(plant.outputs)
    if law.Ki is None:
        return A + Bu @ law.Kx
    Acl = np.zeros((n2 + d, n2 + d))
    Acl[:n2, :n2] = A + Bu @ law.Kx
    Acl[:n2, n2:] = Bu @ law.Ki
    Acl[n2:, :n2] = np.hstack([plant.Cq, np.zeros((d, plant.n))])
    return Acl


def stability(plant: MechanicalPlant, law: Law) -> dict[str, Any]:
    """Eigenvalues of the closed loop on ``plant``: largest real part [1/s], smallest damping
    ratio, the least damped mode's frequency [Hz], and ``stable``."""
    lam = np.linalg.eigvals(closed_loop_matrix(plant, law))
    osc = lam[np.abs(lam.imag) > 1e-9 * np.abs(lam).max()]
    zeta = -lam.real / np.maximum(np.abs(lam), 1e-300)
    i = int(np.argmin(zeta))
    return {"stable": bool(lam.real.max() < 0), "max_real_per_s": float(lam.real.max()),
            "min_damping_ratio": float(zeta[i]), "least_damped_hz": float(abs(lam[i].imag) / (2 * math.pi)),
            "n_oscillatory": int(osc.size)}


def max_stable_scale(plant: MechanicalPlant, make, lo: float = 1e-5, hi: float = 1.0, iters: int = 40) -> float:
    """Largest ``scale`` in [lo, hi] with ``make(scale).design(plant)`` stable on ``plant``
    (bisection in log scale; the stable set of gains is an interval from 0 for these loops);
    0 if even ``lo`` is unstable. Halving it gives a 6 dB gain margin."""
    ok = lambda sc: stability(plant, make(sc).design(plant))["stable"]  # noqa: E731
    if ok(hi):
        return hi
    if not ok(lo):
        return 0.0
    a, b = math.log(lo), math.log(hi)
    for _ in range(iters):
        m = 0.5 * (a + b)
        if ok(math.exp(m)):
            a = m
        else:
            b = m
    return math.exp(a)


CONTROLLERS = {"open": OpenLoop, "slow": SlowControl, "composite": CompositeControl, "pid": PID}


def make_controller(name: str, **kw) -> Any:
    k = name.strip().lower()
    if k not in CONTROLLERS:
        raise ParameterError(f"unknown control {name!r} (known: {', '.join(CONTROLLERS)})")
    return CONTROLLERS[k](**kw)
