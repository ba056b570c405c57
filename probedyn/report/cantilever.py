"""Report section: the plain cantilever (source section 2.3, eqs 2.36-2.46, 3.1-3.3, 3.10).

FEM vs beam theory (nu = 0, where beam theory is the exact slender limit, and the material's
nu), the static tip stiffness, the lumped model at the tip, the mode pictures of the model in
the table, and the tip-mass table with both forms of (3.10)."""

from __future__ import annotations

from pathlib import Path

from probedyn.fem.eigen import reuse_factorizations
from probedyn.fem.render import render_panel
from probedyn.lumped.compare import comparison_rows
from probedyn.lumped.reduce import reduce_modes
from probedyn.plotting import fmt_hz, fmt_um
from probedyn.probes import get_probe
from probedyn.report._tables import markdown_table

COMPARE_COLS = [("mode", "mode", ""), ("family", "family", ""), ("formula", "formula", ""),
                ("fem_hz", "FEM", "hz6"), ("value_hz", "formula", "hz6"), ("rel_pct", "FEM - formula [%]", "+.3f")]
LUMPED_COLS = [("mode", "mode", ""), ("family", "family", ""), ("direction", "dir", ""),
               ("frequency_hz", "f", "hz6"), ("mass", "m_eff [kg]", ".4e"),
               ("stiffness", "k_eff [N/m]", ".5g"), ("damping", "c_eff [N s/m]", ".3e")]


def draw_modes(result, path: Path) -> Path:
    """The first four modes of ``result`` on a 2x2 panel (off-screen VTK), titles with fmt_hz."""
    titles = [f"mode {m.index}: {m.family}, {fmt_hz(m.frequency_hz)}" for m in result.modes[:4]]
    return render_panel(result, path, titles=titles)


def section(outdir: Path, quick: bool) -> str:
    # one factorisation of K per stiffness: the static stiffness and the tip-mass cases (a point
    # mass changes only M) reuse the factor of the modal solve (same K, same arithmetic)
    with reuse_factorizations():
        return _section(outdir, quick)


def _section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    p, _ = get_probe("cantilever")
    mesh = {"elements_through_thickness": 2 if quick else 3}
    parts = []
    for nu in (0.0, None):
        over = {**mesh, "youngs_modulus": 169e9, "density": 2330.0}
        if nu is not None:
            over["poisson_ratio"] = nu
        values = p.resolve(over)
        model = p.build(values)
        result = model.modes(8)
        rows = [{**r, "rel_pct": 100 * r["rel_diff"]} for r in comparison_rows(p, values, result)]
        nu_txt = "0" if nu == 0 else f"{p.material(values).isotropic_constants()[1]:g} (material)"
        parts += [f"### FEM vs beam theory, L = {fmt_um(values['length'])}, w = {fmt_um(values['width'])}, "
                  f"t = {fmt_um(values['thickness'])}, E = 169 GPa, nu = {nu_txt}", "",
                  f"{result.dofs} DOFs, {model.element_kind.title}, assembly {result.timings.get('assemble_s', float('nan')):.1f} s, "
                  f"eigen-solution {result.timings.get('solve_s', float('nan')):.1f} s ({result.solver}).", "",
                  markdown_table(rows, COMPARE_COLS), ""]
        st = p.static_stiffness(values, model)
        parts += [f"Static tip stiffness (free-end face, z): FEM {st['fem_n_per_m']:.5g} N/m; "
                  f"3EI/L^3 = {st['euler_bernoulli_3EI_L3']:.5g} N/m; with Timoshenko shear correction "
                  f"{st['with_shear_correction']:.5g} N/m (FEM {100 * (st['fem_n_per_m'] / st['with_shear_correction'] - 1):+.3f} %).", ""]
        if nu is None:
            lumped = reduce_modes(result, Q=100.0, total_mass=result.total_mass)
            parts += ["### Lumped model at the tip (eqs 3.1-3.3 generalised; damping from Q = 100)", "",
                      markdown_table([lm.to_dict() for lm in lumped], LUMPED_COLS), ""]
            try:
                draw_modes(result, outdir / "cantilever_modes.png")
                parts += ["![first four modes of the default cantilever](cantilever_modes.png)", "",
                          f"*First four modes of the FEM model of the two tables above (nu = {nu_txt}, "
                          f"{result.dofs} DOFs); colour: displacement magnitude normalised per mode, grey: undeformed.*", ""]
            except Exception as exc:  # a missing GL library must not sink the whole report
                parts += [f"(mode pictures skipped: {exc})", ""]

    # tip mass: FEM vs both forms of (3.10)
    rows = []
    values0 = p.resolve({**mesh, "poisson_ratio": 0.0})
    b = p.beam(values0)
    m_beam = b.rho * b.w * b.t * b.L
    for ratio in ((1.0,) if quick else (0.2, 1.0, 5.0)):
        values = p.resolve({**mesh, "poisson_ratio": 0.0, "tip_mass": ratio * m_beam})
        result = p.build(values).modes(2)
        for r in p.references(values, result):
            if r["family"] == "flapwise" and r["order"] == 1:
                rows.append({"ratio": ratio, "formula": r["formula"], "fem_hz": r["fem_hz"], "value_hz": r["value_hz"],
                             "rel_pct": 100 * r["rel_diff"]})
    parts += ["### Tip mass: FEM vs the two forms of (3.10) (first flapwise mode, nu = 0)", "",
              "The printed (3.10) puts the factor lambda L on the 1 + cos cosh term; the standard form "
              "(departure 1) agrees with the FEM.", "",
              markdown_table(rows, [("ratio", "m/(rho A L)", "g"), ("formula", "formula", ""), ("fem_hz", "FEM", "hz6"),
                                    ("value_hz", "formula", "hz6"), ("rel_pct", "FEM - formula [%]", "+.2f")]), ""]
    return "\n".join(parts)
