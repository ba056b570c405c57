"""``probedyn stickslip ...`` and ``probedyn sweep ...``: the two-mass stick-slip model of
section 4.1.3 (eqs 4.2-4.12, Figs 4.8-4.13) and the Dask sweep engine. The maps and boundaries
are computed by :mod:`probedyn.schemes.regimes`; the figures and the report section are in
:mod:`probedyn.report.stickslip`."""

from __future__ import annotations

import math

from pathlib import Path
from typing import Any, Optional

import typer

from probedyn.commands._apps import stickslip_app, sweep_app
from probedyn.commands._probe import PROBE_MODES_OPT, PROBE_OPT, PROBE_Q_OPT, PROBE_SET_OPT, load_probe
from probedyn.commands._common import JSON_OPT, emit, format_table, out_file_option

WORKERS_OPT = typer.Option(2, "--workers", help="Workers of the local Dask cluster.")
SCHED_OPT = typer.Option(None, "--scheduler", help="Address of an existing Dask scheduler (tcp://HOST:PORT).")
PSI_OPT = typer.Option(5.0, "--psi", help="Phase psi of eq 4.11 (rad).")


def _parse_values(spec: str, name: str):
    """``LO:HI:N[:log]`` or ``V1,V2,...`` -> array (grid errors are GridError)."""
    from probedyn.schemes.sweep import parse_axis

    return parse_axis(f"{name}={spec}")[1]


def _probe_scaling(probe, probe_sets, probe_modes, probe_q, sample, U0: float = 0.0, speed: float = 0.0, x0: float = 0.0):
    """(scaling, TwoMassModel) of ``--probe`` through the section 4.1.3 scaling (eqs 4.3-4.7)."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes.probe_hooks import stickslip_scaling, two_mass_model

    rp = load_probe(probe, probe_sets, probe_modes, probe_q)
    sc = stickslip_scaling(rp, U0, V=speed, x_s0=x0, sample=parse_sets(sample))
    return sc, two_mass_model(sc)


def _derivation(sc: dict[str, Any] | None, lines: list[str] | None = None) -> str:
    if not sc:
        return ""
    return "\n".join(["scaling of section 4.1.3:"] + ["  " + line for line in (lines or sc["derivation"])]) + "\n"


def _floats(spec: str, name: str) -> list[float]:
    return [float(x) for x in _parse_values(spec, name)]


SAMPLE_OPT = typer.Option(None, "--sample", help="With --probe: m2, k2, zeta2 or a as NAME=VALUE (default Table 4.3). "
                                                  "Repeatable.")


# --------------------------------------------------------------------------------------
# commands
# --------------------------------------------------------------------------------------


@stickslip_app.command("equilibria")
def cmd_equilibria(
    u0: Optional[float] = typer.Option(None, "--u0", help="Non-dimensional potential amplitude u0 = 4 pi^2 U0/(k a^2) "
                                                        "(or give --probe and --U0)."),
    psi: Optional[float] = typer.Option(None, "--psi", help="Phase psi of eq 4.11 (rad) [default: 5.0; with --probe "
                                                           "it comes from --x0]."),
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    U0: Optional[float] = typer.Option(None, "--U0", help="With --probe: substrate corrugation amplitude U0 of eq 4.1 [J]."),
    x0: Optional[float] = typer.Option(None, "--x0", help="With --probe: initial sample position in the potential [m] (psi = 2 pi x0/a)."),
    speed: Optional[float] = typer.Option(None, "--speed", help="With --probe: pushing speed V [m/s] (for v = (2 pi/a) sqrt(m/k) V)."),
    sample: Optional[list[str]] = typer.Option(None, "--sample", help="With --probe: m2, k2, zeta2 or a as NAME=VALUE "
                                                                      "(default Table 4.3). Repeatable."),
    as_json: bool = JSON_OPT,
) -> None:
    """Quasi-static equilibria X = u0 sin(X + psi) (eq 4.11) and their stability (eq 4.12); with
    --probe, u0 and psi come from the probe and the substrate through the scaling of eqs 4.3-4.7."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.stickslip import equilibria

    scaling = None
    if probe is not None:
        from probedyn.core.params import parse_sets
        from probedyn.schemes.probe_hooks import stickslip_scaling

        if U0 is None or u0 is not None:
            raise ParameterError("with --probe give the corrugation --U0 [J] (u0 is then computed), not --u0")
        if psi is not None:
            raise ParameterError("with --probe psi comes from the sample position: give --x0 [m], not --psi")
        rp = load_probe(probe, probe_sets, probe_modes, probe_q)
        scaling = stickslip_scaling(rp, U0, V=speed or 0.0, x_s0=x0 or 0.0, sample=parse_sets(sample))
        u0, psi = scaling["u0"], scaling["psi"]
    else:
        given = [o for o, v in (("--U0", U0), ("--x0", x0), ("--speed", speed), ("--sample", sample),
                                ("--probe-set", probe_sets)) if v]
        given += [o for o, v in (("--U0", U0), ("--x0", x0), ("--speed", speed)) if v is not None and o not in given]
        if given:
            raise ParameterError(f"{', '.join(given)}: only with --probe (the probe's scaling of eqs 4.3-4.7)")
        if u0 is None:
            raise ParameterError("give --u0, or --probe with --U0")
        psi = 5.0 if psi is None else psi
    res = equilibria(u0, psi).to_dict()
    if scaling is not None:
        res["scaling"] = scaling

    def human(r: dict[str, Any]) -> str:
        rows = [{"X": float(x), "L": float(l), "kind": "stable (node)"} for x, l in zip(r["stable_X"], r["stable_L"])]
        rows += [{"X": float(x), "L": float(l), "kind": "unstable (saddle)"} for x, l in zip(r["unstable_X"], r["unstable_L"])]
        rows.sort(key=lambda q: q["X"])
        head = f"u0 = {r['u0']:g}, psi = {r['psi']:g}: {r['stable']} stable, {r['unstable']} unstable"
        if r["marginal"]:
            head += f", {r['marginal']} marginal (fold)"
        deriv = ("\n".join(["scaling of section 4.1.3:"] + ["  " + line for line in r["scaling"]["derivation"]]) + "\n"
                 if r.get("scaling") else "")
        return deriv + head + "\n" + format_table(rows, [("X", "X", ".6f"), ("L", "1-u0 cos(X+psi)", ".4f"), ("kind", "kind", "")])

    emit(res, as_json, human)


