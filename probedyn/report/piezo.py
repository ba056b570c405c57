"""Report section: piezoelectric actuation of the smart probes (issue 12; source 3.4.2, 3.5.1).

* the bimorph reference: coupled FEM vs laminate theory (series and parallel, plane strain,
  with and without the induced potential);
* ``piezo-duo-range.png`` (Fig 3.17 counterpart): duo-bimorph deflection per volt vs the
  electrode gap w0 and the thickness h, eqs 3.31/3.32 as curves, FEM points on them;
* ``piezo-tube-range.png`` (Fig 3.18): piezotube lateral and axial deflection per volt vs L and
  Re, printed 3.34 (twice too large), corrected 3.34, thick-wall form, 3.35, FEM points;
* ``piezo-gamma.png`` (Fig 3.20): lambda_min of the normalised coupling matrix Gamma vs the
  eccentricity delta_x = delta_y, corrected 3.38-3.44 as a curve, FEM points; the Gamma tables.

Meshes are coarse and FEM points few (one per panel; none for Gamma in quick mode) so that the
section takes a few seconds; their accuracy, measured against converged meshes, is stated in
the captions (docs/piezo.md has the converged studies and the FEM on every point).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from probedyn.core.presets import preset
from probedyn.fem.piezo_benchmarks import bimorph_cantilever, bimorph_drive
from probedyn.fem.piezo_materials import get_piezo_material
from probedyn.lumped import actuation as act
from probedyn.plotting import axis_label, pyplot, savefig
from probedyn.probes.piezo import gamma_study, range_point

#: coarse meshes of the section and their measured bias (docs/piezo.md, "report meshes")
DUO_MESH = {"element_size": 15e-6}
TUBE_MESH = {"element_size": 400e-6}


def _table(rows: list[dict[str, Any]], cols: Sequence[tuple[str, str, str]]) -> str:
    head = "| " + " | ".join(h for _, h, _ in cols) + " |"
    sep = "|" + "|".join("---:" for _ in cols) + "|"
    body = []
    for r in rows:
        cells = []
        for k, _, spec in cols:
            v = r.get(k)
            cells.append("–" if v is None else (format(v, spec) if spec and isinstance(v, (int, float)) else str(v)))
        body.append("| " + " | ".join(cells) + " |")
    return "\n".join([head, sep, *body])


# ---------------------------------------------------------------------------------------------
# bimorph reference
# ---------------------------------------------------------------------------------------------

def bimorph_rows() -> list[dict[str, Any]]:
    """Plane-strain bimorph (L/h = 20, beam-theory clamp): FEM vs laminate theory."""
    h, L = 0.1e-3, 2e-3
    rows = []
    for config in ("series", "parallel"):
        pm = bimorph_cantilever(L, 0.05e-3, h, nx=20, ny=1, nz_layer=1, config=config, clamp="sliding",
                                plane_strain=True)
        st, others = bimorph_drive(config)
        r = pm.static(st, others=others)
        fem = r.displacement_at("x1")[2]
        ref = act.bimorph_tip_deflection(L, h, "pzt-5h", config, "plane_strain")
        cla = act.bimorph_tip_deflection(L, h, "pzt-5h", config, "plane_strain", induced_potential=False)
        rows.append({"config": config, "dofs": r.dofs, "fem": fem * 1e9, "clt": ref * 1e9, "classic": cla * 1e9,
                     "rel": fem / ref - 1, "rel_classic": fem / cla - 1})
    return rows


# ---------------------------------------------------------------------------------------------
# range figures (3.17, 3.18)
# ---------------------------------------------------------------------------------------------

def duo_range_figure(path: Path, quick: bool) -> tuple[Path, list[dict[str, Any]]]:
    d31 = abs(float(get_piezo_material("pzt-5h").d[2, 0]))
    L, w, h0, g0 = 300e-6, 30e-6, 10e-6, 5e-6
    plt = pyplot()
    fig, axs = plt.subplots(1, 2, figsize=(10.5, 4.2), layout="constrained")
    pts = []
    gaps = np.linspace(0.5e-6, 20e-6, 80)
    hs = np.linspace(4e-6, 20e-6, 80)
    fg = [act.duo_bimorph_range(L, w, h0, g, d31) for g in gaps]
    fh = [act.duo_bimorph_range(L, w, h, g0, d31) for h in hs]
    for ax, x, f, xl in ((axs[0], gaps, fg, "electrode gap w0"), (axs[1], hs, fh, "thickness h")):
        ax.plot(x * 1e6, [r["dz"] * 1e9 for r in f], "C0-", label="ΔZ per volt, eq 3.32")
        ax.plot(x * 1e6, [r["dy"] * 1e9 for r in f], "C1-", label="ΔY per volt, eq 3.31")
        ax.set_xlabel(axis_label(xl, "um"))
        ax.set_ylabel(axis_label("deflection at x = L per volt", "nm/V"))
    fem_gaps = [10e-6]
    fem_hs = [] if quick else [14e-6]
    for key, vals, ax in (("electrode_gap", fem_gaps, axs[0]), ("thickness", fem_hs, axs[1])):
        for v in vals:
            r = range_point("duo-bimorph", {**DUO_MESH, key: v})
            pv = r["per_volt"]
            ax.plot(v * 1e6, pv["V_z"][2] * 1e9, "C0o", mfc="none")
            ax.plot(v * 1e6, pv["V_y"][1] * 1e9, "C1s", mfc="none")
            f = act.duo_bimorph_range(L, w, v if key == "thickness" else h0, v if key == "electrode_gap" else g0, d31)
            pts.append({"parameter": key, "value_um": v * 1e6, "fem_z": pv["V_z"][2] * 1e9, "eq_3_32": f["dz"] * 1e9,
                        "ratio_z": pv["V_z"][2] / f["dz"], "fem_y": pv["V_y"][1] * 1e9, "eq_3_31": f["dy"] * 1e9,
                        "ratio_y": pv["V_y"][1] / f["dy"], "dofs": r["dofs"]})
    for ax in axs:
        ax.plot([], [], "ko", mfc="none", label="coupled FEM (V_z: circles, V_y: squares)")
        ax.legend()
    axs[0].set_title("h = 10 µm, w = 30 µm, L = 300 µm")
    axs[1].set_title("w0 = 5 µm, w = 30 µm, L = 300 µm")
    fig.suptitle("Duo-bimorph range per volt (PZT-5H, d31 = -274 pC/N), bare actuator (holder as a point)")
    return savefig(fig, path), pts


def tube_range_figure(path: Path, quick: bool) -> tuple[Path, list[dict[str, Any]]]:
    d31 = float(get_piezo_material("pzt-5h").d[2, 0])
    L0, Re0, t = 5e-3, 0.5e-3, 50e-6
    plt = pyplot()
    fig, axs = plt.subplots(1, 2, figsize=(10.5, 4.2), layout="constrained")
    Ls = np.linspace(2e-3, 10e-3, 80)
    Res = np.linspace(0.25e-3, 1.0e-3, 80)
    pts = []
    for ax, x, geo, xl in ((axs[0], Ls, lambda v: (v, Re0), "tube length L"),
                           (axs[1], Res, lambda v: (L0, v), "outer radius Re (wall 50 µm)")):
        g = [geo(v) for v in x]
        ax.plot(x * 1e3, [act.tube_lateral_per_volt(a, b, b - t, d31, "printed") * 1e9 for a, b in g], "C3--",
                label="lateral, eq 3.34 as printed")
        ax.plot(x * 1e3, [act.tube_lateral_per_volt(a, b, b - t, d31, "thin") * 1e9 for a, b in g], "C0-",
                label="lateral, 3.34 corrected (diameter)")
        ax.plot(x * 1e3, [act.tube_axial_per_volt(a, b, b - t, d31, "thin") * 1e9 for a, b in g], "C2-",
                label="axial, eq 3.35")
        ax.set_xlabel(axis_label(xl, "mm"))
        ax.set_ylabel(axis_label("tube-end deflection per volt", "nm/V"))
        ax.set_yscale("log")
    fem_L = [8e-3]
    fem_R = [] if quick else [0.75e-3]
    for key, vals, ax in (("length", fem_L, axs[0]), ("Re", fem_R, axs[1])):
        for v in vals:
            ov = {**TUBE_MESH, key: v}
            if key == "Re":
                ov["Ri"] = v - t
            r = range_point("piezotube", ov)
            pv = r["per_volt"]
            a, b = (v, Re0) if key == "length" else (L0, v)
            ax.plot(v * 1e3, pv["V_x"][2] * 1e9, "C0o", mfc="none")
            ax.plot(v * 1e3, pv["V_z"][0] * 1e9, "C2s", mfc="none")
            pts.append({"parameter": key, "value_mm": v * 1e3,
                        "fem_lat": pv["V_x"][2] * 1e9,
                        "corrected": act.tube_lateral_per_volt(a, b, b - t, d31, "thin") * 1e9,
                        "printed": act.tube_lateral_per_volt(a, b, b - t, d31, "printed") * 1e9,
                        "fem_ax": pv["V_z"][0] * 1e9, "eq_3_35": act.tube_axial_per_volt(a, b, b - t, d31) * 1e9,
                        "dofs": r["dofs"]})
    for ax in axs:
        ax.plot([], [], "ko", mfc="none", label="coupled FEM (lateral: circles, axial: squares)")
        ax.legend(fontsize="x-small")
    axs[0].set_title("Re = 0.5 mm, Ri = 0.45 mm")
    axs[1].set_title("L = 5 mm, Ri = Re - 50 µm")
    fig.suptitle("Piezotube range per volt (PZT-5H, d31 = -274 pC/N; quarters at ∓V, inner grounded)")
    return savefig(fig, path), pts


def _tube_preset() -> tuple[float, float, float]:
    t = preset("table-3.2")
    return t["R_e"], t["R_i"], t["L"]


def gamma_figure(path: Path, quick: bool) -> tuple[Path, list[dict[str, Any]]]:
    Re, Ri, L = _tube_preset()
    ds = np.linspace(0.0, 5e-6, 41)
    lam = [act.gamma_matrix(Re, Ri, L, d, d).lambda_min() for d in ds]
    sym = [act.gamma_matrix(Re, Ri, L, d, d).symmetric_part_min() for d in ds]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4), layout="constrained")
    ax.plot(ds * 1e6, lam, "C0-", label="λ_min(Γ), corrected 3.38–3.44")
    ax.plot(ds * 1e6, sym, "C1-", label="λ_min((Γ + Γᵀ)/2), corrected 3.38–3.44")
    rows = [] if quick else gamma_study([5e-6], TUBE_MESH)
    for r in rows:
        ax.plot(r["delta"] * 1e6, r["fem"].lambda_min(), "C0o", mfc="none")
        ax.plot(r["delta"] * 1e6, r["fem"].symmetric_part_min(), "C1s", mfc="none")
    if rows:
        ax.plot([], [], "ko", mfc="none", label="coupled FEM")
    ax.set_xlabel(axis_label("eccentricity δx = δy", "um"))
    ax.set_ylabel("smallest eigenvalue of the normalised Γ")
    ax.set_title("Piezotube Re = 0.5 mm, Ri = 0.45 mm, L = 5 mm")
    ax.legend()
    return savefig(fig, path), rows


# ---------------------------------------------------------------------------------------------
# the section
# ---------------------------------------------------------------------------------------------

def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    parts = ["Coupled piezoelectric FEM (displacement + potential, P2 tetrahedra, PZT-5H e-form from the "
             "d-form data of Berlincourt et al. 1964; electrodes grounded, driven or floating). "
             "Formulation, materials, solver measurements and the converged studies: `docs/piezo.md`.", ""]
    # bimorph
    rows = bimorph_rows()
    parts += ["### Bimorph cantilever: FEM vs laminate theory", "",
              "Two PZT-5H layers, h = 0.1 mm, L = 2 mm, plane strain (a slice of a wide plate in cylindrical "
              "bending), beam-theory clamp. Laminate theory with the induced potential (the quadratic potential "
              "that bending makes in each voltage-held layer) vs the classic linear-potential formula.", "",
              _table(rows, [("config", "drive", ""), ("dofs", "DOFs", "d"), ("fem", "FEM [nm/V]", ".5g"),
                            ("clt", "laminate theory [nm/V]", ".5g"), ("rel", "FEM/theory - 1", "+.2e"),
                            ("classic", "classic [nm/V]", ".5g"), ("rel_classic", "FEM/classic - 1", "+.3f")]), ""]
    # duo range
    p, pts = duo_range_figure(outdir / "piezo-duo-range.png", quick)
    parts += ["### Duo-bimorph range (Fig 3.17)", "", f"![duo-bimorph range]({p.name})", "",
              "Curves: eqs 3.31/3.32 (beam theory, linear potential; confirmed by their derivation) with PZT-5H's "
              "d31 (Table 3.1's 185 pC/N would scale them by 0.675). Points: coupled FEM of the bare actuator "
              f"(holder as a point), structured mesh of {DUO_MESH['element_size'] * 1e6:g} µm (1 % below the "
              "5 µm mesh). V_z: all four outer electrodes at -V, middle grounded, both layers poled +z; "
              "V_y: upper-left/lower-right at -V, upper-right/lower-left at +V.", "",
              _table(pts, [("parameter", "varied", ""), ("value_um", "value [µm]", "g"), ("fem_z", "FEM ΔZ", ".4g"),
                           ("eq_3_32", "3.32", ".4g"), ("ratio_z", "ratio", ".3f"), ("fem_y", "FEM ΔY", ".4g"),
                           ("eq_3_31", "3.31", ".4g"), ("ratio_y", "ratio", ".3f")]), "",
              "ΔZ: the induced potential lowers the FEM by 11 % (w0 -> 0); the gap strip between electrodes at "
              "the same potential is partly actuated by the fringing field, which 3.32's (w - w0)/w ignores, so "
              "the ratio grows with w0. ΔY: no induced potential for bending across the width; 3.31 holds "
              "within a few per cent.", ""]
    # tube range
    p, pts = tube_range_figure(outdir / "piezo-tube-range.png", quick)
    parts += ["### Piezotube range (Fig 3.18) and the factor 2 of eq 3.34", "", f"![piezotube range]({p.name})", "",
              "Eq 3.34 as printed, with the outer radius where the standard form has the diameter, is twice the "
              "FEM; the corrected form sqrt(2) d31 L^2 V / (pi R t) and 3.35 agree with it. FEM points: "
              f"element size {TUBE_MESH['element_size'] * 1e3:g} mm, 12 elements around the circumference (about "
              "+3 % lateral, +2 % axial against the converged FEM, which is within 1 % of the thick-wall "
              "formulas).", "",
              _table(pts, [("parameter", "varied", ""), ("value_mm", "value [mm]", "g"), ("fem_lat", "FEM lateral", ".4g"),
                           ("corrected", "3.34 corrected", ".4g"), ("printed", "3.34 printed", ".4g"),
                           ("fem_ax", "FEM axial", ".4g"), ("eq_3_35", "3.35", ".4g")]), ""]
    # gamma
    p, rows = gamma_figure(outdir / "piezo-gamma.png", quick)
    Re, Ri, L = _tube_preset()
    F = act.gamma_matrix(Re, Ri, L, 5e-6, 5e-6)
    parts += ["### Eccentricity coupling Γ (3.38–3.44, Fig 3.20)", "", f"![Gamma]({p.name})", "",
              "Γ maps the inputs (u_x, u_y, u_z) to the tube-end displacement; normalised by the concentric tube's "
              "diagonal (identity without eccentricity). The printed 3.39–3.44 cannot be evaluated as printed "
              "(dimensionally wrong radii) and, with cos(θ + θ_δ), rotate the lateral block by θ_δ; the corrected "
              "model (`probedyn.lumped.actuation.gamma_matrix`) agrees with the FEM "
              "(`probedyn.probes.piezo.gamma_matrix_fem`).", "",
              "Corrected formula, δx = δy = 5 µm (normalised):", "",
              "\n".join("    " + "  ".join(f"{v:+.4f}" for v in row) for row in F.normalised), ""]
    for r in rows:
        parts += [f"FEM ({TUBE_MESH['element_size'] * 1e3:g} mm elements), δx = δy = {r['delta'] * 1e6:g} µm:", "",
                  "\n".join("    " + "  ".join(f"{v:+.4f}" for v in row) for row in r["fem"].normalised), ""]
    parts += [f"λ_min = {F.lambda_min():.4f} (formula)" + (f", {rows[-1]['fem'].lambda_min():.4f} (FEM)" if rows else "")
              + f"; the symmetric part stays positive definite (smallest eigenvalue {F.symmetric_part_min():.4f}).", ""]
    return "\n".join(parts)
