"""Release phase: the sample on the full Maugis-Dugdale contact under tip oscillation, eq 4.42,
Figs 4.22-4.23, with outcome maps as Dask sweeps.

Model. The printed (4.42) is the sample's equation relative to the tip with a piecewise-linear
contact ``k1 Delta + k0``. Here the contact is the **full** Maugis-Dugdale force of the contact
registry (``md-vdw``, the source's :class:`probedyn.schemes.contact.maugis_dugdale.MaugisDugdaleVdW`: stable branch while in contact,
van der Waals tail out of contact, with the jump-out at ``delta_min`` and the jump-in at
``delta_0`` that make the JKR-like curve of ``lambda = 2`` hysteretic), and the probe is not a
prescribed motion but its retained flapwise modes (tip-normalised, :class:`.probe.PlacingProbe`),
driven at the tip by ``F0 sin(omega t + phi)`` (4.13), so the contact force acts back on it::

    m_n q_n'' + c_n q_n' + k_n q_n = F0 sin(omega t + phi) + P(delta) + c_c delta'     (probe modes)
    M y''                          = -P(delta) - c_c delta' - M g - S / (y - zeta_0)^2   (sample)

with the tip height ``h = D + sum q_n`` (``D``: the undeflected tip's height above the substrate,
the release height of 4.43), the penetration ``delta = y - h``, the contact damping ``c_c``
(in contact only; ``c_c = 2 zeta_c sqrt(k1 M)`` with ``k1`` the contact stiffness at zero load)
and the substrate's attraction ``S = H_ss R_s / 6`` (Derjaguin sphere-flat, as 4.43).

The drive amplitude is given as the tip's steady amplitude ``A`` (free probe; the sample's
2e-18 kg does not change it measurably): ``F0 = A / |H(omega)|`` with the retained modes'
compliance ``H``. The run starts in the periodic steady state: the tip at its mean position
moving down, the sample at its static contact equilibrium plus the linear steady-state
motion of the base-excited contact oscillator relative to the tip (above ``omega_c`` the
sample stays nearly still; starting it with the tip's velocity would kick the contact
oscillator and break the contact spuriously).

Outcomes (Fig 4.22): **attached** (the contact never breaks within ``n_periods``), **recaptured**
(it breaks, and contact re-forms: the sample falls back into the tip's attraction or the
returning tip catches it), **released** (after the break the sample is below the tip's lowest
point by a margin, moving away, with enough energy to cross the potential barrier between the
tip's attraction and the substrate's pull and gravity, computed with the tip held at its
lowest point, or it is already past the barrier), **undecided** (none of these ``n_fly``
periods after the break; reported, never hidden).

Physics of the threshold. For ``omega`` well below the sample's contact resonance
``omega_c = sqrt(k1 / M)`` the sample follows the tip and the contact carries its inertia
``M omega^2 A``; the contact breaks when the tension exceeds the pull-off force ``|F_po|``
(load control, 4.67 nN for Table 4.4's ``lambda = 2``). With dynamic amplification of the
contact oscillator the linear estimate is (:func:`threshold_amplitude`)
``A_th = |F_po| |1 - r^2 + 2 i zeta_c r| / (M omega^2)``, ``r = omega / omega_c``; far above
``omega_c`` the sample stays still and the contact is pulled apart by the tip's displacement
itself (``A_th -> |F_po| / k1``). Table 4.4's operating point (``M = 2e-18 kg``,
``omega = 2.5 krad/s``, ``A = F0 / k = 0.5 um``) gives ``M omega^2 A = 6e-18 N``, nine orders of
magnitude below the pull-off force: inertia cannot release a 2e-18 kg sample at kHz.

Integrator: :mod:`._kernel` (numba, ode23s with the analytic Jacobian and event location);
:func:`simulate_scipy` is the same model on ``scipy.integrate.solve_ivp`` (Radau with the
analytic Jacobian and events, restarted at each contact transition), the reference for
speed and for the outcome.

Scaled variables: lengths in the Maugis penetration unit ``l = (pi^2 W^2 R / K^2)^(1/3)``,
forces in ``pi W R``, masses in ``M``, time in ``tau = sqrt(M l / (pi W R))``.
"""

