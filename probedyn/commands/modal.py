"""``probedyn modes|compare|reduce|render|params PROBE``: the modal pipeline on the command line.

PROBE is a registry name (``probedyn params`` without a probe lists them) or a TOML file
(``probe = "cantilever"`` plus parameter keys). ``--set NAME=VALUE`` overrides parameters (SI).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, markdown_table, save
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


def _mode_rows(result) -> list[dict[str, Any]]:
    rows = []
    for m in result.modes:
        d = m.to_dict()
        rows.append({"mode": m.index, "frequency_hz": m.frequency_hz, "family": m.family,
                     "m_eff_z": d.get("effective_mass_tip", {}).get("z"),
                     "m_eff_y": d.get("effective_mass_tip", {}).get("y")})
    return rows


def _modes_text(res: dict[str, Any]) -> str:
    rows = [{"mode": i + 1, **m} for i, m in enumerate(res["modes"])]
    cols = [("mode", "mode", ""), ("frequency_hz", "f [Hz]", ".6g"), ("family", "family", "")]
    return f"{res['probe']}: {res['dofs']} DOFs\n" + format_table(rows, cols)


@app.command("modes")
def modes_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = NMODES_OPT,
              out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Lowest modes of a probe (3D FEM, P2 tetrahedra): frequency, family, effective masses."""
    p, values, result = solve(probe, set_, n_modes)
    res = {"probe": p.name, "parameters": values, **result.to_dict()}
    if out is not None:
        result.write_vtu(Path(out) / "modes.vtu")
        save(out, "modes.json", res)
    emit(res, as_json, _modes_text)


def compare_rows(p, values, result) -> list[dict[str, Any]]:
    from probedyn.lumped.compare import comparison_rows

    return comparison_rows(p, values, result)


@app.command("compare")
def compare_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = NMODES_OPT,
                out: Optional[Path] = OUT_OPT, as_json: bool = JSON_OPT) -> None:
    """Mode-by-mode table: FEM frequency, each applicable analytic formula, relative difference."""
    p, values, result = solve(probe, set_, n_modes)
    rows = compare_rows(p, values, result)
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
    from probedyn.lumped.reduce import reduce_modes

    p, values, result = solve(probe, set_, n_modes)
    model = result.model
    rho_a = None
    if mu is not None:
        rho_a = _mass_per_length(p, values, model)
    lumped = reduce_modes(result, mu=mu, Q=q, mass_per_length=rho_a, total_mass=result.total_mass)
    res = {"probe": p.name, "parameters": values, "dofs": result.dofs,
           "lumped": [lm.to_dict() for lm in lumped],
           "static": static_stiffness(p, values, model)}
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


def _mass_per_length(p, values, model) -> float:
    L = values.get("length")
    if not L:
        from probedyn.core.errors import ParameterError

        raise ParameterError(f"--mu needs a beam length; probe '{p.name}' has none, use --q")
    return (model.total_mass() - (values.get("tip_mass") or 0.0)) / L


def static_stiffness(p, values, model) -> dict[str, Any]:
    """FEM static stiffness of the free end (face-averaged, z) beside 3EI/L^3 (cantilever only)."""
    if p.name != "cantilever":
        return {}
    from probedyn.lumped import beam as bm

    k_fem = float(model.static_stiffness("free_end", (0, 0, 1)))
    b = p.beam(values)
    return {"fem_n_per_m": k_fem,
            "euler_bernoulli_3EI_L3": bm.static_tip_stiffness(b, "flapwise", shear=False),
            "with_shear_correction": bm.static_tip_stiffness(b, "flapwise", shear=True)}


