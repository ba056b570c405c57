"""``probedyn stickslip ...`` and ``probedyn sweep ...``: the two-mass stick-slip model of
section 4.1.3 (eqs 4.2-4.12, Figs 4.8-4.13) and the Dask sweep engine; the report section."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Optional

import typer

from probedyn.commands._apps import stickslip_app, sweep_app
from probedyn.commands._common import JSON_OPT, emit, format_table, markdown_table

WORKERS_OPT = typer.Option(2, "--workers", help="Workers of the local Dask cluster.")
SCHED_OPT = typer.Option(None, "--scheduler", help="Address of an existing Dask scheduler (tcp://HOST:PORT).")
PSI_OPT = typer.Option(5.0, "--psi", help="Phase psi of eq 4.11 (rad).")


def _mpl():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# --------------------------------------------------------------------------------------
# library-level helpers used by commands and the report
# --------------------------------------------------------------------------------------


def equilibria_result(u0: float, psi: float) -> dict[str, Any]:
    from probedyn.schemes.stickslip import equilibria

    return equilibria(u0, psi).to_dict()


def _parse_values(spec: str, name: str):
    """``LO:HI:N[:log]`` or ``V1,V2,...`` -> array (grid errors are GridError)."""
    from probedyn.schemes.sweep import parse_axis

    return parse_axis(f"{name}={spec}")[1]


def plot_basins(ds, path: Path, title: str = "") -> Path:
    """Basin map of a ``sweep basins`` Dataset (Fig 4.9) with the nodes marked."""
    import numpy as np

    from probedyn.core.io import atomic_path

    plt = _mpl()
    lab = ds["label"].values
    x3 = ds["x3_0"].values
    x4 = ds["x4_0"].values
    nodes = np.asarray(ds.attrs.get("nodes", []), dtype=float).ravel()
    n = max(int(lab.max()) + 1, 1)
    fig, ax = plt.subplots(figsize=(6.2, 4.6))
    cmap = plt.get_cmap("tab20", max(n, 2))
    im = ax.pcolormesh(x3, x4, np.ma.masked_less(lab, 0), cmap=cmap, vmin=-0.5, vmax=max(n, 2) - 0.5, shading="nearest")
    if nodes.size:
        ax.plot(nodes, np.zeros_like(nodes), "k*", ms=9, label="nodes (eq 4.11)")
        for i, xn in enumerate(nodes):
            ax.annotate(str(i + 1), (xn, 0), textcoords="offset points", xytext=(4, 6), fontsize=9, weight="bold")
    unstable = np.asarray(ds.attrs.get("saddles", []), dtype=float).ravel()
    if unstable.size:
        ax.plot(unstable, np.zeros_like(unstable), "wx", ms=7, mew=2, label="saddles")
    cb = fig.colorbar(im, ax=ax, ticks=range(n))
    cb.ax.set_yticklabels([str(i + 1) for i in range(n)])
    cb.set_label("node reached")
    ax.set_xlabel("$x_3(0)$ (sample, moving frame)")
    ax.set_ylabel("$x_4(0)$")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    return path


def run_basins(u0: float, psi: float, grid: int, out: Path, workers: int = 2, scheduler: str | None = None,
               processes: bool = True, progress: bool = True, restart: bool = False,
               chunk_size: int | None = None, x3_range: tuple[float, float] | None = None,
               x4_range: tuple[float, float] | None = None) -> dict[str, Any]:
    """``sweep basins``: the basin map on the sweep engine, NetCDF + PNG next to it."""
    import numpy as np

    from probedyn.core.errors import ParameterError
    from probedyn.schemes.stickslip import basin_cell, default_basin_window, equilibria
    from probedyn.schemes.sweep import GridError, axis, run_sweep

    if grid < 1:
        raise GridError(f"--grid must be at least 1 point per axis, got {grid} (zero points)" if grid == 0 else f"--grid must be at least 1 point per axis, got {grid}")
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
    png = plot_basins(ds, out.with_suffix(".png"), f"basins, u0 = {u0:g}, psi = {psi:g} ({grid}x{grid})")
    lab = ds["label"].values
    counts = np.bincount(lab[lab >= 0].ravel(), minlength=eq.n_stable)
    return {
        **res.to_dict(),
        "plot": str(png),
        "u0": u0,
        "psi": psi,
        "grid": grid,
        "nodes": eq.stable,
        "basin_fraction": counts / lab.size,
        "unsettled_cells": int((lab < 0).sum()),
    }


def run_regime_map(v_values, u0_values, out: Path | None, workers: int = 2, scheduler: str | None = None,
                   processes: bool = True, progress: bool = True, restart: bool = False, n_ic: int = 6) -> dict[str, Any]:
    """Regime map (Fig 4.13) over (u0, v) on the sweep engine; NetCDF + PNG."""
    import numpy as np

    from probedyn.schemes.stickslip import REGIMES, regime_cell
    from probedyn.schemes.sweep import run_sweep, validate_grid

    g = validate_grid({"u0": np.asarray(u0_values, float), "v": np.asarray(v_values, float)})
    if np.any(g["v"] <= 0):
        from probedyn.schemes.sweep import GridError

        raise GridError("grid axis 'v' must be positive (v = 0 is the quasi-static problem: use basins/equilibria)")
    if np.any(g["u0"] < 0):
        from probedyn.schemes.sweep import GridError

        raise GridError("grid axis 'u0' must be >= 0")
    res = run_sweep(regime_cell, g, fixed={"n_ic": int(n_ic)}, out=out, workers=workers, scheduler=scheduler,
                    processes=processes, progress=progress, restart=restart,
                    attrs={"regimes": json_regimes()})
    ds = res.dataset
    bis = bisected_boundaries(g["v"], g["u0"])
    png = None
    if out is not None:
        png = plot_regime_map(ds, Path(out).with_suffix(".png"), bis)
    reg = ds["regime"].values
    return {**res.to_dict(), "plot": str(png) if png else None,
            "fractions": {REGIMES[k]: float((reg == k).mean()) for k in REGIMES},
            "grid_boundaries": regime_boundaries(ds), **bis}


def bisected_boundaries(v_values, u0_values, n_u: int = 6) -> dict[str, Any]:
    """Stick-slip boundary refined by bisection: the speed v*(u0) above which stick ends, for
    a few u0 > 1.2 of the map, and the amplitude u0* above which stick-slip starts at the
    lowest speed of the map (-> 1, the fold criterion, as v -> 0)."""
    import numpy as np

    from probedyn.core.errors import SolverError
    from probedyn.schemes.stickslip import DEFAULT_MODEL, stick_boundary

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


def json_regimes() -> str:
    import json

    from probedyn.schemes.stickslip import REGIMES

    return json.dumps({str(k): v for k, v in REGIMES.items()})


def regime_boundaries(ds) -> list[dict[str, Any]]:
    """For each u0 row: the lowest speed above which no stick remains (all attractors
    smooth), and the speed ranges with coexisting attractors."""
    import numpy as np

    reg = ds["regime"].values
    v = ds["v"].values
    rows = []
    for i, u in enumerate(ds["u0"].values):
        r = reg[i]
        stick = (r == 1) | (r == 2)
        last = np.nonzero(stick)[0]
        v_slide = float(v[last[-1] + 1]) if last.size and last[-1] + 1 < v.size else (float(v[0]) if not last.size else None)
        rows.append({"u0": float(u), "v_no_stick_above": v_slide,
                     "coexisting_v": [float(x) for x in v[r == 2]]})
    return rows


def plot_regime_map(ds, path: Path, bis: dict[str, Any] | None = None) -> Path:
    import numpy as np
    from matplotlib.colors import ListedColormap

    from probedyn.core.io import atomic_path
    from probedyn.schemes.stickslip import REGIMES

    plt = _mpl()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    cmap = ListedColormap(["#9ecae1", "#fd8d3c", "#d62728", "#74c476", "#6a51a3"])
    ax.pcolormesh(ds["v"].values, ds["u0"].values, ds["regime"].values, cmap=cmap, vmin=-0.5, vmax=4.5, shading="nearest")
    ax.set_xscale("log")
    ax.set_xlabel("non-dimensional speed v (eq 4.6)")
    ax.set_ylabel("$u_0$")
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    if "period" in ds:
        per = ds["period"].values.astype(float)
        cs = ax.contour(ds["v"].values, ds["u0"].values, per, levels=[1.5, 2.5, 3.5, 4.5], colors="k", linewidths=0.6)
        ax.clabel(cs, fmt=lambda x: f"period {x - 0.5:.0f}|{x + 0.5:.0f}", fontsize=6)
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(k)) for k in REGIMES]
    labels = list(REGIMES.values())
    if bis and bis.get("v_star"):
        h, = ax.plot([r["v_star"] for r in bis["v_star"]], [r["u0"] for r in bis["v_star"]], "k^-", ms=5, lw=1)
        handles.append(h)
        labels.append("end of stick (bisection)")
    ax.legend(handles, labels, loc="upper left", fontsize=7, framealpha=0.9)
    ax.set_title("regime map (Fig 4.13); dashed: quasi-static fold u0 = 1")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return Path(path)


def plot_limit_cycles(lc: dict[str, Any], u0: float, path: Path) -> Path:
    import numpy as np

    from probedyn.core.io import atomic_path

    plt = _mpl()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    cm = plt.get_cmap("viridis")
    for j, (v, orb) in enumerate(zip(lc["v"], lc["orbits"])):
        a1.plot(orb[:, 1], orb[:, 2], color=cm(j / max(1, len(lc["v"]) - 1)), lw=1, label=f"v={v:.3g}")
    a1.set_xlabel("$x_3$")
    a1.set_ylabel("$x_4$")
    a1.set_title(f"limit cycles, u0 = {u0:g} (Fig 4.11)")
    a1.legend(fontsize=7, ncol=2)
    a2.semilogx(lc["v"], lc["amplitude"], "o-", label="amplitude (half x3 range)")
    a2.semilogx(lc["v"], lc["centre"], "s-", label="centre (mean x3)")
    a2.semilogx(lc["v"], lc["linear_amplitude"], "k--", lw=0.8, label="linear response (high-v limit)")
    a2.set_xlabel("v")
    a2.set_ylim(min(-0.2, float(np.nanmin(lc["centre"])) - 0.2), float(np.nanmax(lc["amplitude"])) + 0.5)
    a2.legend(fontsize=8)
    a2.set_title("amplitude and centre vs speed")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return Path(path)


def limit_cycles_result(u0: float, v_values) -> dict[str, Any]:
    import numpy as np

    from probedyn.schemes.stickslip import DEFAULT_MODEL, limit_cycles, linear_response_amplitude

    lc = limit_cycles(u0, np.asarray(v_values, float))
    lc["linear_amplitude"] = np.array([linear_response_amplitude(u0, v) for v in lc["v"]])
    lc["speed_m_s"] = np.array([DEFAULT_MODEL.speed_from_v(v) for v in lc["v"]])
    lc["stick"] = lc["w_min"] < 0.5 * lc["v"]
    return lc


def plot_portraits(u0_list, psi: float, path: Path, v: float = 0.0) -> Path:
    import numpy as np

    from probedyn.core.io import atomic_path
    from probedyn.schemes.stickslip import equilibria, phase_portrait

    plt = _mpl()
    fig, axes = plt.subplots(2, len(u0_list), figsize=(4.2 * len(u0_list), 7))
    axes = np.atleast_2d(axes).reshape(2, len(u0_list))
    psis = np.linspace(-2 * math.pi, 2 * math.pi, 1201)
    for j, u0 in enumerate(u0_list):
        ax = axes[0, j]
        # eq 4.11 solutions over psi (stable solid, unstable dashed)
        for p in psis[::3]:
            e = equilibria(u0, p)
            ax.plot([p] * e.n_stable, e.stable, "b.", ms=1.5)
            ax.plot([p] * e.n_unstable, e.unstable, "r.", ms=0.8)
        ax.set_xlabel(r"$\psi$")
        ax.set_ylabel("X (eq 4.11)")
        ax.set_title(f"u0 = {u0:g}: stable (blue), unstable (red)")
        ax = axes[1, j]
        pp = phase_portrait(u0, psi, v=v, n_ic=18, t_end=40.0)
        for tr in pp["trajectories"]:
            ax.plot(tr[:, 3], tr[:, 4], lw=0.6, color="0.35")
        e = equilibria(u0, psi)
        ax.plot(e.stable, np.zeros(e.n_stable), "bo", ms=5, label=f"{e.n_stable} nodes")
        ax.plot(e.unstable, np.zeros(e.n_unstable), "rx", ms=6, mew=2, label=f"{e.n_unstable} saddles")
        ax.set_xlabel("$x_3$")
        ax.set_ylabel("$x_4$")
        ax.legend(fontsize=8, loc="upper right")
        ax.set_title(f"phase portrait, psi = {psi:g}")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
    return Path(path)


def plot_branches(qs: dict[str, Any], fast: dict[str, Any], path: Path, qs2: dict[str, Any] | None = None) -> Path:
    import numpy as np

    from probedyn.core.io import atomic_path

    plt = _mpl()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    if qs2 is not None:
        for u, xs in zip(qs2["u0"], qs2["x3"]):
            a1.plot([u] * len(xs), xs, ".", color="0.6", ms=2)
    for u, xs in zip(qs["u0"], qs["x3"]):
        a1.plot([u] * len(xs), xs, "k.", ms=2)
    a1.set_title("(a) quasi-static (v = 0): psi = 0 black" + (", psi = 5 grey" if qs2 is not None else ""))
    a1.set_xlabel("$u_0$")
    a1.set_ylabel("$x_3^*$")
    for u, arr in zip(fast["u0"], fast["x3"]):
        for lo, hi, mean in arr:
            a2.plot([u, u], [lo, hi], color="C1", lw=1.2)
            a2.plot(u, mean, "k.", ms=2)
    a2.set_title(f"(b) fast, v = {fast['v']:g}: x3 range of each attractor")
    a2.set_xlabel("$u_0$")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return Path(path)


# --------------------------------------------------------------------------------------
# commands
# --------------------------------------------------------------------------------------


@stickslip_app.command("equilibria")
def cmd_equilibria(
    u0: float = typer.Option(..., "--u0", help="Non-dimensional potential amplitude u0 = 4 pi^2 U0/(k a^2)."),
    psi: float = PSI_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Quasi-static equilibria X = u0 sin(X + psi) (eq 4.11) and their stability (eq 4.12)."""
    res = equilibria_result(u0, psi)

    def human(r: dict[str, Any]) -> str:
        rows = [{"X": float(x), "L": float(l), "kind": "stable (node)"} for x, l in zip(r["stable_X"], r["stable_L"])]
        rows += [{"X": float(x), "L": float(l), "kind": "unstable (saddle)"} for x, l in zip(r["unstable_X"], r["unstable_L"])]
        rows.sort(key=lambda q: q["X"])
        head = f"u0 = {r['u0']:g}, psi = {r['psi']:g}: {r['stable']} stable, {r['unstable']} unstable"
        if r["marginal"]:
            head += f", {r['marginal']} marginal (fold)"
        return head + "\n" + format_table(rows, [("X", "X", ".6f"), ("L", "1-u0 cos(X+psi)", ".4f"), ("kind", "kind", "")])

    emit(res, as_json, human)


