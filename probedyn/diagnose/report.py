"""Plots and Markdown for a diagnosis: residuals before/after and the evidence bar chart."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["plot_residuals", "plot_evidence", "markdown"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_residuals(res: dict[str, Any], path: Path, labels: list[str] | None = None) -> Path:
    """Whitened residuals of the baseline and of the extended model (units of the stated noise)."""
    plt = _plt()
    before = np.asarray(res["baseline"]["residuals"], float)
    after = np.asarray(res["final"]["residuals"], float)
    fig, ax = plt.subplots(figsize=(7, 3.4))
    x = np.arange(len(before))
    if res["kind"] == "modal":
        w = 0.4
        ax.bar(x - w / 2, before, w, label="baseline", color="tab:red")
        ax.bar(x + w / 2, after, w, label=" + ".join(res["final"]["causes"]) or "baseline", color="tab:blue")
        if labels:
            ticks = labels + [f"Q {lb}" for lb in labels][: len(before) - len(labels)]
            ax.set_xticks(x, ticks[: len(x)], rotation=45, ha="right", fontsize=7)
    else:
        ax.plot(x, before, ".", ms=2, color="tab:red", label="baseline")
        ax.plot(x, after, ".", ms=2, color="tab:blue", label=" + ".join(res["final"]["causes"]) or "baseline")
        ax.set_xlabel("sample (scans concatenated)")
    ax.axhspan(-2, 2, color="0.9", zorder=0, label="±2 sigma")
    ax.set_ylabel("residual / noise sigma")
    ax.legend(fontsize=7)
    ax.set_title(f"verdict: {res['verdict']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_evidence(res: dict[str, Any], path: Path) -> Path:
    """Evidence of every candidate cause (nats); hatched: failed the likelihood-ratio test."""
    plt = _plt()
    cands = res["candidates"]
    fig, ax = plt.subplots(figsize=(6, 0.35 * max(len(cands), 3) + 1))
    names = [c["cause"] for c in cands][::-1]
    ev = [c["evidence"] if c["evidence"] is not None else 0.0 for c in cands][::-1]
    ok = [c["lr_pass"] for c in cands][::-1]
    evp = np.sign(ev) * np.log10(1 + np.abs(ev))
    bars = ax.barh(names, evp, color=["tab:green" if o and e > 0 else "0.7" for o, e in zip(ok, ev)])
    for b, o in zip(bars, ok):
        if not o:
            b.set_hatch("//")
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("sign(evidence) log10(1 + |evidence| / nat)")
    ax.set_title(res["method"]["evidence"], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def markdown(res: dict[str, Any], fig_resid: str | None = None, fig_ev: str | None = None) -> str:
    """Markdown summary of a diagnosis (the five steps)."""
    b = res["baseline"]
    lines = [f"**Step 1 — baseline.** chi² = {b['chi2']:.1f} for {b['dof']} degrees of freedom "
             f"(p = {b['p_value']:.2g}); residual RMS {b['residual_rms']:.2f} σ "
             f"({b['residual_rms_physical']:.3g} {res['baseline']['residual_unit'].split('physical: ')[-1].rstrip(')')})."]
    if b["parameters"]:
        lines.append("Calibrated: " + ", ".join(f"{k} = {v['value']:.4g} ± {v['sigma']:.2g}" for k, v in b["parameters"].items()) + ".")
    lines.append("")
    lines.append("**Step 2 — what it gets wrong.** " + _structure_text(res))
    if fig_resid:
        lines += ["", f"![residuals]({fig_resid})"]
    lines += ["", f"**Step 3 — candidate causes** ({res['method']['evidence']}; claim rule: {res['method']['claim_rule']}):", ""]
    lines.append("| cause | evidence [nat] | Δχ² | LR threshold | held-out RMS [σ] |")
    lines.append("|---|---:|---:|---:|---:|")
    for c in res["candidates"]:
        ev = "–" if c["evidence"] is None else f"{c['evidence']:.1f}"
        ho = "–" if c["heldout_rms"] is None else f"{c['heldout_rms']:.2f}"
        lines.append(f"| {c['cause']} | {ev} | {c['delta_chi2']:.1f} | {c['lr_threshold']:.1f} | {ho} |")
    if fig_ev:
        lines += ["", f"![evidence]({fig_ev})"]
    lines += ["", "**Steps 4–5 — extension and gain.**", "", "```", res["summary"], "```"]
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