from __future__ import annotations

import cmath
import json
import math
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError
from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.sweep import run_sweep, validate_grid

from . import _kernel as K
from .probe import TABLE, PlacingProbe

OUTCOMES = {-1: "failed", 0: "attached", 1: "recaptured", 2: "released", 3: "undecided", 4: "tip reaches substrate",
            5: "weight exceeds adhesion"}
G = 9.80665

#: Table 4.1 elastic constants used with Table 4.4's lambda, radii and zeta_0 (Table 4.4 gives none)
_T41 = ("E_t", "nu_t", "E_s", "nu_s")


def placing_contact(lam: float | None = None, H: float | None = None, **overrides):
    """The Maugis-Dugdale contact of Table 4.4: ``lambda = 2``, ``R_t = 50 nm``, ``R_s = 160 nm``,
    ``zeta_0 = 0.375 nm``; elastic constants of Table 4.1 (the registry's defaults; Table 4.4
    gives none). ``lambda`` sets the work of adhesion (2.24); so the tail's Hamaker constant is
    ``12 pi W zeta_0^2 = 1.35e-19 J`` (Table 4.4's ``H_sb = 1.995e-19 J`` would give
    ``lambda = 2.6``: the table is not self-consistent, docs/placing.md). With ``H`` given instead,
    the work of adhesion is ``H / (12 pi zeta_0^2)`` (one Hamaker constant for the tail and the
    adhesion; used to vary ``H_sb`` consistently)."""
    if lam is not None and H is not None:
        raise ParameterError("give lambda or the Hamaker constant H, not both")
    kw = {"R_t": float(TABLE["R_t"]), "R_s": float(TABLE["R_s"]), "z0": float(TABLE["zeta0"])}
    if H is not None:
        kw["H"] = float(H)
    else:
        kw["lam"] = float(TABLE["lambda"] if lam is None else lam)
    kw.update(overrides)
    return get_contact_model("md-vdw", **kw)  # the source's tail: it recaptures a released sample


