"""Spectra and time series: resonance peaks identified against the probe's model, then the modal diagnosis.

1. **Background and peaks.** The PSD is searched for peaks standing above their base by more than
   an averaged periodogram's chi^2 statistics allow anywhere in the spectrum (the quantile ratio
   of Gamma(m N) at 1 % / number of windows, N = ``[measurement] averages`` or estimated from the
   point-to-point scatter; :func:`detect_peaks`).
2. **Line shape.** Each peak is fitted -- by maximum likelihood of the averaged periodogram
   (Gamma deviance) when N is declared, else in log space with the scatter -- by the
   thermal SHO line ``A f0^4 / ((f0^2 - f^2)^2 + (f f0 / Q)^2)`` on a background ``B0 + B1 / f``
   (white plus 1/f); in a declared fluid by the fluid-loaded line of the same ``(f0, Q, A)``
   (:mod:`~probedyn.diagnose.lineshape`: the added mass and damping follow Sader's function across
   the line, skewing it at low Q). Lines whose tails reach each other's peaks (above ``JOINT_TAIL``:
   a lever in a liquid) are fitted together on one background (:func:`joint_refit`). A line's full
   width ``f0 / Q`` is compared with the frequency resolution *at the line* (:func:`bin_width`: a
   swept or zoomed spectrum is denser about its resonances): a line narrower than 2 bins is
   *unresolved* (a sinusoid -- an electronic spur -- or a resonance whose Q the spectrum cannot
   measure).
   Where two predicted modes fall inside a peak's matching window, the peak may be an unresolved
   doublet (two modes closer than their line width): two SHO lines are fitted by the same likelihood
   and kept when the likelihood ratio passes chi^2_3 at the engine's level (:func:`fit_doublet`); the
   two lines then compete for labels as two peaks, with the pair's (profile, correlation-inflated)
   centre uncertainties.
3. **Identification against the model.** The probe's FEM (the modal baseline) predicts every
   mode's frequency and family, and in a declared medium the Sader quality factor of its
   flapwise modes, ``Q <= Q_fluid`` (``1/Q = 1/Q_int + 1/Q_fluid``); with a declared temperature it
   also predicts the thermal peak area ``k_B T / k_eff`` (equipartition, effective stiffness of the
   mode at the tip; recorded by a declared optical lever, ``k_B T g_n^2 / omega_n^2`` with ``g_n`` the slope at
   the laser spot as the instrument calibrates it, :func:`optical_lever_gains`). A common frequency scale ``s`` in [1/2, 2] (the geometry may be off by that
   much) maps predicted onto measured frequencies (the scale that matches most peaks within 3 %);
   a peak is accepted as mode (family, order) when it lies within 3 % of a scaled prediction (the peaks placed
   one to one on the modes, :func:`_match`), its Q
   is below 3 Q_fluid (in a fluid), and (when T is declared) its area is within a factor 100 of
   equipartition times the common factor of the accepted peaks (the median of their area ratios:
   1 for a PSD calibrated in tip displacement; an uncalibrated sensitivity or an optical lever
   scales all thermal peaks alike, a spur or a pick-up line does not). Everything else is rejected *and reported* with the reason (spur, unmatched,
   Q or amplitude implausible).
   The predictions are those of a *hypothesis*: the nominal probe, or the probe carrying one catalog
   cause at parameter values refined where the modes move (:func:`_refined_grids`: neighbouring
   hypotheses move no mode by more than 2 x the window, however non-linear the frequencies are in
   the parameter -- near buckling, a heavy tip mass), on the Ritz reduction. A hidden effect moves
   the families differently (a width error moves lateral and torsional modes only, a length error
   flapwise and lateral as 1/L^2 but torsion as 1/L), so the nearest nominal mode after one common
   scale may be another family's; the hypotheses placing the most resolved peaks propose labellings,
   the nominal probe's labelling always competes (whatever it places), and distinct labellings are
   decided by their goodness of fit -- the baseline's chi-square or a single cause's plus its
   likelihood-ratio threshold (:func:`_labelling_score`), plus for every resolved line of plausible Q
   the labelling leaves unlabelled the largest chi-square a correct label could add
   (:func:`_unlabelled_price`), not by the number of peaks placed (a hypothesis can place every
   peak by mislabelling some: a soft clamp's lowered torsion taken for flapwise 3 under a point
   mass). Labellings within the evidence margin whose best models
   differ leave the peaks they disagree on out (reported as ambiguous); if one cause explains them
   all, the best labelling is kept and the other's parameters reported.
4. The accepted peaks become modal rows (frequency with the fit's standard error and the
   declared calibration uncertainty, Q with its fit error) for :class:`~probedyn.diagnose.modal.ModalProblem`.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
from scipy.constants import k as K_B  # Boltzmann constant [J/K]
from scipy.optimize import least_squares
from scipy.signal import find_peaks
from scipy.stats import gamma as gamma_dist

from probedyn.core.errors import DataFormatError
from probedyn.diagnose.formats import ModalData, SpectrumData
from probedyn.diagnose.lineshape import SHO, FluidLine, sho_psd
from probedyn.diagnose.modal import ModalProblem
from probedyn.diagnose.modal_model import FAMILIES, FEMBaseline, _fluid_mode, _stokes_mode, top_face_forms

__all__ = ["spectrum_problem", "fit_line", "fit_doublet", "detect_peaks", "sho_psd"]

MATCH_TOL = 0.03
Q_FACTOR = 3.0
Q_SPREAD = 10.0  # the Qs of one lever's modes lie within this factor of each other (an unresolved line beyond: a spur)
AREA_FACTOR = 100.0
MAX_GRID_1D = 96  # values per parameter of a one-parameter cause's hypotheses (refined where the modes move)
MAX_GRID_2D = 24  # per parameter of a two-parameter cause (a product grid)
MAX_LABELLINGS = 4  # distinct labellings compared by their modal fit
MAX_ASSIGNMENTS = 24  # one-to-one assignments of the peaks of a window holding several modes, per labelling
NARROW_MAX_BINS = 6.0  # the widest a line found narrow (at most 3 bins at half its local prominence) is fitted
DOUBLET_PLACES = 4  # independent centres of a second line within +- 1 width of a peak (resolved to ~1/2 width)
LABEL_SCREEN_NFEV = 10  # evaluations each start of a cause fit gets in the labelling screen before the best goes on
LABEL_NFEV_PER_PARAM = 40  # and the cap of that fit, per free parameter (+1): a screen, not the diagnosis
JOINT_TAIL = 1e-3  # a neighbour's line above this share of a line's peak couples their fits (joint_refit)
CAUSE_SCALE = 1.1  # common frequency scale allowed on top of a cause hypothesis (E, rho, t of a nominal lever: ~10 %)




def bin_width(freq: np.ndarray, f: float) -> float:
    """The frequency resolution at ``f``: the grid's spacing there (the median of the four spacings
    around it). A spectrum need not be sampled uniformly -- a swept or zoomed measurement is denser
    about its resonances -- and a line's width is judged against the samples it has, not against the
    median spacing of the whole grid (a vacuum line of Q 5000 sampled every 13 Hz about its peak, on a
    grid of 551 Hz elsewhere, is resolved: 5 samples across its half width)."""
    i = int(np.searchsorted(freq, f))
    d = np.diff(freq[max(i - 2, 0):min(i + 3, len(freq))])
    return float(np.median(d)) if len(d) else float(np.median(np.diff(freq)))


def _amplitude(ft: dict) -> float:
    """The low-frequency level ``A`` of a fitted line (its area is ``A pi f0 Q / 2``)."""
    return ft["area_m2"] * 2 / (math.pi * ft["f0_Hz"] * ft["Q"])


def log_scatter(psd: np.ndarray, averages: int | None) -> float:
    """Standard deviation of ln(PSD) of an averaged periodogram: about 1/sqrt(n_avg); without
    the number of averages, from the point-to-point scatter (robust)."""
    if averages:
        return 1.0 / math.sqrt(averages)
    d = np.diff(np.log(np.maximum(psd, 1e-300)))
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2))


def _gamma_ratio(m: float, n_windows: float) -> float:
    """ln of the ratio of the upper to the lower quantile of a Gamma(m, 1/m) variable at 1 % / n_windows."""
    a = 0.01 / max(n_windows, 1.0)
    return math.log(gamma_dist.isf(a, m) / gamma_dist.ppf(a, m))


def _averages(s_log: float, averages: int | None) -> float:
    return averages if averages else max(1.0, 1.0 / max(s_log, 1e-6) ** 2)


def _smoothing(n: int) -> int:
    return max(1, min(n // 4000, 8))


def narrow_lines(psd: np.ndarray, s_log: float, averages: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Narrow lines (at most 3 bins wide) standing out of their neighbourhood, and the spectrum with them notched.

    A narrow line's prominence and width are measured in its neighbourhood (+- 2 k + 4 bins, k the
    smoothing half-width of :func:`detect_peaks`), not down to the spectrum's far background: a spur
    on a mode's flank is one bin above the flank, but as wide as the mode at half its prominence over
    the background. The threshold is the ratio of the Gamma quantiles of one bin at 1 % over the
    spectrum's bins (at least a factor 5). Returns the line indices, their prominences (ln) and the
    PSD with each line's bins replaced by the median of its neighbourhood: the background and broad
    lines beneath, on which the broad peaks are searched and fitted (smoothed, a spur on a mode's flank is a
    maximum that the flank only rises into, and the mode beneath has no maximum of its own: a torsion
    line of Q 32 in water 15 kHz below a spur was never fitted, its power then split flapwise 3 into
    a phantom doublet, and the line fit started on the mode wandered onto the spur)."""
    logp = np.log(np.maximum(psd, 1e-300))
    k = _smoothing(len(psd))
    idx, props = find_peaks(logp, prominence=max(_gamma_ratio(_averages(s_log, averages), len(psd)), math.log(5.0)),
                            width=(None, 3), wlen=2 * (2 * k + 4) + 1)
    clean = psd.copy()
    for l, r in zip(props["left_ips"], props["right_ips"]):
        a, b = int(math.floor(l)), int(math.ceil(r)) + 1
        ring = np.r_[max(a - 2 * k - 4, 0):a, b:min(b + 2 * k + 4, len(psd))]
        if len(ring):
            clean[a:b] = np.median(psd[ring])
    return idx, props["prominences"], clean


def detect_peaks(freq: np.ndarray, psd: np.ndarray, s_log: float, max_peaks: int = 12,
                 averages: int | None = None) -> list[int]:
    """Peaks of ln(PSD) (:func:`find_lines`), by index."""
    return [i for i, _ in find_lines(freq, psd, s_log, max_peaks, averages)]


