"""``probedyn simulate ffm`` (FFM line scans, section 2.1.4–2.1.5) and ``probedyn fit-ffm``.
The report section on nano-friction and the figures are in :mod:`probedyn.report.friction`."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from probedyn.commands._apps import app, simulate_app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, save
from probedyn.commands._probe import PROBE_MODES_OPT, PROBE_OPT, PROBE_Q_OPT, PROBE_SET_OPT, load_probe, probe_line
from probedyn.core.io import make_dirs


def _human(d: dict) -> str:
    def nn(v, s=1e9, u="nN", f=".4g"):
        return "-" if v is None else f"{v * s:{f}} {u}"

    return "\n".join([
        f"FFM line scan: preset {d['preset']}, model {d['model']}, {d['scan_length_m'] * 1e9:.4g} nm at "
        f"{d['scan_speed_m_s'] * 1e6:.4g} µm/s ({d['wall_time_s'] * 1e3:.1f} ms, {d['n_steps']} steps)",
        f"regime: {d['regime']}   slips: {d['n_slips']}",
        f"static friction  {nn(d['static_friction_n'])}   kinetic friction {nn(d['kinetic_friction_n'])}",
        f"period {nn(d['period_m'], 1e9, 'nm')}   first slip at {nn(d['first_slip_m'], 1e9, 'nm')}",
        f"quasi-static estimates: first slip F_s/k_x = {nn(d['first_slip_estimate_m'], 1e9, 'nm')}, "
        f"period (F_s-F_c)/k_x = {nn(d['period_estimate_m'], 1e9, 'nm')}",
        f"max lateral force {nn(d['max_force_n'])}",
        *([f"note: {d['preset_scan']['note']}"] if d.get("preset_scan") else []),
        *([f"note: {d['scan_note']}"] if d.get("scan_note") else []),
        *([probe_line(d["probe"])] if d.get("probe") else [f"probe: {d.get('probe_source')}"]),
    ])


@simulate_app.command("ffm")
def ffm_cmd(
    preset: str = typer.Option("mica", "--preset", help="mica (Table 2.1) or vamwcnt (Table 2.2)."),
    model: str = typer.Option("bristle", "--model", help="Friction model: bristle, lugre or pt."),
    length: Optional[float] = typer.Option(
        None, "--length",
        help="Scan length in m. Default: the preset's scan range (10 nm for mica), extended when "
             "needed to the first slip plus four periods (F_s/k_x + 4 (F_s-F_c)/k_x), so that the "
             "stick-slip regime can be measured; the result for the preset's own range is reported too."),
    sets: Optional[list[str]] = SET_OPT,
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Simulate one FFM line scan (eqs 2.13-2.16); report static/kinetic friction, period, regime."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes.ffm_studies import run_ffm_to_regime

    rp = load_probe(probe, probe_sets, probe_modes, probe_q)
    res, summary = run_ffm_to_regime(preset, model, parse_sets(sets), length=length, probe=rp)
    if out is not None:
        from probedyn.report.friction import plot_scan

        out = Path(out)
        make_dirs(out)
        summary["plot"] = str(plot_scan(res, summary, out / f"ffm_{preset}_{summary['model']}.png"))
        save(out, f"ffm_{preset}_{summary['model']}.json", summary)
    emit(summary, as_json, _human)


@app.command("fit-ffm")
def fit_ffm_cmd(
    trace: Path = typer.Argument(..., help="CSV: base position in m (or time in s), lateral force in N; '# speed = ...', '# k_x = ...' lines."),
    free: str = typer.Option("F_s,F_c", "--free", help="Comma-separated parameters to fit."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Cantilever/friction defaults (default: file's or mica)."),
    model: Optional[str] = typer.Option(None, "--model", help="Friction model (default: file's or bristle)."),
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Fit friction-model parameters to a measured lateral-force trace, with uncertainties."""
    from probedyn.schemes import fit as FT

    tr = FT.read_trace(trace)
    r = FT.fit_trace(tr, [s.strip() for s in free.split(",") if s.strip()], preset=preset, model=model, noise=None)
    summary = {k: v for k, v in r.items() if k not in ("residuals", "model_force", "base")}
    if out is not None:
        from probedyn.report.friction import plot_fit

        out = Path(out)
        make_dirs(out)
        summary["plot"] = str(plot_fit(r, tr, out / "fit_ffm.png"))
        save(out, "fit_ffm.json", summary)

    def human(d):
        lines = [f"fit of {', '.join(d['free'])} ({d['model']}, preset {d['preset']}): {d['message']}"]
        for n in d["free"]:
            lines.append(f"  {n} = {d['values'][n]:.6g} +- {d['uncertainties'][n]:.2g}")
        lines.append(f"residual rms {d['residual_rms_n']:.3g} N, max {d['residual_max_n']:.3g} N, "
                     f"{d['n_points']} points, {d['n_evaluations']} model evaluations")
        return "\n".join(lines)

    emit(summary, as_json, human)