@stickslip_app.command("portrait")
def cmd_portrait(
    u0: str = typer.Option("0.5,6,25", "--u0", help="Comma-separated u0 values."),
    psi: float = PSI_OPT,
    v: float = typer.Option(0.0, "--v", help="Non-dimensional speed (0 = quasi-static)."),
    out: Path = typer.Option(Path("stickslip-portraits.png"), "--out", help="PNG file."),
    as_json: bool = JSON_OPT,
) -> None:
    """Solutions of eq 4.11 vs psi and sample phase portraits (Fig 4.8)."""
    vals = [float(x) for x in _parse_values(u0, "u0")]
    png = plot_portraits(vals, psi, out, v=v)
    emit({"plot": str(png), "u0": vals, "psi": psi, "v": v}, as_json, lambda r: f"wrote {r['plot']}")


@stickslip_app.command("limit-cycles")
def cmd_limit_cycles(
    u0: float = typer.Option(3.0, "--u0"),
    v: str = typer.Option("0.02:20:13:log", "--v", help="Speeds: LO:HI:N[:log] or V1,V2,..."),
    out: Optional[Path] = typer.Option(None, "--out", help="PNG file for the cycles and amplitude/centre vs v."),
    as_json: bool = JSON_OPT,
) -> None:
    """Limit cycles as the speed rises: amplitude and centre vs v (Figs 4.10-4.11)."""
    from probedyn.core.errors import ParameterError

    vv = _parse_values(v, "v")
    if (vv <= 0).any():
        raise ParameterError("--v values must be positive")
    lc = limit_cycles_result(u0, vv)
    if out is not None:
        lc["plot"] = str(plot_limit_cycles(lc, u0, out))
    res = {k: val for k, val in lc.items() if k != "orbits"}

    def human(r):
        rows = [dict(v=r["v"][i], V=r["speed_m_s"][i], amp=r["amplitude"][i], c=r["centre"][i],
                     f=r["friction_mean"][i], st="stick-slip" if r["stick"][i] else "smooth") for i in range(len(r["v"]))]
        return format_table(rows, [("v", "v", ".4g"), ("V", "V [m/s]", ".3g"), ("amp", "amplitude", ".4f"),
                                   ("c", "centre", ".4f"), ("f", "mean friction", ".4f"), ("st", "motion", "")])

    emit(res, as_json, human)


