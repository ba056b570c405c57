"""Correlated measurement noise: when the stated noise is not white, and the whitening that follows.

The diagnosis' statistics (:mod:`.engine`) assume that a correct model leaves residuals
``r ~ N(0, I)`` in units of the stated noise. An instrument's noise is often correlated from sample
to sample (1/f drift of the detector, building vibration, a low-pass filter slower than the
sampling): with the same marginal sigma, the chi-square of the baseline still averages ``n``, but a
smooth extension fits the correlated part and the likelihood-ratio gains grow by up to
``(1 + rho) / (1 - rho)`` (for AR(1) noise of lag-one correlation ``rho``); interleaved
cross-validation folds do not protect, since a held-out sample's neighbours carry its noise. Measured
on the force-curve null generator (``benchmarks/diagnose_noise_correlation.py``, docs/diagnose.md §9.6):
AR(1) noise at the stated marginal sigma, rho = 0.95, gave 3/30 false discoveries taken as white, 0/30
whitened; on the 200 white cases of the declared force-curve benchmark the gate below never fired.

**Which correlation.** A smooth misfit of the baseline (the very effect the diagnosis looks for)
also makes the residuals correlated, so the residuals' own lag-one correlation cannot tell the
noise's correlation from a hidden effect. The stated noise can: it is the marginal sigma of the
noise, while the second differences of the residuals see only its high-frequency part, in which any
smooth misfit is negligible. For AR(1) noise of marginal sigma ``s``,

    Var(Delta^2 e) = s^2 (6 - 8 rho + 2 rho^2),    so    q^2 = (1 - rho)(3 - rho) / 3,

with ``q`` the RMS of ``Delta^2 r / sqrt 6`` (trimmed at ``TRIM_SIGMA`` robust sigmas) (``r`` in units of the stated noise):
``rho_scatter = 2 - sqrt(1 + 3 q^2)``. A stated noise *larger* than the true white noise also gives
``q < 1``; the residuals' lag-one correlation ``rho_lag`` (biased upward by any misfit, never
downward) separates the two: white noise has ``rho_lag ~ 0``. Both estimates must exceed
``GATE_SE`` standard errors of their white-noise scatter (``1.5 / sqrt n`` and ``1 / sqrt n``,
simulated for n = 150 ... 2000); the noise is then taken as AR(1) with ``rho = rho_scatter`` (unbiased;
the lag-one estimate reads low by the fitted baseline's share), at most ``rho_lag`` plus its gate (a stated
noise too large inflates ``rho_scatter`` only). The whitened baseline's chi-square then centres on its
degrees of freedom (the median p-value of 50 nulls at rho = 0.8 is 0.5, none below 0.1: with rho
estimated from the same residuals, the test is conservative, not exact). Records whose noise was
estimated from their own second differences (no stated noise) have ``q = 1`` by construction: nothing changes for them (their sigma is the high-frequency one; a
correlated noise then reads as a significant baseline misfit, a limit stated in docs/diagnose.md §8).

**Whitening** (generalised least squares, Cochrane & Orcutt 1949): within each of the problem's
``sequences`` (samples in recording order), ``r'_i = (r_i - rho^d r_j) / sqrt(1 - rho^(2d))`` with
``j`` the previous sample of the same sequence in the fitted set and ``d`` their distance in samples
(the exact conditional of AR(1) noise sampled with gaps: a cross-validation fold's training data are
whitened over their own samples, the held-out group is never used); the first sample of a sequence
keeps ``r``. A held-out sample is scored by its innovation given the sample before it in the
recording (its one-step predictive density). Rows outside every sequence (prior pseudo-residuals)
are left as they are.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: standard errors (under white noise) that both correlation estimates must exceed before the noise is
#: taken as correlated: 4 SE each (a misfit drives the lag-one estimate past its gate, so on a record with
#: a hidden effect the scatter gate alone decides: 3e-5 of white records are whitened)
GATE_SE = 4.0
#: the white-noise standard deviation of ``rho_scatter`` times sqrt(n) (trimmed RMS of the second
#: differences; simulated, n = 150 ... 2000 in two sequences: 1.46 - 1.56)
SCATTER_SE_SQRT_N = 1.5
#: second differences beyond this many robust (MAD) sigmas are left out of their RMS (a Gaussian loses
#: 6e-5 of its samples and 0.1 % of its variance)
TRIM_SIGMA = 4.0
#: the largest correlation whitened (beyond it the record carries almost no independent samples)
RHO_MAX = 0.95
#: residuals clipped at this many robust sigmas in the lag-one correlation (a misplaced jump is an
#: outlier pair, not noise)
CLIP_SIGMA = 5.0


def noise_correlation(problem, r: np.ndarray) -> dict[str, Any] | None:
    """The AR(1) correlation of the noise from the baseline residuals ``r`` (units of the stated noise)
    of a problem that declares ``sequences`` and a stated noise; None where it does not apply."""
    seqs = [np.asarray(s, int) for s in (getattr(problem, "sequences", None) or []) if len(s) > 3]
    if not seqs:
        return None
    if not getattr(problem, "noise_stated", False):
        return {"model": "white", "reason": "noise not stated (estimated from the record's own scatter)"}
    r = np.asarray(r, float)
    d2 = np.concatenate([np.diff(r[s], 2) for s in seqs])
    dev = np.abs(d2 - np.median(d2))
    keep = dev <= TRIM_SIGMA * 1.4826 * float(np.median(dev))  # a misplaced jump or kink is not noise
    q = float(math.sqrt(np.mean(d2[keep] ** 2) / 6.0))
    rho_s = 2.0 - math.sqrt(1.0 + 3.0 * q * q)
    num = den = 0.0
    for s in seqs:
        x = r[s] - np.median(r[s])
        scale = 1.4826 * float(np.median(np.abs(x))) or 1.0
        x = np.clip(x, -CLIP_SIGMA * scale, CLIP_SIGMA * scale)
        x = x - x.mean()
        num += float(x[1:] @ x[:-1])
        den += float(x @ x)
    rho_l = num / den if den > 0 else 0.0
    n = int(sum(len(s) for s in seqs))
    gate_s, gate_l = GATE_SE * SCATTER_SE_SQRT_N / math.sqrt(n), GATE_SE / math.sqrt(n)
    applied = bool(rho_s > gate_s and rho_l > gate_l)
    # the scatter estimate is unbiased (simulated: 0.800 +- 0.013 at rho = 0.8, n = 600; the lag-one estimate
    # reads 0.78, biased by the fitted baseline); the lag-one estimate only bounds it from above (a stated noise
    # that is too large inflates rho_scatter, not rho_lag1)
    rho = float(min(rho_s, rho_l + gate_l, RHO_MAX)) if applied else 0.0
    return {"model": "AR(1)" if applied else "white", "rho": rho, "rho_scatter": rho_s, "rho_lag1": rho_l,
            "high_frequency_scale": q, "gate_scatter": gate_s, "gate_lag1": gate_l, "n": n}


class AR1Whitener:
    """``r -> r'`` for AR(1) noise of correlation ``rho`` within each sequence (module docstring)."""

    def __init__(self, rho: float, sequences, n: int) -> None:
        self.rho = float(rho)
        self.sequences = [np.asarray(s, int) for s in sequences]
        self.n = n
        self._plans: dict[bytes | None, tuple] = {}

    def _plan(self, mask: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        key = None if mask is None or mask.all() else np.packbits(mask).tobytes()
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        rows, prev, dist = [], [], []
        for s in self.sequences:
            pos = np.arange(len(s))
            # the held-out rows (and every row without a mask): the sample before in the recording
            rows.append(s[1:])
            prev.append(s[:-1])
            dist.append(np.ones(len(s) - 1))
            if key is not None:
                keep = mask[s]
                t, tp = s[keep], pos[keep]
                inside = np.isin(rows[-1], t)
                rows[-1], prev[-1], dist[-1] = rows[-1][~inside], prev[-1][~inside], dist[-1][~inside]
                rows.append(t[1:])
                prev.append(t[:-1])
                dist.append(np.diff(tp).astype(float))
        rows_a, prev_a, d = np.concatenate(rows), np.concatenate(prev), np.concatenate(dist)
        a = self.rho ** d
        scale = 1.0 / np.sqrt(1.0 - a * a)
        hit = (rows_a, prev_a, a, scale)
        self._plans[key] = hit
        return hit

    def __call__(self, r: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        rows, prev, a, scale = self._plan(mask)
        out = np.array(r, float, copy=True)
        out[rows] = (r[rows] - a * r[prev]) * scale
        return out