@stickslip_app.command("portrait")
def cmd_portrait(
    u0: Optional[str] = typer.Option(None, "--u0", help="Comma-separated u0 values (default 0.5,6,25)."),
    psi: float = PSI_OPT,
    v: float = typer.Option(0.0, "--v", help="Non-dimensional speed (0 = quasi-static)."),
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    U0: Optional[str] = typer.Option(None, "--U0", help="With --probe: corrugation amplitudes U0 of eq 4.1 [J], "
                                                       "comma-separated (u0 = 4 pi^2 U0/(k a^2))."),
    x0: float = typer.Option(0.0, "--x0", help="With --probe: sample position in the potential [m] (psi = 2 pi x0/a)."),
    speed: float = typer.Option(0.0, "--speed", help="With --probe: pushing speed V [m/s] (v = (2 pi/a) sqrt(m/k) V)."),
    sample: Optional[list[str]] = SAMPLE_OPT,
    out: Path = out_file_option(Path("stickslip-portraits.png"), "PNG file."),
    as_json: bool = JSON_OPT,
) -> None:
    """Solutions of eq 4.11 vs psi and sample phase portraits (Fig 4.8); with --probe, u0, psi, v
    and the model's ratios and damping come from the probe through eqs 4.3-4.7."""
    from probedyn.core.errors import ParameterError
    from probedyn.report.stickslip import plot_portraits

    sc = model = None
    if probe is not None:
        if U0 is None or u0 is not None:
            raise ParameterError("with --probe give the corrugation(s) --U0 [J] (u0 is then computed), not --u0")
        Us = _floats(U0, "U0")
        scs = [_probe_scaling(probe, probe_sets, probe_modes, probe_q, sample, U, speed, x0) for U in Us]
        sc, model = scs[0]
        vals, psi, v = [c["u0"] for c, _ in scs], sc["psi"], sc["v"]
        title = f"{sc['probe'].get('probe')} ({sc['probe'].get('source')}): k1 = {sc['k1']:.3g} N/m, zeta1 = {sc['zeta1']:.3g}"
    else:
        if U0 is not None:
            raise ParameterError("--U0 needs --probe")
        vals, title = _floats(u0 if u0 is not None else "0.5,6,25", "u0"), None
    png = plot_portraits(vals, psi, out, v=v, model=model, title=title)
    res = {"plot": str(png), "u0": vals, "psi": psi, "v": v}
    if sc is not None:
        res["scaling"] = sc
        res["U0"] = Us

    def human(r):
        return _derivation(r.get("scaling")) + f"u0 = {', '.join(f'{x:.4g}' for x in r['u0'])}, psi = {r['psi']:.4g}, " \
            f"v = {r['v']:.4g}: wrote {r['plot']}"

    emit(res, as_json, human)


