"""``probedyn contact``: tip–sample contact models (section 2.2) and the report section with
Fig 2.19, the pull-off table and the adhesion–friction coupling (section 2.2.4, Fig 2.22)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table, markdown_table

#: lambdas of the reproduced Fig 2.19 (0 = DMT limit, inf = JKR)
FIG_2_19_LAMBDAS = (0.0, 0.1, 0.3, 0.6, 1.0, 2.0, 5.0, float("inf"))


def cos_fit_pull_off(lam: float) -> float:
    """Carpick, Ogletree & Salmeron, J. Colloid Interface Sci. 211 (1999) 395: pull-off load
    in units of pi W R from ``lam = -0.924 ln(1 - 1.02 alpha)`` and
    ``-(0.267 alpha^2 - 0.767 alpha + 2.000)`` (an independent fit of Maugis' result)."""
    import math

    alpha = (1.0 - math.exp(-lam / 0.924)) / 1.02 if math.isfinite(lam) else 1.0 / 1.02
    return -(0.267 * alpha**2 - 0.767 * alpha + 2.000)


def _model_for(name: str, lam: float | None, sets: dict[str, str]):
    from probedyn.schemes.contact import get_contact_model

    kw: dict[str, Any] = dict(sets)
    if lam is not None:
        kw["lam"] = lam
    return get_contact_model(name, **kw)


def contact_result(model: str = "md", lam: float | None = None, sets: dict[str, str] | None = None,
                   n_points: int = 201, D_range: tuple[float, float] = (-2.0, 3.0)) -> dict[str, Any]:
    """Everything ``probedyn contact`` reports, as a JSON-able dict."""
    import numpy as np

    m = _model_for(model, lam, sets or {})
    po = m.nd_pull_off()
    D = np.linspace(D_range[0], D_range[1], n_points)
    loading = m.nd_state(D, "loading")
    unloading = m.nd_state(D, "unloading")
    unstable = m.nd_state(D, "unstable")
    curves = m.nd_curves(D_range)
    s = m.scales
    res: dict[str, Any] = dict(
        model=m.name, title=m.title, equations=m.equations, lam=m.lam,
        pull_off_normalized=po["P_pull_off"],
        pull_off_n=m.pull_off_force(),
        contact_radius_at_pull_off_normalized=po["A_pull_off"],
        jump_out_load_normalized=po["P_jump_out"],
        jump_out_penetration_normalized=po["D_jump_out"],
        contact_transition=dict(penetration_normalized=curves["D0"], load_normalized=curves["P0"]),
        parameters=m.describe(),
        units=dict(load_n=s.P_unit, penetration_m=s.d_unit, contact_radius_m=s.a_unit),
        curve=dict(
            penetration_normalized=D,
            load_normalized_loading=loading["P"],
            load_normalized_unloading=unloading["P"],
            load_normalized_unstable=unstable["P"],
            contact_radius_normalized_unloading=unloading["A"],
        ),
        parametric_curve=dict(contact_radius_normalized=curves["A"][::3],
                              penetration_normalized=curves["D"][::3], load_normalized=curves["P"][::3]),
    )
    if m.name == "md":
        fit = cos_fit_pull_off(m.lam)
        res["pull_off_published_fit"] = dict(
            reference="Carpick, Ogletree & Salmeron, J. Colloid Interface Sci. 211 (1999) 395",
            value=fit, relative_difference=po["P_pull_off"] / fit - 1.0)
    return res


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


def plot_load_penetration(res: dict[str, Any], path: Path) -> Path:
    """Normalised load vs penetration of one model: loading, unloading, unstable branches."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from probedyn.core.io import atomic_path

    c = res["curve"]
    D = np.asarray(c["penetration_normalized"], float)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.plot(D, np.asarray(c["load_normalized_unloading"], float), "C0-", label="unloading (stable branch + tail)")
    ax.plot(D, np.asarray(c["load_normalized_loading"], float), "C1--", label="loading (tail + stable branch)")
    un = np.asarray([np.nan if v is None else v for v in c["load_normalized_unstable"]], float)
    ax.plot(D, un, "C3:", label="unstable branch")
    ax.axhline(res["pull_off_normalized"], color="0.6", lw=0.8)
    ax.set_xlabel(r"penetration $\bar\Delta$")
    ax.set_ylabel(r"load $\bar P = P / (\pi W R)$")
    ax.set_title(f"{res['title']}, $\\lambda$ = {res['lam']:.3g}: pull-off {res['pull_off_normalized']:.4f}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120, format="png")
    plt.close(fig)
    return Path(path)


def plot_fig_2_19(path: Path, lams=FIG_2_19_LAMBDAS, D_range=(-2.2, 3.0)) -> Path:
    """Fig 2.19 reproduced: normalised load vs penetration for several lambda, with the
    unstable branches dashed and the continuous non-contact tails (2.33-2.34)."""
    import math

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from probedyn.core.io import atomic_path
    from probedyn.schemes.contact import JKR, MaugisDugdale

    fig, ax = plt.subplots(figsize=(7, 5))
    cmap = plt.get_cmap("viridis")
    for i, lam in enumerate(lams):
        m = JKR(W=1.0) if not math.isfinite(lam) else MaugisDugdale(lam=lam)
        cv = m.nd_curves(D_range)
        col = cmap(i / max(1, len(lams) - 1))
        st = cv["stable"]
        label = "JKR ($\\lambda=\\infty$)" if not math.isfinite(lam) else (
            "DMT ($\\lambda=0$)" if lam == 0 else f"$\\lambda$ = {lam:g}")
        ax.plot(cv["D"][st], cv["P"][st], color=col, lw=1.6, label=label)
        if np.any(~st):
            ax.plot(cv["D"][~st], cv["P"][~st], color=col, lw=1.0, ls="--")
        if len(cv["D_tail"]):
            ax.plot(cv["D_tail"], cv["P_tail"], color=col, lw=1.0, ls=":")
        ax.plot([cv["D0"]], [cv["P0"]], "o", color=col, ms=3)
    ax.set_xlim(*D_range)
    ax.set_ylim(-2.2, 3.0)
    ax.axhline(0, color="0.5", lw=0.6)
    ax.set_xlabel(r"normalised penetration $\bar\Delta = \Delta / (\pi^2 W^2 R / K^2)^{1/3}$")
    ax.set_ylabel(r"normalised load $\bar P = P / (\pi W R)$")
    ax.set_title("Fig 2.19: Maugis–Dugdale load vs penetration (solid stable, dashed unstable, dotted tail)",
                 fontsize=9)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=130, format="png")
    plt.close(fig)
    return Path(path)


def pull_off_table(lams=(1e-3, 0.01, 0.1, 0.3, 0.5, 0.938, 1.0, 2.0, 5.0, 10.0, 100.0, 1000.0)) -> list[dict[str, Any]]:
    """Pull-off (load and displacement control) of Maugis–Dugdale vs the COS (1999) fit."""
    from probedyn.schemes.contact import MaugisDugdale

    rows = []
    for lam in lams:
        po = MaugisDugdale(lam=lam).nd_pull_off()
        fit = cos_fit_pull_off(lam)
        rows.append(dict(lam=lam, pull_off=po["P_pull_off"], A_pull_off=po["A_pull_off"], cos_fit=fit,
                         rel_diff_pct=100 * (po["P_pull_off"] / fit - 1), jump_out=po["P_jump_out"],
                         D_jump_out=po["D_jump_out"]))
    return rows


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

    res = contact_result(model, lam, parse_sets(sets))
    if out is not None:
        from probedyn.core.io import write_json

        out = Path(out)
        write_json(out / "contact.json", res)
        plot_load_penetration(res, out / f"contact_{res['model']}.png")
    emit(res, as_json, _human)


def report_section(outdir: Path, quick: bool) -> str:
    """Fig 2.19, the pull-off table against the published fit, and the adhesion–friction coupling."""
    from probedyn.schemes import coupling

    outdir = Path(outdir)
    fig = plot_fig_2_19(outdir / "contact_fig_2_19.png")
    rows = pull_off_table()
    worst = max(abs(r["rel_diff_pct"]) for r in rows)
    parts = [
        "Maugis–Dugdale contact (eqs 2.24–2.35 with SOURCE-NOTES item 3: `Delta = A^2 - 4/3 lambda A sqrt(m^2-1)`,"
        " `atan(sqrt(m^2-1))`, `K` in 2.30), solved along the contact radius A (one bracketed root m per A),"
        " with a van der Waals tail that meets the contact curve at its A -> 0 end (2.31–2.32), so the force is"
        " continuous across the contact transition. DMT (2.20) and JKR are the lambda -> 0 and lambda -> inf limits.",
        "",
        f"![Fig 2.19 reproduced]({fig.name})",
        "",
        "Pull-off load (load control, minimum of P along the curve) and jump-out load (displacement control) in units"
        " of pi W R, against the fit of Carpick, Ogletree & Salmeron, J. Colloid Interface Sci. 211 (1999) 395"
        f" (largest difference {worst:.2f} %):",
        "",
        markdown_table(rows, [("lam", "lambda", "g"), ("pull_off", "P_c / (pi W R)", ".5f"),
                              ("A_pull_off", "A at P_c", ".4f"), ("cos_fit", "COS fit", ".5f"),
                              ("rel_diff_pct", "diff [%]", "+.2f"), ("jump_out", "jump-out load", ".4f"),
                              ("D_jump_out", "jump-out penetration", ".4f")]),
        "",
    ]
    parts.append(coupling.report_markdown(outdir, quick))
    return "\n".join(parts)
