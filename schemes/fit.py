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


def slip_events(base: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Index ``i`` of the last sample before each slip (the force drops between ``i`` and ``i + 1``).

    A slip is a run of consecutive large negative steps (more than half the largest drop; a
    densely sampled simulated slip spans several samples): one event per run, at its start."""
    d = np.diff(np.asarray(force, float))
    if not d.size or not d.min() < 0:
        return np.zeros(0, int)
    big = np.nonzero(d < 0.5 * d.min())[0]
    if not big.size:
        return big
    start = np.concatenate([[True], np.diff(big) > 1])
    return big[start]


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
    slips = slip_events(trace.base, trace.force)
    if an["static_friction_n"] is not None and slips.size:
        # noise biases peak (valley) forces up (down); positions are robust. Quasi-static
        # sawtooth (sigma0 >> k_x): first slip at F_s / k_x, period (F_s - F_c) / k_x. A slip
        # lies between the last sample before the drop and the first one after: its midpoint.
        xs = 0.5 * (trace.base[slips] + trace.base[slips + 1]) - base0
        Fs0 = float(k * xs[0])
        Fc0 = Fs0 - float(k) * float(np.median(np.diff(xs))) if xs.size >= 2 else an["kinetic_friction_n"]
        if not (0 < Fc0 < Fs0):
            Fs0, Fc0 = an["static_friction_n"], min(an["kinetic_friction_n"], 0.99 * an["static_friction_n"])
        if "F_s" in p0:
            p0["F_s"] = Fs0
        if "F_c" in p0:
            p0["F_c"] = Fc0
    p0.update(initial or {})
    # F_c <= F_s is a constraint of the model, not a clamp: with both free the fit runs on
    # (F_s, D = F_s - F_c), D > 0 (a clamp gives F_c no effect beyond F_s: a flat direction,
    # a singular J^T J and a NaN uncertainty); with F_c free alone its bound is F_s
    both = "F_s" in free and "F_c" in free
    if both and not p0["F_c"] < p0["F_s"]:
        raise ParameterError(f"initial F_c = {p0['F_c']:g} N must be below F_s = {p0['F_s']:g} N")
    inner = ["D" if (both and nm == "F_c") else nm for nm in free]
    q0 = {nm: (p0["F_s"] - p0["F_c"] if nm == "D" else p0[nm]) for nm in inner}
    scale = np.array([abs(q0[nm]) or 1.0 for nm in inner])
    hi = np.full(len(inner), np.inf)
    if "F_c" in inner and "F_s" not in free:
        hi[inner.index("F_c")] = float(ffm0.friction.values["F_s"]) / scale[inner.index("F_c")]
    nev = [0]

    def physical(theta) -> dict[str, float]:
        q = {nm: float(t * s) for nm, t, s in zip(inner, theta, scale)}
        if "D" in q:
            q["F_c"] = q["F_s"] - q.pop("D")
        return q

    def model_force(theta):
        ffm = FFM.from_preset(preset, model, {**over, **physical(theta)})
        res = line_scan(ffm)
        nev[0] += 1
        return np.interp(xb, res.base, res.lateral_force)

    # residuals in units of fs (scipy's gtol test is absolute: forces of 1e-9 N would stop it at once)
    fs = float(np.ptp(trace.force)) * 1e-2 or 1.0

    def resid(theta):
        return (model_force(theta) - trace.force) / fs

    x0 = np.ones(len(inner))
    x0 = np.minimum(x0, np.where(np.isfinite(hi), hi * (1 - 1e-9), np.inf))
    sol = least_squares(resid, x0, bounds=(1e-6, hi), x_scale=1.0, diff_step=1e-5,
                        method="trf", xtol=1e-8, ftol=1e-8, max_nfev=100)
    theta = sol.x.copy()
    fun = sol.fun
    # F_s, at fixed F_s - F_c, moves only the slips (the stick branches are k_x x - (n+1)(F_s - F_c)):
    # the residual changes in steps when a slip crosses a sample, which a finite-difference
    # Jacobian cannot see. Profile it over the first slip's sampling interval instead: the
    # F_s values whose SSR is within s2 of the least (Delta chi^2 = 1) are its 1-sigma set.
    prof = None
    if "F_s" in inner and slips.size:
        i_s = inner.index("F_s")
        lo, hi_ = k * (trace.base[slips[0]] - base0), k * (trace.base[slips[0] + 1] - base0)
        grid = np.linspace(lo, hi_, 17)
        funs = []
        for v in grid:
            th = theta.copy()
            th[i_s] = v / scale[i_s]
            funs.append(resid(th))
        ssrs = np.array([float(f_ @ f_) for f_ in funs])
        s2_ = float(fun @ fun) / max(trace.force.size - len(free), 1)
        best_i = np.nonzero(ssrs <= ssrs.min() * (1 + 1e-12) + 1e-300)[0]
        j = int(best_i[len(best_i) // 2])
        if ssrs[j] <= float(fun @ fun):
            theta[i_s] = grid[j] / scale[i_s]
            fun = funs[j]
        s2_ = min(s2_, float(fun @ fun) / max(trace.force.size - len(free), 1))
        inside = grid[ssrs <= ssrs.min() + s2_]
        step = grid[1] - grid[0]
        prof = float((inside.max() - inside.min() + step) / math.sqrt(12.0))
        others = [i for i in range(len(inner)) if i != i_s]
        if others:  # the smooth parameters again, at the profiled F_s
            def resid_o(t_o):
                th = theta.copy()
                th[others] = t_o
                return resid(th)

            sub = least_squares(resid_o, theta[others], bounds=(1e-6, hi[others]), x_scale=1.0, diff_step=1e-5,
                                method="trf", xtol=1e-8, ftol=1e-8, max_nfev=50)
            if float(sub.fun @ sub.fun) <= float(fun @ fun):
                theta[others] = sub.x
                fun = sub.fun
                sol.jac[:, others] = sub.jac
    n, p = trace.force.size, len(free)
    r = fun * fs
    ssr = float(r @ r)
    s2 = ssr / max(n - p, 1)
    Jq = sol.jac * fs / scale[None, :]  # d r / d (inner physical parameter)
    # back to the user's parameters: F_c = F_s - D
    T = np.eye(p)
    if both:
        i_s, i_c = free.index("F_s"), free.index("F_c")
        T[i_c, i_s] = 1.0   # D = F_s - F_c: dD/dF_s = 1, dD/dF_c = -1
        T[i_c, i_c] = -1.0
    J = Jq @ T
    best = physical(theta)
    best = {nm: best[nm] for nm in free}
    JTJ = J.T @ J
    # a direction the data do not see: J^T J (numerically) singular -> the fit cannot inform it
    svals = np.linalg.svd(J * np.array([abs(best[nm]) or 1.0 for nm in free])[None, :], compute_uv=False)
    if not svals.size or not np.all(np.isfinite(svals)) or svals.min() <= 1e-9 * svals.max():
        blind = [nm for nm, col in zip(free, J.T) if not np.any(col)] or free
        raise SolverError(f"{trace.path}: the data cannot inform {', '.join(blind)} (the model trace does not "
                          "change with it over this scan); fix it or give a trace that does")
    cov = np.linalg.inv(JTJ) * s2
    if prof is not None:
        # F_s from its profile (the Gauss-Newton variance of F_s sees only the smooth part); in the
        # user's parameters F_s and F_c share it (F_c = F_s - D, D from the stick branches)
        i_s = free.index("F_s")
        covq = np.linalg.inv(Jq.T @ Jq) * s2
        covq[i_s, :] = 0.0
        covq[:, i_s] = 0.0
        covq[i_s, i_s] = prof ** 2
        Ti = np.linalg.inv(T)
        cov = Ti @ covq @ Ti.T
    # sampling resolution: a slip happens somewhere between two samples, so the slip positions,
    # hence F_s = k x_1 and F_c = F_s - (F_s - F_c), are known only to k dx / sqrt(12) (uniform
    # over the interval) whatever the noise; it dominates the noiseless case (s2 = integrator floor)
    res_n = None
    if slips.size and {"F_s", "F_c"} & set(free):
        dx = float(np.max(trace.base[slips + 1] - trace.base[slips]))
        res_n = float(k * dx / math.sqrt(12.0))
        for nm in ("F_s", "F_c"):
            if nm in free:
                i = free.index(nm)
                cov[i, i] += res_n ** 2
    err = np.sqrt(np.diag(cov))
    corr = cov / np.outer(err, err)
    uninformed = [nm for nm, e in zip(free, err) if not (math.isfinite(e) and e < abs(best[nm]))]
    if uninformed:
        raise SolverError(f"{trace.path}: the data cannot inform {', '.join(uninformed)} (uncertainty "
                          "not below the value: the trace does not constrain it); fix it or give more data")
    if "F_s" in best and "F_c" in best and not best["F_c"] <= best["F_s"]:  # pragma: no cover - by construction
        raise SolverError(f"{trace.path}: fit ended with F_c > F_s")
    notes = []
    if res_n is not None and math.sqrt(s2) < 0.1 * res_n * math.sqrt(12.0):
        notes.append(f"noiseless trace (residual rms {math.sqrt(ssr / n):.2g} N): the uncertainties of F_s, F_c "
                     f"are the sampling resolution k_x dx / sqrt(12) = {res_n:.2g} N (the slips fall between samples)")
    return dict(
        preset=preset, model=model, free=free, values=best,
        uncertainties={nm: float(e) for nm, e in zip(free, err)},
        correlation=corr.tolist(), initial=p0, residual_rms_n=math.sqrt(ssr / n),
        residual_max_n=float(np.max(np.abs(r))), n_points=n, n_evaluations=nev[0],
        success=bool(sol.success), message=str(sol.message), sampling_resolution_n=res_n, notes=notes,
        residuals=r, model_force=trace.force + r, base=trace.base,
    )
