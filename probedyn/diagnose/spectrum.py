"""Spectra and time series: resonance peaks identified against the probe's model, then the modal diagnosis.

1. **Background and peaks.** The PSD is searched for peaks standing above their base by more than
   an averaged periodogram's chi^2 statistics allow anywhere in the spectrum (the quantile ratio
   of Gamma(m N) at 1 % / number of windows, N = ``[measurement] averages`` or estimated from the
   point-to-point scatter; :func:`detect_peaks`).
2. **Line shape.** Each peak is fitted -- by maximum likelihood of the averaged periodogram
   (Gamma deviance) when N is declared, else in log space with the scatter -- by the
   thermal SHO line ``A f0^4 / ((f0^2 - f^2)^2 + (f f0 / Q)^2)`` on a background ``B0 + B1 / f``
   (white plus 1/f). Its full width ``f0 / Q`` is compared with the frequency resolution: a line
   narrower than 2 bins is *unresolved* (a sinusoid -- an electronic spur -- or a resonance whose
   Q the spectrum cannot measure).
3. **Identification against the model.** The probe's FEM (the modal baseline) predicts every
   mode's frequency and family, and in a declared medium the Sader quality factor of its
   flapwise modes, ``Q <= Q_fluid`` (``1/Q = 1/Q_int + 1/Q_fluid``); with a declared temperature it
   also predicts the thermal peak area ``k_B T / k_eff`` (equipartition, effective stiffness of the
   mode at the tip). A common frequency scale ``s`` in [1/2, 2] (the geometry may be off by that
   much) maps predicted onto measured frequencies (the scale that matches most peaks within 3 %);
   a peak is accepted as mode (family, order) when it lies within 3 % of a scaled prediction, its Q
   is below 3 Q_fluid (in a fluid), and (when T is declared) its area is within a factor 100 of
   equipartition times the common factor of the accepted peaks (the median of their area ratios:
   1 for a PSD calibrated in tip displacement; an uncalibrated sensitivity or an optical lever
   scales all thermal peaks alike, a spur or a pick-up line does not). Everything else is rejected *and reported* with the reason (spur, unmatched,
   Q or amplitude implausible).
   The predictions are those of a *hypothesis*: the nominal probe, or the probe carrying one catalog
   cause at a grid of its parameters (:func:`_hypotheses`, on the Ritz reduction). A hidden effect
   moves the families differently (a width error moves lateral and torsional modes only), so the
   nearest nominal mode after one common scale may be another family's; the labels are those of the
   hypothesis placing the most resolved peaks (the nominal probe's unless a cause places more), and
   labellings that tie are decided by their modal fit, the peaks they disagree on left out when the
   fits are within the evidence margin (reported as ambiguous).
4. The accepted peaks become modal rows (frequency with the fit's standard error and the
   declared calibration uncertainty, Q with its fit error) for :class:`~probedyn.diagnose.modal.ModalProblem`.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import find_peaks
from scipy.stats import gamma as gamma_dist

from probedyn.core.errors import DataFormatError
from probedyn.diagnose.formats import ModalData, SpectrumData
from probedyn.diagnose.modal import ModalProblem
from probedyn.diagnose.modal_model import FAMILIES, FEMBaseline, _fluid_mode

__all__ = ["spectrum_problem", "fit_line", "detect_peaks", "sho_psd"]

K_B = 1.380649e-23
MATCH_TOL = 0.03
Q_FACTOR = 3.0
AREA_FACTOR = 100.0
GRID_FRACTIONS = (0.002, 0.005, 0.01, 0.015, 0.02, 0.03, 0.04, 0.05, 0.065, 0.08, 0.1, 0.125, 0.15, 0.2, 0.25,
                  0.3, 0.4, 0.55, 0.75, 1.0)
MAX_LABELLINGS = 4
CAUSE_SCALE = 1.1  # common frequency scale allowed on top of a cause hypothesis (E, rho, t of a nominal lever: ~10 %)  # distinct labellings compared by their modal fit


def sho_psd(f, f0, Q, A):
    return A * f0**4 / ((f0**2 - f**2) ** 2 + (f * f0 / Q) ** 2)


def log_scatter(psd: np.ndarray, averages: int | None) -> float:
    """Standard deviation of ln(PSD) of an averaged periodogram: about 1/sqrt(n_avg); without
    the number of averages, from the point-to-point scatter (robust)."""
    if averages:
        return 1.0 / math.sqrt(averages)
    d = np.diff(np.log(np.maximum(psd, 1e-300)))
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2))


def detect_peaks(freq: np.ndarray, psd: np.ndarray, s_log: float, max_peaks: int = 12,
                 averages: int | None = None) -> list[int]:
    """Peaks of ln(PSD): broad ones on a lightly smoothed spectrum (prominence above 5 standard
    deviations of the smoothed scatter) and narrow lines (single bins standing 8 standard
    deviations above their neighbourhood), the most prominent first."""
    logp = np.log(np.maximum(psd, 1e-300))
    k = max(1, min(len(psd) // 4000, 8))
    # smoothing in the linear domain: a mean of m bins of an N-times averaged periodogram is
    # Gamma(m N, S / (m N)) where S is locally flat; a peak must stand above its base by more than
    # the ratio of the upper to the lower quantile of that distribution at alpha / (number of
    # windows) (the look-elsewhere effect: ~1 % chance of one false peak per spectrum). The log of
    # a Gamma variable is skewed (deep dips), so a threshold in standard deviations of ln S would
    # report noise as peaks where averages are few.
    N = averages if averages else max(1.0, 1.0 / max(s_log, 1e-6) ** 2)
    padded = np.pad(psd, k, mode="edge")  # zero padding would dent the ends and make edge 'peaks'
    sm = np.log(np.maximum(np.convolve(padded, np.ones(2 * k + 1) / (2 * k + 1), mode="valid"), 1e-300))

    def _ratio(m: float, n_windows: float) -> float:
        a = 0.01 / max(n_windows, 1.0)
        return math.log(gamma_dist.isf(a, m) / gamma_dist.ppf(a, m))

    thr_broad = max(_ratio((2 * k + 1) * N, len(psd) / (2 * k + 1)), math.log(2.0))
    idx, props = find_peaks(sm, prominence=thr_broad)
    cand = {int(i): float(p) for i, p in zip(idx, props["prominences"])}
    idx2, props2 = find_peaks(logp, prominence=max(_ratio(N, len(psd)), math.log(5.0)), width=(None, 3))
    for i, p in zip(idx2, props2["prominences"]):
        if not any(abs(int(i) - j) <= 2 * k + 1 for j in cand):
            cand[int(i)] = float(p)
    # the smoothed search locates a one-bin line (a spur) up to k bins off: every candidate is moved
    # to the largest raw value within the smoothing window, so the line fit is centred on it (a fit
    # started beside a spur would take the background for the line and wander to another peak)
    snapped: dict[int, float] = {}
    for i in sorted(cand, key=lambda i: -cand[i]):
        lo, hi = max(i - 2 * k - 1, 0), min(i + 2 * k + 2, len(logp))
        j = lo + int(np.argmax(logp[lo:hi]))
        if j not in snapped:
            snapped[j] = cand[i]
    best = sorted(snapped, key=lambda i: -snapped[i])[:max_peaks]
    return sorted(best)


def gamma_deviance_residuals(y: np.ndarray, S: np.ndarray, averages: int) -> np.ndarray:
    """Signed deviance residuals of periodogram bins ``y`` against a model PSD ``S``: an average of
    ``N`` periodograms is ``S chi^2_{2N} / (2N)`` (a Gamma(N, S/N) variable, not Gaussian), whose
    negative log likelihood is ``N (y/S + ln S)`` + const; ``sum r^2`` is the deviance
    ``2N sum (y/S - 1 - ln(y/S))``, minimal at the maximum-likelihood S and ~ chi^2 per bin for large N.
    (A least-squares fit of ln y instead is biased: E[ln y] = ln S + psi(N) - ln N, -1.6 % in the
    line's area at N = 32.)"""
    x = np.maximum(y, 1e-300) / np.maximum(S, 1e-300)
    return np.sign(x - 1.0) * np.sqrt(np.maximum(2.0 * averages * (x - 1.0 - np.log(x)), 0.0))


def fit_line(freq: np.ndarray, psd: np.ndarray, i: int, s_log: float, averages: int | None = None) -> dict[str, Any]:
    """SHO line on a white + 1/f background around peak index i: maximum likelihood of the averaged
    periodogram (:func:`gamma_deviance_residuals`) when the number of averages is known, else
    log-space least squares with the scatter ``s_log``."""
    f0 = float(freq[i])
    p0 = float(psd[i])
    df = float(np.median(np.diff(freq)))
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

    def model(u):
        return sho_psd(fw, u[0], 10 ** u[1], 10 ** u[2]) + 10 ** u[3] + 10 ** u[4] * (fw[0] / fw)

    def res(u):
        if averages:
            return gamma_deviance_residuals(pw, model(u), averages)
        return (np.log(model(u)) - np.log(np.maximum(pw, 1e-300))) / s_log

    u0 = np.array([f0, math.log10(Q0), math.log10(A0), math.log10(B0), math.log10(B0) - 3])
    lo = [fw[0], math.log10(0.5), u0[2] - 8, u0[3] - 8, u0[3] - 10]
    hi = [fw[-1], math.log10(Q0) + 4, u0[2] + 8, u0[3] + 4, u0[3] + 4]
    r = least_squares(res, np.clip(u0, lo, hi), bounds=(lo, hi), x_scale=[fwhm, 0.3, 0.3, 0.3, 0.3])
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
    return {"f0_Hz": float(r.x[0]), "f0_sigma_Hz": float(sd[0]), "Q": float(Q), "Q_sigma": float(Q * math.log(10) * sd[1]),
            "area_m2": float(A * math.pi * r.x[0] * Q / 2), "white_floor": float(10 ** r.x[3]),
            "one_over_f_at_window_start": float(10 ** r.x[4]), "fwhm_bins": float(r.x[0] / Q / df),
            "chi2_per_dof": chi2 / dof, "points": int(len(fw)), "window_Hz": [float(fw[0]), float(fw[-1])]}


def _predictions(base: FEMBaseline, medium, temperature) -> list[dict[str, Any]]:
    out = []
    cnt: dict[str, int] = {}
    rho_f, eta_f = medium if medium is not None else (0.0, 1.8e-5)
    for md in base.result.modes:
        fa = md.family
        cnt[fa] = cnt.get(fa, 0) + 1
        item = {"family": fa, "order": cnt[fa], "f_Hz": md.frequency_hz, "Q_fluid": math.inf,
                "k_eff_z": md.effective_stiffness_tip.get("z", math.inf)}
        if rho_f > 0 and fa == "flapwise" and base.has_top:
            from probedyn.diagnose.fem_terms import directional, face_mass_scalar

            K, M = base.model.assemble()
            e = np.zeros(3)
            e[base.thickness_axis] = 1.0
            Stop = directional(face_mass_scalar(base.model, "top"), np.outer(e, e))
            a = md.shape
            f, Q = _fluid_mode(float(a @ (K @ a)), float(a @ (M @ a)), float(a @ (Stop @ a)), md.omega, base.w,
                               rho_f, eta_f, 1.0, math.inf)
            item.update(f_Hz=f, Q_fluid=Q)
        if temperature:
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


def _matches(fits: list[dict], f_pred: list[float], s: float) -> tuple[int, int, float]:
    """Resolved and all peaks within MATCH_TOL of a distinct predicted mode (nearest first) after the
    common scale ``s``, and the sum of their squared log deviations."""
    taken: dict[int, float] = {}
    n_res = 0
    for ft in sorted(fits, key=lambda ft: -ft["area_m2"]):
        d = [abs(math.log(ft["f0_Hz"] / (s * f))) if f > 0 else math.inf for f in f_pred]
        j = int(np.argmin(d))
        if d[j] < MATCH_TOL and j not in taken:
            taken[j] = d[j]
            n_res += ft["fwhm_bins"] >= 2.0
    return n_res, len(taken), float(sum(v * v for v in taken.values()))


def _grid(p) -> list[float]:
    """Values of one cause parameter for the identification hypotheses: its null and, towards each
    bound, GRID_FRACTIONS of the way (geometric over a log-scaled range). Successive values must move
    a mode by less than twice MATCH_TOL, or a mode that the effect moved between two grid values is
    within the window of neither (a width ratio of 1.165 between 1.12 and 1.21 left the lateral mode
    3.7 % from both; a tensile stress of 24 MPa between 17 and 35 MPa -- the range reaches 30 times
    the buckling stress -- left flapwise 1 5-7 % from both): the fractions step by <= 0.05 of the
    range up to 0.3 of it and by ~1.5x below 0.1, coarser beyond 0.3 where the catalog's effects are rare."""
    if p.scale == "log":
        return [float(x) for x in np.geomspace(p.lo, p.hi, 9)]
    out = [p.null]
    for b in (p.lo, p.hi):
        if b != p.null:
            out += [p.null + (b - p.null) * x for x in GRID_FRACTIONS]
    return out


def _hypotheses(meas: SpectrumData, base: FEMBaseline, preds: list[dict]) -> list[dict]:
    """Mode frequencies of the nominal probe (``preds``) and of the probe carrying each catalog cause
    the declared conditions allow, on a grid of its parameters (:func:`_grid`, products for two
    parameters), from the Ritz reduction of the FEM as ratios to its nominal solution (exact at the
    null). A hidden effect moves the families differently -- a width error moves lateral and
    torsional modes only, a clamp compliance or a compressive stress mostly the first flapwise
    mode -- so one common scale cannot place every peak, and the nearest nominal mode may be
    another family's; the labels are those of the hypothesis that makes the most peaks modes."""
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
        grids = [_grid(p) for p in c.params]
        nulls = [p.null for p in c.params]
        for vals in itertools.product(*grids):
            if list(vals) == nulls:
                continue
            v = {p.name: float(x) for p, x in zip(c.params, vals)}
            try:
                fh, _ = prob.predict(v, (c,))
            except Exception:  # noqa: BLE001 -- a grid point outside what the reduction solves
                continue
            if not np.all(np.isfinite(fh)) or np.any(fh <= 0):
                continue
            f_all = [p["f_Hz"] for p in preds]
            for k, i in enumerate(idx):
                f_all[i] = preds[i]["f_Hz"] * fh[k] / ref[k]
            out.append({"cause": c.key, "values": v, "f_Hz": f_all})
    return out


def spectrum_problem(meas: SpectrumData, base: FEMBaseline | None = None) -> ModalProblem:
    """Identify the peaks of a spectrum against the probe's FEM and return the modal problem of
    the accepted ones (with the peak table for the report). ``base``: the probe's FEM baseline when
    already built (spectra of one probe share it and its reduction)."""
    freq, psd = meas.freq, meas.value
    s_log = log_scatter(psd, meas.averages)
    df = float(np.median(np.diff(freq)))
    idx = detect_peaks(freq, psd, s_log, averages=meas.averages)
    if not idx:
        raise DataFormatError(f"{meas.path}: no peak stands out of the spectrum's background by 5 standard deviations")
    if base is None:
        base = FEMBaseline(meas.probe, meas.probe_values, {"flapwise": 2})
    preds = _predictions(base, meas.medium, meas.temperature)
    fits = []
    for i in idx:
        try:
            fits.append(fit_line(freq, psd, i, s_log, meas.averages))
        except ValueError:
            continue
    hint = list(meas.families)
    fam_ok = (lambda fa: fa in hint) if hint else (lambda fa: fa == "flapwise")
    L = float(meas.probe_values["length"]) if "length" in meas.probe_values else None
    # the labels: the hypotheses (the nominal probe, or a catalog cause at a grid value) under which
    # the most resolved peaks are modes (within MATCH_TOL after a common scale), see _hypotheses
    hyps = _hypotheses(meas, base, preds)
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
    top = max(k for k, *_ in scored)
    # the nominal probe's labels stand unless a cause hypothesis places more peaks: with few peaks
    # many hypotheses (a cause near its bound) place them all too, under other labels, and fit them
    # exactly -- the data cannot prefer them, the declared probe can
    cands = [scored[0]] if scored[0][0] == top else sorted((x for x in scored if x[0] == top), key=lambda x: x[1])
    # distinct labellings among the hypotheses that place the most peaks: where they differ (a peak
    # that is torsion 1 under one hypothesis and lateral 2 under another), frequencies alone cannot
    # decide; the labelling whose modal fit (the baseline or one catalog cause, Q included) has the
    # lowest chi-square is taken -- the likelihood of the whole spectrum's modes decides the labels
    options = []
    for _, _, h, sh in cands:
        tab = _label_table(meas, fits, [dict(p, f_Hz=f) for p, f in zip(preds, h["f_Hz"])], sh, df)
        lab = tuple((t["family"], t["order"]) if t["accepted"] else None for t in tab)
        if lab not in [o[0] for o in options]:
            options.append((lab, tab, h, sh))
        if len(options) >= MAX_LABELLINGS:
            break
    chi2s = []
    if len(options) > 1:
        for lab, tab, h, sh in options:
            chi2s.append(_best_fit_chi2(_modal_problem(meas, tab, base, L)))
        order_ = np.argsort(chi2s)
        k = int(order_[0])
    else:
        k = 0
    _, table, best, s = options[k]
    if len(options) > 1:
        # labellings whose best fits are within the engine's evidence margin of the best one are
        # as likely: the peaks they label differently are ambiguous and left out (a wrong label
        # would be "explained" by a wrong cause)
        from probedyn.diagnose.engine import EVIDENCE_MARGIN

        for j in order_[1:]:
            if chi2s[j] - chi2s[k] < 2 * EVIDENCE_MARGIN:
                for t, lab_j in zip(table, options[j][0]):
                    here = (t["family"], t["order"]) if t["accepted"] else None
                    if here is not None and lab_j != here:
                        t["accepted"] = False
                        other = f"{lab_j[0]} {lab_j[1]}" if lab_j else "not a mode"
                        t["reasons"] = [f"ambiguous: {here[0]} {here[1]} or {other} (the modal fits of the two labellings "
                                        f"differ by chi2 {chi2s[j] - chi2s[k]:.3g} < {2 * EVIDENCE_MARGIN:g})"]
                        t["family"] = t["order"] = None
    acc = [t for t in table if t["accepted"]]
    if not acc:
        raise DataFormatError(f"{meas.path}: none of the {len(table)} peaks is a mode of the probe model "
                              f"({'; '.join(r for t in table for r in t['reasons'][:1])})")
    prob = _modal_problem(meas, table, base, L)
    prob.kind = meas.kind
    c_cal = table[0].get("_c_cal") if table else None
    for t in table:
        t.pop("_c_cal", None)
    # the frequency scale reported is the nominal probe's (measured / nominal frequencies of the
    # matched modes); the labels may come from a hypothesis with its own scale s
    s_nominal = scored[0][3]
    prob.peaks = {"log_scatter": s_log, "resolution_Hz": df, "frequency_scale": s_nominal, "peaks": table,
                  "labels_from": {"hypothesis": best["cause"] or "nominal probe", "values": best["values"], "scale": s,
                                  "hypotheses_tried": len(hyps), "labellings_compared": len(options),
                                  "labelling_chi2": chi2s or None,
                                  "note": "the hypothesis that placed the peaks on modes (labels only, not a diagnosis)"},
                  "thermal_area_factor": c_cal}
    prob.extra_report = lambda: {"peaks": prob.peaks}
    return prob


def _label_table(meas: SpectrumData, fits: list[dict], preds: list[dict], s: float, df: float) -> list[dict]:
    """The peak table under one set of predicted frequencies ``preds`` and common scale ``s``:
    each peak's nearest mode, accepted or rejected with its reasons (see the module docstring)."""
    seen: set = set()
    table = []
    for ft in fits:
        reasons = []
        near = min(preds, key=lambda p: abs(math.log(ft["f0_Hz"] / (s * p["f_Hz"]))))
        dev = ft["f0_Hz"] / (s * near["f_Hz"]) - 1
        if abs(dev) > MATCH_TOL:
            reasons.append(f"no mode of the probe model within {100 * MATCH_TOL:.0f} % (nearest: {near['family']} "
                           f"{near['order']} at {s * near['f_Hz']:.5g} Hz after the common scale {s:.3g})")
        unresolved = ft["fwhm_bins"] < 2.0
        if unresolved:
            # a sinusoid (spur) or a resonance narrower than the resolution: only the second is
            # possible where the model's damping would also leave the line unresolved
            wide = np.isfinite(near["Q_fluid"]) and s * near["f_Hz"] / near["Q_fluid"] / df > 3.0
            if wide or abs(dev) > MATCH_TOL:
                reasons.append(f"unresolved line ({ft['fwhm_bins']:.2g} bins wide)"
                               + (f" where the {meas.medium_name}-damped mode would be {s * near['f_Hz'] / near['Q_fluid'] / df:.2g} bins wide"
                                  if wide else "") + ": an electronic spur")
            else:
                ft = {**ft, "Q": math.nan, "Q_sigma": math.nan, "note": "unresolved: frequency only"}
        elif np.isfinite(near["Q_fluid"]) and ft["Q"] > Q_FACTOR * near["Q_fluid"]:
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
        table.append({**ft, "accepted": accepted, "thermal_ratio": ratio, "family": near["family"] if accepted else None,
                      "order": near["order"] if accepted else None, "predicted_Hz": s * near["f_Hz"],
                      "predicted_Q_fluid": near["Q_fluid"], "reasons": reasons})
    # equipartition: the areas of the accepted peaks are k_B T / k_eff times one detector
    # calibration factor c (their median ratio; 1 for a PSD calibrated in tip displacement, other
    # values for an uncalibrated sensitivity or an optical lever); a peak whose area is more than
    # AREA_FACTOR away from c times its thermal area is not thermal motion of that mode
    ratios = [t["thermal_ratio"] for t in table if t["accepted"] and t["thermal_ratio"]]
    c_cal = float(np.median(ratios)) if ratios else None
    if c_cal is not None and len(ratios) > 1:
        for t in table:
            r = t["thermal_ratio"]
            if t["accepted"] and r and not (1 / AREA_FACTOR < r / c_cal < AREA_FACTOR):
                t["accepted"] = False
                t["reasons"] = [f"peak area {t['area_m2']:.3g} m^2 is {r / c_cal:.3g} x the thermal k_B T / k_eff of "
                                f"{t['family']} {t['order']} (times the spectrum's common factor {c_cal:.3g})"]
                t["family"] = t["order"] = None
    if table:
        table[0]["_c_cal"] = c_cal
    return table


def _modal_problem(meas: SpectrumData, table: list[dict], base: FEMBaseline, L) -> ModalProblem:
    """The modal problem of the accepted peaks (frequency with the fit's standard error and the
    declared calibration uncertainty, Q with its fit error)."""
    acc = [t for t in table if t["accepted"]]
    fam = np.array([t["family"] for t in acc])
    order = np.array([t["order"] for t in acc])
    f = np.array([t["f0_Hz"] for t in acc])
    sig = np.sqrt(np.array([t["f0_sigma_Hz"] for t in acc]) ** 2 + (meas.freq_rel * f) ** 2)
    Q = np.array([t["Q"] for t in acc])
    qrel = np.where(np.isfinite(Q), np.maximum(np.array([t["Q_sigma"] for t in acc]) / Q, 1e-3), np.nan)
    md = ModalData(path=meas.path, kind="modal", meta=meas.meta, description=meas.description, medium=meas.medium,
                   medium_name=meas.medium_name, temperature=meas.temperature, known=meas.known, free=meas.free,
                   probe=meas.probe, probe_values=meas.probe_values, family=fam, order=order, freq=f, freq_sigma=sig,
                   Q=Q, Q_sigma_rel=qrel, length=np.full(len(f), meas.probe_values.get("length", np.nan)),
                   known_mass=meas.known_mass, noise_stated=True)
    return ModalProblem(md, bases={L: base})


def _best_fit_chi2(prob: ModalProblem) -> float:
    """The lowest chi-square of the baseline and of each single catalog cause (nested fits on the
    Ritz reduction, as the diagnosis runs them)."""
    from probedyn.diagnose.engine import Fitter

    F = Fitter(prob)
    try:
        b = F.baseline()
        return float(min([b.chi2, *(f.chi2 for f in F.map_nested([(b, (c,), None) for c in prob.causes]))]))
    except Exception:  # noqa: BLE001 -- a labelling the model cannot fit at all
        return math.inf
    finally:
        F.close_pool()
