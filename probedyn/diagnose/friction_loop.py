"""Friction loops at the mesoscale: lateral-force lines whose samples each average many lattice periods.

An image line of a lateral-force (friction) channel -- micrometres of travel, one sample per ~0.1 um,
trace and retrace -- does not resolve the atomic stick-slip of :mod:`.friction`: every sample is the
mean lateral force over its interval, i.e. over hundreds of lattice periods. What such a record
carries is the mean (kinetic) friction of each direction, and whatever else the lateral channel
records along the line.

Baseline: probedyn's FFM line-scan model (:mod:`probedyn.schemes.ffm`, the registry friction model
``pt`` with ``U0 = u0 N`` at the declared lattice, the lever of the sidecar) run to its steady
stick-slip cycle at each scan's speed and the record's reference load ``N_ref`` (the mean of the scans'
loads); its mean lateral force ``F_k(u0; v, N_ref)``, scaled to each scan's load by Amontons' law,
``F_k(N) = F_k(N_ref) N / N_ref`` (Derjaguin's ``(N + N_adh) / (N_ref + N_adh)`` with the adhesion-load
cause), is the
friction of every sample, with the sign of the scan direction ``d`` (+1 trace, -1 retrace), plus the
lateral channel's zero (an uncalibrated offset, always present in a lateral-force signal):
``F = d F_k + offset``. Fitted: ``u0`` and ``offset``. Cross-validation groups: the trace and the retrace
of each scan.

A record at one speed (every loop the own and the blind generators write) gives the FFM nothing to set but that
level, and the level is then the baseline's parameter, ``F_ref`` = ``F_k(u0; v, N_ref)``, with the corrugations
that reach it reported (``u_crossings``). The PT's mean friction is no smooth function of ``u0`` where the slips
skip wells on an underdamped lever: at eta 10-14 and Q_x 8 it jumps by 10-20 % within 0.2 % of ``u0`` (and
differs between averaging windows of 16 and 96 periods), so a fit in ``u0`` ended 1 % off the recorded level and a
null was left unexplained (blind friction set 2, g06: chi^2 2209 on 766; docs/diagnose.md 9.53). Several speeds
keep ``u0``: the FFM then also sets how the friction changes with the speed.

The reversal (:func:`reversal_deficit`): where the support turns, the tip sticks while the lever's force
runs from the friction of one direction to that of the other, at the lever's stiffness ``k_x``. That takes
``2 F_k / k_x`` of support travel (the PT tip's own travel inside its well, under half a lattice period, is
neglected). The first interval mean of each segment falls short of ``d F_k`` by the ramp's share of it,
``(2 F_k)^2 / (2 k_x Delta)`` for an interval ``Delta`` longer than the ramp. That is small against the friction
but not against the noise: 8 sigma on a blind generator's first samples (f10: 7.2 nN, k_x 8 N/m, 39 nm pixels;
session 55). Until then this was called negligible and left out, and every such record failed its chi-square
test on those six samples. Each segment is taken to start at a reversal at the edge of its first interval.
The segment before it is the other direction of the same scan (a raster repeats its line), so a record's
first trace is treated as if that line's retrace came before it.

Load dependence (a departure from the atomic-scale FFM, docs/source-departures.md): a loop sample averages
hundreds of lattice periods over a multi-asperity (or adhesive single-asperity) contact, whose mean friction
is proportional to the total load (Amontons; Derjaguin with adhesion). The PT model with ``U0 = u0 N`` is
not: its mean friction grows with ``U0`` as the stick-slip's energy drop does (measured 1.6-2.2 times, not 2,
from one load to twice it, at eta 5-49), so with scans at two loads a Coulomb truth without any hidden
effect left the baseline unexplained (session 24: chi^2 2303 on 512 samples). The FFM sets the level (and
its speed dependence) at the reference load; with a single load the two are the same model.

Causes for this regime declare ``regimes = ("loop",)`` (:mod:`.causes.surface_slope`: the load's
component along a sloped surface, and :mod:`.causes.friction_contrast`: friction that differs between the
phases of a blend, which the relief marks; both need the recorded topography, column ``height_m``).
The model state is :class:`LoopState`; the sample's surface slope is ``dh/dx`` of the mean of the heights
the instrument recorded in trace and retrace (:func:`segment_slopes`: the feedback's lag cancels).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from probedyn.core.errors import DataFormatError, ProbedynError
from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.formats import FrictionData
from probedyn.diagnose.friction import RTOL, _ffm, _scatter, bind_scans, clipped_starts, drift_clock, scan_groups
from probedyn.schemes.ffm import line_scan_path

__all__ = ["FrictionLoopProblem", "LoopState", "reversal_deficit", "steady_friction", "slope_force"]

#: lattice periods of the steady-friction integration: the first STEADY_PERIODS[0] are the entry transient,
#: the mean is taken over the rest (whole periods: the stick-slip cycle's mean)
STEADY_PERIODS = (8, 24)
#: the smallest ``1 - d mu c t`` the slope law is evaluated at (the tip locks where it reaches 0: a slope
#: steeper than the friction cone)
LOCK_MARGIN = 0.05


@dataclass
class LoopState:
    u0: float  # corrugation per unit load of the PT substrate [J/N]
    offset: float  # the lateral channel's zero [N]
    slope_c: float = 0.0  # coupling of the surface slope (surface-slope cause; 0: none)
    contrast: float = 0.0  # relative friction change from the lowest to the highest relief (friction-contrast)
    n_adh: float = 0.0  # the adhesion load of Derjaguin's law [N] (adhesion-load cause)
    level: float | None = None  # the FFM's mean friction at the reference load [N] (one speed: the parameter)
    stick_compliance: float = 0.0  # k_x / k_contact: the stick at a reversal rises at k_x / (1 + this)
    drift: float = 0.0  # the lateral channel's drift over the longest scan [N] (force-offset-drift cause)
    transforms: list = field(default_factory=list)  # f(problem, F) -> F, applied last
    #: the load scales the friction (Amontons), not the FFM's corrugation (adhesion-load reads this)
    corrugation_follows_load: ClassVar[bool] = False


def steady_friction(data: FrictionData, u0: float, a: float, v: float, N: float) -> float:
    """Mean lateral force of probedyn's FFM (PT substrate ``U0 = u0 N``, period ``a``, the sidecar's
    lever) sliding at speed ``v`` on its steady stick-slip cycle [N] (positive: against the motion)."""
    n0, n1 = STEADY_PERIODS
    ffm = _ffm(data, u0 * max(N, 0.0), a, 0.0)
    res = line_scan_path(ffm, [0.0, n1 * a], speed=v, y0=(0.0, 0.0, 0.0), hmax=0.02 * a / v, rtol=RTOL,
                         atol_rel=RTOL, atol_v=100.0 * v)
    b, F = res.base, res.lateral_force
    sel = b >= n0 * a
    b, F = b[sel], F[sel]
    return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(b)) / max(b[-1] - b[0], 1e-300))


def reversal_deficit(h, k: float, ua, ub):
    """How far the mean of each interval ``[ua, ub]`` (support travel since the reversal [m], ``ub > ua``)
    falls short of the sliding force, in the direction of motion, while the tip sticks after a reversal. The
    lever's force there rises at ``k`` [N/m] through the height ``h`` [N] (from the friction of the last
    direction to that of this one); the deficit is ``h - k u`` for ``u < h / k`` and 0 after. Its integral
    ``G(u) = h m - k m^2 / 2``, ``m = min(u, h / k)``, gives the interval mean ``(G(ub) - G(ua)) / (ub - ua)``.
    A point interval (``ub = ua``) gives the deficit at that point."""
    h = np.maximum(np.asarray(h, float), 0.0)
    L = h / k

    def G(u):
        m = np.clip(u, 0.0, L)
        return h * m - 0.5 * k * m * m

    w = ub - ua
    pt = np.maximum(h - k * np.maximum(ua, 0.0), 0.0)
    return np.where(w > 0, (G(ub) - G(ua)) / np.where(w > 0, w, 1.0), pt)


def slope_force(Fk, N, d, t, c: float = 1.0, A: float = 0.0):
    """Lateral force of a tip sliding on a surface of slope ``t = dh/dx`` under the vertical load ``N``
    with friction ``F_k = mu (N + A)`` (``A`` the adhesion load) in direction ``d`` (Ogletree, Carpick &
    Salmeron 1996, eqs 2-3, the horizontal force balance of a tip on an incline, to first order in the
    slope): ``F = (c N t + d F_k) / (1 - d mu c t)``; ``c`` scales the slope (1: the load's full component).
    ``c = 0`` is the flat-surface loop ``d F_k``."""
    ct = c * np.asarray(t, float)
    den = np.maximum(1.0 - d * (Fk / (N + A)) * ct, LOCK_MARGIN)
    return (N * ct + d * Fk) / den


#: a height component is kept in the surface where its power exceeds the height noise's this many times
SLOPE_SNR = 4.0
#: the relief (2nd to 98th percentile) must exceed the mean surface's noise this many times for the friction
#: contrast to have a phase coordinate (a flat surface has none: the cause is not offered)
RELIEF_SNR = 8.0
#: ... up to the first run of this many neighbouring frequencies below that (the 5-frequency average of a white
#: noise exceeds 4 times its mean with probability 1e-4 per frequency: over hundreds, a lone one does)
QUIET_BINS = 10


def _height_noise(h: np.ndarray) -> float:
    """White-noise level of a height record: the robust (MAD) spread of its second differences over sqrt(6)."""
    r = np.diff(h, 2)
    return float(1.4826 * np.median(np.abs(r - np.median(r))) / np.sqrt(6.0)) if len(r) else 0.0


def low_pass_surface(grid: np.ndarray, h: np.ndarray, noise: float) -> np.ndarray:
    """The surface's components above its noise: the heights (line removed) mirrored to an even sequence,
    Fourier-transformed, and every component dropped from the first ``QUIET_BINS`` frequencies in a row whose
    power (averaged over five neighbours) stays below ``SLOPE_SNR`` times the noise's. Keeping a band of frequencies
    is a projection: the slope it gives correlates with the true slope exactly as much as it varies, so a
    regression on it stays unbiased (the raw slope's noise would attenuate it, errors in variables)."""
    m = len(h)
    if m < 8 or noise <= 0:
        return h
    line = np.polyval(np.polyfit(grid, h, 1), grid)
    e = np.concatenate([h - line, (h - line)[::-1]])
    X = np.fft.rfft(e)
    P = np.convolve(np.abs(X) ** 2, np.ones(5) / 5.0, mode="same")
    below = P <= SLOPE_SNR * len(e) * noise**2
    # the band ends where QUIET_BINS frequencies in a row stay below it (a lone noise bin beyond is not signal)
    run = np.convolve(below.astype(int), np.ones(QUIET_BINS, int), mode="valid")
    quiet = np.nonzero(run == QUIET_BINS)[0]
    kc = int(quiet[0]) - 1 if len(quiet) else len(X) - 1
    X[kc + 1:] = 0.0
    return line + np.fft.irfft(X, len(e))[:m]


def segment_slopes(scan) -> np.ndarray | None:
    """The surface slope ``dh/dx`` at every sample (``None`` without a height column); see
    :func:`segment_surface`."""
    out = segment_surface(scan)
    return None if out is None else out[0]


def segment_surface(scan) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The surface slope ``dh/dx`` and the relief (the surface with its line removed: the sample's tilt and
    the scanner's are not topography) at every sample, and the noise of the mean surface [m] (``None``
    without a height column). The surface is
    the mean of the heights the scan recorded in each direction at the same position: the feedback's
    lag shifts the trace's topography forward and the retrace's backward (on the real Nanosurf lines
    the two differ by 13 nm RMS), and their mean cancels that shift to first order; a scan recorded in
    one direction only uses its own heights. The mean surface is low-passed above its noise
    (:func:`low_pass_surface`; the noise from the heights' second differences) before it is
    differentiated on a uniform grid."""
    if scan.height is None:
        return None
    x, h, d = scan.position, scan.height, scan.direction
    grid = np.linspace(float(x.min()), float(x.max()), len(np.unique(x)))
    curves, noise = [], []
    for sgn in (1.0, -1.0):
        sel = d == sgn
        if sel.sum() >= 3:
            o = np.argsort(x[sel], kind="stable")
            xs, hs = x[sel][o], h[sel][o]
            u, inv = np.unique(xs, return_inverse=True)
            hm = np.bincount(inv, hs) / np.bincount(inv)  # repeated positions (several segments): their mean
            curves.append(np.interp(grid, u, hm))
            noise.append(_height_noise(hm))
    if not curves or len(grid) < 3:
        return np.zeros(len(x)), np.zeros(len(x)), 0.0
    sd = float(np.sqrt(np.mean(np.square(noise)) / len(curves)))
    surface = low_pass_surface(grid, np.mean(curves, axis=0), sd)
    relief = surface - np.polyval(np.polyfit(grid, surface, 1), grid)
    return np.interp(x, grid, np.gradient(surface, grid)), np.interp(x, grid, relief), sd


#: the share of a line's heights taken as its background when the line is levelled (:func:`background_line`)
BACKGROUND_SHARE = 0.4


def background_line(grid: np.ndarray, h: np.ndarray, iterations: int = 5) -> np.ndarray:
    """The line's tilt and zero fitted to its background: the least-squares line through the lowest
    ``BACKGROUND_SHARE`` of its residuals, refitted ``iterations`` times from the plain fit. A plain fit through
    every height is pulled towards the raised phase by as much as the line holds of it, so the same phase
    reads at different relief in different lines and the friction contrast, whose phase coordinate the relief
    is, comes out inflated (a blind generator's blends with line-to-line height offsets, session 30: the
    friction ratio 2.43 read as 4.08; the masked 'row alignment' of image-processing practice, Gwyddion)."""
    p = np.polyfit(grid, h, 1)
    for _ in range(iterations):
        r = h - np.polyval(p, grid)
        sel = r <= np.quantile(r, BACKGROUND_SHARE)
        if sel.sum() < 3 or np.ptp(grid[sel]) <= 0:
            break
        p = np.polyfit(grid[sel], h[sel], 1)
    return p


class FrictionLoopProblem:
    kind = "friction"
    unit = "N"
    reduced = False
    regime = "loop"

    def __init__(self, data: FrictionData) -> None:
        bind_scans(self, data)
        sc = data.scans
        for s in sc:  # the friction is half the trace-retrace difference: one direction cannot tell it from the zero
            if not ((s.direction > 0).any() and (s.direction < 0).any()):
                raise DataFormatError(f"{data.path}: scan {s.id} runs one way only: a friction loop of interval means "
                                      "needs its trace and its retrace (the friction is half their difference; one "
                                      "direction cannot separate it from the lateral channel's zero)")
        self.sigma_scatter = _scatter(sc)
        self.sigma = data.sigma_force if data.sigma_force > 0 else max(self.sigma_scatter, 1e-15)
        #: an unstated noise is the record's own robust scatter: the chi-square tests include its sampling error
        #: (engine.gof_p)
        self.sigma_from_scatter = not data.noise_stated
        self.force = np.concatenate([s.force for s in sc])
        self.n = len(self.force)
        self.direction = np.concatenate([s.direction for s in sc]).astype(float)
        self.load_of = np.concatenate([np.full(len(s.force), s.load) for s in sc])
        surf = [segment_surface(s) for s in sc]
        self.slopes = np.concatenate([t[0] for t in surf]) if all(t is not None for t in surf) else None
        self.relief, self.relief_range = None, 0.0
        if self.slopes is not None:
            # the phase coordinate of the friction-contrast cause: the relief from its 2nd to its 98th
            # percentile over all lines as 0 .. 1, where that range stands above the surface's noise
            rel = np.concatenate([t[1] for t in surf])
            lo, hi = np.percentile(rel, [2.0, 98.0])
            hnoise = max(t[2] for t in surf)
            if hi - lo > RELIEF_SNR * hnoise and hi > lo:
                # each line levelled on its background, not on all its heights (:func:`background_line`)
                rel = np.concatenate([t[1] - np.polyval(background_line(s.position, t[1]), s.position)
                                      for s, t in zip(sc, surf)])
                lo, hi = np.percentile(rel, [2.0, 98.0])
                self.relief, self.relief_range = (rel - lo) / (hi - lo), float(hi - lo)
        self.slices, self.groups, labels = scan_groups(sc)
        self.group_labels = labels
        self._reversal_geometry()
        # the lateral channel's drift, linear in time on the record's clock (as for stick-slip records,
        # :func:`~probedyn.diagnose.friction.drift_clock`): the drift parameter is its change over the longest scan
        self.drift_clock, t_drift = drift_clock(sc)
        self.t_ref = max(max(float(s.time[-1] - s.time[0]), 1e-12) for s in sc)
        self.drift_x = np.empty(self.n)
        for i, sl in enumerate(self.slices):
            self.drift_x[sl] = t_drift[i] / self.t_ref
        # each line's trace and retrace as recorded, against the stated noise (:mod:`probedyn.diagnose.noise`)
        self.sequences = [np.arange(sl.start, sl.stop) for sl in self.slices]
        self.noise_stated = bool(data.noise_stated)
        self.noise_correlation_declared = data.noise_correlation
        # the image lines are repeats of one measurement: a finding's uncertainty is also their jackknife
        self.replicate_units = self.sequences
        self.replicate_label = f"{len(sc)} image lines"
        # the loop read as recorded: half the trace-retrace difference is the friction, their mean the zero
        fwd = self.direction > 0
        half = 0.5 * (self.force[fwd].mean() - self.force[~fwd].mean()) if fwd.any() and (~fwd).any() else 0.0
        zero = 0.5 * (self.force[fwd].mean() + self.force[~fwd].mean()) if fwd.any() and (~fwd).any() else 0.0
        self.half_loop = float(half)
        a, k = data.lattice, data.k_x
        N = float(self.loads[0]) if np.ptp(self.loads) == 0 else float(np.mean(self.loads))
        #: the reference load: the FFM runs here, Amontons' law carries its friction to each scan's load
        self.N_mean = self.N_ref = N
        # corrugation: from eta = 1 (the PT threshold of stick-slip: no friction below it at low speed; lower where
        # the FFM's damped sliding there exceeds the recorded friction, :meth:`_smooth_sliding_bound`) up;
        # start where the PT's peak force 2 pi U0 / a is the recorded half loop (F_k < F0) and twice that
        u_eta1 = k * a * a / (4 * math.pi**2) / N
        u_half = max(abs(half), 1e-15) * a / (2 * math.pi) / N
        u_lo, u_hi = u_eta1 * 1.0001, max(u_eta1, u_half) * 1e3
        self._fk: dict = {}
        u_lo = self._smooth_sliding_bound(u_lo, abs(half))
        u_st = tuple(x for x in (1.2 * u_half, 2.0 * u_half, 1.5 * u_eta1) if u_lo < x < u_hi)
        self.u_crossings = self._level_crossings(u_lo, min(u_hi, 100.0 * max(u_half, u_eta1)), abs(half))
        u_st += self.u_crossings
        span = max(float(np.ptp(self.force)), 10.0 * self.sigma)
        #: one speed (every scan's): the FFM sets nothing but the friction level, which is then the baseline's
        #: parameter (:meth:`levels`); the corrugations that give it are ``u_crossings``
        self.level_param = bool(np.ptp(self.speeds) == 0 and half > 0)
        if self.level_param:
            top = max(abs(half) + 10.0 * self.sigma, 2.0 * abs(half))
            level = CauseParam("F_ref", "N", 1e-3 * abs(half), 10.0 * top, abs(half),
                               "the FFM's mean friction at the reference load and the scans' speed (its corrugation "
                               "among u_crossings)", scale="log")
        else:
            level = CauseParam("u0", "J/N", u_lo, u_hi, u_st[0] if u_st else 2.0 * u_lo,
                               "corrugation U0 per unit load (sets the FFM's mean friction)", scale="log", starts=u_st[1:])
        self.base_params = [
            level,
            CauseParam("offset", "N", zero - span, zero + span, float(zero), "the lateral channel's zero"),
        ]
        self.train_mask = None
        self.fixed_nuisance = None
        self.nfev_per_param = 40
        self.max_starts = 4
        self.diff_step = 1e-4
        # the FFM's mean friction is not monotone in the corrugation (``u_crossings``: several u0 give the recorded
        # half loop), so a fold fitted from the declared starts alone can end on another crossing (blind f10, the
        # middle load's trace held out: training chi^2 42 709 where the full-data optimum gives 766 on the same
        # samples, held-out chi^2 12 847 against 134); the folds also start from the full-data optimum
        # (engine: cv_warm, cv_warm_all; as for stick-slip records)
        self.cv_warm = True
        self.cv_warm_all = True
        self.causes = []
        self.not_offered = {}
        #: terms every such record implies (the contact's lateral stiffness at the reversals): the baseline takes them
        #: on where the data show them (engine ``_declared_terms``); ``base_terms`` those it took
        self.declared_terms = []
        self.base_terms = ()
        for cls in catalog("friction"):
            if "loop" not in cls.regimes:
                continue
            c = cls().constrain(self)
            if c is not None:
                (self.declared_terms if c.declared else self.causes).append(c)
            elif getattr(cls, "requires", None):
                self.not_offered[cls.key] = f"needs {cls.requires}"

    def supports(self, what: str) -> bool:
        return True

    def _reversal_geometry(self) -> None:
        """Per sample: the support travel since its segment's reversal at the start and at the end of its
        interval (``rev_ua``, ``rev_ub``; the intervals end halfway between samples, the first starts as far
        before its sample as the second edge lies after it). Per segment: its samples, its first sample in the
        direction of motion, and the sample of the segment before it nearest the reversal point."""
        self.rev_ua = np.zeros(self.n)
        self.rev_ub = np.zeros(self.n)
        segs = []
        for i, s in enumerate(self.data.scans):
            base = self.slices[i].start
            cuts = [0, *(np.nonzero(np.diff(s.direction) != 0)[0] + 1).tolist(), len(s.force)]
            runs = [np.arange(base + a, base + b) for a, b in zip(cuts[:-1], cuts[1:]) if b > a]
            for j, idx in enumerate(runs):
                d = float(self.direction[idx[0]])
                o = idx[np.argsort(d * s.position[idx - base], kind="stable")]
                x = d * s.position[o - base]  # increasing along the motion
                if len(x) > 1:
                    mid = 0.5 * (x[1:] + x[:-1])
                    edges = np.concatenate([[x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]])
                else:  # one sample: no interval to place the reversal in (no stick is modelled there)
                    self.rev_ua[o] = self.rev_ub[o] = np.inf
                    segs.append((o, None))
                    continue
                self.rev_ua[o] = edges[:-1] - edges[0]
                self.rev_ub[o] = edges[1:] - edges[0]
                prev = runs[j - 1] if j > 0 else (runs[1] if len(runs) > 1 else None)
                near = None
                if prev is not None:
                    x_rev = d * edges[0]
                    near = int(prev[np.argmin(np.abs(s.position[prev - base] - x_rev))])
                segs.append((o, near))
        self.rev_segments = segs

    def reversal(self, F: np.ndarray, compliance: float = 0.0) -> np.ndarray:
        """The model force ``F`` (signed, without the channel's zero) with each segment's reversal stick
        (:func:`reversal_deficit`): the ramp rises from the force of the segment before at the reversal to this
        segment's force at its first sample, at the lever's stiffness in series with the contact's,
        ``k_x / (1 + compliance)`` (:mod:`.causes.contact_stiffness`)."""
        out = np.array(F, float)
        k = self.data.k_x / (1.0 + compliance)
        for o, near in self.rev_segments:
            if near is None:
                continue
            d = self.direction[o[0]]
            h = d * (F[o[0]] - F[near])
            out[o] -= d * reversal_deficit(h, k, self.rev_ua[o], self.rev_ub[o])
        return out

    def _smooth_sliding_bound(self, u_lo: float, target: float) -> float:
        """The corrugation's lower bound: ``eta = 1`` or below it. Under the stick-slip threshold the FFM's tip
        still slides over the corrugation with a damped modulation of its velocity, and that dissipation is a
        friction falling to zero with the corrugation; at an image line's speed (micrometres per second) and
        the lever's default damping (``Q_x = 1``) it can exceed a small recorded friction at ``eta = 1``
        (a blind generator's loops, session 30: 0.66 nN at ``eta = 1`` against 0.22 nN recorded, k_x 100 N/m,
        3.4 um/s; the baseline stalled at its bound, chi^2 2.9e4 per sample). Halved (at most 40 times) until
        the FFM's friction at the fastest scan is below a tenth of the recorded half loop."""
        if not target > 0:
            return u_lo
        v = float(np.max(self.speeds))
        for _ in range(40):
            try:
                if self.friction_at(u_lo, v, self.N_ref) <= 0.1 * target:
                    break
            except ProbedynError:
                break
            u_lo *= 0.5
        return u_lo

    def _level_crossings(self, u_lo: float, u_hi: float, target: float, n: int = 96, keep: int = 3) -> tuple:
        """Corrugations at which the FFM's friction at the reference load and the median speed reaches the
        recorded half loop on a *rising* stretch. The PT's mean friction is a sawtooth in ``U0``: it drops
        where the slips start to skip one more well (by 10-30 % at eta 14-60), so the recorded level may be
        reached on several stretches and not at all near a start between them, where the fit then stalls at
        a drop's edge (session 25: a loop at two loads left 3 times the noise's chi^2). Tabulated on ``n``
        log-spaced corrugations (memoised for the fit); the first ``keep`` crossings, interpolated."""
        if not (target > 0 and u_hi > u_lo):
            return ()
        v = float(np.median(self.speeds))
        n = max(n, int(42 * math.log10(u_hi / u_lo)) + 1)  # the default's 96 points over 2.3 decades, per decade
        grid = np.geomspace(u_lo, u_hi, n)
        try:
            F = np.array([self.friction_at(u, v, self.N_ref) for u in grid])
        except ProbedynError:
            return ()
        out = []
        for i in range(n - 1):
            if F[i] <= target <= F[i + 1] and F[i + 1] > F[i]:
                w = (target - F[i]) / (F[i + 1] - F[i])
                out.append(float(grid[i] * (grid[i + 1] / grid[i]) ** w))
                if len(out) == keep:
                    break
        return tuple(out)

    def nested_starts(self, ref_values: dict, ref_causes: tuple, new: tuple, mask=None) -> list[dict]:
        """Data-derived starts: each new cause's ``data_starts(problem, ref_values)`` (the slope coupling
        from the regression of the reference fit's residual on ``N t``)."""
        out = clipped_starts(self.base_params, ref_values, new,
                             lambda c: c.data_starts(self, dict(ref_values), tuple(ref_causes))
                             if hasattr(c, "data_starts") else [])
        # the reference's corrugation may sit at a drop of the PT's sawtooth (:meth:`_level_crossings`); each
        # start again from the stretches that reach the recorded level
        if self.level_param:  # the level is a parameter: no sawtooth to start across
            return out
        null = {**ref_values, **{p.name: p.null for c in new for p in c.params}}
        return out + [{**st, "u0": u} for st in (out or [null]) for u in self.u_crossings
                      if abs(u / ref_values["u0"] - 1.0) > 1e-3]

    def residual_start(self, name: str, x: np.ndarray, ref_values: dict, ref_causes: tuple = ()) -> list[dict]:
        """A data start for a cause whose first-order effect is ``value * x``: the least-squares regression of
        the reference fit's residual on ``x`` (none where ``x`` vanishes)."""
        r = self.force - self.predict(ref_values, ref_causes)
        den = float(np.sum(x * x))
        return [{name: float(np.sum(r * x) / den)}] if den > 0 else []

    # -- model --------------------------------------------------------------------------------
    def state(self, values, causes=()) -> LoopState:
        st = LoopState(u0=float(values.get("u0", math.nan)), offset=values["offset"],
                       level=values.get("F_ref") if self.level_param else None)
        for c in (*self.base_terms, *causes):
            c.effect(values, st)
        return st

    def friction(self, u0: float, n_adh: float = 0.0, level: float | None = None) -> np.ndarray:
        """The friction ``F_k`` at every sample: the FFM's steady friction at its scan's speed and the
        reference load (memoised; ``level``: that friction itself, one speed), times ``(N + n_adh) / (N_ref + n_adh)``
        for the scan's load ``N``."""
        out = np.empty(self.n)
        for i, s in enumerate(self.data.scans):
            out[self.slices[i]] = self.friction_at(u0, s.speed, s.load, n_adh, level)
        return out

    def friction_of(self, values: dict) -> np.ndarray:
        """:meth:`friction` at the baseline parameters ``values``."""
        return self.friction(float(values.get("u0", math.nan)), 0.0, values.get("F_ref") if self.level_param else None)

    def friction_at(self, u0: float, v: float, N: float, n_adh: float = 0.0, level: float | None = None) -> float:
        """Mean friction at speed ``v`` and load ``N`` (Amontons-Derjaguin from the FFM at ``N_ref``; ``level``: the
        FFM's friction at ``N_ref``, given, for a record at one speed)."""
        if level is not None:
            return float(level) * (N + n_adh) / (self.N_ref + n_adh)
        key = (float(u0), float(v))
        if key not in self._fk:
            if len(self._fk) > 20000:
                self._fk.clear()
            self._fk[key] = steady_friction(self.data, u0, self.data.lattice, v, self.N_ref)
        return self._fk[key] * (N + n_adh) / (self.N_ref + n_adh)

    def predict(self, values, causes=()) -> np.ndarray:
        st = self.state(values, causes)
        Fk = self.friction(st.u0, st.n_adh, st.level)
        if st.contrast != 0.0 and self.relief is not None:
            Fk = Fk * (1.0 + st.contrast * self.relief)
        if st.slope_c != 0.0 and self.slopes is not None:
            F = slope_force(Fk, self.load_of, self.direction, self.slopes, st.slope_c, st.n_adh)
        else:
            F = self.direction * Fk
        F = self.reversal(F, st.stick_compliance) + st.offset
        if st.drift != 0.0:
            F = F + st.drift * self.drift_x
        for tf in st.transforms:
            F = tf(self, F)
        return F

    def residuals(self, values, causes=()) -> np.ndarray:
        try:
            m = self.predict(values, causes)
        except (ProbedynError, FloatingPointError, ValueError):
            return np.full(self.n, 1e6)
        return (self.force - m) / self.sigma

    def physical_rms(self, r) -> float:
        return float(np.sqrt(np.mean(np.asarray(r) ** 2)) * self.sigma)

    # -- structure ----------------------------------------------------------------------------
    def structure(self, r: np.ndarray) -> dict[str, Any]:
        """Per scan: the residual's mean, RMS and lag-1 autocorrelation, the half loop (friction) and,
        with heights, the correlation of the loop's mean ``(trace + retrace) / 2`` residual with the slope."""
        r = np.asarray(r)
        out: dict[str, Any] = {"scans": []}
        for i, s in enumerate(self.data.scans):
            rr = r[self.slices[i]]
            rc = rr - rr.mean()
            den = float(np.sum(rc**2)) or 1.0
            row = {"scan": s.id, "speed": s.speed, "load": s.load, "mean_residual_sigma": float(rr.mean()),
                   "rms_sigma": float(np.sqrt(np.mean(rr**2))), "lag1_autocorr": float(np.sum(rc[:-1] * rc[1:]) / den)}
            fwd = s.direction > 0
            if fwd.any() and (~fwd).any():
                row["friction_half_loop_N"] = float(0.5 * (s.force[fwd].mean() - s.force[~fwd].mean()))
            if self.slopes is not None:
                t = self.slopes[self.slices[i]]
                if np.ptp(t) > 0 and np.ptp(rr) > 0:
                    row["residual_slope_correlation"] = float(np.corrcoef(rr, t)[0, 1])
            out["scans"].append(row)
        return out

    def predict_observables(self, values, causes) -> list[dict[str, Any]]:
        """Measurements the fitted model predicts: the loop's slope response ``dF/dt`` (the mean of trace
        and retrace per unit slope: ``c N``, the calibration check) and the mean friction (half loop) at
        twice and at half the highest load -- the half loop's growth with the load is ``g mu``, its
        intercept ``g mu A`` (the adhesion the slope coupling does not see, :mod:`.causes.surface_slope`)."""
        st = self.state(values, causes)
        s = self.data.scans[int(np.argmax(self.loads))]
        out = []
        for label, fl in (("at twice the highest load", 2.0), ("at half the highest load", 0.5)):
            N = s.load * fl
            try:
                Fk = self.friction_at(st.u0, s.speed, N, st.n_adh, st.level)
            except ProbedynError:
                continue
            dt = 1e-3
            A = st.n_adh
            resp = 0.5 * (slope_force(Fk, N, 1.0, dt, st.slope_c, A) + slope_force(Fk, N, -1.0, dt, st.slope_c, A)
                          - slope_force(Fk, N, 1.0, 0.0, st.slope_c, A) - slope_force(Fk, N, -1.0, 0.0, st.slope_c, A)) / dt
            out.append({"measure": f"loop mean per unit surface slope {label}", "value": float(resp),
                        "sigma": self.sigma / max(float(np.std(self.slopes)) if self.slopes is not None else 0.0, 1e-3)
                        / math.sqrt(self.n), "unit": "N"})
            out.append({"measure": f"mean friction (half loop) {label}", "value": float(Fk),
                        "sigma": self.sigma / math.sqrt(self.n), "unit": "N"})
        return out

    def describe(self) -> dict[str, Any]:
        d = self.data
        step = float(np.median([np.median(np.abs(np.diff(s.position))) for s in d.scans]))
        return {"kind": "friction", "regime": "loop", "scans": len(d.scans), "samples": self.n,
                "speeds_m_s": sorted(set(self.speeds.tolist())), "loads_N": sorted(set(self.loads.tolist())),
                "k_x_N_per_m": d.k_x, "sigma_force_N": self.sigma, "noise_stated": d.noise_stated,
                "sigma_scatter_N": self.sigma_scatter, "sampling": d.sampling, "sample_step_m": step,
                "lattice_periods_per_sample": step / d.lattice, "height_column": self.slopes is not None,
                "relief_range_m": self.relief_range,
                "friction_half_loop_N": self.half_loop, "medium": d.medium_name or "not declared",
                "causes_not_offered": dict(self.not_offered)}

    def model_description(self) -> dict[str, Any]:
        cp = _ffm(self.data, 1e-21, self.data.lattice, 0.0).cantilever
        return {"baseline": "friction loop of interval means: the FFM line-scan model (schemes/ffm.py, eqs 2.13-2.15, "
                            "registry friction 'pt', U0 = u0 N at the declared lattice) on its steady stick-slip cycle at "
                            "each scan's speed and the reference load N_ref gives the mean friction, carried to each "
                            "scan's load N by Amontons' law, F_k = F_k(N_ref) N / N_ref; sample = d F_k + offset",
                "reference_load_N": self.N_ref,
                "level_parameter": ("F_ref, the FFM's mean friction at the reference load and the record's one speed; "
                                    "the corrugations that give the recorded half loop: u_crossings") if self.level_param
                else None,
                "u_crossings_J_per_N": list(self.u_crossings),
                "lever": {"k_x": cp["k_x"], "m_x": cp["m_x"], "c_x": cp["c_x"]}, "lattice_m": self.data.lattice,
                "sampling": self.data.sampling}
