"""Correlated noise (:mod:`probedyn.diagnose.noise`): the AR(1) estimate, its gates, the exact whitening, and a
force-curve null whose correlated noise the white diagnosis takes for a cause."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from probedyn.diagnose.noise import SCATTER_SE_SQRT_N, AR1Whitener, noise_correlation

from diagnose_truth_curves import correlated, make_curve_case


def _problem(n_seq=2, m=300, stated=True):
    return SimpleNamespace(sequences=[np.arange(i * m, (i + 1) * m) for i in range(n_seq)], noise_stated=stated)


def test_ar1_correlation_recovered_within_its_standard_error():
    """AR(1) residuals of unit marginal variance: rho from the stated noise's high-frequency part within 4
    of its standard errors (1.5 / sqrt n at white noise, smaller as rho grows), whitened as AR(1)."""
    rng = np.random.default_rng(5)
    prob = _problem()
    for rho in (0.5, 0.8):
        r = np.concatenate([correlated(rng.standard_normal(300), rho) for _ in range(2)])
        nz = noise_correlation(prob, r)
        assert nz["model"] == "AR(1)"
        assert abs(nz["rho_scatter"] - rho) < 4 * SCATTER_SE_SQRT_N / math.sqrt(600)
        assert nz["rho"] <= nz["rho_scatter"] + 1e-12 and nz["rho"] <= nz["rho_lag1"] + nz["gate_lag1"] + 1e-12
        assert abs(nz["rho"] - rho) < 4 * SCATTER_SE_SQRT_N / math.sqrt(600)


def test_white_overstated_or_misfit_records_are_not_whitened():
    """White noise is never taken as correlated: as stated (40 records), stated 25 % too high (the scatter
    estimate reads rho ~ 0.3, the lag-one correlation ~ 0), with a smooth misfit of 20 sigma (the lag-one
    correlation ~ 1, the scatter estimate ~ 0), or with the noise estimated from the record itself."""
    rng = np.random.default_rng(6)
    prob = _problem()
    x = np.linspace(0, 1, 300)
    misfit = np.concatenate([20 * np.exp(-((x - 0.6) / 0.1) ** 2)] * 2)
    for _ in range(40):
        e = rng.standard_normal(600)
        assert noise_correlation(prob, e)["model"] == "white"
        assert noise_correlation(prob, e / 1.25)["model"] == "white"
        nz = noise_correlation(prob, e + misfit)
        assert nz["model"] == "white" and nz["rho_lag1"] > 0.5 and abs(nz["rho_scatter"]) < 0.2
    assert noise_correlation(_problem(stated=False), correlated(rng.standard_normal(600), 0.8))["model"] == "white"
    assert noise_correlation(SimpleNamespace(noise_stated=True), rng.standard_normal(600)) is None


def test_whitening_is_the_exact_ar1_likelihood_with_and_without_a_mask():
    """sum r'^2 over a fit's rows = r_m^T Sigma_mm^-1 r_m with the AR(1) covariance Sigma_ij = rho^|i-j| within a
    sequence (exact Gaussian likelihood of the training rows, gaps included), to round-off; a pseudo-residual
    row outside every sequence is left as it is."""
    rng = np.random.default_rng(7)
    rho, m = 0.7, 24
    seqs = [np.arange(0, m), np.arange(m, 2 * m)]
    w = AR1Whitener(rho, seqs, 2 * m + 1)
    r = rng.standard_normal(2 * m + 1)
    idx = np.arange(m)
    S = rho ** np.abs(idx[:, None] - idx[None, :])
    for mask in (None, np.arange(2 * m + 1) % 4 != 1, rng.random(2 * m + 1) < 0.6):
        mk = np.ones(2 * m + 1, bool) if mask is None else mask
        rw = w(r, mask)
        exact = 0.0
        for s in seqs:
            keep = mk[s]
            sub = S[np.ix_(keep, keep)]
            exact += float(r[s][keep] @ np.linalg.solve(sub, r[s][keep]))
        assert float(np.sum(rw[:2 * m][mk[:2 * m]] ** 2)) == pytest.approx(exact, rel=1e-10)
        assert rw[-1] == r[-1]
    # a held-out row is scored by its innovation given the recorded sample before it
    mask = np.arange(2 * m + 1) % 4 != 1
    rw = w(r, mask)
    assert rw[5] == pytest.approx((r[5] - rho * r[4]) / math.sqrt(1 - rho**2), rel=1e-12)


def test_correlated_null_curve_whitened(tmp_path):
    """A force-curve null (Hertz on the lever, seed 6003) with AR(1) noise of rho = 0.8 at the stated marginal
    sigma: the default noise model estimates rho within 0.1, claims nothing, and the baseline parameters'
    uncertainties grow over the white analysis' by more than 1.5 and at most the long-run factor
    sqrt((1 + rho) / (1 - rho)) (2.9 at 0.78: the bound for regressors smooth over the correlation length)."""
    from probedyn.diagnose.engine import run

    path, _ = make_curve_case(tmp_path, 6003, None, noise_rho=0.8)
    auto = run(path)
    nz = auto["method"]["noise"]
    assert nz["model"] == "AR(1)" and abs(nz["rho"] - 0.8) < 0.1
    assert auto["findings"] == [] and auto["verdict"] == "no-significant-discrepancy"
    white = run(path, noise_model="white")
    assert white["method"]["noise"]["model"] == "white"
    bound = math.sqrt((1 + nz["rho"]) / (1 - nz["rho"]))
    for name in ("z_c", "b0", "b1"):
        ratio = auto["baseline"]["parameters"][name]["sigma"] / white["baseline"]["parameters"][name]["sigma"]
        assert 1.5 < ratio <= 1.05 * bound, (name, ratio, bound)
