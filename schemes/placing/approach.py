"""Approach phase of vibrational nano-placing: eqs 4.13-4.21, Fig 4.20.

Model (4.13)-(4.14). The probe's first mode is a one-DOF oscillator of stiffness ``k`` (static
tip stiffness) and equivalent mass ``m = k / omega_1^2`` (:class:`.probe.PlacingProbe`), damping
``c = 2 zeta sqrt(k m)``. Its base holds the undeflected tip at the distance ``z0`` from the
sample; ``w`` is the tip deflection **towards** the sample, so the tip-sample distance is
``z0 - w``. The van der Waals attraction of a sphere of effective radius ``R`` (Derjaguin:
``R = R_t R_s / (R_t + R_s)`` for the tip sphere and the sample sphere) is (4.14)::

    F(w) = C / s^2,     C = H_sb R / 6,     s = z0 - w - zeta_0 > 0

pulling the tip towards the sample, and the equation of motion is
``m w'' + c w' + k w = F(w) + F_0 sin(omega t)``.

Equilibria and jump into contact (Fig 4.20a). Static balance ``k w = C / s^2`` with
``w = z0 - zeta_0 - s`` gives ``z0(s) = zeta_0 + s + C / (k s^2)``. Its minimum, where the force
gradient ``2 C / s^3`` equals ``k``, is the fold at which the stable equilibrium disappears:

    s* = (2 C / k)^(1/3) = (H R / (3 k))^(1/3),    z0* = zeta_0 + 3/2 s*,    w* = s* / 2.

For ``z0 < z0*`` no equilibrium out of contact exists: the tip jumps into contact.

Linearisation (4.15)-(4.17), (4.21). About the **stable equilibrium** ``w_eq(z0)`` (not about
``w = 0`` as printed: at nanometre gaps the static deflection is as large as the gap; the
printed form is returned beside it), ``k* = k - 2 C / s_eq^3`` and
``omega_n(z0) = sqrt(k* / m)``; ``k* -> 0`` at the fold, so the resonance frequency falls to
zero at the jump. Gain and phase (4.19)-(4.20) with ``zeta(z0) = c / (2 sqrt(k* m))``.

Frequency shift at finite amplitude. The small-amplitude shift (4.21) holds for ``A -> 0``.
For an oscillation of amplitude ``A`` about the centre ``w_c`` the first-order perturbation
result of Giessibl (Phys. Rev. B 56, 16010 (1997), eq 7) is::

    Delta f = -f0 / (pi k A) int_{-1}^{1} F(w_c + A u) u / sqrt(1 - u^2) du.

It is checked against two independent evaluations of the same conservative oscillator
(``c = 0``, amplitude held, as in FM-AFM): the exact period of the orbit by quadrature,
``T = 2 int dw / sqrt(2 (E - V(w)) / m)`` with ``V = k w^2/2 - C/s``, and a time simulation
(DOP853) that measures the period between successive turning points. Giessibl's formula
is first order in ``F / (k A)``; it fails where the orbit's lower turning point approaches
the potential barrier (the dynamic jump into contact), and the time simulation decides.

Assumptions: one mode (the first) and no contact (the force is singular at ``s = 0``, i.e.
at the distance ``zeta_0``: every function here works in the non-contact region only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError

from .probe import TABLE, PlacingProbe


def effective_radius(R_t: float, R_s: float) -> float:
    """Derjaguin radius of two spheres ``R_t R_s / (R_t + R_s)`` (``R_s = 0``: flat sample)."""
    if R_t <= 0 or R_s < 0:
        raise ParameterError(f"radii must be positive (R_t = {R_t}, R_s = {R_s})")
    return R_t if R_s == 0 else R_t * R_s / (R_t + R_s)


@dataclass(frozen=True)
class Approach:
    """The approach model (4.13)-(4.14): probe ``k``, ``m``, ``c``; Hamaker constant ``H`` [J],
    effective radius ``R`` [m] and cut-off ``zeta0`` [m]."""

    k: float
    m: float
    c: float
    H: float
    R: float
    zeta0: float

    def __post_init__(self) -> None:
        for name in ("k", "m", "H", "R", "zeta0"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"approach: {name} must be positive, got {v}")
        if not (math.isfinite(self.c) and self.c >= 0):
            raise ParameterError(f"approach: damping must be >= 0, got {self.c}")

    @classmethod
    def from_probe(cls, probe: PlacingProbe, H: float | None = None, R_t: float | None = None,
                   R_s: float | None = None, zeta0: float | None = None) -> "Approach":
        """The probe's ``k``, ``m``, ``c`` with Table 4.4's ``H_sb``, ``R_t``, ``R_s``, ``zeta_0``."""
        H = float(TABLE["H_sb"] if H is None else H)
        R = effective_radius(float(TABLE["R_t"] if R_t is None else R_t), float(TABLE["R_s"] if R_s is None else R_s))
        z = float(TABLE["zeta0"] if zeta0 is None else zeta0)
        return cls(probe.k, probe.m, probe.c, H, R, z)

    # ------------------------------------------------------------------ force (4.14)
    @property
    def C(self) -> float:
        return self.H * self.R / 6.0

    @property
    def omega0(self) -> float:
        return math.sqrt(self.k / self.m)

    @property
    def zeta(self) -> float:
        return self.c / (2.0 * math.sqrt(self.k * self.m))

    def force(self, z0: float, w):
        """vdW force on the tip towards the sample [N] (4.14); NaN where ``s <= 0`` (contact)."""
        s = z0 - self.zeta0 - np.asarray(w, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(s > 0, self.C / s**2, np.nan)

    def force_gradient(self, z0: float, w):
        """``dF/dw = 2 C / s^3`` [N/m] (the linear term of 4.15)."""
        s = z0 - self.zeta0 - np.asarray(w, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(s > 0, 2.0 * self.C / s**3, np.nan)

    def net_force(self, z0: float, w):
        """Total force on the tip ``-k w + F(w)`` [N] (Fig 4.20a): its zeros are the equilibria."""
        return -self.k * np.asarray(w, dtype=float) + self.force(z0, w)

    # ------------------------------------------------------------------ equilibria, jump
    def jump_in(self) -> dict[str, float]:
        """The fold: ``s* = (2C/k)^(1/3)``, ``z0* = zeta0 + 1.5 s*``, ``w* = s*/2`` and the force there."""
        s = (2.0 * self.C / self.k) ** (1.0 / 3.0)
        return {"s_star_m": s, "z0_star_m": self.zeta0 + 1.5 * s, "w_star_m": 0.5 * s,
                "distance_at_jump_m": self.zeta0 + s, "force_at_jump_n": self.C / s**2}

    def equilibria(self, z0: float) -> dict[str, float]:
        """Stable and unstable equilibria at ``z0``: gaps ``s`` solving ``k s^3 - k (z0 - zeta0) s^2 + C = 0``
        (NaN below the jump distance, where none exists out of contact)."""
        d = z0 - self.zeta0
        js = self.jump_in()
        if d < js["z0_star_m"] - self.zeta0:
            return {"w_stable_m": math.nan, "s_stable_m": math.nan, "w_unstable_m": math.nan, "s_unstable_m": math.nan}
        s_star = js["s_star_m"]
        f = lambda s: self.k * s**3 - self.k * d * s**2 + self.C  # noqa: E731
        if abs(f(s_star)) < 1e-14 * self.C:
            s_st = s_un = s_star
        else:
            s_st = brentq(f, s_star, d, xtol=1e-18, rtol=1e-15)
            s_un = brentq(f, 1e-6 * s_star, s_star, xtol=1e-18, rtol=1e-15)
        return {"w_stable_m": d - s_st, "s_stable_m": s_st, "w_unstable_m": d - s_un, "s_unstable_m": s_un}

    def linearised(self, z0: float) -> dict[str, float]:
        """(4.15)-(4.17), (4.21) at the stable equilibrium; ``*_printed`` evaluated at ``w = 0`` as
        printed. ``omega_n`` is 0 at the fold and NaN below it."""
        eq = self.equilibria(z0)
        s = eq["s_stable_m"]
        k_star = self.k - 2.0 * self.C / s**3 if math.isfinite(s) else math.nan
        s0 = z0 - self.zeta0
        k_pr = self.k - 2.0 * self.C / s0**3
        om = math.sqrt(max(k_star, 0.0) / self.m) if math.isfinite(k_star) else math.nan
        return {"z0_m": z0, "w_eq_m": eq["w_stable_m"], "s_eq_m": s, "k_star_n_per_m": k_star,
                "omega_n_rad_s": om, "omega_ratio": om / self.omega0,
                "zeta_eff": self.c / (2.0 * math.sqrt(k_star * self.m)) if k_star > 0 else math.inf,
                "k_star_printed_n_per_m": k_pr,
                "omega_n_printed_rad_s": math.sqrt(k_pr / self.m) if k_pr > 0 else math.nan}

    def force_balance_curves(self, z0_values, n: int = 400) -> dict[str, Any]:
        """Fig 4.20a: net force ``-k w + F`` against the tip deflection for several ``z0``."""
        js = self.jump_in()
        w_max = js["w_star_m"] * 3.0
        w = np.linspace(-0.2 * w_max, w_max, n)
        curves = []
        for z0 in z0_values:
            curves.append({"z0_m": float(z0), "w_m": w, "net_force_n": self.net_force(float(z0), w)})
        return {"curves": curves, "jump": js}

    # ------------------------------------------------------------------ forced response (4.18-4.20)
    def response(self, z0: float, omega) -> dict[str, np.ndarray]:
        """Amplitude per unit force ``|G| / k*`` [m/N] and phase [rad] (4.19)-(4.20) at ``z0``."""
        lin = self.linearised(z0)
        w = np.asarray(omega, dtype=float)
        ks = lin["k_star_n_per_m"]
        if not (ks > 0):
            raise ParameterError(f"z0 = {z0:.4g} m is at or inside the jump distance {self.jump_in()['z0_star_m']:.4g} m")
        wn = math.sqrt(ks / self.m)
        z = self.c / (2.0 * math.sqrt(ks * self.m))
        r = w / wn
        G = 1.0 / np.sqrt((1 - r**2) ** 2 + (2 * z * r) ** 2)
        phase = np.arctan2(2 * z * r, 1 - r**2)
        return {"omega": w, "compliance_m_per_n": G / ks, "gain": G, "phase_rad": phase,
                "omega_n_rad_s": wn, "zeta": z}

    def simulate_forced(self, z0: float, omega: float, F0: float, periods: int = 60,
                        rtol: float = 1e-10) -> dict[str, float]:
        """Time-domain check of (4.19)-(4.20): the nonlinear equation driven by ``F0 sin(omega t)``
        from the static equilibrium; amplitude and phase lag of the last 10 periods by projection
        on ``sin`` and ``cos``."""
        eq = self.equilibria(z0)
        w0 = eq["w_stable_m"]
        if not math.isfinite(w0):
            raise ParameterError("no equilibrium at this z0 (inside the jump distance)")
        T = 2 * math.pi / omega

        def rhs(t, y):
            s = z0 - self.zeta0 - y[0]
            return [y[1], (-self.k * y[0] - self.c * y[1] + self.C / s**2 + F0 * math.sin(omega * t)) / self.m]

        t_end = periods * T
        tt = np.linspace(t_end - 10 * T, t_end, 2001)
        sol = solve_ivp(rhs, (0, t_end), [w0, 0.0], method="DOP853", rtol=rtol, atol=1e-6 * abs(F0) / self.k,
                        t_eval=tt)
        if not sol.success:
            raise SolverError(f"forced approach simulation failed: {sol.message}")
        x = sol.y[0] - np.mean(sol.y[0])
        a = 2 * np.trapezoid(x * np.sin(omega * tt), tt) / (tt[-1] - tt[0])
        b = 2 * np.trapezoid(x * np.cos(omega * tt), tt) / (tt[-1] - tt[0])
        amp = math.hypot(a, b)
        lag = math.atan2(-b, a)  # x = amp sin(omega t - lag)
        return {"amplitude_m": amp, "phase_rad": lag % (2 * math.pi), "mean_m": float(np.mean(sol.y[0]))}

    # ------------------------------------------------------------------ slow approach (time domain)
    def simulate_approach(self, speed: float, z_start: float | None = None, detect_fraction: float = 0.5,
                          rtol: float = 1e-9) -> dict[str, float]:
        """A slow approach ``z0(t) = z_start - speed t`` from rest at the equilibrium. The jump is
        detected when the gap ``s`` falls below ``detect_fraction * s*``; returns ``z0`` then.

        Near a fold the response lags the quasi-static branch by a delay that scales as
        ``speed^(2/3)`` (slow passage through a saddle-node), so the simulated jump distance
        approaches ``z0*`` from below as the speed decreases."""
        js = self.jump_in()
        if not (speed > 0 and math.isfinite(speed)):
            raise ParameterError(f"approach speed must be positive, got {speed}")
        if z_start is None:
            z_start = self.zeta0 + 3.0 * js["s_star_m"]
        w0 = self.equilibria(z_start)["w_stable_m"]
        if not math.isfinite(w0):
            raise ParameterError(f"start distance {z_start:.4g} m is inside the jump distance")
        s_det = detect_fraction * js["s_star_m"]

        def rhs(t, y):
            s = z_start - speed * t - self.zeta0 - y[0]
            return [y[1], (-self.k * y[0] - self.c * y[1] + self.C / s**2) / self.m]

        def ev(t, y):
            return z_start - speed * t - self.zeta0 - y[0] - s_det

        ev.terminal = True
        ev.direction = -1
        t_end = (z_start - self.zeta0) / speed
        T0 = 2 * math.pi / self.omega0
        sol = solve_ivp(rhs, (0, t_end), [w0, 0.0], method="DOP853", rtol=rtol, atol=1e-9 * js["s_star_m"],
                        events=ev, max_step=T0 / 4)
        if sol.status != 1 or not len(sol.t_events[0]):
            raise SolverError("slow approach: no jump detected before the tip reached the sample")
        tj = float(sol.t_events[0][0])
        return {"speed_m_s": speed, "z0_jump_m": z_start - speed * tj, "t_jump_s": tj,
                "z0_star_m": js["z0_star_m"], "delay_m": js["z0_star_m"] - (z_start - speed * tj),
                "n_steps": int(sol.t.size)}

    # ------------------------------------------------------------------ frequency shift
    def potential(self, z0: float, w):
        """``V(w) = k w^2 / 2 - C / s`` [J] (conservative part of 4.13)."""
        w = np.asarray(w, dtype=float)
        s = z0 - self.zeta0 - w
        return 0.5 * self.k * w**2 - self.C / s

    def orbit(self, z0: float, A: float) -> dict[str, float] | None:
        """The undamped periodic orbit of amplitude ``A`` at ``z0``: turning points
        ``w_a < w_b = w_a + 2A`` with ``V(w_a) = V(w_b)``; None if no such orbit stays out of
        contact (the lower turning point beyond the barrier: dynamic jump).

        ``V(w_a) - V(w_b) = (w_b - w_a) [C / (s_a s_b) - k (w_a + w_b) / 2]`` exactly, so the
        turning-point condition is solved on the bracket, free of cancellation."""
        eq = self.equilibria(z0)
        w_eq, w_un = eq["w_stable_m"], eq["w_unstable_m"]
        if not math.isfinite(w_eq) or A <= 0:
            return None
        d = z0 - self.zeta0

        def h(wa):
            wb = wa + 2 * A
            return self.C / ((d - wa) * (d - wb)) - 0.5 * self.k * (wa + wb)

        lo, hi = w_eq - 2 * A, w_eq
        if hi + 2 * A >= d or h(hi) >= 0:
            return None
        wa = brentq(h, lo, hi, xtol=1e-15 * A, rtol=1e-15)
        wb = wa + 2 * A
        if wb >= w_un:
            return None
        return {"w_a": wa, "w_b": wb, "w_c": 0.5 * (wa + wb), "E": float(self.potential(z0, wa))}

    def shift_small_amplitude(self, z0: float) -> float:
        """(4.21) at the static equilibrium: ``Delta f = f0 (sqrt(k*/k) - 1)`` [Hz]."""
        lin = self.linearised(z0)
        f0 = self.omega0 / (2 * math.pi)
        return f0 * (lin["omega_ratio"] - 1.0)

    def shift_giessibl(self, z0: float, A: float, w_c: float | None = None, n: int = 4096,
                       form: str = "first-order") -> float:
        """Giessibl's large-amplitude shift [Hz] about the centre ``w_c`` (default: the centre of
        the exact orbit, else the static equilibrium), through the amplitude-weighted gradient
        ``<k_ts> = 1/(pi A) int_0^{2 pi} F(w_c + A cos phi) cos phi dphi`` (trapezoid rule on the
        periodic integrand, spectrally accurate):

        * ``form="first-order"`` (Giessibl 1997): ``Delta f = -f0 <k_ts> / (2 k)``;
        * ``form="sqrt"``: ``f = f0 sqrt(1 - <k_ts>/k)``, which reduces to (4.21) for ``A -> 0``.
        """
        if w_c is None:
            orb = self.orbit(z0, A)
            w_c = orb["w_c"] if orb else self.equilibria(z0)["w_stable_m"]
        phi = 2 * math.pi * np.arange(n) / n
        F = self.force(z0, w_c + A * np.cos(phi))
        if not np.all(np.isfinite(F)):
            return math.nan
        kts = float(np.sum(F * np.cos(phi))) * 2.0 / (n * A)
        f0 = self.omega0 / (2 * math.pi)
        if form == "first-order":
            return -f0 * kts / (2 * self.k)
        if form == "sqrt":
            return f0 * (math.sqrt(max(1.0 - kts / self.k, 0.0)) - 1.0)
        raise ParameterError(f"unknown Giessibl form {form!r} (first-order, sqrt)")

    def shift_exact(self, z0: float, A: float) -> float:
        """Exact shift [Hz] of the undamped orbit of amplitude ``A`` (NaN if no orbit).

        With ``w = w_c - A cos(phi)`` the energy integral factorises exactly,
        ``E - V(w) = (w - w_a)(w_b - w) Q(w)`` with ``Q = k/2 - C / (s_a s_b s)``, and
        ``(w - w_a)(w_b - w) = A^2 sin^2(phi)``, so the period is the smooth integral
        ``T = 2 int_0^pi dphi / sqrt(2 Q(w(phi)) / m)`` (``Q = k/2`` without the force: ``T = 2 pi sqrt(m/k)``)."""
        orb = self.orbit(z0, A)
        if orb is None:
            return math.nan
        d = z0 - self.zeta0
        sa, sb, wc = d - orb["w_a"], d - orb["w_b"], orb["w_c"]

        def integrand(phi):
            s = d - (wc - A * math.cos(phi))
            Q = 0.5 * self.k - self.C / (sa * sb * s)
            return 1.0 / math.sqrt(2.0 * Q / self.m) if Q > 0 else math.inf

        half, _ = quad(integrand, 0.0, math.pi, limit=200, epsabs=0, epsrel=1e-12)
        T = 2.0 * half
        return 1.0 / T - self.omega0 / (2 * math.pi)

    def shift_simulated(self, z0: float, A: float, periods: int = 8, rtol: float = 1e-10) -> float:
        """Shift [Hz] from a time simulation of the undamped oscillator started at rest at the
        orbit's upper turning point ``w_a``; period = mean spacing of the turning points over
        about ``periods`` periods (the run length is set from the linearised frequency)."""
        orb = self.orbit(z0, A)
        if orb is None:
            return math.nan

        def rhs(t, y):
            s = z0 - self.zeta0 - y[0]
            return [y[1], (-self.k * y[0] + self.C / s**2) / self.m]

        def ev(t, y):
            return y[1]

        ev.direction = 1  # velocity crosses zero upwards: the turning point w_a
        T0 = 2 * math.pi / self.omega0
        wl = self.linearised(z0)["omega_n_rad_s"]
        T_guess = 2 * math.pi / wl if wl > 0 else 10 * T0
        sol = solve_ivp(rhs, (0, 1.5 * (periods + 1) * T_guess), [orb["w_a"], 0.0], method="DOP853", rtol=rtol,
                        atol=1e-12 * A, events=ev, max_step=T0 / 20)
        te = sol.t_events[0]
        te = te[te > 0.1 * T0]
        if te.size < 3:
            raise SolverError("frequency-shift simulation: fewer than three periods found")
        T = (te[-1] - te[0]) / (te.size - 1)
        return 1.0 / T - self.omega0 / (2 * math.pi)

    def frequency_shift_table(self, z0_values, amplitudes, simulate: bool | int = True) -> list[dict[str, float]]:
        """Rows ``z0, A`` and the shifts [Hz]: small-amplitude (4.21), Giessibl (first order and sqrt
        form), exact orbit period, time simulation (``simulate``: True for every gap, an integer
        ``n`` for every n-th gap, False for none)."""
        rows = []
        every = 1 if simulate is True else int(simulate) if simulate else 0
        for j, z0 in enumerate(z0_values):
            small = self.shift_small_amplitude(float(z0))
            for A in amplitudes:
                row = {"z0_m": float(z0), "A_m": float(A), "df_small_hz": small,
                       "df_giessibl_hz": self.shift_giessibl(float(z0), float(A)),
                       "df_giessibl_sqrt_hz": self.shift_giessibl(float(z0), float(A), form="sqrt"),
                       "df_exact_hz": self.shift_exact(float(z0), float(A))}
                row["df_sim_hz"] = self.shift_simulated(float(z0), float(A)) if every and j % every == 0 else math.nan
                rows.append(row)
        return rows


__all__ = ["Approach", "effective_radius"]
