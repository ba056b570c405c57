"""Report section: measured data and their diagnosis (:mod:`probedyn.diagnose`).

The worked example is a real aluminium cantilever whose tip sensor is left out of the
baseline; a second, confounded case shows what the diagnosis says when one measured mode
cannot tell causes apart. Figures ``diagnose_al_residuals.png`` and
``diagnose_al_evidence.png``; :func:`plot_residuals`, :func:`plot_evidence` and
:func:`markdown` are also what ``probedyn diagnose --out`` writes.

The block prints what the library returns (verdict, findings, confounded groups) from the
result's fields, so a verdict and a confounded group are stated together, held parameters are
marked as held, and a p-value below double precision prints as a bound.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.io import make_dirs
from probedyn.diagnose.engine import diagnose, make_problem
from probedyn.plotting import fmt_hz, pyplot, savefig

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "measurements"


def _p(p: float) -> str:
    """A p-value; 0.0 (below the smallest double) prints as a bound."""
    return "< 1e-300" if p == 0 else f"= {p:.2g}"


def _val(v: float, unit: str) -> str:
    """A predicted value with its unit (frequencies through fmt_hz)."""
    return fmt_hz(v) if unit == "Hz" else f"{v:.5g} {unit}"


def _param(name: str, p: dict[str, Any]) -> str:
    if p.get("held"):
        return f"{name} = {p['value']:.4g} (held: not identifiable from these data)"
    if p.get("sigma") is None:
        return f"{name} = {p['value']:.4g}"
    return f"{name} = {p['value']:.4g} ± {p['sigma']:.2g}"


def plot_residuals(res: dict[str, Any], path: Path, labels: list[str] | None = None) -> Path:
    """Whitened residuals of the baseline and of the extended model (units of the stated noise)."""
    before = np.asarray(res["baseline"]["residuals"], float)
    after = np.asarray(res["final"]["residuals"], float)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.4))
    x = np.arange(len(before))
    ext = " + ".join(res["final"]["causes"]) or "baseline"
    if res["kind"] == "modal":
        w = 0.4
        ax.bar(x - w / 2, before, w, label="baseline", color="tab:red")
        ax.bar(x + w / 2, after, w, label=f"baseline + {ext}" if res["final"]["causes"] else ext, color="tab:blue")
        if labels:
            ticks = labels + [f"Q {lb}" for lb in labels][: len(before) - len(labels)]
            ax.set_xticks(x, ticks[: len(x)], rotation=45, ha="right", fontsize=7)
        ax.set_xlabel("measured quantity")
    else:
        ax.plot(x, before, ".", ms=2, color="tab:red", label="baseline")
        ax.plot(x, after, ".", ms=2, color="tab:blue", label=f"baseline + {ext}" if res["final"]["causes"] else ext)
        ax.set_xlabel("sample (scans concatenated)")
    ax.axhspan(-2, 2, color="0.9", zorder=0, label="±2 σ")
    ax.set_ylabel("residual [noise σ]")
    ax.legend(fontsize=7)
    ax.set_title(f"verdict: {res['verdict']}", fontsize=9)
    fig.tight_layout()
    return savefig(fig, path)


def plot_evidence(res: dict[str, Any], path: Path) -> Path:
    """Evidence of every candidate cause in nats on a linear axis (the gap between the leading
    causes is what decides); grey hatched: failed the likelihood-ratio test."""
    cands = res["candidates"]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 0.38 * max(len(cands), 3) + 1.2))
    names = [c["cause"] for c in cands][::-1]
    ev = [c["evidence"] if c["evidence"] is not None else 0.0 for c in cands][::-1]
    ok = [c["lr_pass"] for c in cands][::-1]
    bars = ax.barh(names, ev, color=["tab:green" if o and e > 0 else "0.7" for o, e in zip(ok, ev)])
    for b, o, e in zip(bars, ok, ev):
        if not o:
            b.set_hatch("//")
        ax.annotate(f"{e:.1f}", (e, b.get_y() + b.get_height() / 2), xytext=(3 if e >= 0 else -3, 0),
                    textcoords="offset points", va="center", ha="left" if e >= 0 else "right", fontsize=7)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("evidence [nat]")
    ax.margins(x=0.15)
    ranked = sorted((c for c in cands if c["evidence"] is not None), key=lambda c: -c["evidence"])
    gap = (f"; {ranked[0]['cause']} leads {ranked[1]['cause']} by {ranked[0]['evidence'] - ranked[1]['evidence']:.1f} nat"
           if len(ranked) > 1 else "")
    ax.set_title(f"{res['method']['evidence']}{gap}", fontsize=8)
    ax.bar(0, 0, color="tab:green", label="passes the likelihood-ratio test")
    ax.bar(0, 0, color="0.7", hatch="//", label="fails it")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return savefig(fig, path)


def verdict_text(res: dict[str, Any]) -> str:
    """The verdict with the confounded groups stated beside it (no contradiction between them)."""
    v = res["verdict"]
    conf = res.get("confounded") or []
    if not conf:
        return f"verdict: {v}"
    groups = "; ".join(", ".join(c["causes"]) for c in conf)
    return (f"verdict: {v} by a model extension, but the cause is NOT identified: the data fit equally well with "
            f"any of {groups} (confounded)")


def summary(res: dict[str, Any]) -> str:
    """Plain-text summary of a diagnosis from the result's fields."""
    b = res["baseline"]
    lines = [f"baseline: chi2 = {b['chi2']:.1f} for {b['dof']} dof (p {_p(b['p_value'])}), "
             f"residual RMS {b['residual_rms']:.2f} sigma"]
    if res["verdict"] == "no-significant-discrepancy":
        lines.append("no significant discrepancy: the residual is consistent with the stated noise; nothing is claimed")
    elif res["verdict"] == "unexplained":
        lines.append("significant discrepancy, but no catalog cause explains it out of sample")
    for f in res["findings"]:
        ps = ", ".join(_param(k, p) for k, p in f["parameters"].items())
        g = f["gain"]
        ho = (f", held-out {g['heldout_rms_before']:.2f} -> {g['heldout_rms_after']:.2f}"
              if g.get("heldout_rms_before") is not None else "")
        lines.append(f"{f['status']}: {f['cause']} ({ps}); evidence {f['evidence']:.1f} nats; residual RMS "
                     f"{g['residual_rms_before']:.2f} -> {g['residual_rms_after']:.2f} sigma{ho}")
    for c in res.get("confounded") or []:
        lines.append("confounded: " + ", ".join(c["causes"]) + " explain the data equally well")
        gm = c.get("group_measurement")
        if gm:
            lines.append("  to separate them (every pair > 3 sigma apart), measure: "
                         + "; ".join(m["measure"] for m in gm["measurements"]))
            for m in gm["measurements"]:
                pv = ", ".join(f"{k} {_val(v, m['unit'])}" for k, v in m["predictions"].items())
                lines.append(f"    {m['measure']} predicted: {pv}")
            if gm["pairs_left_unseparated"]:
                lines.append("  still indistinguishable: " + "; ".join(" vs ".join(p) for p in gm["pairs_left_unseparated"]))
        for p in c["pairs"]:
            m = p["separating_measurement"]
            if m:
                lines.append(f"  {c['causes'][0]} vs {p['cause']}: measure {m['measure']} "
                             f"({_val(m['a'], m['unit'])} vs {_val(m['b'], m['unit'])}, "
                             f"{m['separation_sigma']:.1f} sigma apart)")
    fin = res["final"]
    lines.append("final model: baseline" + "".join(f" + {c}" for c in fin["causes"])
                 + f", chi2 = {fin['chi2']:.3g} for {fin['dof']} dof (p {_p(fin['p_value'])})")
    lines.append(verdict_text(res))
    return "\n".join(lines)


