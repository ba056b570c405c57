"""Spectra and time series -> measured modes (then the modal diagnosis).

Each resonance peak of a thermal-noise PSD (or of an amplitude spectrum, squared) is fitted
with the simple-harmonic-oscillator PSD plus a white floor,

    S(f) = A f0^4 / ((f0^2 - f^2)^2 + (f f0 / Q)^2) + B,

in log space (an averaged periodogram has a relative, not absolute, scatter). The fitted f0
and Q with their standard errors (Jacobian, scaled by the residual variance) become the rows
of a modal measurement; families come from ``[measurement] families`` (default: flapwise
modes in order). A time series is first reduced to a Welch PSD (formats.py).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import find_peaks

from probedyn.diagnose.formats import ModalData, SpectrumData, _medium, _noise, _num, _props
from probedyn.core.errors import DataFormatError

__all__ = ["fit_peaks", "spectrum_to_modal", "sho_psd"]


def sho_psd(f, f0, Q, A, B):
    return A * f0**4 / ((f0**2 - f**2) ** 2 + (f * f0 / Q) ** 2) + B


def fit_peaks(freq: np.ndarray, psd: np.ndarray, max_peaks: int = 8, min_prominence: float = 10.0) -> list[dict[str, Any]]:
    """Find resonance peaks (at least ``min_prominence`` x the median floor) and fit each."""
    floor = float(np.median(psd))
    logp = np.log(np.maximum(psd, 1e-300))
    # smooth the log spectrum a little so single noisy bins do not count as peaks
    k = max(1, len(psd) // 2000)
    sm = np.convolve(logp, np.ones(2 * k + 1) / (2 * k + 1), mode="same")
    idx, props = find_peaks(sm, prominence=math.log(min_prominence))
    idx = idx[np.argsort(-props["prominences"])][:max_peaks]
    out = []
    for i in sorted(idx):
        f0 = float(freq[i]); p0 = float(psd[i])
        half = psd > 0.5 * p0
        j0 = i
        while j0 > 0 and half[j0 - 1]:
            j0 -= 1
        j1 = i
        while j1 < len(psd) - 1 and half[j1 + 1]:
            j1 += 1
        fwhm = max(freq[min(j1 + 1, len(freq) - 1)] - freq[max(j0 - 1, 0)], 2 * (freq[1] - freq[0]))
        Q0 = max(f0 / fwhm, 0.6)
        sel = np.abs(freq - f0) < max(8 * fwhm, 20 * (freq[1] - freq[0]))
        fw, pw = freq[sel], psd[sel]
        B0 = max(float(np.median(psd[~sel])) if (~sel).any() else floor, 1e-300)
        A0 = max(p0 / Q0**2, 1e-300)

        def res(u):
            return np.log(sho_psd(fw, u[0], 10 ** u[1], 10 ** u[2], 10 ** u[3])) - np.log(np.maximum(pw, 1e-300))

        u0 = np.array([f0, math.log10(Q0), math.log10(A0), math.log10(B0)])
        lo = [fw[0], math.log10(0.5), u0[2] - 6, u0[3] - 6]
        hi = [fw[-1], math.log10(Q0) + 3, u0[2] + 6, u0[3] + 6]
        try:
            r = least_squares(res, np.clip(u0, lo, hi), bounds=(lo, hi), x_scale=[fwhm, 0.3, 0.3, 0.3])
        except ValueError:
            continue
        dof = max(len(fw) - 4, 1)
        s2 = float(np.sum(r.fun**2)) / dof
        try:
            cov = np.linalg.inv(r.jac.T @ r.jac) * s2
            sd = np.sqrt(np.maximum(np.diag(cov), 0))
        except np.linalg.LinAlgError:
            sd = np.full(4, np.inf)
        Q = 10 ** r.x[1]
        out.append({"f0_Hz": float(r.x[0]), "f0_sigma_Hz": float(sd[0]), "Q": float(Q),
                    "Q_sigma": float(Q * math.log(10) * sd[1]), "amplitude": float(10 ** r.x[2]),
                    "floor": float(10 ** r.x[3]), "points": int(len(fw))})
    return out


def spectrum_to_modal(meas: SpectrumData) -> tuple[ModalData, list[dict[str, Any]]]:
    side = meas.path
    psd = meas.value**2 if meas.quantity == "amplitude" else meas.value
    peaks = fit_peaks(meas.freq, psd)
    if not peaks:
        raise DataFormatError(f"{side}: no resonance peak found in the spectrum (need >= 10x the median floor)")
    fams = list(meas.families) or ["flap"] * len(peaks)
    if len(fams) < len(peaks):
        peaks = peaks[: len(fams)]
    counters: dict[str, int] = {}
    fam, order = [], []
    for k in range(len(peaks)):
        counters[fams[k]] = counters.get(fams[k], 0) + 1
        fam.append(fams[k]); order.append(counters[fams[k]])
    f = np.array([p["f0_Hz"] for p in peaks])
    rel, stated = _noise(meas.meta, side, "frequency_rel", 0.0)
    sig = np.maximum(np.array([p["f0_sigma_Hz"] for p in peaks]), rel * f)
    Q = np.array([p["Q"] for p in peaks])
    qrel, _ = _noise(meas.meta, side, "Q_rel", 0.0)
    qs = np.maximum(np.array([p["Q_sigma"] for p in peaks]) / Q, qrel)
    props = _props(meas.meta, side)
    rho_f, eta_f = _medium(meas.meta, side)
    free = tuple(meas.meta.get("baseline", {}).get("free", ()))
    md = ModalData(path=side, kind="modal", meta=meas.meta, description=meas.description, props=props,
                   family=np.array(fam), order=np.array(order), freq=f, freq_sigma=sig, Q=Q, Q_sigma_rel=qs,
                   length=np.full(len(f), props.length), rho_f=rho_f, eta_f=eta_f,
                   tip_mass=_num(meas.meta, "probe", "tip_mass", side, default=0.0),
                   tip_position=_num(meas.meta, "probe", "tip_position", side, default=1.0), free=free,
                   noise_stated=True)
    return md, peaks