@stickslip_app.command("regime-map")
def cmd_regime_map(
    u0: str = typer.Option("0.25:25:24", "--u0", help="u0 axis: LO:HI:N or V1,V2,..."),
    v: str = typer.Option("0.05:10:24:log", "--v", help="v axis: LO:HI:N[:log] or V1,V2,..."),
    out: Path = typer.Option(Path("regime-map.nc"), "--out", help="NetCDF file (a PNG is written next to it)."),
    n_ic: int = typer.Option(6, "--n-ic", help="Initial conditions per cell."),
    workers: int = WORKERS_OPT,
    scheduler: Optional[str] = SCHED_OPT,
    restart: bool = typer.Option(False, "--restart", help="Discard finished chunks of an interrupted run."),
    progress: bool = typer.Option(True, "--progress/--no-progress"),
    processes: bool = typer.Option(False, "--processes/--threads", help="Local workers as processes or threads."),
    as_json: bool = JSON_OPT,
) -> None:
    """Regime map over (v, u0) with numerically found boundaries (Fig 4.13), on Dask."""
    res = run_regime_map(_parse_values(v, "v"), _parse_values(u0, "u0"), out, workers=workers,
                         scheduler=scheduler, progress=progress, restart=restart, n_ic=n_ic, processes=processes)

    def human(r):
        lines = [f"wrote {r['path']} and {r['plot']} ({r['chunks_run']} chunks run, {r['chunks_skipped']} resumed)"]
        lines += [f"  {k}: {100 * f:.1f} % of cells" for k, f in r["fractions"].items()]
        return "\n".join(lines)

    emit(res, as_json, human)


