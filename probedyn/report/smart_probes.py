"""Report section: the smart probes, duo-bimorph and piezotube (source sections 3.2-3.5).

Per probe: the first four modes of body + holder (Fig 3.15 counterpart) beside the analytic
table of the same model, the lumped model (3.4 / 3.20 / 3.37) from FEM body modes vs the FEM of
the assembled probe, the holder-stiffness sweep of section 3.4.1 (table and
``<probe>-localisation.png``), PZT-5H vs isotropic E = 1/s11, the table vs geometric holder
mass; then the piezotube eccentricity (``piezotube-eccentricity.png``). The figure functions
of ``probedyn localisation --out`` and ``probedyn eccentricity --out`` live here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.io import make_dirs, write_json
from probedyn.fem.render import render_panel
from probedyn.lumped.holder_sweep import lumped_holder_sweep, pair_by_family
from probedyn.plotting import axis_label, fmt_hz, fmt_um, pyplot, savefig
from probedyn.probes import get_probe
from probedyn.probes import studies as S
from probedyn.report._tables import markdown_table

LUMPED_COLS = [("group", "group", ""), ("n", "n", ""), ("fem_mode", "FEM mode", ""), ("fem_hz", "FEM", "hz6"),
               ("lumped_hz", "lumped", "hz6"), ("rel_diff", "rel. diff", "+.2e"),
               ("predicted_error", "predicted", ".2e"), ("tolerance", "tolerance", ".2e"), ("within", "within", ""),
               ("valid", "valid", "")]
PAR_COLS = [("direction", "dir", ""), ("M", "M_i [kg]", ".4g"), ("k", "k_i [N/m]", ".5g"), ("c", "c_i [N s/m]", ".3g"),
            ("k_t", "k_t [N/m]", "g"), ("m", "m [kg]", ".3g"), ("f_body_hz", "f_i", "hz6")]
LOC_COLS = [("k_t", "k_t [N/m]", "g"), ("mode", "mode", ""), ("frequency_hz", "f", "hz"), ("direction", "dir", ""),
            ("ke_tip", "KE tip", ".3f"), ("ke_holder_tip", "KE holder+tip", ".4f"), ("ke_body", "KE body", ".2e"),
            ("se_holder_spring", "SE holder spring", ".3f")]
ECC_COLS = [("delta_um", "|delta| [µm]", "g"), ("f_low_hz", "f low", "hz7"), ("f_high_hz", "f high", "hz7"),
            ("split", "split", ".3e"), ("split_predicted", "split EB", ".3e"), ("angle_low_deg", "angle low [°]", ".3f"),
            ("angle_predicted_deg", "angle EB [°]", ".1f"), ("coupling_yz", "K_yz/sqrt(K_yy K_zz)", "+.3e"),
            ("coupling_axial_lateral", "axial-lateral coupling", ".3e"), ("centroid_um", "centroid offset [µm]", ".3g")]
MAT_COLS = [("mode", "mode", ""), ("family", "family", ""), ("aniso_hz", "PZT-5H", "hz6"),
            ("iso_hz", "iso E=1/s11", "hz6"), ("rel_diff", "rel. diff", "+.3e")]
REF_COLS = [("mode", "mode", ""), ("direction", "dir", ""), ("n", "n", ""), ("formula", "formula", ""),
            ("fem_hz", "FEM", "hz6"), ("value_hz", "formula", "hz6"), ("rel_diff", "rel. diff", "+.4f")]
HOLDER_COLS = [("family", "family", ""), ("order", "n", ""), ("f_a", "f, table m_h", "hz6"),
               ("f_b", "f, geometric holder mass", "hz6"), ("ratio", "ratio", ".3f")]

QUICK_MESH = {"duo-bimorph": {"element_size": 10e-6}, "piezotube": {"element_size": 400e-6}}

#: relative frequency difference below which two modes of one direction group are a degenerate pair
DEGENERATE = 1e-5


# ---------------------------------------------------------------------------------------------
# figures (also used by the commands' --out)
# ---------------------------------------------------------------------------------------------


def _tracks(rows: list[dict], ks: list[float]) -> list[tuple[list[int], str]]:
    """Modes of the sweep as curves: a degenerate pair (same direction, equal frequency at every
    k) is one curve ``([1, 2], "modes 1, 2 (degenerate lateral pair)")``."""
    nm = max(r["mode"] for r in rows)
    at = {(r["k_t"], r["mode"]): r for r in rows}
    tracks: list[list[int]] = []
    for mode in range(1, nm + 1):
        prev = tracks[-1][-1] if tracks else None
        if prev is not None and all(
                at[(k, mode)]["direction"] == at[(k, prev)]["direction"]
                and abs(at[(k, mode)]["frequency_hz"] / at[(k, prev)]["frequency_hz"] - 1) < DEGENERATE for k in ks):
            tracks[-1].append(mode)
        else:
            tracks.append([mode])
    out = []
    for t in tracks:
        d = at[(ks[0], t[0])]["direction"]
        out.append((t, f"modes {', '.join(map(str, t))} (degenerate {d} pair)" if len(t) > 1 else f"mode {t[0]}"))
    return out


def plot_localisation(rows: list[dict], path: Path, title: str, lumped: dict | None = None,
                      n_tracks: int = 3) -> Path:
    """Left: strain-energy share of the holder spring and kinetic-energy share of the tip for the
    lowest modes (a degenerate pair drawn once) vs the holder stiffness; right: FEM frequencies
    (markers, every mode solved) and the lowest modes of the lumped model (lines, as many as
    the FEM solved)."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 5.2))
    ks = sorted({r["k_t"] for r in rows})
    at = {(r["k_t"], r["mode"]): r for r in rows}
    sizes = (9, 6, 3.5)
    for j, (modes, label) in enumerate(_tracks(rows, ks)[:n_tracks]):
        sel = [at[(k, modes[0])] for k in ks]
        c = f"C{j}"
        a1.semilogx(ks, [r["se_holder_spring"] for r in sel], "o-", color=c, ms=sizes[j], mfc="none", label=label)
        a1.semilogx(ks, [r["ke_tip"] for r in sel], "s--", color=c, ms=sizes[j] * 0.7, alpha=0.8)
    # line-style key: solid = strain energy in the holder spring, dashed = kinetic energy in the tip
    a1.plot([], [], "ko-", mfc="none", label="strain energy in holder spring")
    a1.plot([], [], "ks--", ms=4, label="kinetic energy in tip")
    a1.set_xlabel(axis_label("holder stiffness k_t", "N/m"))
    a1.set_ylabel("energy share of the mode")
    a1.set_ylim(-0.02, 1.02)
    a1.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    a1.set_title(f"{title}: where the mode's energy sits")
    nm = max(r["mode"] for r in rows)
    markers = ("o", "x", "+", "s", "^", "v", "d", "*")
    for mode in range(1, nm + 1):  # open markers of decreasing size: coincident modes stay visible
        a2.loglog(ks, [at[(k, mode)]["frequency_hz"] for k in ks], markers[(mode - 1) % len(markers)],
                  ms=max(11 - 1.5 * mode, 4), mfc="none", mew=1.3, color=f"C{mode - 1}", label=f"FEM mode {mode}")
    if lumped:
        kk = np.array(lumped["k"])
        F = np.array(lumped["f"])
        for j in lumped_in_range(lumped, rows):
            a2.loglog(kk, F[:, j], "-", color="grey", lw=0.8, label="lumped model" if j == 0 else None)
    a2.set_xlabel(axis_label("holder stiffness k_t", "N/m"))
    a2.set_ylabel(axis_label("frequency", "Hz"))
    a2.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3)
    a2.set_title("FEM (markers) vs lumped model (lines)")
    fig.tight_layout()
    return savefig(fig, path)


