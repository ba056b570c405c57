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
  registry), Table 2.1 (mica) preset, 1D scan along x at the source's V = 2 µm/s, under the
  constant applied normal load of the mica experiment, ``L = 141.75 nN`` (section 2.1.5.1).
* Tip–sample contact: Maugis–Dugdale (:mod:`probedyn.schemes.contact`), silicon tip
  (E = 169 GPa, nu = 0.28; the source's FFM used a silicon probe), ``R_t = 100 nm`` (the
  radius of Fig 2.20a), flat mica (E = 60 GPa, nu = 0.25: the c-axis indentation modulus of
  muscovite, an assumption: the source gives none), ``zeta_0`` of Table 4.4 (0.375 nm).
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

Table values (load, speed, zeta_0, the Table 2.1 cantilever and friction levels, the mica
lattice constant) come from :mod:`probedyn.core.presets`. The independent scipy solvers the
FFM scans are tested against live in ``tests/ffm_reference.py``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Literal, Sequence

import numpy as np
from scipy.signal import find_peaks

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset as table
from probedyn.schemes.contact import MaugisDugdale
from probedyn.schemes.ffm import FFM, line_scan

#: Table 2.1 (mica FFM: cantilever, friction levels, the scan of 2.1.5.1) and Table 4.2 (mica lattice)
TABLE_2_1 = table("table-2.1")
MICA_LATTICE = table("table-4.2-mica")["a"]

Law = Literal["area", "load"]


@dataclass
class CouplingSetup:
    """Parameters of the adhesion–friction study (SI units)."""

    preset: str = "mica"
    load: float = TABLE_2_1["normal_load"]  # N, applied normal load of the mica FFM experiment (2.1.5.1)
    speed: float = TABLE_2_1["V"]  # m/s, scan speed (2.1.5.1)
    law: Law = "area"
    lams: Sequence[float] = (0.0, 0.1, 0.3, 1.0, 3.0, 10.0)
    contact: dict = field(default_factory=lambda: dict(
        E_t=169e9, nu_t=0.28, R_t=100e-9, E_s=60e9, nu_s=0.25, R_s=0.0, z0=table("table-4.4")["zeta0"]))
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


# --------------------------------------------------------------------------------------------
# The study
# --------------------------------------------------------------------------------------------

ScanFn = Callable[[float, float, float], dict]


def ffm_scan(length: float, speed: float, scale: float, preset: str = "mica", n_out: int = 4000) -> dict:
    """One 1D line scan with the project's FFM model (:mod:`probedyn.schemes.ffm`, numba
    Rosenbrock integrator) and the generalised-bristle friction model, the friction levels
    scaled by ``scale`` (the FFM's normal-load input). Resampled to ``n_out`` base positions."""
    ffm = FFM.from_preset(preset, "bristle", overrides={"V": speed}, friction_scale=scale)
    g = line_scan(ffm, length).on_grid(n_out)
    return dict(base=g["base"], spring_force=g["lateral_force"])


def ffm_pt_scan(eta: float, length: float, speed: float = 2e-6, zeta: float = 1.0,
                a: float = MICA_LATTICE, n_out: int = 6000) -> dict:
    """A 1D Prandtl–Tomlinson scan through the project's FFM model with the registry's ``pt``
    friction model: ``m x'' + gamma x' = k (V t - x) - (2 pi U0 / a) sin(2 pi x / a)``,
    ``eta = 4 pi^2 U0 / (k a^2)``, Table 2.1 ``k_x`` and ``m_x``, cantilever damping c_x set to 0
    and the PT damping ``gamma = 2 zeta sqrt(m k (1 + eta))`` (``zeta = 1``: critically damped at
    the bottom of a well). Tested against an independent scipy solution of the same equation
    (``tests/ffm_reference.py``)."""
    k, m = TABLE_2_1["k_x"], TABLE_2_1["m_x"]
    gam = 2 * zeta * math.sqrt(m * k * (1 + eta))
    U0 = eta * k * a * a / (4 * math.pi**2)
    ffm = FFM.from_preset("mica", "pt", overrides=dict(U0=U0, a=a, gamma=gam, c_x=0.0, V=speed))
    g = line_scan(ffm, length).on_grid(n_out)
    return dict(base=g["base"], spring_force=g["lateral_force"])


def _default_scan(length: float, speed: float, scale: float) -> dict:
    return ffm_scan(length, speed, scale)


