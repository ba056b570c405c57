"""Adhesion–friction coupling (section 2.2.4, Fig 2.22 of the source).

The source simulates FFM line scans "for different values of lambda ranging from 0 to
infinity" at a fixed tip radius and states: the sawtooth persists for all lambda, "as lambda is
increased the pattern is shifted and the initial sticking values are increased", and "higher
adhesion values correspond to larger periods of the sawtooth". It does not say how lambda
enters the friction model (eqs 2.7–2.16 contain no normal force). This module makes that link
explicit and tests the claim with numbers.

Setup (stated assumptions)
--------------------------
* FFM scan: the FFM model of :mod:`probedyn.schemes.ffm` (eqs 2.13–2.16 with the friction
  registry), Table 2.1 (mica) preset, 1D scan along x at the source's V = 2 um/s, under the
  constant applied normal load of the mica experiment, ``L = 141.75 nN`` (section 2.1.5.1).
* Tip–sample contact: Maugis–Dugdale (:mod:`probedyn.schemes.contact`), silicon tip
  (E = 169 GPa, nu = 0.28; the source's FFM used a silicon probe), ``R_t = 100 nm`` (the
  radius of Fig 2.20a), flat mica (E = 60 GPa, nu = 0.25: the c-axis indentation modulus of
  muscovite, an assumption: the source gives none), ``zeta_0 = 3.75e-10 m`` (Table 4.4).
* **Adhesion varies, geometry stays** (the source: "same effective radius"): lambda is set
  through the work of adhesion with (2.24), ``W = (lambda zeta_0 / 2.06)^1.5 sqrt(pi K^2 / R)``,
  so adhesion (pull-off force) grows monotonically with lambda; lambda = 0 is no adhesion
  (Hertz). (The source's sentence "small values [of lambda] are for ... high adhesion" holds
  only if lambda is varied through K or zeta_0; here it is varied through W, as 2.2.4 says.)
* **Contact -> friction** (the physical assumption): single-asperity friction is proportional
  to the true contact area, ``F_f = tau pi a^2`` (Bowden–Tabor; shown for AFM nanocontacts by
  Carpick et al., and the basis of the COS fitting equation). The friction levels of the
  friction model therefore scale with ``a(L, lambda)^2 / a_Hertz(L)^2``: the preset's values
  are taken as those of the adhesion-free contact at the same applied load. The alternative
  ``law="load"`` (Derjaguin's two-term law: friction proportional to ``L - P_c``) is available;
  both give the same ordering. The scale is handed to the FFM model as its normal-load input
  (an equivalent load ``f L``).

Measured per lambda: adhesion ``W``, pull-off ``P_c``, contact radius at ``L``, friction scale
``f``, first stick length (base travel before the first slip), sawtooth period (median spacing
of slips), mean friction after the first slip, peak (static) and valley (kinetic) levels.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Literal, Sequence

import numpy as np

from probedyn.errors import ParameterError, SolverError

Law = Literal["area", "load"]


@dataclass
class CouplingSetup:
    """Parameters of the adhesion–friction study (SI units)."""

    preset: str = "mica"
    load: float = 141.75e-9  # N, applied normal load of the mica FFM experiment (2.1.5.1)
    speed: float = 2e-6  # m/s, scan speed (2.1.5.1)
    law: Law = "area"
    lams: Sequence[float] = (0.0, 0.1, 0.3, 1.0, 3.0, 10.0)
    contact: dict = field(default_factory=lambda: dict(
        E_t=169e9, nu_t=0.28, R_t=100e-9, E_s=60e9, nu_s=0.25, R_s=0.0, z0=3.75e-10))
    n_periods: int = 6  # sawtooth periods to simulate after the first slip

    def validate(self) -> None:
        if not (math.isfinite(self.load) and self.load > 0):
            raise ParameterError(f"applied normal load must be positive, got {self.load} N")
        if not (math.isfinite(self.speed) and self.speed > 0):
            raise ParameterError(f"scan speed must be positive, got {self.speed} m/s")
        if self.law not in ("area", "load"):
            raise ParameterError(f"coupling law must be 'area' or 'load', got {self.law!r}")
        for lam in self.lams:
            if not (math.isfinite(lam) and lam >= 0):
                raise ParameterError(f"transition parameter lambda must be >= 0, got {lam}")


def contact_at(lam: float, setup: CouplingSetup) -> dict[str, float]:
    """Maugis–Dugdale contact at the applied load for transition parameter ``lam``.

    Returns W [J/m^2], pull-off [N], contact radius [m] (and the Hertz radius at the same load),
    and the friction scale ``f`` of the chosen law.
    """
    from probedyn.schemes.contact import MaugisDugdale

    md = MaugisDugdale(lam=lam, **setup.contact)
    s = md.scales
    a_H = (setup.load * s.R / s.K) ** (1.0 / 3.0)
    st = md.at_load(setup.load)
    Pc = md.pull_off_force()
    if setup.law == "area":
        f = (st["radius"] / a_H) ** 2
    else:
        f = (setup.load - Pc) / setup.load
    return dict(lam=lam, W=s.W, pull_off=Pc, pull_off_over_load=-Pc / setup.load,
                radius=st["radius"], radius_hertz=a_H, penetration=st["penetration"], scale=f)


def scan_metrics(x: np.ndarray, F: np.ndarray, drop_fraction: float = 0.3,
                 floor: float = 1e-3) -> dict[str, float]:
    """Stick-slip measures of a lateral-force trace ``F`` against base position ``x``.

    A slip is a local maximum of ``F`` whose prominence (the drop that follows it, in the sense
    of ``scipy.signal.find_peaks``) is at least ``drop_fraction`` of the largest prominence in
    the trace and at least ``floor * max|F|`` (so numerical ringing on a smooth trace is not a
    slip). First stick length: ``x`` travelled before the first slip; period: median spacing of
    consecutive slips; mean friction, peak and valley levels: over the part after the first slip.
    """
    from scipy.signal import find_peaks

    x = np.asarray(x, float)
    F = np.asarray(F, float)
    if x.shape != F.shape or x.size < 10:
        raise ParameterError("scan_metrics needs equal-length traces of at least 10 samples")
    none = dict(first_stick_m=math.nan, period_m=math.nan, mean_friction_n=float(np.mean(F)),
                first_peak_n=math.nan, peak_n=float(np.max(F)), valley_n=math.nan, n_slips=0)
    peaks, props = find_peaks(F, prominence=0.0)
    keep = peaks < F.size - 2  # a maximum at the very end is not followed by a slip
    peaks, prom = peaks[keep], props["prominences"][keep]
    if peaks.size == 0:
        return none
    thr = max(drop_fraction * float(np.max(prom)), floor * float(np.max(np.abs(F))))
    peaks = peaks[prom >= thr]
    if peaks.size == 0:
        return none
    first = peaks[0]
    valleys = [int(np.argmin(F[a:b])) + a for a, b in zip(peaks[:-1], peaks[1:])]
    return dict(
        first_stick_m=float(x[first] - x[0]),
        period_m=float(np.median(np.diff(x[peaks]))) if peaks.size > 1 else math.nan,
        mean_friction_n=float(np.mean(F[first:])),
        first_peak_n=float(F[first]),
        peak_n=float(np.mean(F[peaks[1:]])) if peaks.size > 1 else float(F[first]),
        valley_n=float(np.mean(F[valleys])) if valleys else math.nan,
        n_slips=int(peaks.size),
    )