def find_lines(freq: np.ndarray, psd: np.ndarray, s_log: float, max_peaks: int = 12,
               averages: int | None = None) -> list[tuple[int, str]]:
    """Peaks of ln(PSD), by index and kind: broad ones on a lightly smoothed spectrum with the narrow
    lines notched out (prominence above the Gamma scatter of the smoothed bins; ``"broad"``), narrow
    lines (:func:`narrow_lines`; ``"narrow"``), and a narrow line at a broad one's top (``"both"``: a
    sharp mode, or a spur on a mode's top); the most prominent ``max_peaks``, in frequency order."""
    logp = np.log(np.maximum(psd, 1e-300))
    k = _smoothing(len(psd))
    # smoothing in the linear domain: a mean of m bins of an N-times averaged periodogram is
    # Gamma(m N, S / (m N)) where S is locally flat; a peak must stand above its base by more than
    # the ratio of the upper to the lower quantile of that distribution at alpha / (number of
    # windows) (the look-elsewhere effect: ~1 % chance of one false peak per spectrum). The log of
    # a Gamma variable is skewed (deep dips), so a threshold in standard deviations of ln S would
    # report noise as peaks where averages are few.
    N = _averages(s_log, averages)
    idx2, prom2, clean = narrow_lines(psd, s_log, averages)
    logc = np.log(np.maximum(clean, 1e-300))
    padded = np.pad(clean, k, mode="edge")  # zero padding would dent the ends and make edge 'peaks'
    sm = np.log(np.maximum(np.convolve(padded, np.ones(2 * k + 1) / (2 * k + 1), mode="valid"), 1e-300))
    thr_broad = max(_gamma_ratio((2 * k + 1) * N, len(psd) / (2 * k + 1)), math.log(2.0))
    idx, props = find_peaks(sm, prominence=thr_broad)
    # the smoothed search locates a line up to k bins off: every broad candidate is moved to the
    # largest value of the notched spectrum within the smoothing window, so the line fit is centred on it
    snapped: dict[int, float] = {}
    kind: dict[int, str] = {}
    for i, p in sorted(zip(idx, props["prominences"]), key=lambda x: -x[1]):
        lo, hi = max(int(i) - 2 * k - 1, 0), min(int(i) + 2 * k + 2, len(logc))
        j = lo + int(np.argmax(logc[lo:hi]))
        if j not in snapped:
            snapped[j], kind[j] = float(p), "broad"
    # a narrow line within the smoothing window of a broad one is at its top (a sharp mode whose wings the
    # broad search saw, or a spur on a mode's top: one line fit from the line's bin, as ever), else its own line
    for i, p in zip(idx2, prom2):
        lo, hi = max(int(i) - 2 * k - 1, 0), min(int(i) + 2 * k + 2, len(logp))
        near = [j for j in snapped if lo <= j < hi and kind[j] != "narrow"]
        if near:
            for j in near:  # the line's bin, not the notched neighbourhood's
                pj = snapped.pop(j)
                kind.pop(j)
                snapped[int(i)], kind[int(i)] = max(pj, float(p)), "both"
        else:
            snapped[int(i)], kind[int(i)] = float(p), "narrow"
    best = sorted(snapped, key=lambda i: -snapped[i])[:max_peaks]
    return [(i, kind[i]) for i in sorted(best)]


def gamma_deviance_residuals(y: np.ndarray, S: np.ndarray, averages: int) -> np.ndarray:
    """Signed deviance residuals of periodogram bins ``y`` against a model PSD ``S``: an average of
    ``N`` periodograms is ``S chi^2_{2N} / (2N)`` (a Gamma(N, S/N) variable, not Gaussian), whose
    negative log likelihood is ``N (y/S + ln S)`` + const; ``sum r^2`` is the deviance
    ``2N sum (y/S - 1 - ln(y/S))``, minimal at the maximum-likelihood S and ~ chi^2 per bin for large N.
    (A least-squares fit of ln y instead is biased: E[ln y] = ln S + psi(N) - ln N, -1.6 % in the
    line's area at N = 32.)"""
    x = np.maximum(y, 1e-300) / np.maximum(S, 1e-300)
    return np.sign(x - 1.0) * np.sqrt(np.maximum(2.0 * averages * (x - 1.0 - np.log(x)), 0.0))


