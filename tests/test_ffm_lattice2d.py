"""The FFM scan of a tip held by two lateral springs over a square lattice at an angle
(:mod:`probedyn.schemes.ffm_lattice2d`), against its limits: the decoupled 1D scans of an isotropic lever, the
1D scan at theta = 0, and the quasi-static branch found by minimising the energy independently."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from probedyn.core.errors import ParameterError
from probedyn.schemes.ffm import FFM, line_scan_path
from probedyn.schemes.ffm_lattice2d import lattice2d_path

K, M, A, ETA = 1.5, 3.8e-12, 4e-10, 4.0
U0 = ETA * K * A * A / (4 * math.pi**2)
C = math.sqrt(M * K)  # Q = 1
V = 4e-8
TURNS = [-2 * A, 6 * A, 0.0]
HMAX = A / 48 / V
TIGHT = dict(rtol=1e-7, atol_rel=1e-7)


def _one_d(w: float, phase: float, x0: float):
    """The 1D FFM scan (PT substrate) of one lattice axis: support speed V w, registry ``phase``."""
    ffm = FFM.from_preset("mica", "pt", {"U0": U0, "a": A, "gamma": 0.0, "k_x": K, "m_x": M, "c_x": C})
    return line_scan_path(ffm, [t * w - phase for t in TURNS], speed=V * w, y0=(x0, 0.0, 0.0), hmax=HMAX,
                          atol_v=1e-7 * V * w, **TIGHT)


def test_an_isotropic_lever_decouples_the_lattice_axes_into_two_1d_scans():
    """k_y = k_x, c_y = c_x: the separable lattice's axes are two 1D FFM scans at V cos(theta) and V sin(theta);
    the force along the scan is cos(theta) F_u + sin(theta) F_v. Two integrations of the same physics agree to
    their tolerance (rtol 1e-7: within 1e-4 of the peak force, slips included)."""
    th, pu, pv = math.radians(15.0), 0.13 * A, 0.37 * A
    r = lattice2d_path(U0=U0, a=A, theta=th, k_x=K, k_y=K, m=M, c_x=C, c_y=C, turns=TURNS, speed=V, phases=(pu, pv),
                       hmax=HMAX, atol_v=1e-7 * V, **TIGHT)
    ru = _one_d(math.cos(th), pu, TURNS[0] * math.cos(th) - pu)
    rv = _one_d(math.sin(th), pv, TURNS[0] * math.sin(th) - pv)
    t = np.linspace(0.0, r.t[-1], 4000)
    F2 = np.interp(t, r.t, r.lateral_force)
    F1 = math.cos(th) * np.interp(t, ru.t, ru.lateral_force) + math.sin(th) * np.interp(t, rv.t, rv.lateral_force)
    assert np.max(np.abs(F2 - F1)) < 1e-4 * np.max(np.abs(F1))


@pytest.mark.parametrize("ky_ratio", [0.5, 15.0])
def test_along_the_rows_the_force_is_the_1d_scan_whatever_the_stiffness_across(ky_ratio):
    """theta = 0: the force along the scan depends on the tip's position along it only; the transverse
    stiffness holds the tip in its row and does not enter."""
    r = lattice2d_path(U0=U0, a=A, theta=0.0, k_x=K, k_y=ky_ratio * K, m=M, c_x=C, c_y=C * math.sqrt(ky_ratio),
                       turns=TURNS, speed=V, phases=(0.21 * A, 0.4 * A), hmax=HMAX, atol_v=1e-7 * V, **TIGHT)
    r1 = _one_d(1.0, 0.21 * A, TURNS[0] - 0.21 * A)
    t = np.linspace(0.0, r.t[-1], 4000)
    F1 = np.interp(t, r1.t, r1.lateral_force)
    assert np.max(np.abs(np.interp(t, r.t, r.lateral_force) - F1)) < 1e-4 * np.max(np.abs(F1))


def test_a_slow_scan_follows_the_minimum_of_the_energy_on_an_anisotropic_lever():
    """k_y = 15 k_x at 15 deg, a slow scan: between slips the tip sits at a local minimum of
    E = -U0[cos(q u) + cos(q v)] + k_x (X - s)^2 / 2 + k_y n^2 / 2. The minimum is found independently
    (scipy BFGS on E from the path's tip position, written from the energy, not the integrator's forces),
    and the recorded force k_x (X - s) agrees with the path's on every stick sample (the tip lags the
    quasi-static branch by c V / k ~ 1e-6 of a period at 4 nm/s: agreement within 1e-3 of the peak force).
    Slip samples (the tip moving faster than 10 V) are left out."""
    th, ky, pu, pv = math.radians(15.0), 15.0 * K, 0.1 * A, 0.3 * A
    v_slow = 4e-9
    r = lattice2d_path(U0=U0, a=A, theta=th, k_x=K, k_y=ky, m=M, c_x=C, c_y=C * math.sqrt(15.0), turns=[-2 * A, 4 * A],
                       speed=v_slow, phases=(pu, pv), hmax=A / 200 / v_slow, atol_v=100 * v_slow, rtol=1e-6,
                       atol_rel=1e-6)
    q = 2 * math.pi / A
    ct, st = math.cos(th), math.sin(th)

    def energy(p, X):
        s, n = p
        u, v = ct * s - st * n - pu, st * s + ct * n - pv
        return (-U0 * (math.cos(q * u) + math.cos(q * v)) + 0.5 * K * (X - s) ** 2 + 0.5 * ky * n * n) / (U0 * 1e-4)

    stick = np.nonzero((np.abs(r.v) < 10 * v_slow) & (r.base > 0))[0][::25]
    assert len(stick) > 50
    F0 = q * U0
    worst = 0.0
    for i in stick:
        res = minimize(energy, [r.x[i], r.z[i]], args=(r.base[i],), method="BFGS",
                       options={"gtol": 1e-10})
        F_qs = K * (r.base[i] - res.x[0])
        worst = max(worst, abs(F_qs - r.lateral_force[i]))
        assert abs(res.x[0] - r.x[i]) < 0.05 * A  # the same minimum, not a neighbouring one
    assert worst < 1e-3 * F0, worst
    # the slips exist: within a hundredth of a period of support travel the force drops by a sizeable fraction
    # of the corrugation force
    grid = np.arange(0.0, 4 * A, A / 100)
    assert np.max(-np.diff(np.interp(grid, r.base, r.lateral_force))) > 0.2 * F0


def test_nonsense_parameters_are_refused():
    with pytest.raises(ParameterError):
        lattice2d_path(U0=U0, a=A, theta=0.1, k_x=K, k_y=-1.0, m=M, c_x=C, c_y=C, turns=TURNS, speed=V)
    with pytest.raises(ParameterError):
        lattice2d_path(U0=U0, a=A, theta=0.1, k_x=K, k_y=K, m=M, c_x=C, c_y=C, turns=[0.0], speed=V)
