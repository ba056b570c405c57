"""Nano-pushing (section 4.1.1–4.1.2): physics checks of schemes/pushing.py.

Each push simulation takes 1–3 s; results are cached per module so the suite stays ~30 s.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes import pushing as P


@lru_cache(maxsize=None)
def run(sub: str, **ov):
    return P.push(sub, dict(ov))


# ---------------------------------------------------------------- model building blocks
@pytest.mark.parametrize("angle,dim", [(0.0, 1), (15.0, 2)])
def test_jacobian_matches_finite_differences(angle, dim):
    m = P.make_model("mica", {"angle": angle}, dim=dim)
    # a state in contact (gap < zeta0), sliding, with bristle and memory loaded
    y = np.array([1e-10, 2e-11, 1e-4, 2e-5, 3e-10 - 0.8e-9, 1e-11, 3e-5, -1e-5, 1e-14, 2e-14, 4e-6])
    J = m.jac(1e-5, y)
    Jn = np.zeros_like(J)
    for j in range(y.size):
        h = 1e-6 * max(abs(y[j]), 1e-16)
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        Jn[:, j] = (m.rhs(1e-5, yp) - m.rhs(1e-5, ym)) / (2 * h)
    scale = np.abs(Jn).max(axis=1, keepdims=True) + 1e-300
    # central differences with h = 1e-6 relative: truncation ~h^2, rounding ~1e-16/h = 1e-10
    assert np.max(np.abs(J - Jn) / scale) < 1e-5


def test_hexagonal_potential_reduces_to_the_1d_sinusoid_along_the_axis():
    """Along the lattice axis U = -U0 (1 + 2 cos 2 pi x/a): force (F_s - F_c) sin(2 pi x / a), no y force,
    so the 1D model is the 2D model at angle 0 restricted to y = 0 (exact, by mirror symmetry)."""
    m = P.make_model("hopg", {}, dim=2)
    a, dF = m.p["a"], m.p["F_s"] - m.p["F_c"]
    for x in np.linspace(0, 2 * a, 17):
        g, h = m.lattice_force(m.x0 + x, 0.0)
        assert g[0] == pytest.approx(dF * math.sin(2 * math.pi * x / a), abs=1e-12 * dF)
        assert abs(g[1]) < 1e-12 * dF
    # minima form a triangular lattice of spacing a: U equal at all six neighbours of the start site
    A = P.lattice_vectors(m)
    nb = np.column_stack([A[:, 0], A[:, 1], A[:, 1] - A[:, 0], -A[:, 0], -A[:, 1], A[:, 0] - A[:, 1]])
    U = m.potential(m.x0 + nb[0], nb[1])
    assert np.allclose(U, m.potential(m.x0, 0.0), atol=1e-12 * abs(U[0]))
    # ... and the curvature at a site is isotropic, 8 pi^2 U0 / a^2 (analytic)
    _, h = m.lattice_force(m.x0, 0.0)
    assert np.allclose(h, 8 * math.pi ** 2 * m.U0 / a ** 2 * np.eye(2), rtol=1e-12)


def test_dmt_contact_is_continuous_and_has_the_pull_off_of_eq_2_20():
    m = P.make_model("mica", {})
    z0, H = m.zeta0, m.p["H"]

    def force(s):
        return m.normal_contact(s)[0]

    assert force(z0 * (1 + 1e-12)) == pytest.approx(force(z0 * (1 - 1e-12)), rel=1e-9)
    assert force(z0) == pytest.approx(-H * m.R / (6 * z0 ** 2))
    assert -m.contact.pull_off_force() == pytest.approx(H * m.R / (6 * z0 ** 2))
    # stiffness = -dF/ds in both branches
    for s in (-1e-9, 0.5 * z0, 2 * z0):
        h = 1e-15
        assert m.normal_contact(s)[1] == pytest.approx(-(force(s + h) - force(s - h)) / (2 * h), rel=1e-5)


# ---------------------------------------------------------------- Fig 4.2: stairs with step = a
@pytest.mark.parametrize("sub", ["mica", "hopg"])
def test_stairs_step_equals_lattice_constant(sub):
    """Each slip carries the sample from the fold of one lattice well to the equivalent fold of the
    next: consecutive sticking points are one period apart. The only non-periodic contributions are
    the bristle creep (|v| regularised by v_eps = 1e-8 m/s: <= v_eps * a / V = 1.7 pm per period, 0.7 %
    of HOPG's a) and the 3V slip-onset threshold, which is crossed at the same phase every period.
    Hence 1 % on the mean and 3 % on every individual step."""
    res, r = run(sub)
    a = r["lattice_constant_m"]
    assert r["regime"] == "stick-slip"
    assert len(r["step_lengths_m"]) >= 10
    assert r["mean_step_m"] == pytest.approx(a, rel=0.01)
    assert np.allclose(r["step_lengths_m"], a, rtol=0.03)


@pytest.mark.parametrize("a", [3.5e-10, 8.0e-10])
def test_step_follows_the_lattice_not_the_friction_levels(a):
    """Mica friction levels with another lattice constant: the step follows a (1 %, as above), while
    the bristle model alone would slip by about (F_s - F_c)/k = 0.59 nm (departure 11), which
    differs from both a by more than 20 %."""
    res, r = run("mica", a=a)
    m = res.model
    assert abs((m.p["F_s"] - m.p["F_c"]) / m.k_series(m.p["F_c"]) / a - 1) > 0.2
    assert r["mean_step_m"] == pytest.approx(a, rel=0.01)


# ---------------------------------------------------------------- Fig 4.3: sliding at 150 um/s
@pytest.mark.parametrize("sub", ["mica", "hopg"])
def test_high_speed_sliding_at_kinetic_friction(sub):
    """At 150 um/s = 15 V_s the pinning factor is exp(-225) ~ 0: steady sliding with the friction equal
    to the bristle's saturated F_c plus the viscous F_v V (sigma1 dz/dt = 0 in steady sliding);
    1 % covers the tail of the transient in the averaging window."""
    res, r = run(sub, V=150e-6)
    assert r["regime"] == "sliding"
    assert r["friction_mean_N"] == pytest.approx(r["kinetic_expected_N"], rel=0.01)
    assert r["friction_std_N"] < 0.02 * r["kinetic_expected_N"]
    # the static value is reached first (pre-sliding, Fig 4.3-b). The pinning state starts healed
    # (w = 0) and obeys dw/dt = (|v| - w)/tau_p <= |v|/tau_p, so before the first slip
    # w <= l / tau_p = l V_s / a (l = path length of the sample) and the pinning factor is at least
    # exp(-(l/a)^2): the peak cannot fall below F_c + (F_s - F_c) exp(-(l/a)^2) (2 % for the tilt of
    # the corrugation by the push at the fold), and cannot exceed F_s (+1 % for F_v v, sigma1 dz/dt)
    pre = r["presliding"]
    bound = r["F_c_N"] + (r["F_s_N"] - r["F_c_N"]) * math.exp(-(pre["path_length_m"] / r["lattice_constant_m"]) ** 2)
    assert 0.98 * bound < pre["peak_friction_N"] < 1.01 * r["F_s_N"]


# ---------------------------------------------------------------- Fig 4.4: pre-sliding
def test_presliding_displacement_is_the_prandtl_tomlinson_fold():
    """Before the first slip the sample creeps up its well to the fold of the tilted corrugation,
    x_fold = a/4 + a/(2 pi) asin(1/eta), eta = 2 pi (F_s - F_c)/(a k), k = tip spring in series
    with the DMT contact at the load F_s. 6 %: the slip onset (speed > 3V) is detected slightly
    before the fold, where the creep accelerates, and k varies by a few % along the pre-slide."""
    for a in (3.5e-10, 7.0e-10):
        m = P.make_model("mica", {"a": a})
        travel = 3e-9 + a  # well past the first slip (observed at ~1.5 nm for mica)
        r = P.analyse(P.simulate(m, travel))
        eta = 2 * math.pi * (m.p["F_s"] - m.p["F_c"]) / (a * m.k_series(m.p["F_s"]))
        x_fold = a / 4 + a / (2 * math.pi) * math.asin(1 / eta)
        assert r["presliding"]["sample_displacement_m"] == pytest.approx(x_fold, rel=0.06)


# ---------------------------------------------------------------- transition speed
@pytest.mark.parametrize("sub", ["mica", "hopg"])
def test_transition_brackets_the_quasistatic_fold_criterion(sub):
    """Sliding over the corrugation is quasi-statically stable when eta(V) = eta0 exp(-(V/V_s)^2) < 1
    (the pinning state w tracks the mean speed V). Healing between slips only strengthens the
    pinning, so stick-slip must persist at 0.9 V_qs; at 1.3 V_qs eta(V) < 0.4 and the sliding
    sample (speed >= V/(1+eta)) keeps w high enough that it cannot re-pin."""
    m = P.make_model(sub, {})
    p = m.p
    eta0 = 2 * math.pi * (p["F_s"] - p["F_c"]) / (p["a"] * m.k_series(p["F_c"]))
    Vqs = p["V_s"] * math.sqrt(math.log(eta0))
    assert run(sub, V=0.9 * Vqs)[1]["regime"] == "stick-slip"
    assert run(sub, V=1.3 * Vqs)[1]["regime"] == "sliding"


# ---------------------------------------------------------------- Fig 4.5: 2D zigzag
def test_2d_zigzag_follows_lattice_directions_on_average_the_push():
    res, r = run("mica", angle=15.0)
    hops = [tuple(h) for h in r["site_hops"]]
    assert r["regime"] == "stick-slip" and len(hops) >= 8
    # individual hops join lattice sites: nearest neighbours (-15 deg and +45 deg in the probe frame)
    nn = {(1, 0), (0, 1), (-1, 1), (-1, 0), (0, -1), (1, -1)}
    assert sum(h in nn for h in hops) >= 0.8 * len(hops)
    # zigzag: both the axis (1,0) and the 60-degree direction (0,1) occur
    assert hops.count((1, 0)) >= 2 and hops.count((0, 1)) >= 1
    # the mean direction follows the push: the walk corrects its lateral error one hop at a time,
    # so it stays within one lateral hop component (a sin 60) of the push line
    L = r["advance_per_slip_m"] * len(hops)
    tol = math.degrees(math.atan(r["lattice_constant_m"] * math.sin(math.pi / 3) / L))
    assert abs(r["mean_direction_deg"]) < tol


# ---------------------------------------------------------------- Fig 4.6: viscous term
def test_viscous_term_turns_the_sawtooth_square_wave_like():
    """An overdamped slip lasts a few F_v / k: 1e-7/3 = 30 ns in UHV (<1 % of the 173 us period at
    3 um/s) but 5e-5/3 = 17 us with capillary damping (>5 % of the period): the friction then sits
    on a plateau during slips instead of dropping instantly."""
    fr = [run("mica", F_v=Fv)[1]["slip_time_fraction"] for Fv in (1e-7, 2e-5, 5e-5)]
    assert fr[0] < 0.01
    assert fr[0] < fr[1] < fr[2]
    assert fr[2] > 0.05


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("ov", [{"R_s": -1e-9}, {"m_s": -1e-17}, {"k_tx": 0}, {"E_s": -1},
                                {"V": -1e-6}, {"F_s": 1e-10, "F_c": 2e-10}, {"nope": 1}])
def test_non_physical_parameters_raise(ov):
    with pytest.raises(ParameterError):
        P.make_model("mica", ov)


def test_unknown_substrate_raises():
    with pytest.raises(ParameterError, match="unknown substrate"):
        P.make_model("gold")


def test_probe_object_with_k_and_m():
    class Lumped:  # LumpedModel-like
        stiffness = 12.0
        mass = 3e-18
        damping = 5e-9

    m = P.make_model("hopg", probe=Lumped())
    assert (m.p["k_tx"], m.p["m_tx"], m.p["c_t"], m.p["k_ty"]) == (12.0, 3e-18, 5e-9, 4.0)
    m = P.make_model("hopg", probe={"k": 20.0, "m": 1e-18})
    assert m.p["k_tx"] == 20.0
    with pytest.raises(ParameterError):
        P.make_model("hopg", probe={"k": -20.0, "m": 1e-18})


def test_cli_push_json(tmp_path, capsys):
    from probedyn.cli import main

    capsys.readouterr()
    assert main(["simulate", "push", "--substrate", "hopg", "--json", "--out", str(tmp_path)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["regime"] == "stick-slip"
    assert d["mean_step_m"] == pytest.approx(d["lattice_constant_m"], rel=0.01)
    assert (tmp_path / "push.png").exists() and (tmp_path / "push.json").exists()
    assert main(["simulate", "push", "--substrate", "gold"]) == 2
    assert "unknown substrate" in capsys.readouterr().err
    assert main(["simulate", "push", "--set", "R_s=-1e-9"]) == 2


def test_dmt_closed_form_agrees_with_the_contact_registry_curve_solve():
    """The model's contact is the registry's DMT evaluated by its closed form (``DMT.point``: force,
    stiffness, contact radius and its derivative); the same model's general path
    (``ContactModel.point``) solves Maugis' parametrised curve by Newton iteration: same eq 2.20,
    independent code paths; agreement to 1e-6 relative (the Newton tolerance is near machine
    precision). The Mindlin patch stiffness of the model is ``2 E* a`` (Hertz)."""
    from probedyn.schemes.contact import ContactModel

    m = P.make_model("mica", {})
    c, z0 = m.contact, m.zeta0
    for s in np.array([-2.0, -1.0, -0.3, 0.0, 0.5, 0.99, 1.01, 1.5, 3.0]) * z0:
        delta = z0 - s
        F, k, a, da = c.point(delta)
        Fg, kg, ag, dag = ContactModel.point(c, delta)
        assert F == pytest.approx(Fg, rel=1e-6)
        assert m.normal_contact(s)[0] == F
        if abs(delta) > 1e-3 * z0:
            assert k == pytest.approx(kg, rel=1e-6)
            assert a == pytest.approx(ag, rel=1e-6, abs=1e-6 * z0)
            assert da == pytest.approx(dag, rel=1e-6)
        if delta > 0:
            assert m.normal_contact(s)[2] == pytest.approx(2 * m.E_star * math.sqrt(m.R * delta), rel=1e-12)


def test_lattice_force_agrees_with_the_friction_registry_hexagonal_potential():
    """The pinning potential is the registry's hexagonal Prandtl–Tomlinson potential
    U = -(2 U0'/3) sum cos(b_i.r) with U0' = 3 U0 / 2, rotated by the push angle: the gradients of the
    two implementations agree to rounding (1e-9 relative) over a patch of two lattice cells."""
    from probedyn.schemes.friction.prandtl_tomlinson import _grad_u

    for angle in (0.0, 20.0):
        m = P.make_model("mica", {"angle": angle}, dim=2)
        a = m.p["a"]
        g = math.radians(angle)
        rot = np.array([[math.cos(g), -math.sin(g)], [math.sin(g), math.cos(g)]])  # lattice -> probe
        rng = np.random.default_rng(1)
        for rl in rng.uniform(-2 * a, 2 * a, size=(20, 2)):
            gx, gy = _grad_u(2, 1.5 * m.U0, a, rl[0], rl[1])
            rp = rot.T @ rl  # probe-frame position of the lattice-frame point (lattice rotated by -angle)
            mine, _ = m.lattice_force(m.x0 + rp[0], rp[1])
            assert np.allclose(rot.T @ np.array([gx, gy]), mine, rtol=1e-9, atol=1e-9 * np.abs(mine).max())


def test_bristle_part_is_the_registry_lugre_without_stribeck():
    """In 1D the Coulomb part of the substrate friction is the registry's LuGre kernel with
    F_s = F_c (no Stribeck term: the excess static friction is the lattice pinning) and F_v = 0:
    force, bristle rate and their derivatives agree up to the |v| regularisation
    sqrt(v^2 + v_eps^2) = |v| (1 + (v_eps/v)^2 / 2): relative tolerance (v_eps/v)^2."""
    from probedyn.schemes.friction.lugre import lugre_kernel

    m = P.make_model("mica", {}, dim=1)
    p = m.p
    kp = np.array([p["sigma0"], m.sigma1, p["F_c"], p["F_c"], p["V_s"], 0.0])
    far = 1e3 * m.x0  # any position: the pinning is switched off through the memory speed w
    for v, z in [(1e-4, 3e-14), (-2e-5, -1e-14), (3e-6, 5e-14)]:
        y = np.zeros(P.NS)
        y[4], y[6], y[8], y[10] = far, v, z, 1e3 * p["V_s"]  # memory speed >> V_s: pinning off
        tol = (p["v_eps"] / v) ** 2 + 1e-12
        f = m.forces(0.0, y)
        F, zd, _, dF_dv, dF_dz, _, dzd_dv, dzd_dz = lugre_kernel(kp, 0.0, v, z)
        assert f["Fsub"][0] - p["F_v"] * v == pytest.approx(F, rel=tol, abs=tol * p["F_c"])
        assert f["zdot"][0] == pytest.approx(zd, rel=tol, abs=tol * abs(v))
        J = m.jac(0.0, y)
        assert J[8, 8] == pytest.approx(dzd_dz, rel=tol)
        assert J[8, 6] == pytest.approx(dzd_dv, rel=tol, abs=tol)


def test_2d_model_at_zero_angle_reproduces_the_1d_model():
    """By mirror symmetry of the hexagonal potential about its axis, the 2D model at angle 0 keeps
    y = 0 (to rounding) and reproduces the 1D run: same sticking points to the integrator's
    tolerance (rtol 1e-6 on positions of ~nm: 1e-3 of a covers the step-size differences)."""
    r1 = run("hopg")[1]
    res2, r2 = P.push("hopg", {}, dim=2)
    assert np.max(np.abs(res2.y[[1, 5]])) < 1e-6 * r1["lattice_constant_m"]
    assert r2["mean_step_m"] == pytest.approx(r1["mean_step_m"], rel=1e-3)
    assert len(r2["step_lengths_m"]) == len(r1["step_lengths_m"])