@dataclass
class ContactTables:
    """Scaled MD data for the kernel (independent of the sample mass)."""

    l: float  # m
    P: float  # N
    Dmin: float
    D0: float
    tz: float
    tg: float
    du: float
    Pn: np.ndarray
    dPn: np.ndarray
    k1_bar: float  # stiffness at zero load (scaled)
    P_pull_off_bar: float
    d_zero_bar: float  # penetration at zero load (scaled)
    contact: Any = field(repr=False, default=None)

    @property
    def pull_off_force(self) -> float:
        return self.P_pull_off_bar * self.P

    def penetration_at(self, P_bar: float) -> float:
        """Scaled penetration on the stable branch at the scaled load ``P_bar`` (Newton on the
        kernel's own force table, from the zero-load point; loads above the pull-off load)."""
        if not P_bar > self.P_pull_off_bar:
            raise ParameterError("load below the pull-off force: no contact exists")
        d = self.d_zero_bar
        for _ in range(100):
            f, k = self.force(d, 1)
            step = (float(f[0]) - P_bar) / float(k[0])
            d_new = max(d - step, self.Dmin + 1e-12)
            if abs(d_new - d) < 1e-13 * (1 + abs(d)):
                return d_new
            d = d_new
        raise SolverError("contact equilibrium: Newton did not converge")

    @classmethod
    def build(cls, contact, n: int = 1200, D_max: float = 40.0) -> "ContactTables":
        s = contact.scales
        if s.W <= 0:
            raise ParameterError("the release model needs adhesion (W > 0)")
        tab = contact._table()
        Dmin = float(tab["D_min"])
        D0, P0 = contact.nd_endpoint()
        if not Dmin <= D0:
            raise SolverError("MD curve: jump-out penetration above the jump-in one")
        zb = contact._nd_z0_bar()
        d0 = zb * math.sqrt(2.0 / -P0)
        umax = math.sqrt(D_max - Dmin)
        u = np.linspace(0.0, umax, n)
        D = Dmin + u * u
        D[0] = Dmin + 1e-14
        st = contact.nd_state(D, "stable")
        P = np.asarray(st["P"], float)
        k = np.asarray(st["k"], float)
        dP = k * 2.0 * u
        # at u = 0 dP/du is finite (k ~ 1/u): quadratic extrapolation from the next nodes
        dP[0] = 3 * dP[1] - 3 * dP[2] + dP[3]
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(dP))):
            raise SolverError("MD stable-branch table has non-finite entries")
        z = contact.at_load(0.0)
        k1 = float(z["stiffness"]) * s.d_unit / s.P_unit
        return cls(s.d_unit, s.P_unit, Dmin, float(D0), 2.0 * zb * zb, d0 + float(D0), float(u[1] - u[0]),
                   P, dP, k1, float(contact.nd_pull_off()["P_pull_off"]), float(z["penetration"]) / s.d_unit, contact)

    def force(self, delta_bar, s: int) -> tuple[np.ndarray, np.ndarray]:
        """Scaled force and stiffness from the kernel's tables (for tests and plots)."""
        par = np.zeros(K.NPAR)
        par[8], par[9], par[10], par[11], par[12] = self.Dmin, self.D0, self.tz, self.tg, self.du
        d = np.atleast_1d(np.asarray(delta_bar, float))
        out = np.array([K.md_force(float(x), int(s), par, self.Pn, self.dPn) for x in d])
        return out[:, 0], out[:, 1]


@dataclass
class ReleaseSetup:
    """Everything a release run needs, in SI (inputs) and scaled (kernel) form."""

    probe: PlacingProbe
    M: float
    A: float
    omega: float
    D: float
    F0: float
    phase: float
    zeta_c: float
    H_ss: float
    R_s: float
    g: float
    n_periods: float
    n_fly: float
    tables: ContactTables
    par: np.ndarray
    mm: np.ndarray
    kk: np.ndarray
    cn: np.ndarray
    z0: np.ndarray
    tau: float
    meta: dict[str, Any]

    @property
    def N(self) -> int:
        return self.mm.shape[0]

    def to_si(self, t, z) -> dict[str, np.ndarray]:
        """Physical time, tip height, sample height, penetration (arrays over records)."""
        z = np.atleast_2d(z)
        N = self.N
        l = self.tables.l
        h = (self.par[0] + z[:, :N].sum(axis=1)) * l
        delta = z[:, N] * l
        v = (z[:, N + 1:2 * N + 1].sum(axis=1) + z[:, 2 * N + 1]) * l / self.tau
        return {"t_s": np.asarray(t) * self.tau, "tip_m": h, "sample_m": h + delta, "penetration_m": delta,
                "sample_velocity_m_s": v}


def threshold_amplitude(M, omega, F_po: float, k1: float, zeta_c: float = 0.1):
    """Linear estimate of the tip amplitude [m] at which the contact tension reaches the
    pull-off force ``F_po`` [N]: ``|F_po| |1 - r^2 + 2 i zeta_c r| / (M omega^2)``, ``r = omega/omega_c``."""
    M = np.asarray(M, float)
    w = np.asarray(omega, float)
    r = w / np.sqrt(k1 / M)
    return abs(F_po) * np.abs(1 - r**2 + 2j * zeta_c * r) / (M * w**2)


