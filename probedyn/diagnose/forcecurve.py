"""Force-distance curves: approach and retract of a lever against a sample, with snap-in and pull-off.

Model (quasi-static; the lever's inertia neglected, its fluid drag a cause): the lever (stiffness k)
deflects by ``F / k`` under the tip-sample force ``F = P(delta)``, ``delta`` the penetration
(positive: overlap) and ``z`` the piezo position towards the sample with contact point ``z_c``:

    delta = z - z_c - F / k,   i.e.   Z(delta) = delta + P(delta) / k = z - z_c.

Equilibria are the roots of ``Z(delta) = z - z_c``; one is stable where ``dZ/ddelta > 0``, i.e. where
the force gradient does not exceed the lever stiffness, ``P'(delta) > -k``. Where it does, the
stable branch ends (a fold of Z): on the approach the tip **jumps to contact** (snap-in), on the
retract it **pulls off**. The approach follows the first stable root reached from far away (the
running maximum of Z along increasing delta), the retract the first one reached from deep contact
(the running minimum along decreasing delta); the approach uses the contact model's loading
branch, the retract its unloading branch (the hysteresis of JKR-like contacts).

Baseline: a linear lever plus **Hertz** contact ``P = (4/3) E* sqrt(R) delta^1.5`` (the no-adhesion limit
of the contact registry's models), the declared tip radius; calibrated: the contact point, the
force offset and tilt of the baseline (``F_meas = F + b0 + b1 z``: a virtual deflection of the
optical lever), and ``E*`` unless the sample's modulus is declared. Causes: adhesion after the
contact registry (:mod:`probedyn.schemes.contact`: DMT with its van der Waals tail -- the long-range
attraction that snaps the tip in -- JKR, Maugis-Dugdale with lambda fitted), a tip-radius error and a
miscalibrated deflection sensitivity (the recorded force ``g F`` behind a lever deflected by ``F / k``); and
signals the deflection records besides the force (:meth:`ForceCurveProblem._detector_terms`): the lever's
hydrodynamic drag at the piezo velocity and the optical lever's interference, both functions of the
tip-sample separation and bounded by what the non-contact baseline shows (:meth:`_far_baseline`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.errors import DataFormatError, ProbedynError
from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.formats import ForceData, _noise, _num, col_error, read_csv
from probedyn.schemes.contact.cone import ALPHA_MIN

__all__ = ["ForceCurveProblem", "ForceState", "read_force", "lever_curve", "hertz"]


# ------------------------------------------------------------------------------------------
# Reading
# ------------------------------------------------------------------------------------------


def read_force(side: Path, csv: Path, meta: dict, common: dict) -> ForceData:
    d = read_csv(csv, ["z_m"], ["force_N", "deflection_m", "deflection_V", "segment", "time_s"])
    have = [c for c in ("force_N", "deflection_m", "deflection_V") if c in d]
    if len(have) != 1:
        raise DataFormatError(f"{csv}: give exactly one of the columns force_N, deflection_m, deflection_V (found "
                              f"{', '.join(have) or 'none'})")
    k = _num(meta, "lever", "k", side, positive=True, lo=1e-4, hi=1e4, unit="N/m")
    sens = _num(meta, "lever", "sensitivity", side, default=0.0, lo=0.0, hi=1e-5, unit="m/V") or None
    z = d["z_m"]
    if np.max(np.abs(z)) > 1e-2:
        raise col_error(d, "z_m", int(np.argmax(np.abs(z))), "piezo position beyond 1 cm: values are SI metres")
    if have[0] == "force_N":
        F = d["force_N"]
    elif have[0] == "deflection_m":
        F = k * d["deflection_m"]
    else:
        if sens is None:
            raise DataFormatError(f"{side}: deflection_V needs [lever] sensitivity [m/V]")
        F = k * sens * d["deflection_V"]
    if not np.ptp(F) > 0:
        raise DataFormatError(f"{csv}: the data cannot inform the fit: the force is constant"
                              + (" (all zero)" if not np.any(F) else "") + " (no contact in the curve)")
    if np.max(np.abs(F)) > 1e-3:
        raise col_error(d, have[0], int(np.argmax(np.abs(F))), "force beyond 1 mN: check units (SI) and k")
    if "segment" in d:
        seg = d["segment"].astype(int)
        if not set(np.unique(seg)) <= {0, 1}:
            raise col_error(d, "segment", int(np.nonzero((seg != 0) & (seg != 1))[0][0]), "segment must be 0 (approach) or 1 (retract)")
    else:  # approach up to the turning point (largest z), retract after it
        turn = int(np.argmax(z))
        if turn < 10 and 10 <= int(np.argmin(z)) < len(z) - 10:
            raise DataFormatError(f"{csv}: z_m must increase towards the sample: the record turns at its smallest z "
                                  "(a height that decreases towards the sample? negate it)")
        seg = np.zeros(len(z), int)
        seg[turn + 1:] = 1
    for s_ in (0, 1):
        zz = z[seg == s_]
        if len(zz) < 10:
            raise DataFormatError(f"{csv}: the {'approach' if s_ == 0 else 'retract'} has {len(zz)} points (need >= 10)")
    _check_towards_sample(csv, z[seg == 0], F[seg == 0], k)
    R = _num(meta, "tip", "radius", side, default=20e-9, lo=1e-10, hi=1e-3, unit="m")
    Et = _num(meta, "tip", "E", side, default=169e9, lo=1e6, hi=2e12, unit="Pa")
    nut = _num(meta, "tip", "nu", side, default=0.28, lo=-0.99, hi=0.5)
    Es = _num(meta, "sample", "E", side, default=0.0, lo=0.0, hi=2e12, unit="Pa") or None
    nus = _num(meta, "sample", "nu", side, default=0.3, lo=-0.99, hi=0.5)
    sig, stated = _noise(meta, side, "force", 0.0, 1e-15, 1e-4, "N")
    if not stated and "deflection" in meta.get("noise", {}):
        # the deflection noise in the unit of the deflection column (m, or V with the sensitivity)
        if have[0] == "force_N":
            raise DataFormatError(f"{side}: [noise] deflection needs a deflection column (the data give force_N: "
                                  "state [noise] force in N)")
        unit = "V" if have[0] == "deflection_V" else "m"
        sd, stated = _noise(meta, side, "deflection", 0.0, 1e-15, 1e2 if unit == "V" else 1e-6, unit)
        sig = k * sd * (sens if unit == "V" else 1.0)
    if not stated:  # from the point-to-point scatter of the far (non-contact) quarter of the approach
        za = np.argsort(z[seg == 0])[: max(10, (seg == 0).sum() // 4)]
        fa = F[seg == 0][za]
        r = np.diff(fa, 2)
        sig = float(1.4826 * np.median(np.abs(r - np.median(r))) / math.sqrt(6))
    known = set(common.get("known", ()))
    if Es is not None:
        known.add("modulus")
    common = dict(common, known=frozenset(known))
    t = _one_clock(d, seg) if "time_s" in d else None
    return ForceData(**common, z=z, force=F, segment=seg, k=k, sensitivity=sens, tip_radius=R, E_tip=Et, nu_tip=nut,
                     E_sample=Es, nu_sample=nus, sigma_force=sig, noise_stated=stated, time=t)


def _one_clock(d, seg: np.ndarray) -> np.ndarray:
    """The record's times on one clock. Times increase within each segment (a run of rows with one
    ``segment`` value); at a segment boundary the clock may stand (the turnaround sample recorded in both
    segments, as instruments export it) or restart (a clock per segment, e.g. JPK's segment time): a restarted
    segment is taken to follow the previous one without a pause, its first step the median of its own
    (a dwell at the turnaround is not recorded in such an export and is not modelled)."""
    t = np.array(d["time_s"], float)  # finite: the CSV reader refuses NaN and inf
    starts = np.concatenate([[0], np.nonzero(np.diff(seg) != 0)[0] + 1, [len(t)]])
    for a, b in zip(starts[:-1], starts[1:]):
        steps = np.diff(t[a:b])
        if np.any(steps <= 0):
            raise col_error(d, "time_s", a + 1 + int(np.nonzero(steps <= 0)[0][0]),
                            "times must increase within a segment")
        if a > 0 and t[a] < t[a - 1]:  # a clock that restarts with the segment
            t[a:b] += t[a - 1] - t[a] + (float(np.median(steps)) if len(steps) else 0.0)
    return t


def _check_towards_sample(csv: Path, z: np.ndarray, F: np.ndarray, k: float) -> None:
    """One-line error for a piezo axis that points away from the sample. In contact the approach's force
    rises towards the sample with a slope up to ``k`` (``k P' / (k + P')``); out of contact its slope is the
    baseline's tilt, a few per cent of ``k``. Where the steeper end of the approach (a linear fit to each
    seventh by ``z``) is the *smallest* z and its force falls with z at more than ``k / 5``, the column is a
    height (JPK, and most instruments' "height" channels, decrease towards the sample) exported without its
    sign changed -- a fit of it would put the sample on the wrong side. A curve in contact throughout (both
    ends steep) must rise with z at its steeper end too."""
    order = np.argsort(z)
    zs, Fs = z[order], F[order]
    m = max(5, len(z) // 7)
    s_lo = float(np.polyfit(zs[:m], Fs[:m], 1)[0])
    s_hi = float(np.polyfit(zs[-m:], Fs[-m:], 1)[0])
    if abs(s_lo) > abs(s_hi) and s_lo < -0.2 * k:
        raise DataFormatError(f"{csv}: z_m must increase towards the sample: the approach's force rises towards "
                              "smaller z (a height that decreases towards the sample? negate it)")


# ------------------------------------------------------------------------------------------
# Model
# ------------------------------------------------------------------------------------------


def hertz(delta, E_star: float, R: float):
    """Hertz sphere-flat force [N] against penetration (0 out of contact)."""
    d = np.maximum(np.asarray(delta, float), 0.0)
    return 4.0 / 3.0 * E_star * math.sqrt(R) * d**1.5


#: relative uncertainty of an independent tip-radius measurement (SEM or blind tip reconstruction of a
#: 5-50 nm apex: ~1-3 nm, i.e. about a tenth of the radius); used only to name a separating measurement
TIP_IMAGING_REL_SIGMA = 0.1
#: relative uncertainty of a deflection sensitivity (InvOLS) re-measured from the constant-compliance slope on a
#: rigid sample (a few per cent: the slope's fit range and the spot's position on the lever); naming a measurement only
INVOLS_REL_SIGMA = 0.03


@dataclass
class ForceState:
    z_c: float  # contact point [m]
    E_star: float  # reduced modulus [Pa]
    R: float  # tip radius [m]
    b0: float = 0.0
    b1: float = 0.0  # baseline tilt [N/m]
    drift: float = 0.0  # force drift over the recording [N] (linear in time)
    contact: str | None = None  # registry contact model with adhesion (None: Hertz)
    W: float = 0.0  # work of adhesion [J/m^2]
    lam: float | None = None  # Maugis transition parameter (md)
    z0: float | None = None  # range zeta_0 of the DMT van der Waals tail [m] (None: the registry's default)
    alpha: float = 0.0  # cone half-angle [rad] of a conical tip (0: the sphere of radius R)
    z_shift: float = 0.0  # the retract's true piezo position minus the recorded one [m] (hysteresis)
    visco_strength: float = 0.0  # SLS relaxation strength E_0 / E_inf - 1 of the sample (0: elastic; E_star = E_inf)
    visco_tau: float = 1.0  # SLS relaxation time [s]
    drag_b: float = 0.0  # hydrodynamic drag coefficient of the lever at contact [N s/m] (0: none)
    drag_h: float = 1.0  # its effective height [m]: b(s) = drag_b h / (s + h) at tip-sample separation s
    optical: tuple = ()  # interference of the optical lever: (a_cos [N], a_sin [N], period [m]) in the separation
    gain: float = 1.0  # recorded / true deflection (declared / true sensitivity: deflection-sensitivity)
    transforms: list = field(default_factory=list)


_LAW_CACHE: dict = {}


def _interaction(st: ForceState, E_t, nu_t):
    """P(delta) for loading and unloading (callables) of the state's contact law (the registry model
    is kept for repeated evaluations with the same law parameters, e.g. finite-difference steps in
    the contact point or the baseline)."""
    key = (st.contact if st.W > 0 else None, st.W, st.E_star, st.R, st.lam, st.z0, st.alpha, E_t, nu_t)
    hit = _LAW_CACHE.get(key)
    if hit is None:
        hit = _build_interaction(st, E_t, nu_t)
        if len(_LAW_CACHE) > 16:
            _LAW_CACHE.clear()
        _LAW_CACHE[key] = hit
    return hit


def _build_interaction(st: ForceState, E_t, nu_t):
    """(P_loading, P_unloading, registry model or None). The model is evaluated through its
    normalised curve (parametrised by the contact radius) in :func:`registry_polylines`. The blunted
    cone (non-adhesive, monotone) gives both: its force callables and its model."""
    adhesive = st.contact is not None and st.W > 0
    # the null half-angle: the baseline's Hertz sphere (the registry's cone narrower than its smallest half-angle
    # is Sneddon's exact sphere at every depth, Hertz's while delta << R)
    if not adhesive and st.alpha < ALPHA_MIN:
        f = lambda d: hertz(d, st.E_star, st.R)  # noqa: E731
        return f, f, None
    from probedyn.schemes.contact import get_contact_model

    # a sample modulus that gives the state's E* with the tip's elastic constants
    inv = 1.0 / st.E_star - (1 - nu_t**2) / E_t
    if inv <= 0:
        raise ProbedynError("reduced modulus larger than the tip's own")
    E_s = (1 - 0.3**2) / inv
    kw = dict(E_t=E_t, nu_t=nu_t, E_s=E_s, nu_s=0.3, R_t=st.R, R_s=0.0)
    if st.alpha >= ALPHA_MIN:  # the registry's blunted cone (no adhesion: monotone, same loading and unloading)
        if adhesive:
            raise ProbedynError("adhesion with a conical tip is not in the contact registry")
        cone = get_contact_model("cone", **kw, alpha=st.alpha)
        return cone.force, cone.force, cone
    if st.contact == "md":
        lam = st.lam if st.lam is not None else 1.0
        model = get_contact_model("md", **kw, W=st.W, z0=_z0_for_lambda(lam, st.W, st.R, 4.0 / 3.0 * st.E_star))
    elif st.contact == "dmt" and st.z0 is not None:
        model = get_contact_model("dmt", **kw, W=st.W, z0=st.z0)
    else:
        model = get_contact_model(st.contact, **kw, W=st.W)
    return None, None, model


def registry_polylines(model, d_lo: float, d_hi: float, n_contact: int = 1500, n_tail: int = 400):
    """Loading and unloading force-penetration polylines of a registry contact model, built from
    its normalised curve ``(D(A), P(A))`` (:meth:`nd_curve`, contact radius A) and its tail
    (:meth:`nd_tail` of the branch): loading = tail up to the loading edge (:meth:`nd_edge`: the end point D0,
    or where Maugis-Dugdale's free state ends), then the stable branch from there on (the jump into contact of
    JKR-like curves); unloading = the stable branch down to its minimum penetration D_min (at A_*), then the
    tail. Returns ``{branch: (delta, P, A)}`` with A = -1
    on the tail."""
    sc = model.scales
    du, Pu = sc.d_unit, sc.P_unit
    D0, P0 = model.nd_endpoint()
    Dmax = max(d_hi / du, D0 + 1.0)
    _A_star, D_min, Ac, Dc, Pc = _contact_polyline(model, Dmax, n_contact)
    out = {}
    for branch, edge in (("loading", model.nd_edge("loading")), ("unloading", D_min)):
        keep = Dc >= edge
        Ak, Dk, Pk = Ac[keep], Dc[keep], Pc[keep]
        i = int(np.argmax(keep)) if keep.any() else 0
        if branch == "loading" and i > 0 and Dk[0] > edge:
            # the contact part starts on the curve where it crosses the edge (JKR-like laws land there), not at
            # the first radius past it: the crossing between the two radii, by two rounds of 65 (the spacing
            # / 4096; the landing force was off by up to 3.6e-2 of pi W R)
            a_lo, a_hi = Ac[i - 1], Ac[i]
            for _ in range(2):
                a = np.linspace(a_lo, a_hi, 65)
                j = min(max(int(np.searchsorted(model.nd_curve(a)[0] >= edge, True)), 1), 64)
                a_lo, a_hi = a[j - 1], a[j]
            Dx, Px = (v[0] for v in model.nd_curve(np.array([a_hi]))[:2])
            Ak, Dk, Pk = np.r_[a_hi, Ak], np.r_[Dx, Dk], np.r_[Px, Pk]
        # the tail ends exactly at the branch's edge (the fold: where the loading branch jumps into
        # contact), so the jump is placed at the right piezo position and not one tail spacing early
        Dt = np.linspace(min(d_lo / du, edge) - 1.0, edge, n_tail)
        knots = model.nd_tail_knots(branch)
        if knots.size:  # a tail with its own fold or jump (Maugis-Dugdale's non-contact branch): held exactly
            Dt = np.union1d(Dt, knots[(knots > Dt[0]) & (knots < edge)])
        Pt, _ = model.nd_tail(Dt, branch)
        delta = np.concatenate([Dt, Dk]) * du
        P = np.concatenate([Pt, Pk]) * Pu
        A = np.concatenate([np.full(len(Dt), -1.0), Ak])
        out[branch] = (delta, P, A)
    return out


#: normalised contact polylines of the laws whose curve is costly (Maugis-Dugdale: a root per point), by
#: (:meth:`nd_key`, A_hi, n): a fit's finite differences in W, E*, z_c, the offset and the tilt keep lambda
_POLYLINES: dict[tuple, tuple] = {}
_POLYLINES_MAX = 64
_LADDER = 1.5


def _contact_polyline(model, Dmax: float, n_contact: int):
    """``(A_star, D_min, Ac, Dc, Pc)``: the contact curve from its penetration minimum ``D_min`` (at the contact
    radius ``A_star``, the unloading fold) out to a radius whose penetration exceeds ``Dmax`` (the curve tends to
    ``A^2``). A law with an :meth:`nd_key` (its normalised curve depends on that key alone) takes the radius
    from a ladder of factors 1.5 and 1.5x the points (never coarser than the radius it needs) and keeps the
    result: the polylines are a bracket that Newton steps on the exact curve refine
    (:func:`lever_curve_registry`), so the ladder moves no equilibrium (2e-12 of a 0.1 nN noise over 40 laws;
    a jump's alternative value at the fold, read off the polyline, by its resolution: <= 3e-3 of pi W R), and a
    fit's evaluations at one lambda solve the Maugis equation on the grid once (blind soft-lever case c17,
    Maugis-Dugdale alone: 409 -> 315 s CPU, W and lambda within 3e-5 and 1.4e-3)."""
    key = model.nd_key() if hasattr(model, "nd_key") else None
    A_need = max(2.0, math.sqrt(Dmax) * 1.5 + 2.0)
    if key is None:
        A_hi, n_fine, n_c = A_need, 4 * n_contact, n_contact
        while model.nd_curve(np.array([A_hi]))[0][0] < Dmax:
            A_hi *= _LADDER
    else:
        A_hi = 2.0 * _LADDER ** math.ceil(math.log(A_need / 2.0) / math.log(_LADDER) - 1e-9)
        n_fine, n_c = 6 * n_contact, (3 * n_contact) // 2
        while True:
            hit = _POLYLINES.get((key, A_hi, n_contact))
            if hit is None:
                hit = _nd_contact(model, A_hi, n_fine, n_c)
                if len(_POLYLINES) >= _POLYLINES_MAX:
                    _POLYLINES.pop(next(iter(_POLYLINES)))
                _POLYLINES[(key, A_hi, n_contact)] = hit
            if hit[0] >= Dmax:
                return hit[1]
            A_hi *= _LADDER
    return _nd_contact(model, A_hi, n_fine, n_c)[1]


def _nd_contact(model, A_hi: float, n_fine: int, n_c: int):
    """``(D(A_hi), (A_star, D_min, Ac, Dc, Pc))``: the penetration minimum on ``n_fine`` radii up to ``A_hi``,
    then the stable branch from it on ``n_c`` radii (both uniform in sqrt A: dense where the curve turns)."""
    Ag = np.linspace(0.0, 1.0, n_fine) ** 2 * A_hi + 1e-10
    Dg = model.nd_curve(Ag)[0]
    i_star = int(np.argmin(Dg))
    A_star, D_min = float(Ag[i_star]), float(Dg[i_star])
    Ac = np.linspace(0.0, 1.0, n_c) ** 2 * (A_hi - A_star) + A_star
    Dc, Pc, _, _ = model.nd_curve(Ac)
    return float(Dg[-1]), (A_star, D_min, Ac, Dc, Pc)


def _jump_runs(X: np.ndarray) -> list[tuple[int, int]]:
    """The runs ``[s, e)`` of polyline points below the running maximum of ``X``: a followed branch that moves
    towards increasing ``X`` jumps over each (the point before a run is its fold)."""
    env = np.maximum.accumulate(X)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (X < env).astype(np.int8), [0]])))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def _jump_alternatives(Z, P, zq, dzq):
    """The other branch at every sample of a segment with a jump, for motion towards increasing ``Z``
    (the approach; the retract is passed mirrored). ``Z`` = piezo position of the polyline points,
    ``P`` their force; the followed branch is the running maximum of ``Z`` and a jump is a run of
    points below it: the fold at the point before the run (``Z_j``, force ``P_f``), the landing branch
    from the run's lowest ``Z`` to its end.

    A sample recorded at ``z`` stands for the piezo interval ``[z - dz/2, z + dz/2]`` it was taken
    in (the instant of the snapshot within it is not part of the record; the lever also rings after
    a jump, and thermal motion fires a fold early): relative to the sample, the jump's position is
    uncertain by the interval's standard deviation ``dz / sqrt(12)``. The sample shows the pre-jump
    branch with probability ``q = Phi(sqrt(12) (Z_j - z) / dz)`` and the landing branch otherwise
    (beyond its fold the pre-jump branch is represented by its fold force). Returns ``(alt, log_w)``:
    the other branch's force and the log of its probability (``-inf`` in a segment without a jump;
    ``log_w <= ln 1/2``: the followed branch is always the likelier one; nearest jump if several)."""
    from scipy.special import log_ndtr  # (scipy at first use: the CLI's help lists no scipy)

    alt = np.full(len(zq), np.nan)
    log_w = np.full(len(zq), -np.inf)
    best = np.full(len(zq), np.inf)
    for s, e in _jump_runs(Z):
        if s == 0 or e >= len(Z):
            continue
        zj, Pf = Z[s - 1], P[s - 1]
        u = (zj - zq) / dzq  # > 0: the sample precedes the jump
        take = np.abs(u) < best
        best = np.where(take, np.abs(u), best)
        m = s + int(np.argmin(Z[s:e]))
        landing = np.interp(zq, np.maximum.accumulate(Z[m:e + 1]), P[m:e + 1])
        alt = np.where(take, np.where(u >= 0, landing, Pf), alt)
        log_w = np.where(take, log_ndtr(-math.sqrt(12.0) * np.abs(u)), log_w)
    return alt, log_w


def _exact_extrema(model, k: float, delta, P, A, retract: bool, n: int = 65, rounds: int = 2):
    """The branch polyline ``(delta, P, A)`` with its folds on the exact curve: where the followed branch jumps
    (the running maximum of ``Z = delta + P / k`` for the approach, its running minimum for the retract: a point
    below it starts a jump), the polyline point before the jump and the landing run's extreme point are replaced
    by the curve's own extremum of ``Z`` between their neighbours (``rounds`` rounds of ``n`` points, each across
    the two spacings about the previous round's best: the parameter's spacing / 1024 after two rounds of 65),
    on the law's contact curve in the contact radius or on its tail in the penetration (a point whose neighbours
    are on different pieces is the junction, kept). The fold then is the same point for the followed branch (its
    envelope and the Newton brackets) and for the jump's alternatives and weights (:func:`_jump_alternatives`):
    read off the polyline instead (with the loading contact part cut at the first radius past its edge,
    :func:`registry_polylines`), JKR's alternative branch was off by up to 3.6e-2 of pi W R and the log-weights by
    up to 0.57 on the fits' polylines; now 6.6e-5 and 1.2e-6 (against polylines 16x finer)."""
    sc = model.scales
    du, Pu = sc.d_unit, sc.P_unit
    branch = "unloading" if retract else "loading"
    delta, P, A = delta.copy(), P.copy(), A.copy()
    Z = delta + P / k
    sign = -1.0 if retract else 1.0
    X = sign * Z[::-1] if retract else Z  # the followed branch is the running maximum of X
    m_ = len(Z)

    def orig(i):
        return m_ - 1 - i if retract else i

    for s0, e in _jump_runs(X):
        if s0 == 0:
            continue
        lowest = s0 + int(np.argmin(X[s0:e]))
        for i_x, want_max in ((s0 - 1, True), (lowest, False)):
            j = orig(i_x)
            lo, hi = max(j - 1, 0), min(j + 1, m_ - 1)
            if (A[lo] >= 0) != (A[hi] >= 0) or (A[j] >= 0) != (A[lo] >= 0):
                continue  # the junction of the tail and the contact curve: a polyline point of both
            contact = A[j] >= 0
            x_lo, x_hi = (A[lo], A[hi]) if contact else (delta[lo] / du, delta[hi] / du)
            best = None
            for _ in range(rounds):
                x = np.linspace(x_lo, x_hi, n)
                Dn, Pn = (model.nd_curve(x)[:2] if contact else (x, model.nd_tail(x, branch)[0]))
                Zx = sign * (du * Dn + Pu * Pn / k)  # in X's orientation
                i = int(np.argmax(Zx) if want_max else np.argmin(Zx))
                cand = (Zx[i], x[i], du * Dn[i], Pu * Pn[i])
                if best is None or (cand[0] > best[0] if want_max else cand[0] < best[0]):
                    best = cand
                x_lo, x_hi = x[max(i - 1, 0)], x[min(i + 1, n - 1)]
            here = sign * Z[j]
            if (best[0] > here) if want_max else (best[0] < here):
                _, xb, delta[j], P[j] = best
                if contact:
                    A[j] = xb
                Z[j] = delta[j] + P[j] / k
    return delta, P, A


