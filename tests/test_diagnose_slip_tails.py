"""The tails of the activated slip point's distribution (``friction.slip_nodes``, ``_branch_exchange``).

A sample that only a slip in the tail of the slip point's distribution (probability ``P``) moves to the other stick
branch, a drop ``D`` away, has the two-branch mixture's variance ``D^2 P (1 - P)``. Equal probability intervals gave it
none beyond the first interval's midpoint (1/64 with 32 of them): a slip there (blind g09, 298 K, about 100 slips,
samples at 15 and 8.7 sigma) was read as a misfit. The nodes halve their intervals into the tails, so the variance is
the mixture's to the factor of the midpoint rule on intervals a factor 2 apart (within 1/1.5 ... 1/0.75)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ndtr, ndtri

from probedyn.diagnose import friction as FR


def test_the_nodes_are_a_probability_rule_reaching_the_far_tails():
    p, w = FR.SLIP_NODES
    assert math.isclose(float(w.sum()), 1.0, rel_tol=1e-12)
    assert np.all(np.diff(p) > 0) and np.all((p > 0) & (p < 1))
    assert np.allclose(p + p[::-1], 1.0) and np.allclose(w, w[::-1])  # symmetric
    pt = 1.0 / FR.SLIP_QUANTILES
    inner = (p > pt) & (p < 1 - pt)
    assert np.allclose(w[inner], pt)  # the middle: the equal intervals of before
    # the first node: the midpoint of the last interval, (0, pt 2^-halvings)
    assert math.isclose(float(p[0]), 0.5 * pt * 2.0**-FR.SLIP_TAIL_HALVINGS, rel_tol=1e-12)
    # each node's weight is its interval's width: the cumulative weight below a node brackets it by a factor 2
    cum = np.cumsum(w) - w
    assert np.all(p[1:] >= cum[1:]) and np.all(p[1:] <= 2 * cum[1:] + 1e-15)


def _mixture(x, sd_s, nodes, D, a):
    """Point samples at ``x`` about one slip with a Gaussian slip point N(0, sd_s) between straight branches a drop
    ``D`` apart (the branch table: f(u) = D u / a, so that f(u) - f(u - a) = D)."""
    p, w = nodes
    dq = sd_s * ndtri(p)
    u_b = np.linspace(-3 * a, 3 * a, 6001)
    carry = (D, (u_b, np.zeros_like(u_b), D * u_b / a))
    b = np.concatenate([np.linspace(-3 * a, -1e-12, 3001), np.linspace(1e-12, 3 * a, 3001)])
    path = (b, D * b / a + np.where(b < 0, D, 0.0) - D * 0.0)
    return FR._scatter_moments(x, np.zeros(len(x), int), [(0, 0.0, 1.0)], dq, True, [path], a, carry=carry,
                               nodes=(p, w))


@pytest.mark.parametrize("z", [-4.0, -3.0, -2.5, 2.5, 3.0, 4.0])
def test_a_sample_in_the_tail_carries_the_mixture_s_variance(z):
    """The limit case: a point sample at z standard deviations of a Gaussian slip point from the median, beyond
    the 1/32 quantile (z = 1.86), where the model exchanges the branches. Its variance is ``D^2 P (1 - P)`` with
    ``P = Phi(-|z|)`` within the midpoint rule's factor (1/1.5 ... 1/0.75), and its mean is shifted by ``D P``
    towards the other branch within the same factor; equal intervals gave it 0 (beyond z = 2.15)."""
    sd_s, D, a = 0.05, 1.0, 1.0
    x = np.array([z * sd_s])
    P = float(ndtr(-abs(z)))
    mean, var = _mixture(x, sd_s, FR.SLIP_NODES, D, a)
    assert 0.66 < var[0] / (D * D * P * (1 - P)) < 1.34
    # after the median a sample is on the upper branch (a late slip: up), before it on the lower (an early one)
    assert 0.66 < math.copysign(1.0, z) * mean[0] / (D * P) < 1.34
    M = FR.SLIP_QUANTILES
    equal = ((np.arange(M) + 0.5) / M, np.full(M, 1.0 / M))
    assert _mixture(x, sd_s, equal, D, a)[1][0] < 1e-20 * D * D


def test_the_middle_is_the_equal_rule_and_every_sample_is_the_mixture_s():
    """Within the middle the nodes are the equal intervals of before (the same variance, to round-off); from the
    median to 4.5 standard deviations of the slip point every sample's variance is the two-branch mixture's,
    ``D^2 P (1 - P)``, within the midpoint rule's factor (and the middle's discreteness, 1/32 of D^2)."""
    sd_s, D, a = 0.05, 1.0, 1.0
    z = np.linspace(-4.5, 4.5, 37)
    x = z * sd_s
    _, v = _mixture(x, sd_s, FR.SLIP_NODES, D, a)
    M = FR.SLIP_QUANTILES
    _, ve = _mixture(x, sd_s, ((np.arange(M) + 0.5) / M, np.full(M, 1.0 / M)), D, a)
    middle = np.abs(z) < 1.5  # within the 1/16 ... 15/16 quantiles: no tail node reaches these samples
    assert np.allclose(v[middle], ve[middle], rtol=1e-12, atol=1e-15)
    exact = D * D * ndtr(-np.abs(z)) * (1 - ndtr(-np.abs(z)))
    assert np.all((v > 0.66 * exact - D * D / M) & (v < 1.34 * exact + D * D / M))
    tails = np.abs(z) > 2.2
    assert np.all((v[tails] > 0.66 * exact[tails]) & (v[tails] < 1.34 * exact[tails]))
    assert np.all(ve[tails] < 1e-20)  # the equal rule: none


def test_no_slip_comes_before_the_tip_lands_in_its_well():
    """At U0 = 5 k_B T (blind g09's amplitude at 298 K) the early tail reaches back most of a period; the slip
    point is cut at the landing, a period before the median (the table's branch starts at the well's birth)."""
    T, a, k = 298.0, 4.5e-10, 0.6
    U0 = 5.0 * FR.K_B * T
    tab = FR._barrier_table(U0, a, k)
    dq, drop, (u, H, f) = FR.thermal_slip_scatter(tab, U0, a, k, 5e-9, T, 10**4.5)
    assert dq.min() >= -a * (1 + 1e-12) and dq.min() < -0.5 * a
    # the branches a period apart differ at the median slip point by the slip's drop (the exchange of the tails)
    assert drop > 0 and abs(np.interp(0.0, u, f) - np.interp(-a, u, f) - drop) < 0.02 * drop
