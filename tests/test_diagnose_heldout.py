"""Held-out evidence as a predictive density (engine ``CrossValidation.heldout``; problems with
``heldout_predictive``: modal and spectra).

A fold's fit of a cause predicts its held-out group with the fold's parameter uncertainty: the
score of the group is ``-2 ln`` of the linearised posterior predictive density,
``e^T (I + S)^-1 e + ln det(I + S)``, ``S = J_g C J_g^T``, ``C = (J_-g^T J_-g + P)^-1``. On a
linear model with Gaussian noise that is exact up to the prior: checked here against the Gaussian
conditional written out in the parameters' own units (an independent computation), and on the
case that motivated it -- a parameter that only the held-out group informs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from probedyn.diagnose.causes import Cause, CauseParam
from probedyn.diagnose.engine import CrossValidation, Fitter, folds_of

sys.path.insert(0, str(Path(__file__).resolve().parent))

from toy_problem import ToyProblem  # noqa: E402

SPAN = 20.0  # both parameters bounded in [-10, 10]: a uniform prior of variance SPAN^2 / 12


class _Two(Cause):
    key, kind = "two", "toy"
    params = (CauseParam("a", "1", -10.0, 10.0, 0.0, "gain of x"), CauseParam("b", "1", -10.0, 10.0, 0.0, "gain of z"))

    def effect(self, values, state):
        return None


class _Lin(ToyProblem):
    """Four groups of one sample each, y = a x + b z + noise; ``b`` is informed mostly by the last
    sample (z there 1, elsewhere 0.10-0.15): leave that sample out and ``b`` is fixed by the
    others' noise."""

    noise = 0.1

    def __init__(self, predictive: bool):
        self.x = np.array([1.0, 2.0, -1.0, 0.5])
        self.z = np.array([0.1, -0.15, 0.12, 1.0])
        self.y = 1.5 * self.x + 4.0 * self.z + self.noise * np.array([0.3, -0.8, 0.5, 0.2])
        self.groups = np.arange(4)
        self.base_params = []
        self.causes = [_Two()]
        self.heldout_predictive = predictive

    def residuals(self, values, causes=()):
        m = np.zeros_like(self.x)
        if causes:
            m = values["a"] * self.x + values["b"] * self.z
        return (self.y - m) / self.noise


def _scores(predictive: bool):
    prob = _Lin(predictive)
    F = Fitter(prob)
    base = F.baseline()
    fit = F.nested(base, tuple(prob.causes))
    folds = folds_of(prob.groups)
    cv = CrossValidation(F, folds, len(prob.groups))
    cv.heldout(fit)
    return prob, folds, fit


def test_the_heldout_score_is_the_gaussian_predictive_density():
    prob, folds, fit = _scores(True)
    X = np.column_stack([prob.x, prob.z])
    prior_prec = np.eye(2) * 12.0 / SPAN**2
    for fold, score in zip(folds, fit.cv_fold):
        train = np.ones(len(prob.y), bool)
        train[fold] = False
        theta = np.linalg.lstsq(X[train], prob.y[train], rcond=None)[0]  # the fold's least-squares optimum
        cov = np.linalg.inv(X[train].T @ X[train] / prob.noise**2 + prior_prec)
        xg = X[fold][0]
        var = prob.noise**2 + xg @ cov @ xg  # predictive variance of the held-out sample
        e = prob.y[fold][0] - xg @ theta
        assert fit.cv_r[fold][0] == pytest.approx(e / prob.noise, rel=1e-6, abs=1e-8)
        # the central-difference Jacobian of a linear model is exact up to rounding
        assert score == pytest.approx(e**2 / var + np.log(var / prob.noise**2), rel=1e-6)
    assert fit.cv == pytest.approx(float(np.sum(fit.cv_fold)), rel=1e-12)


def test_a_group_that_alone_informs_a_parameter_is_not_held_to_the_others_noise():
    """Held out, the last sample is predicted with b fitted to the other three (z = 0.10-0.15
    there): the fold's b is off by ten times its full-data error and the prediction 3.6 sigma off.
    Taken as exact that costs e^2 = 12.8; the predictive density knows how poorly the three
    samples fix b (predictive variance 36 noise variances) and charges 3.9, mostly the Occam
    factor ln 36. The other folds' training data include the last sample: their scores move by
    less than that reduction in total."""
    _, folds, plain = _scores(False)
    _, _, pred = _scores(True)
    e2 = np.array([np.nansum(plain.cv_r[f] ** 2) for f in folds])
    assert np.allclose(plain.cv_fold, e2)  # without the flag: the held-out chi^2 itself
    last = len(folds) - 1
    assert e2[last] > 9.0  # more than 3 sigma off with b taken as exact
    assert pred.cv_fold[last] < 0.5 * e2[last]
    assert abs(np.sum(pred.cv_fold[:last] - e2[:last])) < e2[last] - pred.cv_fold[last]
