"""Why a compliant clamp, a tip mass and a length error confound on bending frequencies (issue 11, class 8).

Independent reference: the Euler-Bernoulli cantilever solved here from its boundary conditions (a 4 x 4
determinant, not probedyn's code) with

* a root rotational spring ``k_r`` (``EI w''(0) = k_r w'(0)``), compliance ``c = EI / (k_r L)``;
* a rigid clamp and a point mass ``m`` at the free end, ratio ``mu = m / (rho A L)``;
* a rigid clamp at ``L (1 + eps)``.

Results (exact, not fitted):

1. **Duality**: the root-spring cantilever's characteristic equation
   ``1 + cos b cosh b + c b (cos b sinh b - sin b cosh b) = 0`` is the tip-mass cantilever's
   ``1 + cos b cosh b + mu b (cos b sinh b - sin b cosh b) = 0`` with ``c = mu``: *every* flapwise
   frequency of a lever with root compliance ``c`` equals that of a rigidly clamped lever carrying a tip
   mass ``c rho A L``, at any ``c``. With the same support for lateral bending (clamp_compliance.py: the
   rotational stiffness per unit area ``k_n``, so ``EI_lat / k_r,lat = EI_flap / k_r,flap = E / k_n``) the
   lateral modes are dual too. Bending frequencies alone cannot tell the two apart in beam theory; only
   what the beam omits (shear and rotary inertia of higher modes, the clamp's warping compliance in
   torsion) and another observable (the static spring constant, lowered by the clamp and not by a mass)
   can.
2. **First order**: for small ``c`` both shift every bending mode by ``-2 c`` (``phi_n''(0)^2 = phi_n(L)^2
   = 4`` for the normalised modes, independent of ``n``), exactly as a length error ``dL / L = c`` does
   (``f ~ L^-2``). A length error is told apart by torsion (``f ~ 1 / L``: ``-c``; the clamp and a
   tip mass on the axis: about 0) -- which is why a torsion mode decides clamp against length.
3. The library's own paths reach that limit: the diagnosis FEM's clamp foundation and point mass on a
   slender lever (300 x 30 x 10 um) shift the first bending modes alike and by ``-2 c`` within 10 %.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from probedyn.lumped import beam as bm


def _det(M: np.ndarray, b: float) -> float:
    return float(np.linalg.det(M)) / np.cosh(b) ** 2


def root_spring_equation(b: float, c: float) -> float:
    """w = A cosh + B sinh + C cos + D sin (x in units of L, b = beta L); w(0) = 0, c b^2 (A - C) =
    b (B + D) (the root spring), w''(1) = w'''(1) = 0."""
    ch, sh, co, si = np.cosh(b), np.sinh(b), np.cos(b), np.sin(b)
    return _det(np.array([[1, 0, 1, 0], [c * b * b, -b, -c * b * b, -b], [ch, sh, -co, -si], [sh, ch, si, -co]]), b)


def tip_mass_equation(b: float, mu: float) -> float:
    """Rigid clamp (w = w' = 0), free end w''(1) = 0 and EI w'''(1) = -m omega^2 w(1), i.e.
    w'''(1) = -mu b^4 w(1) in units of L."""
    ch, sh, co, si = np.cosh(b), np.sinh(b), np.cos(b), np.sin(b)
    b3, mb4 = b**3, mu * b**4
    row_w = np.array([ch, sh, co, si])
    row_w3 = b3 * np.array([sh, ch, si, -co])
    return _det(np.array([[1, 0, 1, 0], [0, b, 0, b], b * b * np.array([ch, sh, -co, -si]), row_w3 + mb4 * row_w]), b)


def _roots(f, n: int) -> np.ndarray:
    xs = np.linspace(0.3, 3.2 * n + 2.0, 6000)
    v = np.array([f(x) for x in xs])
    out = []
    for i in np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]:
        r = brentq(f, xs[i], xs[i + 1], xtol=1e-14)
        if abs(f(r)) < 1e-6 * (abs(v[i]) + abs(v[i + 1])):  # a root, not a pole
            out.append(r)
        if len(out) == n:
            break
    return np.array(out)


@pytest.mark.parametrize("c", [1e-3, 0.02, 0.3, 2.0])
def test_root_compliance_and_tip_mass_are_dual(c):
    b_clamp = _roots(lambda b: root_spring_equation(b, c), 4)
    b_mass = _roots(lambda b: tip_mass_equation(b, c), 4)
    assert b_clamp == pytest.approx(b_mass, rel=1e-10)
    # both are roots of the closed form of the module docstring
    for b in b_clamp:
        closed = 1 + np.cos(b) * np.cosh(b) + c * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b))
        assert abs(closed) / np.cosh(b) < 1e-9
    # and both agree with probedyn's tip-mass equation (lumped/beam.py, eq 3.10)
    assert b_mass == pytest.approx(bm.tip_mass_roots(c, 4), rel=1e-9)
    # the rigid limit
    assert _roots(lambda b: root_spring_equation(b, 1e-12), 4) == pytest.approx(bm.eb_roots(4), rel=1e-9)


def test_first_order_shift_is_the_same_for_every_mode_and_equals_a_length_error():
    c = 1e-4
    rel = (_roots(lambda b: root_spring_equation(b, c), 4) / bm.eb_roots(4)) ** 2 - 1.0
    # -2 c for every mode; the second-order term is O(c^2 b_n^2) (mode 4: b = 11, c b^2 = 0.012)
    assert rel / c == pytest.approx(-2.0, rel=0.02)
    assert ((1.0 + c) ** -2 - 1.0) / c == pytest.approx(-2.0, rel=1e-3)


def test_the_diagnosis_fem_clamp_and_tip_mass_reach_the_beam_limit():
    """The clamp foundation (c_rot) and the point mass of the diagnosis FEM on a slender lever
    (300 x 30 x 10 um): the first two flapwise and the first lateral frequencies fall by -2 c within
    10 % and within 10 % of each other (measured: clamp -2.12 c, -2.11 c, -2.10 c; mass -1.99 c,
    -1.96 c, -1.97 c: the 3D root under a Winkler face is a little softer than the beam's plane
    section, and shear/rotary inertia). Torsion: a point mass on the axis leaves it; the clamp lowers it
    by less than a length error's -c (the face foundation frees the root's warping, a release bounded by
    the FEM-to-Saint-Venant gap)."""
    from probedyn.diagnose.modal_model import FEMBaseline, ModalState, ReducedModal
    from probedyn.probes import get_probe

    probe = get_probe("cantilever")[0]
    b = FEMBaseline(probe, probe.resolve(dict(length=300e-6, width=30e-6, thickness=10e-6)),
                    {"flapwise": 2, "lateral": 1, "torsion": 1}, estimate_error=False)
    red = ReducedModal(b)
    need = [("flapwise", 1), ("flapwise", 2), ("lateral", 1), ("torsion", 1)]
    axes = {"length": b.length_axis, "width": b.width_axis, "thickness": b.thickness_axis}
    f0, _ = red.solve(ModalState(axes=axes, length=b.L), need)
    c = 2e-3
    mass = c * float(b.model.total_mass())
    f_clamp, _ = red.solve(ModalState(axes=axes, length=b.L, clamp=(c, 0.0)), need)
    f_mass, _ = red.solve(ModalState(axes=axes, length=b.L, masses=[(1.0, mass)]), need)
    d_clamp = f_clamp / f0 - 1.0
    d_mass = f_mass / f0 - 1.0
    assert d_clamp[:3] / c == pytest.approx([-2.0] * 3, rel=0.10)
    assert d_mass[:3] / c == pytest.approx([-2.0] * 3, rel=0.10)
    assert d_clamp[:3] == pytest.approx(d_mass[:3], rel=0.10)
    assert abs(d_mass[3]) < 0.01 * c
    assert -c < d_clamp[3] < 0.0