def run(setup: CouplingSetup | None = None, scan: ScanFn | None = None) -> dict[str, Any]:
    """FFM line scans for each lambda of ``setup``; rows of the table and the traces.

    ``scan(length, speed, scale)`` runs one line scan with the friction levels multiplied by
    ``scale`` and returns ``base`` and ``spring_force`` arrays (default: :func:`ffm_scan`, the
    project's FFM model; ``tests/ffm_reference.py`` has the independent implementation it is
    tested against).
    The scan length covers the first stick plus ``n_periods`` sawtooth periods, estimated from
    the friction levels (``F_s f / k`` and ``2 (F_s - F_c) f / k``).
    """
    setup = setup or CouplingSetup()
    setup.validate()
    scan = scan or _default_scan
    Fs, Fc, k = TABLE_2_1["F_s_x"], TABLE_2_1["F_c_x"], TABLE_2_1["k_x"]
    rows, traces = [], []
    for lam in setup.lams:
        c = contact_at(lam, setup)
        f = c["scale"]
        first_est = Fs * f / k
        period_est = 2 * (Fs - Fc) * f / k
        length = 1.1 * first_est + setup.n_periods * period_est
        tr = scan(length, setup.speed, f)
        met = scan_metrics(tr["base"], tr["spring_force"])
        rows.append({**c, **met, "scan_length_m": length})
        traces.append(dict(lam=lam, base=tr["base"], force=tr["spring_force"], scale=f))
    return dict(setup=asdict(setup), rows=rows, traces=traces)


def verdict(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Is the source's claim (more adhesion -> longer initial sticking, longer period) borne out?

    Also tests whether the effect is a pure rescaling of the friction levels: first stick / f and
    period / f constant across lambda.
    """
    lam = np.array([r["lam"] for r in rows])
    order = np.argsort(lam)
    first = np.array([r["first_stick_m"] for r in rows])[order]
    period = np.array([r["period_m"] for r in rows])[order]
    f = np.array([r["scale"] for r in rows])[order]
    ok = np.isfinite(first) & np.isfinite(period)
    first_up = bool(np.all(np.diff(first[ok]) > 0))
    period_up = bool(np.all(np.diff(period[ok]) > 0))
    r1 = first[ok] / f[ok]
    r2 = period[ok] / f[ok]
    return dict(first_stick_increases=first_up, period_increases=period_up,
                first_over_scale_spread=float(np.ptp(r1) / np.mean(r1)),
                period_over_scale_spread=float(np.ptp(r2) / np.mean(r2)))


# --------------------------------------------------------------------------------------------
# The same question with a lattice model: 1D Prandtl–Tomlinson
# --------------------------------------------------------------------------------------------

def run_pt(setup: CouplingSetup | None = None, eta0: float = 3.0, zetas: Sequence[float] = (1.0, 0.1),
           n_lattice: int = 10, scan: Callable | None = None) -> list[dict[str, Any]]:
    """Prandtl–Tomlinson scans for each lambda: the corrugation ``U0`` scales with the same
    friction scale ``f`` as the bristle model's levels (``eta = eta0 f``; ``eta0`` at zero adhesion).

    The scan covers the first stick (about ``eta a / 2 pi``) plus ``n_lattice`` lattice constants
    (times ``eta / 10`` more when underdamped, where slips may skip several sites). ``scan``:
    default :func:`ffm_pt_scan` (the project's FFM with the registry's PT model; the independent
    implementation it is tested against is in ``tests/ffm_reference.py``)."""
    setup = setup or CouplingSetup()
    setup.validate()
    a = MICA_LATTICE
    rows = []
    for zeta in zetas:
        for lam in setup.lams:
            c = contact_at(lam, setup)
            eta = eta0 * c["scale"]
            length = eta * a / (2 * math.pi) + n_lattice * a * (1 + (eta / 10 if zeta < 1 else 0))
            tr = (scan or ffm_pt_scan)(eta, length, setup.speed, zeta=zeta)
            met = scan_metrics(tr["base"], tr["spring_force"])
            rows.append(dict(lam=lam, zeta=zeta, scale=c["scale"], eta=eta, **met,
                             period_over_a=met["period_m"] / a))
    return rows


def verdict_pt(pt_rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The source's claim in the Prandtl–Tomlinson rows of :func:`run_pt`: with critical damping
    (zeta >= 1) the largest deviation of the period from the lattice constant and whether the
    first stick grows with adhesion; underdamped (zeta < 1): the multiples of the lattice
    constant the period takes (multiple slips)."""
    crit = [r for r in pt_rows if r["zeta"] >= 1]
    under = [r for r in pt_rows if r["zeta"] < 1]
    return dict(
        period_deviation_critical=max(abs(r["period_over_a"] - 1) for r in crit) if crit else math.nan,
        first_stick_increases_critical=bool(np.all(np.diff([r["first_stick_m"] for r in crit]) > 0)) if crit else False,
        period_multiples_underdamped=sorted({int(round(r["period_over_a"])) for r in under}) if under else [],
    )
