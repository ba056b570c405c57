"""Fitting the friction model's parameters to a measured FFM line scan (issue 4, item 6).

Input: a lateral-force trace as CSV (two columns: base position [m] or time [s], lateral force
[N]) with metadata in ``#`` comment lines ``# key = value``: ``speed`` (scan speed, m/s,
required), ``k_x`` (lateral stiffness, N/m, required), optional ``column = base|time`` (what the
first column is; default ``base``), ``preset`` (cantilever defaults for the other parameters,
default ``mica``), ``model`` (default ``bristle``). A header line of column names is allowed.

Method: the FFM line scan (:func:`probedyn.schemes.ffm.line_scan`) is evaluated at the data
base positions, and the free parameters minimise the sum of squared residuals
(``scipy.optimize.least_squares``, trust-region reflective, parameters scaled by their initial
values, bounded positive). Initial values come from the stick-slip analysis of the data,
through positions rather than levels (noise biases the peak and valley forces): the first slip
at ``F_s / k_x`` and the period ``(F_s - F_c) / k_x`` of the quasi-static sawtooth. Uncertainties: the Gauss–Newton covariance
``s^2 (J^T J)^-1`` with ``s^2 = SSR / (n - p)``; they assume independent Gaussian force
noise. Only parameters that shape a force-vs-base trace are identifiable: with
``sigma0 >> k_x`` the bristle stiffness changes the stick slope by ``k_x / sigma0`` (2e-5 for
mica), so ``sigma0`` is not free by default (its covariance would say so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from scipy.optimize import least_squares

from probedyn.core.errors import DataFormatError, ParameterError, SolverError
from probedyn.core.io import MAX_DATA_BYTES, read_text, write_text
from probedyn.schemes.ffm import FFM, line_scan
from probedyn.schemes.stickslip_analysis import analyze

REQUIRED_META = ("speed", "k_x")


@dataclass
class Trace:
    base: np.ndarray   # m
    force: np.ndarray  # N
    meta: dict[str, Any]
    path: str = "<memory>"


def read_trace(path: str | Path) -> Trace:
    """Read a trace CSV; malformed content raises DataFormatError naming file, line and column."""
    path = Path(path)
    # a regular file of bounded size (no FIFO, device or endless stream), UTF-8; messages name
    # positions, never the file's content
    lines = read_text(path, what="trace file", max_bytes=MAX_DATA_BYTES).splitlines()
    meta: dict[str, Any] = {}
    rows: list[tuple[float, float]] = []
    header_seen = False
    for ln, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s.lstrip("#").strip()
            if "=" in body:
                key, val = (p.strip() for p in body.split("=", 1))
                if key in ("speed", "k_x"):
                    try:
                        meta[key] = float(val)
                    except ValueError:
                        raise DataFormatError(f"{path}:{ln}: metadata '{key}' is not a number") from None
                else:
                    meta[key] = val
            continue
        cells = [c.strip() for c in s.split(",")]
        if len(cells) != 2:
            raise DataFormatError(f"{path}:{ln}: expected 2 comma-separated columns, found {len(cells)}")
        vals = []
        for col, c in enumerate(cells, start=1):
            try:
                v = float(c)
            except ValueError:
                if not rows and not header_seen:
                    vals = None
                    break
                raise DataFormatError(f"{path}:{ln}:{col}: cannot read column {col} as a number") from None
            if not math.isfinite(v):
                raise DataFormatError(f"{path}:{ln}:{col}: value is not finite (NaN or infinite)")
            vals.append(v)
        if vals is None:
            header_seen = True
            continue
        rows.append((vals[0], vals[1]))
    for key in REQUIRED_META:
        if key not in meta:
            raise DataFormatError(f"{path}: missing metadata line '# {key} = ...' (required: speed [m/s], k_x [N/m])")
        if not meta[key] > 0:
            raise DataFormatError(f"{path}: metadata '{key}' must be positive, got {meta[key]:g}")
    if len(rows) < 20:
        raise DataFormatError(f"{path}: {len(rows)} data rows; a trace needs at least 20")
    arr = np.array(rows)
    col = meta.get("column", "base")
    if col not in ("base", "time"):
        raise DataFormatError(f"{path}: metadata 'column' must be 'base' or 'time'")
    base = arr[:, 0] * (meta["speed"] if col == "time" else 1.0)
    d = np.diff(base)
    bad = np.nonzero(d <= 0)[0]
    if bad.size:
        # line number of the offending data row
        data_lines = [i for i, r in enumerate(lines, 1) if r.strip() and not r.strip().startswith("#")]
        off = 1 if header_seen else 0
        ln = data_lines[bad[0] + 1 + off]
        raise DataFormatError(f"{path}:{ln}:1: {col} must increase strictly along the file")
    return Trace(base=base, force=arr[:, 1], meta=meta, path=str(path))


def write_trace(path: str | Path, base: np.ndarray, force: np.ndarray, speed: float, k_x: float,
                **meta: Any) -> Path:
    """Write a trace CSV in the format read by :func:`read_trace` (atomically)."""
    head = [f"# speed = {speed!r}", f"# k_x = {k_x!r}"] + [f"# {k} = {v}" for k, v in meta.items()]
    body = "\n".join(f"{b:.9e},{f:.9e}" for b, f in zip(base, force))
    return write_text(Path(path), "\n".join(head + ["base_m,lateral_force_n", body]) + "\n")


def fit_trace(trace: Trace, free: Sequence[str] = ("F_s", "F_c"), preset: str | None = None,
              model: str | None = None, fixed: dict[str, Any] | None = None,
              initial: dict[str, float] | None = None, noise: float | None = None) -> dict[str, Any]:
    """Least-squares fit of the ``free`` friction-model parameters to ``trace``.

    Returns best values, 1-sigma uncertainties, correlation matrix, residual RMS and the
    residual vector, the number of evaluations, and the model trace."""
    preset = preset or trace.meta.get("preset", "mica")
    model = model or trace.meta.get("model", "bristle")
    free = list(free)
    if not free:
        raise ParameterError("fit_trace: no free parameters")
    base0 = float(trace.base[0])
    xb = trace.base - base0  # the scan starts with the tip at rest at the base
    over = dict(fixed or {})
    over.update(k_x=trace.meta["k_x"], V=trace.meta["speed"], length=float(xb[-1]))
    ffm0 = FFM.from_preset(preset, model, over)
    for n in free:
        if n not in ffm0.friction.values:
            raise ParameterError(f"fit_trace: '{n}' is not a parameter of model {ffm0.friction.name!r}")
    if not np.ptp(trace.force) > 0:
        raise SolverError(f"{trace.path}: the trace is flat (every force is equal): the data cannot inform "
                          f"{', '.join(free)}")
    an = analyze(trace.base, trace.force, noise=noise)
    if an["static_friction_n"] is None and {"F_s", "F_c"} & set(free):
        raise SolverError(f"{trace.path}: the trace shows no slip above the noise: the data cannot inform "
                          f"{', '.join(n for n in free if n in ('F_s', 'F_c'))} (a stick-slip trace is needed)")
    p0 = {n: float(ffm0.friction.values[n]) for n in free}
    k = trace.meta["k_x"]
    if an["static_friction_n"] is not None:
        # noise biases peak (valley) forces up (down); positions are robust. Quasi-static
        # sawtooth (sigma0 >> k_x): first slip at F_s / k_x, period (F_s - F_c) / k_x.
        # slips are the large negative jumps of the sampled force (a slip is far shorter than
        # the sampling step; its size F_s - F_c is far above the noise for a usable trace)
        d = np.diff(trace.force)
        drops = np.nonzero(d < 0.5 * d.min())[0]
        Fs0 = float(k * (trace.base[drops[0]] - base0))
        if drops.size >= 2:
            Fc0 = Fs0 - float(k) * float(np.median(np.diff(trace.base[drops])))
        else:
            Fc0 = an["kinetic_friction_n"]
        if not (0 < Fc0 <= Fs0):
            Fs0, Fc0 = an["static_friction_n"], min(an["kinetic_friction_n"], an["static_friction_n"])
        if "F_s" in p0:
            p0["F_s"] = Fs0
        if "F_c" in p0:
            p0["F_c"] = Fc0
    p0.update(initial or {})
    scale = np.array([abs(p0[n]) or 1.0 for n in free])
    nev = [0]

    def model_force(theta):
        vals = {n: float(t * s) for n, t, s in zip(free, theta, scale)}
        if "F_s" in vals and "F_c" in vals and vals["F_c"] > vals["F_s"]:
            vals["F_c"] = vals["F_s"]
        ffm = FFM.from_preset(preset, model, {**over, **vals})
        res = line_scan(ffm)
        nev[0] += 1
        return np.interp(xb, res.base, res.lateral_force)

    # residuals in units of fs (scipy's gtol test is absolute: forces of 1e-9 N would stop it at once)
    fs = float(np.ptp(trace.force)) * 1e-2 or 1.0

    def resid(theta):
        return (model_force(theta) - trace.force) / fs

    sol = least_squares(resid, np.ones(len(free)), bounds=(1e-6, np.inf), x_scale=1.0, diff_step=1e-5,
                        method="trf", xtol=1e-10, ftol=1e-10, max_nfev=100)
    n, p = trace.force.size, len(free)
    r = sol.fun * fs
    ssr = float(r @ r)
    s2 = ssr / max(n - p, 1)
    J = sol.jac * fs / scale[None, :]  # d r / d (physical parameter) = fs (d r~ / d theta) / scale
    try:
        cov = np.linalg.inv(J.T @ J) * s2
        err = np.sqrt(np.diag(cov))
        corr = cov / np.outer(err, err)
    except np.linalg.LinAlgError:
        cov = np.full((p, p), np.nan)
        err = np.full(p, np.nan)
        corr = cov
    best = {nm: float(t * s) for nm, t, s in zip(free, sol.x, scale)}
    uninformed = [nm for nm, e in zip(free, err) if not (math.isfinite(e) and e < abs(best[nm]))]
    if uninformed:
        raise SolverError(f"{trace.path}: the data cannot inform {', '.join(uninformed)} (uncertainty "
                          "not below the value: the trace does not constrain it); fix it or give more data")
    return dict(
        preset=preset, model=model, free=free, values=best,
        uncertainties={nm: float(e) for nm, e in zip(free, err)},
        correlation=corr.tolist(), initial=p0, residual_rms_n=math.sqrt(ssr / n),
        residual_max_n=float(np.max(np.abs(r))), n_points=n, n_evaluations=nev[0],
        success=bool(sol.success), message=str(sol.message),
        residuals=r, model_force=trace.force + r, base=trace.base,
    )
