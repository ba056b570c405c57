"""Independent reference solvers for the FFM tests (moved out of ``schemes/coupling.py``: they
are test references, not library code).

* :func:`reference_scan`: the 1D FFM line scan (eqs 2.7-2.9, 2.13, 2.15 with V_y = 0) with
  scipy's BDF and its own analytic Jacobian, against the project's numba Rosenbrock integrator;
* :func:`pt_scan`: the 1D Prandtl–Tomlinson scan with scipy's BDF, against the FFM model with
  the registry's ``pt`` friction model.

Parameters: Table 2.1 (mica) and the mica lattice of Table 4.2 from :mod:`probedyn.core.presets`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.presets import preset

T21 = preset("table-2.1")

#: Table 2.1 (mica), x direction, in the names of the equations; F_nu in N s/m (departure 10)
MICA_X = dict(m=T21["m_x"], c=T21["c_x"], k=T21["k_x"], sigma0=T21["sigma0_x"], Vs=T21["V_s"], Fnu=T21["F_v_x"],
              Fs=T21["F_s_x"], Fc=T21["F_c_x"])

#: mica lattice constant (Table 4.2)
MICA_LATTICE = preset("table-4.2-mica")["a"]


def reference_scan(length: float, speed: float = T21["V"], scale: float = 1.0, n_out: int = 4000,
                   params: dict | None = None, rtol: float = 1e-7) -> dict[str, np.ndarray]:
    """1D FFM line scan with the source's generalised-bristle friction, written out here as an
    independent reference for the project's FFM model (scipy BDF instead of the numba Rosenbrock).

    States ``x`` (tip), ``v`` (tip velocity), ``z`` (bristle deflection); base at ``V t``::

        m x'' = c (V - x') + k (V t - x) - F          (2.13) with (2.15)
        F     = sigma0 z + F_nu x'                     (2.7)
        z'    = max(x', 0) - |x'| z / g(x')            (2.8) with V_y = 0: max(V_x, V_y) = max(x', 0)
        g     = [F_c + (F_s - F_c) exp(-(x' / 2 V_s)^2)] / sigma0     (2.9)

    ``scale`` multiplies ``F_s`` and ``F_c`` (the adhesion coupling's friction scale). Stiff
    (sigma0 / m ~ 5e21 s^-2): BDF with the analytic Jacobian. Returns base position, time,
    tip position, the lateral spring force ``k (V t - x)`` (what the FFM measures) and ``F``.
    """
    p = dict(MICA_X)
    p.update(params or {})
    if scale <= 0 or not math.isfinite(scale):
        raise ParameterError(f"friction scale must be positive, got {scale}")
    m, c, k, s0, Vs, Fnu = p["m"], p["c"], p["k"], p["sigma0"], p["Vs"], p["Fnu"]
    Fs, Fc = p["Fs"] * scale, p["Fc"] * scale
    V = speed
    zs = Fs / s0  # bristle scale

    def g_of(v):
        u = v / (2 * Vs)
        e = math.exp(-u * u)
        g = (Fc + (Fs - Fc) * e) / s0
        dg = -(Fs - Fc) * e * u / (Vs * s0)
        return g, dg

    def rhs(t, y):
        x, v, z = y
        g, _ = g_of(v)
        F = s0 * z + Fnu * v
        return [v, (c * (V - v) + k * (V * t - x) - F) / m, max(v, 0.0) - abs(v) * z / g]

    def jac(t, y):
        x, v, z = y
        g, dg = g_of(v)
        sg = math.copysign(1.0, v) if v != 0 else 0.0
        return [[0.0, 1.0, 0.0],
                [-k / m, -(c + Fnu) / m, -s0 / m],
                [0.0, (1.0 if v > 0 else 0.0) - z * (sg / g - abs(v) * dg / (g * g)), -abs(v) / g]]

    T = length / V
    t_eval = np.linspace(0.0, T, n_out)
    sol = solve_ivp(rhs, (0.0, T), [0.0, 0.0, 0.0], method="BDF", jac=jac, t_eval=t_eval,
                    rtol=rtol, atol=[1e-6 * zs * s0 / k, 1e-6 * V, 1e-6 * zs])
    if not sol.success:
        raise SolverError(f"FFM reference scan failed: {sol.message}")
    x, v, z = sol.y
    return dict(base=V * sol.t, t=sol.t, x=x, spring_force=k * (V * sol.t - x),
                friction=s0 * z + Fnu * v, nfev=sol.nfev)


def pt_scan(eta: float, length: float, speed: float = T21["V"], a: float = MICA_LATTICE, k: float = T21["k_x"],
            m: float = T21["m_x"], zeta: float = 1.0, n_out: int = 6000, rtol: float = 1e-6) -> dict[str, np.ndarray]:
    """1D Prandtl–Tomlinson line scan (the standard atomic stick-slip model)::

        m x'' + gamma x' = k (V t - x) - (2 pi U0 / a) sin(2 pi x / a),   eta = 4 pi^2 U0 / (k a^2)

    with ``gamma = 2 zeta sqrt(m k (1 + eta))`` (``zeta = 1``: critically damped at the bottom
    of a well). Defaults: Table 2.1 ``k_x``, ``m_x``; mica lattice ``a`` (Table 4.2). Returns base
    position and the lateral spring force ``k (V t - x)``. BDF with the analytic Jacobian.
    """
    if not (eta > 0 and length > 0 and speed > 0 and a > 0 and k > 0 and m > 0 and zeta > 0):
        raise ParameterError("pt_scan needs positive eta, length, speed, a, k, m and zeta")
    U0 = eta * k * a * a / (4 * math.pi**2)
    q = 2 * math.pi / a
    F0 = q * U0
    gam = 2 * zeta * math.sqrt(m * k * (1 + eta))
    V = speed

    def rhs(t, y):
        x, v = y
        return [v, (k * (V * t - x) - F0 * math.sin(q * x) - gam * v) / m]

    def jac(t, y):
        return [[0.0, 1.0], [(-k - F0 * q * math.cos(q * y[0])) / m, -gam / m]]

    T = length / V
    te = np.linspace(0.0, T, n_out)
    sol = solve_ivp(rhs, (0.0, T), [0.0, 0.0], method="BDF", jac=jac, t_eval=te, rtol=rtol,
                    atol=[1e-6 * a, 1e-6 * a * math.sqrt(k / m)])
    if not sol.success:
        raise SolverError(f"Prandtl-Tomlinson scan failed: {sol.message}")
    return dict(base=V * sol.t, spring_force=k * (V * sol.t - sol.y[0]), x=sol.y[0])
