"""Commands of the smart probes (duo-bimorph, piezotube; source sections 3.2-3.5) and their
report section.

* ``probedyn smart-lumped PROBE``: the lumped model (3.4 / 3.20 / 3.37) assembled from FEM body
  modes vs the FEM of the assembled probe;
* ``probedyn localisation PROBE``: section 3.4.1, holder stiffness sweep (energy shares);
* ``probedyn eccentricity``: piezotube bore offset, split and tilt of the lateral pair (3.38-3.44);
* ``probedyn smart-materials PROBE``: transversely isotropic PZT-5H vs isotropic E = 1/s11;
* ``probedyn smart-convergence PROBE``: mesh convergence of the first four frequencies.

The generic ``probedyn modes|compare|reduce|render|params duo-bimorph|piezotube`` come from
:mod:`probedyn.commands.modal` through the probe registry.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, markdown_table, save

PROBE_ARG = typer.Argument(..., help="duo-bimorph, piezotube, or a TOML probe file")


def _mpl():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _floats(spec: str, name: str) -> list[float]:
    from probedyn.core.errors import ParameterError

    try:
        vals = [float(s) for s in spec.split(",") if s.strip()]
    except ValueError:
        raise ParameterError(f"--{name} expects comma-separated numbers, got {spec!r}") from None
    if not vals or any(not math.isfinite(v) for v in vals):
        raise ParameterError(f"--{name} expects comma-separated finite numbers, got {spec!r}")
    return vals


def _sets(items) -> dict[str, str]:
    from probedyn.core.params import parse_sets

    return parse_sets(items)


# ---------------------------------------------------------------------------------------------
# tables and figures (shared by the commands and the report)
# ---------------------------------------------------------------------------------------------

LUMPED_COLS = [("group", "group", ""), ("order", "n", ""), ("fem_mode", "FEM mode", ""), ("fem_hz", "FEM [Hz]", ".6g"),
               ("lumped_hz", "lumped [Hz]", ".6g"), ("rel_diff", "rel. diff", "+.2e"),
               ("predicted_error", "predicted", ".2e"), ("tolerance", "tolerance", ".2e"), ("within", "within", ""),
               ("valid", "valid", "")]
PAR_COLS = [("direction", "dir", ""), ("M", "M_i [kg]", ".4g"), ("k", "k_i [N/m]", ".5g"), ("c", "c_i [N s/m]", ".3g"),
            ("k_t", "k_t [N/m]", "g"), ("m", "m [kg]", ".3g"), ("f_body_hz", "f_i [Hz]", ".6g")]
LOC_COLS = [("k_t", "k_t [N/m]", "g"), ("mode", "mode", ""), ("frequency_hz", "f [Hz]", ".5g"), ("direction", "dir", ""),
            ("ke_tip", "KE tip", ".3f"), ("ke_holder_tip", "KE holder+tip", ".4f"), ("ke_body", "KE body", ".2e"),
            ("se_holder_spring", "SE holder spring", ".3f")]
ECC_COLS = [("delta_um", "|delta| [um]", "g"), ("f_low_hz", "f low [Hz]", ".7g"), ("f_high_hz", "f high [Hz]", ".7g"),
            ("split", "split", ".3e"), ("split_predicted", "split EB", ".3e"), ("angle_low_deg", "angle low [deg]", ".3f"),
            ("angle_predicted_deg", "angle EB [deg]", ".1f"), ("coupling_yz", "K_yz/sqrt(K_yy K_zz)", "+.3e"),
            ("coupling_axial_lateral", "axial-lateral coupling", ".3e"), ("centroid_um", "centroid offset [um]", ".3g")]
MAT_COLS = [("mode", "mode", ""), ("family", "family", ""), ("aniso_hz", "PZT-5H [Hz]", ".6g"),
            ("iso_hz", "iso E=1/s11 [Hz]", ".6g"), ("rel_diff", "rel. diff", "+.3e")]
REF_COLS = [("mode", "mode", ""), ("direction", "dir", ""), ("order", "n", ""), ("formula", "formula", ""),
            ("fem_hz", "FEM [Hz]", ".6g"), ("value_hz", "formula [Hz]", ".6g"), ("rel_diff", "rel. diff", "+.4f")]
CONV_COLS = [("mode", "mode", ""), ("family", "family", ""), ("f_finest_hz", "finest [Hz]", ".7g"),
             ("f_extrapolated_hz", "extrapolated [Hz]", ".7g"), ("observed_order", "observed order", ".2f"),
             ("rel_change_last", "last change", "+.2e")]


def plot_localisation(rows: list[dict], path: Path, title: str, lumped: dict | None = None) -> Path:
    """Energy shares of modes 1-2 vs holder stiffness, and FEM vs lumped frequencies."""
    import numpy as np

    from probedyn.core.io import atomic_path

    plt = _mpl()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    ks = sorted({r["k_t"] for r in rows})
    for mode, ls in ((1, "-"), (2, "--")):
        sel = [next(r for r in rows if r["k_t"] == k and r["mode"] == mode) for k in ks]
        a1.semilogx(ks, [r["se_holder_spring"] for r in sel], "o" + ls, label=f"mode {mode}: strain energy in holder spring")
        a1.semilogx(ks, [r["ke_tip"] for r in sel], "s" + ls, label=f"mode {mode}: kinetic energy in tip", alpha=0.7)
    a1.set_xlabel("holder stiffness k_t [N/m]")
    a1.set_ylabel("share")
    a1.set_ylim(-0.02, 1.02)
    a1.legend(fontsize=7)
    a1.set_title(title)
    nm = max(r["mode"] for r in rows)
    for mode in range(1, nm + 1):
        a2.loglog(ks, [next(r for r in rows if r["k_t"] == k and r["mode"] == mode)["frequency_hz"] for k in ks], "o",
                  label=f"FEM mode {mode}")
    if lumped:
        kk = np.array(lumped["k"])
        F = np.array(lumped["f"])
        for j in range(min(F.shape[1], 6)):
            a2.loglog(kk, F[:, j], "-", color="grey", lw=0.8, label="lumped model" if j == 0 else None)
    a2.set_xlabel("holder stiffness k_t [N/m]")
    a2.set_ylabel("frequency [Hz]")
    a2.legend(fontsize=7)
    a2.set_title("FEM (markers) vs lumped model (lines)")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


def plot_eccentricity(rows: list[dict], path: Path) -> Path:
    from probedyn.core.io import atomic_path

    plt = _mpl()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    d = [r["delta"] * 1e6 for r in rows]
    ax.plot(d, [r["split"] for r in rows], "o-", label="FEM split f_high/f_low - 1")
    ax.plot(d, [r["split_predicted"] for r in rows], "k--", label="Euler-Bernoulli, exact eccentric section")
    ax.set_xlabel("bore offset |delta| [um]")
    ax.set_ylabel("relative split of the lateral pair")
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


def lumped_sweep_curves(lm_dict: dict, ks: list[float], sweep_dirs) -> dict:
    """Lumped-model frequencies over the holder stiffness (the same J, K_2, m)."""
    import numpy as np

    from probedyn.lumped.smart import SmartLumpedModel

    out = []
    kk = np.geomspace(min(ks), max(ks), 40)
    for k in kk:
        kt = np.array([k if d in sweep_dirs else kt0 for d, kt0 in zip(lm_dict["directions"], lm_dict["kt"])])
        lm = SmartLumpedModel(lm_dict["directions"], np.asarray(lm_dict["J"]), np.asarray(lm_dict["K2"]),
                              np.asarray(lm_dict["C2"]), lm_dict["m"], kt)
        out.append(lm.modes()[0])
    return {"k": kk.tolist(), "f": np.array(out).tolist()}


# ---------------------------------------------------------------------------------------------
# commands
# ---------------------------------------------------------------------------------------------


@app.command("smart-lumped")
def cmd_lumped(probe: str = PROBE_ARG, set_: Optional[list[str]] = SET_OPT, as_json: bool = JSON_OPT,
               out: Optional[Path] = OUT_OPT) -> None:
    """Lumped model (3.4 / 3.20 / 3.37) from FEM body modes vs FEM of the assembled probe."""
    from probedyn.probes.studies import study_lumped

    r = study_lumped(probe, _sets(set_))
    res = {"probe": r["probe"], "lumped": r["lumped"], "rows": r["rows"]}
    save(out, f"{r['probe']}-lumped.json", res)
    emit(res, as_json, lambda x: "body parameters (3.1-3.3 at the holder):\n"
         + format_table(x["lumped"]["parameters"], PAR_COLS) + "\n\n" + format_table(x["rows"], LUMPED_COLS))


@app.command("localisation")
def cmd_localisation(probe: str = PROBE_ARG, k: str = typer.Option("1,2,5,10,20,50,100", "--k", help="Holder stiffnesses [N/m]."),
                     set_: Optional[list[str]] = SET_OPT, as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Section 3.4.1: FEM modes over the holder stiffness, energy shares per mode."""
    from probedyn.probes.studies import study_localisation

    r = study_localisation(probe, _floats(k, "k"), _sets(set_))
    res = {"probe": r["probe"], "rows": r["rows"]}
    if out is not None:
        save(out, f"{r['probe']}-localisation.json", res)
        plot_localisation(r["rows"], Path(out) / f"{r['probe']}-localisation.png", r["probe"])
    emit(res, as_json, lambda x: format_table(x["rows"], LOC_COLS))


