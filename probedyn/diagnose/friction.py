"""The friction diagnosis problem: FFM scans (trace and retrace) against probedyn's FFM model.

Baseline: the FFM line-scan model of :mod:`probedyn.schemes.ffm` -- the lever (k_x, effective
mass m_x, damping c_x) dragged by its support over the Prandtl-Tomlinson substrate of the
friction registry (``pt``: ``U = -U0 cos(2 pi x / a)``), integrated by the same Rosenbrock
integrator ``simulate ffm`` uses, along the measured support path with its reversals
(:func:`probedyn.schemes.ffm.line_scan_path`: trace and retrace, tip inertia at the stated
speeds). The corrugation scales with the normal load, ``U0 = u0 N`` (single-asperity Amontons,
the registry's ``load_params``). Each sample is the model's lateral spring force
``k_x (X - x)`` at the sample's support position (``sampling = "point"``) or its mean over the
sample's interval (``"interval-mean"``, an integrating detector), as the sidecar declares.

Calibrated: ``u0`` [J/N] and the lattice period ``a`` (within 25 % of the periodogram's
estimate); per scan the lattice registry (where the lattice sits relative to the scan's centre)
is a nuisance profiled out by aligning the fundamental of model and data (their cross spectrum
at 1/a over the steady parts of trace and retrace), then re-integrating at that registry.
Cross-validation groups are the trace and the retrace of each scan (the registry of a held-out
half is estimated from the other half only). The model enters the data on its steady stick-slip
cycle (a pre-roll in the scan direction); the data before their own first slip, which depend on
the unrecorded history, are not used.

Nested fits also start where the recorded loop puts each cause (:func:`loop_estimate`: the slip
drop over the peak force gives eta, hence the corrugation, independently of a calibration factor
and an offset; each cause's ``data_starts``): on a rugged stick-slip chi^2 the baseline's
corrugation absorbs a calibration factor or an adhesion load, and a fit from the null stalls there.
Thermally activated slips carry their stochastic slip-position scatter: the model of every sample
is its mean over the activated slip point's distribution and the residual is weighted by its
variance (:func:`thermal_slip_scatter`).

Cost (one evaluation = one FFM integration per scan): every start of a multi-start fit is
screened with ``SCREEN_NFEV`` evaluations and the best continued, with a runner-up within
``SCREEN_MARGIN`` of it; candidate causes and cross-validation folds are fitted in ``engine.WORKERS``
forked processes; the folds start from the null and from the full-data optimum (the chi^2 surface
of stick-slip traces is rugged).
"""

from __future__ import annotations

import functools
import math
from collections import OrderedDict
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np
from scipy.constants import k as K_B  # Boltzmann constant [J/K]

from probedyn.core.errors import DataFormatError, ProbedynError
from probedyn.schemes.ffm_passage import (FALL_MAX_SUBSTEPS, bottleneck_scales, deterministic_escape, escape_hazard,
                                          fall_substeps, overdamped_falls)
from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.formats import FrictionData, FrictionScan, _noise, _num, col_error, read_csv
from probedyn.diagnose.mixture import PitTest, SlipMixture, pit_test
from probedyn.schemes.ffm import FFM, line_scan_path

__all__ = ["FrictionProblem", "FrictionState", "read_friction", "simulate_scan"]

#: lattice periods of support travel before the data start, in the direction of the first segment: the
#: model enters the data on its steady stick-slip cycle; the data before their own first slip (which
#: depend on the unrecorded history, e.g. a previous retrace) are not used (FrictionProblem.use)
PREROLL = 2.0
#: lattice periods of support travel an activated path runs on past the record's last sample (the final segment
#: continued): a slip whose instability lies just beyond the record's end may come, activated, before its last
#: samples, and only a slip in the path carries that scatter (:func:`_scatter_moments`; blind f20, 1.5 K, point
#: samples: the last sample, already slipped, at 60 sigma against a model without it)
POSTROLL = 1.0
START_PERIODS = 1.5  # lattice periods at the start of a scan left out (unknown history before the scan)
#: corrugation above which a slip can carry the tip past the next well (Medyanik et al., PRL 97, 136106
#: (2006): multiple slips need eta > 4.6); there the stick-slip pattern of a scan is one of several
#: coexisting periodic patterns (the tip slips two wells at a time, over the even or the odd ones), and
#: which one a scan follows is set by its unrecorded history: the well the tip starts the pre-roll in
#: is then profiled per scan with the registry (FrictionProblem.nuisance)
MULTISLIP_ETA = 4.6
#: a slip releasing more than this many k_x a of the lateral force carried the tip past the next well (a single
#: slip releases up to ~1 k_x a, a double one ~2): only then are start wells profiled (FrictionProblem._start_well)
MULTISLIP_DROP = 1.5
#: and only where the other well's pattern leaves less than this share of the scan's chi^2 (_start_well)
MULTISLIP_GAIN = 0.5
#: a scan whose aligned samples (:meth:`FrictionProblem._aligned_periods`) span fewer lattice periods than this has its
#: registry from the fundamental's phase checked against ALIGN_GRID registries over one period where the aligned one
#: leaves the scan beyond its noise (session 78: a 4-period record's double-load scan, eta 11.7, its double slips and a
#: stick of 3.5 periods after the turn: the phase read 0.19 a off, chi^2 2.1e5 against 1.2e4 on the grid; the own and
#: blind records hold 8.9 - 77 periods)
ALIGN_PERIODS = 8.0
ALIGN_GRID = 16
#: wells tried besides the one under the support: the tip starts at rest up to this many periods
#: behind or ahead of it (a slip pattern of period up to 2 MULTISLIP_WELLS + 1 lattice periods)
MULTISLIP_WELLS = 1
#: integrator tolerance (relative, and absolute in units of the force scale / k and the speed): the
#: lateral force of stick-slip traces (interval means) agrees with rtol = 1e-7 to 0.15 sigma at the slips and
#: ~1e-15 N elsewhere (tests/test_diagnose_friction.py); 1e-3 misplaces slips by up to 10 sigma
RTOL = 1e-5
#: least-squares evaluations each start of a fit gets before the best start is continued
SCREEN_NFEV = 4
#: a screened runner-up within this fraction of the best start's chi^2 is continued too (at most
#: SCREEN_KEEP starts in all): four evaluations cannot rank two starts 2 % apart (seed 2047: the
#: misalignment's 17 deg start screened at 6.86e5, its 24 deg start at 6.98e5 and converging to 3.5e5)
SCREEN_MARGIN = 0.05
SCREEN_KEEP = 2
#: factor by which the data's scatter must exceed the stated noise to replace it
NOISE_EXCESS = 1.25
#: a first difference this many of its robust standard deviations from its segment's median is a slip's, and the
#: two second differences holding it are left out of the record's scatter (:func:`_scatter`)
SCATTER_SLIP = 5.0
#: the tip's thermal force noise is left out where its mean over the loop's stick branches is below this share of the
#: stated variance: a change of the variance that small is far below the chi-square test's resolution (sqrt(2 / n),
#: 2 % at 5000 samples) and only perturbs the rugged fits (blind null f21 at 2 K, 0.03 %: its activated baseline
#: went to another basin, chi^2 414 -> 460 on 355, and a drift was claimed; docs/diagnose.md 9.46)
THERMAL_NOISE_MIN_SHARE = 0.01
#: the least share of a stated total force noise left to the detector where the tip's thermal force noise is
#: shared out of it (FrictionProblem.predict)
DETECTOR_MIN_SHARE = 0.05
#: registries of the y train of a misaligned scan tried over one lattice period (FrictionProblem._profile_two_trains)
Y_GRID = 8
#: registries remembered per problem (model, scan, training mask): ~ the evaluations of a diagnosis
REGISTRY_MEMORY = 200_000
#: bytes of scan models kept per process (:meth:`FrictionProblem._scan_model`), the least recently used dropped first:
#: ~6500 models of the three-scan example's scans (639 samples each)
SCAN_MEMORY_BYTES = 64 * 2**20
#: the baseline's laws of the corrugation against the load, as the ``load_share`` of :func:`effective_load`: the
#: registry's (``FrictionModel.at_load``: U0 proportional to the load) and a corrugation independent of the load
LOAD_LAWS = {"amontons": 1.0, "load-independent": 0.0}


# ------------------------------------------------------------------------------------------
# Reading
# ------------------------------------------------------------------------------------------


def read_friction(side: Path, csv: Path, meta: dict, common: dict) -> FrictionData:
    d = read_csv(csv, ["scan", "position_m", "lateral_force_N"], ["time_s", "height_m"])
    lev = meta.get("lever", {})
    k_x = _num(meta, "lever", "k_x", side, positive=True, lo=1e-4, hi=1e4, unit="N/m")
    k_y = _num(meta, "lever", "k_y", side, positive=True, lo=1e-4, hi=1e6, unit="N/m") if "k_y" in lev else None
    m_x = _num(meta, "lever", "m_x", side, default=0.0, lo=0.0, hi=1e-3, unit="kg") or None
    c_x = _num(meta, "lever", "c_x", side, default=-1.0) if "c_x" in lev else None
    if c_x is not None and c_x < 0:
        raise DataFormatError(f"{side}: [lever] c_x must be >= 0")
    Q_x = _num(meta, "lever", "Q_x", side, default=0.0, lo=0.01, hi=1e7) if "Q_x" in lev else None
    if c_x is not None and Q_x is not None:
        raise DataFormatError(f"{side}: [lever] give c_x or Q_x, not both")
    lattice = _num(meta, "sample", "lattice", side, default=0.5e-9, positive=True, lo=5e-11, hi=1e-6, unit="m")
    sig, stated = _noise(meta, side, "force", 0.0, 1e-15, 1e-3, "N")
    part = meta.get("noise", {}).get("force_part", "total")
    if part not in ("total", "detector"):
        raise DataFormatError(f"{side}: [noise] force_part must be 'total' (the stated force noise covers every source) "
                              f"or 'detector' (the tip's thermal force noise comes on top), got {part!r}")
    if "force_part" in meta.get("noise", {}) and not stated:
        raise DataFormatError(f"{side}: [noise] force_part says what [noise] force covers: state force too")
    sampling = str(meta["measurement"].get("sampling", "interval-mean"))
    if sampling not in ("point", "interval-mean"):
        raise DataFormatError(f"{side}: [measurement] sampling must be 'point' or 'interval-mean', got {sampling!r}")
    scans_meta = meta.get("scans", [])
    if not isinstance(scans_meta, list) or not scans_meta:
        raise DataFormatError(f"{side}: missing [[scans]] tables (id, speed, load)")
    by_id: dict[int, tuple[float, float]] = {}
    for i, s in enumerate(scans_meta):
        if not isinstance(s, dict):
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1} must be a table")
        for k in s:
            if k not in ("id", "speed", "load"):
                from probedyn.diagnose.formats import _did_you_mean

                raise DataFormatError(f"{side}: unknown key '{k}' in [[scans]] entry {i + 1}"
                                      + _did_you_mean(k, ("id", "speed", "load")))
        if "id" not in s or "speed" not in s or "load" not in s:
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1} needs id, speed [m/s] and load [N]")
        sp, ld = s["speed"], s["load"]
        if isinstance(sp, bool) or not isinstance(sp, (int, float)) or not 1e-12 < sp < 1.0:
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1}: speed {sp!r} m/s is outside (1e-12, 1) m/s (SI)")
        if isinstance(ld, bool) or not isinstance(ld, (int, float)) or not 0 < ld < 1e-3:
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1}: load {ld!r} N is outside (0, 1e-3) N (SI)")
        if int(s["id"]) in by_id:
            raise DataFormatError(f"{side}: [[scans]] id {int(s['id'])} appears twice")
        by_id[int(s["id"])] = (float(sp), float(ld))
    ids = d["scan"]
    scans = []
    for sid in dict.fromkeys(ids.astype(int).tolist()):
        idx = np.nonzero(ids == sid)[0]
        if sid not in by_id:
            raise col_error(d, "scan", idx[0], f"scan id {sid} has no [[scans]] entry in {side.name}")
        if len(idx) < 16:
            raise col_error(d, "scan", idx[0], f"scan {sid} has only {len(idx)} samples (need >= 16)")
        if np.any(np.diff(idx) != 1):
            k = idx[np.nonzero(np.diff(idx) != 1)[0][0] + 1]
            raise col_error(d, "scan", k, f"rows of scan {sid} are not contiguous")
        x = d["position_m"][idx]
        if np.max(np.abs(x)) > 1e-3:
            raise col_error(d, "position_m", idx[int(np.argmax(np.abs(x)))], "position beyond 1 mm: values are SI metres")
        dx = np.diff(x)
        z = np.nonzero(dx == 0)[0]
        bad = [j for j in z if j == 0 or j == len(dx) - 1 or np.sign(dx[j - 1]) == np.sign(dx[j + 1])]
        if bad:  # a repeated position is only allowed at a reversal (the turning point sampled twice)
            raise col_error(d, "position_m", idx[1 + int(bad[0])], "repeated position (speed zero) away from a reversal")
        sgn = np.sign(dx)
        sgn[z] = np.sign(dx[z + 1])  # the repeated turning point belongs to the new direction
        direction = np.concatenate([sgn[:1], sgn])
        sp, ld = by_id[sid]
        if "time_s" in d and not np.any(np.isnan(d["time_s"][idx])):
            t = d["time_s"][idx]
            if np.any(np.diff(t) <= 0):
                raise col_error(d, "time_s", idx[1 + int(np.nonzero(np.diff(t) <= 0)[0][0])], "times must increase")
        else:
            t = np.concatenate([[0.0], np.cumsum(np.abs(dx))]) / sp
        f = d["lateral_force_N"][idx]
        if np.max(np.abs(f)) > 1e-3:
            raise col_error(d, "lateral_force_N", idx[int(np.argmax(np.abs(f)))], "force beyond 1 mN: values are SI newtons")
        h = None
        if "height_m" in d and not np.any(np.isnan(d["height_m"][idx])):
            h = d["height_m"][idx]
            if np.max(np.abs(h)) > 1e-3:
                raise col_error(d, "height_m", idx[int(np.argmax(np.abs(h)))], "height beyond 1 mm: values are SI metres")
        scans.append(FrictionScan(sid, sp, ld, x, f, t, direction, h))
    flat = [s.id for s in scans if not np.ptp(s.force) > 0]
    if flat:
        raise DataFormatError(f"{csv}: the data cannot inform the fit: the lateral force of scan {flat[0]} is constant"
                              + (" (all zero)" if not np.any(scans[[s.id for s in scans].index(flat[0])].force) else ""))
    regime = _regime(scans, lattice, sampling, side)
    if not stated:
        sig = _scatter(scans)
    return FrictionData(**common, scans=scans, k_x=k_x, k_y=k_y, m_x=m_x, c_x=c_x, Q_x=Q_x, lattice=lattice,
                        sigma_force=sig, sampling=sampling, noise_stated=stated, noise_part=part, regime=regime)


#: the most support travel between samples, in lattice periods, for a record the stick-slip baseline can be
#: fitted to: four samples per period resolve a slip's sawtooth (the periodogram's Nyquist limit is two)
MAX_SAMPLE_STEP = 0.25
#: the least support travel per sample, in lattice periods, for a friction loop whose samples are the mean
#: friction of their intervals (:mod:`probedyn.diagnose.friction_loop`): the interval mean of a stick-slip
#: sawtooth over n periods differs from the steady mean by at most one period's excursion / n (5 %)
LOOP_MIN_PERIODS = 20.0


def _regime(scans, lattice: float, sampling: str, side: Path) -> str:
    """Which model the record can be diagnosed against, from the sample spacing in lattice periods:
    ``"stick-slip"`` where the samples resolve the lattice (at most ``MAX_SAMPLE_STEP`` period apart:
    the Prandtl-Tomlinson baseline and its causes act on the slips, periods and registries);
    ``"loop"`` where each interval-mean sample averages at least ``LOOP_MIN_PERIODS`` periods (a
    micrometre image line of a polymer, a Nanosurf or JPK lateral-force channel: the record carries
    the mean friction of each interval and the topography's crosstalk, :mod:`.friction_loop`).
    In between, or point samples of an unresolved stick-slip (aliased: each catches the sawtooth at a
    random phase), the record is refused in one line instead of diagnosed from nothing the model can
    see."""
    steps = [float(np.median(np.abs(np.diff(s.position)[np.diff(s.position) != 0]))) for s in scans]
    worst = int(np.argmax(steps))
    per = steps[worst] / lattice
    if per <= MAX_SAMPLE_STEP:
        return "stick-slip"
    if per >= LOOP_MIN_PERIODS and sampling == "interval-mean" and min(steps) / lattice >= LOOP_MIN_PERIODS:
        return "loop"
    why = ("point samples of an unresolved stick-slip are aliased (declare sampling = \"interval-mean\" if the "
           "instrument averages each interval)" if sampling == "point" and per >= LOOP_MIN_PERIODS else
           f"resolving the stick-slip needs at most {MAX_SAMPLE_STEP:g} period between samples, a friction loop of "
           f"interval means at least {LOOP_MIN_PERIODS:g}")
    raise DataFormatError(
        f"{side}: scan {scans[worst].id}: the samples are {steps[worst]:.3g} m apart, {per:.3g} lattice periods "
        f"([sample] lattice = {lattice:.3g} m): {why}")


def _scatter(scans) -> float:
    """White-noise level from the point-to-point scatter: the robust (MAD) spread of the second
    differences over sqrt(6) (the signal's own increments are removed twice), without the second differences that
    hold a slip: a first difference more than :data:`SCATTER_SLIP` of its robust spread from the segment's median
    (each monotone segment apart, where the scans say their direction).

    The MAD alone takes slips for outliers only while they are rare: at 12 interval means a period a slip and its
    thermal scatter enter a quarter of the second differences, and blind set 2's records read 1.28-1.54 times their
    stated noise (g08, g09, g18, g19), which then replaced it (``NOISE_EXCESS``); without them 1.06-1.16
    (docs/diagnose.md 9.58). On white noise no difference is left out (5 standard deviations)."""
    parts = []
    for s in scans:
        d = getattr(s, "direction", None)
        cuts = np.nonzero(np.diff(d) != 0)[0] + 1 if d is not None and len(d) > 1 else []
        for f in np.split(np.asarray(s.force, float), cuts):
            if len(f) < 3:
                continue
            d1, r = np.diff(f), np.diff(f, 2)
            s0 = 1.4826 * np.median(np.abs(r - np.median(r))) / math.sqrt(6)
            far = np.abs(d1 - np.median(d1)) > SCATTER_SLIP * math.sqrt(2) * s0
            parts.append(r[~(far[:-1] | far[1:])])
    r = np.concatenate(parts) if parts else np.zeros(1)
    return float(1.4826 * np.median(np.abs(r - np.median(r))) / math.sqrt(6))


# ------------------------------------------------------------------------------------------
# Model
# ------------------------------------------------------------------------------------------


def effective_load(st: "FrictionState", load: float) -> float:
    """The load the corrugation is proportional to, ``U0 = u0 N_eff`` [N]: ``N_eff = N_ref + s (N + N_adh - N_ref)``
    with ``s = st.load_share``. ``s = 1`` is the registry's law (:meth:`probedyn.schemes.friction.base.FrictionModel.at_load`,
    Amontons at the single asperity: U0 proportional to the total load ``N + N_adh``); ``s = 0`` is a corrugation
    independent of the load (the plain PT model, ``simulate ffm`` without a normal load: ``U0 = u0 N_ref`` on every
    scan); between, the linear law with an adhesion intercept ``N_ref (1/s - 1)``. Never negative."""
    N = load + st.n_adh
    if st.load_share != 1.0:
        N = st.n_ref + st.load_share * (N - st.n_ref)
    return max(N, 0.0)


@dataclass
class FrictionState:
    u0: float  # corrugation per unit load [J/N]
    a: float  # lattice period [m]
    gamma: float = 0.0  # viscous coefficient of the registry PT model [N s/m]
    n_adh: float = 0.0  # adhesion load [N]
    #: how the corrugation follows the load about the reference load ``n_ref`` (:func:`effective_load`): 1 the
    #: registry's law (U0 proportional to the load), 0 a corrugation independent of the load
    load_share: float = 1.0
    n_ref: float = 0.0  # the reference load of ``load_share`` [N]
    offset: float = 0.0  # [N]
    drift: float = 0.0  # [N over the longest scan: the detector's drift rate times that scan's duration]
    bow: float = 0.0  # scanner nonlinearity
    theta: float = 0.0  # scan angle to the lattice rows [rad]
    ky_ratio: float = 1.0  # the lever's stiffness across the scan over k_x (1: the lattice axes decouple)
    gain: float = 1.0  # lateral-force calibration factor
    thermal: tuple[float, float] | None = None  # (T [K], attempt frequency [Hz])
    #: the declared temperature [K] (0: none declared): the stick branches are the tip's thermal mean over its well
    #: (:func:`thermal_mean_shift`), a declared condition of every model, activated or not
    temperature: float = 0.0
    transforms: list = field(default_factory=list)  # f(problem, scan, F) -> F, applied last


def _largest_slip(F: np.ndarray, direction: np.ndarray) -> float:
    """The largest release of lateral force in one slip of a model trace ``F`` [N]: the largest fall of the force
    over consecutive falling samples in the trace (rise in the retrace; a slip of interval means may straddle
    two samples)."""
    g = np.diff(np.asarray(F, float) * np.asarray(direction, float))
    same = np.asarray(direction[1:] == direction[:-1])
    best = run = 0.0
    for d, ok in zip(g, same):
        run = run - d if (ok and d < 0) else 0.0
        best = max(best, run)
    return best


def drift_clock(scans) -> tuple[str, list[np.ndarray]]:
    """The detector's clock for a drift linear in time: ``("record", t - t_mid)`` where the scans' ``time_s``
    run on one clock through the file (each scan starts at or after the previous one ends; ``t_mid`` the
    record's middle: the scans' mean offsets then differ by the drift between them), else ``("scan", t - t_mid_i)``
    (each scan's clock restarts, as exports of separate lines do: the time between the scans is unknown, so
    the drift is taken within each scan, at one rate, about a common zero). A drift is a rate: a scan ten
    times faster drifts a tenth as much (before session 30 the drift was 'the same amount over every scan',
    which a blind generator's one-clock drift, 2.2e-10 N/s over three scans, left unexplained)."""
    t0 = [float(s.time[0]) for s in scans]
    t1 = [float(s.time[-1]) for s in scans]
    one = len(scans) > 1 and all(t0[i + 1] >= t1[i] for i in range(len(scans) - 1))
    if one:
        mid = 0.5 * (min(t0) + max(t1))
        return "record", [np.asarray(s.time, float) - mid for s in scans]
    return "scan", [np.asarray(s.time, float) - 0.5 * (s.time[0] + s.time[-1]) for s in scans]


