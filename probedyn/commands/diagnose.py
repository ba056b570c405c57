"""``probedyn diagnose``: show what probedyn's simulation gets wrong, name the cause, measure the gain.

The command is argument parsing + one library call (:func:`probedyn.diagnose.engine.run`) + output;
the prose of the summary, the Markdown and the two figures are written here (library modules
neither print nor plot).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Optional

import numpy as np
import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, emit, format_table


def _human_list(rows: list[dict[str, Any]]) -> str:
    out = []
    for kind in ("modal", "friction", "force"):
        out.append(f"{kind} causes:")
        for c in rows:
            if c["kind"] != kind:
                continue
            ps = ", ".join(f"{p['name']} [{p['unit']}]" for p in c["parameters"])
            out.append(f"  {c['id']:<22} {c['title']}  ({ps})")
            out.append(f"  {'':<22} needs: {c['needs']}")
    return "\n".join(out)


def _fmt_param(name: str, p: dict[str, Any]) -> str:
    if not p.get("identifiable", True):
        return f"{name} = {p['value']:.4g} (not identifiable)"
    s = p.get("sigma")
    txt = f"{name} = {p['value']:.4g}" + (f" ± {s:.2g}" if s is not None and math.isfinite(s) else "")
    if p.get("one_sided"):
        lo, hi = p["interval"]
        txt += f" (68 % interval [{lo:.3g}, {hi:.3g}], one-sided)"
    if p.get("at_bound"):
        txt += f" [at {p['bound']} bound]"
    return txt


def summary(res: dict[str, Any]) -> str:
    """The diagnosis in a few lines (also the text block of the report)."""
    b = res["baseline"]
    lines = [f"baseline: chi2 = {b['chi2']:.1f} for {b['dof']} dof (p = {b['p_value']:.2g}), residual RMS "
             f"{b['residual_rms']:.2f} sigma"]
    if res.get("peaks"):
        rej = [p for p in res["peaks"]["peaks"] if not p["accepted"]]
        acc = [p for p in res["peaks"]["peaks"] if p["accepted"]]
        lines.append("peaks: " + ", ".join(f"{p['family']} {p['order']} at {p['f0_Hz']:.6g} Hz" for p in acc))
        for p in rej:
            lines.append(f"  rejected peak at {p['f0_Hz']:.6g} Hz: {'; '.join(p['reasons'])}")
    v = res["verdict"]
    if v == "no-significant-discrepancy":
        lines.append("no significant discrepancy: the residual is consistent with the stated noise; nothing is claimed")
    elif v == "unexplained":
        lines.append("significant discrepancy, but no catalog cause explains it out of sample")
    for f in res["findings"]:
        ps = ", ".join(_fmt_param(k, p) for k, p in f["parameters"].items())
        g = f["gain"]
        ho = (f", held-out {g['heldout_rms_before']:.2f} -> {g['heldout_rms_after']:.2f}"
              if g.get("heldout_rms_before") is not None and g.get("heldout_rms_after") is not None else "")
        lines.append(f"{f['status']}: {f['cause']} ({ps}); evidence {f['evidence']:.1f} nats; residual RMS "
                     f"{g['residual_rms_before']:.2f} -> {g['residual_rms_after']:.2f} sigma{ho}")
        for fl in f["flags"]:
            lines.append(f"  flag: {fl}")
    for c in res["confounded"]:
        lines.append(f"CONFOUNDED within {c['margin_nats']:.2f} nats: " + ", ".join(
            f"{n} ({e:.1f})" for n, e in zip(c["causes"], c["evidence"])))
        for m in c["separating_measurements"]:
            pv = ", ".join(f"{k} {v:.5g}" for k, v in m["predictions"].items())
            lines.append(f"  to separate them, measure {m['measure']} [{m['unit']}]: {pv} (noise {m['sigma']:.2g})")
        if c["pairs_left_unseparated"]:
            lines.append("  still indistinguishable: " + "; ".join(" vs ".join(p) for p in c["pairs_left_unseparated"]))
    fin = res["final"]
    if res["findings"]:
        fm = fin.get("full_model")
        where = " (full model re-solved)" if fm is not None else ""
        ho = f", held-out RMS {fin['heldout_rms']:.2f} sigma (p = {fin['heldout_p_value']:.2g})" if fin.get("heldout_rms") is not None else ""
        lines.append(f"final model{where}: chi2 = {fin['chi2']:.1f} for {fin['dof']} dof (p = {fin['p_value']:.2g}), "
                     f"residual RMS {fin['residual_rms']:.2f} sigma{ho}")
    lines.append(f"verdict: {v}" + ("" if v in ("no-significant-discrepancy", "explained") else
                                    " (" + "; ".join(res["verdict_reasons"]) + ")"))
    return "\n".join(lines)


def plot_residuals(res: dict[str, Any], path: Path, labels: list[str] | None = None) -> Path:
    """Whitened residuals of the baseline and of the final (re-solved) model."""
    from probedyn.plotting import axis_label, pyplot, savefig

    plt = pyplot()
    before = np.asarray(res["baseline"]["residuals"], float)
    after = np.asarray(res["final"]["residuals"], float)
    name = " + ".join(res["final"]["causes"]) or "baseline"
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    x = np.arange(len(before))
    if res["kind"] in ("modal", "spectrum", "timeseries"):
        w = 0.4
        ax.bar(x - w / 2, before, w, label="baseline (probe FEM)", color="tab:red")
        ax.bar(x + w / 2, after, w, label=f"{name} (FEM re-solve)", color="tab:blue")
        if labels:
            ticks = list(labels) + [f"Q {lb}" for lb in labels]
            ax.set_xticks(x, ticks[: len(x)], rotation=45, ha="right", fontsize=7)
        ax.set_xlabel("measured mode")
    else:
        ax.plot(x, before, ".", ms=2, color="tab:red", label="baseline")
        ax.plot(x, after, ".", ms=2, color="tab:blue", label=name)
        ax.set_xlabel("sample (scans / segments concatenated)")
    ax.axhspan(-2, 2, color="0.9", zorder=0, label="±2 σ")
    ax.set_ylabel(axis_label("residual / noise σ"))
    ax.legend(fontsize=7)
    ax.set_title(f"{res['kind']} diagnosis: verdict {res['verdict']}", fontsize=9)
    return savefig(fig, path)


def plot_evidence(res: dict[str, Any], path: Path) -> Path:
    """Held-out evidence of every candidate (linear axis, nats); grey: not claimable."""
    from probedyn.plotting import axis_label, pyplot, savefig

    plt = pyplot()
    cands = [c for c in res["candidates"] if c["evidence"] is not None]
    fig, ax = plt.subplots(figsize=(6.5, 0.4 * max(len(cands), 3) + 1.2))
    if cands:
        names = [c["cause"] for c in cands][::-1]
        ev = np.array([c["evidence"] for c in cands][::-1])
        ok = [c["lr_pass"] and e > 0 for c, e in zip(cands[::-1], ev)]
        ax.barh(names, ev, color=["tab:green" if o else "0.7" for o in ok], label="held-out evidence")
        top = ev.max()
        ax.axvline(top - res["method"]["evidence_margin_nats"], color="k", ls="--", lw=0.8,
                   label=f"winner − {res['method']['evidence_margin_nats']:.2f} nats (confounding margin)")
        ax.legend(fontsize=7, loc="lower right")
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel(axis_label("evidence", "nat"))
    ax.set_title(res["method"]["evidence"], fontsize=8)
    return savefig(fig, path)


def markdown(res: dict[str, Any], fig_resid: str | None = None, fig_ev: str | None = None) -> str:
    b = res["baseline"]
    mm = res["method"].get("model", {})
    lines = [f"**Baseline** ({mm.get('baseline', '')}): chi² = {b['chi2']:.1f} for {b['dof']} degrees of freedom "
             f"(p = {b['p_value']:.2g}), residual RMS {b['residual_rms']:.2f} σ."]
    cal = {k: v for k, v in b["parameters"].items() if not k.startswith("_")}
    if cal:
        lines.append("Calibrated: " + ", ".join(_fmt_param(k, v) for k, v in cal.items()) + ".")
    if fig_resid:
        lines += ["", f"![Whitened residuals of the baseline and of the final model]({fig_resid})"]
    lines += ["", f"**Candidate causes** ({res['method']['evidence']}; claim rule: {res['method']['claim_rule']}):", "",
              "| cause | evidence [nat] | Δχ² | LR threshold | held-out RMS [σ] |", "|---|---:|---:|---:|---:|"]
    for c in res["candidates"]:
        ev = "–" if c["evidence"] is None else f"{c['evidence']:.1f}"
        ho = "–" if c["heldout_rms"] is None else f"{c['heldout_rms']:.2f}"
        lines.append(f"| {c['cause']} | {ev} | {c['delta_chi2']:.1f} | {c['lr_threshold']:.1f} | {ho} |")
    if fig_ev:
        lines += ["", f"![Held-out evidence of the candidate causes]({fig_ev})"]
    lines += ["", "**Result**", "", "```", summary(res), "```"]
    return "\n".join(lines)


@app.command("diagnose")
def diagnose_cmd(
    measurement: Optional[Path] = typer.Argument(None, help="Measurement: TOML sidecar or its CSV."),
    list_causes: bool = typer.Option(False, "--list-causes", help="List the catalog of causes and exit."),
    as_json: bool = JSON_OPT,
    out: Optional[Path] = OUT_OPT,
) -> None:
    """Calibrate probedyn's model, rank catalog causes out of sample, extend the model, report the gain."""
    from probedyn.core.errors import ParameterError

    if list_causes:
        from probedyn.diagnose.causes import catalog_table

        emit(catalog_table(), as_json, _human_list)
        return
    if measurement is None:
        raise ParameterError("diagnose needs a MEASUREMENT file (or --list-causes)")
    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.problems import make_problem

    problem = make_problem(measurement)
    res = diagnose(problem)
    res["summary"] = summary(res)
    if out is not None:
        from probedyn.core.io import write_json, write_text

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        fr = plot_residuals(res, out / "residuals.png", getattr(problem, "group_labels", None)
                            if res["kind"] != "friction" else None)
        fe = plot_evidence(res, out / "evidence.png")
        write_json(out / "diagnose.json", res)
        write_text(out / "diagnose.md", markdown(res, fr.name, fe.name) + "\n")
        res["files"] = [str(out / "diagnose.json"), str(out / "diagnose.md"), str(fr), str(fe)]

    def human(r: dict[str, Any]) -> str:
        rows = [{"cause": c["cause"], "evidence": c["evidence"], "dchi2": c["delta_chi2"],
                 "LR": "pass" if c["lr_pass"] else "fail"} for c in r["candidates"]]
        txt = r["summary"] + "\n\n" + format_table(rows, [("cause", "cause", ""), ("evidence", "evidence [nat]", ".1f"),
                                                           ("dchi2", "delta chi2", ".1f"), ("LR", "LR test", "")])
        if "files" in r:
            txt += "\n\nwritten: " + ", ".join(r["files"])
        return txt

    emit(res, as_json, human)


def report_section(outdir: Path, quick: bool) -> str:
    """The worked example: the real aluminium beam with its tip sensor left out of the baseline."""
    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.problems import make_problem

    here = Path(__file__).resolve().parents[2] / "examples" / "measurements"
    problem = make_problem(here / "al_cantilever_length_sweep.toml")
    res = diagnose(problem)
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    fr = plot_residuals(res, outdir / "diagnose_al_residuals.png", problem.group_labels)
    fe = plot_evidence(res, outdir / "diagnose_al_evidence.png")
    intro = ("Measured f1 and f2 of an aluminium beam (50 mm x 2 mm) clamped at four free lengths with an accelerometer "
             "on its tip (E. Demirkaya, Vibration-Tester-ADXL357-FFT, MIT licence; "
             "`examples/measurements/al_cantilever_length_sweep.*`). The baseline is probedyn's 3D FEM of the bare "
             "clamped beam: the sensor is deliberately not declared. Run time "
             f"{res['runtime_s']:.1f} s.\n\n")
    return intro + markdown(res, fr.name, fe.name)
