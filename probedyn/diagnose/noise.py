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
estimated from the same residuals, the test is conservative, not exact).

**Without a stated noise** (most instrument exports) the record's noise is its own high-frequency scatter
(the MAD of its second differences over sqrt 6), so ``q ~ 1`` whatever the correlation, and a correlated
noise read that way is understated by ``sqrt((1 - rho)(3 - rho) / 3)`` (0.38 at rho = 0.8): every smooth
cause became significant. The first differences then anchor the scale instead of the stated sigma,

    Var(Delta e) = 2 s^2 (1 - rho),    so    Var(Delta^2 e) / Var(Delta e) = 3 - rho

(trimmed as above; its white-noise standard error is the same ``1.5 / sqrt n``, simulated), gated as
above; ``rho_scatter > 1`` (first differences larger than any AR(1) noise gives) is a misfit, not noise. The
innovation's standard deviation follows from ``q`` without the ill-determined marginal sigma:
``s^2 (1 - rho^2) = q^2 3 (1 + rho) / (3 - rho)`` (``innovation_sd``). Unlike the stated case, a misfit
with structure at the sampling scale (a sloped surface's friction, whose slope changes from sample to
sample) raises the first differences more than the second and reads as correlation; the engine
therefore judges an unstated noise on the residuals of the best nested candidate, not the baseline's
(:func:`probedyn.diagnose.engine.diagnose`, step 1b).

**Noise with more power at the record's scale than an AR(1)** (a detector's 1/f noise; session 23). The
differences see only the noise's high-frequency part: on 1/f noise they read an AR(1) of rho ~ 0.46 whose
marginal sigma is ~2/3 of the true one, so that the smooth causes fitted its low-frequency power (5 of 6
force-curve nulls without a stated noise claimed a drift, a hysteresis or an adhesion). The residuals' own
variance (per sequence, mean removed, trimmed) is then the marginal sigma's estimate, as a stated sigma is:
``rho_marginal = 2 - sqrt(1 + Var(Delta^2 r) / (2 Var r))``, and the noise's rho is the larger of the two
(``rho_marginal`` reported). For AR(1) noise both estimate the same rho: the larger of the two lifts the
differences' low draws (on the session-22 benchmark at rho = 0.8, seed 2001: 0.61 -> 0.76) at a small upward
bias (+0.02 to +0.035 at rho 0.5-0.9 without a fitted baseline, which absorbs some record-scale variance and
lowers ``rho_marginal``). A misfit
left in the residuals (a second effect the best single cause leaves) raises ``Var r`` too, without bound: the
excess over the AR(1) the differences imply is taken as noise only up to what flicker noise shows over a
sequence of the same length (:func:`flicker_excess`: 1.8x at 300 samples, 2.6x at 3000), beyond it as
misfit (on the friction-loop benchmark two cases whose second effect read 6x and 27x were otherwise left
without their findings). The gates above still decide whether the noise is correlated at all (a white
record stays white). Judged on the best nested candidate's residuals like the rest of the unstated estimate.