def lever_curve_registry(z_rel, segment, model, k: float, span: float, dz=None):
    """:func:`lever_curve` for a registry contact law: the equilibria are located on the law's
    polylines (contact-radius parametrisation) and refined by Newton steps in A on the exact
    normalised curve (or in the penetration on the tail). With ``dz`` (each sample's piezo interval)
    also returns the other branch and the log of its probability at every sample of a segment with a
    jump (:func:`_jump_alternatives`): ``(F, F_alt, log_w)``.

    Both segments' samples are located on their branch's polyline first and refined together (one Newton
    iteration for all samples in contact, one for all on the tail: the array overhead of a fit's some 10^4
    curves is per iteration, not per point)."""
    zmin, zmax = float(z_rel.min()), float(z_rel.max())
    lines = registry_polylines(model, min(zmin, 0.0) - 0.05 * span, max(zmax, 0.0) + 0.05 * span, n_contact=500,
                               n_tail=300)  # a bracket only: Newton refines on the exact curve
    sc = model.scales
    du, Pu = sc.d_unit, sc.P_unit
    F = np.empty(len(z_rel))
    F_alt = np.full(len(z_rel), np.nan)
    lw_alt = np.full(len(z_rel), -np.inf)
    # per sample: its polyline cell's end points (radius or penetration, and Z - z) and the interpolated force
    where, a_lo, a_hi, g_lo, g_hi, start, Fq, on_contact, unload = ([] for _ in range(9))
    for s_, branch in ((0, "loading"), (1, "unloading")):
        sel = np.flatnonzero(segment == s_)
        if not sel.size:
            continue
        zq = z_rel[sel]
        delta, P, A = _exact_extrema(model, k, *lines[branch], retract=s_ == 1)
        Z = delta + P / k
        n = len(Z)
        if dz is not None:  # the retract mirrored: its followed branch is the running maximum of -Z
            alt, lw = (_jump_alternatives(Z, P, zq, dz[sel]) if s_ == 0 else
                       _jump_alternatives(-Z[::-1], P[::-1], -zq, dz[sel]))
            F_alt[sel], lw_alt[sel] = alt, lw
        if s_ == 0:
            env = np.maximum.accumulate(Z)
            idx = np.searchsorted(env, zq, side="left") - 1
        else:
            env = np.minimum.accumulate(Z[::-1])[::-1]
            idx = np.searchsorted(env, zq, side="right") - 1
        idx = np.clip(idx, 0, n - 2)
        Z0, Z1 = Z[idx], Z[idx + 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.clip(np.where(Z1 != Z0, (zq - Z0) / (Z1 - Z0), 0.0), 0.0, 1.0)
        contact = (A[idx] >= 0) & (A[idx + 1] >= 0)
        var = np.where(contact, A[idx], delta[idx]), np.where(contact, A[idx + 1], delta[idx + 1])
        where.append(sel)
        a_lo.append(var[0])
        a_hi.append(var[1])
        g_lo.append(Z0 - zq)
        g_hi.append(Z1 - zq)
        start.append(var[0] + t * (var[1] - var[0]))
        Fq.append(P[idx] + t * (P[idx + 1] - P[idx]))
        on_contact.append(contact)
        unload.append(np.full(len(sel), s_ == 1))
    if not where:
        return F if dz is None else (F, F, lw_alt)
    where, lo, hi, g_lo, g_hi, a0, Fq, contact, unload = (np.concatenate(v) for v in
                                                           (where, a_lo, a_hi, g_lo, g_hi, start, Fq, on_contact, unload))
    zq = z_rel[where]
    tail = ~contact
    t_lo, t_hi = np.minimum(lo[tail], hi[tail]), np.maximum(lo[tail], hi[tail])
    if contact.any():
        zc = zq[contact]
        a = a0[contact]
        # Newton in A on g(A) = Z(A) - z = du D(A) + Pu P(A) / k - z, kept inside the polyline's bracket
        # where its end points (exact points of the curve) straddle the root: a step that leaves it
        # bisects (a cone close to the sphere: D(A) steep near the cap's edge, where an unguarded step
        # overshot to 30x the force); until the steps are below 1e-13 A
        lo, hi, gl = lo[contact], hi[contact], g_lo[contact]
        bracket = gl * g_hi[contact] <= 0
        for it in range(40):
            D_, P_, dD_, dP_ = model.nd_curve(a)
            g = du * D_ + Pu * P_ / k - zc
            gp = du * dD_ + Pu * dP_ / k
            same = np.sign(g) == np.sign(gl)
            up, down = bracket & same, bracket & ~same
            lo, gl = np.where(up, a, lo), np.where(up, g, gl)
            hi = np.where(down, a, hi)
            rising = gp > 0
            a_new = np.where(rising, a - g / np.where(rising, gp, 1.0), a)
            out = bracket & ~((a_new - lo) * (a_new - hi) <= 0)
            a_new = np.where(out, 0.5 * (lo + hi), a_new)
            step = a_new - a
            done = bool((np.abs(step) <= 1e-13 * np.maximum(np.abs(a), 1.0)).all())
            a = a_new
            if it >= 2 and done:
                break
        # converged: the last evaluation's force carried over the last step (|step| <= 1e-13 A: its
        # second-order term is ~1e-26 of the force), else the curve at the final radius
        Fq[contact] = Pu * (P_ + dP_ * step if done else model.nd_curve(a)[1])
    if tail.any():
        d = a0[tail]
        zt = zq[tail]
        unl = unload[tail]

        def on_tail(x):  # each sample on its own branch's tail
            P_, dP_ = np.empty_like(x), np.empty_like(x)
            for b, m in (("loading", ~unl), ("unloading", unl)):
                if m.any():
                    P_[m], dP_[m] = model.nd_tail(x[m] / du, b)
            return P_, dP_

        # Newton in the penetration; where the sample's polyline cell straddles the root, kept in the cell (a
        # tail with a jump: Maugis-Dugdale's); until the steps are below 1e-10 of the penetration unit
        straddle = g_lo[tail] * g_hi[tail] <= 0
        for _ in range(8):
            Pt, dPt = on_tail(d)
            g = d + Pu * Pt / k - zt
            gp = 1.0 + Pu * dPt / (du * k)
            d_new = np.where(gp > 0, d - g / np.where(gp > 0, gp, 1.0), d)
            d_new = np.where(straddle, np.clip(d_new, t_lo, t_hi), d_new)
            step, d = np.abs(d_new - d).max(), d_new
            if step <= 1e-10 * du:
                break
        Fq[tail] = Pu * on_tail(d)[0]
    F[where] = Fq
    if dz is None:
        return F
    return F, np.where(np.isfinite(lw_alt), F_alt, F), lw_alt


def _z0_for_lambda(lam: float, W: float, R: float, K: float) -> float:
    """The interaction range z0 that gives the transition parameter lam for W (eq 2.24)."""
    from probedyn.schemes.contact.base import MAUGIS_206

    return MAUGIS_206 / lam * (W * W * R / (math.pi * K * K)) ** (1.0 / 3.0)


def lever_curve(z_rel: np.ndarray, segment: np.ndarray, P_load, P_unload, k: float, span: float, n: int = 600,
                refine: int = 8) -> np.ndarray:
    """Equilibrium tip-sample force along the piezo positions ``z_rel = z - z_c`` (approach: segment 0,
    retract: 1) with the jumps where the force gradient exceeds k (module docstring).

    The stable root is located on a penetration grid (``n`` points) by the running maximum
    (approach) or minimum (retract) of ``Z(delta)``, which brackets it between two grid points; the
    root is then refined inside the bracket by ``refine`` Illinois (modified regula falsi) steps,
    to a relative accuracy far below the noise."""
    F = np.empty(len(z_rel))
    zmin, zmax = float(z_rel.min()), float(z_rel.max())
    lo = min(zmin, -1e-10) - 0.02 * span
    hi = max(zmax, 1e-10) + 0.02 * span
    dgrid = np.linspace(lo, hi, n)
    for s_, P in ((0, P_load), (1, P_unload)):
        sel = segment == s_
        if not sel.any():
            continue
        zq = z_rel[sel]
        Z = dgrid + np.asarray(P(dgrid), float) / k
        if s_ == 0:
            env = np.maximum.accumulate(Z)  # approach: the first stable root reached from far away
            idx = np.searchsorted(env, zq, side="left") - 1  # env[idx] < z <= env[idx + 1]
        else:
            env = np.minimum.accumulate(Z[::-1])[::-1]  # retract: the first one reached from deep contact
            idx = np.searchsorted(env, zq, side="right") - 1  # env[idx] <= z < env[idx + 1]
        idx = np.clip(idx, 0, n - 2)
        a, b = dgrid[idx].copy(), dgrid[idx + 1].copy()
        ga, gb = Z[idx] - zq, Z[idx + 1] - zq
        for _ in range(refine):  # Illinois (modified regula falsi) on g(delta) = Z(delta) - z
            with np.errstate(invalid="ignore", divide="ignore"):
                c = b - gb * (b - a) / (gb - ga)
            bad = ~np.isfinite(c) | (c < np.minimum(a, b)) | (c > np.maximum(a, b))
            c = np.where(bad, 0.5 * (a + b), c)
            gc = c + np.asarray(P(c), float) / k - zq
            same = np.sign(gc) == np.sign(gb)
            a, ga = np.where(same, a, b), np.where(same, 0.5 * ga, gb)
            b, gb = c, gc
        d = np.where(np.abs(ga) < np.abs(gb), a, b)
        F[sel] = np.asarray(P(d), float)
    return F


class ForceCurveProblem:
    kind = "force"
    unit = "N"
    reduced = False
    #: the record carries no noise (a benchmark's noise-free twin, whose chi-square is the effect's signal
    #: alone): the escape starts of :meth:`nested_starts` are then offered whenever the reference misfits at
    #: all, not only beyond the noise's own chi-square
    noise_free = False
    #: alternatives (the contact laws) whose in-sample Akaike scores are within the evidence margin of the
    #: leader's are confounded with it whatever their held-out evidence says: next to a jump the held-out
    #: comparison between laws is dominated by the few held-out samples whose prediction falls on one side of it
    #: or the other (AR(1) seeds 2032 and 2048: laws 0.3-0.5 nats apart in sample, 8-12 apart held out)
    insample_confounds_alternatives = True

    def __init__(self, data: ForceData) -> None:
        self.data = data
        self.path = data.path
        from probedyn.diagnose.engine import WORKERS

        self.workers = WORKERS  # the candidates' and the folds' fits through the engine's pool (docs/diagnose.md 9.62)
        self.known = set(data.known) | set(data.free)
        self.declared_medium = data.medium
        self.medium_name = data.medium_name
        d = data
        self.n = len(d.z)
        self.sigma = d.sigma_force if d.sigma_force > 0 else 1e-12
        # cross-validation groups: every fourth point of the approach and of the retract (interleaved:
        # the contact point, the snap-in and the pull-off are each seen by every fold, so a held-out
        # group tests the model's prediction between measured points, not an extrapolation)
        g = np.empty(self.n, int)
        for s_ in (0, 1):
            idx = np.nonzero(d.segment == s_)[0]
            g[idx] = 4 * s_ + (np.arange(len(idx)) % 4)
        self.groups = g
        self.group_labels = [f"{'approach' if i < 4 else 'retract'} points {i % 4 + 1}::4" for i in range(8)]
        # approach and retract in recording order, against the stated noise (:mod:`probedyn.diagnose.noise`)
        seqs = [np.nonzero(d.segment == s_)[0] for s_ in (0, 1)]
        self.sequences = [ix[np.argsort(d.time[ix], kind="stable")] if d.time is not None else ix for ix in seqs]
        self.noise_stated = bool(d.noise_stated)
        # the targeted route (engine step 2b: a cause's likelihood-ratio test at alpha / N alone shows a
        # discrepancy): the contact mechanics are solved on the exact branch, so the likelihood carries no model
        # error to speak of and is complete when the noise is declared. Read from the record, the noise's model
        # is a guess, and its misfit in one direction passes such a test (unstated flicker nulls: 15 of 30 have a
        # cause past it): there the omnibus chi-square test stays the gate (docs/diagnose.md 9.30)
        self.model_error_in_likelihood = self.noise_stated
        # a white floor plus a slow noise is read as such (:func:`.noise.white_plus_ar1`): a force curve's
        # detector (1/f above its floor) and the deflection's slow thermal drift; not on friction loops, whose
        # second effect's misfit (a contrast beside a slope, 7022 and 7064) the mixture took for noise
        self.noise_mixture = True
        # ... and without a stated noise, the approach's and the retract's noise each its own where they differ
        # (:func:`.noise.sequence_scales`: recorded at different rates, as the JPK QI curve's 5 and 50 kHz)
        self.noise_per_sequence = True
        self.noise_correlation_declared = d.noise_correlation
        self.cv_warm = True  # interleaved groups: folds start from the null and the full-data optimum
        # ... of every parameter, not only the cause's own: the snap-in and pull-off make the misfit
        # piecewise (a W warm-started with the fold baseline's contact point, biased by the adhesion,
        # stalled: a JKR truth got 322 nats less held-out evidence than Maugis-Dugdale at the same
        # in-sample chi-square, seed 2009); the fold's optimum is still fitted on its training points
        self.cv_warm_all = True
        # recording time normalised to [-1/2, 1/2] (the row order where no time column is given:
        # uniform sampling), for a drift of the deflection signal in time
        t = d.time if d.time is not None else np.arange(self.n, dtype=float)
        self.tau = (t - 0.5 * (t.min() + t.max())) / max(float(np.ptp(t)), 1e-300)
        self.separation = False  # residuals in the force-separation domain (starting values only)
        # the piezo velocity [m/s] of every sample (towards the sample positive), for the lever's drag:
        # a local quadratic (Savitzky-Golay) derivative of z and t along each segment's record order
        self.velocity = None
        if d.time is not None:
            from scipy.signal import savgol_filter

            v = np.empty(self.n)
            for s_ in (0, 1):
                idx = np.nonzero(d.segment == s_)[0]
                w = min(21, len(idx) - (1 - len(idx) % 2))
                v[idx] = (savgol_filter(d.z[idx], w, 2, deriv=1, mode="interp")
                          / savgol_filter(d.time[idx], w, 2, deriv=1, mode="interp"))
            self.velocity = v
        # each sample's piezo interval (the spacing to its neighbours along its segment): where a
        # predicted jump falls inside it, the sample is a mixture of the two branches
        # (:func:`_jump_alternatives`), so the misfit is continuous in the parameters
        self.dz = np.empty(self.n)
        for s_ in (0, 1):
            idx = np.nonzero(d.segment == s_)[0]
            o = idx[np.argsort(d.z[idx], kind="stable")]
            g_ = np.abs(np.gradient(d.z[o])) if len(o) > 1 else np.zeros(len(o))
            pos = g_[g_ > 0]
            self.dz[o] = np.where(g_ > 0, g_, float(np.median(pos)) if len(pos) else 1e-12)
        # starting values: contact point where the approach force first exceeds 20 noise levels above
        # its far baseline (fitted as a line over the far half)
        app = d.segment == 0
        za, fa = d.z[app], d.force[app]
        o = np.argsort(za)
        za, fa = za[o], fa[o]
        far = slice(0, max(5, len(za) // 3))
        b1, b0 = np.polyfit(za[far], fa[far], 1)
        self.far_line = (float(b0), float(b1))  # baseline of the far third of the approach (no interaction)
        excess = fa - (b0 + b1 * za)
        thr = 20 * self.sigma
        above = np.nonzero(excess > thr)[0]
        zc0 = float(za[above[0]]) if len(above) else float(za[int(0.8 * len(za))])
        self.span = float(np.ptp(d.z))
        self.E_t = d.E_tip
        self.nu_t = d.nu_tip
        Fmax = float(np.max(excess))
        dmax = max(float(za.max()) - zc0 - Fmax / d.k, 1e-10)
        Es_guess = max(Fmax / (4 / 3 * math.sqrt(d.tip_radius) * dmax**1.5), 1e4)
        self.E_star_declared = None
        if d.E_sample is not None:
            self.E_star_declared = 1.0 / ((1 - d.nu_tip**2) / d.E_tip + (1 - d.nu_sample**2) / d.E_sample)
        Fs = max(np.ptp(d.force), 10 * self.sigma)
        # the tilt's bound: the force range over the span, and at least 3x the tilt the far line shows -- a tilt
        # of the opposite sign to the contact force cancels part of the range (stiff levers: a 2 % tilt of
        # k over the span against the contact force), so the range alone can leave the true tilt out of bounds
        B1 = max(Fs / self.span, 3.0 * abs(float(b1)))
        # the offset's bound: a deflection's zero is the instrument's (an offset larger than the whole force
        # range is common: blind case c23, -19 nN on a 15 nN curve), so it is centred on the far line's
        # intercept, widened by the force range and by what a tilt within its bound moves the intercept at z = 0
        B0 = Fs + B1 * float(np.max(np.abs(d.z)))
        self.base_params = [
            CauseParam("z_c", "m", float(d.z.min()), float(d.z.max()), zc0, "contact point (piezo position)"),
            CauseParam("b0", "N", float(b0) - B0, float(b0) + B0, float(b0), "force offset of the baseline"),
            CauseParam("b1", "N/m", -B1, B1, float(b1), "baseline tilt (virtual deflection)"),
        ]
        if self.E_star_declared is None:
            # E* = 1 / ((1 - nu_t^2) / E_t + (1 - nu_s^2) / E_s) < E_t / (1 - nu_t^2), the rigid-sample
            # limit; bounded at a sample of 1 TPa (diamond), the stiffest the contact registry takes
            E_hi = 1.0 / ((1 - d.nu_tip**2) / d.E_tip + (1 - 0.3**2) / 1e12)
            e0 = min(Es_guess, 0.5 * E_hi)
            self.base_params.append(CauseParam("E_star", "Pa", 1e3, E_hi, e0, "reduced modulus E* (below the rigid-"
                                               "sample limit E_tip / (1 - nu_tip^2))", scale="log",
                                               starts=(min(10 * e0, 0.9 * E_hi),)))
        self.far = self._far_baseline(zc0)
        # snap-in and pull-off make the misfit piecewise smooth: capped least-squares runs, few starts
        self.nfev_per_param = 30
        self.max_starts = 3
        self.causes = []
        self.not_offered = {}  # causes the record cannot inform, with the reason (a missing column)
        for cls in catalog("force"):
            c = cls().constrain(self)
            if c is not None:
                self.causes.append(c)
            elif getattr(cls, "requires", None) and not (set(cls.changes) & self.known):
                self.not_offered[cls.key] = f"needs {cls.requires}"

    def _far_baseline(self, zc0: float) -> dict[str, Any]:
        """What the non-contact baseline alone says (the detector causes' bounds are derived from it): the
        points of both segments more than 5 % of the ramp before the contact point's start ``zc0``, the
        approach's snap-in and the retract's pull-off, one line
        in z fitted to them, the RMS of its residuals, and the split of the two segments' mean residuals
        (approach minus retract) with its standard error."""
        d = self.data
        # the retract may adhere beyond the contact point and the approach snap in before it: the far region
        # also ends before the pull-off and the snap-in (each segment's deepest attraction below the line of
        # its own far third, when it exceeds 5 noise levels and three times the RMS that line leaves above
        # the noise -- a wave's trough is not an attraction; a long-range attraction is not a baseline)
        for s_ in (0, 1):
            idx = np.nonzero(d.segment == s_)[0]
            far3 = idx[np.argsort(d.z[idx])[: max(5, len(idx) // 3)]]  # the segment's own far third and line
            line = np.polyfit(d.z[far3], d.force[far3], 1)  # (a drag offsets the retract's line from the approach's)
            r3 = d.force[far3] - np.polyval(line, d.z[far3])
            wave = math.sqrt(max(float(np.mean(r3 * r3)) - self.sigma**2, 0.0))  # what the line leaves (a wave: A/sqrt2)
            exc = d.force[idx] - np.polyval(line, d.z[idx])
            if exc.min() < -5.0 * self.sigma - 3.0 * wave:
                zc0 = min(zc0, float(d.z[idx][int(np.argmin(exc))]))
        far = d.z < zc0 - 0.05 * self.span
        out = {"mask": far, "length": float(zc0 - d.z.min()), "n": int(far.sum()), "rms": None, "split": 0.0,
               "split_se": math.inf}
        na, nr = int((far & (d.segment == 0)).sum()), int((far & (d.segment == 1)).sum())
        if min(na, nr) < 5:
            return out
        r = d.force[far] - np.polyval(np.polyfit(d.z[far], d.force[far], 1), d.z[far])
        seg = d.segment[far]
        out.update(rms=float(np.sqrt(np.mean(r * r))), split=float(r[seg == 0].mean() - r[seg == 1].mean()),
                   split_se=float(self.sigma * math.sqrt(1.0 / na + 1.0 / nr)))
        return out

    def supports(self, what: str) -> bool:
        return True

    def state(self, values, causes=()) -> ForceState:
        st = ForceState(z_c=values["z_c"], E_star=values.get("E_star", self.E_star_declared), R=self.data.tip_radius,
                        b0=values["b0"], b1=values["b1"])
        for c in causes:
            c.effect(values, st)
        return st

    def _z_rel(self, st: ForceState) -> np.ndarray:
        """The piezo positions relative to the contact point, the retract shifted by the piezo hysteresis."""
        d = self.data
        return d.z + st.z_shift * (d.segment == 1) - st.z_c

    def predict(self, values, causes=()) -> np.ndarray:
        return self._predict_branches(values, causes)[0]

    def _predict_branches(self, values, causes=()):
        """The predicted force at every sample, the other branch of a jump and the log of its
        probability (``-inf`` without a jump; :func:`_jump_alternatives`)."""
        d = self.data
        st = self.state(values, causes)
        F, F_alt, w = self._curve(st, self._z_rel(st), d.segment, d.k, self.dz, d.time)
        out = []
        z_rel = self._z_rel(st)
        for Gt in (F, F_alt):  # the true force; recorded: times the sensitivity's gain, plus the detector's terms
            G = st.gain * Gt + st.b0 + st.b1 * d.z + st.drift * self.tau + self._detector_terms(st, Gt, z_rel)
            for tf in st.transforms:
                G = tf(self, G)
            out.append(G)
        return out[0], out[1], w

    def _detector_terms(self, st: ForceState, F: np.ndarray, z_rel: np.ndarray) -> np.ndarray | float:
        """Signals the deflection records besides the tip-sample force ``F``, as functions of the
        tip-sample separation ``s = F / k - z_rel`` (the lever end's height above the undeformed surface;
        ``-delta`` in contact): the **hydrodynamic drag** on the lever moving at the piezo velocity ``v``,
        ``b(s) v`` with ``b(s) = b_drag h / (max(s, 0) + h)`` (Alcaraz et al. 2002; positive: repulsive on the
        approach, attractive on the retract), and the **optical interference** of the light the sample
        reflects into the detector with the lever's, periodic in ``s`` (:mod:`..causes.optical_interference`).
        0 without these causes."""
        if st.drag_b == 0.0 and not st.optical:
            return 0.0
        s = F / self.data.k - z_rel
        out = np.zeros(self.n)
        if st.drag_b != 0.0 and self.velocity is not None:
            out += st.drag_b * st.drag_h / (np.maximum(s, 0.0) + st.drag_h) * self.velocity
        for a_c, a_s, period in st.optical:
            ph = 2.0 * math.pi * s / period
            out += a_c * np.cos(ph) + a_s * np.sin(ph)
        return out

    def _separation_residuals(self, values, causes) -> np.ndarray:
        """Residuals in the force-separation domain: the measured force minus the baseline, against
        the contact law on the segment's branch at the measured penetration
        ``delta = z - z_c - F / k``. No folds (the jumps of the lever are absent in this domain), so
        the misfit is smooth in the contact point and the law's parameters; used only to find
        starting values of nested fits (the noise of F enters delta through F / k)."""
        d = self.data
        st = self.state(values, causes)
        Fx = d.force - st.b0 - st.b1 * d.z - st.drift * self.tau
        Fx = (Fx - self._detector_terms(st, Fx / st.gain, self._z_rel(st))) / st.gain  # the true force
        delta = self._z_rel(st) - Fx / d.k
        Pl, Pu, model = _interaction(st, self.E_t, self.nu_t)
        P = np.empty(self.n)
        dP = np.empty(self.n)
        if model is None or not model.adhesive:
            P[:] = Pl(delta)
            if st.alpha >= ALPHA_MIN:  # the cone's law: its slope by central differences (smooth in delta > 0)
                h = 1e-3 * max(float(np.ptp(delta)), 1e-9)
                dP[:] = (Pl(delta + h) - Pl(delta - h)) / (2 * h)
            else:
                dP[:] = 2.0 * st.E_star * math.sqrt(st.R) * np.sqrt(np.maximum(delta, 0.0))
        else:
            lines = registry_polylines(model, float(delta.min()) - 0.05 * self.span, float(delta.max()) + 0.05 * self.span,
                                       n_contact=600, n_tail=200)
            for s_, branch in ((0, "loading"), (1, "unloading")):
                sel = d.segment == s_
                x, y, _ = lines[branch]
                P[sel] = np.interp(delta[sel], x, y)
                h = 1e-11  # central difference on the polyline (it has a repeated abscissa at a jump)
                dP[sel] = (np.interp(delta[sel] + h, x, y) - np.interp(delta[sel] - h, x, y)) / (2 * h)
        # effective variance: the force noise enters delta through F / k, so the misfit's standard
        # deviation is sigma (1 + P'(delta) / k) on a stable branch (P' > -k)
        r = st.gain * (Fx - P) / (self.sigma * np.maximum(1.0 + dP / d.k, 0.1))
        # robust (soft-l1) misfit: near a fold the noise can move a point's measured penetration
        # across the end of its branch, where the law jumps; such points must not steer the start
        return np.sign(r) * np.sqrt(2.0 * (np.sqrt(1.0 + r * r) - 1.0))

    def nested_starts(self, ref_values: dict, ref_causes: tuple, new: tuple, mask=None) -> list[dict]:
        """Data-derived starting values for fitting ``new`` causes on top of a fit (``ref_values`` of
        the model with ``ref_causes``)
        (called by the engine besides the null start and the declared starts): a fit in the
        force-separation domain (:meth:`_separation_residuals`, smooth where the lever curve
        jumps) from the works of adhesion that give the measured pull-off force under the DMT
        (2 pi W R) and the JKR (3/2 pi W R) limits and Maugis' lambda at 0.3 and 3; and each new cause's own
        ``data_starts`` (the deflection sensitivity from the contact branch's slope), as read and refined in the
        same domain. Only the training points (``mask``) are used."""
        causes = tuple(ref_causes) + tuple(new)
        # a cause's own reading of the record (:meth:`DeflectionSensitivity.data_starts`), offered as read and
        # refined in the force-separation domain
        own = [{**ref_values, **st} for c in new if hasattr(c, "data_starts")
               for st in c.data_starts(self, dict(ref_values), mask)]
        own = own + self._separation_optima(causes, own, mask) if own else []
        laws = [c for c in new if any(p.name == "W" for p in c.params)]
        if not laws:
            return own
        d = self.data
        m = np.ones(self.n, bool) if mask is None else np.asarray(mask, bool)
        r_ref = self.residuals(ref_values, tuple(ref_causes))
        white = getattr(self, "whitener", None)  # the AR(1) noise the fits use (engine._whiten), if any
        r_ref = (white(r_ref, None if mask is None else m) if white is not None else r_ref)[m]
        n_m = int(m.sum())
        floor = 0.0 if self.noise_free else n_m
        if float(np.sum(r_ref**2)) < floor + 3.0 * math.sqrt(2.0 * n_m):
            return own  # the reference already fits within the noise: no minimum to escape from
        ret = m & (d.segment == 1)
        if not ret.any():
            return own
        exc = d.force[ret] - ref_values["b0"] - ref_values["b1"] * d.z[ret]
        F_po = max(-float(np.min(exc)), 3.0 * self.sigma)
        R = d.tip_radius * ref_values.get("r_ratio", 1.0)
        W_hi = min(p.hi for c in laws for p in c.params if p.name == "W")
        starts = []
        # the contact point near the approach's deepest attraction (the snap-in lands in contact),
        # below the far baseline; and the reference fit's own (biased by the adhesion)
        app = m & (d.segment == 0)
        exa = d.force[app] - self.far_line[0] - self.far_line[1] * d.z[app]
        zc_min = float(d.z[app][int(np.argmin(exa))])
        zc_lo, zc_hi = self.base_params[0].lo, self.base_params[0].hi
        far = {**ref_values, "b0": self.far_line[0], "b1": self.far_line[1]}
        bases = [ref_values, {**far, "z_c": min(max(zc_min, zc_lo), zc_hi)}]
        for c_po in (2.0, 1.5):
            W0 = min(F_po / (c_po * math.pi * R), 0.9 * W_hi)
            lams = (0.3, 3.0) if any(p.name == "lam" for c in laws for p in c.params) else (None,)
            for lam in lams:
                for base in bases:
                    st = dict(base, W=W0)
                    if lam is not None:
                        st["lam"] = lam
                    starts.append(st)
        return own + self._separation_optima(causes, starts, mask)

    #: the registration scan's moves of the contact point, in median piezo intervals (:meth:`registration_starts`)
    REGISTRATION_SHIFTS = (-2, -1, 1, 2)

    def registration_starts(self, values: dict, causes: tuple, new: tuple) -> list[dict]:
        """Starts for the engine's registration scan (:meth:`.engine.Fitter.registered`, whitened fits only):
        the optimum with the contact point ``z_c`` moved by 1 and 2 median piezo intervals either way, when a
        new cause is an adhesion law (a predicted snap-in or pull-off). Under AR(1) noise the fit runs on
        innovations (differences of neighbouring samples), which weigh a jump's position relative to the
        samples sharply: the misfit has minima one or two samples apart in ``z_c`` (seed 2001, rho = 0.8: DMT
        632.75 from its best start, 625.37 after the scan's rounds; docs/diagnose.md 9.27-9.28)."""
        if not any(p.name == "W" for c in new for p in c.params):
            return []
        dz = float(np.median(self.dz))
        lo, hi = self.base_params[0].lo, self.base_params[0].hi
        zc = values["z_c"]
        return [dict(values, z_c=zc + s * dz) for s in self.REGISTRATION_SHIFTS if lo <= zc + s * dz <= hi]

    def _separation_optima(self, causes: tuple, starts: list[dict], mask=None) -> list[dict]:
        """The optimum of a fit in the force-separation domain (:meth:`_separation_residuals`) from each start;
        every one is offered (that misfit ranks them only roughly)."""
        from probedyn.diagnose.engine import Fitter  # the engine imports no problem module

        F = Fitter(self)
        out = []
        self.separation = True
        try:
            for st in starts:
                try:
                    out.append(dict(F.fit(causes, [st], mask).values))
                except ProbedynError:
                    continue
        finally:
            self.separation = False
        return out

    def _curve(self, st: ForceState, z_rel, segment, k, dz=None, t=None):
        """The lever's force along ``z_rel``; with ``dz`` (the samples' piezo intervals) the triple
        ``(F, F_alt, log_w)`` of :func:`lever_curve_registry` (laws without jumps: ``log_w`` = -inf).
        A viscoelastic sample (``st.visco_strength > 0``) needs the samples' times ``t`` (increasing:
        the record's order): the Lee-Radok / Ting lever curve of :mod:`probedyn.schemes.contact.viscoelastic`
        (no jumps; without times, e.g. the synthetic curves of :meth:`predict_observables`, the relaxed
        elastic law)."""
        if st.visco_strength > 0 and t is not None:
            from probedyn.schemes.contact.viscoelastic import power_law, sls_lever_curve

            if st.contact is not None and st.W > 0 or st.alpha >= ALPHA_MIN:
                raise ProbedynError("the viscoelastic contact is implemented for a non-adhesive sphere only")
            c, m = power_law("sphere", st.R)
            F = sls_lever_curve(t, z_rel, k, c, m, st.E_star, st.visco_strength, st.visco_tau)
            return F if dz is None else (F, F, np.full(len(F), -np.inf))
        Pl, Pu, model = _interaction(st, self.E_t, self.nu_t)
        if model is None or not model.adhesive:  # Hertz, cone: monotone, no jumps
            # the cone on its exact curve in the contact radius (each force at a given penetration is a
            # root in A: 7x the cost of the polyline bracket refined by Newton, equal to 1e-12 of the force)
            F = (lever_curve(z_rel, segment, Pl, Pu, k, self.span) if model is None
                 else lever_curve_registry(z_rel, segment, model, k, self.span))
            return F if dz is None else (F, F, np.full(len(F), -np.inf))
        return lever_curve_registry(z_rel, segment, model, k, self.span, dz)

    def residuals(self, values, causes=()) -> np.ndarray:
        """Normalised residuals; in a segment with a predicted jump, the signed root of the deviance of
        the two-branch mixture, ``-2 ln((1 - w) e^{-ra^2/2} + w e^{-rb^2/2})`` (>= the smaller of
        ``ra^2``, ``rb^2 - 2 ln w``; :func:`_jump_alternatives`): continuous in the parameters as a jump
        crosses a sample, where the point residual changes by the whole step (a finite-difference Jacobian
        across it stalled the fits). The sign is the likelier branch's (the larger of the two terms), so
        away from the jump, where ``w`` vanishes, the residual is the point residual, sign included. (Until
        session 44 it was the nearer branch's: where the other branch lies within the noise of the followed
        one -- a weak adhesion on a soft lever, over the whole non-contact part -- the signs of the samples
        nearer the other branch flipped at any ``w``; a square is blind to that, but the noise's statistics
        read from the residuals are not: blind null f25 read its white scale 0.90 on a JKR candidate's
        residuals against 0.94 on the point residuals, and its Hertz baseline, the truth, failed, docs 9.30.)"""
        try:
            if self.separation:
                return self._separation_residuals(values, causes)
            m, m_alt, lw = self._predict_branches(values, causes)
        except (ProbedynError, FloatingPointError, ValueError):
            return np.full(self.n, 1e6)
        y = self.data.force
        r = (y - m) / self.sigma
        mix = np.isfinite(lw)
        if mix.any():
            ra, rb, lwm = r[mix], (y[mix] - m_alt[mix]) / self.sigma, lw[mix]
            la, lb = np.log1p(-np.exp(lwm)) - 0.5 * ra * ra, lwm - 0.5 * rb * rb
            dev = -2.0 * np.logaddexp(la, lb)
            sgn = np.where(np.where(la >= lb, ra, rb) >= 0, 1.0, -1.0)
            r[mix] = sgn * np.sqrt(np.maximum(dev, 0.0))
        return r

    def physical_rms(self, r) -> float:
        return float(np.sqrt(np.mean(np.asarray(r) ** 2)) * self.sigma)

    def structure(self, r) -> dict[str, Any]:
        d = self.data
        out = {}
        for s_, name in ((0, "approach"), (1, "retract")):
            sel = d.segment == s_
            rr = np.asarray(r)[sel]
            o = np.argsort(d.z[sel])
            out[name] = {"rms_sigma": float(np.sqrt(np.mean(rr**2))), "mean_sigma": float(rr.mean()),
                         "min_residual_at_z_m": float(d.z[sel][o][int(np.argmin(rr[o]))]),
                         "largest_residual_sigma": float(rr[np.argmax(np.abs(rr))])}
        # adhesion signatures: the largest attraction below the fitted baseline in each segment
        return out

    def predict_observables(self, values, causes) -> list[dict[str, Any]]:
        """Measurements that separate confounded causes: the pull-off force with a lever 10x softer
        and 10x stiffer (adhesion laws), and, where the record has times, the approach force at the
        record's deepest point with the same piezo path run 10x slower and 10x faster. An elastic
        contact (any radius, modulus or tip shape) predicts the same force at every rate; a
        viscoelastic sample relaxes on the slower ramp and stiffens on the faster one (Lee-Radok /
        Ting), so the ramp rate is what separates it from a tip-radius error (Hertz: the force
        depends on E* sqrt(R) only) unless the relaxation is much slower than the ramp (then the
        sample is simply stiffer than declared). Hence also the tip radius imaged independently
        (SEM or a tip characteriser), with an uncertainty of :data:`TIP_IMAGING_REL_SIGMA` of the
        declared radius."""
        d = self.data
        st = self.state(values, causes)
        out = [{"measure": "tip radius imaged independently (SEM / tip characteriser)", "value": float(st.R),
                "sigma": TIP_IMAGING_REL_SIGMA * d.tip_radius, "unit": "m"},
               {"measure": "deflection sensitivity re-measured on a rigid sample (recorded / true deflection)",
                "value": float(st.gain), "sigma": INVOLS_REL_SIGMA, "unit": "1"}]
        for label, kf in (("pull-off force with a lever 10x softer", 0.1), ("pull-off force with a lever 10x stiffer", 10.0)):
            z = np.concatenate([np.linspace(-0.2, 0.2, 400), np.linspace(0.2, -0.2, 400)]) * self.span
            seg = np.concatenate([np.zeros(400, int), np.ones(400, int)])
            F = self._curve(st, z, seg, d.k * kf)
            out.append({"measure": label, "value": float(F[seg == 1].min()), "sigma": self.sigma, "unit": "N"})
        if d.time is not None:
            z_rel = self._z_rel(st)
            app = np.flatnonzero(d.segment == 0)
            deepest = app[np.argmax(z_rel[app])]
            for label, tf in (("approach force at the deepest point, ramp 10x slower", 10.0),
                              ("approach force at the deepest point, ramp 10x faster", 0.1)):
                F = self._curve(st, z_rel, d.segment, d.k, t=(d.time - d.time[0]) * tf)
                out.append({"measure": label, "value": float(F[deepest]), "sigma": self.sigma, "unit": "N"})
        return out

    def describe(self) -> dict[str, Any]:
        d = self.data
        return {"kind": "force", "points": self.n, "approach": int((d.segment == 0).sum()),
                "retract": int((d.segment == 1).sum()), "k_N_per_m": d.k, "tip_radius_m": d.tip_radius,
                "sample_E_declared": d.E_sample, "sigma_force_N": self.sigma, "noise_stated": d.noise_stated,
                "time_column": d.time is not None, "causes_not_offered": dict(self.not_offered)}

    def model_description(self) -> dict[str, Any]:
        return {"baseline": "linear lever + Hertz contact, quasi-static equilibrium with snap-in / pull-off at the "
                            "folds where the force gradient exceeds k; baseline offset and tilt",
                "contact_registry": "probedyn.schemes.contact (dmt, jkr, md) for the adhesion causes; "
                                    "schemes.contact.viscoelastic (Lee-Radok / Ting, SLS) for a viscoelastic sample"}