@sweep_app.command("basins")
def cmd_sweep_basins(
    u0: float = typer.Option(8.0, "--u0"),
    psi: float = PSI_OPT,
    grid: int = typer.Option(256, "--grid", help="Points per axis of the initial-condition grid."),
    out: Path = typer.Option(..., "--out", help="NetCDF file (FILE.nc); the plot goes to FILE.png."),
    x3_range: Optional[str] = typer.Option(None, "--x3-range", help="LO:HI of x3(0) (default +-1.5 u0)."),
    x4_range: Optional[str] = typer.Option(None, "--x4-range", help="LO:HI of x4(0) (default +-u0)."),
    workers: int = WORKERS_OPT,
    scheduler: Optional[str] = SCHED_OPT,
    chunk_size: Optional[int] = typer.Option(None, "--chunk-size", help="Cells per task (default: 64 chunks)."),
    restart: bool = typer.Option(False, "--restart", help="Discard finished chunks of an interrupted run."),
    progress: bool = typer.Option(True, "--progress/--no-progress"),
    processes: bool = typer.Option(False, "--processes/--threads", help="Local workers as processes or as threads "
                                   "(default threads: the compiled kernel releases the GIL)."),
    as_json: bool = JSON_OPT,
) -> None:
    """Basins of attraction of the sample for v = 0 (Fig 4.9) on Dask; resumable."""
    from probedyn.schemes.sweep import GridError

    def rng(s: str | None, name: str):
        if s is None:
            return None
        try:
            lo, hi = (float(x) for x in s.split(":"))
        except ValueError:
            raise GridError(f"--{name} expects LO:HI, got {s!r}") from None
        return lo, hi

    res = run_basins(u0, psi, grid, out, workers=workers, scheduler=scheduler, progress=progress, restart=restart,
                     processes=processes,
                     chunk_size=chunk_size, x3_range=rng(x3_range, "x3-range"), x4_range=rng(x4_range, "x4-range"))

    def human(r):
        lines = [f"wrote {r['path']} and {r['plot']} in {r['elapsed_s']:.1f} s "
                 f"({r['chunks_run']} chunks run, {r['chunks_skipped']} resumed)"]
        for i, (x, f) in enumerate(zip(r["nodes"], r["basin_fraction"])):
            lines.append(f"  node {i + 1}: X = {x:8.4f}, basin {100 * f:5.1f} % of the grid")
        if r["unsettled_cells"]:
            lines.append(f"  {r['unsettled_cells']} cells did not settle")
        return "\n".join(lines)

    emit(res, as_json, human)


