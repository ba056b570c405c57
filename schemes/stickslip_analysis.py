"""Analysis of a lateral-force trace (FFM line scan): slips, static / kinetic friction, period,
regime.

Definitions (section 2.1.5.1 of the source: "the static friction is obtained by averaging the
highest values of the friction curve and the kinetic friction by averaging the lowest values
of the periodic part"):

* **peaks** are local maxima of the lateral force with a prominence above a threshold
  ``max(rel_prominence * (F_max - F_min), noise_factor * sigma_noise)`` (``sigma_noise`` from the
  median absolute second difference, zero for a clean simulation); each peak is followed by a
  **valley**, the minimum before the next peak (or before the end of the trace);
* ``static_friction_n`` = mean force at the peaks, ``kinetic_friction_n`` = mean force at the
  valleys, ``period_m`` = median base distance between consecutive peaks,
  ``first_slip_m`` = base position of the first peak;
* **shape measure** ``slip_fraction``: for each complete cycle valley -> peak -> valley, the
  share of the base travel spent with a falling force, ``fall / (rise + fall)``, averaged over the
  cycles (over the single first slip when there is no complete cycle). A regular sawtooth
  (slow loading, abrupt slip) has slip_fraction -> 0; reverse stick-slip (abrupt sticking,
  gradual slipping, Fig 2.10) has slip_fraction > 1/2.
* **abruptness**: the steepest force change over the periodic part (after the first peak),
  ``max |dF/dX|`` divided by the median ``|dF/dX|`` there (the loading slope). A slip is a fold
  of the force-balance curve, so in the quasi-static limit ``dF/dX`` is infinite at the slip
  and the ratio is bounded only by the sampling (of order ``points per period``); a smooth
  periodic modulation (Prandtl–Tomlinson with eta < 1) has the finite ratio
  ``(1 + eta) / (1 - eta)``. Periodic traces with abruptness < ``abrupt_ratio`` (default 50)
  are ``smooth``.
* **regime**: ``regular`` (slip_fraction < 1/2), ``reverse`` (>= 1/2), ``smooth`` (no slip and
  a force plateau: the force over the last 20 % of the trace varies by less than the threshold;
  or a periodic force without abrupt changes, see abruptness) or ``presliding`` (no slip yet: the force still rises at the end of the scan, the initial
  sticking of the scan has not ended; this is what a 10 nm mica scan with Table 2.1 gives,
  departure 11).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.signal import find_peaks

from probedyn.core.errors import DataFormatError


def noise_sigma(force: np.ndarray) -> float:
    """Robust white-noise estimate from second differences (a sawtooth contributes only at the
    few slip points): sigma = 1.4826 MAD(d2F) / sqrt(6)."""
    d2 = np.diff(force, 2)
    if d2.size < 5:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def analyze(base, force, rel_prominence: float = 0.01, noise_factor: float = 6.0,
            n_grid: int | None = 20000, abrupt_ratio: float = 50.0,
            noise: float | None = 0.0) -> dict[str, Any]:
    """Slips, friction levels, period and regime of a trace (see the module docstring).

    ``base``: base position (or time; then ``period_m`` is in the unit of ``base``), increasing;
    ``force``: lateral force [N]. Clean traces are resampled to ``n_grid`` uniform points
    (``None``: used as given). ``noise``: the force noise standard deviation [N]; 0 for a
    simulation (default), ``None`` to estimate it from the data (measured traces)."""
    b = np.asarray(base, float)
    f = np.asarray(force, float)
    if b.ndim != 1 or b.shape != f.shape or b.size < 10:
        raise DataFormatError("stick-slip analysis needs two 1D arrays of equal length >= 10")
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(f))):
        raise DataFormatError("stick-slip analysis: trace contains NaN or inf")
    if np.any(np.diff(b) <= 0):
        raise DataFormatError("stick-slip analysis: base position must increase strictly")
    sig = noise_sigma(f) if noise is None else float(noise)
    if sig < 0:
        raise DataFormatError(f"noise sigma must be >= 0, got {sig}")
    if n_grid is not None and sig == 0.0:
        bg = np.linspace(b[0], b[-1], n_grid)
        f = np.interp(bg, b, f)
        b = bg
    rng = float(f.max() - f.min())
    thr = max(rel_prominence * rng, noise_factor * sig, 1e-300)
    pk, _ = find_peaks(f, prominence=thr)
    # a peak counts as a slip only if the force then falls by thr
    peaks, valleys = [], []
    for j, i in enumerate(pk):
        end = pk[j + 1] if j + 1 < len(pk) else len(f)
        iv = i + int(np.argmin(f[i:end]))
        if f[i] - f[iv] >= thr:
            peaks.append(int(i))
            valleys.append(int(iv))
    out: dict[str, Any] = dict(n_slips=len(peaks), threshold_n=thr, noise_sigma_n=sig,
                               peaks_m=[float(b[i]) for i in peaks], valleys_m=[float(b[i]) for i in valleys],
                               peak_forces_n=[float(f[i]) for i in peaks],
                               valley_forces_n=[float(f[i]) for i in valleys])
    if not peaks:
        tail = f[int(0.8 * len(f)):]
        rising = (tail[-1] - tail[0]) > thr
        out.update(static_friction_n=None, kinetic_friction_n=None, period_m=None, first_slip_m=None,
                   slip_fraction=None, regime="presliding" if rising else "smooth",
                   max_force_n=float(f.max()), mean_force_n=float(f.mean()))
        return out
    Fs = float(np.mean(f[peaks]))
    Fk = float(np.mean(f[valleys]))
    period = float(np.median(np.diff(b[peaks]))) if len(peaks) >= 2 else None
    fracs = []
    for j in range(1, len(peaks)):
        rise = b[peaks[j]] - b[valleys[j - 1]]
        fall = b[valleys[j]] - b[peaks[j]]
        if valleys[j] < len(f) - 1:  # a complete fall inside the trace
            fracs.append(fall / (rise + fall))
    if not fracs:  # only the first slip: use its fall against the initial rise
        rise = b[peaks[0]] - b[0]
        fall = b[valleys[0]] - b[peaks[0]]
        fracs.append(fall / (rise + fall))
    sf = float(np.mean(fracs))
    seg = slice(peaks[0], None)
    dfdx = np.abs(np.diff(f[seg]) / np.diff(b[seg]))
    med = float(np.median(dfdx)) if dfdx.size else 0.0
    abrupt = float(dfdx.max() / med) if med > 0 else math.inf
    if sig > 0:  # noisy data: the derivative ratio is meaningless, rely on the slip detection
        abrupt = math.inf
    regime = "smooth" if abrupt < abrupt_ratio else ("reverse" if sf >= 0.5 else "regular")
    out.update(static_friction_n=Fs, kinetic_friction_n=Fk, period_m=period, first_slip_m=float(b[peaks[0]]),
               slip_fraction=sf, abruptness=abrupt, regime=regime,
               max_force_n=float(f.max()), mean_force_n=float(f[peaks[0]:].mean()))
    return out
