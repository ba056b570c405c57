"""``probedyn modes|compare|reduce|render|params PROBE``: the modal pipeline on the command line.

PROBE is a registry name (``probedyn params`` without a probe lists them) or a TOML file
(``probe = "cantilever"`` plus parameter keys). ``--set NAME=VALUE`` overrides parameters (SI).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, out_folder_option, save
from probedyn.core.params import parse_sets

PROBE_ARG = typer.Argument(..., help="Probe name (cantilever, duo-bimorph, piezotube) or a TOML probe file.")
NMODES_OPT = typer.Option(8, "--n-modes", min=1, max=200, help="Number of lowest modes.")


def solve(probe_name: str, sets: list[str] | None, n_modes: int):
    """Resolve the probe and its parameters, build the FEM model and solve the lowest modes."""
    from probedyn.probes import get_probe

    probe, toml_overrides = get_probe(probe_name)
    overrides = {**toml_overrides, **parse_sets(sets)}
    values = probe.resolve(overrides)
    model = probe.build(values)
    result = model.modes(n_modes)
    return probe, values, result


def _modes_text(res: dict[str, Any]) -> str:
    rows = [{"mode": i + 1, **m} for i, m in enumerate(res["modes"])]
    cols = [("mode", "mode", ""), ("frequency_hz", "f [Hz]", ".6g"), ("family", "family", "")]
    return f"{res['probe']}: {res['dofs']} DOFs\n" + format_table(rows, cols)


@app.command("modes")
def modes_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = NMODES_OPT,
              electrodes: Optional[str] = typer.Option(None, "--electrodes", help="Smart probes: coupled piezo modes with the electrodes short, open, or both (k_eff^2)."),
              out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Lowest modes of a probe (3D FEM, P2 tetrahedra): frequency, family, effective masses."""
    if electrodes is not None:
        from probedyn.commands.piezo import modes_with_electrodes

        return modes_with_electrodes(probe, set_, n_modes, electrodes, out, as_json)
    p, values, result = solve(probe, set_, n_modes)
    res = {"probe": p.name, "parameters": values, **result.to_dict()}
    if out is not None:
        result.write_vtu(Path(out) / "modes.vtu")
        save(out, "modes.json", res)
    emit(res, as_json, _modes_text)


@app.command("compare")
def compare_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = NMODES_OPT,
                out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Mode-by-mode table: FEM frequency, each applicable analytic formula, relative difference."""
    from probedyn.lumped.compare import comparison_rows

    p, values, result = solve(probe, set_, n_modes)
    rows = comparison_rows(p, values, result)
    res = {"probe": p.name, "parameters": values, "dofs": result.dofs,
           "modes": [m.to_dict() for m in result.modes], "comparison": rows}
    save(out, "compare.json", res)

    def text(r):
        cols = [("mode", "mode", ""), ("family", "family", ""), ("formula", "formula", ""),
                ("fem_hz", "FEM [Hz]", ".6g"), ("value_hz", "formula [Hz]", ".6g"), ("rel_pct", "diff [%]", "+.3f")]
        return format_table([{**x, "rel_pct": 100 * x["rel_diff"]} for x in r["comparison"]], cols)

    emit(res, as_json, text)


@app.command("reduce")
def reduce_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = NMODES_OPT,
               mu: Optional[float] = typer.Option(None, "--mu", help="Environment damping per length [N s/m^2] (eq 3.2)."),
               q: Optional[float] = typer.Option(None, "--q", help="Quality factor (c = sqrt(k m)/Q)."),
               out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Lumped model per mode at the tip (eqs 3.1-3.3 generalised) and the static tip stiffness."""
    from probedyn.lumped.reduce import check_damping, reduce_modes

    check_damping(mu, q)  # before the FEM solve
    p, values, result = solve(probe, set_, n_modes)
    model = result.model
    rho_a = p.mass_per_length(values, model) if mu is not None else None
    lumped = reduce_modes(result, mu=mu, Q=q, mass_per_length=rho_a, total_mass=result.total_mass)
    res = {"probe": p.name, "parameters": values, "dofs": result.dofs,
           "lumped": [lm.to_dict() for lm in lumped], "static": p.static_stiffness(values, model)}
    save(out, "lumped.json", res)

    def text(r):
        cols = [("mode", "mode", ""), ("family", "family", ""), ("direction", "dir", ""),
                ("frequency_hz", "f [Hz]", ".6g"), ("mass", "m_eff [kg]", ".4e"), ("stiffness", "k_eff [N/m]", ".4g"),
                ("damping", "c_eff [N s/m]", ".3e")]
        s = format_table(r["lumped"], cols)
        st = r["static"]
        if st:
            s += "\n\n" + "\n".join(f"static tip stiffness {k}: {v:.6g}" for k, v in st.items() if v is not None)
        return s

    emit(res, as_json, text)


@app.command("render")
def render_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = typer.Option(4, "--n-modes", min=1, max=50),
               out: Path = out_folder_option(Path("out/render"), "Output folder for the PNGs."),
               as_json: bool = JSON_OPT) -> None:
    """PNG pictures of the first modes (off-screen), one per mode plus a 2x2 panel."""
    from probedyn.fem.render import check_offscreen_gl, render_modes, render_panel

    check_offscreen_gl()  # fail with a clear message before VTK could segfault
    p, values, result = solve(probe, set_, n_modes)
    files = render_modes(result, out, n_modes, prefix=f"{p.name}_mode")
    files.append(render_panel(result, Path(out) / f"{p.name}_modes_panel.png"))
    res = {"probe": p.name, "files": [str(f) for f in files],
           "modes": [{"frequency_hz": m.frequency_hz, "family": m.family} for m in result.modes], "dofs": result.dofs}
    emit(res, as_json, lambda r: "\n".join(r["files"]))


@app.command("params")
def params_cmd(probe: Optional[str] = typer.Argument(None, help="Probe name or TOML file; omit to list probes."),
               as_json: bool = JSON_OPT) -> None:
    """Parameters of a probe with units, defaults and plausible ranges (or the list of probes)."""
    from probedyn.probes import get_probe, list_probes

    if probe is None:
        emit({"probes": list_probes()}, as_json, lambda r: "\n".join(r["probes"]))
        return
    p, _ = get_probe(probe)
    rows = p.params.table()
    cols = [("name", "name", ""), ("unit", "unit", ""), ("default", "default", ""), ("description", "description", "")]
    emit({"probe": p.name, "parameters": rows}, as_json, lambda r: format_table(r["parameters"], cols))