@stickslip_app.command("limit-cycles")
def cmd_limit_cycles(
    u0: Optional[float] = typer.Option(None, "--u0", help="Non-dimensional amplitude (default 3)."),
    v: Optional[str] = typer.Option(None, "--v", help="Speeds: LO:HI:N[:log] or V1,V2,... (default 0.02:20:13:log)."),
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    U0: Optional[float] = typer.Option(None, "--U0", help="With --probe: corrugation amplitude U0 of eq 4.1 [J]."),
    speeds: Optional[str] = typer.Option(None, "--speeds", help="With --probe: pushing speeds V [m/s], LO:HI:N[:log] "
                                                              "or V1,V2,... (v = (2 pi/a) sqrt(m/k) V)."),
    sample: Optional[list[str]] = SAMPLE_OPT,
    out: Optional[Path] = out_file_option(None, "PNG file for the cycles and amplitude/centre vs v."),
    as_json: bool = JSON_OPT,
) -> None:
    """Limit cycles as the speed rises: amplitude and centre vs v (Figs 4.10-4.11); with --probe,
    u0, v and the model come from the probe through eqs 4.3-4.7."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.regimes import limit_cycles_result
    from probedyn.schemes.stickslip import DEFAULT_MODEL

    sc, model = None, DEFAULT_MODEL
    if probe is not None:
        if U0 is None or speeds is None or u0 is not None or v is not None:
            raise ParameterError("with --probe give --U0 [J] and --speeds [m/s] (u0 and v are then computed), "
                                 "not --u0/--v")
        sc, model = _probe_scaling(probe, probe_sets, probe_modes, probe_q, sample, U0, 0.0, 0.0)
        Vs = _parse_values(speeds, "speeds")
        if (Vs <= 0).any():
            raise ParameterError("--speeds values must be positive")
        u0 = sc["u0"]
        vv = Vs * (2 * math.pi / sc["a"]) * sc["time_unit_s"]
    else:
        if U0 is not None or speeds is not None:
            raise ParameterError("--U0 and --speeds need --probe")
        u0 = 3.0 if u0 is None else u0
        vv = _parse_values(v if v is not None else "0.02:20:13:log", "v")
    if (vv <= 0).any():
        raise ParameterError("--v values must be positive")
    lc = limit_cycles_result(u0, vv, model)
    if out is not None:
        from probedyn.report.stickslip import plot_limit_cycles

        lc["plot"] = str(plot_limit_cycles(lc, u0, out))
    res = {k: val for k, val in lc.items() if k != "orbits"}
    res["u0"] = u0
    if sc is not None:
        res["scaling"] = sc
        res["derivation"] = sc["derivation"][:6] + [
            f"(4.6)  v = (2 pi/a) sqrt(m/k) V = V x {2 * math.pi / sc['a'] * sc['time_unit_s']:.4g} s/m"]

    def human(r):
        rows = [dict(v=r["v"][i], V=r["speed_m_s"][i], amp=r["amplitude"][i], c=r["centre"][i],
                     f=r["friction_mean"][i], st="stick-slip" if r["stick"][i] else "smooth") for i in range(len(r["v"]))]
        return _derivation(r.get("scaling"), r.get("derivation")) + f"u0 = {r['u0']:.4g}\n" + format_table(
            rows, [("v", "v", ".4g"), ("V", "V [m/s]", ".3g"), ("amp", "amplitude", ".4f"),
                   ("c", "centre", ".4f"), ("f", "mean friction", ".4f"), ("st", "motion", "")])

    emit(res, as_json, human)


@stickslip_app.command("regime-map")
def cmd_regime_map(
    u0: str = typer.Option("0.25:25:24", "--u0", help="u0 axis: LO:HI:N or V1,V2,..."),
    v: str = typer.Option("0.05:10:24:log", "--v", help="v axis: LO:HI:N[:log] or V1,V2,..."),
    out: Path = out_file_option(Path("regime-map.nc"), "NetCDF file (a PNG is written next to it)."),
    n_ic: int = typer.Option(6, "--n-ic", help="Initial conditions per cell."),
    workers: int = WORKERS_OPT,
    scheduler: Optional[str] = SCHED_OPT,
    restart: bool = typer.Option(False, "--restart", help="Discard finished chunks of an interrupted run."),
    progress: bool = typer.Option(True, "--progress/--no-progress"),
    processes: bool = typer.Option(False, "--processes/--threads", help="Local workers as processes or threads."),
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    sample: Optional[list[str]] = SAMPLE_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Regime map over (v, u0) with numerically found boundaries (Fig 4.13), on Dask; with --probe
    the two-mass model's ratios and damping are the probe's (eqs 4.3-4.7) and the axes are also
    given in SI (U0 [J], V [m/s])."""
    from probedyn.report.stickslip import plot_regime_map
    from probedyn.schemes.regimes import run_regime_map

    sc = mp = None
    if probe is not None:
        sc, model = _probe_scaling(probe, probe_sets, probe_modes, probe_q, sample)
        mp = dict(m1=model.m1, m2=model.m2, k1=model.k1, k2=model.k2, zeta1=model.zeta1, zeta2=model.zeta2, a=model.a)
    vv, uu = _parse_values(v, "v"), _parse_values(u0, "u0")
    res = run_regime_map(vv, uu, out, workers=workers, scheduler=scheduler, progress=progress, restart=restart,
                         n_ic=n_ic, processes=processes, model_params=mp)
    res["plot"] = str(plot_regime_map(res.pop("dataset"), Path(out).with_suffix(".png"), res))
    if sc is not None:
        k, a, T = sc["k"], sc["a"], sc["time_unit_s"]
        res["scaling"] = sc
        res["U0_axis_J"] = [float(x * k * a * a / (4 * math.pi**2)) for x in uu]
        res["V_axis_m_s"] = [float(x * a / (2 * math.pi * T)) for x in vv]
        res["derivation"] = sc["derivation"][:5] + [
            f"(4.7)  axis u0 -> U0 = u0 k a^2/(4 pi^2) = u0 x {k * a * a / (4 * math.pi**2):.4g} J",
            f"(4.6)  axis v -> V = v a/(2 pi sqrt(m/k)) = v x {a / (2 * math.pi * T):.4g} m/s"]

    def human(r):
        lines = ([_derivation(r["scaling"], r["derivation"]).rstrip()] if r.get("scaling") else [])
        lines += [f"wrote {r['path']} and {r['plot']} ({r['chunks_run']} chunks run, {r['chunks_skipped']} resumed)"]
        lines += [f"  {k}: {100 * f:.1f} % of cells" for k, f in r["fractions"].items()]
        return "\n".join(lines)

    emit(res, as_json, human)


@sweep_app.command("basins")
def cmd_sweep_basins(
    u0: float = typer.Option(8.0, "--u0"),
    psi: float = PSI_OPT,
    grid: int = typer.Option(256, "--grid", help="Points per axis of the initial-condition grid."),
    out: Path = out_file_option(..., "NetCDF file (FILE.nc); the plot goes to FILE.png."),
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
    from probedyn.report.stickslip import plot_basins
    from probedyn.schemes.regimes import run_basins
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
    res["plot"] = str(plot_basins(res.pop("dataset"), Path(out).with_suffix(".png"),
                                  f"basins, u0 = {u0:g}, psi = {psi:g} ({grid}x{grid})"))

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
    out: Path = out_file_option(..., "NetCDF file (FILE.nc)."),
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
