"""``probedyn track PROBE --path ... --control ...``: path tracking with the smart probes
(source sections 3.2.3, 3.3.3, 3.5). A thin command: argument parsing, one library call
(:func:`probedyn.schemes.tracking.studies.track` on the plants of
:func:`probedyn.probes.tracking.plant_factory`), output (``--json``, ``--out`` plots through
the report layer :mod:`probedyn.report.tracking`)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, save


@app.command("track")
def track_cmd(
    probe: str = typer.Argument(..., help="duo-bimorph, piezotube, or a TOML probe file"),
    path: str = typer.Option(..., "--path", help="line|circle|square (duo-bimorph), circle|cylinder|sphere|cone "
                                                 "(piezotube), or a CSV file t,x,y,z [s, m]"),
    control: str = typer.Option("composite", "--control", help="open|slow|composite|pid"),
    disturbance: Optional[str] = typer.Option(None, "--disturbance", help="kbr: KBr(100) substrate force (3.45)"),
    disturbance_scale: float = typer.Option(1.0, "--disturbance-scale", help="multiply p1, p2 of the disturbance"),
    speed: Optional[float] = typer.Option(None, "--speed", help="mean tip speed along the path [m/s] (sets the duration)"),
    duration: Optional[float] = typer.Option(None, "--duration", help="path duration [s] (default 1 s)"),
    size: Optional[float] = typer.Option(None, "--size", help="path radius or side [m]"),
    k_t: Optional[float] = typer.Option(None, "--k-t", help="holder stiffness in every direction [N/m]"),
    body: str = typer.Option("analytic", "--body", help="analytic | fem: where the body's J, K2, C2 come from"),
    gains: str = typer.Option("analytic", "--gains", help="analytic | fem: actuation gains (formulas or the piezo FEM)"),
    v_max: Optional[float] = typer.Option(None, "--v-max", help="amplifier limit [V] (default 200 tube, 20 duo-bimorph)"),
    eccentricity: Optional[float] = typer.Option(None, "--eccentricity", help="tube bore offset delta_x = delta_y [m]"),
    noise: float = typer.Option(0.0, "--noise", help="sensor noise RMS on the measured tip [m] (10 kHz band)"),
    sets: Optional[list[str]] = SET_OPT,
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Simulate the tip along a path: RMS and max error per axis, voltage peaks, gains' provenance."""
    from probedyn.core.params import parse_sets
    from probedyn.probes.tracking import plant_factory
    from probedyn.schemes.tracking.studies import track

    res, summary = track(plant_factory(body, gains=gains), probe, path, control, disturbance=disturbance,
                         disturbance_scale=disturbance_scale, speed=speed, duration=duration, size=size, k_t=k_t,
                         v_max=v_max, eccentricity=eccentricity, noise_rms=noise, overrides=parse_sets(sets))
    if out is not None:
        from probedyn.report.tracking import tracking_figure

        out = Path(out)
        summary["plot"] = str(tracking_figure(res, out / "track.png", f"{summary['probe']}, {summary['control']}"))
        save(out, "track.json", summary)

    def human(d):
        m = d["metrics"]
        rows = [{"axis": a, "rms": v["rms_m"], "max": v["max_m"], "max_late": v["max_after_transient_m"]}
                for a, v in m["axes"].items()]
        lines = [f"{d['probe']} along {d['path']['name']} with {d['control']}"
                 + (f", disturbance {d['disturbance']['name']}" if d["disturbance"] else ""),
                 format_table(rows, [("axis", "axis", ""), ("rms", "RMS error [m]", ".3e"), ("max", "max error [m]", ".3e"),
                                     ("max_late", f"max after {m['transient_s']:.3g} s [m]", ".3e")]),
                 f"max error / path extent after the transient: {m['relative_max_error_after_transient']:.3e}",
                 "voltage peaks: " + ", ".join(f"{k} {v:.4g} V" for k, v in m["voltage_peak_V"].items()),
                 f"gains: {d['provenance']['gains']}", f"body: {d['provenance']['body']}"]
        return "\n".join(lines)

    emit(summary, as_json, human)