def lumped_in_range(lumped: dict, rows: list[dict], margin: float = 1.05) -> list[int]:
    """Indices of the lumped modes that come within ``margin`` of the highest FEM frequency of the
    sweep somewhere on it: the lines that have FEM markers to compare with."""
    top = margin * max(r["frequency_hz"] for r in rows)
    F = np.array(lumped["f"])
    return [j for j in range(F.shape[1]) if float(F[:, j].min()) <= top]


def plot_eccentricity(rows: list[dict], path: Path) -> Path:
    """Relative split of the piezotube's lateral pair vs the bore offset: FEM and the
    Euler-Bernoulli prediction of the exact eccentric section."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    d = [r["delta"] * 1e6 for r in rows]
    ax.plot(d, [r["split"] for r in rows], "o-", label="FEM split f_high/f_low - 1")
    ax.plot(d, [r["split_predicted"] for r in rows], "k--", label="Euler-Bernoulli, exact eccentric section")
    ax.set_xlabel(axis_label("bore offset |delta|", "um"))
    ax.set_ylabel("relative split of the lateral pair")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return savefig(fig, path)


def eccentricity_rows(rows: list[dict]) -> list[dict]:
    """The rows of :func:`probedyn.probes.studies.study_eccentricity` with offsets in µm for tables."""
    return [{**r, "delta_um": r["delta"] * 1e6, "centroid_um": r["centroid_offset"] * 1e6} for r in rows]


def draw_modes(result, path: Path, what: str) -> str:
    """Fig 3.15 counterpart: the first four modes of ``result`` (a 2x2 panel); Markdown image
    with a caption naming the model, or a note when no off-screen GL library is there."""
    titles = [f"mode {m.index}: {m.family}, {fmt_hz(m.frequency_hz)}" for m in result.modes[:4]]
    try:
        render_panel(result, path, titles=titles)
    except Exception as exc:  # no OpenGL: report it, keep the numbers
        return f"(mode panel not rendered: {str(exc).splitlines()[0]})"
    return (f"![First four modes: {what}]({Path(path).name})\n\n*First four modes of the {what} "
            f"(FEM, {result.model.element_kind.title}, {result.dofs} DOFs): the model of the analytic table below; colour: displacement "
            "magnitude normalised per mode, grey: undeformed.*")


def _pair_orders(rows: list[dict], group: tuple[str, ...], value: str, out_key: str = "n") -> list[dict]:
    """Number rows by mode order within their group (``group`` keys): the partner of a degenerate
    pair (the same ``value`` within DEGENERATE as the row before it in the group) keeps the
    order of its partner, marked "(pair)"."""
    out, seen = [], {}
    for r in rows:
        vals = seen.setdefault(tuple(r[k] for k in group), [])
        if vals and abs(r[value] / vals[-1] - 1) < DEGENERATE:
            n = f"{len(vals)} (pair)"
        else:
            vals.append(r[value])
            n = str(len(vals))
        out.append({**r, out_key: n})
    return out


def _reference_orders(rows: list[dict]) -> list[dict]:
    """Analytic rows numbered by the formula's mode order n (a degenerate partner compares with
    the same analytic value and keeps its partner's n)."""
    return _pair_orders(rows, ("direction", "formula"), "value_hz")


