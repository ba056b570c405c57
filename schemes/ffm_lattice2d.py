"""FFM line scan of a tip held by two lateral springs over a square lattice at an angle.

The lever holds the tip with the stiffness ``k_x`` along the scan (the torsion the lateral-force
channel reads) and ``k_y`` across it (the lever's bending through the tip height, or its torsion when
the scan runs along the lever axis). The two differ: for a rectangular lever scanned across its
axis, ``k_y / k_x ~ 0.65`` from beam theory (torsion ``G w t^3 / (3 L h^2)`` against bending
``E w t^3 / (12 L h^2)``), and the contact and the tip add their own compliances in series. The
substrate is the separable square lattice of the 2D PT model
(:mod:`probedyn.schemes.friction.prandtl_tomlinson`), ``U = -U0 [cos(q u) + cos(q v)]``, ``q = 2 pi / a``,
whose rows (the ``u`` axis) make the angle ``theta`` with the scan. In the scan frame (``s`` along the
scan, ``n`` across it; the support at ``(X(t), 0)``)::

    m s'' = c_x (X' - s') + k_x (X - s) + F_s,     m n'' = -c_y n' - k_y n + F_n
    u = cos(theta) s - sin(theta) n - phi_u,       v = sin(theta) s + cos(theta) n - phi_v
    (F_s, F_n) = R(theta)^T (-U0 q sin(q u), -U0 q sin(q v))

which is the 1D FFM equation (2.13), (2.15) of the source with the PT substrate, written for two lateral
degrees of freedom. The force the lateral channel records is ``k_x (X - s)``. ``phi_u``, ``phi_v`` are the
lattice's registry at the support coordinate 0. A viscous tip-substrate friction ``gamma`` (the PT model's, on
the tip's velocity) may be added to both equations.

Limits (tested): for ``k_y = k_x`` and ``c_y = c_x`` the lattice axes decouple into two 1D FFM scans at
the speeds ``V cos(theta)`` and ``V sin(theta)``, the recorded force being ``cos(theta) F_u + sin(theta) F_v``
(the isotropic model of ``diagnose``'s lattice misalignment); for ``theta = 0`` the force along the scan is
the 1D scan's whatever ``k_y``; at a slow scan the tip sits on the quasi-static branch, a minimum of
``U + k_x (X - s)^2 / 2 + k_y n^2 / 2``.

Integrator: the numba Rosenbrock W-method of order 2(3) of :mod:`probedyn.schemes.rosenbrock` (Shampine &
Reichelt 1997) with the analytic Jacobian, four states ``(s, n, s', n')``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from probedyn.core.errors import ParameterError
from probedyn.schemes.ffm import ScanResult, along_turns
from probedyn.schemes.rosenbrock import ros23, stable_identity


@njit(cache=True)
def _system(kern, ctx, t, y, f, J, Tt, want_j):
    """The two-spring PT tip, ``y = (s, n, s', n')``, ``ctx = (p, V, X0)`` with
    ``p = (U0, q, cos, sin, phi_u, phi_v, m, c_x, c_y, k_x, k_y, gamma)`` (``kern`` unused: the substrate is
    written out). Returns the potential's force along the scan."""
    p, V, X0 = ctx
    U0, q, ct, st, pu, pv, m, cx, cy, kx, ky = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10]
    g = p[11]
    s, n, vs, vn = y[0], y[1], y[2], y[3]
    u = ct * s - st * n - pu
    v = st * s + ct * n - pv
    Fu = -U0 * q * math.sin(q * u)
    Fv = -U0 * q * math.sin(q * v)
    Fs = ct * Fu + st * Fv
    Fn = -st * Fu + ct * Fv
    f[0] = vs
    f[1] = vn
    f[2] = (cx * (V - vs) - g * vs + kx * (X0 + V * t - s) + Fs) / m
    f[3] = (-(cy + g) * vn - ky * n + Fn) / m
    if want_j:
        gu = -U0 * q * q * math.cos(q * u)
        gv = -U0 * q * q * math.cos(q * v)
        dss = ct * ct * gu + st * st * gv
        dsn = st * ct * (gv - gu)
        dnn = st * st * gu + ct * ct * gv
        for i in range(4):
            for j in range(4):
                J[i, j] = 0.0
        J[0, 2] = 1.0
        J[1, 3] = 1.0
        J[2, 0] = (-kx + dss) / m
        J[2, 1] = dsn / m
        J[2, 2] = -(cx + g) / m
        J[3, 0] = dsn / m
        J[3, 1] = (-ky + dnn) / m
        J[3, 3] = -(cy + g) / m
        Tt[0] = 0.0
        Tt[1] = 0.0
        Tt[2] = kx * V / m
        Tt[3] = 0.0
    return Fs