def _ffm(data: FrictionData, U0: float, a: float, gamma: float) -> FFM:
    k = data.k_x
    m = data.m_x if data.m_x else k / (2 * math.pi * 1e5) ** 2
    if data.c_x is not None:
        c = data.c_x
    elif data.Q_x is not None:
        c = math.sqrt(m * k) / data.Q_x
    else:
        c = math.sqrt(m * k)  # Q = 1 (a strongly damped slip), stated in the docs
    return FFM.from_preset("mica", "pt", {"U0": max(U0, 1e-30), "a": a, "gamma": max(gamma, 0.0), "k_x": k, "m_x": m,
                                          "c_x": c})


def _barrier_table(U0: float, a: float, k: float, n: int = 400):
    """Quasi-static PT: for support positions X on the branch of the well at 0 up to its
    instability X_c, the barrier to the next well. Returns (X, dE, X_c, x_s(X), x_m(X)), the arrays read-only.
    Memoised (:data:`BARRIER_MEMORY` tables): a scan's table depends on its corrugation, period and stiffness only,
    and the registry's profile integrates the same model a dozen times (7000 tables in the three-scan example)."""
    return _barrier_table_memo(float(U0), float(a), float(k), int(n))


#: barrier tables kept (:func:`_barrier_table`)
BARRIER_MEMORY = 64


@functools.lru_cache(maxsize=BARRIER_MEMORY)
def _barrier_table_memo(U0: float, a: float, k: float, n: int):
    """:func:`_barrier_table` computed."""
    q = 2 * math.pi / a
    F0 = q * U0
    eta = q * F0 / k
    if eta <= 1.0:
        return None
    xc = math.acos(-1.0 / eta) / q
    xm = np.linspace(-0.25 * a, xc * (1 - 1e-6), n)
    X = xm + (F0 / k) * np.sin(q * xm)
    # saddle: the unstable equilibrium x_s in (x_c, a/2 + x_c): k (X - x) = F0 sin(q x), by
    # bisection on every support position at once
    lo = np.full_like(X, xc)
    hi = np.full_like(X, 0.5 * a + xc)
    glo = k * (X - lo) - F0 * np.sin(q * lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        gm = k * (X - mid) - F0 * np.sin(q * mid)
        same = (gm > 0) == (glo > 0)
        lo = np.where(same, mid, lo)
        glo = np.where(same, gm, glo)
        hi = np.where(same, hi, mid)
    xs = 0.5 * (lo + hi)
    E = lambda x, Xi: -U0 * np.cos(q * x) + 0.5 * k * (Xi - x) ** 2  # noqa: E731
    dE = E(xs, X) - E(xm, X)
    Xc = xc + (F0 / k) * math.sin(q * xc)
    dE = np.maximum(dE, 0.0)
    for arr in (X, dE, xs, xm):
        arr.setflags(write=False)
    return X, dE, Xc, xs, xm


def thermal_slip_advance(U0: float, a: float, k: float, V: float, T: float, f0: float) -> tuple[float, Any]:
    """Median support position of a thermally activated slip before the athermal instability:
    the hazard ``int f0 exp(-dE(X) / k_B T) dX / V`` reaches ln 2 (Kramers rate with attempt frequency
    f0; Gnecco et al. 2000, Sang et al. 2001). Returns ``(X_c - X*, table)`` (0 where the median slip is the instability: the hazard below ln 2 there)."""
    tab = _barrier_table(U0, a, k)
    if tab is None or T <= 0 or f0 <= 0:
        return 0.0, tab
    return _median_advance(tab, thermal_hazard(tab, V, T, f0)), tab


def _median_advance(tab, H: np.ndarray) -> float:
    """``X_c - X*`` for the cumulative hazard ``H`` along a barrier table: 0 where it stays below ln 2."""
    if H[-1] < math.log(2.0):
        return 0.0
    return max(tab[2] - float(np.interp(math.log(2.0), H, tab[0])), 0.0)


#: total hazard of an activated slip over a stick branch (up to the athermal instability) below which the
#: slips are taken as athermal: at most this fraction of the slips comes early. Above it the slips are
#: activated even where the median is still the instability (the hazard below ln 2: a fast scan or a
#: low temperature), their scatter then being that of the early fraction
THERMAL_MIN_HAZARD = 1e-3


def thermal_hazard(tab, V: float, T: float, f0: float) -> np.ndarray:
    """Cumulative hazard ``H(X) = int f0 exp(-dE / k_B T) dX / V`` of an activated slip along the stick
    branch of a barrier table (:func:`_barrier_table`), from its start to each support position."""
    X, dE = tab[0], tab[1]
    rate = f0 * np.exp(-dE / (K_B * T)) / V
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(X))])


#: quantiles of the activated slip point carried per slip (the mean and variance of every sample
#: near a slip are averages over them): the middle of the distribution in SLIP_QUANTILES equal probability
#: intervals, each tail beyond the first of them in intervals halving SLIP_TAIL_HALVINGS times down to
#: 1/32 2^-14 = 1.9e-6 (:func:`slip_nodes`)
SLIP_QUANTILES = 32
#: halvings of each tail's probability intervals beyond the middle's first (:func:`slip_nodes`). Equal intervals
#: alone left a slip beyond the 1/64 quantile no variance: blind g09 (298 K, U0 10.5 k_B T peak to peak, 100 slips) had samples
#: at r = 15 and 8.7 where a slip came two samples early or late, chi^2 1052 on 663 samples at its detector's
#: 5 pN, and 622 with 2048 equal quantiles (docs/diagnose.md 9.56)
SLIP_TAIL_HALVINGS = 14


def slip_nodes(mid: int = SLIP_QUANTILES, halvings: int = SLIP_TAIL_HALVINGS) -> tuple[np.ndarray, np.ndarray]:
    """The slip point's quantile nodes: probabilities ``p`` and weights ``w`` (summing to 1) of a midpoint rule
    in probability. The middle ``(1/mid, 1 - 1/mid)`` in ``mid - 2`` equal intervals; each tail from ``1/mid``
    in intervals halving ``halvings`` times, the last one from 0. A sample's mean and variance over the slip
    point are ``sum w F(p)`` and ``sum w (F(p) - mean)^2``: a sample that only a slip beyond the quantile ``p``
    moves to the other branch carries ``p (1 - p) D^2`` within the rule's factor, 0.67-1.33 in the tails, where
    each interval is twice the next (equal intervals gave it 0 beyond ``1/(2 mid)``)."""
    pt = 1.0 / mid
    edges = [0.0] + [pt * 2.0**-j for j in range(halvings, 0, -1)] + list(np.linspace(pt, 1.0 - pt, mid - 1))
    edges = np.array(edges + [1.0 - pt * 2.0**-j for j in range(1, halvings + 1)] + [1.0])
    p, w = 0.5 * (edges[1:] + edges[:-1]), np.diff(edges)
    p.setflags(write=False)
    w.setflags(write=False)
    return p, w


#: the slip point's quantile nodes (probabilities, weights) every activated path carries
SLIP_NODES = slip_nodes()


def thermal_slip_scatter(tab, U0: float, a: float, k: float, V: float, T: float, f0: float,
                         H: np.ndarray | None = None, ext: tuple[np.ndarray, np.ndarray] | None = None):
    """The distribution of a thermally activated slip point around its median (the stochastic
    slip-position scatter): the survival ``exp(-H(X))`` of the stick state with the hazard of
    :func:`thermal_slip_advance` gives the slip point's CDF ``1 - exp(-H)`` (the athermal
    instability ends the branch: the rest of the probability slips there). Returns the
    quantiles at :data:`SLIP_NODES` of the slip point relative to the median, in the direction of
    motion, the force drop k (x_after - x_before) at the median (the tip lands in the next
    well) and, along the branch, the cumulative hazard and the quasi-static force, ``(X - X_median, H, F)`` (a slip
    carried across a reversal, a slip in the tails, :func:`_scatter_moments`). ``H``: the hazard along the table if already computed.
    ``ext``: support positions and the cumulative hazard on them that replace the table's and the instability's end
    (an overdamped tip's noisy passage past the instability, :func:`_passage_hazard`); beyond ``X_c`` the branch's
    force is the lever's ``k (X - x_c)``, the tip held at the inflection."""
    X, dE, Xc, xs, xm = tab
    if ext is not None:
        Xe, H = ext
        C = 1.0 - np.exp(-H)
    else:
        H = thermal_hazard(tab, V, T, f0) if H is None else H
        C = np.append(1.0 - np.exp(-H), 1.0)
        Xe = np.append(X, Xc)
    keep = np.concatenate([[True], np.diff(C) > 0])
    C, Xe = C[keep], Xe[keep]
    Xq = np.interp(SLIP_NODES[0], C, Xe)
    Xmed = float(np.interp(0.5, C, Xe))
    # the tip lands in this well at the previous slip, a period before the median: no slip comes earlier (the
    # hazard before it, which the table's branch accumulates from the well's birth, is put at the landing)
    Xq = np.maximum(Xq, Xmed - a)
    q = 2 * math.pi / a
    F0 = q * U0
    xb = float(np.interp(Xmed, X, xm))
    xx = np.linspace(float(np.interp(Xmed, X, xs)), a + 0.25 * a, 4000)
    g = k * (Xmed - xx) - F0 * np.sin(q * xx)
    down = np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0]
    xa = float(xx[down[0]]) if len(down) else xb + a
    if ext is not None:
        Xg = ext[0]
        Fg = np.where(Xg < X[-1], np.interp(Xg, X, k * (X - xm)), k * (Xg - xm[-1]))
        return Xq - Xmed, k * (xa - xb), (Xg - Xmed, ext[1], Fg)
    return Xq - Xmed, k * (xa - xb), (X - Xmed, H, k * (X - xm))


#: the thermal mean's table (:func:`thermal_mean_shift`): the stick branch's support positions where the Boltzmann mean
#: is taken (interpolated to the barrier table's, whose memory it shares), and the points of its two grids (the
#: period behind the forward saddle, where the backward saddle is found; the well's thermal width each side of the
#: minimum, where the mean is taken). Against grids four times finer: within 2 % of the shift's largest value (measured
#: 0.7-2.0 % at U0 = 5-1500 k_B T; tests/test_diagnose_thermal_mean.py)
THERMAL_MEAN_POINTS = (100, 301, 201)
#: thermal widths of the well each side of its minimum that the mean is taken over (clipped to the saddles): the
#: Boltzmann weight there is exp(-WIDTHS^2 / 2) of the minimum's (1e-31), beyond any share of the mean
THERMAL_MEAN_WIDTHS = 12.0
#: corrugation over k_B T above which the shift is its leading term in T (the next is smaller by about k_B T / U0:
#: measured 0.3 % of the shift at U0 = 520 k_B T, and 0.03 % at 5200)
THERMAL_MEAN_LEADING = 2000.0
#: forward barrier [k_B T] below which the tip is no longer bound in its well: nearer the instability the mean over
#: the well is its wide backward side (the restricted Boltzmann mean turns to the other sign within about k_B T of
#: it), and an activated tip has slipped long before (:func:`thermal_slip_advance`); there the shift is held at its
#: value where the barrier is this high
THERMAL_MEAN_BOUND = 3.0


def thermal_mean_shift(U0: float, a: float, k: float, T: float):
    """The stick branch at a temperature: the lateral force's thermal mean less its quasi-static value, along the
    branch of the well at 0 (the support positions of :func:`_barrier_table`, motion in +x).

    Between slips the tip is in thermal equilibrium within its well: its relaxation time ``c / k_tot`` (about a
    microsecond) is far below a sample's time, so a sample records the Boltzmann mean of ``k (X - x)`` over the
    well, from its backward saddle to its forward one, ``exp(-E(x) / k_B T)`` with ``E = -U0 cos(q x) + k (X - x)^2
    / 2``. The well is asymmetric wherever the lever pulls: its forward side is the shallow one, so the mean lies
    ahead of the minimum and the recorded force below the quasi-static branch, by more the nearer the slip. Its
    leading term in T is ``k k_B T E3 / (2 E2^2)`` with ``E2 = k + q^2 U0 cos(q x_m)`` and
    ``E3 = -q^3 U0 sin(q x_m)``: the softening of the corrugation a fluctuating tip sees (the Debye-Waller factor
    ``exp(-q^2 k_B T / (2 E2))`` for small fluctuations). Where the forward barrier is below
    :data:`THERMAL_MEAN_BOUND` k_B T the shift is held (the tip is no longer bound). The quasi-static branch with
    the Kramers slip point alone fitted blind friction set 2's room-temperature records with a corrugation 7-19 %
    low and an attempt frequency 0.25-1.1 decades low: the low corrugation took the rounded branch, the low
    frequency kept the slips in place (docs/diagnose.md 9.55). Returns ``(X, dF, X_c)`` (``dF`` [N], read-only),
    None where the branch has no instability (eta <= 1) or T <= 0. Memoised."""
    if not (T > 0):
        return None
    return _thermal_mean_memo(float(U0), float(a), float(k), float(T))


@functools.lru_cache(maxsize=BARRIER_MEMORY)
def _thermal_mean_memo(U0: float, a: float, k: float, T: float):
    """:func:`thermal_mean_shift` computed: on a cold tip its leading term; else at :data:`THERMAL_MEAN_POINTS`
    support positions the well's backward saddle located on a grid over the period behind the forward saddle, then
    the mean on a grid across the well's thermal width ``sqrt(k_B T / E'')`` about the minimum
    (:data:`THERMAL_MEAN_WIDTHS` each side), clipped to the saddles; interpolated to the barrier table's positions."""
    tab = _barrier_table(U0, a, k)
    if tab is None:
        return None
    Xall, dEall, Xc, xsall, xmall = tab
    q = 2 * math.pi / a
    kT = K_B * T
    if U0 > THERMAL_MEAN_LEADING * kT:
        E2 = np.maximum(k + q * q * U0 * np.cos(q * xmall), 1e-300)
        dF = k * kT * (-(q**3) * U0 * np.sin(q * xmall)) / (2.0 * E2 * E2)
    else:
        rows, m1, m2 = THERMAL_MEAN_POINTS
        idx = np.unique(np.linspace(0, len(Xall) - 1, rows).astype(int))
        X, xs, xm = Xall[idx], xsall[idx], xmall[idx]

        def energy(x):
            return -U0 * np.cos(q * x) + 0.5 * k * (X[:, None] - x) ** 2

        x = xs[:, None] - a + a * np.linspace(0.0, 1.0, m1)[None, :]
        E = energy(x)
        back = np.argmax(np.where(x <= xm[:, None], E, -np.inf), axis=1)
        xb = x[np.arange(len(X)), back]
        width = np.sqrt(kT / np.maximum(k + q * q * U0 * np.cos(q * xm), 1e-300))
        lo = np.maximum(xb, xm - THERMAL_MEAN_WIDTHS * width)
        hi = np.minimum(xs, xm + THERMAL_MEAN_WIDTHS * width)
        x = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, m2)[None, :]
        Emin = -U0 * np.cos(q * xm) + 0.5 * k * (X - xm) ** 2
        w = np.exp(-np.clip(energy(x) - Emin[:, None], 0.0, 700.0 * kT) / kT)
        dF = np.interp(Xall, X, k * (xm - np.sum(w * x, axis=1) / np.sum(w, axis=1)))
    loose = np.nonzero(dEall < THERMAL_MEAN_BOUND * kT)[0]
    if len(loose) and loose[0] > 0:
        dF[loose[0]:] = dF[loose[0] - 1]
    elif len(loose):
        dF[:] = 0.0
    dF.setflags(write=False)
    return Xall, dF, Xc


def _thermal_mean_correction(F: np.ndarray, Xl: np.ndarray, direction: np.ndarray, st: "FrictionState", U0: float,
                             k: float) -> np.ndarray:
    """The thermal mean's shift (:func:`thermal_mean_shift`) at a scan's samples: each sample on the stick branch of
    the well its model force ``F`` places the tip in (``x = X - F / k``), mirrored for motion in -x; zero past the
    branch's instability and where no temperature is declared (``st.temperature`` 0: the record's temperature is
    not known, and an activation cause's assumed 295 K is no baseline's)."""
    if not st.temperature > 0 or U0 <= 0:
        return np.zeros(len(F))
    tab = thermal_mean_shift(U0, st.a, k, st.temperature)
    if tab is None:
        return np.zeros(len(F))
    Xt, dF, Xc = tab
    d = np.asarray(direction, float)
    n = np.round((Xl - F / k) / st.a)
    Xr = d * (Xl - n * st.a)
    return d * np.where(Xr <= Xc, np.interp(Xr, Xt, dF, left=0.0, right=0.0), 0.0)


def thermal_force_variance(F: np.ndarray, U0: float, a: float, k: float, c: float, T: float, dt: float) -> np.ndarray:
    """Variance of the lateral force sample ``k (X - x)`` from the tip's thermal motion in its well, per sample
    of a stick branch whose quasi-static force is ``F`` (equipartition and fluctuation-dissipation).

    In the well the tip is an oscillator of stiffness ``k_tot = k + U''(x)``, damping ``c`` and temperature T:
    its position varies by ``k_B T / k_tot`` (equipartition) about the stick branch, with the correlation time
    ``tau = c / k_tot`` of the overdamped limit. A sample that is the mean over an interval ``dt`` (an
    instrument's interval mean) averages that motion: the variance of the mean of an Ornstein-Uhlenbeck
    process, ``(k_B T / k_tot) (2 / u) (1 - (1 - exp(-u)) / u)`` with ``u = dt / tau``, which is the equipartition
    value at ``dt = 0`` (a point sample) and ``2 c k_B T / (k_tot^2 dt)`` for ``dt >> tau`` (the zero-frequency
    spectrum ``2 c k_B T / k_tot^2`` of the position, exact for an oscillator of any Q: its inertia sets only
    how fast the limit is reached). The force sample ``k (X - x)`` carries ``k^2`` times it. On the stick branch
    of the Prandtl-Tomlinson potential ``U0 cos(q x)`` the force is ``F = q U0 sin(q x)`` and
    ``U'' = q^2 U0 cos(q x) = q^2 U0 sqrt(1 - (F / q U0)^2)``, taken on the well's stable side (``k_tot >= k``;
    past the inflection, where the branch softens towards the slip, the slip-point scatter of the thermal
    activation term carries the samples). ``F``: the train's model force [N] before the detector's gain."""
    q = 2 * math.pi / a
    F0 = max(q * U0, 1e-300)
    sn = np.clip(np.asarray(F, float) / F0, -1.0, 1.0)
    kt = k + q * q * max(U0, 0.0) * np.sqrt(1.0 - sn * sn)
    var_x = K_B * T / kt
    if dt > 0:
        u = dt * kt / c
        # (2 / u)(1 - (1 - e^-u) / u), by its series where u is small (cancellation)
        shape = np.where(u > 1e-4, (2.0 / np.maximum(u, 1e-300)) * (1.0 - (-np.expm1(-u)) / np.maximum(u, 1e-300)),
                         1.0 - u / 3.0)
        var_x = var_x * shape
    return k * k * var_x


