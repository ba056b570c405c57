"""``probedyn contact``: tip–sample contact models (section 2.2). The report section with
Fig 2.19, the pull-off table and the adhesion–friction coupling is :mod:`probedyn.report.contact`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table
from probedyn.commands._probe import PROBE_MODES_OPT, PROBE_OPT, PROBE_Q_OPT, PROBE_SET_OPT, load_probe, probe_line


def _human_indenter(res: dict[str, Any]) -> list[dict[str, str]]:
    """Rows of a non-adhesive law: what it defines (no pull-off, lambda or jumps: it has no attraction)."""
    p = res["parameters"]
    rows = [dict(q="model", v=f"{res['title']} ({res['model']}), {res['equations']}"),
            dict(q="adhesion", v="none: no pull-off, no jump-to-contact or jump-out (monotone load, loading = unloading)"),
            dict(q="reduced modulus E* [Pa] / tip radius R [m]", v=f"{p['E_star_pa']:.4g} / {p['R_m']:.4g}"),
            dict(q="half-angle / equivalent cone half-angle [deg]",
                 v=f"{math.degrees(p['alpha_rad']):.3f} / {math.degrees(p['equivalent_cone_half_angle_rad']):.3f}"),
            dict(q="cap edge: contact radius R cot / depth R cot^2 [m]",
                 v=f"{p['cap_edge_radius_m']:.4e} / {p['cap_edge_depth_m']:.4e}"),
            dict(q="load at the cap edge depth [N]", v=f"{res['cap_edge_load_n']:.4e}")]
    fc = res.get("force_curve")
    if fc:
        rows.append(dict(q="normal stiffness of the probe [N/m]", v=f"{fc['k']:.4g}"))
        rows.append(dict(q="force curve", v="no jumps (the force gradient is never negative)"))
    return rows


def _human(res: dict[str, Any]) -> str:
    if not res.get("adhesive", True):
        text = format_table(_human_indenter(res), [("q", "quantity", ""), ("v", "value", "")])
        return text + ("\n" + probe_line(res["probe"]) if res.get("probe") else "")
    rows = [
        dict(q="model", v=f"{res['title']} ({res['model']}), {res['equations']}"),
        dict(q="lambda (2.24)", v=f"{res['lam']:.6g}"),
        dict(q="pull-off / (pi W R), load control", v=f"{res['pull_off_normalized']:.6f}"),
        dict(q="pull-off force [N]", v=f"{res['pull_off_n']:.4e}"),
        dict(q="jump-out load / (pi W R), displacement control", v=f"{res['jump_out_load_normalized']:.6f}"),
        dict(q="contact transition (D0, P0)", v="({penetration_normalized:.5f}, {load_normalized:.5f})".format(
            **res["contact_transition"])),
    ]
    if "pull_off_published_fit" in res:
        f = res["pull_off_published_fit"]
        rows.append(dict(q="COS (1999) fit / difference", v=f"{f['value']:.6f} / {100 * f['relative_difference']:+.2f} %"))
    fc = res.get("force_curve")
    if fc:
        ji, jo = fc["jump_in"], fc["jump_out"]
        rows.append(dict(q="normal stiffness of the probe [N/m]", v=f"{fc['k']:.4g}"))
        rows.append(dict(q=f"predicted jump-in gap {fc['predicted_jump_rule']} [m]",
                         v=f"{fc['predicted_tail_jump_gap']:.4e}" + ("" if fc["jumps_at_range"] or fc["predicted_tail_jump_gap"] > fc["tail_end_gap"]
                                                                      else f" (< tail end {fc['tail_end_gap']:.3e}: no jump)")))
        rows.append(dict(q="jump-in: gap before [m] / load before, after [N]",
                         v="none (continuous approach)" if ji is None else
                         f"{ji['gap_before']:.4e} / {ji['P_before']:.4e}, {ji['P_after']:.4e}"))
        rows.append(dict(q="jump-out: load before [N]", v="none" if jo is None else f"{jo['P_before']:.4e}"))
    text = format_table(rows, [("q", "quantity", ""), ("v", "value", "")])
    return text + ("\n" + probe_line(res["probe"]) if res.get("probe") else "")


def _model_list() -> str:
    """The registry's contact laws, '<key> (<title>)' (imports the model modules: numpy only)."""
    from probedyn.schemes.contact import CONTACT_MODELS

    return "; ".join(f"{c.key} ({c.title})" for c in CONTACT_MODELS)


_MODELS = _model_list()


@app.command("contact")
def contact(
    model: str = typer.Option("md", "--model", help=f"Contact model, a key of the contact registry: {_MODELS}."),
    lam: Optional[float] = typer.Option(None, "--lambda", help="Maugis transition parameter (2.24); sets W."),
    sets: Optional[List[str]] = SET_OPT,
    probe: Optional[str] = PROBE_OPT,
    probe_sets: Optional[List[str]] = PROBE_SET_OPT,
    probe_modes: int = PROBE_MODES_OPT,
    probe_q: float = PROBE_Q_OPT,
    as_json: bool = JSON_OPT,
    out: Optional[Path] = OUT_OPT,
) -> None:
    """Tip-sample contact: pull-off force and normalised load-penetration curve (Fig 2.19); with
    --probe, the force curve of its normal spring (jump-to-contact, jump-out)."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes.contact.curves import contact_summary

    params = parse_sets(sets)
    res = contact_summary(model, lam, params)
    rp = load_probe(probe, probe_sets, probe_modes, probe_q)
    if rp is not None:
        from probedyn.schemes.contact import get_contact_model
        from probedyn.schemes.contact.force_curve import force_curve
        from probedyn.schemes.probe_hooks import normal_stiffness

        kw = dict(params)
        if lam is not None:
            kw["lam"] = lam
        m = get_contact_model(model, **kw)
        if m.adhesive:
            fc = force_curve(m, normal_stiffness(rp))
            res["force_curve"] = {k: v for k, v in fc.items() if k not in ("delta", "P", "s")}
        else:  # no attraction: the equilibrium is unique at every base position, nothing jumps
            res["force_curve"] = {"k": normal_stiffness(rp), "jump_in": None, "jump_out": None}
        res["probe"] = rp.summary()
    if out is not None:
        from probedyn.core.io import write_json
        from probedyn.report.contact import plot_load_penetration

        out = Path(out)
        write_json(out / "contact.json", res)
        plot_load_penetration(res, out / f"contact_{res['model']}.png")
    emit(res, as_json, _human)