def setup_release(probe: PlacingProbe, M: float | None = None, A: float | None = None, omega: float | None = None,
                  D: float | None = None, F0: float | None = None, zeta_c: float = 0.1, H_ss: float | None = None,
                  R_s: float | None = None, g: float = G, n_modes: int = 1, n_periods: float = 3.0,
                  n_fly: float = 20.0, tables: ContactTables | None = None, contact=None) -> ReleaseSetup:
    """Build a release run. Defaults from Table 4.4: ``M = 2e-18 kg``, ``omega = 2.5 krad/s``,
    ``D = 5 um``, ``H_ss``, ``R_s``; the tip amplitude ``A`` (or the tip force ``F0``; default
    ``F0 = 5e-7 N``). ``n_modes``: retained probe modes (1 = the one-DOF model of 4.13)."""
    M = float(TABLE["M1"] if M is None else M)
    omega = float(TABLE["omega"] if omega is None else omega)
    D = float(TABLE["D"] if D is None else D)
    H_ss = float(TABLE["H_ss"] if H_ss is None else H_ss)
    R_s = float(TABLE["R_s"] if R_s is None else R_s)
    for name, v in (("sample mass M", M), ("drive frequency omega", omega), ("release height D", D),
                    ("H_ss", H_ss), ("R_s", R_s)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be positive and finite, got {v}")
    if not (0 <= zeta_c < 10):
        raise ParameterError(f"contact damping ratio zeta_c must be in [0, 10), got {zeta_c}")
    if not (1 <= int(n_modes) <= len(probe.omegas)):
        raise ParameterError(f"n_modes must be between 1 and {len(probe.omegas)} (the probe's retained modes)")
    if n_periods <= 0 or n_fly <= 0:
        raise ParameterError("n_periods and n_fly must be positive")
    if tables is None:
        tables = ContactTables.build(contact if contact is not None else placing_contact())
    l, P = tables.l, tables.P
    tau = math.sqrt(M * l / P)
    N = int(n_modes)
    mn = np.array(probe.modal_masses[:N], float)
    wn = np.array(probe.omegas[:N], float)
    kn = mn * wn**2
    cn = 2.0 * probe.zeta * np.sqrt(kn * mn)
    Hn = 1.0 / (kn - mn * omega**2 + 1j * cn * omega)
    H = complex(np.sum(Hn))
    if A is None and F0 is None:
        F0 = float(TABLE["F_0"])
    if A is not None and F0 is not None:
        raise ParameterError("give the tip amplitude A or the drive force F0, not both")
    if A is not None:
        if not (math.isfinite(A) and A >= 0):
            raise ParameterError(f"tip amplitude A must be >= 0, got {A}")
        F0 = A / abs(H)
    else:
        if not (math.isfinite(F0) and F0 >= 0):
            raise ParameterError(f"drive force F0 must be >= 0, got {F0}")
        A = F0 * abs(H)
    if A >= 0.9 * D:
        raise ParameterError(f"tip amplitude {A:.3g} m reaches the substrate (release height D = {D:.3g} m)")
    phase = math.pi - cmath.phase(H)
    S = H_ss * R_s / 6.0
    # static contact equilibrium: P = -M g + F_sub(y0)  (tension), y0 ~ D
    F_sub = -S / (D - float(TABLE["zeta0"])) ** 2
    P_eq = -M * g + F_sub
    F_po = tables.pull_off_force
    if P_eq <= F_po:
        raise ParameterError(f"the sample's weight and the substrate's pull ({-P_eq:.3g} N) exceed the pull-off force")
    d_eq = tables.penetration_at(P_eq / P)
    q_stat = P_eq / kn  # static share of the contact load (tiny)
    E = F0 * cmath.exp(1j * phase)
    q0 = np.array([(Hn[i] * E).imag for i in range(N)]) / l + q_stat / l
    v0 = np.array([(1j * omega * Hn[i] * E).imag for i in range(N)]) * tau / l
    # the sample's linear steady state relative to the tip (base-excited contact oscillator):
    # delta' = M w^2 h / (k1 - M w^2 + i c_c w), h the tip's complex amplitude
    k1 = tables.k1_bar * P / l
    c_c = 2.0 * zeta_c * math.sqrt(k1 * M)
    Dc = M * omega**2 * (H * E) / (k1 - M * omega**2 + 1j * c_c * omega)
    z0 = np.concatenate([q0, [d_eq + Dc.imag / l], v0, [(1j * omega * Dc).imag * tau / l]])
    # scaled parameters
    Db = D / l
    zeta0_b = float(TABLE["zeta0"]) / l
    Sb = S / (P * l * l)
    gb = M * g / P
    cc = 2.0 * zeta_c * math.sqrt(tables.k1_bar)  # scaled: c_c l / (tau P) with c_c = 2 zeta_c sqrt(k1 M)
    par = np.zeros(K.NPAR)
    par[0], par[1], par[2], par[3] = Db, F0 / P, omega * tau, phase
    par[4], par[5], par[6], par[7] = cc, gb, Sb, zeta0_b
    par[8], par[9], par[10], par[11], par[12] = tables.Dmin, tables.D0, tables.tz, tables.tg, tables.du
    hlow = Db + float(np.sum(q_stat)) / l - A / l
    par[13], par[14] = hlow, 5.0
    yb, Vb = _barrier(par, hlow)
    par[15], par[16] = Vb, yb
    Tw = 2 * math.pi / (omega * tau)
    par[17], par[18] = n_periods * Tw, n_fly * Tw
    meta = {"F_pull_off_n": F_po, "k1_n_per_m": tables.k1_bar * P / l,
            "omega_c_rad_s": math.sqrt(tables.k1_bar * P / l / M), "inertial_force_n": M * omega**2 * A,
            "barrier_height_m": yb * l, "tip_lowest_m": hlow * l, "l_m": l, "P_n": P, "tau_s": tau,
            "A_threshold_linear_m": float(threshold_amplitude(M, omega, F_po - P_eq,
                                                              tables.k1_bar * P / l, zeta_c))}
    return ReleaseSetup(probe, M, A, omega, D, F0, phase, zeta_c, H_ss, R_s, g, n_periods, n_fly, tables, par,
                        mn / M, kn * l / P, cn * l / (tau * P), z0, tau, meta)


def _barrier(par: np.ndarray, hlow: float) -> tuple[float, float]:
    """Height (scaled) of the potential barrier between the tip (held at ``hlow``) and the
    substrate, and the potential there (tail + substrate + gravity)."""
    tz, tg, S, z0, g, D0 = par[10], par[11], par[6], par[7], par[5], par[9]

    def dV(y):
        d = y - hlow
        return -tz / (tg - d) ** 2 + S / (y - z0) ** 2 + g

    lo = z0 * (1 + 1e-9) + 1e-12
    hi = hlow + D0
    a, b = lo + 1e-9 * (hi - lo), hi
    if dV(a) <= 0 or dV(b) >= 0:
        # no interior barrier (the substrate never wins): the barrier is at the substrate
        yb = lo
    else:
        yb = brentq(dV, a, b, xtol=1e-12 * max(1.0, hi), rtol=1e-14)
    Vb = -tz / (tg - (yb - hlow)) - S / (yb - z0) + g * yb
    return float(yb), float(Vb)


@dataclass
class ReleaseResult:
    outcome: str
    code: int
    t_end_s: float
    t_separation_s: float
    n_steps: int
    n_rejected: int
    max_tension_n: float
    sample_height_m: float
    sample_velocity_m_s: float
    wall_s: float
    setup: ReleaseSetup = field(repr=False)
    trajectory: dict[str, np.ndarray] | None = field(default=None, repr=False)
    #: after the separation: the tip's force on the sample integrated once (per unit mass) and twice
    probe_impulse_velocity_m_s: float = math.nan
    probe_impulse_length_m: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        d = {k: getattr(self, k) for k in ("outcome", "code", "t_end_s", "t_separation_s", "n_steps", "n_rejected",
                                           "max_tension_n", "sample_height_m", "sample_velocity_m_s", "wall_s",
                                           "probe_impulse_velocity_m_s", "probe_impulse_length_m")}
        s = self.setup
        d["inputs"] = {"M_kg": s.M, "A_m": s.A, "omega_rad_s": s.omega, "D_m": s.D, "F0_n": s.F0,
                       "zeta_c": s.zeta_c, "n_modes": s.N, "probe": s.probe.source, "mass_source": s.probe.mass_source}
        d["physics"] = dict(s.meta)
        return d


def simulate(setup: ReleaseSetup, record: bool = False, rtol: float = 1e-6, atol: float = 1e-6,
             max_steps: int = 3_000_000, max_rec: int = 200_000) -> ReleaseResult:
    """One release run with the compiled integrator (see :mod:`._kernel`)."""
    n = setup.z0.size
    at = np.full(n, float(atol))
    Tw = 2 * math.pi / setup.par[2]
    t0 = time.perf_counter()
    out = K.simulate(setup.z0, 1, setup.par, setup.mm, setup.kk, setup.cn, setup.tables.Pn, setup.tables.dPn,
                     float(rtol), at, 1e-3, Tw / 20.0, int(max_steps), bool(record), int(max_rec))
    wall = time.perf_counter() - t0
    code, t, z, s, t_sep, n_acc, n_rej, minP, Iy, Xy, ts, zs, ss, Fs, n_rec = out
    si = setup.to_si(np.array([t]), z[None, :])
    traj = None
    if record:
        traj = setup.to_si(ts, zs)
        traj["contact"] = ss
        traj["contact_force_n"] = Fs * setup.tables.P
    l, tau = setup.tables.l, setup.tau
    return ReleaseResult(OUTCOMES[int(code)], int(code), t * tau, t_sep * tau if t_sep >= 0 else math.nan,
                         int(n_acc), int(n_rej), -minP * setup.tables.P, float(si["sample_m"][0]),
                         float(si["sample_velocity_m_s"][0]), wall, setup, traj,
                         probe_impulse_velocity_m_s=float(Iy) * l / tau, probe_impulse_length_m=float(Xy) * l)


def simulate_scipy(setup: ReleaseSetup, rtol: float = 1e-6, atol: float = 1e-6, method: str = "Radau") -> ReleaseResult:
    """The same model on ``scipy.integrate.solve_ivp`` (the plain reference): ``method`` with
    the analytic Jacobian, terminal events for the contact transitions and the release check,
    restarted at each transition; the right-hand side calls the compiled kernel."""
    par, mm, kk, cn, Pn, dPn = setup.par, setup.mm, setup.kk, setup.cn, setup.tables.Pn, setup.tables.dPn
    n = setup.z0.size
    N = setup.N
    f = np.empty(n)
    J = np.empty((n, n))
    Tt = np.empty(n)
    state = {"s": 1}

    def rhs(t, z):
        K.rhs_jac(t, z, state["s"], par, mm, kk, cn, Pn, dPn, f, J, Tt, False)
        return f.copy()

    def jac(t, z):
        K.rhs_jac(t, z, state["s"], par, mm, kk, cn, Pn, dPn, f, J, Tt, True)
        return J.copy()

    def ev_switch(t, z):
        return z[N] - (par[8] if state["s"] == 1 else par[9])

    ev_switch.terminal = True

    def ev_release(t, z):
        if state["s"] == 1 or t_sep[0] < 0:
            return 1.0
        E, y, v = K._energy(z, par, N)
        ok_b = y < par[16] and v < 0
        ok_e = y < par[13] - par[14] and v < 0 and E > par[15]
        return -1.0 if (ok_b or ok_e) else 1.0

    ev_release.terminal = True
    ev_release.direction = -1
    t0w = time.perf_counter()
    t, z = 0.0, setup.z0.copy()
    t_sep = [-1.0]
    n_steps = 0
    code = -1
    Tw = 2 * math.pi / par[2]
    minP = 0.0
    while True:
        T_lim = par[17] if t_sep[0] < 0 else t_sep[0] + par[18]
        if t >= T_lim:
            code = 0 if t_sep[0] < 0 else 3
            break
        ev_switch.direction = -1 if state["s"] == 1 else 1
        sol = solve_ivp(rhs, (t, T_lim), z, method=method, jac=jac, rtol=rtol, atol=atol,
                        events=[ev_switch, ev_release], max_step=Tw / 20.0, first_step=1e-3 if t == 0 else 1e-9)
        n_steps += sol.t.size - 1
        if state["s"] == 1:
            minP = min(minP, min(K.md_force(float(d), 1, par, Pn, dPn)[0] for d in sol.y[N]))
        if not sol.success:
            raise SolverError(f"solve_ivp release run failed: {sol.message}")
        t, z = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status == 1 and len(sol.t_events[0]):
            if state["s"] == 1:
                state["s"] = 0
                if t_sep[0] < 0:
                    t_sep[0] = t
                z[N] = min(z[N], par[8] - 1e-12)
            else:
                state["s"] = 1
                code = 1
                break
        elif sol.status == 1 and len(sol.t_events[1]):
            code = 2
            break
    wall = time.perf_counter() - t0w
    si = setup.to_si(np.array([t]), z[None, :])
    return ReleaseResult(OUTCOMES[code], code, t * setup.tau, t_sep[0] * setup.tau if t_sep[0] >= 0 else math.nan,
                         n_steps, 0, -minP * setup.tables.P, float(si["sample_m"][0]),
                         float(si["sample_velocity_m_s"][0]), wall, setup)


# ------------------------------------------------------------------------------------------
# Outcome maps (Dask sweeps)
# ------------------------------------------------------------------------------------------

_PROBE_CACHE: dict[Any, PlacingProbe] = {}


def _probe_from_spec(spec: Mapping[str, Any]) -> PlacingProbe:
    """A PlacingProbe rebuilt from the plain numbers a sweep carries (picklable, hashable)."""
    key = tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v) for k, v in spec.items()))
    if key not in _PROBE_CACHE:
        _PROBE_CACHE[key] = PlacingProbe(float(spec["k"]), tuple(spec["omegas"]), tuple(spec["modal_masses"]),
                                         float(spec["zeta"]), float(spec["L"]), float(spec["EI"]),
                                         float(spec["rhoA"]), str(spec["mass_source"]), str(spec["source"]))
    return _PROBE_CACHE[key]