def _scatter_moments(Xl, seg_of, slips, dq, point: bool, paths, a: float, carry=None, nodes=None, atoms=None):
    """Mean shift and variance of every sample from the stochastic slip points, on the model's own path.

    A slip at ``Y = X* + d delta`` instead of the path's ``X*`` translates the slip and its transient
    (the tip's fall into the next well and its ringing) along the support by ``s = d delta``, while the stick
    branches before and after stay functions of the support position: near the slip the force is
    ``F(X - s) + k_b s``, with ``k_b`` the stick branches' slope ``dF/dX`` (the same for trace and retrace).
    On a straight branch this is ``F(X)``; across an instantaneous slip it moves the samples between ``X*``
    and ``Y`` from one branch to the other (the force differs by the drop there: the step model of the
    earlier code, which a test checks as the limit); a sample caught *during* a slip takes the transient's
    own slope times the shift (a fast scan's sample in the fall or the ringing: blind f11, 1 K, 500 nm/s,
    a sample at -11.4 sigma). Each slip moves the samples from ``reach`` (its largest shift) before it to
    ``reach`` plus half a lattice period after it, and no others (the next slip's own scatter is its own).
    ``paths``: the model path's (support, force) per segment (:func:`_segments`); samples are point values
    or interval means as the data's (``point``). ``dq``: the slip point's offsets at the quantile nodes
    ``nodes = (p, w)`` (probabilities and weights, :func:`slip_nodes`; default: equal-probability midpoints).

    The tails (the nodes below the quantile ``1 / SLIP_QUANTILES`` or above its complement, where ``carry`` has the
    branch's quasi-static force): the slip there may be most of a period from the median, where a translated path
    would carry the neighbouring slips; the samples between the median and the node's slip point exchange the two
    quasi-static branches instead (:func:`_branch_exchange`), and the translation is kept to the middle's reach.

    A slip near a reversal (``carry``: the force drop at the slip and the cumulative hazard ``H`` along the stick
    branch against the offset from the median slip point): a slip point beyond the segment's turn is a tip still
    stuck when the support turns. Going back, the support passes the same barriers again, so the hazard keeps
    accumulating at the rate of the same positions: the realization whose slip point needs the hazard
    ``H_j = -ln(1 - q_j)`` (its quantile) slips on the way back where ``H = 2 H_turn - H_j``, or not at all before
    the returning path's own slip where that is negative. Until then the returning samples sit on the branch of the
    old well, the drop above the path's (own seed 6000 at 300 K: the first retrace sample after a turn 0.1 nm past
    the median slip point, at 29 sigma against the path that had slipped before the turn).

    ``atoms`` (a list): receives the mixture itself, each (slip, sample) pair's offsets at the nodes
    (:class:`.mixture.SlipMixture`, the slip's index in ``slips`` its group), for the record's normal scores."""
    n = len(Xl)
    mean = np.zeros(n)
    var = np.zeros(n)
    if not slips:
        return mean, var
    dq = np.asarray(dq, float)
    if nodes is None:
        nodes = ((np.arange(len(dq)) + 0.5) / len(dq), np.full(len(dq), 1.0 / len(dq)))
    wq = np.asarray(nodes[1], float)[:, None]
    reach = float(np.max(np.abs(dq)))
    # the tails' realizations exchange the two quasi-static branches (the slip point's offsets ``u`` from the
    # median, the quasi-static force along the branch in the direction of motion: ``carry[1][0]``, ``carry[1][2]``)
    tail = np.zeros(len(dq), bool)
    if carry is not None and len(carry[1]) > 2:
        pq = np.asarray(nodes[0], float)
        tail = (pq < 1.0 / SLIP_QUANTILES) | (pq > 1.0 - 1.0 / SLIP_QUANTILES)
        u_b, f_b = carry[1][0], carry[1][2]
    inner = ~tail
    reach_mid = float(np.max(np.abs(dq[inner]))) if np.any(inner) else 0.0
    after = max(reach_mid + 0.5 * a, reach)
    lo, hi = _sample_bounds(Xl, seg_of, point)
    lo_, hi_ = np.minimum(lo, hi), np.maximum(lo, hi)
    seg_idx = {sg: np.nonzero(seg_of == sg)[0] for sg in np.unique(seg_of)}
    by_seg: dict[int, list[tuple[int, float, float]]] = {}
    for k, (sg, Xs, d) in enumerate(slips):
        by_seg.setdefault(sg, []).append((k, Xs, d))
    for sg, these in by_seg.items():
        b, f = paths[sg][0], paths[sg][1]
        o = np.argsort(b, kind="stable")
        b, f = b[o], f[o]
        db = np.diff(b)
        ok = db > 1e-9 * max(float(np.ptp(b)), 1e-300)
        # the stick branches' slope: the median over the path's steps (the tip sticks most of the way)
        kb = float(np.median(np.diff(f)[ok] / db[ok])) if np.any(ok) else 0.0
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * db)])
        if carry is not None and sg + 1 in seg_idx:  # the data go on after the turn ending this segment
            for k, Xs, d in these:
                _carry_across_turn(mean, var, lo, hi, seg_of, sg, Xs, d, dq, b, slips, carry, point, a, nodes,
                                   atoms=atoms, group=k)
        # the slip the path would have made next, had the support not turned: its early quantiles come before the
        # turn (blind g09: a slip 0.3 a early at the last sample, 4 % of the realizations, absent from the model)
        virtual = _next_slip(these, b, a, float(np.min(dq)))
        if virtual is not None:
            k_v = len(slips) + sg  # a group of its own (SlipMixture)
            if carry is not None and sg + 1 in seg_idx:  # its return: nodes of its own, and so a group of its own
                _carry_virtual(mean, var, lo, hi, seg_of, sg, virtual[0], virtual[1], dq, b, slips, carry[0], point,
                               a, nodes, atoms=atoms, group=len(slips) + len(paths) + sg)
            these = these + [(k_v, virtual[0], virtual[1])]
        seg = seg_idx.get(sg)
        if seg is None:
            continue
        # the samples each slip's scatter reaches: from its earliest quantile before it to the latest after it (the
        # translated path's: from the middle's reach before to that plus a / 2 after), in its direction of motion;
        # every (slip, sample) pair of the segment at once
        Xs = np.array([x for _, x, _ in these])[:, None]
        dd = np.array([d for _, _, d in these])[:, None]
        u_lo = np.where(dd > 0, lo_[seg][None, :] - Xs, Xs - hi_[seg][None, :])
        u_hi = np.where(dd > 0, hi_[seg][None, :] - Xs, Xs - lo_[seg][None, :])
        js, cs = np.nonzero((u_hi >= -reach) & (u_lo <= after))
        if not len(js):
            continue
        idx, u_lo, u_hi, d = seg[cs], u_lo[js, cs], u_hi[js, cs], dd[js, 0]
        # the translated path stands for the samples from reach before to reach + a / 2 after the slip (the
        # middle's reach), and not past a period less the reach (a sample there, read a reach earlier on the path,
        # would take the next slip's drop: a wide middle, an overdamped tip's noisy passage); beyond, a translation
        # would carry the neighbouring slips: there, the path itself
        near = (u_hi >= -reach_mid) & (u_lo <= min(reach_mid + 0.5 * a, a - reach_mid))
        Fs = np.empty((1 + len(dq), len(idx)))
        shift = np.concatenate([[0.0], dq[inner]])[:, None] * d[None, :]  # the path itself first
        Ft = _translated(Xl[idx], lo[idx], hi[idx], shift, b, f, cum, kb, point, a)
        Ft[1:, ~near] = Ft[0, ~near]
        Fs[0] = Ft[0]
        Fs[1:][inner] = Ft[1:]
        if np.any(tail):  # the tails: the samples between the median slip point and the node's on the other branch
            Fs[1:][tail] = Fs[0] + d * _branch_exchange(u_lo, u_hi, dq[tail], u_b, f_b, a, point)
        m = np.sum(wq * Fs[1:], axis=0)
        np.add.at(mean, idx, m - Fs[0])
        np.add.at(var, idx, np.sum(wq * (Fs[1:] - m) ** 2, axis=0))
        if atoms is not None:
            atoms.append(SlipMixture(idx, np.array([k for k, _, _ in these])[js], Fs[1:] - m, wq[:, 0]))
    return mean, var


def _next_slip(these, b, a: float, earliest: float) -> tuple[float, float] | None:
    """The slip a segment's path would have made after its last one had the support gone on past the turn: one
    slip spacing (the last two slips', else the lattice period) further, in the direction of motion. Returned as
    ``(X, d)`` where its earliest quantile (``earliest``, the slip point's least offset from the median, < 0) comes
    before the turn, else None (:func:`_scatter_moments`)."""
    if not these:
        return None
    _, X_last, d = these[-1]
    step = abs(X_last - these[-2][1]) if len(these) > 1 else a
    if not 0.5 * a < step < 1.5 * a:
        step = a
    X_v = X_last + d * step
    X_t = float(b[-1]) if d > 0 else float(b[0])
    u_t = d * (X_t - X_v)  # the turn's offset from the next slip's median point (negative: before it)
    if u_t >= 0 or u_t <= earliest:
        return None
    return X_v, d


def _carry_virtual(mean, var, lo, hi, seg_of, sg: int, X_v: float, d: float, dq, b, slips, drop: float,
                   point: bool, a: float, nodes, atoms=None, group: int = 0) -> None:
    """The returning segment's samples for the realizations of the next slip (:func:`_next_slip`, the path's
    median beyond the turn) that came before it: the tip turns one well ahead of the path's, so until its own slip
    back it reads the slip's drop below the path (in the direction of the first segment's motion). That slip back
    is the same activated backward instability as the returning path's first slip, a well further on: its median a
    period before that slip's, and its scatter that slip's quantiles (``dq``, in the returning direction), drawn
    independently of the forward slip's (a new barrier, crossed afresh); a realization whose slip back would come
    before the turn slips back at it. The law of each sample is then exact in ``1 + len(dq)`` nodes: the forward slip
    after the turn (probability ``1 - P_early``, no change), or before it and the slip back at node ``l``
    (``P_early w_l``). Before session 74 the slip back sat at its median: own seed 2002 at 300 K read a slip back
    more than half a sample past it at -45 sigma in one fold's fit (docs/diagnose.md 9.59). Adds to ``mean`` and
    ``var`` in place (``atoms``: the nodes' offsets, as the slip ``group``'s; these nodes are not the forward
    slip's, so the group is the caller's own for the return)."""
    Xt = float(b[-1]) if d > 0 else float(b[0])
    u_t = d * (Xt - X_v)
    dq = np.asarray(dq, float)
    w = np.asarray(nodes[1], float)
    early = dq < u_t
    p_early = float(np.sum(w[early]))
    if p_early <= 0.0:
        return
    back = [x for (g, x, dd) in slips if g == sg + 1]
    if not back:
        return
    X_rb = back[0] + d * a - d * dq  # the slip back of the tip a well ahead, at each node (returning: -d)
    X_rb = np.where(d * (X_rb - Xt) > 0, Xt, X_rb)
    first = float(np.min(d * X_rb))  # the latest slip back, in the first segment's direction
    if first >= d * Xt:
        return
    idx = np.nonzero((seg_of == sg + 1) & (d * np.maximum(lo, hi) > first) & (d * np.minimum(lo, hi) < d * Xt))[0]
    if not len(idx):
        return
    share = _covered(lo[idx], hi[idx], np.minimum(X_rb, Xt)[:, None], np.maximum(X_rb, Xt)[:, None], point)
    dF = np.vstack([np.zeros((1, len(idx))), -d * drop * share])
    _add_nodes(mean, var, idx, dF, (None, np.concatenate([[1.0 - p_early], p_early * w])), atoms, group)


def _covered(lo, hi, s_lo, s_hi, point: bool) -> np.ndarray:
    """The share of each sample's interval ``(lo, hi)`` (either order; a point where equal) inside the spans
    ``(s_lo, s_hi)`` (columns: one span per row), for the samples a carried realization moves to the other branch."""
    if point:
        x = 0.5 * (lo + hi)[None, :]
        return ((x >= s_lo) & (x <= s_hi)).astype(float)
    l_, h_ = np.minimum(lo, hi)[None, :], np.maximum(lo, hi)[None, :]
    return np.clip((np.minimum(h_, s_hi) - np.maximum(l_, s_lo)) / np.maximum(h_ - l_, 1e-300), 0.0, 1.0)


def _add_nodes(mean, var, idx, dF, nodes, atoms, group: int) -> None:
    """A slip's change ``dF`` (nodes x samples ``idx``) added to the samples' mean and variance over the nodes'
    weights (``atoms``: the offsets themselves, the slip ``group``'s, :class:`.mixture.SlipMixture`)."""
    wq = np.asarray(nodes[1], float)[:, None]
    m = np.sum(wq * dF, axis=0)
    mean[idx] += m
    var[idx] += np.sum(wq * (dF - m) ** 2, axis=0)
    if atoms is not None:
        atoms.append(SlipMixture(idx, np.full(len(idx), group), dF - m, wq[:, 0]))