def fit_line(freq: np.ndarray, psd: np.ndarray, i: int, s_log: float, averages: int | None = None,
             others: list[dict] | None = None, start: dict | None = None,
             narrow: bool = False, lines: np.ndarray | None = None, shape=SHO) -> dict[str, Any]:
    """SHO line on a white + 1/f background around peak index i: maximum likelihood of the averaged
    periodogram (:func:`gamma_deviance_residuals`) when the number of averages is known, else
    log-space least squares with the scatter ``s_log``.

    ``others``: the one-line fits of the other detected peaks. The thermal motions of a lever's modes
    are independent, so their PSDs add: a neighbour's line inside this line's window (+- 10 widths) is
    another mode's power, and fitted as this line's it broadens it (a fluid-damped flapwise 2 of Q 48
    beside a sharp lateral 1 7 % below it was read at Q 39, 19 % low, with a 2.7 % standard error).
    Their bins (+- 3 of their widths; a spur's +- 6 bins) are left out and their fitted tails are part of
    the background, as in :func:`fit_doublet`. ``start``: this line's first fit (its window and start).
    ``narrow``: a line found narrow (:func:`narrow_lines`) is held to its bin (+- 2) and to at most
    ``NARROW_MAX_BINS`` bins of width: on a broad mode's flank a free fit started on a spur wanders onto
    the mode, which carries more of the window's deviance. ``lines``: other lines' PSD on ``freq`` (their
    fits), part of this line's background."""
    f0 = float(freq[i])
    p0 = float(psd[i])
    df = bin_width(freq, f0)
    if start is not None and others:
        return _refit_line(freq, psd, start, s_log, averages, others, shape)
    half = psd > 0.5 * p0
    j0 = i
    while j0 > 0 and half[j0 - 1]:
        j0 -= 1
    j1 = i
    while j1 < len(psd) - 1 and half[j1 + 1]:
        j1 += 1
    fwhm = max(float(freq[min(j1 + 1, len(freq) - 1)] - freq[max(j0 - 1, 0)]), 2 * df)
    Q0 = max(f0 / fwhm, 0.6)
    sel = np.abs(freq - f0) < max(10 * fwhm, 30 * df)
    fw, pw = freq[sel], psd[sel]
    bg = np.concatenate([pw[:max(3, len(pw) // 10)], pw[-max(3, len(pw) // 10):]])
    B0 = max(float(np.median(bg)), 1e-300)
    A0 = max(p0 / Q0**2, 1e-300)
    u0 = np.array([f0, math.log10(Q0), math.log10(A0), math.log10(B0), math.log10(B0) - 3])
    lo = [fw[0], math.log10(0.5), u0[2] - 8, u0[3] - 8, u0[3] - 10]
    hi = [fw[-1], math.log10(Q0) + 4, u0[2] + 8, u0[3] + 4, u0[3] + 4]
    if narrow:
        lo[0], hi[0] = max(f0 - 2 * df, fw[0]), min(f0 + 2 * df, fw[-1])
        lo[1] = math.log10(f0 / (NARROW_MAX_BINS * df))
        hi[1] = max(hi[1], lo[1] + 1)
    tails = 0.0 if lines is None else lines[sel]
    r = _line_fit(fw, pw, u0, lo, hi, [fwhm, 0.3, 0.3, 0.3, 0.3], s_log, averages, tails, shape)
    return _line_result(r, fw, freq, (fw[0], fw[-1]))


def _line_fit(fw, pw, u0, lo, hi, x_scale, s_log: float, averages: int | None, tails=0.0, shape=SHO):
    """One line of ``shape`` (the SHO by default), ``u = (f0, log10 Q, log10 A, log10 white, log10 1/f at fw[0])``,
    on a white + 1/f background (plus fixed ``tails``) fitted to the periodogram ``pw`` at ``fw``: Gamma deviance with the number of averages,
    else log-space least squares with the scatter ``s_log``."""
    wf0 = fw[0]

    def model(u):
        return shape.psd(fw, u[0], 10 ** u[1], 10 ** u[2]) + 10 ** u[3] + 10 ** u[4] * (wf0 / fw) + tails

    def res(u):
        if averages:
            return gamma_deviance_residuals(pw, model(u), averages)
        return (np.log(model(u)) - np.log(np.maximum(pw, 1e-300))) / s_log

    return least_squares(res, np.clip(u0, lo, hi), bounds=(lo, hi), x_scale=x_scale)


def _refit_line(freq, psd, first: dict, s_log: float, averages: int | None, others: list[dict], shape=SHO) -> dict:
    """:func:`fit_line` of ``first`` again with the other lines' bins left out and their tails added."""
    f0, Q0 = first["f0_Hz"], first["Q"]
    df = bin_width(freq, f0)
    fwhm = f0 / Q0 if np.isfinite(Q0) and Q0 > 0 else 2 * df
    fw, pw = _window(freq, psd, first)
    keep = np.ones(len(fw), bool)
    tails = np.zeros(len(fw))
    near = False
    for o in others:
        wide = np.isfinite(o.get("Q", math.nan)) and o.get("fwhm_bins", 0.0) >= 2.0
        # a resolved neighbour within this line's width is this line's own power; a spur is left out wherever it is
        if o is first or (wide and abs(o["f0_Hz"] - f0) < fwhm) or not (fw[0] <= o["f0_Hz"] <= fw[-1]):
            continue
        near = True
        dfo = bin_width(freq, o["f0_Hz"])
        wo = 3 * o["f0_Hz"] / o["Q"] if wide else 6 * dfo
        keep &= np.abs(fw - o["f0_Hz"]) > max(wo, 3 * dfo)
        if wide:
            tails += shape.psd(fw, o["f0_Hz"], o["Q"], _amplitude(o))
    # only the core of this line must stay (+- 2 widths, at least 12 bins): else the first fit stands
    if not near or np.count_nonzero(keep & (np.abs(fw - f0) <= 2 * fwhm)) < 12:
        return first
    fw, pw, tails = fw[keep], pw[keep], tails[keep]
    A0 = _amplitude(first)
    B0, B1 = first["white_floor"], max(first["one_over_f_at_window_start"], 1e-300)
    u0 = np.array([f0, math.log10(Q0), math.log10(A0), math.log10(B0), math.log10(B1)])
    lo = [f0 - 2 * fwhm, math.log10(0.5), u0[2] - 8, u0[3] - 8, u0[4] - 8]
    hi = [f0 + 2 * fwhm, u0[1] + 4, u0[2] + 8, u0[3] + 4, u0[4] + 4]
    r = _line_fit(fw, pw, u0, lo, hi, [fwhm / 4, 0.3, 0.3, 0.3, 0.3], s_log, averages, tails, shape)
    return _line_result(r, fw, freq, first["window_Hz"], others_masked=True)


def _line_result(r, fw: np.ndarray, freq: np.ndarray, window, others_masked: bool = False) -> dict[str, Any]:
    dof = max(len(fw) - 5, 1)
    chi2 = float(np.sum(r.fun**2))
    scale = max(1.0, chi2 / dof)
    try:
        cov = np.linalg.pinv(r.jac.T @ r.jac) * scale
        sd = np.sqrt(np.maximum(np.diag(cov), 0))
    except np.linalg.LinAlgError:
        sd = np.full(5, np.inf)
    Q = 10 ** r.x[1]
    A = 10 ** r.x[2]
    out = {"f0_Hz": float(r.x[0]), "f0_sigma_Hz": float(sd[0]), "Q": float(Q), "Q_sigma": float(Q * math.log(10) * sd[1]),
           "area_m2": float(A * math.pi * r.x[0] * Q / 2), "white_floor": float(10 ** r.x[3]),
           "one_over_f_at_window_start": float(10 ** r.x[4]), "fwhm_bins": float(r.x[0] / Q / bin_width(freq, r.x[0])),
           "chi2_per_dof": chi2 / dof, "points": int(len(fw)), "window_Hz": [float(window[0]), float(window[1])],
           "deviance": chi2}
    if others_masked:
        out["neighbours_masked"] = True
    return out


def fit_lines(freq: np.ndarray, psd: np.ndarray, peaks: list[tuple[int, str]], s_log: float,
              averages: int | None, shape=SHO) -> list[dict]:
    """The lines at the detected peaks (:func:`find_lines`), each first fitted alone (:func:`fit_line`):
    a broad line on the spectrum with the narrow lines notched out (:func:`narrow_lines`: a fit started
    on a mode with a spur on its flank would otherwise wander onto the spur), a narrow line on the data
    held to its bin with the broad lines' fits in its background, a narrow line at a broad one's top on
    the data; then every resolved line again on the data with its neighbours' bins left out and their
    tails in the background (:func:`refit_with_neighbours`)."""
    clean = narrow_lines(psd, s_log, averages)[2]
    first: dict[int, dict] = {}
    for i, kind in peaks:
        if kind != "narrow":
            try:
                first[i] = fit_line(freq, clean if kind == "broad" else psd, i, s_log, averages, shape=shape)
            except ValueError:
                continue
    lines = sum((shape.psd(freq, b["f0_Hz"], b["Q"], _amplitude(b))
                 for b in first.values() if np.isfinite(b["Q"])), np.zeros(len(freq)))
    fits = []
    for i, kind in peaks:
        if kind == "narrow":
            try:
                fits.append(fit_line(freq, psd, i, s_log, averages, narrow=True, lines=lines, shape=shape))
            except ValueError:
                continue
        elif i in first:
            fits.append(first[i])
    return joint_refit(freq, psd, refit_with_neighbours(freq, psd, fits, s_log, averages, shape), s_log, averages,
                       shape)


def refit_with_neighbours(freq, psd, fits: list[dict], s_log: float, averages: int | None, shape=SHO) -> list[dict]:
    """Every resolved line re-fitted with the other detected lines' bins left out and their one-line
    fits' tails in the background (:func:`fit_line` ``others``); unresolved lines (spurs) as they were."""
    out = []
    for ft in fits:
        if ft["fwhm_bins"] < 2.0 or not np.isfinite(ft["Q"]):
            out.append(ft)
            continue
        try:
            out.append(fit_line(freq, psd, int(np.argmin(np.abs(freq - ft["f0_Hz"]))), s_log, averages,
                                others=fits, start=ft, shape=shape))
        except ValueError:
            out.append(ft)
    return out


def coupled_groups(fits: list[dict], shape=SHO) -> list[list[int]]:
    """Groups (by index into ``fits``, two or more) of resolved lines whose fits are coupled: a line's PSD at
    another's centre is more than ``JOINT_TAIL`` of that line's own peak (the lines of one connected component of
    that relation). A one-line fit's white + 1/f background then takes the neighbour's tail -- neither white nor
    1/f across a broad line's window -- for its own (and the one-line fit's background, having absorbed it, cannot
    say how large the tail is: the criterion is against the peak). Sharp lines are not coupled (a line's level
    away from its resonance is 1/Q^2 of its peak: 1e-5 at Q 300 in air); the fluid-damped lines of a lever in a
    liquid are (blind spectrum s19, water, Q 5-16: each line's tails 0.4-1 % of the others' peaks).
    """
    res = [i for i, ft in enumerate(fits) if ft["fwhm_bins"] >= 2.0 and np.isfinite(ft["Q"])]
    link = {i: {i} for i in res}
    for i in res:
        fi = fits[i]["f0_Hz"]
        peak = float(shape.psd(np.array([fi]), fi, fits[i]["Q"], _amplitude(fits[i]))[0])
        for j in res:
            if j != i and float(shape.psd(np.array([fi]), fits[j]["f0_Hz"], fits[j]["Q"], _amplitude(fits[j]))[0]) \
                    > JOINT_TAIL * peak:
                link[i].add(j)
                link[j].add(i)
    groups, seen = [], set()
    for i in res:
        if i in seen:
            continue
        comp, todo = set(), [i]
        while todo:
            k = todo.pop()
            if k not in comp:
                comp.add(k)
                todo.extend(link[k] - comp)
        seen |= comp
        if len(comp) > 1:
            groups.append(sorted(comp))
    return groups


def joint_refit(freq: np.ndarray, psd: np.ndarray, fits: list[dict], s_log: float, averages: int | None,
                shape=SHO) -> list[dict]:
    """The coupled lines (:func:`coupled_groups`) fitted together: their lines and one white + 1/f background
    on the union of their windows, by the same likelihood as :func:`fit_line`, the other lines' fits in the
    background and unresolved lines (spurs) left out. The thermal motions of the modes are independent, so
    their PSDs add; one line fitted with a neighbour's *fitted* tail inherits that fit's error, and where the
    tails are a large part of the spectrum (a lever in water: blind spectrum s19, flapwise 3 at Q 16 read at
    19.7 with chi^2/dof 11) only the joint fit is the model of the spectrum. Every line of a group takes the
    joint fit's centre, Q and area with their standard errors (the Jacobian's, scaled by chi^2/dof when above 1);
    lines in no group are returned as they were."""
    groups = coupled_groups(fits, shape)
    if not groups:
        return fits
    out = list(fits)
    for grp in groups:
        lo = min(fits[i]["window_Hz"][0] for i in grp)
        hi = max(fits[i]["window_Hz"][1] for i in grp)
        sel = (freq >= lo) & (freq <= hi)
        fw, pw = freq[sel], psd[sel]
        keep = np.ones(len(fw), bool)
        tails = np.zeros(len(fw))
        for k, o in enumerate(fits):
            if k in grp:
                continue
            if o["fwhm_bins"] < 2.0 or not np.isfinite(o.get("Q", math.nan)):
                if lo <= o["f0_Hz"] <= hi:  # a spur: its bins left out
                    keep &= np.abs(fw - o["f0_Hz"]) > 6 * bin_width(freq, o["f0_Hz"])
            else:
                tails += shape.psd(fw, o["f0_Hz"], o["Q"], _amplitude(o))
        fw, pw, tails = fw[keep], pw[keep], tails[keep]
        m = len(grp)
        if len(fw) < 3 * m + 2 + 10:
            continue
        first = min(grp, key=lambda i: fits[i]["window_Hz"][0])
        b1 = max(fits[first]["one_over_f_at_window_start"], 1e-300) * fits[first]["window_Hz"][0] / fw[0]
        b0 = float(np.median([fits[i]["white_floor"] for i in grp]))
        u0, lb, ub, xs = [], [], [], []
        for i in grp:
            ft = fits[i]
            w = ft["f0_Hz"] / ft["Q"]
            u0 += [ft["f0_Hz"], math.log10(ft["Q"]), math.log10(_amplitude(ft))]
            lb += [ft["f0_Hz"] - 2 * w, math.log10(ft["Q"]) - 1, math.log10(_amplitude(ft)) - 4]
            ub += [ft["f0_Hz"] + 2 * w, math.log10(ft["Q"]) + 1, math.log10(_amplitude(ft)) + 4]
            xs += [w / 4, 0.3, 0.3]
        u0 += [math.log10(max(b0, 1e-300)), math.log10(b1)]
        lb += [u0[-2] - 6, u0[-1] - 6]
        ub += [u0[-2] + 4, u0[-1] + 4]
        xs += [0.3, 0.3]
        wf0 = fw[0]

        def model(u):
            S = 10 ** u[-2] + 10 ** u[-1] * (wf0 / fw) + tails
            for k in range(m):
                S = S + shape.psd(fw, u[3 * k], 10 ** u[3 * k + 1], 10 ** u[3 * k + 2])
            return S

        def res(u):
            if averages:
                return gamma_deviance_residuals(pw, model(u), averages)
            return (np.log(model(u)) - np.log(np.maximum(pw, 1e-300))) / s_log

        try:
            r = least_squares(res, np.clip(u0, lb, ub), bounds=(lb, ub), x_scale=xs)
        except ValueError:
            continue
        dev = float(np.sum(r.fun**2))
        dof = max(len(fw) - len(u0), 1)
        try:
            cov = np.linalg.pinv(r.jac.T @ r.jac) * max(1.0, dev / dof)
            sd = np.sqrt(np.maximum(np.diag(cov), 0))
        except np.linalg.LinAlgError:
            continue
        for k, i in enumerate(grp):
            f0, Q, A = float(r.x[3 * k]), 10 ** r.x[3 * k + 1], 10 ** r.x[3 * k + 2]
            out[i] = {**fits[i], "f0_Hz": f0, "f0_sigma_Hz": float(sd[3 * k]), "Q": float(Q),
                      "Q_sigma": float(Q * math.log(10) * sd[3 * k + 1]), "area_m2": float(A * math.pi * f0 * Q / 2),
                      "white_floor": float(10 ** r.x[-2]), "one_over_f_at_window_start": float(10 ** r.x[-1]),
                      "fwhm_bins": float(f0 / Q / bin_width(freq, f0)), "chi2_per_dof": dev / dof,
                      "points": int(len(fw)), "window_Hz": [float(fw[0]), float(fw[-1])], "deviance": dev,
                      "joint_with": [float(r.x[3 * j]) for j in range(m) if j != k]}
    return out


def _window(freq: np.ndarray, psd: np.ndarray, line: dict) -> tuple[np.ndarray, np.ndarray]:
    sel = (freq >= line["window_Hz"][0]) & (freq <= line["window_Hz"][1])
    return freq[sel], psd[sel]


def fit_doublet(freq: np.ndarray, psd: np.ndarray, single: dict[str, Any], s_log: float, averages: int | None = None,
                pair: tuple[float, float] | None = None, n_tests: int = 1,
                others: list[dict] | None = None, shape=SHO) -> dict[str, Any] | None:
    """Two SHO lines on the background of ``single`` (a :func:`fit_line` result) in its window, by the
    same likelihood (Gamma deviance of the averaged periodogram, else log-space least squares), and
    the likelihood-ratio test of the two lines against the one.

    Physical reason: two modes of a lever closer than about their line width f0 / Q (flapwise 3 and
    torsion 1 of a clamped lever, a few kHz apart at MHz in air) make ONE peak in the spectrum; fitted
    by one SHO line, the blend has a Q below either mode's and the area of both (equipartition gives
    each mode its own k_B T / k_eff), and its centre is neither mode's. Two SHO lines are the model of
    the thermal motion of two modes (their thermal forces are independent, so the PSDs add).

    The test runs on the pair's core (f0 +- 4 widths) against the one line re-fitted on the same bins,
    both on a white + 1/f background plus the tails of the other detected lines (``others``: their
    one-line fits; peaks inside the core are masked). Each line of the pair is a mode: its centre within
    the one line's centre +- its width (an unresolved pair), Q >= the one line's Q / 1.5 (the components
    of a blend are narrower than the blend) and resolved (width >= 2 bins). The second line has 3
    parameters (centre, Q, area); the split is kept when the deviance drops by more than the chi^2_3
    quantile at 1 - ALPHA / (DOUBLET_PLACES n_tests): the engine's level over the peaks tested and
    over the independent places of the second line's centre (undefined under one line: the
    look-elsewhere effect). Measured false-split rate on single lines: ``tests/test_diagnose_doublet.py``.
    ``pair``: the predicted pair's frequencies (the hypothesis' modes in the window, after its scale),
    used as one start.

    Returns None if the split is not supported; else ``{"lines": [two fit_line-like dicts, low
    frequency first], "lr": ..., "threshold": ..., "rho_f": correlation of the centres}``. Each centre's
    sigma is its profile-likelihood half-width (:func:`_profile_sigma`) times sqrt(1 + |rho|): an unresolved pair's centres are
    correlated (the mean is fixed by the data far better than the split), the modal fit takes
    independent rows, and sigma_i^2 (1 + |rho|) on the diagonal bounds the 2 x 2 covariance from above
    (D - C is positive semi-definite), so a pair's chi-square is never counted with more precision
    than the data carry."""
    from probedyn.diagnose.tails import chi2 as chi2_dist

    from probedyn.diagnose.engine import ALPHA

    if single.get("fwhm_bins", 0.0) < 2.0 or not np.isfinite(single.get("Q", math.nan)):
        return None
    fw, pw = _window(freq, psd, single)
    f0, Q0 = single["f0_Hz"], single["Q"]
    fwhm = f0 / Q0
    # other detected peaks inside the window (a resolved neighbour mode): their bins (+- 3 of their
    # widths) are left out of both fits, else the second line would be spent on a neighbour's flank
    # the test's bins: the pair's core, f0 +- 4 widths (the pair lies within +- 1 width; a line's shape
    # beyond 4 widths carries little of it, and far from the peak a neighbour's flank would dominate)
    keep = np.abs(fw - f0) <= 4 * fwhm
    for o in others or ():
        # a resolved line within the width is the pair's own; an unresolved one (a spur) is left out wherever it is
        if o is single or (abs(o["f0_Hz"] - f0) < fwhm and o.get("fwhm_bins", 0.0) >= 2.0):
            continue
        wo = 3 * max(o["f0_Hz"] / o["Q"] if np.isfinite(o.get("Q", math.nan)) else 0.0, 2 * bin_width(freq, o["f0_Hz"]))
        keep &= np.abs(fw - o["f0_Hz"]) > wo
    fw, pw = fw[keep], pw[keep]
    if len(fw) < 12:
        return None
    df = bin_width(freq, f0)
    # the other detected lines' tails (their one-line fits) are part of the background of both fits: a
    # neighbour mode's flank rises across the window, which white + 1/f (falling) cannot follow, and a
    # second line would otherwise be spent on it
    tails = np.zeros(len(fw))
    for o in others or ():
        if o is not single and np.isfinite(o.get("Q", math.nan)) and abs(o["f0_Hz"] - f0) >= fwhm:
            tails += shape.psd(fw, o["f0_Hz"], o["Q"], _amplitude(o))
    A0 = _amplitude(single)  # the line's amplitude
    B0, B1 = single["white_floor"], single["one_over_f_at_window_start"]

    def model(u):
        return (shape.psd(fw, u[0], 10 ** u[2], 10 ** u[4]) + shape.psd(fw, u[1], 10 ** u[3], 10 ** u[5])
                + 10 ** u[6] + 10 ** u[7] * (fw[0] / fw) + tails)

    def res(u):
        if averages:
            return gamma_deviance_residuals(pw, model(u), averages)
        return (np.log(model(u)) - np.log(np.maximum(pw, 1e-300))) / s_log

    # the one line re-fitted on these bins with the neighbours' tails (the nested model: the second
    # line's area -> 0), with its Q free as in fit_line: the first fit's Q may be biased by a neighbour
    # mode's flank, and the pair's Q bounds below are relative to this one line
    ql_hi = max(math.log10(f0 / (2 * df)), math.log10(Q0))
    b1_lo = [f0 - fwhm, math.log10(0.5), math.log10(A0) - 6, math.log10(B0) - 4, math.log10(max(B1, 1e-300)) - 4]
    b1_hi = [f0 + fwhm, ql_hi, math.log10(A0) + 3, math.log10(B0) + 2, math.log10(max(B1, 1e-300)) + 2]

    def res1(v):
        return res(np.array([v[0], v[0], v[1], v[1], v[2], v[2] - 12, v[3], v[4]]))

    r1 = least_squares(res1, np.clip([f0, math.log10(Q0), math.log10(A0), math.log10(B0), math.log10(max(B1, 1e-300))],
                                     b1_lo, b1_hi), bounds=(b1_lo, b1_hi), x_scale=[fwhm / 4, 0.3, 0.3, 0.3, 0.3])
    dev1 = float(np.sum(r1.fun**2))
    f0, Q0, A0, B0, B1 = float(r1.x[0]), 10 ** r1.x[1], 10 ** r1.x[2], 10 ** r1.x[3], 10 ** r1.x[4]
    fwhm = f0 / Q0
    lq = math.log10(Q0)
    # each line of a pair is a mode of this lever: at least about as narrow as the blend of the two
    # (Q >= Q0 / 1.5, the one line's Q with room for its scatter) -- a broad low line would be
    # background, not a mode -- and resolved (width >= 2 bins, as for a labelled line: a narrower
    # second line is a spur or one bin's scatter, and its Q could not be measured)
    q_lo, q_hi = lq - math.log10(1.5), max(min(lq + 1.5, math.log10(f0 / (2 * df))), lq)
    lo = [f0 - fwhm, f0 - fwhm, q_lo, q_lo, math.log10(A0) - 6, math.log10(A0) - 6,
          math.log10(B0) - 4, math.log10(max(B1, 1e-300)) - 4]
    hi = [f0 + fwhm, f0 + fwhm, q_hi, q_hi, math.log10(A0) + 3, math.log10(A0) + 3,
          math.log10(B0) + 2, math.log10(max(B1, 1e-300)) + 2]
    starts = []
    seps = [0.5 * fwhm, 0.25 * fwhm]
    if pair is not None and 0 < abs(pair[1] - pair[0]) < 2 * fwhm:
        seps.insert(0, abs(pair[1] - pair[0]))
    for d in seps:
        for w in (0.7, 0.3):  # share of the (blend's) peak height of the lower line
            # a blend of two lines of Q_i is broader than either: each line is narrower (Q up to ~2 Q0)
            q = lq + math.log10(1.6)
            starts.append([f0 - d / 2, f0 + d / 2, q, q, math.log10(A0 * w / 1.6**2), math.log10(A0 * (1 - w) / 1.6**2),
                           math.log10(B0), math.log10(max(B1, 1e-300))])
    # the single line with a vanishing second one: the two-line fit nests the one-line fit
    starts.append([f0, f0, lq, lq, math.log10(A0), math.log10(A0) - 5.9, math.log10(B0), math.log10(max(B1, 1e-300))])
    best = None
    for u0 in starts:
        u0 = np.clip(u0, np.array(lo) + 1e-12 * np.abs(lo), np.array(hi) - 1e-12 * np.abs(hi))
        try:
            r = least_squares(res, u0, bounds=(lo, hi), x_scale=[fwhm / 4, fwhm / 4, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3])
        except ValueError:
            continue
        if best is None or r.cost < best.cost:
            best = r
    if best is None:
        return None
    dev2 = float(np.sum(best.fun**2))
    lr = dev1 - dev2
    # the level: ALPHA over the peaks tested and over the independent places the second line can take
    # (its centre ranges over 2 widths, resolved to about half a width: 4), the look-elsewhere effect
    # of a parameter (the centre) that is undefined under the one-line hypothesis
    thr = float(chi2_dist.ppf(1 - ALPHA / (DOUBLET_PLACES * max(n_tests, 1)), 3))
    if not lr > thr:
        return None
    dof = max(len(fw) - 8, 1)
    scale = max(1.0, dev2 / dof)
    try:
        cov = np.linalg.pinv(best.jac.T @ best.jac) * scale
    except np.linalg.LinAlgError:
        return None
    sd = np.sqrt(np.maximum(np.diag(cov), 0))
    rho = float(cov[0, 1] / (sd[0] * sd[1])) if sd[0] > 0 and sd[1] > 0 else 0.0
    u = best.x
    # the centres' sigmas from the profile likelihood (deviance up by `scale`, i.e. 1 sigma): the
    # split of an unresolved pair is poorly determined and its likelihood is far from quadratic (the
    # blend fixes mostly the second moment, ~ separation^2), so the curvature at the optimum
    # understates it (measured: pulls of rms ~1.8 with the Hessian's sigma)
    sd_f = [_profile_sigma(res, u, k, lo, hi, dev2, scale, max(sd[k], fwhm / 200)) for k in (0, 1)]
    lines = []
    for k in (0, 1):
        f, Q, A = float(u[k]), 10 ** u[2 + k], 10 ** u[4 + k]
        lines.append({"f0_Hz": f, "f0_sigma_Hz": float(sd_f[k] * math.sqrt(1 + abs(rho))),
                      "f0_sigma_marginal_Hz": float(sd_f[k]), "Q": float(Q),
                      "Q_sigma": float(Q * math.log(10) * sd[2 + k]), "area_m2": float(A * math.pi * f * Q / 2),
                      "white_floor": float(10 ** u[6]), "one_over_f_at_window_start": float(10 ** u[7]),
                      "fwhm_bins": float(f / Q / bin_width(freq, f)), "chi2_per_dof": dev2 / dof, "points": int(len(fw)),
                      "window_Hz": list(single["window_Hz"]), "deviance": dev2})
    lines.sort(key=lambda x: x["f0_Hz"])
    return {"lines": lines, "lr": lr, "threshold": thr, "rho_f": rho, "single": {
        "f0_Hz": f0, "Q": Q0, "area_m2": A0 * math.pi * f0 * Q0 / 2}}


def _profile_sigma(res, u: np.ndarray, k: int, lo, hi, dev: float, scale: float, h0: float) -> float:
    """Half-width (the larger side) of the interval of parameter ``k`` where the profile deviance
    (the other parameters re-fitted) stays within ``scale`` of the optimum ``dev``."""
    free = [j for j in range(len(u)) if j != k]

    def prof(x):
        def r(v):
            w = np.array(u, float)
            w[free] = v
            w[k] = x
            return res(w)
        v0 = np.clip(np.asarray(u)[free], np.array(lo)[free], np.array(hi)[free])
        rr = least_squares(r, v0, bounds=(np.array(lo)[free], np.array(hi)[free]))
        return float(np.sum(rr.fun**2))

    widths = []
    for sgn in (-1.0, 1.0):
        h, prev_h, prev_d = h0, 0.0, 0.0
        w = None
        for _ in range(8):
            x = u[k] + sgn * h
            if not lo[k] <= x <= hi[k]:
                w = abs(np.clip(x, lo[k], hi[k]) - u[k])  # the bound: the interval reaches it
                break
            d = max(prof(x) - dev, 0.0) / scale
            if d >= 1.0:
                # sqrt of the profile deviance is ~linear in the distance: interpolate to 1
                a, b = math.sqrt(prev_d), math.sqrt(d)
                w = prev_h + (h - prev_h) * (1.0 - a) / max(b - a, 1e-12)
                break
            prev_h, prev_d = h, d
            h *= 2.0
        widths.append(h if w is None else w)
    return float(max(widths))


def _line_shape(freq: np.ndarray, medium, base: FEMBaseline, preds: list[dict]):
    """The lines' shape (:mod:`~probedyn.diagnose.lineshape`): fluid-loaded in a declared medium that loads the
    probe's flapwise modes (with the first flapwise mode's mass ratio from the FEM), else the SHO."""
    a = next((p["mass_ratio"] for p in preds if p["family"] == "flapwise" and p.get("mass_ratio")), None)
    if medium is None or a is None or not medium[0] > 0:
        return SHO
    return FluidLine(freq, base.w, medium[0], medium[1], a)


#: the step of the optical lever's slope difference, a fraction of the length (a one-sided second-order difference
#: of the quadratic elements' field: its error ~ (step x wavenumber)^2, 1e-5 at flapwise 6)
SLOPE_STEP = 1e-3
#: a mode whose recorded amplitude is below this fraction of its largest displacement component at the tip is not
#: seen by the detector (no thermal area test: the displacement detector's infinite k_eff along z)
UNSEEN = 1e-3


def optical_lever_gains(base: FEMBaseline, spot: float = 1.0) -> np.ndarray:
    """Per FEM mode of ``base``, what an optical lever records per unit of the (mass-normalised) modal coordinate:
    the lever's slope ``dw/dx`` at the laser spot (``x_s = spot L`` on the lever's centre line, where a spot sees no
    twist) times the calibration of its signal as a deflection, the static end load's ``w(L) / w'(x_s) =
    2 L^3 / (3 (2 L x_s - x_s^2))`` (an InvOLS measured by pressing the tip on a hard surface; Euler-Bernoulli).
    Flapwise mode n's thermal area is then ``k_B T gain_n^2 / omega_n^2``, not the displacement detector's ``k_B T /
    k_eff``: the ratio ``gain_n / w_n(L)`` is 0.918 for flapwise 1 at the free end (Butt & Jaschke 1995: the
    optical lever's 0.817 k_B T / <z*^2> against 0.971 k_B T / <z^2>) and grows about as 2 n (flapwise 5: 9.4), so
    the areas of a lever's higher modes differ from a displacement detector's by up to two decades."""
    m, ax, ta = base.model, base.length_axis, base.thickness_axis
    x0 = float(m.mesh.p[ax].min())
    L = base.L
    xs = x0 + min(spot, 1.0 - 1e-9) * L
    d = SLOPE_STEP * L
    u = []
    for k in range(3):  # backward: the spot may be at the free end
        q = np.array(base.clamp_centroid, dtype=float)
        q[ax] = xs - k * d
        u.append(np.asarray(m.attachment(q)[ta] @ base.shapes).ravel())
    slope = (3 * u[0] - 4 * u[1] + u[2]) / (2 * d)
    xl = xs - x0
    return slope * 2 * L**3 / (3 * (2 * L * xl - xl**2))


def _predictions(base: FEMBaseline, medium, temperature, detector: str = "displacement",
                 spot: float = 1.0) -> list[dict[str, Any]]:
    out = []
    gains = optical_lever_gains(base, spot) if temperature and detector == "optical-lever" else None
    cnt: dict[str, int] = {}
    rho_f, eta_f = medium if medium is not None else (0.0, 1.8e-5)
    loaded = rho_f > 0 and base.has_top
    if loaded:  # the fluid's load: Sader's on the flapwise modes, Green & Sader's on torsion, the Stokes layers on lateral
        K, M = base.model.assemble()
        Stop, Sw = top_face_forms(base.model, base.thickness_axis, base.width_axis)
    for md in base.result.modes:
        fa = md.family
        cnt[fa] = cnt.get(fa, 0) + 1
        item = {"family": fa, "order": cnt[fa], "f_Hz": md.frequency_hz, "Q_fluid": math.inf,
                "k_eff_z": md.effective_stiffness_tip.get("z", math.inf)}
        a = md.shape
        if loaded and fa in ("flapwise", "torsion"):
            mq, sq = float(a @ (M @ a)), float(a @ (Stop @ a))
            f, Q, _ = _fluid_mode(float(a @ (K @ a)), mq, sq, md.omega, base.w, rho_f, eta_f, 1.0, math.inf,
                                  torsion=fa == "torsion")
            item.update(f_Hz=f, Q_fluid=Q)
            if fa == "flapwise":  # the fluid's inviscid added mass over the mode's own (the line shape's a)
                item["mass_ratio"] = 0.25 * math.pi * rho_f * base.w * sq / mq
        elif loaded and fa == "lateral":
            f, Q = _stokes_mode(float(a @ (K @ a)), float(a @ (M @ a)), float(a @ (Sw @ a)), md.omega, rho_f, eta_f,
                                1.0, math.inf)
            item.update(f_Hz=f, Q_fluid=Q)
        if temperature and gains is not None:  # an optical lever: the slope at the spot, as calibrated
            g = float(gains[len(out)])
            seen = abs(g) > UNSEEN * float(np.max(np.abs(md.tip_displacement))) and md.omega > 0
            item["thermal_area_m2"] = K_B * temperature * g * g / md.omega**2 if seen else 0.0
        elif temperature:
            k = item["k_eff_z"]
            item["thermal_area_m2"] = K_B * temperature / k if np.isfinite(k) and k > 0 else 0.0
        out.append(item)
    return out


def _best_scale(peaks: list[float], preds: list[float], span: float = 2.0) -> float:
    """The frequency scale in [1/span, span] that maps the most predictions onto peaks within
    MATCH_TOL (ties: the scale nearest 1)."""
    cands = [p / q for p in peaks for q in preds if 1 / span <= p / q <= span] or [1.0]
    best, best_key = 1.0, None
    for s in cands:
        n = sum(any(abs(p / (s * q) - 1) < MATCH_TOL for q in preds) for p in peaks)
        key = (n, -abs(math.log(s)))
        if best_key is None or key > best_key:
            best, best_key = s, key
    return best


def _match(fits: list[dict], f_pred: list[float], s: float) -> dict[int, int]:
    """The peaks placed on distinct predicted modes within MATCH_TOL after the common scale ``s``, one to
    one: ``{peak index: mode index}``, the most resolved peaks placed, then the most peaks, then the
    smallest sum of |ln f_peak / (s f_mode)| (an optimal assignment, :func:`scipy.optimize.linear_sum_assignment`).
    Nearest-first (each peak, larger areas first, to its nearest mode if free) leaves a peak out where two
    modes are close: blind spectrum s18 (session 47), a <110> silicon lever's torsion 10.6 % low, 1.7 % above
    lateral 1; under the crystal hypothesis nearest to both, the stronger torsion line took lateral 1's label,
    the lateral line found it taken, and the hypothesis placed three peaks where it places four."""
    from scipy.optimize import linear_sum_assignment

    n, m = len(fits), len(f_pred)
    if not n or not m:
        return {}
    d = np.full((n, m), np.inf)
    for i, ft in enumerate(fits):
        for j, f in enumerate(f_pred):
            if f > 0:
                d[i, j] = abs(math.log(ft["f0_Hz"] / (s * f)))
    ok = d < MATCH_TOL
    bonus = np.array([(n + 1.0) if ft["fwhm_bins"] >= 2.0 else 1.0 for ft in fits])[:, None]
    cost = np.where(ok, np.where(ok, d, 0.0) - bonus, 0.0)
    rows, cols = linear_sum_assignment(cost)
    return {int(i): int(j) for i, j in zip(rows, cols) if ok[i, j]}


def _matches(fits: list[dict], f_pred: list[float], s: float) -> tuple[int, int, float]:
    """Resolved and all peaks placed on distinct predicted modes (:func:`_match`) after the common scale
    ``s``, and the sum of their squared log deviations."""
    a = _match(fits, f_pred, s)
    n_res = sum(fits[i]["fwhm_bins"] >= 2.0 for i in a)
    return n_res, len(a), float(sum(math.log(fits[i]["f0_Hz"] / (s * f_pred[j])) ** 2 for i, j in a.items()))


def _refined_grids(params, move, max_values: int) -> list[list[float]]:
    """Values of a cause's parameters for the identification hypotheses, refined where the modes move.

    Each parameter starts at its null and its bounds; an interval between neighbouring values is
    subdivided (in the parameter's fitted coordinate: linear, or log10 for a log-scaled one) while the
    hypotheses at its ends -- at every combination of the other parameters' current values -- place
    some mode more than ``2 MATCH_TOL`` apart in frequency (``move``: the largest |ln f_a / f_b| over
    the modes), so that a peak passed by a mode between two neighbours lies within MATCH_TOL of one of
    them. The frequencies are not linear in a parameter -- a compressive stress lowers flapwise 1 as
    sqrt(1 - sigma / sigma_cr), steeply near buckling; a tip mass as 1 / sqrt(1 + m / m_eff) -- so a
    fixed grid is either too coarse where they move fast or wasteful where they do not. At most
    ``max_values`` values per parameter (the widest moves are refined first)."""
    grids = []
    for p in params:
        g = sorted({p.lo, p.null, p.hi})
        grids.append([x for x in g])
    for _round in range(12):
        added = False
        for j, p in enumerate(params):
            if len(grids[j]) >= max_values:
                continue
            others = [grids[i] if i != j else [None] for i in range(len(params))]
            gaps = []
            for a, b in zip(grids[j][:-1], grids[j][1:]):
                worst = 0.0
                for combo in itertools.product(*others):
                    va = [a if x is None else x for x in combo]
                    vb = [b if x is None else x for x in combo]
                    worst = max(worst, move(va, vb))
                if worst > 2 * MATCH_TOL:
                    gaps.append((worst, a, b))
            room = max_values - len(grids[j])
            for worst, a, b in sorted(gaps, reverse=True):
                # as many evenly spaced values as the move needs at its average rate (the next round
                # refines where the rate is not even)
                m = min(int(math.ceil(worst / (2 * MATCH_TOL))) - 1, room)
                if m <= 0:
                    break
                ua, ub = p.to_u(a), p.to_u(b)
                grids[j] += [float(p.from_u(ua + (ub - ua) * q / (m + 1))) for q in range(1, m + 1)]
                room -= m
                added = True
            grids[j].sort()
        if not added:
            break
    return grids


def _hypotheses(meas: SpectrumData, base: FEMBaseline, preds: list[dict]) -> list[dict]:
    """Mode frequencies of the nominal probe (``preds``) and of the probe carrying each catalog cause
    the declared conditions allow, at parameter values refined where the modes move
    (:func:`_refined_grids`, products for two parameters; a third stays at its null value), from the Ritz
    reduction of the FEM as ratios
    to its nominal solution (exact at the null). A hidden effect moves the families differently -- a
    width error moves lateral and torsional modes only, a clamp compliance or a compressive stress
    mostly the first flapwise mode -- so one common scale cannot place every peak, and the nearest
    nominal mode may be another family's; the labels are those of the hypothesis that makes the most
    peaks modes."""
    out = [{"cause": None, "values": {}, "f_Hz": [p["f_Hz"] for p in preds]}]
    idx = [i for i, p in enumerate(preds) if p["family"] in FAMILIES]
    if not idx:
        return out
    L = float(meas.probe_values["length"]) if "length" in meas.probe_values else None
    n = len(idx)
    fam = np.array([preds[i]["family"] for i in idx])
    order = np.array([preds[i]["order"] for i in idx])
    f0 = np.array([preds[i]["f_Hz"] for i in idx])
    md = ModalData(path=meas.path, kind="modal", meta=meas.meta, description=meas.description, medium=meas.medium,
                   medium_name=meas.medium_name, temperature=meas.temperature, known=meas.known, free=(),
                   probe=meas.probe, probe_values=meas.probe_values, family=fam, order=order, freq=f0,
                   freq_sigma=1e-3 * f0, Q=np.full(n, np.nan), Q_sigma_rel=np.full(n, np.nan),
                   length=np.full(n, meas.probe_values.get("length", np.nan)), known_mass=meas.known_mass,
                   noise_stated=True)
    prob = ModalProblem(md, bases={L: base})
    try:
        ref, _ = prob.predict({})
    except Exception:  # noqa: BLE001 -- a probe the reduction cannot handle: nominal labels only
        return out
    for c in prob.causes:
        cache: dict[tuple, np.ndarray | None] = {}

        def ratios(vals, _c=c, _cache=cache):
            key = tuple(float(x) for x in vals)
            if key not in _cache:
                v = {p.name: x for p, x in zip(_c.params, key)}
                try:
                    fh, _ = prob.predict(v, (_c,))
                    r = fh / ref
                    _cache[key] = r if np.all(np.isfinite(r)) and np.all(r > 0) else None
                except Exception:  # noqa: BLE001 -- a value outside what the reduction solves
                    _cache[key] = None
            return _cache[key]

        def move(va, vb):
            ra, rb = ratios(va), ratios(vb)
            if ra is None or rb is None:
                return 0.0
            return float(np.max(np.abs(np.log(ra / rb))))

        # a cause's first two parameters span its hypotheses; a third (the bonded overlap's length, which matters
        # only on a soft bond) stays at its null value: a product of three refined grids is hundreds of solves
        nulls = [p.null for p in c.params]
        grids = _refined_grids(list(c.params[:2]), lambda va, vb: move([*va, *nulls[2:]], [*vb, *nulls[2:]]),
                               MAX_GRID_1D if len(c.params) == 1 else MAX_GRID_2D) + [[x] for x in nulls[2:]]
        for vals in itertools.product(*grids):
            if list(vals) == nulls:
                continue
            r = ratios(vals)
            if r is None:
                continue
            f_all = [p["f_Hz"] for p in preds]
            for k, i in enumerate(idx):
                f_all[i] = preds[i]["f_Hz"] * r[k]
            out.append({"cause": c.key, "values": {p.name: float(x) for p, x in zip(c.params, vals)}, "f_Hz": f_all})
    return out


def spectrum_problem(meas: SpectrumData, base: FEMBaseline | None = None) -> ModalProblem:
    """Identify the peaks of a spectrum against the probe's FEM and return the modal problem of
    the accepted ones (with the peak table for the report). ``base``: the probe's FEM baseline when
    already built (spectra of one probe share it and its reduction)."""
    freq, psd = meas.freq, meas.value
    s_log = log_scatter(psd, meas.averages)
    df = float(np.median(np.diff(freq)))
    peaks = find_lines(freq, psd, s_log, averages=meas.averages)
    if not peaks:
        raise DataFormatError(f"{meas.path}: no peak stands out of the spectrum's background by 5 standard deviations")
    if base is None:
        base = FEMBaseline(meas.probe, meas.probe_values, {"flapwise": 2})
    preds = _predictions(base, meas.medium, meas.temperature, meas.detector, meas.spot)
    shape = _line_shape(freq, meas.medium, base, preds)
    fits = fit_lines(freq, psd, peaks, s_log, meas.averages, shape)
    hint = list(meas.families)
    fam_ok = (lambda fa: fa in hint) if hint else (lambda fa: fa == "flapwise")
    L = float(meas.probe_values["length"]) if "length" in meas.probe_values else None
    # the labels: the hypotheses (the nominal probe, or a catalog cause at a grid value) under which
    # the most resolved peaks are modes (within MATCH_TOL after a common scale), see _hypotheses
    hyps = _hypotheses(meas, base, preds)

    def _score(fits):
        scored = []
        for h in hyps:
            fh = h["f_Hz"]
            pf = [f for f, p in zip(fh, preds) if fam_ok(p["family"])]
            # the nominal probe may be off by up to 2x (geometry); a cause hypothesis is a specific
            # deviation, on top of which only the uniform uncertainty of the nominal material and
            # geometry (CAUSE_SCALE) is left -- else a cause at its bound times a 2x scale relabels
            # flapwise 2 as flapwise 1 on a two-peak spectrum, and both labellings fit exactly
            sh = (_best_scale([f["f0_Hz"] for f in fits], pf, 2.0 if h["cause"] is None else CAUSE_SCALE)
                  if pf else 1.0)
            n_res, n_all, dev2 = _matches(fits, fh, sh)
            # only resolved lines count: unresolved ones are spurs or frequency-only modes, and with
            # many hypotheses some place a spur on a mode (a spur labelled torsion 1 moved the real
            # torsion onto lateral 2 and flapwise 3 onto axial 1 in a noise-only spectrum)
            scored.append(((n_res,), (round(abs(math.log(sh)) / 0.01), round(dev2 / MATCH_TOL**2, 2),
                                      h["cause"] is not None), h, sh))
        return scored

    scored = _score(fits)
    # unresolved doublets: a peak whose matching window holds two predicted modes under a competing
    # hypothesis may be both (two modes closer than their line width make one peak); the two-line
    # fit is kept where the line shape demands it (fit_doublet: likelihood-ratio test at the
    # engine's level over the peaks tested), and its lines then compete as two peaks
    split = _split_doublets(freq, psd, fits, scored, preds, s_log, meas.averages, shape)
    if split is not None:
        fits = split
        scored = _score(fits)
    top = max(k for k, *_ in scored)
    # every hypothesis placing the most resolved peaks proposes a labelling, by how closely it places
    # the peaks, and the nominal probe's labelling always competes (first), however many peaks it
    # places. Where labellings differ (a peak that is torsion 1 under a length error and lateral 2
    # under the nominal probe after a common scale; a torsion lowered by a soft clamp that no
    # hypothesis places, labelled flapwise 3 under a point mass that places every peak),
    # frequencies alone cannot decide: the labelling with the best goodness of fit -- its best model
    # (the baseline, or one catalog cause penalised by its likelihood-ratio threshold) plus the price
    # of the resolved lines it leaves unlabelled -- is taken (see _labelling_score, _unlabelled_price).
    # Counting placed peaks first would let a labelling win by placing a peak wrongly; scoring alone
    # would let a labelling win by leaving out a peak that no catalog model fits well (below)
    cands = [scored[0], *sorted((x for x in scored[1:] if x[0] == top), key=lambda x: x[1])]
    distinct: dict[tuple, tuple] = {}
    for _, _, h, sh in cands:
        preds_h = [dict(p, f_Hz=f) for p, f in zip(preds, h["f_Hz"])]
        tab = _label_table(meas, fits, preds_h, sh)
        # where nearest-first leaves a line out that the hypothesis' one-to-one placement labels (two close
        # modes, the stronger line nearest to the other's), the hypothesis' labelling is that placement
        force = _match(fits, h["f_Hz"], sh)
        if len(force) > sum(t["accepted"] for t in tab):
            tab_f = _label_table(meas, fits, preds_h, sh, force=force)
            if sum(t["accepted"] for t in tab_f) > sum(t["accepted"] for t in tab):
                tab = tab_f
        lab = tuple((t["family"], t["order"]) if t["accepted"] else None for t in tab)
        distinct.setdefault(lab, (lab, tab, h, sh))
    # a labelling that agrees with another on every peak it labels and only leaves out lines the other
    # places (each within the window of its predicted mode) does not compete: it proposes no other
    # label for any line, it only deletes data, and a worse fit of the placed line is evidence about
    # the model (a cause, an undeclared medium), which the modal engine judges, not about the labels
    # (an undeclared air load moves flapwise 3 of a thin lever by ~3 %: dropping it halves the
    # baseline's chi-square and would hide the very discrepancy to be diagnosed). Only the deletion
    # of lines whose shape says they are modes (resolved, plausible Q and area: ``_mode_line``)
    # counts: an unresolved line is a spur or a mode whose Q the spectrum cannot measure, which the
    # labelling that leaves it out explains as well (it costs nothing in _unlabelled_price), so that
    # labelling competes (a spur placed on lateral 1 under a width error must not remove the nominal
    # labels flapwise 1 and 2 that leave the spur out)
    def _sub(a: tuple, b: tuple) -> bool:
        tab_b = distinct[b][1]
        return a != b and all(x is None or x == y for x, y in zip(a, b)) and all(
            t["_mode_line"] for x, y, t in zip(a, b, tab_b) if x is None and y is not None)

    labs = list(distinct)
    options = [distinct[a] for a in labs if not any(_sub(a, b) for b in labs)][:1 + MAX_LABELLINGS]
    # where two or more predicted modes lie within one peak's matching window (or two peaks compete
    # for the same modes), nearness cannot label them: the line centre, the calibration and the
    # model-form floor make the predicted frequencies uncertain by about the spacing of the modes
    # (torsion 1 and flapwise 3 of a lever 0.9 % apart, lateral 2 in the same window), and under a
    # hidden effect that moves the families differently the nearest mode is not the true one. Every
    # one-to-one assignment of those peaks to those modes is proposed as a labelling (at most
    # MAX_ASSIGNMENTS per labelling, the closest first) and the goodness of fit of the whole set
    # decides, as between hypotheses; each assigns every peak the labelling assigns there (no
    # deletion), so the nominal labelling and the declared-probe prior below still apply
    seen_labs = {o[0] for o in options}
    extra = []
    for lab0, tab0, h, sh in list(options):
        preds_h = [dict(p, f_Hz=f) for p, f in zip(preds, h["f_Hz"])]
        for force in _assignments(fits, tab0, preds_h, sh):
            tab = _label_table(meas, fits, preds_h, sh, force=force)
            lab = tuple((t["family"], t["order"]) if t["accepted"] else None for t in tab)
            if lab not in seen_labs and sum(x is not None for x in lab) >= sum(x is not None for x in lab0):
                seen_labs.add(lab)
                extra.append((lab, tab, h, sh))
    options = options + extra
    # a labelling that places no peak is no reading of the spectrum: it fits nothing and, where every line is
    # unresolved (priced at nothing), it would always score best -- it competes only if no labelling places a
    # peak (the tip-motion example: two unresolved flapwise lines, labelled "not a mode" by a hypothesis
    # 44 % stiffer, whose empty fit scored 0 against the nominal labels' few chi-square units)
    placed = [o for o in options if any(t["accepted"] for t in o[1])]
    if placed:
        options = placed
    from probedyn.diagnose.engine import EVIDENCE_MARGIN

    scores: list[tuple[float, str | None, dict]] = []
    ambiguous = []
    nominal_first = options[0][2]["cause"] is None
    if len(options) > 1:
        scores = _labelling_scores(meas, options, base, L)
        order_ = np.argsort([x[0] for x in scores])
        k = int(order_[0])
        # the declared probe is prior information: labels that contradict its nominal ones must be
        # demanded by the data (a better score by more than twice the evidence margin), not merely
        # allowed (with two peaks a heavy point mass relabels flapwise 1 as lateral 1 and fits too)
        if nominal_first and scores[0][0] - scores[k][0] < 2 * EVIDENCE_MARGIN:
            k = 0
            order_ = [0]
    else:
        k = 0
    _, table, best, s = options[k]
    if len(options) > 1:
        # labellings whose scores are within twice the engine's evidence margin of the best one are
        # as likely. If their best models differ, the peaks they label differently are left out (a
        # wrong label would be explained by a wrong cause). If every such labelling is best explained
        # by the same model (both by a width error: lateral 1 and torsion 1 swapped, at two width
        # ratios), the cause does not depend on the labels: the best labelling is kept and the
        # ambiguity reported with the other labelling's parameters
        close = [int(j) for j in order_[1:] if scores[j][0] - scores[k][0] < 2 * EVIDENCE_MARGIN]
        same = all(scores[j][1] == scores[k][1] for j in close)
        for j in close:
            diff = [(i, lab_j) for i, (t, lab_j) in enumerate(zip(table, options[j][0]))
                    if ((t["family"], t["order"]) if t["accepted"] else None) != lab_j]
            if not diff:
                continue
            ambiguous.append({"labels": [(f"{x[0]} {x[1]}" if x else None) for x in options[j][0]],
                              "score": scores[j][0], "best_model": scores[j][1] or "baseline",
                              "parameters": scores[j][2]})
            for i, lab_j in diff:
                t = table[i]
                here = (t["family"], t["order"]) if t["accepted"] else None
                other = f"{lab_j[0]} {lab_j[1]}" if lab_j else "not a mode"
                if here is None:
                    continue
                msg = (f"ambiguous: {here[0]} {here[1]} or {other} (the modal fits of the two labellings "
                       f"differ by {scores[j][0] - scores[k][0]:.3g} < {2 * EVIDENCE_MARGIN:g})")
                if same:
                    t.setdefault("notes", []).append(msg + f"; both best explained by {scores[k][1] or 'the baseline'}: "
                                                     "label kept")
                else:
                    t["accepted"] = False
                    t["reasons"] = [msg]
                    t["family"] = t["order"] = None
    acc = [t for t in table if t["accepted"]]
    if not acc:
        raise DataFormatError(f"{meas.path}: none of the {len(table)} peaks is a mode of the probe model "
                              f"({'; '.join(r for t in table for r in t['reasons'][:1])})")
    # the labels are settled on the identification mesh; the fit is made on the mesh whose estimated
    # discretisation error of every accepted peak is at most DISC_NOISE_FRACTION of that peak's
    # frequency uncertainty (the modal problem's rule for its stated noise, within the same DOF
    # budget): the peaks' uncertainties are known only once they are labelled
    fit_base = base.refined(_peak_noise(meas, table))
    prob = _modal_problem(meas, table, fit_base, L)
    prob.kind = meas.kind
    prob.identification_baseline = base
    # the folds start from the null and from the full-data optimum (ModalProblem.cv_warm: a point mass
    # fitting five modes to chi2 5.9 had lost its held-out evidence to a modulus error at chi2 162)
    c_cal = table[0].get("_c_cal") if table else None
    for t in table:
        t.pop("_c_cal", None)
        t.pop("_mode_line", None)
        t.pop("_thermal_line", None)
    # the frequency scale reported is the nominal probe's (measured / nominal frequencies of the
    # matched modes); the labels may come from a hypothesis with its own scale s
    s_nominal = scored[0][3]
    prob.peaks = {"log_scatter": s_log, "resolution_Hz": df, "frequency_scale": s_nominal, "peaks": table,
                  "line_shape": shape.name, "joint_fits": sum(1 for t in table if t.get("joint_with")),
                  "labels_from": {"hypothesis": best["cause"] or "nominal probe", "values": best["values"], "scale": s,
                                  "hypotheses_tried": len(hyps), "labellings_compared": len(options),
                                  "labelling_scores": [x[0] for x in scores] or None,
                                  "labelling_models": [x[1] or "baseline" for x in scores] or None,
                                  "ambiguous_labellings": ambiguous or None,
                                  "note": "the hypothesis that placed the peaks on modes (labels only, not a diagnosis)"},
                  "thermal_area_factor": c_cal,
                  "detector": meas.detector if meas.detector != "optical-lever" else f"optical-lever (spot {meas.spot:g} L)"}
    prob.extra_report = lambda: {"peaks": prob.peaks}
    return prob


def _split_doublets(freq, psd, fits: list[dict], scored: list, preds: list[dict], s_log: float,
                    averages: int | None, shape=SHO) -> list[dict] | None:
    """The peaks with two supported lines replaced by both (:func:`fit_doublet`), or None if none is.

    A resolved peak is tested where the hypotheses that compete for the labels (the nominal probe's
    and those placing the most resolved peaks) put two or more predicted modes within its matching
    window (MATCH_TOL after the hypothesis' scale): only there can a second mode hide in the line.
    The two modes nearest the peak give the starting pair. The likelihood-ratio test's level is
    ALPHA divided by the number of peaks tested."""
    top = max(k for k, *_ in scored)
    cands = [scored[0], *[x for x in scored[1:] if x[0] == top]]
    pairs: dict[int, tuple[float, float]] = {}
    for i, ft in enumerate(fits):
        if ft["fwhm_bins"] < 2.0 or not np.isfinite(ft["Q"]):
            continue
        lf = math.log(ft["f0_Hz"])
        for _, _, h, sh in cands:
            near = sorted((abs(lf - math.log(sh * f)), sh * f) for f in h["f_Hz"] if f > 0
                          and abs(lf - math.log(sh * f)) <= MATCH_TOL)
            if len(near) >= 2:
                pairs[i] = (near[0][1], near[1][1])
                break
    if not pairs:
        return None
    out: list[dict] = []
    changed = False
    for i, ft in enumerate(fits):
        d = (fit_doublet(freq, psd, ft, s_log, averages, pair=pairs[i], n_tests=len(pairs), others=fits, shape=shape)
             if i in pairs else None)
        if d is None:
            out.append(ft)
            continue
        changed = True
        for k, ln in enumerate(d["lines"]):
            other = d["lines"][1 - k]
            note = (f"one of two lines in one peak (unresolved doublet with {other['f0_Hz']:.6g} Hz; two SHO lines "
                    f"against one: likelihood ratio {d['lr']:.3g} > {d['threshold']:.3g}; one line would have had "
                    f"Q {d['single']['Q']:.3g} at {d['single']['f0_Hz']:.6g} Hz)")
            out.append({**ln, "notes": [note], "doublet": {"partner_Hz": other["f0_Hz"], "likelihood_ratio": d["lr"],
                                                          "threshold": d["threshold"], "rho_centres": d["rho_f"],
                                                          "one_line": d["single"]}})
    return out if changed else None


def _assignments(fits: list[dict], table: list[dict], preds: list[dict], s: float) -> list[dict[int, int]]:
    """The alternative one-to-one assignments of a labelling's peaks to the predicted modes within
    their matching windows (MATCH_TOL after the common scale ``s``), where a window holds more than
    one mode: ``{peak index: index into preds}`` for every peak of such a group, closest (least summed
    squared log deviation) first, at most MAX_ASSIGNMENTS, the labelling's own assignment excluded.
    Peaks taken are the accepted ones and those rejected only because a stronger peak took their
    nearest mode (two peaks competing for the same modes)."""
    import itertools

    def cand(i):
        lf = math.log(fits[i]["f0_Hz"])
        return [j for j, p in enumerate(preds) if abs(lf - math.log(s * p["f_Hz"])) <= MATCH_TOL]

    peaks = [i for i, t in enumerate(table)
             if t["accepted"] or (t["reasons"] and all("already taken" in r for r in t["reasons"]))]
    cands = {i: cand(i) for i in peaks}
    # groups: peaks linked by a shared candidate mode
    groups: list[tuple[list[int], set[int]]] = []
    for i in peaks:
        if not cands[i]:
            continue
        g = ([i], set(cands[i]))
        for other in [x for x in groups if x[1] & g[1]]:
            groups.remove(other)
            g = (other[0] + g[0], other[1] | g[1])
        groups.append(g)
    groups = [g for g in groups if len(g[1]) > 1 and len(g[1]) >= len(g[0])]
    if not groups:
        return []
    def cost(a):
        return sum(math.log(fits[i]["f0_Hz"] / (s * preds[j]["f_Hz"])) ** 2 for i, j in a.items())

    per_group = []
    for pk, md in groups:
        opts = [dict(zip(pk, perm)) for perm in itertools.permutations(sorted(md), len(pk))
                if all(perm[k] in cands[i] for k, i in enumerate(pk))]
        per_group.append(sorted(opts, key=cost)[:MAX_ASSIGNMENTS])  # the closest first, then the cap

    combos = []
    for combo in itertools.islice(itertools.product(*per_group), 4 * MAX_ASSIGNMENTS):
        a = {k: v for part in combo for k, v in part.items()}
        combos.append(a)
    own = {i: next((j for j, p in enumerate(preds) if (p["family"], p["order"]) == (table[i]["family"], table[i]["order"])), None)
           for i in peaks}
    combos = [a for a in combos if any(own.get(i) != j for i, j in a.items())]
    return sorted(combos, key=cost)[:MAX_ASSIGNMENTS]


def _label_table(meas: SpectrumData, fits: list[dict], preds: list[dict], s: float,
                 force: dict[int, int] | None = None) -> list[dict]:
    """The peak table under one set of predicted frequencies ``preds`` and common scale ``s``:
    each peak's nearest mode (or the mode ``force`` assigns it: ``{peak index: index into preds}``,
    see _assignments), accepted or rejected with its reasons (see the module docstring)."""
    seen: set = set()
    table = []
    # the highest Q among the resolved lines: the loss mechanisms of one lever (thermoelastic, clamp,
    # surface, the medium) give its modes Qs within about an order of magnitude of each other, so an
    # unresolved line -- Q above f0 / (2 bins) -- whose least possible Q exceeds Q_SPREAD times every
    # resolved line's is not a mode of that lever but a sinusoid (a spur that fell near a predicted
    # mode: high in the band the modes are dense, lateral 2, torsion 2 and axial 1 of a short lever
    # within 7 %)
    q_res = [ft["Q"] for ft in fits if ft["fwhm_bins"] >= 2.0]
    q_res_max = max(q_res) if q_res else math.inf
    # a mode goes to the strongest line that matches it: resolved lines (a mode's line shape) before
    # unresolved ones (a spur or a frequency-only mode), larger areas first -- in frequency order a spur
    # beside a fluid-broadened flapwise 3 took its label, and the mode was "already taken"
    rank = sorted(range(len(fits)), key=lambda j: (fits[j]["fwhm_bins"] < 2.0, -fits[j].get("area_m2", 0.0)))
    rows: dict[int, dict] = {}
    unresolved_modes: set[int] = set()  # unresolved lines whose shape allows a mode of this lever
    for i_ft in rank:
        ft = fits[i_ft]
        reasons = []
        near = (preds[force[i_ft]] if force and i_ft in force
                else min(preds, key=lambda p: abs(math.log(ft["f0_Hz"] / (s * p["f_Hz"])))))
        dev = ft["f0_Hz"] / (s * near["f_Hz"]) - 1
        if abs(dev) > MATCH_TOL:
            reasons.append(f"no mode of the probe model within {100 * MATCH_TOL:.0f} % (nearest: {near['family']} "
                           f"{near['order']} at {s * near['f_Hz']:.5g} Hz after the common scale {s:.3g})")
        unresolved = ft["fwhm_bins"] < 2.0
        df = bin_width(meas.freq, ft["f0_Hz"])
        if unresolved:
            # a sinusoid (spur) or a resonance narrower than the resolution: only the second is
            # possible where the model's damping would also leave the line unresolved
            wide = np.isfinite(near["Q_fluid"]) and s * near["f_Hz"] / near["Q_fluid"] / df > 3.0
            q_min = ft["f0_Hz"] / (2.0 * df)
            sharp = q_min > Q_SPREAD * q_res_max
            if not (wide or sharp):
                unresolved_modes.add(i_ft)
            if wide or sharp or abs(dev) > MATCH_TOL:
                reasons.append(f"unresolved line ({ft['fwhm_bins']:.2g} bins wide)"
                               + (f" where the {meas.medium_name}-damped mode would be {s * near['f_Hz'] / near['Q_fluid'] / df:.2g} bins wide"
                                  if wide else "")
                               + (f": Q > {q_min:.3g}, over {Q_SPREAD:g} x the highest Q of the resolved lines ({q_res_max:.3g})"
                                  if sharp and not wide else "") + ": an electronic spur")
            else:
                ft = {**ft, "Q": math.nan, "Q_sigma": math.nan, "note": "unresolved: frequency only"}
        # line-shape evidence that the peak is a mode of this lever (whatever its label): a resolved
        # line whose Q is plausible (below Q_FACTOR x Q_fluid in a fluid; its area is checked below)
        mode_line = not unresolved
        if not unresolved and np.isfinite(near["Q_fluid"]) and ft["Q"] > Q_FACTOR * near["Q_fluid"]:
            mode_line = False
            reasons.append(f"Q = {ft['Q']:.3g} exceeds {Q_FACTOR:g} x the {meas.medium_name}-damped Q_fluid = "
                           f"{near['Q_fluid']:.3g} of {near['family']} {near['order']}")
        ratio = (ft["area_m2"] / near["thermal_area_m2"]) if meas.temperature and near.get("thermal_area_m2") else None
        key = (near["family"], near["order"])
        if not reasons and key in seen:
            reasons.append(f"{key[0]} {key[1]} already taken by a stronger peak")
        # a resolved line that matches a mode is accepted; an unresolved one only in vacuum-like
        # damping where its Q is plausible is still not measurable: rejected
        accepted = not reasons
        if accepted:
            seen.add(key)
        if "notes" in ft:  # a list per table (notes are added to the chosen labelling's table)
            ft = {**ft, "notes": list(ft["notes"])}
        rows[i_ft] = {**ft, "accepted": accepted, "_mode_line": mode_line, "thermal_ratio": ratio,
                      "family": near["family"] if accepted else None,
                      "order": near["order"] if accepted else None, "predicted_Hz": s * near["f_Hz"],
                      "predicted_Q_fluid": near["Q_fluid"], "reasons": reasons}
    table = [rows[j] for j in range(len(fits))]
    # equipartition: the areas of the accepted peaks are k_B T / k_eff times one detector
    # calibration factor c (their median ratio; 1 for a PSD calibrated in tip displacement, other
    # values for an uncalibrated sensitivity or an optical lever); a peak whose area is more than
    # AREA_FACTOR away from c times its thermal area is not thermal motion of that mode
    ratios = [t["thermal_ratio"] for t in table if t["accepted"] and t["thermal_ratio"]]
    c_cal = float(np.median(ratios)) if ratios else None
    # an unresolved line that could be a mode by its shape (not too sharp for this lever's Qs, not in a fluid) and
    # whose area is the thermal motion of its nearest mode times that factor is thermal motion of a mode, whatever
    # a labelling calls it: its frequency is evidence (_unlabelled_price). Without the area (no declared temperature,
    # no factor) nothing tells it from a spur
    for j, t in enumerate(table):
        r = j in unresolved_modes and t["thermal_ratio"]
        t["_thermal_line"] = bool(r and c_cal and len(ratios) > 1 and 1 / AREA_FACTOR < r / c_cal < AREA_FACTOR)
    if c_cal is not None and len(ratios) > 1:
        for t in table:
            r = t["thermal_ratio"]
            if t["accepted"] and r and not (1 / AREA_FACTOR < r / c_cal < AREA_FACTOR):
                t["accepted"] = t["_mode_line"] = t["_thermal_line"] = False
                t["reasons"] = [f"peak area {t['area_m2']:.3g} m^2 is {r / c_cal:.3g} x the thermal k_B T / k_eff of "
                                f"{t['family']} {t['order']} (times the spectrum's common factor {c_cal:.3g})"]
                t["family"] = t["order"] = None
    if table:
        table[0]["_c_cal"] = c_cal
    return table


def _unlabelled_price(table: list[dict]) -> float:
    """The goodness-of-fit price of the resolved lines a labelling leaves unlabelled.

    A resolved line with a plausible Q (and area) is, by its line shape, a mode of the lever: the
    detector sees every family through the off-axis, tilted spot. Labelled correctly, its rows
    (frequency, and Q when measured) add a chi-square with that many degrees of freedom to the
    labelling's fit; a labelling that leaves it out is charged the largest such contribution that is
    still plausible, the ``1 - ALPHA / N`` quantile (the engine's level, N = number of peaks: the
    look-elsewhere correction over the peaks). A labelling that places the line is therefore
    preferred whenever its fit of it is consistent with the noise (incl. the model-form floor), and a
    labelling that places it only by mislabelling other peaks -- a fit worse than any correct label
    could give -- loses to the one that leaves it out. An unresolved line (a spur, or a mode whose Q the
    spectrum cannot measure) costs its frequency's quantile (one degree of freedom) where its shape allows a mode
    of this lever and its area is thermal motion (within ``AREA_FACTOR`` of its nearest mode's equipartition times
    the spectrum's common factor: ``_thermal_line``): blind p01 of the second spectrum set, whose flapwise 1 and 2
    were narrower than a bin, was labelled without them for free, and the prestress that moved them went unseen.
    Lines whose Q or area no mode of the lever could have carry no such evidence and cost nothing."""
    from probedyn.diagnose.tails import chi2 as chi2_dist

    from probedyn.diagnose.engine import ALPHA

    n = max(len(table), 1)
    price = 0.0
    for t in table:
        if t["accepted"]:
            continue
        if t.get("_mode_line"):
            d = 1 + int(bool(np.isfinite(t.get("Q", math.nan))))
        elif t.get("_thermal_line"):
            d = 1  # an unresolved mode: its frequency only
        else:
            continue
        price += float(chi2_dist.ppf(1 - ALPHA / n, d))
    return price


def _peak_sigma(meas: SpectrumData, acc: list[dict]) -> np.ndarray:
    """Frequency uncertainty (Hz) of accepted peaks: the line fit's standard error of the centre and
    the declared relative calibration uncertainty, in quadrature."""
    f = np.array([t["f0_Hz"] for t in acc])
    return np.sqrt(np.array([t["f0_sigma_Hz"] for t in acc]) ** 2 + (meas.freq_rel * f) ** 2)


def _peak_noise(meas: SpectrumData, table: list[dict]) -> dict[tuple[str, int], float]:
    """The frequency uncertainty (Hz) of every accepted peak by its ``(family, order)`` label: the
    ``noise`` a FEM baseline is refined for (:meth:`FEMBaseline.refined`)."""
    acc = [t for t in table if t["accepted"]]
    return {(t["family"], int(t["order"])): float(s) for t, s in zip(acc, _peak_sigma(meas, acc))}


def _modal_problem(meas: SpectrumData, table: list[dict], base: FEMBaseline, L) -> ModalProblem:
    """The modal problem of the accepted peaks (frequency with the fit's standard error and the
    declared calibration uncertainty, Q with its fit error)."""
    acc = [t for t in table if t["accepted"]]
    fam = np.array([t["family"] for t in acc])
    order = np.array([t["order"] for t in acc])
    f = np.array([t["f0_Hz"] for t in acc])
    sig = _peak_sigma(meas, acc)
    Q = np.array([t["Q"] for t in acc])
    qrel = np.where(np.isfinite(Q), np.maximum(np.array([t["Q_sigma"] for t in acc]) / Q, 1e-3), np.nan)
    md = ModalData(path=meas.path, kind="modal", meta=meas.meta, description=meas.description, medium=meas.medium,
                   medium_name=meas.medium_name, temperature=meas.temperature, known=meas.known, free=meas.free,
                   probe=meas.probe, probe_values=meas.probe_values, family=fam, order=order, freq=f, freq_sigma=sig,
                   Q=Q, Q_sigma_rel=qrel, length=np.full(len(f), meas.probe_values.get("length", np.nan)),
                   known_mass=meas.known_mass, static=meas.static, noise_stated=True)
    return ModalProblem(md, bases={L: base})


def _labelling_scores(meas: SpectrumData, options: list[tuple], base: FEMBaseline, L) -> list[tuple[float, str | None, dict]]:
    """Goodness of fit of every labelling ``(labels, table, hypothesis, scale)``: its best model's score
    (:func:`_labelling_score`) plus the price of the resolved lines it leaves unlabelled
    (:func:`_unlabelled_price`).

    Only the best labelling and those within twice the evidence margin of it are used, so a labelling
    that cannot come that close is not fitted with the catalog: every cause's score is at least its
    likelihood-ratio threshold, so ``min(baseline chi^2, smallest threshold) + price`` bounds its score
    from below. The baselines are fitted first (their score bounds the best one from above), the
    labellings then in the order of that bound; one whose lower bound exceeds the best score so far by
    more than twice the margin keeps its baseline score (an upper bound) and is not fitted further
    (exact: it could be neither the best nor close to it)."""
    from probedyn.diagnose.engine import EVIDENCE_MARGIN

    rows = []
    refused = []
    for lab, tab, h, sh in options:
        price = _unlabelled_price(tab)
        if not any(t["accepted"] for t in tab):  # places no peak: fits nothing (chi^2 0 on no rows), only its price
            rows.append((price, price, None, h, price))
            continue
        try:
            prob = _modal_problem(meas, tab, base, L)
        except DataFormatError as e:
            # the modal problem's units check: this labelling's peaks lie more than 30 times from the declared
            # probe's modes (a heavy point mass's hypothesis naming a water-loaded flapwise 1 lateral 1, blind
            # p07 of the second spectrum set). That is no reading of the spectrum, not a units error of the
            # record -- unless no labelling is any better (then the record's error stands)
            refused.append(e)
            rows.append((math.inf, math.inf, None, h, price))
            continue
        b = _labelling_score(prob, baseline_only=True)
        rows.append((b[0] + price, price + min(b[0], _threshold_min(prob)), prob, h, price))
    if refused and all(math.isinf(r[0]) for r in rows):
        raise refused[0]
    scores: list[tuple[float, str | None, dict]] = [(up, None, {}) for up, *_ in rows]
    best = min(scores)[0]
    for j in sorted(range(len(rows)), key=lambda j: rows[j][0]):
        up, low, prob, h, price = rows[j]
        if prob is None or low > best + 2 * EVIDENCE_MARGIN:
            continue
        sc, model, pars = _labelling_score(prob, hint=h)
        scores[j] = (sc + price, model, pars)
        best = min(best, scores[j][0])
    return scores


def _threshold(c, n_c: int) -> float:
    """A cause's likelihood-ratio threshold ``chi2_k(1 - alpha / N)`` (the engine's claim rule)."""
    from probedyn.diagnose.tails import chi2 as chi2_dist

    from probedyn.diagnose.engine import ALPHA

    return float(chi2_dist.ppf(1 - ALPHA / max(n_c, 1), len(c.params)))


def _threshold_min(prob: ModalProblem) -> float:
    return min((_threshold(c, len(prob.causes)) for c in prob.causes), default=math.inf)


def _labelling_score(prob: ModalProblem, hint: dict | None = None,
                     baseline_only: bool = False) -> tuple[float, str | None, dict]:
    """How well a labelling's peaks are explained: the lowest of the baseline's chi-square and each
    single catalog cause's chi-square plus its likelihood-ratio threshold chi2_k(1 - alpha / N) (the
    engine's claim rule: a cause with k parameters must buy at least that much), with the best model
    and its cause parameters. Without the penalty, with few peaks a labelling that needs a cause at
    some value fits them exactly and always beats the nominal labels' baseline.

    A screen, not the diagnosis: each start of a cause fit gets ``LABEL_SCREEN_NFEV`` evaluations and the
    best start goes on to at most ``LABEL_NFEV_PER_PARAM`` per parameter; the cause of the hypothesis that
    proposed the labelling (``hint``) starts from its null and from that hypothesis's values instead of its
    declared starts (the hypothesis placed the peaks there). ``baseline_only``: the
    baseline fit alone (kept on ``prob`` for the causes' nested fits)."""
    from probedyn.diagnose.engine import Fitter

    prob.screen_nfev = LABEL_SCREEN_NFEV
    prob.nfev_per_param = LABEL_NFEV_PER_PARAM
    F = Fitter(prob)
    try:
        b = getattr(prob, "_labelling_baseline", None)
        if b is None:
            b = prob._labelling_baseline = F.baseline()
        best = (float(b.chi2), None, {})
        if baseline_only:
            return best
        n_c = len(prob.causes)
        hint = hint or {}
        jobs = [(b, (c,), None, dict(hint["values"])) if c.key == hint.get("cause") and hint.get("values")
                else (b, (c,), None) for c in prob.causes]
        F.open_pool()  # the causes' fits through the problem's workers (forked with the baseline kept on prob)
        for c, f in zip(prob.causes, F.map_nested(jobs)):
            sc = float(f.chi2) + _threshold(c, n_c)
            if sc < best[0]:
                best = (sc, c.key, {p.name: float(f.values[p.name]) for p in c.params})
        return best
    except Exception:  # noqa: BLE001 -- a labelling the model cannot fit at all
        return math.inf, None, {}
    finally:
        F.close_pool()