@app.command("eccentricity")
def cmd_eccentricity(probe: str = typer.Argument("piezotube", help="piezotube (or a TOML file of it)"),
                     delta: str = typer.Option("0,1e-6,2e-6,3e-6,4e-6,5e-6", "--delta", help="Bore offsets |delta| [m]."),
                     angle: float = typer.Option(45.0, "--angle", help="Direction of the offset, degrees from +y to +z."),
                     set_: Optional[list[str]] = SET_OPT, as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Eccentric piezotube: split and tilt of the lateral pair (FEM counterpart of Gamma, 3.38-3.44)."""
    from probedyn.core.errors import ParameterError
    from probedyn.probes.studies import study_eccentricity

    if probe != "piezotube" and not probe.endswith(".toml"):
        raise ParameterError("eccentricity applies to the piezotube")
    r = study_eccentricity(_floats(delta, "delta"), angle, _sets(set_), probe)
    for row in r["rows"]:
        row["delta_um"] = row["delta"] * 1e6
        row["centroid_um"] = row["centroid_offset"] * 1e6
    if out is not None:
        save(out, "piezotube-eccentricity.json", r)
        plot_eccentricity(r["rows"], Path(out) / "piezotube-eccentricity.png")
    emit(r, as_json, lambda x: format_table(x["rows"], ECC_COLS))


@app.command("smart-materials")
def cmd_materials(probe: str = PROBE_ARG, set_: Optional[list[str]] = SET_OPT, as_json: bool = JSON_OPT) -> None:
    """First four modes with transversely isotropic PZT-5H vs the isotropic E = 1/s11 option."""
    from probedyn.probes.studies import study_materials

    r = study_materials(probe, _sets(set_))
    emit(r, as_json, lambda x: format_table(x["rows"], MAT_COLS))


@app.command("smart-convergence")
def cmd_convergence(probe: str = PROBE_ARG, sizes: str = typer.Option(None, "--sizes", help="Element sizes [m], constant ratio."),
                    set_: Optional[list[str]] = SET_OPT, as_json: bool = JSON_OPT) -> None:
    """Mesh convergence of the first four frequencies (observed order, extrapolated values)."""
    from probedyn.probes.studies import study_convergence

    default = {"duo-bimorph": "10e-6,6.6667e-6,4.4444e-6", "piezotube": "300e-6,200e-6,133.33e-6"}
    spec = sizes or default.get(probe, default["duo-bimorph"])
    r = study_convergence(probe, _floats(spec, "sizes"), _sets(set_))
    emit(r, as_json, lambda x: format_table(x["levels"], [("element_size", "size [m]", ".4g"), ("dofs", "dofs", ""),
                                                          ("seconds", "time [s]", ".1f")])
         + "\n\n" + format_table(x["modes"], CONV_COLS))


# ---------------------------------------------------------------------------------------------
# report
# ---------------------------------------------------------------------------------------------

QUICK_MESH = {"duo-bimorph": {"element_size": 10e-6}, "piezotube": {"element_size": 400e-6}}


def _panel(probe: str, outdir: Path, ov: dict) -> tuple[str, Any]:
    """Fig 3.15: the first four modes of the probe body with its holder (duo-bimorph: with
    the meshed tip cone; the lumped tip cannot be drawn)."""
    from probedyn.probes import get_probe

    p, _ = get_probe(probe)
    extra = {"tip": "meshed"} if probe == "duo-bimorph" else {"tip": "none"}
    v = p.resolve({**ov, **extra})
    res = p.build(v).modes(4)
    titles = [f"mode {m.index}: {m.family}, {m.frequency_hz:.4g} Hz" for m in res.modes]
    try:
        from probedyn.fem.render import render_panel

        path = render_panel(res, outdir / f"{probe}-modes.png", titles=titles)
        return f"![First four modes of the {probe}]({path.name})", res
    except Exception as exc:  # no OpenGL: report it, keep the numbers
        return f"(mode panel not rendered: {str(exc).splitlines()[0]})", res


def report_section(outdir: Path, quick: bool = False) -> str:
    """Per probe: Fig 3.15 panel, analytic comparison, lumped vs FEM, localisation table and
    plot; the piezotube eccentricity table; isotropic vs anisotropic PZT."""
    from probedyn.core.io import write_json
    from probedyn.probes import studies as S
    from probedyn.probes import get_probe

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    ks = [1.0, 100.0] if quick else [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
    deltas = [0.0, 5e-6] if quick else [0.0, 1e-6, 2e-6, 3e-6, 4e-6, 5e-6]
    parts = ["Source sections 3.2-3.5. FEM: P2 tetrahedra, PZT-5H transversely isotropic (poled through the thickness "
             "in the bimorph, radially in the tube); tip lumped as mass m on the holder springs k_t; holder mass from "
             "Table 3.1/3.2 (m_h) unless stated. Details and departures from the print: `docs/smart-probes.md`."
             + (" Quick mode: coarse meshes." if quick else "")]
    data: dict[str, Any] = {}
    for probe in ("duo-bimorph", "piezotube"):
        ov = dict(QUICK_MESH[probe]) if quick else {}
        parts.append(f"### {probe}")
        img, res = _panel(probe, outdir, ov)
        parts += ["", img, ""]
        p, _ = get_probe(probe)
        v = p.resolve({**ov, "tip": "none"})
        refs = p.references(v, res if probe == "piezotube" else p.build(v).modes(6))
        parts += [f"Analytic references (body + holder, no tip; holder mass {p.holder_mass(v):.3g} kg, "
                  f"geometric holder mass {p.holder_geometric_mass(v):.3g} kg):", "",
                  markdown_table(refs, REF_COLS), ""]
        lum = S.study_lumped(probe, ov)
        parts += ["Lumped model from FEM body modes (3.1-3.3 at the holder end face) vs FEM of the assembled probe "
                  "(tolerance = 2 x predicted truncation error + 1e-3, see `lumped/smart.py`):", "",
                  markdown_table(lum["lumped"]["parameters"], PAR_COLS), "",
                  markdown_table(lum["rows"], LUMPED_COLS), ""]
        loc = S.study_localisation(probe, ks, ov)
        curves = lumped_sweep_curves(lum["lumped"], ks, get_probe(probe)[0].sweep_directions)
        fig = plot_localisation(loc["rows"], outdir / f"{probe}-localisation.png", probe, curves)
        parts += ["Section 3.4.1, holder stiffness sweep (KE = kinetic energy share, SE = strain energy share):", "",
                  markdown_table(loc["rows"], LOC_COLS), "", f"![localisation]({fig.name})", ""]
        mat = S.study_materials(probe, {**ov, "tip": "none"})
        parts += ["Transversely isotropic PZT-5H vs isotropic E = 1/s11 (body + holder):", "",
                  markdown_table(mat["rows"], MAT_COLS), ""]
        hm = S.study_holder_mass(probe, ov)
        parts += [f"Holder mass (SOURCE-NOTES 10): table m_h = {hm['holder_mass']['table']:.3g} kg vs holder geometry "
                  f"{hm['holder_mass']['geometry']:.3g} kg (set `holder_mass_source`), body + holder modes:", "",
                  markdown_table(hm["rows"], [("mode", "mode", ""), ("family_table", "family (table)", ""),
                                              ("table_hz", "f table [Hz]", ".6g"), ("family_geometry", "family (geometry)", ""),
                                              ("geometry_hz", "f geometry [Hz]", ".6g"), ("ratio", "ratio", ".3f")]), ""]
        data[probe] = {"holder_mass": hm, "references": refs, "lumped": lum["rows"], "localisation": loc["rows"], "materials": mat["rows"]}
    ecc = S.study_eccentricity(deltas, 45.0, QUICK_MESH["piezotube"] if quick else {})
    for row in ecc["rows"]:
        row["delta_um"] = row["delta"] * 1e6
        row["centroid_um"] = row["centroid_offset"] * 1e6
    fig = plot_eccentricity(ecc["rows"], outdir / "piezotube-eccentricity.png")
    parts += ["### Piezotube eccentricity (bore offset along 45 degrees, as delta_x = delta_y in section 3.5.4)", "",
              markdown_table(ecc["rows"], ECC_COLS), "", f"![eccentricity]({fig.name})", ""]
    data["eccentricity"] = ecc["rows"]
    write_json(outdir / "smart-probes.json", data)
    return "\n".join(parts)
