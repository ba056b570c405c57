"""FFM line-scan model, eqs (2.13)–(2.16) of the source, with any friction model of the registry.

The cantilever is a 2-DOF spring–mass system (2.13)–(2.14); the base moves along x at the scan
speed V (2.15):

    m_x x'' + c_x x' + k_x x = D_x - I_x - F_x,     D_x = c_x V + k_x V t          (2.13), (2.15)
    m_y y'' + c_y y' + k_y y = D_y - I_y - F_y,     D_y = F_y - F_cy               (2.14), (2.16)

Reading: ``x`` is the tip position in the sample frame (the tip starts at the base at t = 0);
``D_x`` is the spring-dashpot force of the moving base, so (2.13) is
``m x'' = c (V - x') + k (V t - x) - F``. The lateral force an FFM measures is the spring
force ``k_x (V t - x)``. The interaction force ``I`` (Derjaguin, 2.2) is normal to the sample
and its lateral components are taken as zero (``I_x = I_y = 0``).

(2.16) makes ``F_y`` cancel in (2.14): ``m_y y'' + c_y y' + k_y y = -F_cy``. The y-motion is
then a damped relaxation to ``y = -F_cy / k_y`` that feeds back into x only through
``max(V_x, V_y)``, ``||V||_inf`` and ``V_x + V_y`` in (2.8)–(2.9). :func:`line_scan_2d`
integrates this full model; :func:`line_scan` the 1D reduction (``V_y = 0``, eqs 2.7–2.9,
2.13, 2.15) with any registry model. ``tests/test_ffm.py`` checks that the two agree after
the y-transient (about c_y/k_y = 70 ns).

Fast integrator: the system is stiff (sigma0 / m_x ~ 5e21 s^-2, (c + F_v)/m ~ 5e10 s^-1 against a
5 ms scan), so it is integrated by a numba-compiled linearly implicit Rosenbrock method of order
2(3) (the W-method of Shampine & Reichelt 1997, MATLAB ode23s; L-stable) with the analytic
Jacobian from the friction model's kernel, adaptive steps and an embedded error estimate
(:mod:`probedyn.schemes.rosenbrock`, shared with the N-mode and 2D-lattice scans). The
source used MATLAB ode23tb with rtol 1e-2 and atol 1e-15.

Presets: ``mica`` (Table 2.1; F_nu in N s/m, departure 10; scan 10 nm at 2 um/s,
section 2.1.5.1) and ``vamwcnt`` (Table 2.2; scan range 1 um; the scan speed is not stated
for this sample, 2 um/s of the mica experiment is assumed); the values are those of
:mod:`probedyn.core.presets`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset as table
from probedyn.lumped.reduced import ReducedProbe
from probedyn.schemes.friction import FrictionModel, model_class
from probedyn.schemes.friction.bristle import bristle2d_eval
from probedyn.schemes.friction.prandtl_tomlinson import MICA_LATTICE
from probedyn.schemes.probe_hooks import ffm_cantilever
from probedyn.schemes.rosenbrock import ros23, stable_identity
from probedyn.schemes.stickslip_analysis import analyze

# ------------------------------------------------------------------------------------------
# Parameters and presets
# ------------------------------------------------------------------------------------------

_T21 = table("table-2.1")

CANTILEVER_PARAMS = ParamSet([
    Param("m_x", _T21["m_x"], "kg", "effective mass, x", positive=True, hi=1e-3, source="(2.13); Table 2.1"),
    Param("c_x", _T21["c_x"], "N s/m", "damping, x", lo=0.0, hi=1.0, source="(2.13); Table 2.1"),
    Param("k_x", _T21["k_x"], "N/m", "lateral stiffness, x", positive=True, hi=1e7, source="(2.13); Table 2.1"),
    Param("m_y", _T21["m_y"], "kg", "effective mass, y", positive=True, hi=1e-3, source="(2.14); Table 2.1"),
    Param("c_y", _T21["c_y"], "N s/m", "damping, y", lo=0.0, hi=1.0, source="(2.14); Table 2.1"),
    Param("k_y", _T21["k_y"], "N/m", "stiffness, y", positive=True, hi=1e7, source="(2.14); Table 2.1"),
    Param("V", _T21["V"], "m/s", "scan speed of the base", positive=True, hi=1.0, source="(2.15); 2.1.5.1"),
    Param("length", _T21["scan_length"], "m", "scan length (base travel)", positive=True, hi=1e-3, source="2.1.5.1"),
])

#: y-direction friction parameters of the 2D model (2.10)-(2.12)
Y_FRICTION_PARAMS = ParamSet([
    Param("sigma0_y", _T21["sigma0_y"], "N/m", "bristle stiffness sigma_0y", positive=True, hi=1e9, source="(2.10)"),
    Param("F_sy", _T21["F_s_y"], "N", "static friction F_sy", positive=True, hi=1e-3, source="(2.12)"),
    Param("F_cy", _T21["F_c_y"], "N", "kinetic friction F_cy", positive=True, hi=1e-3, source="(2.12), (2.16)"),
    Param("F_vy", _T21["F_v_y"], "N s/m", "viscous friction F_vy", lo=0.0, hi=1.0, source="(2.10)"),
])


def _ffm_preset(key: str, source: str) -> dict[str, Any]:
    """A table of :mod:`probedyn.core.presets` split into cantilever, x-friction and y-friction."""
    t = table(key)
    return dict(
        cantilever=dict(t.pick("m_x", "c_x", "k_x", "m_y", "c_y", "k_y", "V"), length=t["scan_length"]),
        friction=t.pick("V_s", sigma0="sigma0_x", F_s="F_s_x", F_c="F_c_x", F_v="F_v_x"),
        friction_y=t.pick(sigma0_y="sigma0_y", F_sy="F_s_y", F_cy="F_c_y", F_vy="F_v_y"),
        source=source,
    )


PRESETS: dict[str, dict[str, Any]] = {
    # F_nu printed in N; N s/m per departure 10.
    "mica": _ffm_preset("table-2.1", "Table 2.1; scan 10 nm x 10 nm at 2000 nm/s (2.1.5.1)"),
    # Scan speed not given in 2.1.5.2: 2 um/s assumed.
    "vamwcnt": _ffm_preset("table-2.2", "Table 2.2; scan range 1 um (2.1.5.2); speed 2 um/s assumed (not stated)"),
}


@dataclass
class FFM:
    """An FFM line-scan setup: cantilever + scan (:data:`CANTILEVER_PARAMS`) and a friction model."""

    cantilever: dict[str, float]
    friction: FrictionModel
    friction_y: dict[str, float] = field(default_factory=lambda: Y_FRICTION_PARAMS.defaults())
    preset: str | None = None
    #: the reduced probe the cantilever parameters came from (None: the preset's table values)
    probe: ReducedProbe | None = None

    @classmethod
    def from_preset(cls, preset: str = "mica", model: str = "bristle",
                    overrides: Mapping[str, Any] | None = None, friction_scale: float = 1.0,
                    normal_load: float | None = None, probe: ReducedProbe | None = None) -> "FFM":
        """Build from a preset; ``overrides`` may name cantilever, friction-model or y-friction
        parameters. ``friction_scale`` multiplies the friction levels (normal-load input of
        the adhesion coupling); ``normal_load`` [N] does it with ``L / 141.75 nN``. ``probe``: a
        :class:`~probedyn.lumped.reduced.ReducedProbe` whose scan / lateral one-mode models
        replace the table's ``m, c, k`` (:func:`probedyn.schemes.probe_hooks.ffm_cantilever`);
        explicit ``overrides`` still win."""
        if preset not in PRESETS:
            raise ParameterError(f"unknown FFM preset {preset!r} (known: {', '.join(PRESETS)})")
        pr = PRESETS[preset]
        cls_m = model_class(model)
        over = dict(overrides or {})
        cant_over = {k: over.pop(k) for k in list(over) if k in CANTILEVER_PARAMS}
        y_over = {k: over.pop(k) for k in list(over) if k in Y_FRICTION_PARAMS}
        fr = {k: v for k, v in pr["friction"].items() if k in cls_m.params}
        unknown = [k for k in over if k not in cls_m.params]
        if unknown:
            known = [p.name for p in CANTILEVER_PARAMS] + [p.name for p in cls_m.params] + \
                [p.name for p in Y_FRICTION_PARAMS]
            raise ParameterError(f"unknown parameter '{unknown[0]}' for model {cls_m.key!r} "
                                 f"(known: {', '.join(known)})")
        fr.update(over)
        fm = cls_m(**fr)
        if normal_load is not None:
            fm = fm.at_load(normal_load)
        if friction_scale != 1.0:
            fm = fm.scaled(friction_scale)
        from_probe = ffm_cantilever(probe) if probe is not None else {}
        cant = CANTILEVER_PARAMS.resolve({**pr["cantilever"], **from_probe, **cant_over})
        fy = Y_FRICTION_PARAMS.resolve({**pr["friction_y"], **y_over})
        if fy["F_cy"] > fy["F_sy"]:
            raise ParameterError(f"F_cy = {fy['F_cy']:g} N > F_sy = {fy['F_sy']:g} N: kinetic friction "
                                 "cannot exceed static friction in the bristle model")
        return cls(cantilever=cant, friction=fm, friction_y=fy, preset=preset, probe=probe)

    @property
    def alpha(self) -> float:
        """alpha = sigma0^2 / k_x (section 2.1.4.2, Fig 2.10) [N/m]; NaN without a bristle stiffness."""
        s0 = self.friction.presliding_stiffness()
        return math.nan if s0 is None else s0 * s0 / self.cantilever["k_x"]


# ------------------------------------------------------------------------------------------
# The 1D FFM model (2.13), (2.15) as a system of the shared Rosenbrock integrator
# ------------------------------------------------------------------------------------------
# ``kern`` is the friction model's numba kernel, passed as an argument: numba compiles (and
# caches on disk, see friction.base._stable_identity) one specialisation per model, with the
# kernel inlined, so a new model runs at the speed of the built-in ones.

@njit(cache=True)
def _system(kern, ctx, t, y, f, J, Tt, want_j):
    """``y = (x, x', z)``, ``ctx = (p, m, c, k, V, X0)``: the support at ``X0 + V t``; returns the friction."""
    p, m, c, k, V, X0 = ctx
    x, v, z = y[0], y[1], y[2]
    F, zd, dFx, dFv, dFz, dzx, dzv, dzz = kern(p, x, v, z)
    f[0] = v
    f[1] = (c * (V - v) + k * (X0 + V * t - x) - F) / m
    f[2] = zd
    if want_j:
        J[0, 0] = 0.0
        J[0, 1] = 1.0
        J[0, 2] = 0.0
        J[1, 0] = (-k - dFx) / m
        J[1, 1] = (-c - dFv) / m
        J[1, 2] = -dFz / m
        J[2, 0] = dzx
        J[2, 1] = dzv
        J[2, 2] = dzz
        Tt[0] = 0.0
        Tt[1] = k * V / m
        Tt[2] = 0.0
    return F


stable_identity(_system, "ffm")  # the on-disk cache finds ros23's specialisation again (schemes/rosenbrock.py)


def _ros23(kern, p, m, c, k, V, T, y0, rtol, atol, h0, hmax, max_steps, X0=0.0):
    """One support segment ``X = X0 + V t``, ``0 <= t <= T`` (:func:`probedyn.schemes.rosenbrock.ros23`)."""
    return ros23(_system, kern, (p, float(m), float(c), float(k), float(V), float(X0)), float(T), y0, rtol, atol,
                 float(h0), float(hmax), int(max_steps))


@dataclass
class ScanResult:
    """A line scan on the solver's own steps and on a uniform base-position grid."""

    t: np.ndarray           # s
    base: np.ndarray        # m, base position V t
    x: np.ndarray           # m, tip position
    v: np.ndarray           # m/s, tip velocity
    z: np.ndarray           # internal state (bristle deflection, m)
    lateral_force: np.ndarray  # N, spring force k_x (V t - x) (the FFM signal)
    friction: np.ndarray    # N, friction force F
    n_steps: int
    n_rejected: int
    setup: dict

    def on_grid(self, n: int = 4000) -> dict[str, np.ndarray]:
        """Linear interpolation onto ``n`` uniformly spaced base positions."""
        b = np.linspace(self.base[0], self.base[-1], n)
        return dict(base=b, lateral_force=np.interp(b, self.base, self.lateral_force),
                    x=np.interp(b, self.base, self.x), friction=np.interp(b, self.base, self.friction))


def _atol(ffm: FFM, atol_rel: float) -> np.ndarray:
    """Absolute tolerances: ``atol_rel`` of the model's force scale / k_x (x), of V (x') and of
    the model's state scale (z), :meth:`FrictionModel.scales`."""
    Fscale, zscale = ffm.friction.scales()
    k = ffm.cantilever["k_x"]
    V = ffm.cantilever["V"]
    return np.array([atol_rel * Fscale / k, atol_rel * V, atol_rel * zscale])


def line_scan(ffm: FFM, length: float | None = None, rtol: float = 1e-5, atol_rel: float = 1e-7,
              max_steps: int = 5_000_000) -> ScanResult:
    """1D FFM line scan (2.13), (2.15) with the friction model of ``ffm`` (V_y = 0).

    Initial state: tip at rest at the base position (spring relaxed), x = 0, bristle undeflected
    (z = 0), as in 2.1.5.1 (zero initial velocities and deflections). For the PT model x = 0 is
    a potential minimum.
    Tolerances: relative ``rtol``; absolute ``atol_rel`` times the natural scales (friction
    level / k_x for x, V for x', friction level / sigma0 for z).
    """
    cp = ffm.cantilever
    L = cp["length"] if length is None else float(length)
    if not (L > 0 and math.isfinite(L)):
        raise ParameterError(f"scan length must be positive, got {length!r}")
    fm = ffm.friction
    m, c, k, V = cp["m_x"], cp["c_x"], cp["k_x"], cp["V"]
    T = L / V
    p = fm.pack()
    y0 = np.zeros(3)
    h0 = 1e-3 * math.sqrt(m / k)
    ts, ys, Fr, nst, nrej = _ros23(fm.kernel, p, m, c, k, V, T, y0, rtol, _atol(ffm, atol_rel), h0, T / 50.0,
                                   max_steps)
    if nst < 0:
        raise SolverError(f"FFM line scan: more than {max_steps} steps (shorten the scan or loosen rtol)")
    x = ys[:, 0]
    return ScanResult(t=ts, base=V * ts, x=x, v=ys[:, 1], z=ys[:, 2], lateral_force=k * (V * ts - x),
                      friction=Fr, n_steps=int(nst), n_rejected=int(nrej),
                      setup=dict(preset=ffm.preset, model=fm.key, cantilever=dict(cp),
                                 friction=dict(fm.values), length=L, rtol=rtol, atol_rel=atol_rel))


def along_turns(turns, speed: float, y, hmax: float | None, segment, what: str, max_steps: int):
    """Integrate a scan segment by segment along a piecewise-linear support path ``turns`` visited at ``speed``,
    the state carried over: ``segment(V, T, y, hmax, X_a)`` integrates ``X = X_a + V t`` for ``0 <= t <= T`` and
    returns ``(t, states, extra, n_steps, n_rejected)`` (``extra``: a per-step array or None); ``hmax`` is capped
    at a fiftieth of a segment. Returns the concatenated ``(t, base, states, extra, n_steps, n_rejected)``."""
    t_off = 0.0
    parts_t, parts_b, parts_y, parts_e = [], [], [], []
    steps = rej = 0
    for Xa, Xb in zip(turns[:-1], turns[1:]):
        if Xb == Xa:
            continue
        V = speed if Xb > Xa else -speed
        T = abs(Xb - Xa) / speed
        hm = T / 50.0 if hmax is None else min(hmax, T / 50.0)
        ts, ys, extra, nst, nrej = segment(V, T, y, hm, Xa)
        if nst < 0:
            raise SolverError(f"{what}: more than {max_steps} steps in one segment")
        first = 0 if not parts_t else 1
        parts_t.append(ts[first:] + t_off)
        parts_b.append(Xa + V * ts[first:])
        parts_y.append(ys[first:])
        if extra is not None:
            parts_e.append(extra[first:])
        y = ys[-1].copy()
        t_off += T
        steps += int(nst)
        rej += int(nrej)
    return (np.concatenate(parts_t), np.concatenate(parts_b), np.concatenate(parts_y),
            np.concatenate(parts_e) if parts_e else None, steps, rej)


def line_scan_path(ffm: FFM, turns, speed: float | None = None, y0=None, rtol: float = 1e-6,
                   atol_rel: float = 1e-7, hmax: float | None = None, max_steps: int = 2_000_000,
                   atol_v: float | None = None) -> ScanResult:
    """FFM scan (2.13) along a piecewise-linear support path: ``turns`` = support positions
    ``[X_0, X_1, ...]`` visited in order at ``speed`` (default the cantilever's V), e.g.
    ``[0, L, 0]`` for a trace and its retrace (a friction loop). Initial state ``y0`` =
    (x, x', z) (default: at rest at ``X_0``, spring relaxed). The segments are integrated one after
    the other with the state carried over, so the reversal is resolved (the tip sticks while the
    support runs back through twice the friction force over k, then slips backwards).
    ``hmax`` caps the step (default: a fiftieth of a segment); ``atol_v`` is the absolute tolerance
    on the tip velocity (default ``atol_rel * speed``). The result concatenates the
    segments (``base`` not monotonic)."""
    cp = ffm.cantilever
    fm = ffm.friction
    m, c, k = cp["m_x"], cp["c_x"], cp["k_x"]
    V0 = cp["V"] if speed is None else float(speed)
    if not (V0 > 0 and math.isfinite(V0)):
        raise ParameterError(f"scan speed must be positive, got {speed!r}")
    turns = [float(x) for x in turns]
    if len(turns) < 2:
        raise ParameterError("line_scan_path needs at least two turning points")
    p = fm.pack()
    atol = _atol(ffm, atol_rel)
    atol[1] = atol_rel * V0 if atol_v is None else atol_v
    y = np.array([turns[0], 0.0, 0.0]) if y0 is None else np.asarray(y0, float).copy()
    h0 = 1e-3 * math.sqrt(m / k)

    def segment(V, T, y, hm, Xa):
        ts, ys, Fr, nst, nrej = _ros23(fm.kernel, p, m, c, k, V, T, y, rtol, atol, h0, hm, max_steps, Xa)
        return ts, ys, Fr, nst, nrej

    t, base, ys, Fr, steps, rej = along_turns(turns, V0, y, hmax, segment, "FFM scan path", max_steps)
    return ScanResult(t=t, base=base, x=ys[:, 0], v=ys[:, 1], z=ys[:, 2], lateral_force=k * (base - ys[:, 0]),
                      friction=Fr, n_steps=steps, n_rejected=rej,
                      setup=dict(preset=ffm.preset, model=fm.name, cantilever=dict(cp), friction=dict(fm.values),
                                 turns=turns, speed=V0, rtol=rtol, atol_rel=atol_rel))


def warm_up(model: str = "bristle") -> None:
    """Compile the integrator for ``model``'s kernel (cached on disk after the first run)."""
    ffm = FFM.from_preset("mica", model)
    line_scan(ffm, length=1e-10)


# ------------------------------------------------------------------------------------------
# Full 2D model (2.10)-(2.12), (2.14), (2.16) - scipy Radau with the analytic Jacobian
# ------------------------------------------------------------------------------------------

def line_scan_2d(ffm: FFM, length: float | None = None, rtol: float = 1e-6, n_out: int = 4000,
                 method: str = "Radau") -> dict[str, np.ndarray]:
    """The full model: states (x, x', z_x, y, y', z_y); friction (2.7)–(2.12); drives (2.15),
    (2.16) with ``I = 0``. Requires the ``bristle`` model. Returns the x lateral force
    ``k_x (V t - x)``, ``y``, the friction components and the solver statistics."""
    fm = ffm.friction
    if fm.key != "bristle":
        raise ParameterError("line_scan_2d implements (2.7)-(2.12): use the 'bristle' model")
    cp, fy = ffm.cantilever, ffm.friction_y
    L = cp["length"] if length is None else float(length)
    mx, cx, kx, my, cy, ky, V = (cp[n] for n in ("m_x", "c_x", "k_x", "m_y", "c_y", "k_y", "V"))
    fv = fm.values
    p = np.array([fv["sigma0"], fy["sigma0_y"], fv["F_s"], fy["F_sy"], fv["F_c"], fy["F_cy"], fv["V_s"],
                  fv["F_v"], fy["F_vy"], 1.0 if fv["vmax"] == "literal" else 0.0])
    Fcy = fy["F_cy"]

    def rhs(t, s):
        x, vx, zx, y, vy, zy = s
        Fx, Fy, zxd, zyd, _ = bristle2d_eval(p, vx, vy, zx, zy)
        Dy = Fy - Fcy
        return [vx, (cx * (V - vx) + kx * (V * t - x) - Fx) / mx, zxd,
                vy, (-cy * vy - ky * y + Dy - Fy) / my, zyd]

    def jac(t, s):
        x, vx, zx, y, vy, zy = s
        _, _, _, _, Jf = bristle2d_eval(p, vx, vy, zx, zy)
        # Jf rows (Fx, Fy, zx', zy') wrt (vx, vy, zx, zy); state order (x, vx, zx, y, vy, zy)
        col = {0: 1, 1: 4, 2: 2, 3: 5}
        Jm = np.zeros((6, 6))
        Jm[0, 1] = 1.0
        Jm[1, 0] = -kx / mx
        Jm[1, 1] = -cx / mx
        for j in range(4):
            Jm[1, col[j]] -= Jf[0, j] / mx
            Jm[2, col[j]] += Jf[2, j]
            Jm[5, col[j]] += Jf[3, j]
        Jm[3, 4] = 1.0
        Jm[4, 3] = -ky / my
        Jm[4, 4] = -cy / my  # D_y - F_y = -F_cy: F_y cancels
        return Jm

    T = L / V
    te = np.linspace(0.0, T, n_out)
    sc = np.array([1e-7 * fv["F_s"] / kx, 1e-7 * V, 1e-7 * fv["F_s"] / fv["sigma0"],
                   1e-7 * Fcy / ky, 1e-7 * V, 1e-7 * fy["F_sy"] / fy["sigma0_y"]])
    sol = solve_ivp(rhs, (0.0, T), np.zeros(6), method=method, jac=jac, t_eval=te, rtol=rtol, atol=sc,
                    first_step=1e-13)
    if not sol.success:
        raise SolverError(f"2D FFM line scan failed: {sol.message}")
    x, vx, zx, y, vy, zy = sol.y
    return dict(t=sol.t, base=V * sol.t, x=x, y=y, zx=zx, zy=zy,
                lateral_force=kx * (V * sol.t - x), nfev=sol.nfev)


# ------------------------------------------------------------------------------------------
# Quasi-static references
# ------------------------------------------------------------------------------------------

def presliding_force(ffm: FFM, base: np.ndarray) -> np.ndarray:
    """Quasi-static pre-sliding (stick) branch of the bristle/LuGre models in the limit
    V << V_s, inertia and damping negligible. With z' = x' (1 - z/g0), g0 = F_s/sigma0, and
    the force balance sigma0 z = k (X - x):

        x = g0 ln(1 / (1 - z/g0)),  X = x + sigma0 z / k,   lateral force = sigma0 z.

    Returns the lateral force at the base positions ``base`` (NaN beyond the first slip)."""
    s0, lv = ffm.friction.presliding_stiffness(), ffm.friction.levels()
    if s0 is None or lv is None:
        raise ParameterError("presliding_force needs a bristle-type model (sigma0, F_s)")
    Fs, k = lv[0], ffm.cantilever["k_x"]
    g0 = Fs / s0
    zeta = np.linspace(0.0, 1.0 - 1e-12, 20001)
    xx = -g0 * np.log1p(-zeta)
    X = xx + s0 * zeta * g0 / k
    return np.interp(base, X, s0 * zeta * g0, right=np.nan)


# ------------------------------------------------------------------------------------------
# One call: scan + analysis (used by the CLI, the report and other schemes)
# ------------------------------------------------------------------------------------------

def run_ffm(preset: str = "mica", model: str = "bristle", overrides: Mapping[str, Any] | None = None,
            length: float | None = None, friction_scale: float = 1.0, normal_load: float | None = None,
            rtol: float = 1e-5, probe: ReducedProbe | None = None) -> tuple[ScanResult, dict[str, Any]]:
    """Line scan of ``preset`` with friction model ``model``; returns the scan and a summary:
    static / kinetic friction, period, regime (:func:`probedyn.schemes.stickslip_analysis.analyze`),
    the quasi-static estimates ``F_s / k_x`` (first slip) and ``(F_s - F_c) / k_x`` (period),
    alpha, wall time and solver statistics; with a ``probe`` (a reduced probe: its scan/lateral
    one-mode models drive the cantilever) the summary carries the probe's provenance."""
    ffm = FFM.from_preset(preset, model, overrides, friction_scale=friction_scale, normal_load=normal_load,
                          probe=probe)
    line_scan(ffm, 1e-3 * ffm.cantilever["V"] * math.sqrt(ffm.cantilever["m_x"] / ffm.cantilever["k_x"]))
    # ^ loads / compiles the numba kernels so that wall_time_s measures the integration only
    t0 = time.perf_counter()
    res = line_scan(ffm, length, rtol=rtol)
    wall = time.perf_counter() - t0
    an = analyze(res.base, res.lateral_force)
    fv = ffm.friction.values
    lv = ffm.friction.levels()
    k = ffm.cantilever["k_x"]
    summary = dict(
        preset=preset, model=ffm.friction.key, scan_length_m=res.setup["length"],
        scan_speed_m_s=ffm.cantilever["V"], k_x=k, alpha=ffm.alpha,
        static_friction_n=an["static_friction_n"], kinetic_friction_n=an["kinetic_friction_n"],
        period_m=an["period_m"], regime=an["regime"], first_slip_m=an["first_slip_m"],
        n_slips=an["n_slips"], slip_fraction=an["slip_fraction"], abruptness=an.get("abruptness"),
        max_force_n=an["max_force_n"],
        first_slip_estimate_m=(lv[0] / k) if lv else None,
        period_estimate_m=((lv[0] - lv[1]) / k) if lv else None,
        F_s=lv[0] if lv else None, F_c=lv[1] if lv else None,
        wall_time_s=wall, n_steps=res.n_steps, n_rejected=res.n_rejected,
        parameters=dict(cantilever=dict(ffm.cantilever), friction=dict(fv)),
        probe=probe.summary() if probe is not None else None,
        probe_source=probe.source if probe is not None else PRESETS[preset]["source"],
    )
    kin = an["kinetic_friction_n"]
    if lv and kin is not None and kin < lv[1] - 0.01 * (lv[0] - lv[1]):
        # the source's "kinetic friction" (mean of the lowest values, 2.1.5.1) equals F_c only for an
        # overdamped slip; an underdamped probe swings past F_c towards 2 F_c - F_s
        zeta = ffm.cantilever["c_x"] / (2.0 * math.sqrt(ffm.cantilever["k_x"] * ffm.cantilever["m_x"]))
        summary["kinetic_note"] = (
            f"the valleys ({kin * 1e9:.4g} nN) lie below the model's F_c = {lv[1] * 1e9:.4g} nN: the slip "
            f"overshoots (damping ratio of the scan spring {zeta:.3g}; undamped limit 2 F_c - F_s = "
            f"{(2 * lv[1] - lv[0]) * 1e9:.4g} nN), so the mean of the lowest values is not F_c")
    return res, summary


# ------------------------------------------------------------------------------------------
# Studies: alpha sweep (Fig 2.10), Prandtl-Tomlinson eta sweep
# ------------------------------------------------------------------------------------------

def alpha_sweep(sigma0_values=None, preset: str = "mica", length: float = 150e-9) -> list[dict[str, Any]]:
    """Regime vs alpha = sigma0^2 / k_x (Fig 2.10): the bristle stiffness is varied (the source's
    tuning knob, 2.1.4.2) with everything else of ``preset`` fixed; each row has alpha, the shape
    measures (slip_fraction, abruptness), the regime and the friction levels."""
    if sigma0_values is None:
        sigma0_values = np.logspace(1, 5, 9)
    rows = []
    for s0 in sigma0_values:
        _, r = run_ffm(preset, "bristle", {"sigma0": float(s0)}, length=length)
        rows.append(dict(sigma0=float(s0), alpha=r["alpha"], regime=r["regime"], n_slips=r["n_slips"],
                         slip_fraction=r["slip_fraction"], abruptness=r["abruptness"],
                         static_friction_n=r["static_friction_n"], kinetic_friction_n=r["kinetic_friction_n"],
                         period_m=r["period_m"], first_slip_m=r["first_slip_m"], max_force_n=r["max_force_n"]))
    return rows


def pt_eta_sweep(etas=(0.3, 0.6, 0.9, 1.2, 2.0, 4.0), n_lattice: int = 12, preset: str = "mica",
                 rtol: float = 1e-5) -> list[dict[str, Any]]:
    """1D Prandtl–Tomlinson through the FFM model (2.13), (2.15) with the ``pt`` registry model:
    the cantilever of ``preset``, the mica lattice, ``U0 = eta k_x a^2 / (4 pi^2)``. Each row:
    eta, period / a, regime, abruptness and the quasi-static abruptness of smooth sliding
    ``(1 + eta) / (1 - eta)`` (eta < 1)."""
    a = MICA_LATTICE
    k = PRESETS[preset]["cantilever"]["k_x"]
    rows = []
    for eta in etas:
        U0 = eta * k * a * a / (4 * math.pi**2)
        ffm = FFM.from_preset(preset, "pt", {"U0": U0, "a": a})
        res = line_scan(ffm, n_lattice * a, rtol=rtol)
        an = analyze(res.base, res.lateral_force)
        rows.append(dict(eta=float(eta), period_over_a=(an["period_m"] / a) if an["period_m"] else None,
                         regime=an["regime"], abruptness=an.get("abruptness"), n_slips=an["n_slips"],
                         slip_fraction=an["slip_fraction"],
                         smooth_abruptness_qs=((1 + eta) / (1 - eta)) if eta < 1 else None,
                         max_force_n=an["max_force_n"], F0_n=2 * math.pi * U0 / a))
    return rows
