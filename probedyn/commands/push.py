"""``probedyn simulate push``: nano-pushing of a sphere on mica / HOPG (section 4.1.1–4.1.2).
The report section and the figures are in :mod:`probedyn.report.pushing`."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from probedyn.commands._apps import simulate_app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, save
from probedyn.commands._probe import PROBE_MODES_OPT, PROBE_OPT, PROBE_Q_OPT, PROBE_SET_OPT, load_probe, probe_line
from probedyn.core.io import make_dirs


@simulate_app.command("push")
def push_cmd(
    substrate: str = typer.Option("mica", "--substrate", help="mica or hopg (Table 4.2)."),
    speed: Optional[float] = typer.Option(None, "--speed", help="Base pushing speed V in m/s (default 3e-6)."),
    angle: Optional[float] = typer.Option(None, "--angle", help="Angle between push direction and main lattice axis, in degrees (2D if non-zero)."),
    sets: Optional[list[str]] = SET_OPT,
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[list[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Push a sphere with the probe tip; report step length vs lattice constant and the regime."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes import pushing as P

    ov: dict = parse_sets(sets)
    if speed is not None:
        ov["V"] = speed
    if angle is not None:
        ov["angle"] = angle
    rp = load_probe(probe, probe_sets, probe_modes, probe_q)
    res, r = P.push(substrate, ov, probe=rp)
    r = dict(r, probe=rp.summary() if rp is not None else None,
             probe_source=rp.source if rp is not None else "Table 4.1")
    if out is not None:
        out = Path(out)
        make_dirs(out)
        from probedyn.report.pushing import plot_push

        r["plot"] = str(plot_push(res, r, out / "push.png", f"{substrate}, V = {res.model.p['V'] * 1e6:g} µm/s"))
        save(out, "push.json", r)

    def human(d):
        lines = [f"substrate {d['substrate']}, V = {d['speed_m_s']:g} m/s, angle = {d['angle_deg']:g} deg: {d['regime']}",
                 f"lattice constant a = {d['lattice_constant_m']:.4g} m"]
        if d.get("mean_step_m"):
            lines.append(f"mean step = {d['mean_step_m']:.4g} m (= {d['mean_step_over_a']:.4f} a), "
                         f"std {d['std_step_m']:.2g} m over {len(d['step_lengths_m'])} steps")
        lines.append(f"friction mean {d['friction_mean_N']:.4g} N (kinetic F_c + F_v V = {d['kinetic_expected_N']:.4g} N), "
                     f"pre-sliding peak {d['presliding']['peak_friction_N']:.4g} N")
        lines.append(probe_line(d["probe"]) if d.get("probe") else f"probe: {d['probe_source']}")
        return "\n".join(lines)

    emit(r, as_json, human)