def _load_target(target: str):
    """``package.module:function`` -> the function (a clear error if it does not exist)."""
    import importlib

    from probedyn.core.errors import ParameterError

    if ":" not in target:
        raise ParameterError(f"sweep target {target!r}: expected MODULE:FUNCTION, e.g. probedyn.schemes.stickslip:regime_cell")
    mod_name, func_name = target.split(":", 1)
    try:
        mod = importlib.import_module(mod_name)
    except ImportError as exc:
        raise ParameterError(f"sweep target {target!r}: cannot import {mod_name} ({exc})") from None
    func = getattr(mod, func_name, None)
    if not callable(func):
        raise ParameterError(f"sweep target {target!r}: {mod_name} has no function {func_name!r}")
    return func


def _parse_fixed(items: list[str] | None) -> dict[str, Any]:
    from probedyn.core.params import parse_sets

    out: dict[str, Any] = {}
    for k, val in parse_sets(items).items():
        try:
            f = float(val)
            out[k] = int(f) if f.is_integer() and "." not in val and "e" not in val.lower() else f
        except ValueError:
            out[k] = val
    return out


@sweep_app.command("run")
def cmd_sweep_run(
    target: str = typer.Argument(..., help="Cell function MODULE:FUNCTION, e.g. probedyn.schemes.stickslip:regime_cell."),
    grid: list[str] = typer.Option(..., "--grid", help="Axis NAME=LO:HI:N[:log] or NAME=V1,V2,... Repeatable."),
    fixed: Optional[list[str]] = typer.Option(None, "--fixed", help="Fixed parameter NAME=VALUE. Repeatable."),
    out: Path = typer.Option(..., "--out", help="NetCDF file (FILE.nc)."),
    scalar: bool = typer.Option(False, "--scalar", help="The function takes scalars (one call per cell)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Sweep seed: the function receives per-cell seeds."),
    chunk_size: Optional[int] = typer.Option(None, "--chunk-size"),
    workers: int = WORKERS_OPT,
    scheduler: Optional[str] = SCHED_OPT,
    processes: bool = typer.Option(True, "--processes/--threads", help="Local workers as processes (default) or threads."),
    restart: bool = typer.Option(False, "--restart", help="Discard finished chunks of an interrupted run."),
    progress: bool = typer.Option(True, "--progress/--no-progress"),
    as_json: bool = JSON_OPT,
) -> None:
    """Any scheme's cell function over any grid, on Dask (docs/sweeps.md); resumable."""
    from probedyn.schemes.sweep import GridError, parse_axis, run_sweep

    func = _load_target(target)
    axes: dict[str, Any] = {}
    for spec in grid:
        name, vals = parse_axis(spec)
        if name in axes:
            raise GridError(f"grid axis '{name}' given twice")
        axes[name] = vals
    res = run_sweep(func, axes, fixed=_parse_fixed(fixed), out=out, vectorized=not scalar, seed=seed,
                    chunk_size=chunk_size, workers=workers, scheduler=scheduler, processes=processes,
                    restart=restart, progress=progress, attrs={"target": target})
    emit(res.to_dict(), as_json, lambda r: f"wrote {r['path']} {r['dims']} in {r['elapsed_s']:.1f} s "
                                          f"({r['chunks_run']} chunks run, {r['chunks_skipped']} resumed)")


