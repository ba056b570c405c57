"""``probedyn actuate PROBE``: volts in, displacement out (coupled piezoelectric FEM); and the
electrode conditions of ``probedyn modes PROBE --electrodes short|open|both``.

A drive is a pattern (``--pattern V_y``; the probe's patterns are listed in the error message
and in docs/piezo.md) or electrodes with voltages (``--electrode electrode_zp --volts 10``,
repeatable; one ``--volts`` for all or one per electrode).  The other electrodes of the layout
are grounded.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, save

PROBE_ARG = typer.Argument(..., help="Smart probe (duo-bimorph, piezotube) or a TOML file of one.")


@app.command("actuate")
def actuate_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT,
                electrode: Optional[List[str]] = typer.Option(None, "--electrode", help="Electrode to drive (repeatable)."),
                volts: Optional[List[float]] = typer.Option(None, "--volts", help="Voltage [V]: one for all or one per --electrode."),
                pattern: Optional[str] = typer.Option(None, "--pattern", help="Drive pattern, e.g. V_y, V_z (duo-bimorph), V_x, V_y, V_z (piezotube)."),
                layout: Optional[str] = typer.Option(None, "--layout", help="Electrode layout: split (duo-bimorph), quarters or sectors (piezotube)."),
                poling: Optional[str] = typer.Option(None, "--poling", help="duo-bimorph: parallel (default) or series."),
                picture: bool = typer.Option(False, "--picture", help="With --out: also a PNG of the deformed probe (off-screen GL)."),
                out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Static displacement for electrode voltages: tip displacement, charges, VTU and picture."""
    from probedyn.core.params import parse_sets
    from probedyn.probes.piezo import run_actuation

    a, values = run_actuation(probe, parse_sets(set_), pattern, electrode or [], volts if volts else 1.0, layout, poling)
    res = {**a.to_dict(), "pattern": pattern, "layout": layout or "default", "parameters": values,
           "axes": "probedyn axes: x along the probe, y lateral, z up" + (
               "; source frame x = probedyn z, y = y, z = probedyn x (tube axis)" if a.probe == "piezotube" else "")}
    if out is not None:
        files = [str(a.result.write_vtu(Path(out) / "actuate.vtu"))]
        if picture:
            files.append(str(_picture(a, a.probe, pattern, volts[0] if volts else 1.0, Path(out) / "actuate.png")))
        res["files"] = files
        save(out, "actuate.json", res)
    emit(res, as_json, _actuate_text)


def _actuate_text(r: dict[str, Any]) -> str:
    tip = r["tip_displacement_m"]
    lines = [f"{r['probe']}: {r['dofs']} DOFs ({r['solver']}), drive "
             + ", ".join(f"{k} = {v:+g} V" for k, v in r["voltages"].items()),
             f"tip displacement [nm]: x {tip[0] * 1e9:+.4f}  y {tip[1] * 1e9:+.4f}  z {tip[2] * 1e9:+.4f}"]
    for k, v in r["displacements_m"].items():
        lines.append(f"{k} [nm]: x {v[0] * 1e9:+.4f}  y {v[1] * 1e9:+.4f}  z {v[2] * 1e9:+.4f}")
    lines.append("electrode charges [pC]: " + ", ".join(f"{k} {v * 1e12:+.4g}" for k, v in r["electrode_charges_C"].items()))
    lines.append(r["axes"])
    for f in r.get("files", []):
        lines.append(f"wrote {f}")
    return "\n".join(lines)


def _picture(a, probe: str, pattern: Optional[str], volts: float, path: Path) -> Path:
    """PNG of the deformed probe through fem/render.py (one "mode" = the static field)."""
    import numpy as np

    from probedyn.fem.modes import ModalResult, Mode
    from probedyn.fem.render import check_offscreen_gl, render_mode

    check_offscreen_gl()
    tip = np.asarray(a.tip)
    fam = ("axial", "lateral", "flapwise")[int(np.argmax(np.abs(tip)))]
    mode = Mode(index=1, frequency_hz=0.0, omega=0.0, family=fam, shape=a.result.u, tip_displacement=tip)
    res = ModalResult([mode], a.dofs, a.result.model.mech)
    drive = (f"pattern {pattern} = {volts:g} V" if pattern else
             ", ".join(f"{k.replace('electrode_', '')} {v:+g} V" for k, v in list(a.voltages.items())[:3])
             + (" ..." if len(a.voltages) > 3 else ""))
    title = f"{probe}, {drive}: tip {np.linalg.norm(tip) * 1e6:.4g} \u00b5m (magnified)"
    return render_mode(res, 0, path, title=title)


def modes_with_electrodes(probe: str, set_: Optional[List[str]], n_modes: int, electrodes: str,
                          out: Optional[Path], as_json: bool) -> None:
    """``probedyn modes PROBE --electrodes short|open|both`` (called from commands/modal.py)."""
    from probedyn.core.params import parse_sets
    from probedyn.probes.piezo import electrode_modes

    res = electrode_modes(probe, parse_sets(set_), n_modes, electrodes)
    save(out, "modes_electrodes.json", res)
    if electrodes == "both":
        cols = [("mode", "mode", ""), ("family", "family", ""), ("f_sc_hz", "f short [Hz]", ".7g"),
                ("f_oc_hz", "f open [Hz]", ".7g"), ("shift_pct", "shift [%]", ".4f"), ("k_eff2", "k_eff^2", ".5f")]
        emit(res, as_json, lambda r: f"{r['probe']}: {r['dofs']} DOFs, open = electrodes floating, "
             f"{r['reference_electrode']} grounded\n" + format_table(
                 [{**x, "shift_pct": 100 * x["shift"]} for x in r["rows"]], cols))
        return
    cols = [("mode", "mode", ""), ("frequency_hz", "f [Hz]", ".7g"), ("family", "family", "")]
    emit(res, as_json, lambda r: f"{r['probe']} (electrodes {r['electrodes']}): {r['dofs']} DOFs\n"
         + format_table(r["modes"], cols))
