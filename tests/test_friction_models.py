"""Friction model registry: interface, analytic Jacobians, steady states, parameter checks."""

import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes.friction import get_friction_model, list_models, register
from probedyn.schemes.friction.bristle import bristle2d_eval

KEYS = ("F", "zdot", "dF_dx", "dF_dv", "dF_dz", "dzd_dx", "dzd_dv", "dzd_dz")


def test_registry_lists_models_and_rejects_unknown():
    assert {"bristle", "lugre", "pt"} <= set(list_models())
    assert get_friction_model("Prandtl-Tomlinson").name == "pt"
    with pytest.raises(ParameterError, match="unknown friction model"):
        get_friction_model("coulomb-ish")
    with pytest.raises(TypeError):
        register(int)


@pytest.mark.parametrize("name", ["bristle", "lugre", "pt"])
def test_analytic_jacobian_matches_central_differences(name):
    """Central differences are O(h^2) accurate; with h = 1e-6 of the variable's scale the
    truncation error is ~1e-12 relative, far below the 1e-5 tolerance (cancellation limits it)."""
    m = get_friction_model(name, **({"sigma1": 1e-8} if name == "lugre" else {}))
    rng = np.random.default_rng(0)
    Vs = 1e-5
    zs = 12.95e-9 / 1e4
    for _ in range(20):
        x = rng.uniform(0, 1e-9)
        v = rng.choice([-1, 1]) * 10 ** rng.uniform(-7, -3)  # away from the kinks at v = 0
        z = rng.uniform(-0.9, 0.9) * zs
        e = m.evaluate(x, v, z)
        for var, h, dF, dz in (("x", 1e-15, "dF_dx", "dzd_dx"), ("v", abs(v) * 1e-6, "dF_dv", "dzd_dv"),
                               ("z", zs * 1e-6, "dF_dz", "dzd_dz")):
            args_p = dict(x=x, v=v, z=z)
            args_m = dict(x=x, v=v, z=z)
            args_p[var] += h
            args_m[var] -= h
            ep, em = m.evaluate(**args_p), m.evaluate(**args_m)
            for key, dkey in (("F", dF), ("zdot", dz)):
                fd = (ep[key] - em[key]) / (2 * h)
                scale = max(abs(fd), abs(e[dkey]), 1e-30)
                assert abs(fd - e[dkey]) <= 1e-5 * scale + 1e-12 * (abs(e[key]) / h if h else 0), (name, var, key)


@pytest.mark.parametrize("name,arg", [("lugre", 1.0), ("bristle", 0.5)])
def test_steady_state_is_the_stribeck_curve(name, arg):
    """dz/dt = 0 at z = g(v) (v > 0) and the force there is the Stribeck curve
    F_c + (F_s - F_c) exp(-(arg v / V_s)^2) + F_v v (LuGre: arg 1, eq 2.4; bristle: 1/2, eq 2.9)."""
    m = get_friction_model(name)
    p = m.values
    for v in (1e-7, 1e-5, 3e-5, 1e-3):
        g = (p["F_c"] + (p["F_s"] - p["F_c"]) * math.exp(-(arg * v / p["V_s"]) ** 2)) / p["sigma0"]
        e = m.evaluate(0.0, v, g)
        assert abs(e["zdot"]) < 1e-12 * v
        assert e["F"] == pytest.approx(float(m.steady_force(v)), rel=1e-12)
        assert e["F"] == pytest.approx(p["sigma0"] * g + p["F_v"] * v, rel=1e-12)


def test_bristle_literal_reading_gives_no_backward_plateau():
    """(2.8) read literally: for v < 0 in 1D, dz/dt = -|v| z / g only relaxes z (docstring)."""
    lit = get_friction_model("bristle")
    mag = get_friction_model("bristle", vmax="magnitude")
    assert lit.rate(0.0, -1e-6, 0.0) == 0.0
    assert mag.rate(0.0, -1e-6, 0.0) == pytest.approx(-1e-6)
    assert float(mag.steady_force(-1e-6)) == pytest.approx(-float(mag.steady_force(1e-6)))


def test_bristle_2d_reduces_to_1d_and_has_exact_jacobian():
    p = np.array([1e4, 1e4, 12.95e-9, 12.95e-9, 12.45e-9, 12.45e-9, 1e-5, 1e-7, 1e-7, 1.0])
    m = get_friction_model("bristle")
    for vx, zx in ((3e-6, 1e-12), (2e-5, 0.5e-12)):
        Fx, Fy, zxd, zyd, J = bristle2d_eval(p, vx, 0.0, zx, 0.0)
        e = m.evaluate(0.0, vx, zx)
        assert Fx == pytest.approx(float(e["F"]), rel=1e-14)
        assert zxd == pytest.approx(float(e["zdot"]), rel=1e-14)
    y = np.array([2e-6, -1e-6, 0.7e-12, -0.2e-12])
    _, _, _, _, J = bristle2d_eval(p, *y)
    sc = np.array([1e-12, 1e-12, 1e-18, 1e-18])
    for j in range(4):
        yp, ym = y.copy(), y.copy()
        yp[j] += sc[j]
        ym[j] -= sc[j]
        fp = np.array(bristle2d_eval(p, *yp)[:4])
        fm = np.array(bristle2d_eval(p, *ym)[:4])
        fd = (fp - fm) / (2 * sc[j])
        assert np.allclose(fd, J[:, j], rtol=1e-5, atol=1e-6 * np.abs(J).max())


def test_non_physical_parameters_are_rejected():
    with pytest.raises(ParameterError, match="sigma0.*positive"):
        get_friction_model("bristle", sigma0=-1.0)
    with pytest.raises(ParameterError, match="F_c <= F_s"):
        get_friction_model("bristle", F_s=1e-9, F_c=2e-9)
    # velocity strengthening is admissible in LuGre (g stays positive)
    assert get_friction_model("lugre", F_s=1e-9, F_c=2e-9).values["F_c"] == 2e-9
    with pytest.raises(ParameterError):
        get_friction_model("lugre", F_s=0.0)
    with pytest.raises(ParameterError, match="unknown parameter"):
        get_friction_model("pt", sigma0=1.0)
    with pytest.raises(ParameterError):
        get_friction_model("bristle").scaled(-2.0)


def test_normal_load_input_scales_the_force_levels():
    m = get_friction_model("bristle")
    m2 = m.at_load(2 * m.reference_load)
    assert m2.values["F_s"] == pytest.approx(2 * m.values["F_s"])
    assert m2.values["F_c"] == pytest.approx(2 * m.values["F_c"])
    assert m2.values["sigma0"] == m.values["sigma0"]
    with pytest.raises(ParameterError, match="normal load"):
        m.at_load(-1e-9)