def probe_spec(probe: PlacingProbe) -> dict[str, Any]:
    """The plain numbers of a probe that a sweep's fixed parameters carry."""
    return {"k": probe.k, "omegas": list(probe.omegas), "modal_masses": list(probe.modal_masses),
            "zeta": probe.zeta, "L": probe.L, "EI": probe.EI, "rhoA": probe.rhoA,
            "mass_source": probe.mass_source, "source": probe.source}


_TABLE_CACHE: dict[Any, ContactTables] = {}


def _tables(lam: float) -> ContactTables:
    if lam not in _TABLE_CACHE:
        _TABLE_CACHE[lam] = ContactTables.build(placing_contact(lam))
    return _TABLE_CACHE[lam]


def _tables_H(H: float) -> ContactTables:
    key = ("H", H)
    if key not in _TABLE_CACHE:
        _TABLE_CACHE[key] = ContactTables.build(placing_contact(H=H))
    return _TABLE_CACHE[key]


def release_cells(M, A, omega, D, probe: Mapping[str, Any], zeta_c: float = 0.1, lam: float = 2.0,
                  n_modes: int = 1, n_periods: float = 3.0, n_fly: float = 20.0, rtol: float = 1e-6) -> dict[str, np.ndarray]:
    """Sweep cell function (vectorised): the release outcome of every cell (``M``, ``A``,
    ``omega``, ``D`` arrays of equal length, or scalars broadcast). Returns ``outcome`` (code),
    ``t_separation`` [s], ``release_velocity`` [m/s], ``n_steps``, ``cpu_s`` per cell."""
    M, A, omega, D = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, float)) for v in (M, A, omega, D)))
    pr = _probe_from_spec(probe)
    tabs = _tables(float(lam))
    n = M.size
    out = {"outcome": np.full(n, -1, dtype=np.int8), "t_separation": np.full(n, np.nan),
           "release_velocity": np.full(n, np.nan), "n_steps": np.zeros(n, dtype=np.int64),
           "cpu_s": np.zeros(n)}
    for i in range(n):
        t0 = time.perf_counter()
        if A[i] >= 0.9 * D[i]:  # the oscillating tip would hit the substrate: no release experiment
            out["outcome"][i] = 4
            continue
        if M[i] * G >= abs(tabs.pull_off_force):  # cannot even be held: falls under its own weight
            out["outcome"][i] = 5
            continue
        st = setup_release(pr, M=float(M[i]), A=float(A[i]), omega=float(omega[i]), D=float(D[i]), zeta_c=zeta_c,
                           n_modes=n_modes, n_periods=n_periods, n_fly=n_fly, tables=tabs)
        r = simulate(st, rtol=rtol)
        out["outcome"][i] = r.code
        out["t_separation"][i] = r.t_separation_s
        out["release_velocity"][i] = r.sample_velocity_m_s if r.code == 2 else np.nan
        out["n_steps"][i] = r.n_steps
        out["cpu_s"][i] = time.perf_counter() - t0
    return out


