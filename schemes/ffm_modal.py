"""FFM line scan on N modes of a reduced probe (eqs 2.13, 2.15 with modal superposition).

The one-mode FFM model (2.13) reads, with the elastic deflection of the apex ``w = x - V t``,
``m w'' + c w' + k w = -F``: a single oscillator loaded by the friction F at the tip.  A
reduced probe (:class:`probedyn.lumped.reduced.ReducedProbe`) gives the apex deflection along
the scan direction as a sum over its retained modes, each an oscillator referred to the apex
(``m_i = 1/phi_i^2``, ``k_i = omega_i^2 m_i``, ``c_i = 2 zeta_i omega_i m_i``) loaded by the same
force (they act in series), plus the static residual ``R`` of the discarded modes:

    m_i u_i'' + c_i u_i' + k_i u_i = -F(x, x', z),   x = V t + sum_i u_i,   z' = zdot(x, x', z).

The residual is carried by one pseudo-oscillator of stiffness ``1/R`` at the validity limit
(the first discarded mode: it responds quasi-statically to anything slower, which is what the
reduction is valid for) and critically damped (it stands for many modes; ringing at an invented
frequency would be spurious).  With it the static compliance of the N-mode chain is the FEM's
for every N.  The measured FFM signal is the static-equivalent spring force ``k_s (V t - x)``
(``k_s`` the probe's static scan stiffness), the one-mode model's ``k (V t - x)``.

Integrator: the linearly implicit Rosenbrock 2(3) W-method of :mod:`probedyn.schemes.rosenbrock`
on ``2N + 1`` states, with the analytic Jacobian from the friction model's kernel
(``kernel(p, x, v, z)``), numba-compiled.  The rate states are ``s_i = u_i' + V r_i`` (``r_i``
the oscillator's share of the static compliance), whose sum is the tip velocity: they vanish
while the tip sticks, so the relative error control resolves the slow pre-sliding creep as the
one-mode integrator (state x') does; with the plain rates ``u_i'`` (= -V r_i while sticking) it
cannot, and the step size collapses on the non-smooth |v| of the bristle law.  For N = 1 without residual it is the same method on the
same equations as :func:`probedyn.schemes.ffm.line_scan` (tested).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit

from probedyn.core.errors import ParameterError, SolverError
from probedyn.lumped.reduced import ReducedProbe
from probedyn.schemes.rosenbrock import ros23, stable_identity


@njit(cache=True)
def _system(kern, ctx, t, y, f, J, Tt, want_j):
    """States ``u_i`` (deflections), ``s_i = u_i' + V sh_i`` (rates relative to the static share of the base
    motion: ``sum_i s_i`` is the tip velocity, ~0 while sticking), ``z``; ``ctx = (p, m, c, k, sh, V)``.
    Returns the friction."""
    p, m, c, k, sh, V = ctx
    n = m.shape[0]
    x = V * t
    vt = 0.0
    for i in range(n):
        x += y[i]
        vt += y[n + i]
    z = y[2 * n]
    F, zd, dFx, dFv, dFz, dzx, dzv, dzz = kern(p, x, vt, z)
    for i in range(n):
        f[i] = y[n + i] - V * sh[i]
        f[n + i] = (-c[i] * (y[n + i] - V * sh[i]) - k[i] * y[i] - F) / m[i]
    f[2 * n] = zd
    if want_j:
        for a in range(2 * n + 1):
            for b in range(2 * n + 1):
                J[a, b] = 0.0
        for i in range(n):
            J[i, n + i] = 1.0
            for j in range(n):
                J[n + i, j] = -dFx / m[i]
                J[n + i, n + j] = -dFv / m[i]
            J[n + i, i] -= k[i] / m[i]
            J[n + i, n + i] -= c[i] / m[i]
            J[n + i, 2 * n] = -dFz / m[i]
            J[2 * n, i] = dzx
            J[2 * n, n + i] = dzv
            Tt[i] = 0.0
            Tt[n + i] = -dFx * V / m[i]
        J[2 * n, 2 * n] = dzz
        Tt[2 * n] = dzx * V
    return F


stable_identity(_system, "ffm_modal")  # the on-disk cache finds ros23's specialisation again (schemes/rosenbrock.py)


@dataclass
class ModalFFM:
    """Oscillators in series along the scan direction (module docstring) + a friction model.

    ``masses``, ``dampings``, ``stiffnesses``: per oscillator [kg, N s/m, N/m] (the last one may
    be the residual pseudo-oscillator, ``labels`` say which); ``k_static`` [N/m] the static
    stiffness of the chain (the lateral-force signal's calibration); ``V`` [m/s] scan speed."""

    masses: np.ndarray
    dampings: np.ndarray
    stiffnesses: np.ndarray
    friction: Any
    V: float
    labels: list[str] = field(default_factory=list)
    probe: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.masses = np.asarray(self.masses, dtype=float)
        self.dampings = np.asarray(self.dampings, dtype=float)
        self.stiffnesses = np.asarray(self.stiffnesses, dtype=float)
        n = self.masses.size
        if n < 1 or self.dampings.size != n or self.stiffnesses.size != n:
            raise ParameterError("ModalFFM needs the same number (>= 1) of masses, dampings and stiffnesses")
        if not (np.all(self.masses > 0) and np.all(self.stiffnesses > 0) and np.all(self.dampings >= 0)):
            raise ParameterError("modal masses and stiffnesses must be positive, dampings >= 0")
        if not (math.isfinite(self.V) and self.V > 0):
            raise ParameterError(f"scan speed must be positive, got {self.V}")

    @property
    def k_static(self) -> float:
        return float(1.0 / np.sum(1.0 / self.stiffnesses))

    @classmethod
    def from_probe(cls, probe: ReducedProbe, friction: Any, V: float, n_modes: int | None = None,
                   direction: str = "scan", residual: bool = True) -> "ModalFFM":
        """The N-mode chain of ``probe`` along ``direction``: the ``n_modes`` modes with the
        largest participation (+ the residual pseudo-oscillator at ``probe.validity_hz``).
        ``n_modes=None``: the one-mode model :meth:`ReducedProbe.lumped` (static stiffness,
        dominant mode's mass and damping), which is what the FFM scheme uses by default."""
        if n_modes is None:
            o = probe.lumped(direction)
            return cls([o.mass], [o.damping], [o.stiffness], friction, V, labels=[f"mode {o.mode} (static k)"],
                       probe=probe.summary())
        osc, r = probe.oscillators(direction, n_modes)
        if len(osc) < n_modes:
            raise ParameterError(f"the probe has only {len(osc)} modes along {direction}; reduce it with more modes")
        m = [o.mass for o in osc]
        c = [o.damping for o in osc]
        k = [o.stiffness for o in osc]
        labels = [f"mode {o.mode} ({o.family})" for o in osc]
        if residual and r > 0:
            if probe.validity_hz is None:
                raise ParameterError("a residual pseudo-mode needs the probe's validity limit")
            kr = 1.0 / r
            wr = 2.0 * math.pi * probe.validity_hz
            mr = kr / wr**2
            m.append(mr)
            k.append(kr)
            c.append(2.0 * math.sqrt(kr * mr))
            labels.append("static residual")
        return cls(m, c, k, friction, V, labels=labels, probe=probe.summary())


@dataclass
class ModalScan:
    """A modal line scan: time, base, tip position/velocity, bristle state, the lateral-force
    signal ``k_s (V t - x)``, the friction force and the modal deflections ``u`` (n, steps)."""

    t: np.ndarray
    base: np.ndarray
    x: np.ndarray
    v: np.ndarray
    z: np.ndarray
    lateral_force: np.ndarray
    friction: np.ndarray
    u: np.ndarray
    n_steps: int
    n_rejected: int
    setup: dict


def line_scan(ffm: ModalFFM, length: float, rtol: float = 1e-5, atol_rel: float = 1e-7,
              max_steps: int = 5_000_000, start: str = "rest") -> ModalScan:
    """Integrate a line scan of ``length`` [m]: deflections and the bristle start at zero.

    ``start="rest"``: the tip starts at rest while the base starts moving (the convention of
    :func:`probedyn.schemes.ffm.line_scan`, section 2.1.5.1: zero initial velocities), the
    deflection rate ``-V`` shared among the oscillators as their static compliances (for one
    oscillator: ``w' = -V``); ``"moving"``: the tip moves with the base (no starting transient)."""
    if start not in ("rest", "moving"):
        raise ParameterError(f"start must be 'rest' or 'moving', got {start!r}")
    if not (math.isfinite(length) and length > 0):
        raise ParameterError(f"scan length must be positive, got {length!r}")
    fm = ffm.friction
    n = ffm.masses.size
    V = float(ffm.V)
    T = length / V
    Fscale, zscale = fm.scales() if hasattr(fm, "scales") else _scales(fm)
    atol = np.empty(2 * n + 1)
    for i in range(n):
        atol[i] = atol_rel * Fscale / ffm.stiffnesses[i]
        atol[n + i] = atol_rel * V
    atol[2 * n] = atol_rel * zscale
    w_max = float(np.max(np.sqrt(ffm.stiffnesses / ffm.masses)))
    h0 = 1e-3 / w_max
    comp = 1.0 / ffm.stiffnesses
    share = comp / comp.sum()
    # rate states s_i = u_i' + V share_i: zero for the tip at rest ("rest"), V share_i for the tip
    # moving with the base ("moving")
    y0 = np.zeros(2 * n + 1)
    if start == "moving":
        y0[n:2 * n] = V * share
    ctx = (fm.pack(), ffm.masses, ffm.dampings, ffm.stiffnesses, share, V)
    ts, ys, Fr, nst, nrej = ros23(_system, fm.kernel, ctx, T, y0, rtol, atol, h0, T / 50.0, int(max_steps))
    if nst < 0:
        raise SolverError(f"modal FFM line scan: more than {max_steps} steps (shorten the scan or loosen rtol)")
    u = ys[:, :n].T
    w = u.sum(axis=0)
    return ModalScan(t=ts, base=V * ts, x=V * ts + w, v=ys[:, n:2 * n].sum(axis=1), z=ys[:, 2 * n],
                     lateral_force=-ffm.k_static * w, friction=Fr, u=u, n_steps=int(nst), n_rejected=int(nrej),
                     setup=dict(labels=ffm.labels, masses=ffm.masses, dampings=ffm.dampings,
                                stiffnesses=ffm.stiffnesses, V=V, length=length, model=getattr(fm, "key", fm.name),
                                friction=dict(fm.values), rtol=rtol, atol_rel=atol_rel, probe=ffm.probe,
                                start=start))


def _scales(fm: Any) -> tuple[float, float]:
    """Force and state scales of a friction model without ``scales()`` (older interface)."""
    v = fm.values
    if "F_s" in v:
        return v["F_s"], v["F_s"] / v["sigma0"]
    return 2 * math.pi * v["U0"] / v["a"], 1.0


def modal_participation(probe: ReducedProbe, direction: str = "scan") -> list[dict[str, Any]]:
    """Per retained mode along ``direction``: frequency, participation and the velocity ratio
    ``(p_i omega_i) / (p_1 omega_1)`` of its response to a step of the tip force (a mode's
    velocity amplitude after a force step dF is ``dF phi_i^2 / omega_i``)."""
    osc = probe.direction_modes(direction)
    if not osc:
        return []
    dom = max(osc, key=lambda o: o.participation)
    ref = dom.participation * dom.frequency_hz
    return [dict(mode=o.mode, family=o.family, frequency_hz=o.frequency_hz, participation=o.participation,
                 step_velocity_ratio=o.participation * o.frequency_hz / ref) for o in osc]


__all__ = ["ModalFFM", "ModalScan", "line_scan", "modal_participation"]