**An unstated white noise's scale** (session 27). Where the gates find no correlation, the record's noise is
white and its sigma is the residuals' high-frequency scale ``q`` times the problem's (read from part of the
record: a force curve's far quarter of the approach): the result carries ``white_scale = q`` when ``q`` differs
from 1 by more than ``SCALE_GATE_SE`` of its standard error ``1 / sqrt n``, and the engine re-fits on it. A
declared correlation of 0 keeps the problem's sigma.

**A white floor under a slow noise** (session 27, force curves: ``problem.noise_mixture``). A detector's 1/f
noise above its white floor: the differences see only the floor (the scatter gate reads white) while the
residuals' lag-one correlation passes its gate. That state is ambiguous between such a noise and a misfit; on
a force curve it is read by maximum likelihood as white noise plus an AR(1) (:func:`white_plus_ar1`), taken
when its likelihood ratio against white exceeds ``MIX_LR_GATE``, and every fit is whitened exactly by the
dense covariance per sequence (:class:`MixtureWhitener`), provided the fitted mixture implies the scatter
statistic read within its gate (:func:`mixture_rho_scatter`; session 28: the real JPK curve's slow misfit and
segment-dependent noise fitted as an AR(1) of share 1 and rho 0.99, implying 0.99 against the 0.10 read, which
made its marginal sigma 55x the scatter and every finding vanish; the white-floor nulls imply within 0.09 of
what they read). Blind nulls with such noise claimed a drift or a
hysteresis on 3 of 4 records; on this model none. Not on friction loops: there the state more often means a
second effect's misfit (a contrast beside a slope, 7022 and 7064 lost their second finding to it).

**A noise per sequence** (session 28, force curves: ``problem.noise_per_sequence``). Without a stated noise,
the sequences' own second-difference scales are compared first (:func:`sequence_scales`); where they differ
beyond chance (a chi-square at ``GATE_SE`` standard errors) each sequence's residuals are put in units of its
own scale (:class:`SequenceScale`) and every estimate above is made on them. A force curve whose approach and
retract are recorded at different rates has different detector bandwidths in the two: the real JPK QI curve's
retract (50 kHz) scatters 4.3x its approach (5 kHz); one pooled sigma weighs the approach 4x too little and
reads the retract's noise as misfit.

**A declared correlation** (``[noise] correlation`` in the sidecar, measured by the user, e.g. on a
record off the surface or with the tip retracted) replaces the estimate and its gates: ``rho`` as
declared (0: white whatever the record shows). With a stated noise the whitening follows from it; without
one, the innovation's scale still comes from the residuals' second differences with the declared ``rho``
(the formula above), judged on the best nested candidate's residuals like an estimated one. The estimates
are reported beside it, so that a declaration the record contradicts can be seen.

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
#: standard errors of the high-frequency scale ``q`` (white noise: ``1 / sqrt n``, simulated for n = 300 ... 2000
#: in two sequences: 0.98 - 1.00) beyond which an unstated white noise's scale is re-read from the residuals
SCALE_GATE_SE = 2.0
#: the white-plus-AR(1) noise (:func:`white_plus_ar1`): its name, the likelihood ratio against white noise it
#: needs (the chi-square of two parameters at 1e-4 is 18.4; the AR(1)'s rho is not identified under white noise,
#: which raises the null's tail: 0 of 400 white records of 600 samples passed 25, simulated), and the longest
#: sequence its dense covariance is built for
MIXTURE = "white + AR(1)"
MIX_LR_GATE = 25.0
MIX_MAX_SEQUENCE = 1000
#: the standard error of ``ln q`` (``q`` a sequence's second-difference scale) times sqrt of its length under
#: white noise: ``Var(mean (Delta^2 e)^2) / E^2 = 2 (1 + 2 ((4/6)^2 + (1/6)^2)) / n = 3.89 / n``, halved in the
#: log of the root: 0.986 (simulated with the trimming: 0.977; AR(1) 0.5-0.8 and 1/f noise 0.86-0.97: the
#: white value is the conservative one)
LOGQ_SE_SQRT_N = 0.986
#: residuals clipped at this many robust sigmas in the lag-one correlation (a misplaced jump is an
#: outlier pair, not noise)
CLIP_SIGMA = 5.0


def _trimmed_mean_square(d: np.ndarray) -> float:
    """Mean square of ``d`` without the samples beyond ``TRIM_SIGMA`` robust sigmas (a misplaced jump or kink
    is not noise)."""
    dev = np.abs(d - np.median(d))
    keep = dev <= TRIM_SIGMA * 1.4826 * float(np.median(dev))
    return float(np.mean(d[keep] ** 2))


def flicker_excess(m: float) -> float:
    """How much larger the variance of flicker (1/f) noise over a sequence of ``m`` samples (its own mean
    removed) is than the marginal variance of the AR(1) that its first and second differences imply
    (``Var(Delta e) / (2 (1 - rho))`` with ``rho = 3 - Var(Delta^2 e) / Var(Delta e)``): 1.8 at m = 300, 2.0 at
    600, 2.6 at 3000 (the excess grows as log m; insensitive, within 3 %, to the spectrum's low cut-off between
    one and four sequence lengths, here two). From the exact autocovariance of the spectrum ``1/f`` on the
    frequencies of ``2 m`` samples."""
    m = max(int(round(m)), 4)
    f = np.fft.rfftfreq(2 * m)
    f[0] = f[1]
    c = np.fft.irfft(1.0 / f, 2 * m)
    c = c / c[0]
    k = np.arange(1, m)
    var_mean = (1.0 + 2.0 * float(np.sum((1.0 - k / m) * c[1:m]))) / m
    ms1, ms2 = 2.0 * (1.0 - c[1]), 6.0 - 8.0 * c[1] + 2.0 * c[2]
    rho = 3.0 - ms2 / ms1
    return float((1.0 - var_mean) / (ms1 / (2.0 * (1.0 - rho))))


def noise_correlation(problem, r: np.ndarray) -> dict[str, Any] | None:
    """The AR(1) correlation of the noise from the baseline residuals ``r`` (units of the problem's noise,
    stated or estimated from the record's scatter) of a problem that declares ``sequences``; None where it
    does not apply. Without a stated noise the correlation comes from the first against the second
    differences and the result carries ``innovation_sd``, the one-step innovation's standard deviation
    in the residuals' units (module docstring). A problem's ``noise_correlation_declared`` (not None: the
    sidecar's ``[noise] correlation``) replaces the estimate and its gates."""
    seqs = [np.asarray(s, int) for s in (getattr(problem, "sequences", None) or []) if len(s) > 3]
    if not seqs:
        return None
    stated = bool(getattr(problem, "noise_stated", False))
    r = np.asarray(r, float)
    declared = getattr(problem, "noise_correlation_declared", None)
    scales = None
    if not stated and declared is None and getattr(problem, "noise_per_sequence", False) and len(seqs) > 1:
        scales = sequence_scales(r, seqs)
        if scales is not None:  # every statistic below on the residuals each in units of its own sequence's noise
            r = r.copy()
            for s, qs in zip(seqs, scales["scales"]):
                r[s] = r[s] / qs
    ms2 = _trimmed_mean_square(np.concatenate([np.diff(r[s], 2) for s in seqs]))
    q = float(math.sqrt(ms2 / 6.0))
    if stated:
        rho_s = 2.0 - math.sqrt(1.0 + 3.0 * q * q)
    else:  # Var(Delta^2 e) / Var(Delta e) = 3 - rho, whatever the noise's scale
        ms1 = _trimmed_mean_square(np.concatenate([np.diff(r[s]) for s in seqs]))
        rho_s = 3.0 - ms2 / ms1 if ms1 > 0 else 0.0
        # the residuals' own variance read as the marginal sigma (the stated case's estimator): larger than
        # the differences imply where the noise has more power at the record's scale than an AR(1) (1/f)
        ms0 = _trimmed_mean_square(np.concatenate([r[s] - r[s].mean() for s in seqs]))
        # ... at most as much larger as a flicker noise's is over sequences of this length (beyond: a misfit)
        if 0.0 < rho_s < 1.0:
            ms0 = min(ms0, flicker_excess(float(np.mean([len(s) for s in seqs]))) * ms1 / (2.0 * (1.0 - rho_s)))
        rho_m = 2.0 - math.sqrt(1.0 + ms2 / (2.0 * ms0)) if ms0 > 0 else 0.0
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
    # without a stated noise, Var(Delta^2) < 2 Var(Delta) (rho_scatter > 1) is no AR(1) noise: a misfit
    # carries the first differences
    beyond = bool(not stated and rho_s > 1.0 + gate_s)
    applied = applied and not beyond
    # the scatter estimate is unbiased (simulated: 0.800 +- 0.013 at rho = 0.8, n = 600; the lag-one estimate
    # reads 0.78, biased by the fitted baseline); the lag-one estimate only bounds it from above (a stated noise
    # that is too large inflates rho_scatter, not rho_lag1)
    rho = float(min(rho_s if stated else max(rho_s, rho_m), rho_l + gate_l, RHO_MAX)) if applied else 0.0
    estimator = ("stated noise against the second differences" if stated
                 else "first against second differences (no stated noise)")
    if declared is not None:  # measured by the user: taken as declared, the estimates kept for comparison
        applied, beyond, rho = declared > 0, False, float(declared)
        estimator = "declared ([noise] correlation)"
    out = {"model": "AR(1)" if applied else "white", "rho": rho, "rho_scatter": rho_s, "rho_lag1": rho_l,
           "high_frequency_scale": q, "gate_scatter": gate_s, "gate_lag1": gate_l, "n": n,
           "estimator": estimator}
    if not stated:
        out["rho_marginal"] = rho_m
    if scales is not None:
        out.update(sequence_scales=scales["scales"], sequence_scale_chi2=scales["chi2"],
                   sequence_scale_threshold=scales["threshold"])
    if beyond:
        out["reason"] = "first differences beyond AR(1) noise (rho_scatter > 1): a misfit, not the noise"
    elif declared is not None and not applied:
        out["reason"] = "declared white ([noise] correlation = 0)"
    if not applied and not stated and declared is None and not beyond and abs(q - 1.0) > SCALE_GATE_SE / math.sqrt(n):
        # an unstated white noise: the problem's sigma came from part of the record (a force curve: the far
        # quarter of the approach, ~75 second differences, about 12 % standard error); the residuals' second
        # differences over the whole record read it to 1 / sqrt n (4 % at n = 600); blind null c21 read
        # q = 1.27 and its Hertz baseline, the truth, failed at chi^2 967 on 596 dof
        out["white_scale"] = q
    if (not applied and not stated and declared is None and not beyond and rho_l > gate_l
            and getattr(problem, "noise_mixture", False) and max(len(s) for s in seqs) <= MIX_MAX_SEQUENCE):
        # the ambiguous state: correlated at the record's scale (lag one) but white from sample to sample
        # (the differences): a white floor plus a slow noise (a detector's 1/f above its white floor), or a misfit
        mix = white_plus_ar1(r, seqs)
        # ... that must reproduce the state it is chosen for: the differences' statistic it implies within
        # the scatter gate of the one read (a slow misfit fitted as an AR(1) of share 1 and rho 0.99 implies
        # rho_scatter = 0.99: the JPK curve, read 0.10, whose marginal sigma came out 55x its scatter)
        implied = mixture_rho_scatter(mix["share"], mix["phi"])
        if mix["lr"] > MIX_LR_GATE and abs(implied - rho_s) <= gate_s:
            out.pop("white_scale", None)
            out.update(model=MIXTURE, rho=mix["phi"], share=mix["share"], mixture_lr=mix["lr"],
                       mixture_rho_scatter=implied, marginal_sd=math.sqrt(mix["variance"]))
        else:
            out.update(mixture_lr=mix["lr"], mixture_rho_scatter=implied)
            if mix["lr"] > MIX_LR_GATE:
                out["reason"] = (f"white + AR(1) rejected: it implies rho_scatter {implied:.2f}, the record's "
                                 f"differences read {rho_s:.2f} (a slow misfit, not a white floor under a slow noise)")
    if applied and not stated:
        # s^2 (1 - rho)(3 - rho) / 3 = q^2 gives the marginal sigma s (ill-determined as rho -> 1) and the
        # innovation's s^2 (1 - rho^2) = q^2 3 (1 + rho) / (3 - rho) (well determined: the 1 - rho cancels)
        out["innovation_sd"] = q * math.sqrt(3.0 * (1.0 + rho) / (3.0 - rho))
        out["marginal_sd"] = q * math.sqrt(3.0 / ((1.0 - rho) * (3.0 - rho)))
    return out


def sequence_scales(r: np.ndarray, seqs) -> dict[str, Any] | None:
    """The noise scale of each sequence (its residuals' second differences, ``q_s = sqrt(ms(Delta^2 r) / 6)``,
    trimmed) where they differ beyond chance; None where they do not. The test: ``chi2 = sum (ln q_s - m)^2 /
    se_s^2`` (``m`` their inverse-variance mean, ``se_s = LOGQ_SE_SQRT_N / sqrt(n_s)``) above the chi-square
    quantile of ``len(seqs) - 1`` degrees of freedom at the two-sided tail of ``GATE_SE`` standard errors
    (6.3e-5). A force curve's approach and retract recorded at different rates (the JPK QI curve: 5 kHz and
    50 kHz, the retract's scatter 4.3x the approach's) carry different detector bandwidths, hence noise."""
    from probedyn.diagnose.tails import chi2 as chi2_dist, norm

    ln_q, w = [], []
    for s in seqs:
        d2 = np.diff(np.asarray(r, float)[s], 2)
        ms = _trimmed_mean_square(d2) if len(d2) > 2 else 0.0
        if ms <= 0.0:
            return None
        ln_q.append(0.5 * math.log(ms / 6.0))
        w.append(len(d2) / LOGQ_SE_SQRT_N**2)
    ln_q, w = np.asarray(ln_q), np.asarray(w)
    m = float(np.sum(w * ln_q) / np.sum(w))
    stat = float(np.sum(w * (ln_q - m) ** 2))
    thr = float(chi2_dist.ppf(1.0 - 2.0 * norm.sf(GATE_SE), len(ln_q) - 1))
    if not stat > thr:
        return None
    return {"scales": [float(x) for x in np.exp(ln_q)], "chi2": stat, "threshold": thr}


class SequenceScale:
    """``r -> inner(r / s)``: each sequence's residuals in units of its own noise (:func:`sequence_scales`;
    ``scales`` per sequence, rows outside every sequence unscaled), then the correlated noise's whitener
    ``inner`` if any. A held-out mask changes nothing in the scaling (each row's own)."""

    def __init__(self, scales, sequences, n: int, inner=None) -> None:
        self.row_scale = np.ones(n)
        for s, qs in zip(sequences, scales):
            self.row_scale[np.asarray(s, int)] = float(qs)
        self.inner = inner

    def __call__(self, r: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        x = np.asarray(r, float) / self.row_scale
        return x if self.inner is None else self.inner(x, mask)


def mixture_rho_scatter(share: float, phi: float) -> float:
    """The scatter statistic ``3 - Var(Delta^2 e) / Var(Delta e)`` of white noise plus an AR(1) carrying the
    fraction ``share`` of the variance (autocorrelation ``share phi^k`` at lag ``k >= 1``): with ``c_k`` the
    autocorrelation, ``Var Delta = 2 (1 - c_1)`` and ``Var Delta^2 = 6 - 8 c_1 + 2 c_2``. ``share = 0``: 0
    (white); ``share = 1``: ``phi`` (the AR(1)'s own)."""
    c1, c2 = share * phi, share * phi * phi
    return float(3.0 - (6.0 - 8.0 * c1 + 2.0 * c2) / (2.0 * (1.0 - c1)))


def _mix_cov(m: int, share: float, phi: float) -> np.ndarray:
    """Unit-variance covariance of ``m`` consecutive samples of white noise plus an AR(1) of correlation
    ``phi`` carrying the fraction ``share`` of the variance: ``C_ij = share phi^|i-j|`` off the diagonal."""
    lag = np.abs(np.subtract.outer(np.arange(m), np.arange(m)))
    C = share * phi ** lag.astype(float)
    C[np.diag_indices(m)] = 1.0
    return C


def _mix_quad_logdet(x: np.ndarray, share: float, phi: float) -> tuple[float, float]:
    """``(x' C^-1 x, log det C)`` of :func:`_mix_cov` in O(m), without forming C: with ``K`` the AR(1)'s
    correlation matrix (``phi^|i-j|``), whose inverse ``T`` is tridiagonal (``(1 - phi^2) T`` has the
    diagonal ``1, 1 + phi^2, ..., 1 + phi^2, 1`` and ``-phi`` beside it), ``C = (1 - share) I + share K =
    K ((1 - share) T + share I)``, so ``C^-1 = ((1 - share) T + share I)^-1 T`` (the two commute) and ``det C
    = (1 - phi^2)^(m-1) det((1 - share) T + share I)``: one banded Cholesky factor of a tridiagonal matrix.
    Raises ``LinAlgError`` where that matrix is not positive definite (as the dense factor would)."""
    from scipy.linalg import cho_solve_banded, cholesky_banded

    m = len(x)
    g = 1.0 - phi * phi
    a, b = 1.0 - share, share
    diag = np.full(m, (1.0 + phi * phi) / g)
    diag[0] = diag[-1] = 1.0 / g
    if m == 1:
        diag[0] = 1.0
    off = np.full(m - 1, -phi / g)
    Tx = diag * x
    Tx[:-1] += off * x[1:]
    Tx[1:] += off * x[:-1]
    ab = np.zeros((2, m))  # upper form: ab[0, 1:] the superdiagonal, ab[1] the diagonal
    ab[0, 1:] = a * off
    ab[1] = a * diag + b
    cf = cholesky_banded(ab, lower=False, check_finite=False)
    z = cho_solve_banded((cf, False), Tx, check_finite=False)
    logdet = (m - 1) * math.log(g) + 2.0 * float(np.sum(np.log(cf[1])))
    return float(x @ z), logdet


def white_plus_ar1(r: np.ndarray, seqs) -> dict[str, float]:
    """Maximum-likelihood white-plus-AR(1) noise of the residuals ``r`` over ``seqs`` (each a Gaussian of
    covariance ``v C(share, phi)``, :func:`_mix_cov`; ``v`` profiled: ``v = sum r' C^-1 r / n``); returns the
    variance ``v`` (units of ``r`` squared), ``share``, ``phi`` and ``lr``, twice the log-likelihood gain over
    white noise of the same data (``share = 0``). A white floor with a slow noise above it (a detector's 1/f
    noise over its white floor, blind cases c22, c26, c30: the differences see only the floor, the lag-one
    correlation the slow part) is this model's case; an AR(1) noise is its ``share = 1``."""
    from scipy.optimize import minimize

    xs = [np.asarray(r, float)[s] for s in seqs]
    n = sum(len(x) for x in xs)

    def quad_logdet(share: float, phi: float) -> tuple[float, float]:  # sum r' C^-1 r and sum log det C
        q = logdet = 0.0
        for x in xs:
            qx, lx = _mix_quad_logdet(x, share, phi)
            q += qx
            logdet += lx
        return q, logdet

    def nll(u):
        try:
            q, logdet = quad_logdet(1.0 / (1.0 + math.exp(-u[0])), 1.0 / (1.0 + math.exp(-u[1])))
        except np.linalg.LinAlgError:
            return 1e300
        return 0.5 * (n * math.log(q / n) + logdet)

    logit = lambda p: math.log(p / (1.0 - p))  # noqa: E731
    grid = [(logit(a), logit(b)) for a in (0.1, 0.3, 0.5, 0.7, 0.9) for b in (0.5, 0.8, 0.9, 0.95, 0.98, 0.995)]
    u0 = min(grid, key=nll)
    res = minimize(nll, u0, method="Nelder-Mead", options={"xatol": 1e-3, "fatol": 1e-4, "maxiter": 400})
    u = res.x if res.fun < nll(u0) else np.asarray(u0)
    share, phi = 1.0 / (1.0 + math.exp(-u[0])), 1.0 / (1.0 + math.exp(-u[1]))
    white = 0.5 * n * math.log(float(sum(x @ x for x in xs)) / n)
    q, _ = quad_logdet(share, phi)
    return {"variance": q / n, "share": share, "phi": phi, "lr": max(2.0 * (white - nll(u)), 0.0)}


class MixtureWhitener:
    """``r -> r'`` for white-plus-AR(1) noise (:func:`white_plus_ar1`; ``r`` in units of its marginal sigma)
    within each sequence. The rows of ``mask`` (a fit's training data) are whitened by the Cholesky factor of
    their own covariance; a held-out row (``mask`` False) by its predictive density given the training rows of
    its sequence, jointly with the other held-out rows (``r_H - C_HT C_TT^-1 r_T`` whitened by the Cholesky
    factor of the conditional covariance): the exact Gaussian likelihood of the training data and the exact
    predictive density of the held-out data. Dense per sequence (``MIX_MAX_SEQUENCE``)."""

    def __init__(self, share: float, rho: float, sequences, n: int) -> None:
        self.share, self.rho = float(share), float(rho)
        self.sequences = [np.asarray(s, int) for s in sequences]
        self.n = n
        self._plans: dict[bytes | None, list] = {}

    def _plan(self, mask: np.ndarray | None) -> list:
        from scipy.linalg import cholesky, solve_triangular

        key = None if mask is None or mask.all() else np.packbits(mask).tobytes()
        hit = self._plans.get(key)
        if hit is not None:
            return hit
        plan = []
        for s in self.sequences:
            C = _mix_cov(len(s), self.share, self.rho)
            keep = np.ones(len(s), bool) if key is None else np.asarray(mask, bool)[s]
            T, H = np.nonzero(keep)[0], np.nonzero(~keep)[0]
            LT = cholesky(C[np.ix_(T, T)], lower=True) if len(T) else None
            K = LS = None
            if len(H) and len(T):
                A = solve_triangular(LT, C[np.ix_(T, H)], lower=True)  # L_T^-1 C_TH
                K = solve_triangular(LT, A, lower=True, trans="T").T  # C_HT C_TT^-1
                LS = cholesky(C[np.ix_(H, H)] - A.T @ A, lower=True)
            elif len(H):
                LS = cholesky(C[np.ix_(H, H)], lower=True)
            plan.append((s[T], s[H], LT, K, LS))
        self._plans[key] = plan
        return plan

    def __call__(self, r: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        from scipy.linalg import solve_triangular

        out = np.array(r, float, copy=True)
        for rows_T, rows_H, LT, K, LS in self._plan(mask):
            rT = r[rows_T]
            if LT is not None:
                out[rows_T] = solve_triangular(LT, rT, lower=True, check_finite=False)
            if LS is not None:
                rH = r[rows_H] - (K @ rT if K is not None else 0.0)
                out[rows_H] = solve_triangular(LS, rH, lower=True, check_finite=False)
        return out


class AR1Whitener:
    """``r -> r'`` for AR(1) noise of correlation ``rho`` within each sequence (module docstring).
    ``innovation_sd``: the one-step innovation's standard deviation in the units of ``r`` (default
    ``sqrt(1 - rho^2)``: ``r`` in units of the noise's marginal sigma, as with a stated noise)."""

    def __init__(self, rho: float, sequences, n: int, innovation_sd: float | None = None) -> None:
        self.rho = float(rho)
        self.sequences = [np.asarray(s, int) for s in sequences]
        self.n = n
        self.innovation_sd = None if innovation_sd is None else float(innovation_sd)
        self._rows = np.concatenate(self.sequences) if self.sequences else np.zeros(0, int)
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
        if self.innovation_sd is None:
            scale = 1.0 / np.sqrt(1.0 - a * a)
        else:  # s^2 (1 - rho^2d) = innovation_sd^2 (1 - rho^2d) / (1 - rho^2), the ratio a finite sum
            scale = 1.0 / (self.innovation_sd * np.sqrt((1.0 - a * a) / (1.0 - self.rho**2)))
        hit = (rows_a, prev_a, a, scale)
        self._plans[key] = hit
        return hit

    def __call__(self, r: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        rows, prev, a, scale = self._plan(mask)
        out = np.array(r, float, copy=True)
        if self.innovation_sd is not None:  # a sequence's first sample (and a fold's): its marginal sigma
            out[self._rows] = r[self._rows] * (math.sqrt(1.0 - self.rho**2) / self.innovation_sd)
        out[rows] = (r[rows] - a * r[prev]) * scale
        return out