# --------------------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------------------


def report_section(outdir: Path, quick: bool) -> str:
    """Figs 4.8-4.13 and the equilibrium table of SOURCE-NOTES item 5."""
    import time

    import numpy as np

    from probedyn.schemes.stickslip import DEFAULT_MODEL, REGIMES, equilibria, steady_branches

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    md: list[str] = []
    m = DEFAULT_MODEL
    md.append(
        f"Two-mass model of Fig 4.7 with Table 4.3 (m1 = {m.m1:g} kg, m2 = {m.m2:g} kg, k1 = {m.k1:g} N/m, "
        f"k2 = {m.k2:g} N/m, zeta1 = {m.zeta1:g}, zeta2 = {m.zeta2:g}); non-dimensional form eq 4.7 "
        f"(time unit sqrt(m/k) = {m.time_scale:.3e} s). Speeds: v = 1 corresponds to V = {m.speed_from_v(1.0) * 1e6:.1f} um/s "
        f"for the potential period a = {m.a * 1e9:.0f} nm implied by the text (docs/stickslip.md)."
    )
    rows = []
    for u0 in (0.5, 6.0, 8.0, 20.0, 25.0):
        e = equilibria(u0, 5.0)
        rows.append({"u0": u0, "s": e.n_stable, "u": e.n_unstable, "X": ", ".join(f"{x:.3f}" for x in e.stable)})
    md += ["", "**Quasi-static equilibria at psi = 5 (eqs 4.11-4.12).** For u0 = 25 the equation gives 8 nodes and "
           "7 saddles, not the 16/15 of the text (SOURCE-NOTES item 5).", "",
           markdown_table(rows, [("u0", "u0", "g"), ("s", "stable", ""), ("u", "unstable", ""), ("X", "stable X", "")])]
    plot_portraits([0.5, 6.0, 25.0], 5.0, outdir / "stickslip_portraits.png")
    md += ["", "![eq 4.11 and phase portraits](stickslip_portraits.png)", ""]

    grid = 96 if quick else 256
    for u0 in (8.0, 20.0):
        t0 = time.perf_counter()
        r = run_basins(u0, 5.0, grid, outdir / f"stickslip_basins_u0_{u0:g}.nc", workers=2, processes=False,
                       progress=False, restart=True)
        dt = time.perf_counter() - t0
        frac = ", ".join(f"{i + 1}: {100 * f:.1f} %" for i, f in enumerate(r["basin_fraction"]))
        md += [f"Basins for u0 = {u0:g}, psi = 5 on a {grid} x {grid} grid ({dt:.1f} s on 2 Dask workers); "
               f"share of the grid per node: {frac}.", "",
               f"![basins u0={u0:g}](stickslip_basins_u0_{u0:g}.png)", ""]

    v = np.geomspace(0.02, 20, 9 if quick else 13)
    lc = limit_cycles_result(3.0, v)
    plot_limit_cycles(lc, 3.0, outdir / "stickslip_limit_cycles.png")
    rows = [dict(v=lc["v"][i], V=lc["speed_m_s"][i] * 1e6, a=lc["amplitude"][i], c=lc["centre"][i],
                 lin=lc["linear_amplitude"][i], st="stick-slip" if lc["stick"][i] else "smooth") for i in range(len(v))]
    md += ["**Limit cycles for u0 = 3 (Figs 4.10-4.11).** The amplitude shrinks and the centre moves to 0 as v "
           "rises; at high v the amplitude approaches the linear forced response (dashed), the independent limit.", "",
           markdown_table(rows, [("v", "v", ".3g"), ("V", "V [um/s]", ".3g"), ("a", "amplitude", ".4f"),
                                 ("c", "centre", ".4f"), ("lin", "linear response", ".4f"), ("st", "motion", "")]),
           "", "![limit cycles](stickslip_limit_cycles.png)", ""]

    u0s = np.linspace(0.25, 12 if quick else 25, 24 if quick else 60)
    qs = steady_branches(u0s, 0.0, n_ic=16 if quick else 32, psi=0.0)
    qs5 = steady_branches(u0s, 0.0, n_ic=16 if quick else 32, psi=5.0)
    fast = steady_branches(u0s, 0.5, n_ic=8 if quick else 12)
    plot_branches(qs, fast, outdir / "stickslip_branches.png", qs5)
    md += ["**Steady-state branches vs u0 (Fig 4.12)**: (a) nodes reached quasi-statically from rest states "
           "spread over |x3(0)| <= u0 + pi, at psi = 0 (black: symmetric, equally spaced by about 2 pi, as in the "
           "text) and psi = 5 (grey); (b) x3 range (bars) and mean (dots) of the attractors at v = 0.5: stick-slip "
           "widens the branches and only negative separations (sample lagging the base) remain.", "",
           "![branches](stickslip_branches.png)", ""]

    vv = np.geomspace(0.05, 10, 12 if quick else 24)
    uu = np.linspace(0.25, 25, 10 if quick else 24)
    rm = run_regime_map(vv, uu, outdir / "stickslip_regime_map.nc", workers=2, processes=False, progress=False,
                        restart=True, n_ic=4 if quick else 6)
    fr = ", ".join(f"{k} {100 * f:.1f} %" for k, f in rm["fractions"].items())
    md += [f"**Regime map (Fig 4.13)** over {len(uu)} u0 x {len(vv)} v cells: {fr}. Classification "
           "(docs/stickslip.md): stick when the lab sample speed drops below v/2 (this puts the quasi-static "
           "boundary at the fold u0 = 1), steady sliding when its modulation is below 20 % of v, coexisting when "
           "several periodic attractors are reached from different initial conditions, irregular when a trajectory "
           "is not periodic (period <= 4) after the transient. Contours: period of the attractor in lattice "
           "periods (single, double, triple slips).", "",
           "![regime map](stickslip_regime_map.png)", ""]
    brows = [dict(u=r["u0"], v=r["v_star"], V=r["V_star_m_s"] * 1e6, w=r["v_star_over_well_frequency"]) for r in rm["v_star"]]
    md += [f"Boundaries by bisection: stick-slip starts above u0* = {rm['u0_star_at_vmin']:.4f} at v = {rm['vmin']:.3g} "
           "(the fold criterion u0 = 1 of eq 4.12 is the v -> 0 limit); stick ends (stick-slip gives way to sliding) above "
           "the speed v*(u0):", "",
           markdown_table(brows, [("u", "u0", ".2f"), ("v", "v*", ".3f"), ("V", "V* [um/s]", ".0f"),
                                  ("w", "v* / sqrt(u0 m/m2)", ".2f")]),
           "", "The last column compares v* with the frequency of the sample in a substrate well: stick-slip ends "
           "when the washboard frequency v exceeds it by about 20 %.", ""]
    return "\n".join(md)
