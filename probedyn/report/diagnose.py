"""Report section: measured data and their diagnosis (:mod:`probedyn.diagnose`).

The worked example is a real aluminium beam whose tip sensor is left out of the baseline (the
baseline is probedyn's 3D FEM of the bare clamped beam); a second, confounded case shows what the
diagnosis says when one measured mode cannot tell causes apart. Figures
``diagnose_al_residuals.png`` and ``diagnose_al_evidence.png``; :func:`plot_residuals`,
:func:`plot_evidence`, :func:`summary` and :func:`markdown` are also what ``probedyn diagnose``
prints and writes with ``--out``.

The text prints what the library returns (verdict, findings, confounded groups, the final model
re-solved with the FEM) from the result's fields, so a verdict and a confounded group are stated
together, parameters that cannot be identified say so instead of a number, and a p-value below
double precision prints as a bound.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.io import make_dirs
from probedyn.diagnose.engine import run
from probedyn.diagnose.problems import make_problem
from probedyn.plotting import axis_label, fmt_hz, pyplot, savefig

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "measurements"


def _p(p: float) -> str:
    """A p-value; 0.0 (below the smallest double) prints as a bound."""
    return "< 1e-300" if p == 0 else f"= {p:.2g}"


def _val(v: float, unit: str) -> str:
    """A predicted value with its unit (frequencies through fmt_hz, lengths in µm)."""
    if unit == "Hz":
        return fmt_hz(v)
    if unit == "m":
        return f"{v * 1e6:.5g} µm"
    return f"{v:.5g} {unit}"


def _fmt_param(name: str, p: dict[str, Any]) -> str:
    if not p.get("identifiable", True):
        return f"{name} = {p['value']:.4g} (not identifiable)"
    s = p.get("sigma")
    txt = f"{name} = {p['value']:.4g}" + (f" ± {s:.2g}" if s is not None and math.isfinite(s) else "")
    if p.get("one_sided") or p.get("sweep_points_within"):
        lo, hi = p["interval"]
        txt += f" (68 % interval [{lo:.3g}, {hi:.3g}], " + (
            "one-sided)" if p.get("one_sided") else f"{p['sweep_points_within']} points of its swept profile within it)")
    if p.get("at_bound"):
        txt += f" [at {p['bound']} bound" + ("" if p.get("bound_binding", True) else ", not binding") + "]"
    return txt


#: the baseline's laws of the corrugation against the load (``probedyn.diagnose.friction.LOAD_LAWS``), in words
LOAD_LAW_WORDS = {"amontons": "proportional to the load (the registry's law)",
                  "load-independent": "independent of the load (the plain PT model)"}


def _term_values(t: dict[str, Any]) -> str:
    """What a declared term taken on was fitted to, in words (its derived values)."""
    d = t.get("derived") or {}
    if "attempt_frequency_Hz" in d:
        return f" (attempt frequency {d['attempt_frequency_Hz']:.3g} Hz at the declared {d['temperature_K']:g} K)"
    if d.get("k_contact_N_per_m"):
        return f" (contact {d['k_contact_N_per_m']:.3g} N/m: the stick rises at {d['k_stick_N_per_m']:.3g} N/m)"
    return ""


def summary(res: dict[str, Any]) -> str:
    """The diagnosis in a few lines (also the text block of the report)."""
    b = res["baseline"]
    lines = [f"baseline: chi2 = {b['chi2']:.1f} for {b['dof']} dof (p {_p(b['p_value'])}), residual RMS "
             f"{b['residual_rms']:.2f} sigma"]
    law = b.get("load_law")
    if law:
        other = {k: v for k, v in law["chi2"].items() if k != law["law"]}
        wc = law.get("with_cause")
        if law.get("chosen_with") and wc:
            sc = wc["score"]
            lines.append(f"baseline corrugation {LOAD_LAW_WORDS.get(law['law'], law['law'])}: chosen with the lead cause "
                         f"{wc['cause']} (-2 ln L {sc[law['law']]:.1f} nested in it, against "
                         + ", ".join(f"{v:.1f} {LOAD_LAW_WORDS.get(k, k)}" for k, v in sc.items() if k != law["law"])
                         + f"; taken where lower by more than {wc['threshold']:.2f}); the baseline alone fit better "
                         "under the other law (chi2 " + ", ".join(f"{v:.1f} {k}" for k, v in law["chi2"].items())
                         + "); the record does not say which law its instrument follows")
        else:
            lines.append(f"baseline corrugation {LOAD_LAW_WORDS.get(law['law'], law['law'])}: the better of the laws the "
                         f"simulation runs (chi2 {law['chi2'][law['law']]:.1f}, against "
                         + ", ".join(f"{v:.1f} {LOAD_LAW_WORDS.get(k, k)}" for k, v in other.items())
                         + ", before the terms and the noise model below"
                         + (f"; kept with the lead cause {wc['cause']}, -2 ln L "
                            + ", ".join(f"{v:.1f} {k}" for k, v in wc["score"].items()) if wc else "")
                         + "); the record does not say which its instrument follows")
    for t in b.get("declared_terms") or ():
        why = f"{t['implied_by']} implies" if t.get("implied_by") else "the declared conditions imply"
        if t["taken"]:
            what = _term_values(t)
            lines.append(f"baseline includes {t['title'].lower()}{what}: {why} it, and it "
                         f"lowers -2 ln L by {t['lr_gain']:.1f} (threshold {t['lr_threshold']:.2f})")
        elif t["lr_gain"] > t["lr_threshold"]:
            lines.append(f"baseline without {t['title'].lower()}: {why} it, and it lowers "
                         f"-2 ln L by {t['lr_gain']:.1f}, but the baseline with it still leaves an excess chi2 - dof of "
                         f"{t['remainder']:.1f}: a gain within that misfit is not separable from it")
        else:
            lines.append(f"baseline without {t['title'].lower()}: {why} it, but it lowers "
                         f"-2 ln L by {t['lr_gain']:.1f} only (threshold {t['lr_threshold']:.2f})")
    for t in b.get("declared_terms_after_claims") or ():
        if t["taken"]:
            what = _term_values(t)
            lines.append(f"{t['title'].lower()}{what} joined the model after the claim of {t['after']}: it lowers "
                         f"-2 ln L by {t['lr_gain']:.1f} there, beyond the excess chi2 - dof of {t['remainder']:.1f} left")
    st = (b.get("structure") or {}).get("static")
    if st:
        lines.append(f"static spring constant: measured {st['k_meas_N_per_m']:.5g} ± {st['sigma_N_per_m']:.2g} N/m "
                     f"(1 sigma, the FEM's discretisation {st['fem_discretisation_N_per_m']:.2g} N/m included); baseline residual "
                     f"{st['residual_sigma']:+.2f} sigma ({100 * st['residual_rel']:+.2f} %)")
    nz = res["method"].get("noise") or {}
    if str(nz.get("estimator", "")).startswith("declared"):
        lines.append(f"noise: {'AR(1) rho = ' + format(nz['rho'], '.2f') if nz['model'] == 'AR(1)' else 'white'} as "
                     f"declared ([noise] correlation; the record itself reads {nz['rho_scatter']:.2f} from its differences, "
                     f"residual lag-one correlation {nz['rho_lag1']:.2f})"
                     + (": residuals are whitened (innovations) in every fit" if nz["model"] == "AR(1)" else ""))
    elif nz.get("model") == "AR(1)" and "innovation_sd" in nz:
        on = f" on {nz['judged_on']}" if nz.get("judged_on") else ""
        how = ("the residuals' variance against their second differences (more power at the record's scale than "
               f"the differences' AR(1) of rho {nz['rho_scatter']:.2f} gives: 1/f-like)"
               if nz["rho"] > nz["rho_scatter"] + 1e-9 else "first against second differences")
        lines.append(f"noise: correlated, AR(1) rho = {nz['rho']:.2f} (no stated noise: {how}"
                     f"{on}; marginal sigma {nz['marginal_sd']:.2f}x the scatter-read one; residual lag-one correlation "
                     f"{nz['rho_lag1']:.2f}): residuals are whitened (innovations) in every fit")
    elif nz.get("model") == "AR(1)":
        lines.append(f"noise: correlated, AR(1) rho = {nz['rho']:.2f} (the stated noise is {1 / nz['high_frequency_scale']:.2f}x "
                     f"its sample-to-sample part; residual lag-one correlation {nz['rho_lag1']:.2f}): residuals are "
                     "whitened (innovations) in every fit")
    elif nz.get("model") == "white + AR(1)":
        on = f" on {nz['judged_on']}" if nz.get("judged_on") else ""
        lines.append(f"noise: white floor plus a slow AR(1) of rho {nz['rho']:.3f} carrying {100 * nz['share']:.0f} % of "
                     f"the variance (no stated noise: white from sample to sample, rho {nz['rho_scatter']:.2f} from the "
                     f"differences, but lag-one correlation {nz['rho_lag1']:.2f}{on}; likelihood ratio "
                     f"{nz['mixture_lr']:.1f} against white): residuals are whitened in every fit")
    elif nz.get("model") == "white" and nz.get("white_scale"):
        on = f" on {nz['judged_on']}" if nz.get("judged_on") else ""
        lines.append(f"noise: white (no stated noise: its sigma re-read from the second differences{on}, "
                     f"{nz['white_scale']:.2f}x the part of the record first read)")
    if nz.get("sequence_scales"):
        sc = ", ".join(f"{x:.2f}" for x in nz["sequence_scales"])
        lines.append(f"noise: each recording sequence on its own scale ({sc} x the sigma; for a force curve approach, "
                     f"retract), their second differences differing beyond chance (chi2 {nz['sequence_scale_chi2']:.0f} "
                     f"against {nz['sequence_scale_threshold']:.1f})")
    th = (res.get("data") or {}).get("thermal_force_noise", "")
    if th.startswith("the tip's"):
        lines.append(f"noise: {th}")
    if res.get("peaks"):
        rej = [p for p in res["peaks"]["peaks"] if not p["accepted"]]
        acc = [p for p in res["peaks"]["peaks"] if p["accepted"]]
        shape = res["peaks"].get("line_shape", "SHO")
        lines.append("peaks: " + ", ".join(f"{p['family']} {p['order']} at {p['f0_Hz']:.6g} Hz" for p in acc)
                     + (f" ({shape} lines" + (", fitted together" if res["peaks"].get("joint_fits") else "") + ")"
                        if shape != "SHO" or res["peaks"].get("joint_fits") else ""))
        if res["peaks"].get("thermal_area_factor") is not None:
            lines.append(f"  thermal areas ({res['peaks'].get('detector', 'displacement')} detector): "
                         f"{res['peaks']['thermal_area_factor']:.3g} x equipartition (the detector's calibration)")
        for p in rej:
            lines.append(f"  rejected peak at {p['f0_Hz']:.6g} Hz: {'; '.join(p['reasons'])}")
        for p in acc:
            for note in p.get("notes", []):
                lines.append(f"  peak at {p['f0_Hz']:.6g} Hz: {note}")
        for a in (res["peaks"].get("labels_from") or {}).get("ambiguous_labellings") or []:
            vals = ", ".join(f"{k} = {v:.4g}" for k, v in a["parameters"].items())
            lines.append(f"  another labelling fits as well: best model {a['best_model']}" + (f" ({vals})" if vals else ""))
    v = res["verdict"]
    if v == "no-significant-discrepancy":
        lines.append("no significant discrepancy: the residual is consistent with the "
                     + ("stated" if res.get("data", {}).get("noise_stated", True) else "estimated") + " noise; nothing is claimed")
    elif v == "unexplained":
        lines.append("significant discrepancy, but no catalog cause explains it out of sample")
    for f in res["findings"]:
        ps = ", ".join(_fmt_param(k, p) for k, p in f["parameters"].items())
        g = f["gain"]
        ho = (f", held-out {g['heldout_rms_before']:.2f} -> {g['heldout_rms_after']:.2f}"
              if g.get("heldout_rms_before") is not None and g.get("heldout_rms_after") is not None else "")
        lines.append(f"{f['status']}: {f['cause']} ({ps}); evidence {f['evidence']:.1f} nats; residual RMS "
                     f"{g['residual_rms_before']:.2f} -> {g['residual_rms_after']:.2f} sigma{ho}")
        for nm, it in f["parameters"].items():
            if it.get("sigma_jacobian") is not None:
                lines.append(f"  {nm}: sigma from the {it['method']}; the Jacobian's alone {it['sigma_jacobian']:.2g}")
        jd = f.get("derived_sigma_jackknife") or {}
        if f.get("derived"):
            lines.append("  derived: " + ", ".join(
                f"{k} = {v:.4g}" + (f" ± {jd[k]:.2g}" if k in jd else "") for k, v in f["derived"].items()
                if isinstance(v, (int, float))))
        for fl in f["flags"]:
            lines.append(f"  flag: {fl}")
        for nt in f.get("notes") or []:
            lines.append(f"  note: {nt}")
        pa = f.get("parsimony")
        if pa and pa.get("contains_leader") and not any(pa["container"] in c["causes"] for c in res["confounded"]):
            vals = ", ".join(f"{k} = {v:.4g}" for k, v in pa["container_parameters"].items())
            lines.append(f"  {pa['container']} ({vals}; evidence {pa['container_evidence']:.1f} nats) contains it as a "
                         "limit: its extra parameter is not supported, so it is the same explanation, not a rival")
    for x in res.get("not_claimed") or []:
        lines.append(f"not claimed: {x['cause']} (Delta chi2 {x['delta_chi2']:.4g}; the chain up to it leaves an excess "
                     f"chi2 - dof of {x['remainder']:.4g} that no cause describes: not separable from that model error)")
    for c in res["confounded"]:
        lines.append(f"CONFOUNDED within {c['margin_nats']:.2f} nats: " + ", ".join(
            f"{n} ({e:.1f})" for n, e in zip(c["causes"], c["evidence"])))
        if c.get("not_claimed"):
            lines.append(f"  not claimed, but as well supported: {', '.join(c['not_claimed'])} (each failed its own "
                         f"likelihood-ratio test)")
        for m in c["separating_measurements"]:
            pv = ", ".join(f"{k} {_val(v, m['unit'])}" for k, v in m["predictions"].items())
            lines.append(f"  to separate them, measure {m['measure']}: {pv} (noise {_val(m['sigma'], m['unit'])})")
        if c["pairs_left_unseparated"]:
            lines.append("  still indistinguishable: " + "; ".join(" vs ".join(p) for p in c["pairs_left_unseparated"]))
    fin = res["final"]
    if res["findings"]:
        fm = fin.get("full_model")
        where = " (full model re-solved)" if fm is not None else ""
        ho = f", held-out RMS {fin['heldout_rms']:.2f} sigma (p {_p(fin['heldout_p_value'])})" if fin.get("heldout_rms") is not None else ""
        lines.append(f"final model{where}: chi2 = {fin['chi2']:.1f} for {fin['dof']} dof (p {_p(fin['p_value'])}), "
                     f"residual RMS {fin['residual_rms']:.2f} sigma{ho}")
    lines.append(f"verdict: {v}" + ("" if v in ("no-significant-discrepancy", "explained") else
                                    " (" + "; ".join(res["verdict_reasons"]) + ")"))
    return "\n".join(lines)


def plot_residuals(res: dict[str, Any], path: Path, labels: list[str] | None = None) -> Path:
    """Whitened residuals of the baseline and of the final (re-solved) model."""
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
        rl = res.get("data", {}).get("residual_labels")
        if rl and len(rl) == len(x):  # one label per residual (modes, static, Q, model-form priors)
            ax.set_xticks(x, rl, rotation=45, ha="right", fontsize=7)
        elif labels:
            ticks = list(labels) + ([f"Q {lb}" for lb in labels] if res.get("data", {}).get("with_Q") else [])
            # residuals beyond the measured ones: the modal noise model's model-form prior pseudo-residuals
            ticks += [f"model-form prior {i + 1}" for i in range(len(x) - len(ticks))]
            ax.set_xticks(x, ticks[: len(x)], rotation=45, ha="right", fontsize=7)
        if rl and len(rl) == len(x):
            parts = ["mode frequencies"] + (["static spring constant"] if "static spring constant" in rl else []) \
                + (["Q"] if any(lb.startswith("Q ") for lb in rl) else []) + ["model-form priors"]
            ax.set_xlabel("observable (" + ", ".join(parts) + ")")
        else:
            ax.set_xlabel("measured mode")
    else:
        ax.plot(x, before, ".", ms=2, color="tab:red", label="baseline")
        ax.plot(x, after, ".", ms=2, color="tab:blue", label=name)
        ax.set_xlabel("sample (scans / segments concatenated)")
    ax.axhspan(-2, 2, color="0.9", zorder=0, label="±2 σ")
    ax.set_ylabel(axis_label("residual / noise σ"))
    ax.legend(fontsize=7)
    ax.set_title(f"{res['kind']} diagnosis: verdict {res['verdict']}", fontsize=9)
    fig.tight_layout()
    return savefig(fig, path)


def plot_evidence(res: dict[str, Any], path: Path) -> Path:
    """Held-out evidence of every candidate (linear axis, nats); grey: not claimable."""
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
    fig.tight_layout()
    return savefig(fig, path)


def markdown(res: dict[str, Any], fig_resid: str | None = None, fig_ev: str | None = None) -> str:
    b = res["baseline"]
    mm = res["method"].get("model", {})
    lines = [f"**Baseline** ({mm.get('baseline', '')}): chi² = {b['chi2']:.1f} for {b['dof']} degrees of freedom "
             f"(p {_p(b['p_value'])}), residual RMS {b['residual_rms']:.2f} σ."]
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


#: the worked example's result as ``probedyn diagnose al_cantilever_length_sweep.toml --json`` wrote it
#: (four FEMs and their reductions: minutes on two cores); the report prints it (the slow test
#: ``tests/test_diagnose_cli.py`` recomputes the diagnosis), ``PROBEDYN_REPORT_RECOMPUTE=1`` recomputes it here
AL_RESULT = EXAMPLES / "al_cantilever_length_sweep.diagnose.json"


def section(outdir: Path, quick: bool) -> str:
    import json

    outdir = Path(outdir)
    make_dirs(outdir)
    import os

    if AL_RESULT.exists() and os.environ.get("PROBEDYN_REPORT_RECOMPUTE") != "1":
        res = json.loads(AL_RESULT.read_text())
        how = (f"result stored in `{AL_RESULT.name}` by `probedyn diagnose "
               "examples/measurements/al_cantilever_length_sweep.toml --json`; `PROBEDYN_REPORT_RECOMPUTE=1` "
               "recomputes it for the report")
        labels = res.get("data", {}).get("group_labels")
    else:
        problem = make_problem(EXAMPLES / "al_cantilever_length_sweep.toml")
        res = run(problem)
        how = "computed for this report"
        labels = problem.group_labels
    fr = plot_residuals(res, outdir / "diagnose_al_residuals.png", labels)
    fe = plot_evidence(res, outdir / "diagnose_al_evidence.png")
    intro = ("Measured f1 and f2 of an aluminium beam (50 mm x 2 mm) clamped at four free lengths with an accelerometer "
             "on its tip (E. Demirkaya, Vibration-Tester-ADXL357-FFT, MIT licence; "
             "`examples/measurements/al_cantilever_length_sweep.*`). The baseline is probedyn's 3D FEM of the bare "
             "clamped beam: the sensor is deliberately not declared (the authors state a 5 g sensor at the tip). "
             f"Run time {res['runtime_s']:.0f} s ({how}).\n\n")
    text = intro + markdown(res, fr.name, fe.name)
    if not quick:
        conf = run(EXAMPLES / "afm_cantilever_one_mode.toml")
        text += ("\n\n**A confounded case.** Only the first flapwise mode of a Si cantilever 3 % thicker than nominal "
                 "(`examples/measurements/afm_cantilever_one_mode.*`): one number fits every cause that can move one "
                 "frequency, so the diagnosis names the group and the measurements that would separate it instead of "
                 "guessing.\n\n```\n" + summary(conf) + "\n```\n")
    return text