def _structure_text(res: dict[str, Any]) -> str:
    st = res["baseline"]["structure"]
    if res["kind"] == "modal":
        parts = []
        for fam, it in st.get("by_family", {}).items():
            s = f"{fam}: mean {it['mean_sigma']:+.1f} σ over {it['n']} mode(s)"
            if "slope_per_order_sigma" in it:
                s += f", trend {it['slope_per_order_sigma']:+.1f} σ per order (t = {it['slope_t']:.1f})"
            parts.append(s)
        return "; ".join(parts) + "."
    parts = []
    for s in st.get("scans", []):
        parts.append(f"scan {s['scan']} (v = {s['speed']:.3g} m/s, N = {s['load']:.3g} N): mean {s['mean_residual_sigma']:+.1f} σ, "
                     f"lag-1 autocorrelation {s['lag1_autocorr']:.2f} (Ljung–Box p = {s['ljung_box_p']:.2g})")
    return "; ".join(parts) + "."


def markdown(res: dict[str, Any], fig_resid: str | None = None, fig_ev: str | None = None) -> str:
    """Markdown of a diagnosis (the five steps)."""
    b = res["baseline"]
    unit = b["residual_unit"].split("physical: ")[-1].rstrip(")")
    lines = [f"**Step 1 — baseline.** chi² = {b['chi2']:.1f} for {b['dof']} degrees of freedom "
             f"(p {_p(b['p_value'])}); residual RMS {b['residual_rms']:.2f} σ ({b['residual_rms_physical']:.3g} {unit})."]
    if b["parameters"]:
        lines.append("Calibrated: " + ", ".join(_param(k, v) for k, v in b["parameters"].items()) + ".")
    lines += ["", "**Step 2 — what it gets wrong.** " + _structure_text(res)]
    if fig_resid:
        lines += ["", f"![residuals]({fig_resid})", "",
                  "*Residuals of the baseline (red) and of the extended model (blue) in units of the stated noise.*"]
    lines += ["", f"**Step 3 — candidate causes** ({res['method']['evidence']}; claim rule: {res['method']['claim_rule']}):", "",
              "| cause | evidence [nat] | Δχ² | LR threshold | held-out RMS [σ] |", "|---|---:|---:|---:|---:|"]
    for c in res["candidates"]:
        ev = "–" if c["evidence"] is None else f"{c['evidence']:.1f}"
        ho = "–" if c["heldout_rms"] is None else f"{c['heldout_rms']:.2f}"
        lines.append(f"| {c['cause']} | {ev} | {c['delta_chi2']:.1f} | {c['lr_threshold']:.1f} | {ho} |")
    if fig_ev:
        lines += ["", f"![evidence]({fig_ev})", "",
                  "*Evidence of each candidate cause (nats, linear axis) with the margin of the leading cause.*"]
    lines += ["", "**Steps 4–5 — extension and gain.**", "", "```", summary(res), "```"]
    return "\n".join(lines)


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    make_dirs(outdir)
    problem = make_problem(EXAMPLES / "al_cantilever_length_sweep.toml")
    res = diagnose(problem)
    fr = plot_residuals(res, outdir / "diagnose_al_residuals.png", problem.group_labels)
    fe = plot_evidence(res, outdir / "diagnose_al_evidence.png")
    f0 = res["findings"][0] if res["findings"] else None
    intro = [
        "Measured f1 and f2 of an aluminium beam (50 mm x 2 mm) clamped at four free lengths with an "
        "accelerometer on its tip (E. Demirkaya, Vibration-Tester-ADXL357-FFT, MIT licence; "
        "`examples/measurements/al_cantilever_length_sweep.*`). The baseline is the bare clamped "
        "Euler-Bernoulli beam: the sensor is deliberately not declared.",
        "",
    ]
    if f0 and f0["cause"] == "point-mass":
        m = f0["derived"]["mass_kg"]
        mu = f0["parameters"]["mu"]
        xi = f0["parameters"]["xi"]
        intro += [f"Diagnosis: a point mass of {m * 1e3:.2f} ± {mu['sigma'] / mu['value'] * m * 1e3:.2f} g at "
                  f"x/L = {xi['value']:.3f} ± {xi['sigma']:.3f}; the authors state a 5 g sensor "
                  f"(one of their scripts uses 10 g) mounted at the tip. Run time {res['runtime_s']:.2f} s.", ""]
    text = "\n".join(intro) + "\n" + markdown(res, fr.name, fe.name)
    conf = diagnose(EXAMPLES / "afm_cantilever_one_mode.toml")
    text += ("\n\n**A confounded case.** Only the first flapwise mode of a Si cantilever with a hidden tip mass "
             "(`examples/measurements/afm_cantilever_one_mode.*`): one number fits every cause that can move one "
             "frequency, so the diagnosis names the group and the measurements that would separate it instead of "
             "guessing.\n\n```\n" + summary(conf) + "\n```\n")
    return text


