"""Maps of the two-mass stick-slip model (source section 4.1.3, Figs 4.9-4.13) on the sweep
engine, and the boundaries and limit cycles read from them. Shared by ``probedyn sweep
basins``, ``probedyn stickslip regime-map|limit-cycles`` and the report.

* :func:`run_basins`: basins of attraction of the sample at v = 0 (Fig 4.9) over a grid of
  initial conditions, NetCDF via :func:`probedyn.schemes.sweep.run_sweep`, resumable;
* :func:`run_regime_map`: regime over (u0, v) (Fig 4.13), with :func:`regime_boundaries` read
  off the grid and :func:`bisected_boundaries` refined by bisection;
* :func:`limit_cycles_result`: limit cycles vs speed with the linear-response amplitude (the
  independent high-speed limit) and the lab speed of each v (Figs 4.10-4.11).

Nothing here plots: the figures are in :mod:`probedyn.report.stickslip`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.schemes.stickslip import (DEFAULT_MODEL, REGIMES, basin_cell, default_basin_window, equilibria,
                                        limit_cycles, linear_response_amplitude, regime_cell, stick_boundary)
from probedyn.schemes.sweep import GridError, axis, run_sweep, validate_grid


def run_basins(u0: float, psi: float, grid: int, out: Path, workers: int = 2, scheduler: str | None = None,
               processes: bool = True, progress: bool = True, restart: bool = False,
               chunk_size: int | None = None, x3_range: tuple[float, float] | None = None,
               x4_range: tuple[float, float] | None = None) -> dict[str, Any]:
    """Basin map at v = 0 on a ``grid`` x ``grid`` grid of initial conditions (x3(0), x4(0))
    (default window :func:`probedyn.schemes.stickslip.default_basin_window`), written to the
    NetCDF file ``out``. Returns the sweep summary, the nodes and saddles, the share of the
    grid per node, the number of cells that did not settle and the Dataset (``dataset``)."""
    if grid < 1:
        raise GridError(f"--grid must be at least 1 point per axis, got {grid}" + (" (zero points)" if grid == 0 else ""))
    eq = equilibria(u0, psi)
    (a3, b3), (a4, b4) = default_basin_window(u0)
    if x3_range:
        a3, b3 = x3_range
    if x4_range:
        a4, b4 = x4_range
    g = {"x4_0": axis("x4_0", a4, b4, grid), "x3_0": axis("x3_0", a3, b3, grid)}
    out = Path(out)
    if out.suffix != ".nc":
        raise ParameterError(f"--out {out} must end in .nc")
    attrs = {"nodes": eq.stable, "saddles": eq.unstable, "u0": float(u0), "psi": float(psi),
             "description": "basins of attraction of the sample, v = 0 (source Fig 4.9); label = index of the node in increasing X"}
    res = run_sweep(basin_cell, g, fixed={"u0": float(u0), "psi": float(psi)}, out=out, workers=workers,
                    scheduler=scheduler, processes=processes, progress=progress, restart=restart,
                    chunk_size=chunk_size, attrs=attrs)
    ds = res.dataset
    ds.attrs["nodes"] = eq.stable
    ds.attrs["saddles"] = eq.unstable
    lab = ds["label"].values
    counts = np.bincount(lab[lab >= 0].ravel(), minlength=eq.n_stable)
    return {**res.to_dict(), "u0": u0, "psi": psi, "grid": grid, "nodes": eq.stable,
            "basin_fraction": counts / lab.size, "unsettled_cells": int((lab < 0).sum()), "dataset": ds}


def json_regimes() -> str:
    """The regime codes as a JSON string (a NetCDF attribute)."""
    return json.dumps({str(k): v for k, v in REGIMES.items()})


def run_regime_map(v_values, u0_values, out: Path | None, workers: int = 2, scheduler: str | None = None,
                   processes: bool = True, progress: bool = True, restart: bool = False, n_ic: int = 6) -> dict[str, Any]:
    """Regime over the grid (u0, v) (Fig 4.13) on the sweep engine (NetCDF ``out`` if given):
    the share of cells per regime, the boundaries on the grid and refined by bisection, and
    the Dataset (``dataset``)."""
    if isinstance(n_ic, bool) or int(n_ic) != n_ic or not 1 <= n_ic <= 1000:  # before a cluster is started
        raise ParameterError(f"n_ic (initial conditions per cell) must be an integer from 1 to 1000, got {n_ic!r}")
    g = validate_grid({"u0": np.asarray(u0_values, float), "v": np.asarray(v_values, float)})
    if np.any(g["v"] <= 0):
        raise GridError("grid axis 'v' must be positive (v = 0 is the quasi-static problem: use basins/equilibria)")
    if np.any(g["u0"] < 0):
        raise GridError("grid axis 'u0' must be >= 0")
    res = run_sweep(regime_cell, g, fixed={"n_ic": int(n_ic)}, out=out, workers=workers, scheduler=scheduler,
                    processes=processes, progress=progress, restart=restart, attrs={"regimes": json_regimes()})
    ds = res.dataset
    reg = ds["regime"].values
    return {**res.to_dict(), "fractions": {REGIMES[k]: float((reg == k).mean()) for k in REGIMES},
            "grid_boundaries": regime_boundaries(ds), **bisected_boundaries(g["v"], g["u0"]), "dataset": ds}


def bisected_boundaries(v_values, u0_values, n_u: int = 6) -> dict[str, Any]:
    """Stick-slip boundary refined by bisection: the speed v*(u0) above which stick ends, for
    a few u0 > 1.2 of the map, and the amplitude u0* above which stick-slip starts at the
    lowest speed of the map (-> 1, the fold criterion, as v -> 0)."""
    vmin, vmax = float(np.min(v_values)), float(np.max(v_values))
    rows = []
    us = [u for u in np.linspace(max(1.2, float(np.min(u0_values))), float(np.max(u0_values)), n_u) if u >= 1.2]
    for u in us:
        try:
            vs = stick_boundary(float(u), vmin, vmax, along="v", rtol=1e-2)
        except SolverError:
            continue
        rows.append({"u0": float(u), "v_star": vs, "V_star_m_s": DEFAULT_MODEL.speed_from_v(vs),
                     "v_star_over_well_frequency": vs / math.sqrt(u / DEFAULT_MODEL.mu2)})
    try:
        u_star = stick_boundary(vmin, 0.3, 2.0, along="u0", rtol=1e-3)
    except SolverError:
        u_star = None
    return {"v_star": rows, "u0_star_at_vmin": u_star, "vmin": vmin}


def regime_boundaries(ds) -> list[dict[str, Any]]:
    """For each u0 row of a regime map: the lowest speed above which no stick remains (all
    attractors smooth), and the speeds with coexisting attractors."""
    reg = ds["regime"].values
    v = ds["v"].values
    rows = []
    for i, u in enumerate(ds["u0"].values):
        r = reg[i]
        stick = (r == 1) | (r == 2)
        last = np.nonzero(stick)[0]
        v_slide = float(v[last[-1] + 1]) if last.size and last[-1] + 1 < v.size else (float(v[0]) if not last.size else None)
        rows.append({"u0": float(u), "v_no_stick_above": v_slide, "coexisting_v": [float(x) for x in v[r == 2]]})
    return rows


def limit_cycles_result(u0: float, v_values) -> dict[str, Any]:
    """:func:`probedyn.schemes.stickslip.limit_cycles` with the linear forced-response amplitude
    (the high-speed limit), the lab speed V [m/s] of each v and whether the motion sticks (the
    sample's lab speed drops below v/2)."""
    lc = limit_cycles(u0, np.asarray(v_values, float))
    lc["linear_amplitude"] = np.array([linear_response_amplitude(u0, v) for v in lc["v"]])
    lc["speed_m_s"] = np.array([DEFAULT_MODEL.speed_from_v(v) for v in lc["v"]])
    lc["stick"] = lc["w_min"] < 0.5 * lc["v"]
    return lc