# ---------------------------------------------------------------------------------------------
# section
# ---------------------------------------------------------------------------------------------


def section(outdir: Path, quick: bool = False) -> str:
    outdir = Path(outdir)
    make_dirs(outdir)
    ks = [1.0, 100.0] if quick else [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
    deltas = [0.0, 5e-6] if quick else [0.0, 1e-6, 2e-6, 3e-6, 4e-6, 5e-6]
    parts = ["Source sections 3.2-3.5. FEM: structured 20-node serendipity hexahedra (the default element, "
             "`docs/fem.md`; meshed tip cones: P2 tetrahedra), PZT-5H transversely isotropic (poled through the thickness "
             "in the bimorph, radially in the tube); tip lumped as mass m on the holder springs k_t; holder mass from "
             "Table 3.1/3.2 (m_h) unless stated. Three models appear below and each table and figure names its own: "
             "**body + holder** (no tip), the **assembled probe** (body + holder + tip mass on k_t) and the "
             "**lumped model** built from body + holder modes. Details and departures from the print: "
             "`docs/smart-probes.md`." + (" Quick mode: coarse meshes." if quick else "")]
    data: dict[str, Any] = {}
    for probe in ("duo-bimorph", "piezotube"):
        ov = dict(QUICK_MESH[probe]) if quick else {}
        parts.append(f"### {probe}")
        p, _ = get_probe(probe)
        v = p.resolve({**ov, "tip": "none"})
        res = S.solve_modes(p, v, 6 if probe == "duo-bimorph" else 4)  # memoised: the studies reuse this solve
        parts += ["", draw_modes(res, outdir / f"{probe}-modes.png", f"{probe} body + holder (no tip)"), ""]
        refs = _reference_orders(p.references(v, res))
        parts += [f"Analytic references for body + holder (no tip; holder mass {p.holder_mass(v):.3g} kg, "
                  f"geometric holder mass {p.holder_geometric_mass(v):.3g} kg); n is the order of the formula's mode"
                  + ("; the lateral modes come in degenerate pairs (y and z), each partner is compared with the "
                     "same analytic value" if probe == "piezotube" else "") + ":", "",
                  markdown_table(refs, REF_COLS), ""]
        lum = S.study_lumped(probe, ov)
        mu = lum["values"].get("mu")
        parts += ["Lumped model from FEM body modes (3.1-3.3 at the holder end face) vs FEM of the assembled probe "
                  "(tolerance = 2 x predicted truncation error + 1e-3, see `lumped/smart.py`). Damping c_i = mu x "
                  f"(modal mass share in the PZT body) / (rho A) with mu = {mu:g} N s/m^2"
                  + (" (Table 3.2 gives mu for the piezotube)" if mu else
                     " (Table 3.1 gives no damping for the duo-bimorph, so c_i = 0; set `--set mu=...` to add it)") + ":", "",
                  markdown_table(lum["lumped"]["parameters"], PAR_COLS), "",
                  markdown_table(_pair_orders(lum["rows"], ("group",), "lumped_hz"), LUMPED_COLS), ""]
        loc = S.study_localisation(probe, ks, ov)
        n_fem = max(r["mode"] for r in loc["rows"])
        curves = lumped_holder_sweep(lum["lumped"], ks, p.sweep_directions)
        drawn = lumped_in_range(curves, loc["rows"])
        above = [float(np.min(np.array(curves["f"])[:, j])) for j in range(len(curves["f"][0])) if j not in drawn]
        fig = plot_localisation(loc["rows"], outdir / f"{probe}-localisation.png", probe, curves)
        parts += [f"Section 3.4.1, holder stiffness sweep of the assembled probe (FEM, lowest {n_fem} modes; KE = kinetic "
                  "energy share, SE = strain energy share; dir \"-\": a torsion mode or no direction carrying 60 % of the "
                  "holder and tip motion):", "",
                  markdown_table(loc["rows"], LOC_COLS), "", f"![localisation]({fig.name})", "",
                  f"*{probe}, assembled probe: energy shares of the lowest modes (left; a degenerate pair is one curve) "
                  f"and frequencies (right) vs the holder stiffness k_t. Markers: FEM; lines: the lumped model of the "
                  f"table above, drawn for its modes that reach the frequency range of the {n_fem} FEM modes solved"
                  + (f" (its modes from {fmt_hz(min(above))} up lie above that range and are not drawn)" if above else "")
                  + "."
                  + (" Modes with dir \"-\" (torsion) have no counterpart in the lumped model: where one is among the "
                     f"lowest {n_fem} FEM modes, a FEM marker has no line and the highest line no marker."
                     if any(r["direction"] == "-" for r in loc["rows"]) else "") + "*", ""]
        mat = S.study_materials(probe, {**ov, "tip": "none"})
        parts += ["Transversely isotropic PZT-5H vs isotropic E = 1/s11 (body + holder):", "",
                  markdown_table(mat["rows"], MAT_COLS), ""]
        hm = S.study_holder_mass(probe, ov)
        pairs = pair_by_family([(r["family_table"], r["table_hz"]) for r in hm["rows"]],
                               [(r["family_geometry"], r["geometry_hz"]) for r in hm["rows"]])
        parts += [f"Holder mass (departure 5): table m_h = {hm['holder_mass']['table']:.3g} kg vs holder geometry "
                  f"{hm['holder_mass']['geometry']:.3g} kg (set `holder_mass_source`); lowest {len(hm['rows'])} modes of "
                  "body + holder with each, paired by family and order (\"–\": no mode of that family among them):", "",
                  markdown_table(pairs, HOLDER_COLS), ""]
        data[probe] = {"holder_mass": hm, "references": refs, "lumped": lum["rows"], "localisation": loc["rows"],
                       "materials": mat["rows"]}
    ecc = S.study_eccentricity(deltas, 45.0, QUICK_MESH["piezotube"] if quick else {})
    rows = eccentricity_rows(ecc["rows"])
    fig = plot_eccentricity(rows, outdir / "piezotube-eccentricity.png")
    parts += [f"### Piezotube eccentricity (bore offset along 45°, as delta_x = delta_y in section 3.5.4; up to "
              f"{fmt_um(max(deltas))})", "",
              markdown_table(rows, ECC_COLS), "", f"![eccentricity]({fig.name})", "",
              "*Piezotube body + holder (no tip), FEM: relative split of the lateral pair vs the bore offset, beside the "
              "Euler-Bernoulli prediction with the exact eccentric cross-section.*", ""]
    data["eccentricity"] = rows
    write_json(outdir / "smart-probes.json", data)
    return "\n".join(parts)