def outcome_map(probe: PlacingProbe, grid: Mapping[str, Any], fixed: Mapping[str, Any] | None = None,
                out=None, workers: int = 2, chunk_size: int | None = None, progress: bool = False,
                processes: bool = True, restart: bool = False, **kw):
    """An outcome map over any of ``M``, ``A``, ``omega``, ``D`` (the others fixed, Table 4.4
    defaults; ``A`` defaults to the tip amplitude of ``F0 = 5e-7 N``) on Dask
    (:func:`probedyn.schemes.sweep.run_sweep`), NetCDF at ``out``. Returns the SweepResult."""
    fixed = dict(fixed or {})
    g = validate_grid(grid, fixed)
    for name in g:
        if name not in ("M", "A", "omega", "D"):
            raise ParameterError(f"outcome map axis must be one of M, A, omega, D; got {name!r}")
    defaults = {"M": float(TABLE["M1"]), "omega": float(TABLE["omega"]), "D": float(TABLE["D"])}
    for k, v in defaults.items():
        if k not in g:
            fixed.setdefault(k, v)
    if "A" not in g and "A" not in fixed:
        fixed["A"] = float(TABLE["F_0"]) / probe.k
    fixed["probe"] = probe_spec(probe)
    fixed.update(kw)
    attrs = {"outcomes": json_outcomes(), "model": "schemes.placing.release (full Maugis-Dugdale, eq 4.42)"}
    return run_sweep(release_cells, g, fixed=fixed, out=out, workers=workers, chunk_size=chunk_size,
                     progress=progress, processes=processes, attrs=attrs, restart=restart)


def json_outcomes() -> str:
    return json.dumps({str(k): v for k, v in OUTCOMES.items()})


__all__ = ["ContactTables", "ReleaseSetup", "ReleaseResult", "OUTCOMES", "placing_contact", "setup_release",
           "simulate", "simulate_scipy", "threshold_amplitude", "release_cells", "outcome_map", "probe_spec"]
