"""A minimal diagnose problem for engine tests: a 1D record y(t) with a stated noise, no physical
structure to report. Subclasses set ``t``, ``y``, ``groups``, ``base_params``, ``causes`` and
``residuals`` (normalised by :attr:`noise`)."""

from __future__ import annotations

import numpy as np


class ToyProblem:
    kind, unit, path, reduced = "toy", "1", "toy", False
    noise = 0.01

    def physical_rms(self, r):
        return float(np.sqrt(np.mean(np.asarray(r) ** 2))) * self.noise

    def structure(self, r):
        return {}

    def describe(self):
        return {}

    def model_description(self):
        return {}
