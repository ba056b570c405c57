"""``probedyn contact``: tip–sample contact models (section 2.2). The report section with
Fig 2.19, the pull-off table and the adhesion–friction coupling is :mod:`probedyn.report.contact`."""

from __future__ import annotations

from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table


def _human(res: dict[str, Any]) -> str:
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
    return format_table(rows, [("q", "quantity", ""), ("v", "value", "")])


@app.command("contact")
def contact(
    model: str = typer.Option("md", "--model", help="Contact model: dmt, jkr or md (Maugis-Dugdale)."),
    lam: Optional[float] = typer.Option(None, "--lambda", help="Maugis transition parameter (2.24); sets W."),
    sets: Optional[List[str]] = SET_OPT,
    as_json: bool = JSON_OPT,
    out: Optional[Path] = OUT_OPT,
) -> None:
    """Tip-sample contact: pull-off force and normalised load-penetration curve (Fig 2.19)."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes.contact.curves import contact_summary

    res = contact_summary(model, lam, parse_sets(sets))
    if out is not None:
        from probedyn.core.io import write_json
        from probedyn.report.contact import plot_load_penetration

        out = Path(out)
        write_json(out / "contact.json", res)
        plot_load_penetration(res, out / f"contact_{res['model']}.png")
    emit(res, as_json, _human)
