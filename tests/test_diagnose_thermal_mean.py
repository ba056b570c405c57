"""The stick branch at a temperature (``friction.thermal_mean_shift``): the recorded force is the Boltzmann mean
over the tip's well, not its minimum. Checked against its leading term in T (a limit case) and against an
independent quadrature over the well (scipy's ``quad`` between the saddles found by ``brentq``)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from probedyn.diagnose import friction as fr

# blind friction set 2's g09 lever and corrugation (U0 the amplitude of -U0 cos(q x)): eta = 7
U0, A, K = 2.15e-20, 4.5e-10, 0.6
Q = 2 * math.pi / A


def _leading(xm, T):
    """dF = k k_B T E''' / (2 E''^2) at the minimum: <x> - x_m = -k_B T E''' / (2 E''^2) for E ~ E'' d^2/2 + E''' d^3/6."""
    E2 = K + Q * Q * U0 * np.cos(Q * xm)
    E3 = -(Q**3) * U0 * np.sin(Q * xm)
    return K * fr.K_B * T * E3 / (2 * E2 * E2)


@pytest.mark.parametrize("ratio", [20.0, 50.0])
def test_a_cold_tip_s_shift_is_the_leading_term_in_temperature(ratio):
    """The next term is smaller by about k_B T / U0: the Boltzmann mean's deviation from the leading term is within
    2.5 k_B T / U0 of its size on the branch's middle (measured 1.8-2.0), and falls tenfold when T does (first
    order). Above THERMAL_MEAN_LEADING the shift is that leading term."""
    T = U0 / (fr.K_B * ratio)
    X, dF, Xc = fr.thermal_mean_shift(U0, A, K, T)
    xm = fr._barrier_table(U0, A, K)[4]
    lead = _leading(xm, T)
    mid = (X > -0.5 * Xc) & (X < 0.6 * Xc)
    dev = np.max(np.abs(dF[mid] - lead[mid])) / np.max(np.abs(lead[mid]))
    assert dev < 2.5 / ratio
    T10 = T / 10
    fr._thermal_mean_memo.cache_clear()
    old = fr.THERMAL_MEAN_LEADING
    fr.THERMAL_MEAN_LEADING = 1e9  # the Boltzmann mean itself at the colder temperature too
    try:
        X2, dF2, _ = fr.thermal_mean_shift(U0, A, K, T10)
    finally:
        fr.THERMAL_MEAN_LEADING = old
        fr._thermal_mean_memo.cache_clear()
    dev10 = np.max(np.abs(dF2[mid] - _leading(xm, T10)[mid])) / np.max(np.abs(_leading(xm, T10)[mid]))
    assert 7.0 < dev / dev10 < 13.0
    cold = U0 / (fr.K_B * 2 * fr.THERMAL_MEAN_LEADING)
    Xc_, dFc, _ = fr.thermal_mean_shift(U0, A, K, cold)
    assert np.allclose(dFc[mid], _leading(xm, cold)[mid], rtol=1e-12, atol=0)


def test_the_room_temperature_shift_is_the_boltzmann_mean_over_the_well():
    """At 298 K (U0 = 5.2 k_B T, the barrier at zero force 10.5 k_B T) the shift is far from its leading term; against
    an adaptive quadrature between the well's saddles it agrees within 2 % of its largest value (the grids of
    THERMAL_MEAN_POINTS), is zero where the well is symmetric (no lateral
    force) and lowers the force towards the slip."""
    T = 298.0
    X, dF, Xc = fr.thermal_mean_shift(U0, A, K, T)
    _, barrier, _, xs, xm = fr._barrier_table(U0, A, K)
    kT = fr.K_B * T
    scale = np.max(np.abs(dF))
    bound = np.nonzero(barrier < fr.THERMAL_MEAN_BOUND * kT)[0][0]  # nearer the instability the shift is held
    assert np.all(dF[bound:] == dF[bound - 1])
    for i in np.linspace(0.1 * len(X), bound - 1, 7).astype(int):
        Xi = X[i]

        def dE(x):
            return Q * U0 * math.sin(Q * x) - K * (Xi - x)

        def E(x):
            return -U0 * math.cos(Q * x) + 0.5 * K * (Xi - x) ** 2

        # the backward saddle: the maximum of E between the forward saddle's image a period behind and the minimum
        xb = brentq(dE, xs[i] - A + 1e-16, xm[i] - 1e-16) if dE(xs[i] - A + 1e-16) * dE(xm[i] - 1e-16) < 0 else xs[i] - A
        Em = E(xm[i])
        z = quad(lambda x: math.exp(-(E(x) - Em) / kT), xb, xs[i], points=[xm[i]], limit=200)[0]
        xmean = quad(lambda x: x * math.exp(-(E(x) - Em) / kT), xb, xs[i], points=[xm[i]], limit=200)[0] / z
        assert abs(dF[i] - K * (xm[i] - xmean)) < 0.02 * scale
    i0 = int(np.argmin(np.abs(xm)))
    assert abs(dF[i0]) < 0.01 * scale
    # ... on the branch the tip still holds: a forward barrier of a few k_B T (within about k_B T of the instability
    # the restricted well is its wide backward side, and the tip has slipped long before: the hazard of
    # thermal_slip_advance)
    near = (X > 0.5 * Xc) & (barrier > 3 * kT)
    assert near.sum() > 10 and np.all(dF[near] < 0)


def test_the_correction_follows_the_direction_and_needs_a_declared_temperature():
    """A retrace is the trace mirrored: the same position in its well moving in -x has the opposite shift; without a
    declared temperature nothing is added."""
    T = 298.0
    X, dF, Xc = fr.thermal_mean_shift(U0, A, K, T)
    xm = fr._barrier_table(U0, A, K)[4]
    j = int(0.8 * len(X))
    st = fr.FrictionState(u0=1.0, a=A, temperature=T)
    Xl = np.array([X[j], -X[j]])
    F = np.array([K * (X[j] - xm[j]), -K * (X[j] - xm[j])])  # the quasi-static force: the tip in the well at 0
    c = fr._thermal_mean_correction(F, Xl, np.array([1.0, -1.0]), st, U0, K)
    assert c[0] == pytest.approx(dF[j], rel=1e-12)
    assert c[1] == pytest.approx(-dF[j], rel=1e-12)
    cold = fr.FrictionState(u0=1.0, a=A, thermal=(T, 1e5))  # an activation's assumed temperature is no declared one
    assert np.all(fr._thermal_mean_correction(F, Xl, np.array([1.0, -1.0]), cold, U0, K) == 0.0)