stable_identity(_system, "ffm_lattice2d")  # the on-disk cache finds ros23's specialisation again (schemes/rosenbrock.py)


def lattice2d_path(*, U0: float, a: float, theta: float, k_x: float, k_y: float, m: float, c_x: float,
                   c_y: float, turns, speed: float, phases=(0.0, 0.0), gamma: float = 0.0, y0=None, hmax: float | None = None,
                   rtol: float = 1e-5, atol_rel: float = 1e-5, atol_v: float | None = None,
                   max_steps: int = 2_000_000) -> ScanResult:
    """The scan (module docstring) along the support path ``turns`` (positions along the scan visited in
    order at ``speed``), from the state ``y0 = (s, n, s', n')`` (default: at rest at the first turn, on the
    scan line). ``theta`` [rad]; ``phases`` = (phi_u, phi_v) [m]; ``gamma`` [N s/m] the viscous tip-substrate friction. Returns a :class:`ScanResult` with the
    tip's transverse position in ``z``; ``lateral_force`` is ``k_x (X - s)``, ``friction`` the substrate's
    force along the scan against the tip (``-F_s``). Tolerances as :func:`schemes.ffm.line_scan_path`:
    ``atol_rel`` of the corrugation force over the smaller stiffness for positions, ``atol_v`` for velocities
    (default ``atol_rel`` times the speed)."""
    for nm, val in (("U0", U0), ("a", a), ("k_x", k_x), ("k_y", k_y), ("m", m), ("speed", speed)):
        if not (math.isfinite(val) and val > 0):
            raise ParameterError(f"lattice2d_path: '{nm}' must be positive, got {val!r}")
    if not (c_x >= 0 and c_y >= 0 and gamma >= 0 and math.isfinite(theta)):
        raise ParameterError("lattice2d_path: damping must be >= 0 and theta finite")
    turns = [float(x) for x in turns]
    if len(turns) < 2:
        raise ParameterError("lattice2d_path needs at least two turning points")
    q = 2 * math.pi / a
    p = np.array([U0, q, math.cos(theta), math.sin(theta), float(phases[0]), float(phases[1]), m, c_x, c_y, k_x,
                  k_y, gamma])
    F0 = q * U0
    kmin = min(k_x, k_y)
    av = atol_rel * speed if atol_v is None else float(atol_v)
    atol = np.array([atol_rel * F0 / kmin, atol_rel * F0 / kmin, av, av])
    y = np.array([turns[0], 0.0, 0.0, 0.0]) if y0 is None else np.asarray(y0, float).copy()
    h0 = 1e-3 * math.sqrt(m / max(k_x, k_y))

    def segment(V, T, y, hm, Xa):
        ts, ys, _, nst, nrej = ros23(_system, None, (p, float(V), float(Xa)), float(T), y, rtol, atol, h0, float(hm),
                                     int(max_steps))
        return ts, ys, None, nst, nrej

    t, base, ys, _, steps, rej = along_turns(turns, speed, y, hmax, segment, "2D lattice scan", max_steps)
    s, n = ys[:, 0], ys[:, 1]
    u = math.cos(theta) * s - math.sin(theta) * n - phases[0]
    v = math.sin(theta) * s + math.cos(theta) * n - phases[1]
    Fs = -F0 * (math.cos(theta) * np.sin(q * u) + math.sin(theta) * np.sin(q * v)) - gamma * ys[:, 2]
    return ScanResult(t=t, base=base, x=s, v=ys[:, 2], z=n, lateral_force=k_x * (base - s), friction=-Fs,
                      n_steps=steps, n_rejected=rej,
                      setup=dict(model="pt-square-2d", U0=U0, a=a, theta=theta, k_x=k_x, k_y=k_y, m=m, c_x=c_x,
                                 c_y=c_y, gamma=gamma, phases=[float(phases[0]), float(phases[1])], turns=turns,
                                 speed=speed, rtol=rtol, atol_rel=atol_rel))