@app.command("render")
def render_cmd(probe: str = PROBE_ARG, set_: Optional[List[str]] = SET_OPT, n_modes: int = typer.Option(4, "--n-modes", min=1, max=50),
               out: Path = typer.Option(Path("out/render"), "--out", help="Output folder for the PNGs."),
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


# ----------------------------------------------------------------------------- report

def report_section(outdir: Path, quick: bool) -> str:
    """The default cantilever: FEM vs beam theory (nu = 0 and the material's nu), tip-mass table
    with both forms of (3.10), static stiffness, lumped models and mode pictures."""
    from probedyn.lumped.reduce import reduce_modes
    from probedyn.probes import get_probe

    outdir = Path(outdir)
    p, _ = get_probe("cantilever")
    mesh = {"elements_through_thickness": 2 if quick else 3}
    parts = []
    cols = [("mode", "mode", ""), ("family", "family", ""), ("formula", "formula", ""),
            ("fem_hz", "FEM [Hz]", ".6g"), ("value_hz", "formula [Hz]", ".6g"), ("rel_pct", "FEM - formula [%]", "+.3f")]

    for nu in (0.0, None):
        over = {**mesh, "youngs_modulus": 169e9, "density": 2330.0}
        if nu is not None:
            over["poisson_ratio"] = nu
        values = p.resolve(over)
        model = p.build(values)
        result = model.modes(8)
        rows = [{**r, "rel_pct": 100 * r["rel_diff"]} for r in compare_rows(p, values, result)]
        nu_txt = "0" if nu == 0 else f"{p.material(values).isotropic_constants()[1]:g} (material)"
        parts += [f"### FEM vs beam theory, L = 300 um, w = 30 um, t = 10 um, E = 169 GPa, nu = {nu_txt}", "",
                  f"{result.dofs} DOFs, P2 tetrahedra, assembly {result.timings.get('assemble_s', float('nan')):.1f} s, "
                  f"eigen-solution {result.timings.get('solve_s', float('nan')):.1f} s ({result.solver}).", "",
                  markdown_table(rows, cols), ""]
        st = static_stiffness(p, values, model)
        parts += [f"Static tip stiffness (free-end face, z): FEM {st['fem_n_per_m']:.5g} N/m; "
                  f"3EI/L^3 = {st['euler_bernoulli_3EI_L3']:.5g} N/m; with Timoshenko shear correction "
                  f"{st['with_shear_correction']:.5g} N/m (FEM {100 * (st['fem_n_per_m'] / st['with_shear_correction'] - 1):+.3f} %).", ""]
        if nu is None:
            lumped = reduce_modes(result, Q=100.0, total_mass=result.total_mass)
            lrows = [lm.to_dict() for lm in lumped]
            parts += ["### Lumped model at the tip (eqs 3.1-3.3 generalised; damping from Q = 100)", "",
                      markdown_table(lrows, [("mode", "mode", ""), ("family", "family", ""), ("direction", "dir", ""),
                                             ("frequency_hz", "f [Hz]", ".6g"), ("mass", "m_eff [kg]", ".4e"),
                                             ("stiffness", "k_eff [N/m]", ".5g"), ("damping", "c_eff [N s/m]", ".3e")]), ""]
            try:
                from probedyn.fem.render import render_panel

                render_panel(result, outdir / "cantilever_modes.png")
                parts += ["![first four modes of the default cantilever](cantilever_modes.png)", ""]
            except Exception as exc:  # a missing GL library must not sink the whole report
                parts += [f"(mode pictures skipped: {exc})", ""]

    # tip mass: FEM vs both forms of (3.10)
    rows = []
    values0 = p.resolve({**mesh, "poisson_ratio": 0.0})
    b = p.beam(values0)
    m_beam = b.rho * b.w * b.t * b.L
    for ratio in ((1.0,) if quick else (0.2, 1.0, 5.0)):
        tm = ratio * m_beam
        values = p.resolve({**mesh, "poisson_ratio": 0.0, "tip_mass": tm})
        result = p.build(values).modes(2)
        for r in p.references(values, result):
            if r["family"] == "flapwise" and r["order"] == 1:
                rows.append({"ratio": ratio, "formula": r["formula"], "fem_hz": r["fem_hz"], "value_hz": r["value_hz"],
                             "rel_pct": 100 * r["rel_diff"]})
    parts += ["### Tip mass: FEM vs the two forms of (3.10) (first flapwise mode, nu = 0)", "",
              "The printed (3.10) puts the factor lambda L on the 1 + cos cosh term; the standard form "
              "(SOURCE-NOTES item 1) agrees with the FEM.", "",
              markdown_table(rows, [("ratio", "m/(rho A L)", "g"), ("formula", "formula", ""), ("fem_hz", "FEM [Hz]", ".6g"),
                                    ("value_hz", "formula [Hz]", ".6g"), ("rel_pct", "FEM - formula [%]", "+.2f")]), ""]
    return "\n".join(parts)
