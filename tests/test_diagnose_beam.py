"""The reduced 1D FE beam of the diagnosis against analytic limits and exact solutions."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from probedyn.diagnose.beam import BeamFE, BeamProps, sader_gamma, solve_family

sys.path.insert(0, str(Path(__file__).parent))
from diagnose_truth import MODAL_EFFECTS, MODES, draw_modal_effect, modal_truth  # noqa: E402

# clamped-free roots of 1 + cos(b) cosh(b) = 0 (eq 2.40)
CF = [brentq(lambda b: 1 + math.cos(b) * math.cosh(b), lo, lo + 2.5) for lo in (1.0, 3.5, 6.5, 10.0, 13.0, 16.0)]


def test_clamped_free_roots_and_h4_convergence():
    # Hermite cubics: eigenvalue error O(h^4) -> halving h divides it by ~16.
    e20 = np.abs(BeamFE(20).bending(6) ** 0.25 / np.array(CF) - 1)
    e40 = np.abs(BeamFE(40).bending(6) ** 0.25 / np.array(CF) - 1)
    assert abs(CF[0] - 1.8751040687) < 1e-9
    ratio = e20 / e40
    # mode 1 at n = 40 is already at round-off (~1e-9); the order shows on modes 2-6
    assert np.all((ratio[1:] > 12) & (ratio[1:] < 20)), ratio  # 16 within the pre-asymptotic scatter
    # mode 1: round-off of a K with condition ~ (n_el)^4 / lambda_1 ~ 1e6 -> ~1e-8; mode 6: (beta h)^4 / 1440 = 1.3e-4
    assert e40[0] < 1e-7 and e40[5] < 2e-4


def test_tip_mass_matches_corrected_eq_3_10():
    # SOURCE-NOTES item 1: 1 + cos cosh + mu b (cos sinh - sin cosh) = 0; mu = 1 -> b = 1.248
    for mu in (0.1, 1.0, 3.0):
        f = lambda b: 1 + math.cos(b) * math.cosh(b) + mu * b * (math.cos(b) * math.sinh(b) - math.sin(b) * math.cosh(b))  # noqa: E731
        b1 = brentq(f, 0.3, 1.87)
        fe = BeamFE(40).bending(1, mu=mu, xi=1.0) ** 0.25
        assert abs(fe[0] / b1 - 1) < 1e-6  # FE error (beta h)^4/1440 ~ 3e-9; tolerance leaves margin
    assert abs(brentq(lambda b: 1 + math.cos(b) * math.cosh(b) + b * (math.cos(b) * math.sinh(b) - math.sin(b) * math.cosh(b)), 0.3, 1.87) - 1.248) < 1e-3


def test_spring_hinged_limit_pinned_free():
    # kappa_t -> inf, kappa_r -> 0: pinned-free beam, tan b = tanh b (b = 3.9266, 7.0686) plus a rigid mode
    lam = BeamFE(40).bending(3, kappa_r=0.0, kappa_t=math.inf) ** 0.25
    roots = [brentq(lambda b: math.tan(b) - math.tanh(b), lo, hi) for lo, hi in ((3.5, 4.7), (6.5, 7.8))]
    assert lam[0] < 0.05  # rigid rotation about the pin (numerically ~0)
    assert np.allclose(lam[1:], roots, rtol=1e-6)
    # and stiff springs recover the clamp (first-order compliance 1/kappa: kappa = 1e7 -> ~1e-7)
    assert np.allclose(BeamFE(40).bending(3, kappa_r=1e7, kappa_t=1e9) ** 0.25, CF[:3], rtol=1e-5)


def test_torsion_linear_elements_are_fourth_order():
    # averaged consistent/lumped mass: eigenvalue error O(h^4) for the 1D wave equation
    exact = ((2 * np.arange(1, 4) - 1) * math.pi / 2) ** 2
    e = [np.abs(BeamFE(n).torsion(3) / exact - 1) for n in (20, 40)]
    assert np.all(e[0] / e[1] > 12)


def test_sader_gamma_limits():
    # inviscid limit: Gamma_r -> 1 (added mass pi/4 rho w^2 of a plate), Gamma_i -> 0
    g = sader_gamma(np.array([1e4 * 4 * 1.8e-5 / 1.2]), 1.0, 1.2, 1.8e-5)
    assert abs(g.real[0] - 1) < 0.1 and g.imag[0] < 0.05
    # circular-cylinder asymptote Gamma ~ 1 + 2 sqrt(2)(1 + i)/sqrt(Re) (large Re)
    re = 1e6
    gc = sader_gamma(np.array([re * 4 * 1.8e-5 / 1.2]), 1.0, 1.2, 1.8e-5, circular=True)[0]
    assert abs(gc.real - 1 - 2 * math.sqrt(2) / math.sqrt(re)) < 1e-5
    assert abs(gc.imag - 2 * math.sqrt(2) / math.sqrt(re)) < 1e-5
    # the fluid-loaded uniform beam obeys Sader's eq 25 for Q
    p = BeamProps(200e-6, 30e-6, 2e-6, 169e9, 2330.0)
    fe = BeamFE(30)
    f, Q = solve_family(fe, p, "flap", 2, rho_f=1.18, eta_f=1.85e-5)
    T = math.pi * 1.18 * p.width / (4 * p.rho * p.thickness)
    g = sader_gamma(2 * math.pi * f, p.width, 1.18, 1.85e-5)
    assert np.allclose(Q, (1 / T + g.real) / g.imag, rtol=1e-9)


@pytest.mark.parametrize("effect", MODAL_EFFECTS)
def test_extended_beam_matches_exact_transfer_matrix_truth(effect, tmp_path):
    """Every catalog extension against the independent exact solution (tests/diagnose_truth.py)."""
    from probedyn.diagnose.causes import get_cause
    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.modal import ModalProblem

    from diagnose_truth import write_modal

    rng = np.random.default_rng(7)
    params = draw_modal_effect(effect, rng)
    f, q = modal_truth(effect, params)
    path = write_modal(tmp_path, effect, f, q)
    prob = ModalProblem(read_measurement(path))
    c = get_cause(effect)()
    v = dict(params)
    for p in c.params:
        v.setdefault(p.name, p.hold if p.hold is not None else p.starts[0])
    v["Q_int"] = 2e4
    fm, qm = prob.predict(prob.state(v, (c,)))
    # FE discretisation: n_el chosen so (beta h)^4/1440 < 3e-5; clamp: kappa_t held at 1e8
    # (compliance 1e-8 of the free-end one) -> 5e-5 covers both.
    assert np.max(np.abs(fm / f - 1)) < 5e-5
    assert np.max(np.abs(qm / q - 1)) < 1e-4  # fluid Q: same Gamma, fixed point converged


@pytest.mark.slow
def test_reduced_beam_against_3d_fem():
    """Once against the 3D FEM (helper's probes/cantilever.py): plain Si cantilever with a tip mass."""
    probes = pytest.importorskip("probedyn.probes")
    try:
        from probedyn.probes import cantilever  # noqa: F401  (registration)
        probe, _ = probes.get_probe("cantilever")
    except Exception as exc:  # pragma: no cover - depends on the other helper's API
        pytest.skip(f"3D FEM cantilever not available: {exc}")
    L, w, t = 300e-6, 30e-6, 3e-6
    m_tip = 0.2 * 2330.0 * L * w * t
    res = probe.modes({"length": L, "width": w, "thickness": t, "tip_mass": m_tip, "elements_through_thickness": 2}, n_modes=6)
    flap = [m.frequency_hz for m in res.modes if m.family in ("flap", "flapwise", "z", "vertical", "bending-z")]
    if len(flap) < 2:
        pytest.skip("FEM mode families not labelled as flapwise")
    p = BeamProps(L, w, t, 169e9, 2330.0, 0.28)
    f, _ = solve_family(BeamFE(30), p, "flap", 2, mass=m_tip, xi=1.0)
    # a plate of w/t = 10 is stiffer than a beam by up to 1/sqrt(1 - nu^2) = 1.04 in f; the 3D
    # tip mass sits on the end face (no rotary inertia either): 5 % covers both
    assert np.allclose(flap[:2], f, rtol=0.05), (flap[:2], f)
