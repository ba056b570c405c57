"""Report section: tip–sample contact (source section 2.2, Fig 2.19) and the adhesion–friction
coupling (section 2.2.4, Fig 2.22; its part is :mod:`probedyn.report.coupling`).

Figures: ``contact_fig_2_19.png``; :func:`plot_load_penetration` is the figure of
``probedyn contact --out``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.plotting import pyplot, savefig
from probedyn.report import coupling
from probedyn.report._tables import markdown_table
from probedyn.schemes.contact import JKR, MaugisDugdale
from probedyn.schemes.contact.maugis_dugdale import MaugisDugdaleVdW
from probedyn.schemes.contact.carpick import REFERENCE, pull_off_table

#: lambdas of the reproduced Fig 2.19 (0 = DMT limit, inf = JKR)
FIG_2_19_LAMBDAS = (0.0, 0.1, 0.3, 0.6, 1.0, 2.0, 5.0, float("inf"))


def plot_load_penetration(res: dict[str, Any], path: Path) -> Path:
    """Normalised load vs penetration of one model (the dict of
    :func:`probedyn.schemes.contact.curves.contact_summary`): loading, unloading, unstable branches."""
    c = res["curve"]
    D = np.asarray(c["penetration_normalized"], float)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4.2))
    if not res.get("adhesive", True):  # a non-adhesive indenter: one monotone branch in E* R^2 and R units
        ax.plot(D, np.asarray(c["load_normalized_loading"], float), "C0-", label="loading = unloading")
        edge = res["parameters"].get("cap_edge_depth_m")
        if edge:
            ax.axvline(edge / res["units"]["penetration_m"], color="0.6", lw=0.8, label="cap edge depth R cot$^2$")
        ax.set_xlabel(r"penetration $\delta / R$")
        ax.set_ylabel(r"load $P / (E^* R^2)$")
        ax.set_title(f"{res['title']}", fontsize=9)
        ax.legend(fontsize=8)
        fig.tight_layout()
        return savefig(fig, path)
    ax.plot(D, np.asarray(c["load_normalized_unloading"], float), "C0-", label="unloading (stable branch + tail)")
    ax.plot(D, np.asarray(c["load_normalized_loading"], float), "C1--", label="loading (tail + stable branch)")
    un = np.asarray([np.nan if v is None else v for v in c["load_normalized_unstable"]], float)
    ax.plot(D, un, "C3:", label="unstable branch")
    ax.axhline(res["pull_off_normalized"], color="0.6", lw=0.8, label="pull-off load")
    ax.set_xlabel(r"normalised penetration $\bar\Delta$")
    ax.set_ylabel(r"normalised load $\bar P = P / (\pi W R)$")
    ax.set_title(f"{res['title']}, $\\lambda$ = {res['lam']:.3g}: pull-off {res['pull_off_normalized']:.4f}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return savefig(fig, path)


def plot_fig_2_19(path: Path, lams=FIG_2_19_LAMBDAS, D_range=(-2.2, 3.0)) -> Path:
    """Fig 2.19 reproduced: normalised load vs penetration for several lambda, with the
    unstable branches dashed, the source's continuous non-contact tails (2.33-2.34, ``md-vdw``) dotted and
    Maugis' own non-contact branch (the Dugdale zone before the surfaces touch, ``md``, departure 47) dash-dotted."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    cmap = plt.get_cmap("viridis")
    for i, lam in enumerate(lams):
        m = JKR(W=1.0) if not math.isfinite(lam) else MaugisDugdaleVdW(lam=lam)
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
        if math.isfinite(lam) and lam > 0:  # Maugis' own non-contact branch: from the free state to the end point
            Dn, Pn = MaugisDugdale(lam=lam).nd_noncontact_path(200)
            ax.plot(np.r_[D_range[0], Dn], np.r_[0.0, Pn], color=col, lw=0.9, ls="-.")
        ax.plot([cv["D0"]], [cv["P0"]], "o", color=col, ms=3)
    # line-style key (one entry per style, in black)
    ax.plot([], [], "k-", lw=1.6, label="stable branch")
    ax.plot([], [], "k--", lw=1.0, label="unstable branch")
    ax.plot([], [], "k:", lw=1.0, label="van der Waals tail (2.33-2.34, md-vdw)")
    ax.plot([], [], "k-.", lw=0.9, label="Dugdale zone out of contact (md)")
    ax.plot([], [], "ko", ms=3, label="contact transition")
    ax.set_xlim(*D_range)
    ax.set_ylim(-2.2, 3.0)
    ax.axhline(0, color="0.5", lw=0.6)
    ax.set_xlabel(r"normalised penetration $\bar\Delta = \Delta / (\pi^2 W^2 R / K^2)^{1/3}$")
    ax.set_ylabel(r"normalised load $\bar P = P / (\pi W R)$")
    ax.set_title("Fig 2.19: Maugis–Dugdale load vs penetration", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", ncol=2)
    fig.tight_layout()
    return savefig(fig, path)


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    fig = plot_fig_2_19(outdir / "contact_fig_2_19.png")
    rows = pull_off_table()
    worst = max(abs(r["rel_diff_pct"]) for r in rows)
    parts = [
        "Maugis–Dugdale contact (eqs 2.24–2.35 with departure 7: `Delta = A^2 - 4/3 lambda A sqrt(m^2-1)`,"
        " `atan(sqrt(m^2-1))`, `K` in 2.30), solved along the contact radius A (one bracketed root m per A),"
        " with a van der Waals tail that meets the contact curve at its A -> 0 end (2.31–2.32, departure 8), so the"
        " force is continuous across the contact transition (`md-vdw`, the source's form; the nano-placing uses it)."
        " The registry's `md` is Maugis' own model out of contact too (departure 47): the Dugdale stress on a disc"
        " whose rim has the gap h0, over elastic half-spaces, from the free state (gap h0) to the first touch, which is"
        " the end point (2.31–2.32) exactly. DMT (2.20) and JKR (departure 9) are the lambda -> 0 and"
        " lambda -> inf limits.",
        "",
        f"![Fig 2.19 reproduced]({fig.name})",
        "",
        "*Normalised load vs penetration of the Maugis–Dugdale model for lambda from 0 (DMT) to infinity (JKR); "
        "solid: stable branch, dashed: unstable, dotted: the source's van der Waals tail (2.33–2.34), dash-dotted: "
        "Maugis' own non-contact branch (Dugdale zone, its unstable part included), dot: contact transition.*",
        "",
        "Pull-off load (load control, minimum of P along the curve) and jump-out load (displacement control; below"
        " lambda = 0.938 at the fold of Maugis' own non-contact branch, where the Dugdale zone lets go) in units"
        f" of pi W R, against the fit of {REFERENCE} (largest difference {worst:.2f} %):",
        "",
        markdown_table(rows, [("lam", "lambda", "g"), ("pull_off", "P_c / (pi W R)", ".5f"),
                              ("A_pull_off", "A at P_c", ".4f"), ("cos_fit", "COS fit", ".5f"),
                              ("rel_diff_pct", "diff [%]", "+.2f"), ("jump_out", "jump-out load", ".4f"),
                              ("D_jump_out", "jump-out penetration", ".4f")]),
        "",
        coupling.section(outdir, quick),
    ]
    return "\n".join(parts)