def _sample_bounds(Xl, seg_of, point: bool) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's interval along the support (interval means: midway to its neighbours in its segment, the ends
    mirrored: a whole step, which is the sample's where the support turned half a step past it,
    :func:`_turn_overshoot`, and the first sample's after any turn) or its point (``lo = hi``). A turning point
    sampled once (the own generator) straddles the turn, half out and half back; it keeps the mirrored step, as the
    scatter always had it (the path's mean takes its half step out, :func:`_sample_path`)."""
    n = len(Xl)
    lo = np.empty(n)
    hi = np.empty(n)
    for sg in np.unique(seg_of):
        idx = np.nonzero(seg_of == sg)[0]
        x = Xl[idx]
        if point or len(x) < 2:
            lo[idx] = hi[idx] = x
            continue
        lo[idx], hi[idx] = _intervals(x, True, True)
    return lo, hi


def _turn_overshoot(Xl, starts, ends) -> np.ndarray:
    """How far past each segment's last sample the support turned (signed, along ``Xl``): half a sample step where
    the record gives the last sample of a segment and the first of the next the same position (an image's trace and
    retrace pixels over one range: each sample the mean over its own step, the turn at the range's edge, half a step
    beyond the pixels' centres; blind set 2), else 0 (the turning point sampled once, the return starting a step
    back: the own generator). The last segment ends as the record's other turns do.

    Read as turning at the last sample, a record that turned half a step later lost the slips the support met in
    that half step (blind g09: the last sample of a segment 26-44 sigma from every realization of the slip mixture,
    docs/diagnose.md 9.58)."""
    n_seg = len(starts)
    seg = [(int(s0), int(e0)) for s0, e0 in zip(starts, ends)]
    # half a step in each segment's direction (0 for a segment of one sample)
    half = np.array([0.5 * float(np.median(np.abs(np.diff(Xl[s0:e0])))) * np.sign(Xl[e0 - 1] - Xl[s0])
                     if e0 - s0 >= 2 else 0.0 for s0, e0 in seg])
    repeated = np.array([j + 1 < n_seg and abs(Xl[seg[j + 1][0]] - Xl[seg[j][1] - 1]) < 0.5 * abs(half[j])
                         for j in range(n_seg)])
    if n_seg > 1 and np.any(repeated[:-1] & (half[:-1] != 0)):
        repeated[-1] = True
    return np.where(repeated, half, 0.0)


def _carry_turns(mean, var, Xl, seg_of, slips, scat, point: bool, paths, a: float, atoms=None) -> None:
    """Every slip's part carried across the reversal that ends its segment (:func:`_carry_across_turn`), where the
    slips' own scatter is not :func:`_scatter_moments`' (an overdamped tip's noisy passage, :func:`_passage_moments`)."""
    lo, hi = _sample_bounds(Xl, seg_of, point)
    segs = set(int(g) for g in np.unique(seg_of))
    for k, (sg, Xs, d) in enumerate(slips):
        if sg + 1 in segs and sg < len(paths):
            b = np.sort(paths[sg][0], kind="stable")
            _carry_across_turn(mean, var, lo, hi, seg_of, sg, Xs, d, np.asarray(scat[0], float), b, slips,
                               (scat[1], scat[2]), point, a, SLIP_NODES, atoms=atoms, group=k)


def _translated(x, lo, hi, shift, b, f, cum, kb: float, point: bool, a: float) -> np.ndarray:
    """The path ``(b, f)`` (``cum``: its running integral) translated along the support by each ``shift`` (a column)
    and raised by ``kb shift``, at point samples ``x`` or interval means over ``(lo, hi)`` (:func:`_scatter_moments`).

    A translated position beyond the segment's path (a sample near the turn, read for a slip earlier than the
    path's: the path ends at the turn) is read a whole number of lattice periods ``a`` back inside it: the stick-slip
    before a turn is periodic in the support, ``F(X + a) = F(X)`` (its running integral gains one period's integral
    per period). Held at the path's last value instead (before session 73), an interval mean past the end read 0 pN
    (blind g09: the last sample of three segments at 12-26 sigma from every node of the mixture)."""
    if point:
        Fs = np.interp(_periodic(x[None, :] - shift, b, a)[0], b, f)
    else:
        a_, b_ = lo[None, :] - shift, hi[None, :] - shift
        w = b_ - a_
        Fs = np.where(np.abs(w) > 0, (_cum_at(b_, b, cum, a) - _cum_at(a_, b, cum, a)) / np.where(w == 0, 1.0, w),
                      np.interp(_periodic(x[None, :] - shift, b, a)[0], b, f))
    return Fs + kb * shift


def _periodic(q, b, a: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``q`` moved by whole periods ``a`` into the path's span ``[b[0], b[-1]]`` where beyond it, and the
    number of periods each was moved back (positive past the end); unchanged where the span is shorter than a period
    or ``a`` is 0 (:func:`_translated`)."""
    q = np.asarray(q, float)
    n = np.zeros(q.shape)
    if a <= 0 or b[-1] - b[0] < a:
        return q, n
    n = np.where(q > b[-1], np.ceil((q - b[-1]) / a), np.where(q < b[0], -np.ceil((b[0] - q) / a), 0.0))
    return q - n * a, n


def _cum_at(q, b, cum, a: float) -> np.ndarray:
    """The path's running integral ``cum`` at ``q``, continued periodically beyond its span (:func:`_periodic`): a
    period past the end adds the last period's integral, one before the start takes away the first's."""
    qq, n = _periodic(q, b, a)
    out = np.interp(qq, b, cum)
    if np.any(n):
        last = float(cum[-1] - np.interp(b[-1] - a, b, cum))
        first = float(np.interp(b[0] + a, b, cum) - cum[0])
        out = out + np.where(n > 0, n * last, n * first)
    return out


def _branch_exchange(u_lo, u_hi, uq, u_b, f_b, a: float, point: bool) -> np.ndarray:
    """A slip far from the median (a tail quantile of the slip point, :func:`_scatter_moments`): the force change
    of samples ``(u_lo, u_hi)`` (interval means, or points where equal; offsets from the median slip point in the
    direction of motion) for slips at ``uq``, in the direction of motion. A sample between the median and a slip
    later than it (``u_q > 0``) is still on the stick branch before the slip, ``f(u)``, where the path has slipped
    to the next well's, ``f(u - a)``: it is higher by the drop ``f(u) - f(u - a)`` there; a slip earlier than the
    median puts the samples between them that much lower. ``f``: the quasi-static branch ``(u_b, f_b)`` of the
    barrier table. The translated path (:func:`_scatter_moments`) stands for the realization near the median; over
    a tail's shift, up to most of a period at U0 = 5 k_B T, it would carry the neighbouring slips and extrapolate
    the branch by its median slope (blind g09: a mean beyond both branches). Returns ``(len(uq), len(u_lo))``."""
    u0, u1 = np.minimum(uq, 0.0)[:, None], np.maximum(uq, 0.0)[:, None]
    if point:
        frac = ((u_lo[None, :] > u0) & (u_lo[None, :] < u1)).astype(float)
        um = np.broadcast_to(u_lo[None, :], frac.shape)
    else:
        o0, o1 = np.maximum(u_lo[None, :], u0), np.minimum(u_hi[None, :], u1)
        width = np.maximum(u_hi - u_lo, 1e-300)[None, :]
        frac = np.clip((o1 - o0) / width, 0.0, 1.0)
        um = 0.5 * (o0 + o1)
    drop = np.interp(um, u_b, f_b) - np.interp(um - a, u_b, f_b)
    return np.sign(uq)[:, None] * frac * drop


def _carry_across_turn(mean, var, lo, hi, seg_of, sg: int, Xs: float, d: float, dq, b, slips, carry, point: bool,
                       a: float, nodes, atoms=None, group: int = 0) -> None:
    """The part of a slip's scatter carried across the reversal that ends its segment (:func:`_scatter_moments`):
    adds to ``mean`` and ``var`` of the returning segment's samples in place (``atoms``: the nodes' offsets too,
    as the slip ``group``'s: the same realization as before the turn)."""
    drop, (u_tab, H_tab) = carry[0], carry[1][:2]
    M = len(dq)
    Xt = float(b[-1]) if d > 0 else float(b[0])  # the turn: the segment's far end in the direction of motion
    u_t = d * (Xt - Xs)  # the turn's offset from the median slip point, in the direction of motion
    beyond = np.nonzero(dq > u_t)[0]
    if not len(beyond) or u_t < float(u_tab[0]):
        return
    H_t = float(np.interp(u_t, u_tab, H_tab))
    Hq = -np.log1p(-np.asarray(nodes[0], float))  # the hazard each quantile's slip point needs
    # the returning path's own first slip: beyond it the realizations are one again
    back = [x for (g, x, dd) in slips if g == sg + 1]
    X_end = back[0] if back else Xt - d * a
    rest = 2.0 * H_t - Hq[beyond]
    u_back = np.where(rest > float(H_tab[0]), np.interp(np.maximum(rest, float(H_tab[0])), H_tab, u_tab), np.nan)
    X_back = np.where(np.isfinite(u_back), Xs + d * u_back, X_end)  # support position of the slip on the way back
    idx = np.nonzero((seg_of == sg + 1) & (d * np.maximum(lo, hi) > d * X_end - 1e-15) & (d * np.minimum(lo, hi) < d * Xt))[0]
    if not len(idx):
        return
    # each carried realization: the samples between its slip on the way back and the turn are the drop higher
    # (in the direction of the slip: d * drop), by the share of each sample's interval they cover
    share = _covered(lo[idx], hi[idx], np.minimum(X_back, Xt)[:, None], np.maximum(X_back, Xt)[:, None], point)
    dF = np.zeros((M, len(idx)))
    dF[beyond] = d * drop * share
    _add_nodes(mean, var, idx, dF, nodes, atoms, group)


def _centre(scan: FrictionScan) -> float:
    """The support position the lattice registry refers to: the middle of the scan. (Referred to
    one end, a change of the lattice period moves every slip of the scan and the registry with it;
    the least-squares fit of the period at a fixed registry then converges only slowly.)"""
    return 0.5 * (float(scan.position.min()) + float(scan.position.max()))


def _coupled(st: FrictionState) -> bool:
    """A misaligned scan whose lever holds the tip across the scan with another stiffness than along it: the
    lattice axes do not decouple (:func:`simulate_scan_2d`)."""
    return st.theta > 1e-6 and st.ky_ratio != 1.0


def _polish(fun, x: float, cx: float, steps, repeat: int = 1) -> tuple[float, float]:
    """Minimise a rugged 1D ``fun`` from ``x`` (value ``cx``): per step size the two neighbours and, where the three
    points are convex, the parabola's vertex (at most two steps away); the lowest of them is kept, and the step is
    repeated (at most ``repeat`` times) while the minimum lies beyond them (the vertex beyond two steps, or a
    neighbour lowest without one)."""
    for h in steps:
        for _ in range(repeat):
            cm, cp = fun(x - h), fun(x + h)
            den = cm - 2 * cx + cp
            pts = [(cx, x), (cm, x - h), (cp, x + h)]
            inside = False  # the parabola's vertex lies within two steps: the minimum is bracketed
            if den > 0:
                dx = 0.5 * h * (cm - cp) / den
                inside = abs(dx) < 2 * h
                xn = x + float(np.clip(dx, -2 * h, 2 * h))
                pts.append((fun(xn), xn))
            c_new, x_new = min(pts)
            moved = abs(x_new - x)
            cx, x = c_new, x_new
            if inside or moved < h:  # the minimum lies within reach of this step: on to the finer one
                break
    return x, cx


def _intervals(xs: np.ndarray, full_start: bool = False, full_end: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The support interval of each interval-mean sample at positions ``xs`` (one monotone segment): from the midpoint
    with the previous sample to the midpoint with the next; the segment's ends at its first and last sample, or a
    whole step (mirrored) where the support runs on past it (``full_start``: a pre-roll or a turn half a step before
    the first sample; ``full_end``: the turn half a step after the last, :func:`_turn_overshoot`)."""
    mid = 0.5 * (xs[1:] + xs[:-1])
    first = xs[0] - (mid[0] - xs[0]) if full_start else xs[0]
    last = xs[-1] + (xs[-1] - mid[-1]) if full_end else xs[-1]
    return np.concatenate([[first], mid]), np.concatenate([mid, [last]])


def _path_intervals(xs: np.ndarray, j: int, ext) -> tuple[np.ndarray, np.ndarray]:
    """The intervals the path's mean is taken over in segment ``j`` (:func:`_intervals`): a whole step at an end where
    the support turned half a step past it (``ext``, :func:`_turn_overshoot`) and at the start after such a turn (or
    the pre-roll, in a record whose turns do so); else half a step at the ends, as before session 73 (``ext`` None)."""
    if ext is None or not np.any(ext):
        return _intervals(xs)
    return _intervals(xs, j == 0 or ext[j - 1] != 0, ext[j] != 0)


def _sample_path(res, Xl: np.ndarray, starts, ends, n_seg: int, sampling: str, ext=None) -> np.ndarray:
    """The model's lateral force at a scan's samples from a path result along the support coordinate ``Xl``:
    the value at the sample's position (``sampling = "point"``) or its mean over the sample's interval, per
    monotone segment (``starts``/``ends``: the data's segments; the pre-roll runs on into the first; ``ext``: the turns'
    overshoot, :func:`_turn_overshoot`, None: the segments' ends at their end samples)."""
    F = np.empty(len(Xl))
    seg_model = _segments(res, n_seg)
    for j, (s0, e0) in enumerate(zip(starts, ends)):
        mb, mf, mt = seg_model[j]
        xs = Xl[s0:e0]
        order = np.argsort(mb)
        b, fz = mb[order], mf[order]
        if sampling == "point" or len(xs) < 2:
            F[s0:e0] = np.interp(xs, b, fz)
        else:
            cum = np.concatenate([[0.0], np.cumsum(0.5 * (fz[1:] + fz[:-1]) * np.diff(b))])
            lo, hi = _path_intervals(xs, j, ext)
            width = hi - lo
            Ilo, Ihi = np.interp(lo, b, cum), np.interp(hi, b, cum)
            with np.errstate(invalid="ignore", divide="ignore"):
                F[s0:e0] = np.where(np.abs(width) > 0, (Ihi - Ilo) / np.where(width == 0, 1.0, width), np.interp(xs, b, fz))
    return F


def _support(scan: FrictionScan, st: FrictionState) -> np.ndarray:
    """The support's true positions at a scan's samples: the recorded ones bowed by the scanner (``st.bow``)."""
    X = scan.position
    if st.bow:
        # the bow's displacement less its value at the centre (a constant shift is a registry change,
        # and the registry is profiled at the centre: referred to the ends, bow and registry trade off
        # and the alternating fit stalls in another basin)
        x0, x1 = X.min(), X.max()
        X = X + st.bow * ((X - x0) * (x1 - X) / max(x1 - x0, 1e-30) - 0.25 * (x1 - x0))
    return X


def _segment_edges(scan: FrictionScan):
    """First and one-past-last sample of each monotone segment (trace, retrace, ...) of a scan."""
    cuts = np.nonzero(np.diff(scan.direction) != 0)[0] + 1
    return np.concatenate([[0], cuts]), np.concatenate([cuts, [len(scan.position)]])


def simulate_scan_2d(data: FrictionData, st: FrictionState, scan: FrictionScan, phis, hmax_frac: float = 0.5
                     ) -> np.ndarray:
    """Model lateral force of a misaligned scan whose lever holds the tip with ``k_y = st.ky_ratio k_x`` across
    the scan: the two lattice axes coupled through the lever (:func:`probedyn.schemes.ffm_lattice2d.lattice2d_path`;
    for ``k_y = k_x`` they decouple into the two trains of :func:`simulate_scan`). ``phis[0]``, ``phis[1]``: the
    lattice's registry along its two axes at the scan's centre, as the trains'. The damping across the scan is
    the one along it, ``c_y = c_x``, as in the source's Table 2.1 (c_x = c_y = 7e-9 N s/m with k_y = k_x / 2):
    the dissipation is the contact's and the medium's, not the lever's bending. Athermal: a 2D tip's activated
    slips are not modelled, nor its thermal mean over the well (:func:`thermal_mean_shift`)."""
    from probedyn.schemes.ffm_lattice2d import lattice2d_path

    Xs = _support(scan, st) - _centre(scan)
    V = scan.speed
    U0 = max(st.u0 * effective_load(st, scan.load), 1e-30)
    cp = _ffm(data, U0, st.a, st.gamma).cantilever
    k, m, c = cp["k_x"], cp["m_x"], cp["c_x"]
    ky = st.ky_ratio * k
    starts, ends = _segment_edges(scan)
    d0 = scan.direction[0]
    # the pre-roll carries each lattice axis through PREROLL periods of its own, as the decoupled trains' do
    # (the y axis's a / sin(theta) along the scan): the model is then continuous into theirs at k_y = k_x
    pre = PREROLL * st.a / max(min(math.sin(st.theta), math.cos(st.theta)), 1e-3)
    ext = _turn_overshoot(Xs, starts, ends)
    turns = [Xs[0] - d0 * pre, Xs[0]] + [Xs[e - 1] + x for e, x in zip(ends, ext)]
    # phis[2] (if given): the tip starts the pre-roll that many lattice periods from the support along the lattice's
    # x axis, at rest (the trains' start well, :func:`simulate_scan`, train 0)
    well = round(phis[2]) * st.a if len(phis) > 2 else 0.0
    y0 = (turns[0] + math.cos(st.theta) * well, -math.sin(st.theta) * well, 0.0, 0.0)
    dX = float(np.median(np.abs(np.diff(Xs)))) if len(Xs) > 1 else st.a
    res = lattice2d_path(U0=U0, a=st.a, theta=st.theta, k_x=k, k_y=ky, m=m, c_x=c, c_y=c, turns=turns, speed=V,
                         phases=(phis[0], phis[1]), gamma=max(st.gamma, 0.0), y0=y0, hmax=hmax_frac * dX / max(V, 1e-30),
                         rtol=RTOL, atol_rel=RTOL, atol_v=100 * V)
    return _sample_path(res, Xs, starts, ends, len(turns) - 2, data.sampling, ext)


def simulate_scan(data: FrictionData, st: FrictionState, scan: FrictionScan, phis, hmax_frac: float = 0.5,
                  train: int = 0, var_out: list | None = None, skip_out: list | None = None,
                  atoms: list | None = None) -> np.ndarray:
    """Model lateral force of one lattice train (0: along x, 1: along y of a misaligned scan) at
    the scan's samples, for lattice registry ``phis[train]``; ``phis[2]`` (if given) is the well the tip
    starts the pre-roll in along the x train, in lattice periods from the support (0: under it; at rest). With thermally
    activated slips the force is the mean over the slip points' distribution and ``var_out`` (a list)
    receives its variance per sample (the stochastic slip-position scatter). ``skip_out`` (a list) receives the
    path's slips that could have carried the tip one well further (:func:`_skip_regions`). ``atoms`` (a list)
    receives the slip points' mixture itself (:func:`_scatter_moments`)."""
    X = _support(scan, st)
    Xc = _centre(scan)
    w = math.cos(st.theta) if train == 0 else math.sin(st.theta)
    Xl = (X - Xc) * w - phis[train]  # the registry is the lattice's offset at the scan's centre
    V = scan.speed * w
    U0 = st.u0 * effective_load(st, scan.load)
    ffm = _ffm(data, U0, st.a, st.gamma)
    d0 = scan.direction[0]
    starts, ends = _segment_edges(scan)
    ext = _turn_overshoot(Xl, starts, ends)
    turns = [Xl[0] - d0 * PREROLL * st.a, Xl[0]] + [Xl[e - 1] + x for e, x in zip(ends, ext)]
    x0 = turns[0] + (round(phis[2]) * st.a if len(phis) > 2 and train == 0 else 0.0)
    # resolve the stick branches between samples: the step at most half a sample interval
    dX = float(np.median(np.abs(np.diff(Xl)))) if len(Xl) > 1 else st.a
    hmax = hmax_frac * dX / max(V, 1e-30)
    slips = None
    if st.thermal is not None and U0 > 0:
        res, slips, scat = _thermal_path(ffm, turns, V, st, hmax, x0)
    else:
        res = _ffm_path(ffm, turns, V, hmax, (x0, 0.0, 0.0))
    F = _sample_path(res, Xl, starts, ends, len(turns) - 2, data.sampling, ext)
    # between slips the tip samples its well thermally: the recorded force is the Boltzmann mean (thermal_mean_shift)
    F = F + _thermal_mean_correction(F, Xl, scan.direction, st, U0, ffm.cantilever["k_x"])
    if skip_out is not None and slips:  # landing wells at random where the slips are activated (_skip_regions)
        skip_out.extend(_skip_regions(res, len(turns) - 2, Xl, starts, ends, data.sampling, st.a,
                                      ffm.cantilever["k_x"], U0, ext))
    var = np.zeros(len(X))
    if slips:
        seg_of = np.zeros(len(X), int)
        for j, (s0, e0) in enumerate(zip(starts, ends)):
            seg_of[s0:e0] = j
        paths = _segments(res, len(turns) - 2)
        if len(scat) > 3:  # an overdamped tip's noisy passage: each node's own trace (_passage_realizations)
            mean, var = np.zeros(len(Xl)), np.zeros(len(Xl))
            _passage_moments(Xl, seg_of, slips, data.sampling == "point", scat[3], SLIP_NODES[1], mean, var, atoms)
            _carry_turns(mean, var, Xl, seg_of, slips, scat, data.sampling == "point", paths, st.a, atoms)
        else:
            mean, var = _scatter_moments(Xl, seg_of, slips, scat[0], data.sampling == "point", paths, st.a,
                                         carry=(scat[1], scat[2]), nodes=SLIP_NODES, atoms=atoms)
        F = F + mean
    if var_out is not None:
        var_out.append(var)
    return F


def _nbytes(*arrays) -> int:
    """Bytes held by the arrays among ``arrays`` (a kept scan model, :meth:`FrictionProblem._scan_model`)."""
    return sum(a.nbytes for a in arrays if isinstance(a, np.ndarray))


def _ffm_path(ffm: FFM, turns, V: float, hmax: float, y0):
    """The FFM line scan along ``turns`` from state ``y0`` at the diagnosis' tolerances."""
    return line_scan_path(ffm, turns, speed=V, y0=y0, hmax=hmax, rtol=RTOL, atol_rel=RTOL, atol_v=100 * abs(V))


def _segments(res, n_seg: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Split a path result into its monotone support segments (at the reversals)."""
    b = res.base
    edges = _path_edges(res)
    out = []
    for i0, i1 in zip(edges[:-1], edges[1:]):
        sl = slice(i0, i1 + 1)
        out.append((b[sl], res.lateral_force[sl], res.t[sl]))
    if len(out) != n_seg:
        raise ProbedynError(f"FFM path: expected {n_seg} monotone segments, found {len(out)}")
    return out


def _path_edges(res) -> np.ndarray:
    """The path points where a path result's support reverses (and its ends), kept on the result (``_edges``): a
    scan's path is split by the sampling, the slips' scatter and the landing wells, each once per model evaluation."""
    edges = getattr(res, "_edges", None)
    if edges is not None:
        return edges
    b = res.base
    db = np.diff(b)
    # steps below 1e-9 of the path's span are round-off where integrated pieces meet (the end
    # of one piece, X_a + V T, may overshoot the start of the next by an ulp): no direction
    d = np.sign(np.where(np.abs(db) > 1e-9 * max(float(np.ptp(b)), 1e-300), db, 0.0))
    nz = np.nonzero(d)[0]  # repeated points keep the direction of travel
    d = d[nz[np.maximum(np.searchsorted(nz, np.arange(len(d)), side="right") - 1, 0)]]
    cuts = np.nonzero(d[1:] * d[:-1] < 0)[0] + 1
    edges = np.concatenate([[0], cuts, [len(b) - 1]])
    try:
        res._edges = edges
    except AttributeError:  # pragma: no cover - a result that takes no attributes
        pass
    return edges


#: median advance of an activated slip (in lattice periods) from which the tip is placed over the saddle at
#: the median slip point (:func:`_thermal_path`); below it the slips are the athermal path's, scattered
#: about the instability (the stick branch's slope over the advance neglected: a relative error of the
#: order of the advance over a period)
THERMAL_PLACE_ADVANCE = 0.05


def _athermal_slips(res, n_seg: int, a: float, k: float, Xc: float, delays: list | None = None
                    ) -> list[tuple[int, float, float]]:
    """The slips of an athermal path as (data segment, support position of the instability, direction):
    every change of the tip's well in the direction of motion starts a slip at the instability of the well
    it leaves, ``n a + d X_c`` (a slip over several wells counts once: the changes within a tenth of a
    period of support travel of the first). ``delays`` (a list) receives each slip's support travel from the
    instability to the change of well (the saddle-node's delay, :func:`_passage_hazard`)."""
    out = []
    for j, (b, f, _) in enumerate(_segments(res, n_seg)):
        if len(b) < 2:
            continue
        d = 1.0 if b[-1] > b[0] else -1.0
        well = np.round((b - f / k) / a)
        last = None
        for c in np.nonzero(np.diff(well) * d > 0)[0]:
            if last is not None and abs(b[c] - last) < 0.1 * a:
                continue
            last = float(b[c])
            out.append((j, float(well[c]) * a + d * Xc, d))
            if delays is not None:
                delays.append(d * (0.5 * (b[c] + b[c + 1]) - float(well[c]) * a) - Xc)
    return out


#: support travel before the instability [lattice periods] from which an overdamped tip's noisy passage
#: (:func:`_passage_hazard`) adds its rate: there the normal form's cubic barrier is within 8 % of the Prandtl-Tomlinson
#: barrier at eta = 2 and within 2 % at eta >= 6 (measured on the barrier table)
PASSAGE_REACH = 0.2
#: the noisy passage's shift of the median slip and its 10-90 % spread [lattice periods] below which it is left out
#: (a fast scan on a critically damped lever at 1 K: 4e-3 of a period; g16's fast scan 0.1)
PASSAGE_MIN = 5e-3
#: the cumulative hazard at which an extended slip-point grid ends (a survival of e^-40)
PASSAGE_END_HAZARD = 40.0


def _passage_hazard(tab, U0: float, a: float, k: float, V: float, T: float, f0: float, gamma: float, m: float,
                    delay: float | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """The activated slip point's cumulative hazard of an overdamped tip, through its noisy passage past the
    instability (:mod:`probedyn.schemes.ffm_passage`): along the support, the larger of Kramers' rate on the quasi-static barrier
    (attempt frequency ``f0``, :func:`thermal_hazard`) and the normal form's, the latter from
    :data:`PASSAGE_REACH` before the instability ``X_c`` to where every tip has gone. The normal form's passage is
    placed so that its noiseless one falls at ``X_c + delay`` (the athermal path's own change of well,
    :func:`_athermal_slips`; default: the normal form's own, ``2.17 V t*``). ``gamma``: the tip's whole damping
    (lever and substrate), ``m`` its mass. Returns ``(X, H)`` on a grid from the table's start, or None where the
    tip is not overdamped at the passage, its noise is outside the normal form's table
    (:func:`probedyn.schemes.ffm_passage.bottleneck_scales`, :data:`probedyn.schemes.ffm_passage.THETA_RANGE`) or the passage's noise moves the slip by
    less than :data:`PASSAGE_MIN` of a period: the slip is then the hazard's and the integrator's alone."""
    sc = bottleneck_scales(U0, a, k, V, gamma, m, T)
    nf = escape_hazard(sc["theta"]) if sc is not None else None
    if nf is None:
        return None
    s, Hs = nf
    X, dE, Xc = tab[0], tab[1], tab[2]
    L = V * sc["t_star"]
    s_det = deterministic_escape()
    q10, q50, q90 = np.interp([0.1, 0.5, 0.9], 1.0 - np.exp(-Hs), s)
    if L * max(abs(q50 - s_det), q90 - q10) < PASSAGE_MIN * a:
        return None  # the noise moves the passage by less than the integrator's own tolerance on the slip
    if fall_substeps(V, k, U0, a, gamma, PASSAGE_STEP * a) > FALL_MAX_SUBSTEPS:
        return None  # the tip relaxes far faster than the passage: not the overdamped bottleneck
    Xs = Xc + (L * s_det if delay is None else delay) + L * (s - s_det)
    Xg = np.union1d(X, Xs[(Xs > X[0]) & (Xs >= Xc - PASSAGE_REACH * a)])
    r_kr = np.interp(Xg, X, f0 * np.exp(-dE / (K_B * T)) / V, right=0.0)
    r_nf = np.where(Xg >= Xc - PASSAGE_REACH * a, np.interp(Xg, Xs, np.gradient(Hs, Xs), left=0.0), 0.0)
    r = np.maximum(r_kr, np.maximum(r_nf, 0.0))
    Hg = np.concatenate([[0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * np.diff(Xg))])
    end = int(np.searchsorted(Hg, PASSAGE_END_HAZARD)) + 1
    return Xg[:end], Hg[:end]


#: the realizations' grid step along the support [lattice periods] (:func:`_passage_realizations`)
PASSAGE_STEP = 1.0 / 400.0
#: tip positions within this fraction of a period count as the same (a realization back on the path's branch)
PASSAGE_MERGE = 1e-3
#: the nodes' traces kept (:func:`_thermal_path`: per model and speed, least recently made dropped first)
PASSAGE_MEMORY = 64
_PASSAGE_MEMO: OrderedDict = OrderedDict()
#: falls integrated per direction (:func:`_passage_realizations`): at nodes spread evenly over the slip points'
#: quantile nodes, each node taking the nearest one's fall moved by their distance (0.01-0.03 of a period in the
#: middle, where the fall's pace changes by a few per cent)
PASSAGE_FALLS = 12


def _passage_realizations(res, n_seg: int, slips, dq, a: float, k: float, U0: float, V: float, gamma: float,
                          X_cross: float) -> dict:
    """Each slip-point node's own force trace about an overdamped tip's slip, less the path's (:func:`_passage_hazard`):
    the slip's scatter where the noisy passage spreads it over a fifth of a period and more (blind g16, 1.5 um/s:
    10-90 % over 0.3 a). A realization that changes well at ``dq`` from the path's change of well (support travel,
    in the direction of motion) is on the path's branch before it (past the path's force peak, the tip held there:
    the lever's force rising at ``k``), falls from the lattice maximum at ``dq`` (:func:`probedyn.schemes.ffm_passage.overdamped_falls`:
    the fall's pace set by the tilt where it starts, which a translated path would carry from the median) and is on
    the path's branch again when its tip is within :data:`PASSAGE_MERGE` of a period of the path's. ``X_cross``: the
    path's change of well from its well's centre (motion in +x). Returns per direction ``d`` (+1, -1) the offsets
    ``u`` from the change of well and the traces' differences ``(node, u)`` in the data's sign; a direction without a
    slip inside a segment is left out."""
    out = {}
    dq = np.asarray(dq, float)
    h = PASSAGE_STEP * a
    segs = _segments(res, n_seg)
    for d in (1.0, -1.0):
        # a representative slip of this direction: the one with the most path on each side within its segment
        best, span = None, -1.0
        for j, M, dd in slips:
            if dd != d:
                continue
            b = segs[j][0]
            room = min(d * (M - b[0]), d * (b[-1] - M))  # the segment in time order: b[0] its start
            if room > span:
                best, span = (j, M), room
        if best is None or span < 0.5 * a:
            continue
        j, M = best
        b, f = segs[j][0], segs[j][1]
        u_p = d * (b - M)
        o = np.argsort(u_p, kind="stable")
        u_p, F_p = u_p[o], d * f[o]  # the path along the motion, its force in the direction of motion
        keep = np.concatenate([[True], np.diff(u_p) > 0])
        u_p, F_p = u_p[keep], F_p[keep]
        before = (u_p > -0.5 * a) & (u_p <= 0.0)
        if not np.any(before):
            continue
        i_pk = np.nonzero(before)[0][int(np.argmax(F_p[before]))]
        u_pk, F_pk = float(u_p[i_pk]), float(F_p[i_pk])
        lo = min(float(dq.min()), u_pk) - h
        hi = min(max(float(dq.max()), 0.0) + 0.75 * a, float(u_p[-1]))
        u = np.arange(lo, hi + 0.5 * h, h)
        Fp = np.interp(u, u_p, F_p)
        xp = (X_cross + u) - Fp / k  # the path's tip from its well's centre
        held = np.where(u < u_pk, Fp, F_pk + k * (u - u_pk))
        n_out = int(round((hi - float(dq.min())) / h)) + 2
        order = np.argsort(dq, kind="stable")
        picks = order[np.unique(np.round(np.linspace(0, len(dq) - 1, PASSAGE_FALLS)).astype(int))]
        xs = overdamped_falls(X_cross + dq[picks], 0.5 * a, V, k, U0, a, gamma, h, n_out)
        D = np.zeros((len(dq), len(u)))
        for i, dqi in enumerate(dq):
            j_f = int(np.argmin(np.abs(dq[picks] - dqi)))  # the nearest fall, moved along by the distance
            uf = dqi + h * np.arange(n_out)
            xf = np.interp(u, uf, xs[j_f], left=np.nan, right=np.nan)
            Fq = np.where(u < dqi, held, k * ((X_cross + u) - xf))
            back = np.nonzero((u > max(dqi, 0.0)) & (np.abs(xf - xp) < PASSAGE_MERGE * a))[0]
            if len(back):
                Fq[back[0]:] = Fp[back[0]:]
            Fq = np.where(np.isfinite(Fq), Fq, Fp)
            D[i] = Fq - Fp
        out[d] = (u, d * D)
    return out


def _passage_moments(Xl, seg_of, slips, point: bool, real: dict, weights, mean, var, atoms=None) -> None:
    """Mean shift and variance of every sample near an overdamped tip's slips from the nodes' own traces
    (:func:`_passage_realizations`), interval means or points as the data's; added to ``mean`` and ``var`` in
    place (``atoms``: the nodes' offsets, :func:`_scatter_moments`)."""
    w = np.asarray(weights, float)[:, None]
    lo, hi = _sample_bounds(Xl, seg_of, point)
    # each node's running integral along the support (interval means: its differences over the sample's interval)
    cums = {d: np.concatenate([np.zeros((len(D), 1)), np.cumsum(0.5 * (D[:, 1:] + D[:, :-1]) * np.diff(u), axis=1)],
                              axis=1) for d, (u, D) in real.items()}
    for k, (sg, M, d) in enumerate(slips):
        if d not in real:
            continue
        u, D = real[d]
        idx = np.nonzero(seg_of == sg)[0]
        u0, u1 = d * (lo[idx] - M), d * (hi[idx] - M)
        ul, uh = np.minimum(u0, u1), np.maximum(u0, u1)
        near = (uh >= u[0]) & (ul <= u[-1])
        if not np.any(near):
            continue
        idx, ul, uh = idx[near], ul[near], uh[near]
        if point:
            Dm = np.array([np.interp(ul, u, Dq, left=0.0, right=0.0) for Dq in D])
        else:
            width = np.maximum(uh - ul, 1e-300)
            Dm = np.array([(np.interp(uh, u, c) - np.interp(ul, u, c)) / width for c in cums[d]])
        m = np.sum(w * Dm, axis=0)
        np.add.at(mean, idx, m)
        np.add.at(var, idx, np.sum(w * (Dm - m) ** 2, axis=0))
        if atoms is not None:
            atoms.append(SlipMixture(idx, np.full(len(idx), k), Dm - m, w[:, 0]))


#: the least chi^2 a skipped well must gain to be taken (:meth:`FrictionProblem._skips`): a whole stick segment on the
#: next well's branch, one slip's drop from the model (blind f08: 120 sigma), is either the data's or far from them;
#: a gain of 25 (one 5 sigma sample) is not reached by noise on a branch that far away
SKIP_MIN_GAIN = 25.0


def _skip_regions(res, n_seg: int, Xl: np.ndarray, starts, ends, sampling: str, a: float, k: float, U0: float,
                  ext=None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Where a slip could have carried the tip one well further than the model's path: for every slip of the path
    (a change of the tip's well, direction ``d``), the lateral force with the tip one well further on, from the slip
    until the path's tip moves into that well (its next slip: the two agree again) or that well can no longer hold
    the tip (the further tip slips back into the path's well). Returns per slip ``(samples, force change)``, the
    interval means (or point values) of the change at the samples it reaches.

    Physics: on the stick branch the tip sits where the lever's pull balances the lattice's, ``k (X - x) =
    q U0 sin(q x)``; a well ``n`` periods on holds the tip at the same support only where that equation has a stable
    root near ``x + n a`` (``k + q^2 U0 cos(q x) > 0``). At the instability the well beyond the next is stable only for
    ``eta = q^2 U0 / k > 4.6`` (Medyanik et al., PRL 97, 136106 (2006)); where it is, a slip ends in it or not by the
    tip's kinetic energy as it passes the next well, which the thermal force and the damping decide slip by slip at a
    finite temperature (a Langevin tip at 300 K, eta 7.5, Q = 2: one slip of 14 in a scan). The path's integration
    lands each slip deterministically; which well the recorded tip landed in is the data's (``FrictionProblem._skips``).
    Offered where the model's slips are thermally activated (:func:`simulate_scan`): a record whose slips the
    temperature does not move lands them as deterministically as the model does (the own generator at 0.01 K).
    """
    b, x = res.base, res.x
    if len(b) < 3 or not (2 * math.pi / a) ** 2 * U0 / k > MULTISLIP_ETA:
        return []
    q = 2 * math.pi / a
    w = np.round(x / a).astype(np.int64)
    ch = np.nonzero(np.diff(w) != 0)[0] + 1  # first path point in the new well
    if len(ch) == 0:
        return []
    # the sample intervals along the support per data segment, and which path points belong to which segment
    seg_model = _segments(res, n_seg)
    bounds = np.cumsum([0] + [len(m[0]) - 1 for m in seg_model])  # path index of each segment's first point
    lo_hi = [(Xl[s0:e0], Xl[s0:e0]) if sampling == "point" or e0 - s0 < 2 else
             _path_intervals(Xl[s0:e0], j, ext)
             for j, (s0, e0) in enumerate(zip(starts, ends))]
    # per path point after the first slip: the direction of the last slip, and the further well's root of
    # g(x') = k (b - x') - q U0 sin(q x'), which falls monotonically over the well's stable interval
    # |q (x' - c)| < arccos(-k / (q^2 U0)): a root there is the stable one (bisection, to 2^-30 of the interval)
    last = np.searchsorted(ch, np.arange(len(b)), side="right") - 1
    after = last >= 0
    dn = np.where(after, np.sign(w[ch[np.maximum(last, 0)]] - w[ch[np.maximum(last, 0)] - 1]), 0)
    c = (w + dn) * a
    half = math.acos(-k / (q * q * U0)) / q
    lo, hi = c - half, c + half
    ok = after & (k * (b - lo) - q * U0 * np.sin(q * lo) >= 0) & (k * (b - hi) - q * U0 * np.sin(q * hi) <= 0)
    # each slip's region: from the slip to the path's next slip or the first point the further well cannot hold;
    # regions alternate in parity, so a sample straddling the boundary of two is shared out by the parity's integral
    spans = []
    used = np.zeros(len(b), bool)
    for j, p0 in enumerate(ch):
        p1 = ch[j + 1] if j + 1 < len(ch) else len(b)
        bad = np.nonzero(~ok[p0:p1])[0]
        stop = int(bad[0]) if len(bad) else p1 - p0
        if stop:
            used[p0:p0 + stop] = True
            spans.append((j % 2, p0, p0 + stop - 1))
    # the further well's root where a region uses it (the bisection on those points only: session 65)
    sel = np.nonzero(used)[0]
    bs, los, his = b[sel], lo[sel], hi[sel]
    for _ in range(30):
        mid = 0.5 * (los + his)
        up = k * (bs - mid) - q * U0 * np.sin(q * mid) > 0
        los, his = np.where(up, mid, los), np.where(up, his, mid)
    dF_all = np.zeros(len(b))
    dF_all[sel] = k * (x[sel] - 0.5 * (los + his))  # k (b - x') - k (b - x)
    dF = [np.zeros(len(b)), np.zeros(len(b))]
    for par, p0, p1 in spans:
        dF[par][p0:p1 + 1] = dF_all[p0:p1 + 1]
    if not spans:
        return []
    # the two parities' changes sampled as the data are (a sample straddling two regions gets each one's share)
    sampled = [_sample_path(SimpleNamespace(base=b, lateral_force=d, t=res.t, _edges=_path_edges(res)), Xl, starts,
                            ends, n_seg, sampling, ext)
               for d in dF]
    out = []
    for par, p0, p1 in spans:
        idx = []
        for sj, (mb, _, _) in enumerate(seg_model[:len(starts)]):
            i0, i1 = int(bounds[sj]), int(bounds[sj]) + len(mb) - 1
            if i1 < p0 or i0 > p1:
                continue
            reach = mb[max(p0, i0) - i0:min(p1, i1) - i0 + 1]
            lo_s, hi_s = lo_hi[sj]
            sel = np.nonzero((np.maximum(lo_s, hi_s) >= np.min(reach)) & (np.minimum(lo_s, hi_s) <= np.max(reach)))[0]
            idx.append(starts[sj] + sel)
        idx = np.concatenate(idx) if idx else np.zeros(0, int)
        if len(idx):
            out.append((idx, sampled[par][idx]))
    return out


def _thermal_path(ffm: FFM, turns, V, st: FrictionState, hmax, x0: float | None = None):
    """Trace/retrace with thermally activated slips: between slips the FFM integration runs as
    usual; when the support reaches the median activated slip point of the current well, the tip
    is placed just over the saddle (at rest) and the FFM dynamics carries out the slip. The tip starts at
    rest at ``x0`` (default: under the support, ``turns[0]``). An activated path runs on ``POSTROLL`` periods past
    the last turn (the record's end), so that a slip just beyond it scatters into the last samples."""
    from probedyn.schemes.ffm import ScanResult

    x0 = turns[0] if x0 is None else x0

    T, f0 = st.thermal
    fv = ffm.friction.values
    U0, a, k = fv["U0"], fv["a"], ffm.cantilever["k_x"]
    tab = _barrier_table(U0, a, k)
    H = thermal_hazard(tab, V, T, f0) if tab is not None and T > 0 and f0 > 0 else None
    # an overdamped tip's slip point through its noisy passage past the instability (the normal form's hazard)
    gam, m = ffm.cantilever["c_x"] + fv["gamma"], ffm.cantilever["m_x"]
    ext = _passage_hazard(tab, U0, a, k, V, T, f0, gam, m) if H is not None else None
    if ext is None and (H is None or H[-1] < THERMAL_MIN_HAZARD):
        return _ffm_path(ffm, turns, V, hmax, (x0, 0.0, 0.0)), None, None
    Xtab, _, Xc, xs_tab, _ = tab
    scat = thermal_slip_scatter(tab, U0, a, k, V, T, f0, H, ext=ext)
    # the median slip point's advance on the instability (the grid less its offsets from the median)
    adv = max(Xc - float(ext[0][0] - scat[2][0][0]), 0.0) if ext is not None else _median_advance(tab, H)
    d_end = 1.0 if turns[-1] > turns[-2] else -1.0
    turns = list(turns[:-1]) + [turns[-1] + d_end * POSTROLL * a]  # the record's end run on (POSTROLL)
    if adv < THERMAL_PLACE_ADVANCE * a:
        # activated slips close to the instability: the athermal path (its slips resolved by the
        # integrator, the saddle-node delay included) with every slip's scatter about the instability
        res = _ffm_path(ffm, turns, V, hmax, (x0, 0.0, 0.0))
        if ext is None:
            return res, _athermal_slips(res, len(turns) - 2, a, k, Xc), (scat[0] - adv, scat[1],
                                                                         (scat[2][0] - adv, *scat[2][1:]))
        # an overdamped tip: the scatter about the path's own change of well, its delay past the instability
        # measured on the path and the noisy passage placed by it (a translated path carries its slip from there)
        delays: list = []
        slips = _athermal_slips(res, len(turns) - 2, a, k, Xc, delays)
        if not delays:
            return res, slips, (scat[0] - adv, scat[1], (scat[2][0] - adv, *scat[2][1:]))
        D = float(np.median(delays))
        ext = _passage_hazard(tab, U0, a, k, V, T, f0, gam, m, delay=D)
        scat = thermal_slip_scatter(tab, U0, a, k, V, T, f0, H, ext=ext)
        off = Xc + D - float(ext[0][0] - scat[2][0][0])  # the change of well's offset from the median
        slips = [(j, Xs + d * D, d) for j, Xs, d in slips]
        # the nodes' traces depend on the model and the speed, not on where the lattice sits (the registry's profile
        # integrates the same model a dozen times): kept per model (_PASSAGE_MEMORY)
        key = (U0, a, k, V, gam, m, T, f0, round(D / a, 6), len(turns))
        real = _PASSAGE_MEMO.get(key)
        if real is None:
            real = _passage_realizations(res, len(turns) - 2, slips, scat[0] - off, a, k, U0, V, gam, Xc + D)
            _PASSAGE_MEMO[key] = real
            while len(_PASSAGE_MEMO) > PASSAGE_MEMORY:
                _PASSAGE_MEMO.popitem(last=False)
        return res, slips, (scat[0] - off, scat[1], (scat[2][0] - off, *scat[2][1:]), real)
    slips = []  # (data segment, support position, direction) of every activated slip
    X_slip = Xc - adv  # relative to the well centre, for motion in +x
    xs_slip = float(np.interp(X_slip, Xtab, xs_tab))  # saddle position at the slip point
    y = np.array([x0, 0.0, 0.0])
    parts = []
    for Xa, Xb in zip(turns[:-1], turns[1:]):
        d = 1.0 if Xb > Xa else -1.0
        Xcur = Xa
        seg = []
        n = round(y[0] / a)  # the well the tip sits in (kept explicitly: a tip just placed over a
        # saddle belongs to the next well although it is nearer the old one)
        while (Xb - Xcur) * d > 0:
            Xs = n * a + d * X_slip
            if (Xs - Xcur) * d <= 1e-9 * a:  # already past this well's slip point: slip now
                Xs = Xcur
            Xend = Xs if (Xb - Xs) * d > 0 else Xb
            if (Xend - Xcur) * d > 1e-12 * a:
                r = _ffm_path(ffm, [Xcur, Xend], V, hmax, y)
                seg.append(r)
                y = np.array([r.x[-1], r.v[-1], r.z[-1]])
                Xcur = Xend
                n = round(y[0] / a)
            if Xend == Xs and (Xb - Xcur) * d > 0:
                y = np.array([n * a + d * (xs_slip + 0.02 * a), 0.0, 0.0])  # over the saddle, at rest
                slips.append((max(len(parts) - 1, 0), Xs, d))  # parts[0] is the pre-roll
                n += int(d)
        parts.append(seg)
    # flatten into one result; segment boundaries are recovered from the turns by _segments
    t, base, x, v, z, F = [], [], [], [], [], []
    toff = 0.0
    for seg in parts:
        for r in seg:
            t.append(r.t + toff)
            base.append(r.base)
            x.append(r.x)
            v.append(r.v)
            z.append(r.z)
            F.append(r.friction)
            toff += r.t[-1]
    base = np.concatenate(base)
    x = np.concatenate(x)
    return (ScanResult(t=np.concatenate(t), base=base, x=x, v=np.concatenate(v), z=np.concatenate(z),
                       lateral_force=k * (base - x), friction=np.concatenate(F), n_steps=0, n_rejected=0, setup={}),
            slips, scat)


# ------------------------------------------------------------------------------------------
# The stick-slip loop as recorded: data-derived starting values of the nested fits
# ------------------------------------------------------------------------------------------


def _pt_loop_ratio(eta: np.ndarray, m: int = 1) -> np.ndarray:
    """Quasi-static PT stick-slip whose slips advance the tip by ``m`` wells (m = 1 on a strongly
    damped slip; more where the slip's momentum carries it further): the force drop at a slip over
    the peak force, ``k (x_land - x_c) / (F0 sqrt(1 - 1/eta^2))``, a function of
    eta = 2 pi F0 / (k a) alone (a = k = 1 here). A calibration factor scales the drop and the peak
    alike, so their ratio measures eta -- the corrugation in units of k a^2 -- independently of the
    factor (and of an offset: the drop is a difference)."""
    out = np.empty(len(eta))
    q = 2 * math.pi
    for i, e in enumerate(np.asarray(eta, float)):
        F0 = e / q
        xc = math.acos(-1.0 / e) / q
        Xc = xc + F0 * math.sin(q * xc)
        x = xc + np.linspace(1e-6, m + 0.5, 20000 * (m + 1))
        g = (Xc - x) - F0 * np.sin(q * x)  # net force on the tip at the support position X_c
        down = x[np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0]]  # stable equilibria ahead
        near = down[np.abs(down - m) < 0.5]  # the m-th well ahead holds a stable equilibrium at X_c
        out[i] = (float(near[0]) - xc) / (F0 * math.sqrt(1.0 - 1.0 / e**2)) if len(near) else np.nan
    return out


_ETA_GRID = np.geomspace(1.1, 60.0, 240)
_RATIO: dict[int, np.ndarray] = {}


def _eta_from_ratio(r: float, m: int = 1) -> float:
    if m not in _RATIO:
        _RATIO[m] = _pt_loop_ratio(_ETA_GRID, m)
    # the ratio falls monotonically with eta where the m-th well exists at the instability
    # (checked in tests/test_diagnose_friction.py)
    ok = np.isfinite(_RATIO[m])
    return float(np.interp(r, _RATIO[m][ok][::-1], _ETA_GRID[ok][::-1]))


@dataclass
class LoopEstimate:
    """Per scan, from the recorded loop only: peak force (half the trace-retrace difference of the
    peaks: an offset cancels), slip drop, and the quasi-static PT reading of them: eta, the
    corrugation U0 [J] (independent of a calibration factor) and the calibration factor g;
    the slip positions of every steady monotone segment (for the scanner's period drift)."""

    peak: np.ndarray
    drop: np.ndarray
    eta: np.ndarray
    U0: np.ndarray
    g: np.ndarray
    slips: list  # per scan: list of (direction, slip positions of one segment)


def _stick_slip_range(f: np.ndarray, groups: list, sigma: float) -> float:
    """The force range of a segment's steady stick-slip (1st to 99th percentile), from its first slip on: a
    segment that begins at a reversal begins with the reversal's stick, where the force crosses the whole loop
    (twice the peak), and a threshold read from that range can exceed every slip's drop (the three-scan example's
    fast retrace: range 1040 pN with the reversal, slips of 130-180 pN over several samples, and the loop unread).
    The first slip is the first run of falling samples (``groups``) that falls by more than 10 sigma; a segment
    without one keeps its whole range."""
    first = next((g[0] for g in groups if f[g[0]] - f[g[-1] + 1] > 10.0 * sigma), None)
    h = f[first:] if first is not None and len(f) - first >= 8 else f
    return float(np.percentile(h, 99) - np.percentile(h, 1))


def loop_estimate(data: FrictionData, use: np.ndarray, slices: list, a: float, sigma: float) -> LoopEstimate | None:
    """Read the stick-slip loop of each scan (the samples marked ``use``: steady, after the first slip)."""
    peaks, drops, slips, wells = [], [], [], []
    for i, s in enumerate(data.scans):
        u = use[slices[i]]
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        pk = {1: [], -1: []}
        dr = []
        sl = []
        for seg in np.split(np.arange(len(s.force)), cuts):
            seg = seg[u[seg]]
            if len(seg) < 8 or np.any(np.diff(seg) != 1):
                continue
            d = int(s.direction[seg[0]])
            f = d * s.force[seg]
            x = s.position[seg]
            falls = np.nonzero(f[:-1] - f[1:] > 3.0 * sigma)[0]
            # slip groups: runs of falling samples whose total drop exceeds the threshold
            groups, cur = [], []
            for j in falls:
                if cur and j != cur[-1] + 1:
                    groups.append(cur)
                    cur = []
                cur.append(j)
            if cur:
                groups.append(cur)
            thr = max(10.0 * sigma, 0.2 * _stick_slip_range(f, groups, sigma))
            pos = []
            for grp in groups:
                j0, j1 = grp[0], grp[-1] + 1
                if f[j0] - f[j1] < thr or j0 < 1 or j1 + 4 > len(f):
                    continue
                # the stick branch after the slip, extrapolated back to the last sample before it
                c1 = np.polyfit(x[j1:j1 + 4] - x[j0], f[j1:j1 + 4], 1)
                pk[d].append(float(f[j0]))
                dr.append(float(f[j0] - np.polyval(c1, 0.0)))
                pos.append(0.5 * (x[j0] + x[j1]))
            if len(pos) >= 2:
                sl.append((d, np.array(pos)))
        if not pk[1] or not pk[-1] or not dr:
            return None
        peaks.append(0.5 * (float(np.median(pk[1])) + float(np.median(pk[-1]))))
        drops.append(float(np.median(dr)))
        slips.append(sl)
        # wells per slip: the median spacing of successive slips in lattice periods
        sp = np.concatenate([np.abs(np.diff(p)) for _, p in sl]) if sl else np.array([a])
        wells.append(max(int(round(float(np.median(sp)) / a)), 1))
    peak, drop = np.array(peaks), np.array(drops)
    eta = np.array([_eta_from_ratio(r, m) for r, m in zip(drop / np.maximum(peak, 1e-30), wells)])
    k = data.k_x
    F0 = eta * k * a / (2 * math.pi)
    return LoopEstimate(peak, drop, eta, F0 * a / (2 * math.pi), peak / (F0 * np.sqrt(1.0 - 1.0 / eta**2)), slips)


# ------------------------------------------------------------------------------------------
# The problem
# ------------------------------------------------------------------------------------------


def _period_estimate(data: FrictionData) -> float:
    """Lattice period from the periodogram of the traces (0.6 - 1.6 x the nominal lattice)."""
    cand = data.lattice * np.linspace(0.6, 1.6, 501)
    power = np.zeros_like(cand)
    for s in data.scans:
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        for seg in np.split(np.arange(len(s.position)), cuts):
            if len(seg) < 8:
                continue
            x = s.position[seg]
            f = s.force[seg] - s.force[seg].mean()
            E = np.exp(-2j * np.pi * np.outer(1.0 / cand, x))
            power += np.abs(E @ (f * np.hanning(len(f)))) ** 2
    return float(cand[int(np.argmax(power))])


def _first_slip(force: np.ndarray, direction: float, sigma: float) -> int | None:
    """Index of the sample where the first slip of a monotone segment ends: the first drop of the
    lateral force against the direction of motion, over up to three samples (an overdamped slip
    spans several), larger than a quarter of the segment's force range and 10 noise levels."""
    f = direction * np.asarray(force, float)
    if len(f) < 8:
        return None
    thr = max(0.25 * float(np.percentile(f, 99) - np.percentile(f, 1)), 10.0 * sigma)
    for w in (1, 2, 3):
        drop = f[:-w] - f[w:]
        idx = np.nonzero(drop > thr)[0]
        if len(idx):
            i = int(idx[0]) + w
            # the slip ends where the force stops falling
            while i + 1 < len(f) and f[i + 1] < f[i] - 3.0 * sigma:
                i += 1
            return i
    return None


def _slip_period(data: FrictionData, a_est: float, sigma: float) -> float:
    """The lattice period from the positions of the slips (jumps of the lateral force larger than
    10 noise levels against the direction of motion): within each segment the spacing of
    successive slips is an integer number of periods (multiple slips), ``a = sum dX / sum n`` with
    ``n = round(dX / a)``, iterated from ``a = a_est`` to its fixed point (the integers from the
    estimate they give). On a record of a few periods the periodogram's ``a_est`` is coarse (4
    periods: 0.80 nm read for 0.50 nm), and a double slip of 1.0 nm then counts as one period;
    the iteration recounts it as two. Falls back to ``a_est`` with fewer than three slips."""
    spacings = []
    for s in data.scans:
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        for seg in np.split(np.arange(len(s.force)), cuts):
            if len(seg) < 4:
                continue
            d = s.direction[seg[0]]
            jump = -d * np.diff(s.force[seg])
            idx = np.nonzero(jump > 10 * sigma)[0]
            if len(idx) < 2:
                continue
            # one slip may span two samples (interval means): keep the larger of adjacent jumps
            keep = [idx[0]]
            for j in idx[1:]:
                if j - keep[-1] <= 1:
                    if jump[j] > jump[keep[-1]]:
                        keep[-1] = j
                else:
                    keep.append(j)
            x = s.position[seg]
            xs = np.array([0.5 * (x[j] + x[j + 1]) for j in keep])
            spacings.append(np.abs(np.diff(xs)))
    a, seen = a_est, []
    for _ in range(8):
        num = den = 0.0
        counts = []
        for dx in spacings:  # summed segment by segment (the estimate of one pass to the last bit)
            n = np.round(dx / a)
            ok = n >= 1
            num += float(dx[ok].sum())
            den += float(n[ok].sum())
            counts.append(n)
        if den < 3:
            return a_est
        counts = np.concatenate(counts)
        if any(np.array_equal(counts, c) for c in seen):
            return a  # the integers repeat: the estimate they give is the fixed point
        seen.append(counts)
        a = num / den
    return a


def bind_scans(problem, data: FrictionData) -> None:
    """What every friction problem keeps of its measurement: the data, its path, the quantities declared
    known or free, the declared medium, and each scan's speed and load."""
    problem.data = data
    problem.path = data.path
    problem.known = set(data.known) | set(data.free)
    problem.declared_medium = data.medium
    problem.medium_name = data.medium_name
    problem.speeds = np.array([s.speed for s in data.scans])
    problem.loads = np.array([s.load for s in data.scans])


def scan_groups(scans) -> tuple[list[slice], np.ndarray, list[str]]:
    """Each scan's slice of the concatenated samples, the cross-validation group of every sample (one
    per monotone segment: the trace and the retrace of each scan) and the groups' labels."""
    slices, gid, labels, pos = [], [], [], 0
    for i, s in enumerate(scans):
        slices.append(slice(pos, pos + len(s.force)))
        pos += len(s.force)
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        seg_id = np.zeros(len(s.force), int)
        for j, c in enumerate(cuts):
            seg_id[c:] = j + 1
        gid.append(1000 * i + seg_id)
        for j in range(len(cuts) + 1):
            labels.append(f"scan {s.id} {'trace' if (s.direction[0] > 0) == (j % 2 == 0) else 'retrace'}")
    return slices, np.concatenate(gid), labels


#: the registry polish's steps in lattice periods (:meth:`FrictionProblem._profile_one_train`): the first walks up to
#: REGISTRY_REPEAT parabolas of reach 8e-3 a (2.4e-2 a) from the fundamental's phase, the second ends on one through
#: points 1e-3 a apart (before session 62: these two parabolas once each, always taken)
REGISTRY_STEPS = (4e-3, 1e-3)
REGISTRY_REPEAT = 3
#: the starts kept from a cause's ridge (:meth:`FrictionProblem.nested_starts`), best first by the model's chi^2
RIDGE_KEEP = 2
#: the corrugation ridge of a data-derived start that moves the period: U0 per unit load at the reference's eta
#: times 1 + k ETA_RIDGE_STEP, |k| <= ETA_RIDGE_HALF (:func:`eta_ridge`)
ETA_RIDGE_STEP = 0.005
ETA_RIDGE_HALF = 8
#: the period profile of a kept ridge start that carries the reference's period along the scan
#: (:meth:`FrictionProblem._period_profiles`): ``a`` times 1 + k PERIOD_STEP, |k| <= PERIOD_HALF, at the start's eta
#: (U0 with a^2), then U0 times 1 + k U0_STEP, |k| <= U0_HALF. The chi^2 basin is ~0.5 % wide in a on a scan of
#: 8 periods (a relative change f moves the last slips by 8 f periods) and a few per cent in U0
PERIOD_STEP = 0.005
PERIOD_HALF = 5
U0_STEP = 0.02
U0_HALF = 3
#: the term's ridge start that best gives the recorded peaks (:meth:`FrictionProblem._term_ridge_starts`) profiled
#: in U0: times 1 + k TERM_RIDGE_STEP, |k| <= TERM_RIDGE_HALF, by the whole model's chi^2. The ridge's U0 is read
#: quasi-statically from the slowest scan's peak (a few per cent off the dynamics), and the chi^2 basin lies beside
#: a cliff: own 2002 at 300 K, 2472 at 1.5 % below a U0 where a slip at a reversal becomes improbable (7.8e4)
TERM_RIDGE_STEP = 0.01
TERM_RIDGE_HALF = 6


def eta_ridge(start: dict, ref: dict) -> list[dict]:
    """Corrugation starts for a data-derived start that sets the period ``a`` and not the corrugation: the slip
    pattern is set by eta = 4 pi^2 U0 / (k a^2), so U0 keeps the reference fit's eta (``u0_ref (a / a_ref)^2``), on
    a grid of ``ETA_RIDGE_STEP`` about it: the reference's U0 has absorbed part of what the new cause explains, and
    the basin in U0 is under a per cent wide. Own study s48, 2025 (a scanner bow of -0.095; n = 1709): from the slip
    positions a bow of -0.096 and a within 0.06 % of the truth; chi^2 9.6e5 at the baseline's U0, 2.2e5 at its eta,
    2.5e3 at 2 % above (the truth's U0 is 1.9 % above). Session 62: 0.4 % from the truth's U0 is 5 times the chi^2 of
    the basin's floor, so the grid's step is 0.5 % (it was 1 %)."""
    if "a" not in start or "u0" in start or "a" not in ref or "u0" not in ref:
        return []
    u = float(ref["u0"]) * (float(start["a"]) / float(ref["a"])) ** 2
    return u0_grid(start, u, ETA_RIDGE_STEP, ETA_RIDGE_HALF)


def u0_grid(start: dict, u: float, step: float, half: int) -> list[dict]:
    """``start`` with its corrugation per unit load at ``u`` times 1 + k ``step``, |k| <= ``half``."""
    return [{**start, "u0": u * (1.0 + step * k)} for k in range(-half, half + 1)]


def clipped_starts(base_params, ref_values: dict, new: tuple, starts_of) -> list[dict]:
    """The data-derived starts ``starts_of(cause)`` of the new causes as full value dicts: the reference
    fit's values, the new parameters at their nulls, each start's values clipped into their bounds."""
    newp = [p for c in new for p in c.params]
    bounds = {p.name: (p.lo, p.hi) for p in list(base_params) + newp}
    base = {**ref_values, **{p.name: p.null for p in newp}}
    out = []
    for c in new:
        for st in starts_of(c):
            v = dict(base)
            for name, x in st.items():
                if name in bounds and np.isfinite(x):
                    v[name] = min(max(float(x), bounds[name][0]), bounds[name][1])
            out.append(v)
    return out


class FrictionProblem:
    kind = "friction"
    unit = "N"
    reduced = False

    def __init__(self, data: FrictionData) -> None:
        bind_scans(self, data)
        sc = data.scans
        self.sigma = data.sigma_force if data.sigma_force > 0 else 1e-12
        # a thermal trace carries, besides the detector's white noise, the tip's thermal motion (and
        # stochastic slips): the sample-to-sample scatter of the data (second differences, robust to the
        # slips) is the noise the model is measured against when it clearly exceeds the stated noise:
        # by more than NOISE_EXCESS (the estimate reads 9 % high on cold stick-slip traces with white
        # noise only, from the curvature before the slips: tests/diagnose_truth.py seeds 3-6)
        self.sigma_scatter = _scatter(data.scans)
        self.noise_excess = bool(data.noise_stated and self.sigma_scatter > NOISE_EXCESS * self.sigma)
        if self.noise_excess:
            self.sigma = self.sigma_scatter
        #: the sigma is the record's own robust scatter (unstated, or replacing the stated one): the chi-square
        #: tests include its sampling error (engine.gof_p)
        self.sigma_from_scatter = bool(not data.noise_stated or self.noise_excess)
        self.force = np.concatenate([s.force for s in sc])
        self.n = len(self.force)
        self.model_var = np.zeros(self.n)  # the model's own variance per sample (set by predict)
        self.slices, gid, labels = scan_groups(sc)
        self.a_est = _period_estimate(data)
        # the samples within START_PERIODS lattice periods of a scan's start depend on the unrecorded
        # history before it (where the tip sat when the scan began): they are not used
        use = []
        self.first_slip = []
        for s in sc:
            u = np.ones(len(s.force), bool)
            cuts = np.nonzero(np.diff(s.direction) != 0)[0]
            end0 = (cuts[0] + 1) if len(cuts) else len(s.force)
            u[:end0] = np.abs(s.position[:end0] - s.position[0]) >= START_PERIODS * self.a_est
            # ... and up to the first slip of the scan: where the tip sat when the scan began (which
            # well, after a multiple-slip pre-history) decides where the first slip comes; after a slip
            # the state is that of the stick branch, independent of the history
            i_s = _first_slip(s.force[:end0], s.direction[0], self.sigma)
            if i_s is not None and i_s + 2 < end0:
                u[: i_s + 2] = False
            self.first_slip.append(i_s)
            use.append(u)
        self.use = np.concatenate(use)
        self.groups = gid[self.use]
        # the residuals' recording sequences (one per scan, in residual rows) and whether the noise they
        # are measured against is the stated one (correlated noise, :mod:`probedyn.diagnose.noise`)
        row = np.cumsum(self.use) - 1
        self.sequences = [row[sl][self.use[sl]] for sl in self.slices]
        self.noise_stated = bool(data.noise_stated and not self.noise_excess)
        self.noise_correlation_declared = data.noise_correlation
        self.group_labels = labels
        N = float(np.mean(self.loads))
        self.a_slip = _slip_period(data, self.a_est, self.sigma)
        #: the scans too short for the fundamental's phase alone (:data:`ALIGN_PERIODS`, :meth:`_profile_one_train`)
        self.short_scans = [self._aligned_periods(i) < ALIGN_PERIODS for i in range(len(sc))]
        # corrugation start from the stick-slip loop: the largest lateral force of a PT stick branch is
        # F_max = F0 sqrt(1 - 1/eta^2) with eta = 2 pi F0 / (k a), so F0 = sqrt(F_max^2 + (k a / 2 pi)^2)
        # ... at the slips' period where the periodogram does not resolve the period (a record of a few periods)
        q = 2 * math.pi / (self.a_slip if self._period_unresolved() else self.a_est)
        self._U0_peaks = []  # the corrugation each scan's peak force reads
        for s_ in sc:
            fmax = 0.5 * float(np.percentile(s_.force, 99.5) - np.percentile(s_.force, 0.5))
            F0 = math.sqrt(fmax**2 + (data.k_x / q) ** 2)
            self._U0_peaks.append(F0 / q)
        # the loop read as recorded (peak and slip drop): eta and U0 per scan, independent of a
        # calibration factor and an offset; its U0 per unit load is a further start of the baseline
        self.loop = loop_estimate(data, self.use, self.slices, self.a_slip, self.sigma)
        self.N_mean = N
        #: the baseline's laws of the corrugation against the load (:func:`effective_load`), where the scans have
        #: more than one load: the registry's (Amontons, U0 proportional to the load; the FFM's ``normal_load``) and a
        #: corrugation independent of the load (the plain PT model, the FFM without a normal load). The record does
        #: not say which its instrument follows (docs/diagnose.md 9.53): the engine fits both and keeps the better
        #: (``engine._baseline_law``); an adhesion intercept between them is the adhesion-load cause
        self.baseline_laws = tuple(LOAD_LAWS) if np.ptp(self.loads) > 0 else ()
        self.baseline_law = "amontons"
        self.base_params = self._base_params()
        self.temperature = data.temperature
        # the tip's thermal force noise (thermal_force_variance): at a declared temperature, with the stated noise
        # not replaced by the record's scatter (which would already hold it); added to a stated detector noise
        # ([noise] force_part = "detector"), shared out of a stated total (the default: predict).
        # At 300 K on the own generator's fast scan (10 x 50 nm/s, 40 interval means per 0.5 nm) it is 2.5-3.4 pN
        # beside 5 pN of detector noise; at 1 K, 0.2 pN
        stated = bool(data.noise_stated and not self.noise_excess)
        self.thermal_noise_T = float(data.temperature) if (stated and data.temperature and data.temperature > 0) else 0.0
        self.c_tip = float(_ffm(data, 1e-30, self.a_est, 0.0).cantilever["c_x"])
        self.sample_dt = [0.0 if data.sampling == "point" or len(s_.time) < 2 else float(np.median(np.abs(np.diff(s_.time))))
                          for s_ in sc]
        self.thermal_var = np.zeros(self.n)  # its variance per sample (set by predict; part of every model)
        #: at a declared temperature the model's variance (the activated slip scatter, the tip's thermal noise) depends
        #: on its parameters: the fits minimise -2 ln L, chi^2 with that variance's log-determinant (engine
        #: ``Fitter.var_rows``); without one (an activation cause's assumed temperature) chi^2 as before
        self.variance_in_objective = bool(data.temperature and data.temperature > 0)
        self._last_ok = False
        if (self.noise_excess and data.noise_part == "detector" and data.temperature and data.temperature > 0
                and data.sigma_force > 0):
            # a stated *detector* noise at a declared temperature: the record's scatter holds the tip's thermal force
            # noise besides it, which the model carries itself (thermal_force_variance). The excess is measured
            # against both: the stated noise stands, and the thermal part is the model's, unless the scatter
            # exceeds the two together (blind g09, 298 K: 5 pN stated, 7.6 pN scattered, the thermal part 5-9 pN;
            # replaced by the scatter, the detector's noise was then re-read from residuals at 4.3 pN)
            self.thermal_noise_T, self.sigma = float(data.temperature), float(data.sigma_force)
            expected = self.sigma * math.sqrt(1.0 + self._thermal_share())
            if self.sigma_scatter <= NOISE_EXCESS * expected:
                self.noise_excess = self.sigma_from_scatter = False
                self.noise_stated = True
            else:
                self.thermal_noise_T, self.sigma = 0.0, self.sigma_scatter
        if self.thermal_noise_T and self._thermal_share() < THERMAL_NOISE_MIN_SHARE:
            self.thermal_noise_T = 0.0
        self._last_thermal = None
        self._scan_memo: OrderedDict = OrderedDict()  # key -> (F, var, thermal var): the scan models kept (_scan_model)
        self._scan_memo_bytes = 0
        self.v_max = float(self.speeds.max())
        self.drift_clock, self.t_drift = drift_clock(sc)
        #: the drift parameter is the detector's drift over the longest scan: a rate drift / t_ref [N/s]
        self.t_ref = max(max(s.time[-1] - s.time[0], 1e-12) for s in sc)
        self.train_mask = None
        self.fixed_nuisance = None
        #: the engine's map over its worker pool (``Fitter.map_calls``), None: in turn (:meth:`_map`)
        self.parallel = None
        # (model key, scan, training mask) -> (registry, chi^2 of the scan): the best registry seen
        # for each model (nuisance(), predict())
        self._registry: dict = {}
        # the integrated model is accurate to ~1e-5 of the force scale (RTOL): finite differences
        # need steps of 1e-3 of the parameter scale; fewer evaluations and starts per fit
        self.diff_step = 1e-3
        self.nfev_per_param = 20
        self.max_starts = 4
        # every start of a fit gets SCREEN_NFEV evaluations, the best one (and a runner-up within
        # SCREEN_MARGIN) is run to convergence; the
        # candidate causes and the cross-validation folds are fitted in WORKERS processes
        self.screen_nfev = SCREEN_NFEV
        self.screen_margin = SCREEN_MARGIN
        self.screen_keep = SCREEN_KEEP
        from probedyn.diagnose.engine import WORKERS

        self.workers = WORKERS
        # the chi^2 surface of stick-slip traces is rugged (the slip pattern jumps with the parameters):
        # a fold fitted from the declared starts alone can end in another basin (seed 11 viscous, scan 2
        # trace held out: training chi^2 33652 instead of ~1200); the folds also start from the
        # full-data optimum (engine: cv_warm, cv_warm_all)
        self.cv_warm = True
        self.cv_warm_all = True
        # a cause is claimed only if its gain exceeds the excess the greedy chain up to it leaves
        # (engine._beyond_remainder): the stick-slip models of thermal activation and misalignment do not
        # reproduce a Langevin truth's slips to the noise, and any cause absorbs part of that model error
        # (session 6: 15/50 hidden cases reported a second cause not in the truth)
        self.extension_vs_model_error = True
        self.causes = []
        #: effects the declared conditions imply (thermal activation at a declared temperature): terms the baseline
        #: takes on where the data show them (engine ``_declared_terms``), not causes; ``base_terms`` those it took
        self.declared_terms = []
        self.base_terms = ()
        self._constrain_catalog()

    def _constrain_catalog(self) -> None:
        """The catalog's causes and the declared conditions' terms, constrained by this record (and the baseline's
        load law, which the adhesion-load cause extends)."""
        self.causes, self.declared_terms = [], []
        for cls in catalog("friction"):
            if cls.regimes and "stick-slip" not in cls.regimes:
                continue
            c = cls().constrain(self)
            if c is not None:
                (self.declared_terms if c.declared else self.causes).append(c)

    @property
    def load_share(self) -> float:
        """The baseline law's ``load_share`` (:func:`effective_load`)."""
        return LOAD_LAWS[self.baseline_law]

    def set_baseline_law(self, law: str) -> None:
        """Take the baseline's load law ``law`` (a key of :data:`LOAD_LAWS`): the baseline's corrugation starts and
        the causes (the adhesion-load cause is parametrised about the baseline's law) follow it."""
        if law not in LOAD_LAWS:
            raise ValueError(f"unknown load law {law!r} (known: {', '.join(LOAD_LAWS)})")
        self.baseline_law = law
        self.base_params = self._base_params()
        self._constrain_catalog()

    def effective_loads(self, ref: dict | None = None) -> np.ndarray:
        """Every scan's :func:`effective_load` under the baseline's law, with the adhesion load or load share
        ``ref`` holds (a cause's parameters; none: the baseline's)."""
        ref = ref or {}
        st = FrictionState(u0=1.0, a=self.a_slip, n_adh=float(ref.get("n_adh", 0.0)),
                           load_share=self.load_share + float(ref.get("load_share", 0.0)), n_ref=self.N_mean)
        return np.array([effective_load(st, float(N)) for N in self.loads])

    def _period_unresolved(self) -> bool:
        """Whether the two estimates of the period (the periodogram's ``a_est``, the slips' ``a_slip``) differ by
        more than the periodogram resolves over the longest scan (half a period over its ``n`` periods)."""
        n_per = max(float(max(np.ptp(s_.position) for s_ in self.data.scans)) / self.a_est, 1.0)
        return abs(self.a_est - self.a_slip) > 0.5 * self.a_est / n_per

    def _base_params(self) -> list:
        """The baseline's parameters under its load law: the corrugation per unit (effective) load started from the
        scans' peak forces and from the recorded loop, and the lattice period."""
        Neff = np.maximum(self.effective_loads(), 1e-30)
        u0_start = float(np.median(np.asarray(self._U0_peaks) / Neff))
        u0_loop = float(np.median(self.loop.U0 / Neff)) if self.loop is not None else u0_start
        u0_starts = tuple(x for x in (0.85 * u0_start, 1.2 * u0_start, u0_loop)
                          if 1e-2 * u0_start <= x <= 1e2 * u0_start)
        # the period sets the slip pattern: a period off by da misplaces the n-th slip by n da, another
        # basin once n da exceeds half a period over the scan; where the two independent estimates (the
        # slip positions, the periodogram) differ by that much, the baseline also starts from the other
        a_starts = (self.a_est,) if self._period_unresolved() else ()
        # the period's bounds, 25 % about the periodogram's reading, widened to hold 10 % about the slips' estimate
        # (the null): on a record of a few periods the periodogram resolves the period only to ~1/n_per of itself
        # (4 periods: 0.8 nm read for 0.5 nm), the slips' spacing far better
        a_lo, a_hi = min(0.75 * self.a_est, 0.9 * self.a_slip), max(1.25 * self.a_est, 1.1 * self.a_slip)
        return [
            CauseParam("u0", "J/N", u0_start * 1e-2, u0_start * 1e2, u0_start, "corrugation U0 per unit load",
                       scale="log", starts=u0_starts),
            CauseParam("a", "m", a_lo, a_hi, self.a_slip, "lattice period", starts=a_starts),
        ]

    def _thermal_share(self) -> float:
        """The tip's thermal force noise (:func:`thermal_force_variance`) over the stated variance, averaged over the
        stick branches of the recorded loop (the baseline's starting corrugation, read from every scan's peak force,
        the branch's force uniform in ``(-q U0, q U0)``), weighted by the scans' samples. Not the loop's reading per
        scan: a scan whose slips a viscous force smears reads a corrugation several times too large (the example's
        fast scan: 4.5 times), and the variance falls with the well's stiffness squared (the example at 300 K: a
        share of 0.024 instead of 0.12)."""
        u0 = next(p.null for p in self.base_params if p.name == "u0")  # the baseline's start
        q = 2 * math.pi / self.a_slip
        tot = 0.0
        for i, s in enumerate(self.data.scans):
            U0 = u0 * float(s.load)
            F = np.linspace(-0.99, 0.99, 41) * q * U0
            v = thermal_force_variance(F, U0, self.a_slip, self.data.k_x, self.c_tip, self.thermal_noise_T, self.sample_dt[i])
            tot += float(np.mean(v)) * len(s.force)
        return tot / self.n / self.sigma**2

    def supports(self, what: str) -> bool:
        return True

    def nested_starts(self, ref_values: dict, ref_causes: tuple, new: tuple, mask=None) -> list[dict]:
        """Data-derived starts of the new causes (called by the engine besides the null start and
        the declared starts): each cause reads what it changes from the recorded loop
        (``cause.data_starts(problem, ref_values)``, e.g. a calibration factor from the ratio of
        the slip drop to the peak force). The stick-slip chi^2 surface is rugged: from the null
        start a factor of 1.9 is not found (the baseline's corrugation has absorbed it)."""
        if self.loop is None:
            # a record without a loop (trace only) gives a cause only the starts it reads from the reference model:
            # an activation's corrugation raised by its peak lowering at each REFERENCE_F0 (blind f21, 2 K, trace
            # only: from the declared starts, u0 raised 1.3-2 times for 300 K, the term's fit ended at 5 Hz, chi^2
            # 1446 on 358, where 1e6 Hz gives 392)
            return clipped_starts(self.base_params, ref_values, new, lambda c: c.reference_starts(self, dict(ref_values))
                                  if hasattr(c, "reference_starts") else [])
        data = {c: c.data_starts(self, dict(ref_values)) if hasattr(c, "data_starts") else [] for c in new}
        for c in new:
            # a data start that also reads the reference's own parameters from the loop (a corrugation) is offered again
            # with the reference's values kept and only the cause's own read: the loop is read quasi-statically, and
            # where the reference carries a declared temperature's activation its corrugation and attempt frequency
            # are the record's, not the loop's (blind friction set 2's g08 at 295 K: the adhesion load read 3.29 nN
            # for its 3.0, the loop's corrugation 20 % below the activated baseline's; from the loop's, chi^2 1.2e5
            # and the nested fit stayed at its null, 3331; from the baseline's, 2169 at the start and 1328 fitted)
            own = {p.name for p in c.params}
            data[c] = data[c] + [kept for st in data[c] if set(st) - own
                                 and (kept := {k: x for k, x in st.items() if k in own})]
        out = clipped_starts(self.base_params, ref_values, new, lambda c: data[c])
        if mask is None:  # a cause's ridge of starts (parameters that trade), ranked by the whole model's chi^2
            causes = tuple(ref_causes) + tuple(new)
            for c in new:
                own = [c.ridge_starts(self, dict(ref_values))] if hasattr(c, "ridge_starts") else []
                # the data starts that move the period: their corrugation ridges
                ridges = own + [r for st in data[c] if (r := eta_ridge(st, ref_values))]
                for j, ridge in enumerate(ridges):
                    cands = clipped_starts(self.base_params, ref_values, new,
                                           lambda cc, c=c, ridge=ridge: ridge if cc is c else [])
                    scored = self._ranked(cands, causes)
                    kept = [cands[i] for _, i in scored[:RIDGE_KEEP]]
                    out += kept
                    # a cause's own ridge that carries the reference's period along the scan: its kept starts
                    # profiled in (a, U0), where the reference leaves the data beyond their noise; a profile that
                    # found nothing lower is its start, kept already, and is not offered twice
                    if j < len(own) and ridge and "a" in ridge[0] and self._beyond_noise(ref_values, ref_causes):
                        profiled = self._period_profiles([(cands[i], c2) for c2, i in scored[:RIDGE_KEEP]], causes)
                        out += [pr for pr, v in zip(profiled, kept) if pr != v]
                out += self._term_ridge_starts(clipped_starts(self.base_params, ref_values, new,
                                                              lambda cc, c=c: data[c] if cc is c else []), causes)
        return out

    def _ranked(self, cands: list[dict], causes: tuple) -> list[tuple[float, int]]:
        """``(chi^2, index)`` of the candidate starts ``cands`` of the model with ``causes``, best first."""
        return sorted((c2, i) for i, c2 in enumerate(self._map("_chi2_at", [(v,) for v in cands], causes)))

    def _chi2_at(self, values: dict, causes: tuple) -> float:
        """The model's chi^2 at ``values`` (its registry profiled)."""
        return float(np.sum(self.residuals(values, causes) ** 2))

    def _map(self, method: str, items: list[tuple], causes: tuple) -> list:
        """``self.<method>(*item, causes)`` for every item, through ``parallel`` where the engine has set one (its
        worker pool: :meth:`probedyn.diagnose.engine.Fitter.map_calls`), else in turn."""
        if self.parallel is not None:
            return self.parallel(method, items, causes)
        return [getattr(self, method)(*it, causes) for it in items]

    def _term_ridge_starts(self, starts: list[dict], causes: tuple) -> list[dict]:
        """A baseline term's parameters (a declared temperature's attempt frequency) started again along the term's
        ridge (``ridge_starts``: the corrugation that gives the recorded peaks at each attempt frequency) at each
        data start of a new cause, the best :data:`RIDGE_KEEP` by the whole model's chi^2. The baseline's term was
        fitted without the cause and may have taken part of its effect: own seed 2002 at a declared 300 K, an
        adhesion load of 13.5 nN, the activation's attempt frequency went to 4e3 Hz to mimic the peaks' load
        dependence (the Langevin tip's is ~3e5 Hz), and the adhesion nested from there, with that frequency,
        lost to viscous friction. The ridge's corrugation is per unit total load; the start's own corrugation
        parameter is scaled by the ratio to the state's (a cause may define u0 at a reference load). A ridge may
        also move a free parameter of the cause that it reads (an adhesion load: ``ridge_starts``). Besides, the
        ridge's first start (the best by the recorded peaks) with its corrugation profiled by the model's chi^2
        (:data:`TERM_RIDGE_STEP`): the peaks are read quasi-statically, and the basin can lie a few per cent off,
        beside a cliff (own 2002 at 300 K: the ridge's first start at chi^2 7.6e4, profiled 1.1e4, fitted 2347;
        ranked unprofiled, the two kept ended at 2.0e4 and viscous friction was named)."""
        terms = [t for t in self.base_terms if hasattr(t, "ridge_starts")]
        if not terms or self.loop is None:
            return []
        out = []
        for v0 in starts:
            try:
                st = self.state(v0, causes)
            except ProbedynError:
                continue
            ref = {**v0, "a": st.a}
            if st.n_adh and "n_adh" not in v0:
                ref["n_adh"] = st.n_adh  # a load the model carries but does not fit here
            if st.load_share != self.load_share and "load_share" not in v0:
                ref["load_share"] = st.load_share - self.load_share  # (the same, on the load-independent baseline)
            cands = []
            for t in terms:
                for r in t.ridge_starts(self, ref):
                    w = dict(v0)
                    w.update({k: float(x) for k, x in r.items() if k != "u0" and k in w})
                    if "u0" in r:
                        try:
                            sw = self.state(w, causes)
                        except ProbedynError:
                            continue
                        if sw.u0 > 0:
                            w["u0"] = float(w["u0"]) * float(r["u0"]) / sw.u0
                    cands.append(w)
            if not cands:
                continue
            kept = [cands[i] for _, i in self._ranked(cands, causes)[:RIDGE_KEEP]]
            lead = cands[0]  # the ridge's first: the best by the recorded peaks, its U0 profiled
            if "u0" in lead:
                grid = u0_grid(lead, float(lead["u0"]), TERM_RIDGE_STEP, TERM_RIDGE_HALF)
                kept.append(grid[self._ranked(grid, causes)[0][1]])
            out += kept
        return out

    def _beyond_noise(self, values: dict, causes: tuple) -> bool:
        """Whether the model ``causes`` at ``values`` fails its chi-square test at the diagnosis' alpha (the
        engine's detectability criterion): a reference that fits the data to their noise leaves no basin for an
        extension to be searched for."""
        from probedyn.diagnose.tails import chi2 as chi2_dist

        from probedyn.diagnose.engine import ALPHA

        r = self.residuals(values, causes)
        return bool(chi2_dist.sf(float(np.sum(r**2)), max(len(r) - len(values), 1)) < ALPHA)

    def _period_profiles(self, starts: list[tuple[dict, float]], causes: tuple) -> list[dict]:
        """Ridge starts ``(v, c0)`` (a start and its chi^2) each profiled in the period and corrugation: ``a`` on a grid of
        ``PERIOD_STEP`` with U0 at the start's eta (U0 with a^2), then U0 on a grid of ``U0_STEP``, each kept where
        the whole model's chi^2 falls. A ridge that keeps the reference's period along the scan (a misaligned
        scan's x train, ``a = a_ref cos(theta)``) inherits that period's error: on a lever stiffer across the scan
        the scan's force has two periods, a / cos(theta) and a / sin(theta), and the baseline's one period lies
        ~1 % from the first, where the basin is ~0.5 % wide. Own study, 2019 (10.2 deg, k_y = 2.56 k_x): the
        ridge point from the lattice constant (10.9 deg, k_y / k_x = 3) has chi^2 6.6e5 at the baseline's period and
        1.8e5 profiled; the least-squares fit from the profiled point ends at 1.4e4 (the truth's own 2.8e4; theta
        within 2.7 %), from the raw point at 4.9e5 (the baseline's 5.7e5).

        The trials are the whole model's chi^2 at independent points, so each of the two grids of every start goes
        through :meth:`_map` as one map of ``_chi2_at`` (the engine's pool: 20 trials, then 12, spread over the
        workers; until session 66 one job per start, 10.5 s and 7.6 s, the second worker idle for the difference).
        Each start keeps the first of its lowest trials in the grid's order, as when the trials ran in turn."""
        bounds = {p.name: (p.lo, p.hi) for p in self.base_params}

        def clip(name: str, x: float) -> float:
            lo, hi = bounds.get(name, (-math.inf, math.inf))
            return min(max(x, lo), hi)

        best = [(c0, v) for v, c0 in starts]

        def grid(trials: list[list[dict]]) -> None:
            c2s = iter(self._map("_chi2_at", [(w,) for ws in trials for w in ws], causes))
            for j, ws in enumerate(trials):
                for w in ws:
                    c2 = next(c2s)
                    if c2 < best[j][0]:
                        best[j] = (c2, w)

        grid([[{**v, "a": clip("a", v["a"] * f), "u0": clip("u0", v["u0"] * f * f)}
               for f in (1.0 + PERIOD_STEP * k for k in range(-PERIOD_HALF, PERIOD_HALF + 1) if k)] for _, v in best])
        grid([[{**b, "u0": clip("u0", b["u0"] * (1.0 + U0_STEP * k))} for k in range(-U0_HALF, U0_HALF + 1) if k]
              for _, b in best])
        return [b for _, b in best]

    # -- model --------------------------------------------------------------------------------
    def state(self, values, causes=()) -> FrictionState:
        st = FrictionState(u0=values["u0"], a=values["a"], load_share=self.load_share, n_ref=self.N_mean)
        if self.temperature is not None and self.temperature > 0:
            st.temperature = float(self.temperature)  # declared (read_friction): the thermal mean of the branches
        if self.data.k_y:
            st.ky_ratio = self.data.k_y / self.data.k_x  # declared: the lever's own
        for c in self.base_terms:
            c.effect(values, st)
        for c in causes:
            c.effect(values, st)
        return st

    def _align(self, i: int, st: FrictionState, train: int, m0: np.ndarray, target: np.ndarray) -> float:
        """Registry of one lattice train of scan i: phase of the fundamental of model vs data over
        the steady parts of each segment (the training samples only during cross-validation)."""
        s = self.data.scans[i]
        w = math.cos(st.theta) if train == 0 else math.sin(st.theta)
        if w <= 1e-9:
            return 0.0
        kx = 2 * math.pi * w / st.a  # along the support coordinate
        mask = self._fit_mask(i)
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        acc = 0.0 + 0.0j
        for seg in np.split(np.arange(len(s.force)), cuts):
            x = s.position[seg]
            steady = np.abs(x - x[0]) > 1.5 * st.a / w
            sel = seg[steady & mask[seg]]
            if len(sel) < 8:
                continue
            e = np.exp(-1j * kx * (s.position[sel] - _centre(s))) * np.hanning(len(sel))
            acc += np.sum(m0[sel] * e) * np.conj(np.sum(target[sel] * e))
        if acc == 0:
            return 0.0
        return float(np.angle(acc)) / (2 * math.pi / st.a)

    # -- the registry profile ---------------------------------------------------------------
    def _model_key(self, st: FrictionState):
        """The physical model a state stands for, as a hashable key (None: not memoised). Two states
        that integrate the same model have the same key: thermal activation whose activated slip
        point does not precede the athermal one on any scan (the attempt frequency at its null) is
        the athermal model."""
        if st.transforms:
            return None
        th = st.thermal
        if th is not None:
            # the hazard of an activated slip before the instability is below f0 / V times the stick
            # branch's support span (< 3a/4 + F0/k; the Boltzmann factor <= 1): below THERMAL_MIN_HAZARD
            # on every scan the slips stay athermal (_thermal_path), the model is the athermal one
            ws = [math.cos(st.theta)] + ([math.sin(st.theta)] if st.theta > 1e-6 else [])
            k = self.data.k_x
            bound = max(th[1] * (0.75 * st.a + 2 * math.pi * st.u0 * effective_load(st, s.load) / (k * st.a))
                        / max(s.speed * w, 1e-300) for s in self.data.scans for w in ws)
            th = (float(th[0]), float(th[1])) if bound >= THERMAL_MIN_HAZARD else None
        return (float(st.u0), float(st.a), float(st.gamma), float(st.n_adh), float(st.load_share), float(st.n_ref),
                float(st.offset), float(st.drift),
                float(st.bow), float(st.theta), float(st.gain), th, float(st.ky_ratio) if _coupled(st) else 1.0,
                float(st.temperature))

    def _mask_key(self):
        return None if self.train_mask is None else hash(np.asarray(self.train_mask, bool).tobytes())

    def _scan_model(self, i: int, st: FrictionState, phis) -> tuple[np.ndarray, np.ndarray]:
        """Model lateral force of scan i at registry ``phis`` (both lattice trains, gain, offset,
        drift and transforms applied) and its variance from stochastic slip points. The models evaluated are kept
        (:meth:`_scan_model_once`; at most :data:`SCAN_MEMORY_BYTES`, the least recently used dropped), keyed by
        everything they depend on: the scan, the registry, the training mask, the noise and every field of the state.
        The registry's profile ends at the registry it returns, which the start well's test, the registry memory and
        the prediction then evaluate again (up to three integrations of the same scan and model); a fit's steps,
        its finite differences and the polishing of registries come back to models evaluated a few hundred
        evaluations before. Until session 66 only the last model of each scan was kept: in the three-scan example
        3658 of 24280 evaluations (13 s of 87 s) were models evaluated before. A kept model is the one evaluated, so
        the diagnosis' numbers do not depend on what is kept."""
        if st.transforms:  # a transform is a function: no key for it
            return self._scan_model_once(i, st, phis)
        # ... and the detector's clock the drift is read on (drift_clock: a problem read again on another clock must
        # not find the models of the first)
        key = (i, tuple(float(p) for p in phis), self._mask_key(), float(self.sigma), float(self.thermal_noise_T),
               self.drift_clock, *(getattr(st, f.name) for f in fields(st) if f.name != "transforms"))
        memo = self._scan_memo
        hit = memo.get(key)
        if hit is not None:
            memo.move_to_end(key)
            F, var, th = hit
        else:
            F, var = self._scan_model_once(i, st, phis)
            th = self._last_thermal
            memo[key] = (F, var, th)
            self._scan_memo_bytes += _nbytes(F, var, th)
            while self._scan_memo_bytes > SCAN_MEMORY_BYTES and len(memo) > 1:
                self._scan_memo_bytes -= _nbytes(*memo.popitem(last=False)[1])
        self._last_thermal = th
        return F.copy(), var.copy()

    def _scan_model_once(self, i: int, st: FrictionState, phis, atoms: list | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_scan_model` evaluated; ``atoms`` (a list) receives the slip points' mixture at the scan's samples
        (:class:`.mixture.SlipMixture`, its offsets in the recorded force: each train's weight and the gain applied, its
        groups told apart by train)."""
        s = self.data.scans[i]
        if _coupled(st):
            return self._combine(i, st, [simulate_scan_2d(self.data, st, s, phis)], [np.zeros(len(s.force))],
                                 weights=(1.0,))
        trains = [0] + ([1] if st.theta > 1e-6 else [])
        parts = []
        vs: list = []
        regions: list | None = [] if len(trains) == 1 else None  # an aligned scan: one train, its slips' landing wells
        for tr in trains:
            own: list | None = [] if atoms is not None else None
            parts.append(simulate_scan(self.data, st, s, phis, train=tr, var_out=vs, skip_out=regions, atoms=own))
            if own:
                wt = st.gain * (math.cos(st.theta) if tr == 0 else math.sin(st.theta))
                atoms.extend(SlipMixture(P.sample, P.group * len(trains) + tr, wt * P.offsets, P.weights) for P in own)
        F, var = self._combine(i, st, parts, vs)
        if regions:
            F = self._skips(i, st, F, var, regions)
        return F, var

    def _skips(self, i: int, st: FrictionState, F: np.ndarray, var: np.ndarray, regions) -> np.ndarray:
        """The landing well of each slip of scan i that could have carried the tip one well further
        (:func:`_skip_regions`), profiled against the data: the further well is taken where it lowers the scan's
        chi^2 (its fitted samples) by more than :data:`SKIP_MIN_GAIN`. A discrete nuisance per slip, as the registry is
        per scan: which well a stochastic slip ended in is the record's, not a parameter of the model (blind f08,
        300 K, eta 7.5 on its high-load scan: one slip of 14 landed a well further, its segment 120 sigma below the
        model, chi^2 2.3e5 of the scan's 2.3e5 at the generator's parameters)."""
        s = self.data.scans[i]
        mask = self._fit_mask(i)
        w2 = 1.0 / (self.sigma**2 + var)
        F = F.copy()
        for idx, dF in regions:
            alt = F[idx] + st.gain * dF
            m = mask[idx]
            gain = float(np.sum(((s.force[idx] - F[idx]) ** 2 - (s.force[idx] - alt) ** 2) * w2[idx] * m))
            if gain > SKIP_MIN_GAIN:
                F[idx] = alt
        return F

    def _combine(self, i: int, st: FrictionState, parts, vs, weights=None) -> tuple[np.ndarray, np.ndarray]:
        """Lateral force of scan i and its variance from the simulated trains ``parts`` (x, then y
        for a misaligned scan) and their slip-point variances ``vs``: weights cos/sin theta (``weights``: others,
        e.g. 1 for the coupled trains' force along the scan), gain, offset, drift and transforms."""
        s = self.data.scans[i]
        w = [math.cos(st.theta), math.sin(st.theta)] if weights is None else list(weights)
        F = st.gain * sum(wt * p for wt, p in zip(w, parts))
        var = st.gain**2 * sum(wt**2 * v for wt, v in zip(w, vs))
        if self.thermal_noise_T:  # the tip's thermal motion in its well, per train (independent axes)
            U0 = st.u0 * effective_load(st, s.load)
            # the lever's damping only: a viscous tip-substrate friction brings its noise too (fluctuation-
            # dissipation), but a cause that widens the variance lowers chi^2 without the likelihood's
            # log-determinant, which the causes' comparison leaves out (own seed 2002 at 300 K: with c + gamma the
            # viscous friction was named for the adhesion; docs/diagnose.md 9.46)
            th = st.gain**2 * sum(wt**2 * thermal_force_variance(p, U0, st.a, self.data.k_x, self.c_tip,
                                                                  self.thermal_noise_T, self.sample_dt[i])
                                  for wt, p in zip(w, parts))
            var = var + th
            self._last_thermal = th
        F = F + self._zero(i, st)
        for tf in st.transforms:
            F = tf(self, s, F)
        return F, var

    def _zero(self, i: int, st: FrictionState) -> np.ndarray:
        """The detector's zero at scan i's samples: the offset and the drift, one rate on the drift clock."""
        return st.offset + st.drift * self.t_drift[i] / self.t_ref

    def _scan_chi2(self, i: int, F: np.ndarray, var: np.ndarray) -> float:
        """The weighted squared residuals of scan i over the samples the fit uses."""
        s = self.data.scans[i]
        r = (s.force - F) / np.sqrt(self.sigma**2 + var)
        return float(np.sum(r[self._fit_mask(i)] ** 2))

    # -- the registry memory across processes (engine: pool jobs) -----------------------------
    def memo_fork(self) -> None:
        """In a forked worker: the registry memory as forked is the state every job starts from (:meth:`memo_reset`),
        so that a job's result does not depend on which jobs the same worker ran before it."""
        self._memo_base = dict(self._registry)

    def memo_reset(self) -> None:
        """Before a worker's job: the memory as forked."""
        self._registry = dict(getattr(self, "_memo_base", self._registry))

    def memo_clear(self) -> None:
        """Forget every registry found: a diagnosis run again from its start (engine ``diagnose``, the baseline's law
        chosen again) is then the diagnosis a fresh problem under that law gives, not one steered by the first run's
        registries (own seed 2015: chi^2 7383 after the first run's memory, 1826 from a fresh problem)."""
        self._registry = {}

    def memo_delta(self) -> dict:
        """After a worker's job: the registries it found (new models, or better ones), for the parent's memory."""
        base = getattr(self, "_memo_base", {})
        return {k: v for k, v in self._registry.items() if base.get(k) is not v}

    def memo_merge(self, delta: dict) -> None:
        """In the parent: a job's registries merged into the memory (each kept where it is the best seen); the parent
        merges the jobs of one map in their order, whichever worker ran them."""
        for key, (phis, c2) in delta.items():
            self._remember(key, phis, c2)

    def _remember(self, key, phis, c2: float) -> None:
        """Keep the registry of a scan at a model if it is the best seen there (bounded memory)."""
        old = self._registry.get(key)
        if old is None or c2 < old[1]:
            if old is None and len(self._registry) >= REGISTRY_MEMORY:
                self._registry.pop(next(iter(self._registry)))
            self._registry[key] = ([float(p) for p in phis], c2)

    def nuisance(self, values, causes=()) -> list[list[float]]:
        """The lattice registry of every scan (and train) at these parameters: the model at
        registry 0 aligned with the data (training samples only) by the phase of the fundamental,
        polished by least squares; or, where it fits that scan better, the registry of the best
        evaluation of the same model seen before (a profile over a rugged stick-slip chi^2 is not
        a smooth function of the parameters: the alignment alone may land on another registry than
        the one a fit held and converged with; a cause at its null values is the baseline's model,
        so its profile is the baseline's own registry)."""
        st = self.state(values, causes)
        trains = [0] + ([1] if st.theta > 1e-6 else [])
        mkey = self._model_key(st)
        mk = self._mask_key()
        out = []
        for i, s in enumerate(self.data.scans):
            if len(trains) == 1:
                phis = self._start_well(i, st, self._profile_one_train(i, st, 0),
                                        lambda well: self._profile_one_train(i, st, well))
            else:
                phis = [0.0, 0.0]
                for tr in trains:
                    m0 = simulate_scan(self.data, st, s, [0.0, 0.0], train=tr)
                    phis[tr] = self._align(i, st, tr, m0, s.force)
                phis = self._profile_two_trains(i, replace(st, ky_ratio=1.0), phis)
                phis = self._start_well(i, st, self._profile_coupled(i, st, phis),
                                        lambda well, p=phis: self._profile_coupled(i, st, [*p[:2], float(well)]))
            known = self._registry.get((mkey, i, mk)) if mkey is not None else None
            if known is not None:
                c2 = self._scan_chi2(i, *self._scan_model(i, st, phis))
                if known[1] <= c2:
                    phis = list(known[0])
                else:
                    self._remember((mkey, i, mk), phis, c2)
            out.append(phis)
        return out

    def _profile_one_train(self, i: int, st: FrictionState, well: int) -> list[float]:
        """Registry of an aligned scan with the tip starting the pre-roll ``well`` periods from the support:
        the model at registry 0 aligned with the data by the phase of the fundamental, then polished on the scan's
        chi^2 (:func:`_polish`, steps :data:`REGISTRY_STEPS`). The phase of the fundamental is biased by the reversal
        transients and by the activated slips' scatter by up to about 1e-2 a (blind f08's fast scan at 300 K: 1.1e-2 a, chi^2 720 where
        the polished registry gives 255 on 323 samples; the two fixed parabolas before session 62 reached 1e-2 a
        at most and weighed the samples equally, so a slip one well further, 120 sigma off, set them)."""
        s = self.data.scans[i]
        tail = [float(well)] if well else []
        m0 = simulate_scan(self.data, st, s, [0.0, 0.0, *tail])
        phi = self._align(i, st, 0, m0, s.force)

        def chi2(ph: float) -> float:
            return self._scan_chi2(i, *self._scan_model(i, st, [ph, 0.0, *tail]))

        phi, c = _polish(chi2, phi, chi2(phi), [h * st.a for h in REGISTRY_STEPS], repeat=REGISTRY_REPEAT)
        if self.short_scans[i]:
            n_fit = int(np.sum(self._fit_mask(i)))
            if c > n_fit + 4.0 * math.sqrt(2.0 * n_fit):
                # a short scan: the fundamental's phase may be another registry's; the best of ALIGN_GRID over a
                # period, polished, where it fits the scan better
                grid = phi + st.a * np.arange(1, ALIGN_GRID) / ALIGN_GRID
                cg = [chi2(float(g)) for g in grid]
                j = int(np.argmin(cg))
                if cg[j] < c:
                    steps = [st.a / (2 * ALIGN_GRID), st.a / (8 * ALIGN_GRID)] + [h * st.a for h in REGISTRY_STEPS]
                    pg, c2 = _polish(chi2, float(grid[j]), cg[j], steps, repeat=REGISTRY_REPEAT)
                    if c2 < c:
                        phi = pg
        return [phi, 0.0, *tail]

    def _aligned_periods(self, i: int) -> float:
        """The lattice periods of scan i whose samples :meth:`_align` reads the phase of the fundamental from (the
        steady used samples of every segment, both directions together), in the slips' period: a property of the
        record, not of a model's period or of a cross-validation fold (one segment held out), so that the registry's
        profile is one procedure across a fit and its folds."""
        s, a = self.data.scans[i], self.a_slip
        mask = self.use[self.slices[i]]
        cuts = np.nonzero(np.diff(s.direction) != 0)[0] + 1
        tot = 0.0
        for seg in np.split(np.arange(len(s.force)), cuts):
            x = s.position[seg]
            sel = seg[(np.abs(x - x[0]) > 1.5 * a) & mask[seg]]
            if len(sel) >= 8:
                tot += float(np.ptp(s.position[sel])) / a
        return tot

    def _start_well(self, i: int, st: FrictionState, phis, profile) -> list[float]:
        """Coexisting slip patterns (scan i's corrugation above MULTISLIP_ETA): the registry ``phis`` of the tip
        starting under the support, or the start well whose pattern fits the scan best (``profile(well)``: the
        registry profiled with the tip starting ``well`` lattice periods from the support along the x axis), tried
        only where the one under the support leaves the scan beyond its noise. The same for a misaligned scan, on
        either lever (own study s48, 2019: a double-load scan at eta 12 and k_y = 2.6 k_x has chi^2 4.4e6 at the
        truth from under the support, 2.4e4 from the next well; on 577 samples)."""
        U0 = st.u0 * effective_load(st, self.data.scans[i].load)
        if not (2 * math.pi / st.a) ** 2 * U0 / self.data.k_x > MULTISLIP_ETA:
            return phis
        F0, v0 = self._scan_model(i, st, phis)
        c2 = self._scan_chi2(i, F0, v0)
        n_fit = int(np.sum(self._fit_mask(i)))
        if c2 <= n_fit + 4.0 * math.sqrt(2.0 * n_fit):
            return phis
        # patterns coexist only where the model's own tip slips past the next well: a single slip releases at
        # most ~k a of the spring's force, a double one ~2 k a. Where the model slips one well at a time every
        # start well ends in the same pattern, and choosing among them by their pre-roll transients alone makes
        # the fit's objective jump between wells (own friction study s47: a scanner non-linearity at eta 6, Q 1,
        # left at its null, 'unexplained', where session 39 found it with chi^2 1764 on 1709)
        if _largest_slip(F0, self.data.scans[i].direction) < MULTISLIP_DROP * st.gain * self.data.k_x * st.a:
            return phis
        # another start well is taken where it explains most of the scan's misfit (chi^2 below MULTISLIP_GAIN of the
        # one under the support's): a pattern a period out of phase misfits every slip of the scan (blind f03:
        # 1.2e6 -> 2.9), while under a wrong model another well only shifts part of the misfit, and a choice
        # made on that part switches wells between the evaluations of a fit (own study s47, 2032 and 2047: 5 %
        # lower at the baseline, and the nested causes could no longer leave their nulls)
        best = MULTISLIP_GAIN * c2
        for well in range(-MULTISLIP_WELLS, MULTISLIP_WELLS + 1):
            if well:
                ph = profile(well)
                cw = self._scan_chi2(i, *self._scan_model(i, st, ph))
                if cw < best:
                    phis, best = ph, cw
        return phis

    def _profile_two_trains(self, i: int, st: FrictionState, phis) -> list[float]:
        """Registries of the two lattice trains of a misaligned scan. The y train has the period
        a / sin(theta) along the scan: a scan of a few lattice periods holds one or two of its
        periods, too few for the phase of its fundamental (the steady parts are empty); its registry
        is the best of ``Y_GRID`` registries over one period, polished by parabolas; then the x
        train's registry (from the fundamental) is polished the same way."""
        s = self.data.scans[i]
        a = st.a

        def train(tr: int, ph: float):
            vs: list = []
            f = simulate_scan(self.data, st, s, [ph, ph], train=tr, var_out=vs)
            return f, vs[0]

        def chi2(fx, fy) -> float:
            return self._scan_chi2(i, *self._combine(i, st, (fx[0], fy[0]), (fx[1], fy[1])))

        fx = train(0, phis[0])
        grid = phis[1] + a * np.arange(Y_GRID) / Y_GRID
        fys = [train(1, g) for g in grid]
        c = [chi2(fx, fy) for fy in fys]
        j = int(np.argmin(c))
        p1, c1 = _polish(lambda x: chi2(fx, train(1, x)), float(grid[j]), c[j], (a / (2 * Y_GRID), a / (8 * Y_GRID), 1e-3 * a))
        fy = train(1, p1)
        p0, _ = _polish(lambda x: chi2(train(0, x), fy), float(phis[0]), c1, (4e-3 * a, 1e-3 * a))
        return [p0, p1]

    def _profile_coupled(self, i: int, st: FrictionState, phis) -> list[float]:
        """Registries of a misaligned scan from the decoupled trains' (``phis``, :meth:`_profile_two_trains`): the
        best of ``Y_GRID`` registries of the y axis over one period with the x axis's held, then both polished by
        parabolas, on the scan's own model (the lattice axes coupled where ``k_y != k_x``). On an isotropic lever
        too, so that the profile is one procedure on either side of ``k_y = k_x`` (the coupled model is
        continuous into the decoupled one; the trains' profile, polishing the x registry last on a short step,
        leaves it up to a tenth of a period from the joint optimum)."""
        a = st.a
        tail = [float(w) for w in phis[2:]]  # the start well, if any (:meth:`_start_well`)

        def chi2(p0: float, p1: float) -> float:
            return self._scan_chi2(i, *self._scan_model(i, st, [p0, p1, *tail]))

        p0 = float(phis[0])
        grid = float(phis[1]) + a * np.arange(Y_GRID) / Y_GRID
        c = [chi2(p0, g) for g in grid]
        j = int(np.argmin(c))
        p1, c1 = _polish(lambda x: chi2(p0, x), float(grid[j]), c[j], (a / (2 * Y_GRID), a / (8 * Y_GRID), 1e-3 * a))
        p0, c0 = _polish(lambda x: chi2(x, p1), p0, c1, (a / (2 * Y_GRID), a / (8 * Y_GRID), 1e-3 * a))
        p1, _ = _polish(lambda x: chi2(p0, x), p1, c0, (a / (8 * Y_GRID), 1e-3 * a))
        return [p0, p1, *tail]

    def _fit_mask(self, i: int) -> np.ndarray:
        """Samples of scan i that the fit uses (start transient out; training samples during CV)."""
        mask = self.use[self.slices[i]].copy()
        if self.train_mask is not None:
            full = np.zeros(self.n, bool)
            full[np.nonzero(self.use)[0][self.train_mask]] = True
            mask &= full[self.slices[i]]
        return mask

    def predict(self, values, causes=()) -> np.ndarray:
        st = self.state(values, causes)
        out = np.empty(self.n)
        nu = self.fixed_nuisance if self.fixed_nuisance is not None else self.nuisance(values, causes)
        self.model_var = np.zeros(self.n)
        self.thermal_var = np.zeros(self.n)
        # the registry profile of a model is the best registry known for it (nuisance()): a held
        # registry is replaced where the same model was seen with a better one, and remembered
        # where it is the best (so that the same model always gives the same residuals, whichever
        # fit reached it: the nested-fit guarantee at a cause's null values)
        mkey = self._model_key(st)
        mk = self._mask_key()
        self._last_phis = list(nu)
        for i, s in enumerate(self.data.scans):
            F, var = self._scan_model(i, st, nu[i])
            if mkey is not None:
                c2 = self._scan_chi2(i, F, var)
                known = self._registry.get((mkey, i, mk))
                if known is not None and known[1] < c2:
                    F, var = self._scan_model(i, st, known[0])
                    self._last_phis[i] = known[0]
                else:
                    self._remember((mkey, i, mk), nu[i], c2)
            th = self._last_thermal if self.thermal_noise_T else 0.0
            self.thermal_var[self.slices[i]] = th
            self.model_var[self.slices[i]] = var - th
            out[self.slices[i]] = F
        if self.thermal_noise_T and self.data.noise_part == "total":
            # the stated noise is the samples' total: the thermal part's mean square is taken out of it and shared
            # out by its own pattern (the fast scan's interval means and the soft ends of the stick branches carry
            # more), so that the mean variance stays the stated one; a thermal part beyond 95 % of the stated
            # variance leaves the detector 5 % (the statement then understates the noise)
            self.thermal_var -= min(float(np.mean(self.thermal_var[self.use])), (1.0 - DETECTOR_MIN_SHARE) * self.sigma**2)
        return out

    def variance_fitted(self, values, causes=()) -> bool:
        """Whether the model carries a variance of its own that its parameters set (the thermal slip scatter,
        :func:`_scatter_moments`). The fit minimises ``sum r^2 / (sigma^2 + var)`` without ``ln(sigma^2 + var)``,
        so it can lower its chi-square by widening the scatter; the engine then also tests the chi-square's lower
        tail (engine ``gof_p_lower``; blind f20: 650 on 892 degrees of freedom, docs/diagnose.md 9.41)."""
        try:
            self.predict(values, causes)
        except ProbedynError:
            return False
        return bool(np.any(self.model_var[self.use] > 0))

    def variance_logdet(self, values, causes=()) -> float:
        """``sum ln(1 + var / sigma^2)`` over the fitted samples: the part of ``-2 ln L`` that the chi-square leaves
        out where the model carries a variance of its own (the thermal slip scatter, and the tip's thermal force noise,
        whose well stiffness the model sets: :func:`thermal_force_variance`). A likelihood-ratio test of such
        a model against one without adds it to the model's chi-square: a widened scatter lowers chi^2 by down-weighting
        the worst samples even where there is no scatter to model (own seed 7 at 0.01 K: chi^2 -17.9 with a scatter up to
        2 sigma^2 on a few samples, of which the log term takes back 6.5)."""
        try:
            self.predict(values, causes)
        except ProbedynError:
            return 0.0
        return float(np.sum(np.log1p((self.model_var + self.thermal_var)[self.use] / self.sigma**2)))

    def variance_rows(self) -> np.ndarray:
        """``sqrt(ln(1 + var / sigma^2) + L0)`` per fitted sample of the model :meth:`residuals` last evaluated (its
        slip scatter and thermal force noise, :meth:`variance_logdet`'s terms; ``sqrt(L0)`` after a model that could
        not be evaluated): the rows a fit adds to its objective so that it minimises ``-2 ln L``, not chi^2 alone
        (``variance_in_objective``, engine ``Fitter.var_rows``). ``L0`` (:attr:`variance_floor`) is a constant of the
        record: where the stated noise is the samples' total, the thermal part's own pattern is taken out of it
        (:meth:`predict`), so ``var`` is negative on the samples that carry less than its mean, down to
        ``-(1 - DETECTOR_MIN_SHARE) sigma^2``; ``L0 = -ln DETECTOR_MIN_SHARE`` keeps every row real (before session
        74 such a row was the square root of a negative number: blind f04, 1 K, a total noise stated, no fit could
        start). A constant per row shifts every fit of the record alike, so no comparison of fits moves."""
        L0 = self.variance_floor
        if not self._last_ok:
            return np.full(int(self.use.sum()), math.sqrt(L0))
        e = np.log1p((self.model_var + self.thermal_var)[self.use] / self.sigma**2) + L0
        return np.sqrt(np.maximum(e, 0.0))

    @property
    def variance_floor(self) -> float:
        """``L0`` of :meth:`variance_rows`: ``-ln DETECTOR_MIN_SHARE`` where the thermal force noise is shared out of
        a stated total (its rows can then be negative), else 0."""
        return -math.log(DETECTOR_MIN_SHARE) if (self.thermal_noise_T and self.data.noise_part == "total") else 0.0

    def mixture(self, values, causes=()) -> tuple[np.ndarray, np.ndarray, list[SlipMixture]] | None:
        """The model's law per sample beyond its mean and variance: ``(mean, total variance, parts)`` with ``parts``
        the slip points' mixture (:class:`.mixture.SlipMixture`, record sample numbers, a group per slip). None where
        the model has no slip scatter or cannot be evaluated."""
        try:
            m = self.predict(values, causes)
        except ProbedynError:
            return None
        if not np.any(self.model_var[self.use] > 0):
            return None
        st = self.state(values, causes)
        parts: list[SlipMixture] = []
        for i in range(len(self.data.scans)):
            own: list = []
            self._scan_model_once(i, st, self._last_phis[i], atoms=own)
            # the record's sample numbers, and each scan's slips their own groups
            parts.extend(SlipMixture(P.sample + self.slices[i].start, np.asarray(P.group, np.int64) + (i << 32),
                                     P.offsets, P.weights) for P in own)
        return m, self.sigma**2 + self.thermal_var + self.model_var, parts

    def pit(self, values, causes=()) -> PitTest | None:
        """The fitted samples' probability integral transform through the model's own law (:func:`.mixture.pit_test`):
        where the model is a mixture over the slip points (a declared temperature's activated slips), each sample read
        against the slip law's own distribution, not its mean and variance (the engine's ``slip_law_check``,
        docs/diagnose.md 9.58). None where the model has no slip scatter (the residuals are the scores) or cannot be
        evaluated."""
        mix = self.mixture(values, causes)
        if mix is None:
            return None
        m, total, parts = mix
        return pit_test(self.force - m, total, parts, self.use)

    def residuals(self, values, causes=()) -> np.ndarray:
        self._last_ok = False
        try:
            m = self.predict(values, causes)
        except ProbedynError:
            return np.full(int(self.use.sum()), 1e6)
        self._last_ok = True
        # the stochastic slip-position scatter (thermal activation) and, at a declared temperature, the tip's
        # thermal force noise (thermal_force_variance) add their variances sample by sample
        return ((self.force - m) / np.sqrt(self.sigma**2 + self.thermal_var + self.model_var))[self.use]

    def physical_rms(self, r) -> float:
        return float(np.sqrt(np.mean(np.asarray(r) ** 2)) * self.sigma)

    # -- structure ----------------------------------------------------------------------------
    def structure(self, r: np.ndarray) -> dict[str, Any]:
        from probedyn.diagnose.tails import chi2

        out: dict[str, Any] = {"scans": [], "left_out_start_samples": int((~self.use).sum())}
        fr = []
        full = np.full(self.n, np.nan)
        full[self.use] = np.asarray(r)
        for i, s in enumerate(self.data.scans):
            rr = full[self.slices[i]]
            rr = rr[np.isfinite(rr)]
            rc = rr - rr.mean()
            den = float(np.sum(rc**2)) or 1.0
            m = len(rr)
            ac = [float(np.sum(rc[:-L] * rc[L:]) / den) for L in range(1, 11)]
            Qlb = m * (m + 2) * sum(c * c / (m - L) for L, c in enumerate(ac, start=1))
            fwd = s.direction > 0
            half = 0.5 * (s.force[fwd].mean() - s.force[~fwd].mean()) if fwd.any() and (~fwd).any() else float("nan")
            fr.append(half)
            out["scans"].append({"scan": s.id, "speed": s.speed, "load": s.load, "mean_residual_sigma": float(rr.mean()),
                                 "rms_sigma": float(np.sqrt(np.mean(rr**2))), "lag1_autocorr": ac[0],
                                 "ljung_box_p": float(chi2.sf(Qlb, 10)), "friction_half_loop_N": float(half)})
        fr = np.array(fr)
        for key, xv in (("ln_speed", np.log(self.speeds)), ("load", self.loads)):
            ok = np.isfinite(fr)
            if ok.sum() >= 2 and np.ptp(xv[ok]) > 0:  # scans recorded one way only have no half loop
                A = np.vstack([np.ones(ok.sum()), xv[ok] - xv[ok].mean()]).T
                out[f"friction_vs_{key}_slope"] = float(np.linalg.lstsq(A, fr[ok], rcond=None)[0][1])
        return out

    def predict_observables(self, values, causes) -> list[dict[str, Any]]:
        """Mean friction (half the trace-retrace loop) of hypothetical scans of the fastest scan's
        path at 10x and 0.1x its speed and at 2x and 0.5x its load."""
        st = self.state(values, causes)
        ref = self.data.scans[int(np.argmax(self.speeds))]
        out = []
        for label, fs, fl in (("a scan at 10x the highest speed", 10.0, 1.0),
                              ("a scan at 1/10 of the lowest speed", 0.1 * self.speeds.min() / ref.speed, 1.0),
                              ("a scan at twice the highest load", 1.0, 2.0 * self.loads.max() / ref.load),
                              ("a scan at half the lowest load", 1.0, 0.5 * self.loads.min() / ref.load)):
            sc = replace(ref, speed=ref.speed * fs, load=ref.load * fl, time=ref.time / fs)
            try:
                F = st.gain * simulate_scan(self.data, st, sc, [0.0, 0.0]) + st.offset
            except ProbedynError:
                continue
            fwd = sc.direction > 0
            half = 0.5 * (F[fwd].mean() - F[~fwd].mean()) if fwd.any() and (~fwd).any() else float(np.mean(F))
            out.append({"measure": f"{label} (mean friction, half the trace-retrace loop)", "value": float(half),
                        "sigma": self.sigma / math.sqrt(len(F)), "unit": "N"})
        return out

    def describe(self) -> dict[str, Any]:
        d = self.data
        return {"kind": "friction", "scans": len(d.scans), "samples": self.n, "speeds_m_s": sorted(set(self.speeds.tolist())),
                "loads_N": sorted(set(self.loads.tolist())), "k_x_N_per_m": d.k_x, "sigma_force_N": self.sigma,
                "noise_stated": d.noise_stated, "sigma_stated_N": d.sigma_force, "sigma_scatter_N": self.sigma_scatter,
                "noise_excess": self.noise_excess, "sampling": d.sampling, "lattice_estimate_m": self.a_est,
                "temperature_K": d.temperature, "medium": d.medium_name or "not declared",
                "thermal_force_noise": (f"the tip's thermal force noise at {self.thermal_noise_T:g} K (equipartition in the "
                                        "well, averaged over each sample's interval) "
                                        + ("added to the stated detector noise" if d.noise_part == "detector" else
                                           "shared out of the stated total noise by its own pattern")
                                        if self.thermal_noise_T else "not added (no temperature declared, or the noise "
                                        "is the record's own scatter)"),
                "drift_clock": ("one clock through the record" if self.drift_clock == "record"
                                else "each scan's own clock (the time between scans unknown)")}

    def model_description(self) -> dict[str, Any]:
        ffm = _ffm(self.data, 1e-21, self.a_est, 0.0)
        cp = ffm.cantilever
        return {"baseline": "FFM line-scan model (schemes/ffm.py, eqs 2.13-2.15) with the registry friction model 'pt', "
                            "trace and retrace along the measured support path (line_scan_path)",
                "lever": {"k_x": cp["k_x"], "m_x": cp["m_x"], "c_x": cp["c_x"]},
                "sampling": self.data.sampling, "registry": "profiled per scan (fundamental alignment, then re-integration)",
                "corrugation_load_law": {"amontons": "U0 = u0 N (the registry's at_load)",
                                         "load-independent": "U0 = u0 N_ref on every scan (the plain PT model)"}[
                    self.baseline_law] + (f", N_ref = {self.N_mean:.4g} N" if self.baseline_law != "amontons" else "")}
