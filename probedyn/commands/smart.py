"""Commands of the smart probes (duo-bimorph, piezotube; source sections 3.2-3.5).

* ``probedyn smart-lumped PROBE``: the lumped model (3.4 / 3.20 / 3.37) assembled from FEM body
  modes vs the FEM of the assembled probe;
* ``probedyn localisation PROBE``: section 3.4.1, holder stiffness sweep (energy shares);
* ``probedyn eccentricity``: piezotube bore offset, split and tilt of the lateral pair (3.38-3.44);
* ``probedyn smart-materials PROBE``: transversely isotropic PZT-5H vs isotropic E = 1/s11;
* ``probedyn smart-convergence PROBE``: mesh convergence of the first four frequencies.

The generic ``probedyn modes|compare|reduce|render|params duo-bimorph|piezotube`` come from
:mod:`probedyn.commands.modal` through the probe registry. The report section and the figures
are in :mod:`probedyn.report.smart_probes`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, save

PROBE_ARG = typer.Argument(..., help="duo-bimorph, piezotube, or a TOML probe file")


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
# text tables (the report's tables and figures: probedyn.report.smart_probes)
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
ECC_COLS = [("delta_um", "|delta| [µm]", "g"), ("f_low_hz", "f low [Hz]", ".7g"), ("f_high_hz", "f high [Hz]", ".7g"),
            ("split", "split", ".3e"), ("split_predicted", "split EB", ".3e"), ("angle_low_deg", "angle low [°]", ".3f"),
            ("angle_predicted_deg", "angle EB [°]", ".1f"), ("coupling_yz", "K_yz/sqrt(K_yy K_zz)", "+.3e"),
            ("coupling_axial_lateral", "axial-lateral coupling", ".3e"), ("centroid_um", "centroid offset [µm]", ".3g")]
MAT_COLS = [("mode", "mode", ""), ("family", "family", ""), ("aniso_hz", "PZT-5H [Hz]", ".6g"),
            ("iso_hz", "iso E=1/s11 [Hz]", ".6g"), ("rel_diff", "rel. diff", "+.3e")]
CONV_COLS = [("mode", "mode", ""), ("family", "family", ""), ("f_finest_hz", "finest [Hz]", ".7g"),
             ("f_extrapolated_hz", "extrapolated [Hz]", ".7g"), ("observed_order", "observed order", ".2f"),
             ("rel_change_last", "last change", "+.2e")]


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
        from probedyn.report.smart_probes import plot_localisation

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
    from probedyn.report.smart_probes import eccentricity_rows, plot_eccentricity

    r = study_eccentricity(_floats(delta, "delta"), angle, _sets(set_), probe)
    r["rows"] = eccentricity_rows(r["rows"])
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
