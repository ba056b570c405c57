"""``probedyn simulate ffm`` (FFM line scans, section 2.1.4–2.1.5), ``probedyn fit-ffm`` and the
report section on nano-friction."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from probedyn.commands._apps import app, simulate_app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, markdown_table, save


def _savefig(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    from probedyn.core.io import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format=path.suffix.lstrip("."))
    plt.close(fig)
    return path


def plot_scan(res, summary: dict, path: Path, title: str = "") -> Path:
    """Lateral force vs base position, with the F_s / F_c levels and detected slips."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.4), constrained_layout=True)
    ax.plot(res.base * 1e9, res.lateral_force * 1e9, lw=1, label="lateral force k_x (V t - x)")
    if summary.get("F_s"):
        ax.axhline(summary["F_s"] * 1e9, ls="--", c="gray", lw=0.8, label="F_s")
        ax.axhline(summary["F_c"] * 1e9, ls=":", c="gray", lw=0.8, label="F_c")
    ax.set_xlabel("base position [nm]")
    ax.set_ylabel("lateral force [nN]")
    ax.set_title(title or f"{summary['preset']} / {summary['model']}: {summary['regime']}")
    ax.legend(fontsize=8, loc="lower right")
    return _savefig(fig, path)


def _human(d: dict) -> str:
    def nn(v, s=1e9, u="nN", f=".4g"):
        return "-" if v is None else f"{v * s:{f}} {u}"

    return "\n".join([
        f"FFM line scan: preset {d['preset']}, model {d['model']}, {d['scan_length_m'] * 1e9:.4g} nm at "
        f"{d['scan_speed_m_s'] * 1e6:.4g} um/s ({d['wall_time_s'] * 1e3:.1f} ms, {d['n_steps']} steps)",
        f"regime: {d['regime']}   slips: {d['n_slips']}",
        f"static friction  {nn(d['static_friction_n'])}   kinetic friction {nn(d['kinetic_friction_n'])}",
        f"period {nn(d['period_m'], 1e9, 'nm')}   first slip at {nn(d['first_slip_m'], 1e9, 'nm')}",
        f"quasi-static estimates: first slip F_s/k_x = {nn(d['first_slip_estimate_m'], 1e9, 'nm')}, "
        f"period (F_s-F_c)/k_x = {nn(d['period_estimate_m'], 1e9, 'nm')}",
        f"max lateral force {nn(d['max_force_n'])}",
        *([f"note: {d['preset_scan']['note']}"] if d.get("preset_scan") else []),
    ])


@simulate_app.command("ffm")
def ffm_cmd(
    preset: str = typer.Option("mica", "--preset", help="mica (Table 2.1) or vamwcnt (Table 2.2)."),
    model: str = typer.Option("bristle", "--model", help="Friction model: bristle, lugre or pt."),
    length: Optional[float] = typer.Option(
        None, "--length",
        help="Scan length in m. Default: the preset's scan range (10 nm for mica), extended when "
             "needed to the first slip plus four periods (F_s/k_x + 4 (F_s-F_c)/k_x), so that the "
             "stick-slip regime can be measured; the result for the preset's own range is reported too."),
    sets: Optional[list[str]] = SET_OPT,
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Simulate one FFM line scan (eqs 2.13-2.16); report static/kinetic friction, period, regime."""
    from probedyn.core.params import parse_sets
    from probedyn.schemes import ffm as F

    ov = parse_sets(sets)
    res, summary = F.run_ffm(preset, model, ov, length=length)
    if length is None and summary["regime"] == "presliding" and summary.get("first_slip_estimate_m"):
        # SOURCE-NOTES item 12: the source's scan range ends before the first slip. Report that
        # finding, then scan far enough to measure the stick-slip the preset's parameters give.
        source = {k: summary[k] for k in ("scan_length_m", "regime", "max_force_n", "n_slips")}
        auto = 1.05 * summary["first_slip_estimate_m"] + 4.0 * (summary["period_estimate_m"] or 0.0)
        res, summary = F.run_ffm(preset, model, ov, length=max(auto, summary["scan_length_m"]))
        summary["preset_scan"] = {
            **source,
            "note": f"no slip within the preset's {source['scan_length_m'] * 1e9:.3g} nm scan: the first slip "
                    f"needs F_s/k_x = {summary['first_slip_estimate_m'] * 1e9:.4g} nm of base travel "
                    "(SOURCE-NOTES item 12); the scan was extended to measure the stick-slip",
        }
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        summary["plot"] = str(plot_scan(res, summary, out / f"ffm_{preset}_{summary['model']}.png"))
        save(out, f"ffm_{preset}_{summary['model']}.json", summary)
    emit(summary, as_json, _human)


@app.command("fit-ffm")
def fit_ffm_cmd(
    trace: Path = typer.Argument(..., help="CSV: base position in m (or time in s), lateral force in N; '# speed = ...', '# k_x = ...' lines."),
    free: str = typer.Option("F_s,F_c", "--free", help="Comma-separated parameters to fit."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Cantilever/friction defaults (default: file's or mica)."),
    model: Optional[str] = typer.Option(None, "--model", help="Friction model (default: file's or bristle)."),
    out: Optional[Path] = OUT_OPT,
    as_json: bool = JSON_OPT,
) -> None:
    """Fit friction-model parameters to a measured lateral-force trace, with uncertainties."""
    from probedyn.schemes import fit as FT

    tr = FT.read_trace(trace)
    r = FT.fit_trace(tr, [s.strip() for s in free.split(",") if s.strip()], preset=preset, model=model, noise=None)
    summary = {k: v for k, v in r.items() if k not in ("residuals", "model_force", "base")}
    if out is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True, constrained_layout=True)
        ax[0].plot(r["base"] * 1e9, tr.force * 1e9, ".", ms=2, label="data")
        ax[0].plot(r["base"] * 1e9, r["model_force"] * 1e9, lw=1, label="fit")
        ax[0].set_ylabel("lateral force [nN]")
        ax[0].legend(fontsize=8)
        ax[1].plot(r["base"] * 1e9, r["residuals"] * 1e9, ".", ms=2)
        ax[1].set_ylabel("residual [nN]")
        ax[1].set_xlabel("base position [nm]")
        summary["plot"] = str(_savefig(fig, out / "fit_ffm.png"))
        save(out, "fit_ffm.json", summary)

    def human(d):
        lines = [f"fit of {', '.join(d['free'])} ({d['model']}, preset {d['preset']}): {d['message']}"]
        for n in d["free"]:
            lines.append(f"  {n} = {d['values'][n]:.6g} +- {d['uncertainties'][n]:.2g}")
        lines.append(f"residual rms {d['residual_rms_n']:.3g} N, max {d['residual_max_n']:.3g} N, "
                     f"{d['n_points']} points, {d['n_evaluations']} model evaluations")
        return "\n".join(lines)

    emit(summary, as_json, human)


def report_section(outdir: Path, quick: bool) -> str:
    """Nano-friction: mica and VAMWCNT scans, pre-sliding, alpha sweep, full-2D check,
    Prandtl–Tomlinson eta sweep and 2D zigzag, fit recovery."""
    import math

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from probedyn.schemes import ffm as F
    from probedyn.schemes import fit as FT
    from probedyn.schemes.friction.prandtl_tomlinson import MICA_LATTICE, lattice_sites, pt2d_scan

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    md = ["### Nano-friction and FFM line scans (sections 2.1.4–2.1.5)", ""]

    # 1. mica: the 10 nm scan of the source and a long scan
    res10, s10 = F.run_ffm("mica")
    resL, sL = F.run_ffm("mica", length=100e-9)
    pre = F.presliding_force(F.FFM.from_preset("mica"), resL.base)
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.4), constrained_layout=True)
    ax[0].plot(resL.base * 1e9, resL.lateral_force * 1e9, lw=1, label="FFM model (2.13-2.15, 2.7-2.9)")
    ax[0].plot(resL.base * 1e9, pre * 1e9, "--", lw=1, label="quasi-static pre-sliding")
    ax[0].axhline(sL["F_s"] * 1e9, ls="--", c="gray", lw=0.7)
    ax[0].axhline(sL["F_c"] * 1e9, ls=":", c="gray", lw=0.7)
    ax[0].axvspan(0, 10, color="orange", alpha=0.15, label="source's 10 nm scan range")
    ax[0].set_xlabel("base position [nm]")
    ax[0].set_ylabel("lateral force [nN]")
    ax[0].set_title("mica preset (Table 2.1)")
    ax[0].legend(fontsize=7)
    w = resL.base > 60e-9
    ax[1].plot(resL.base[w] * 1e9, resL.lateral_force[w] * 1e9, lw=1)
    ax[1].axhline(sL["F_s"] * 1e9, ls="--", c="gray", lw=0.7)
    ax[1].axhline(sL["F_c"] * 1e9, ls=":", c="gray", lw=0.7)
    ax[1].set_xlabel("base position [nm]")
    ax[1].set_title("zoom: regular sawtooth between F_c and F_s")
    _savefig(fig, outdir / "friction_mica.png")
    resV, sV = F.run_ffm("vamwcnt", length=4e-6)
    md += [
        "![mica](friction_mica.png)", "",
        markdown_table([
            dict(case="mica, 10 nm (source's scan)", **s10), dict(case="mica, 100 nm", **sL),
            dict(case="VAMWCNT, 4 um", **sV)],
            [("case", "scan", ""), ("regime", "regime", ""), ("n_slips", "slips", "d"),
             ("static_friction_n", "static [N]", ".5g"), ("kinetic_friction_n", "kinetic [N]", ".5g"),
             ("F_s", "F_s [N]", ".5g"), ("F_c", "F_c [N]", ".5g"), ("period_m", "period [m]", ".4g"),
             ("period_estimate_m", "(F_s-F_c)/k_x [m]", ".4g"), ("first_slip_m", "first slip [m]", ".4g"),
             ("first_slip_estimate_m", "F_s/k_x [m]", ".4g"), ("wall_time_s", "wall [s]", ".3f")]),
        "",
        "What sets the sawtooth in the source's model (SOURCE-NOTES item 12, checked with the model): the "
        "lateral force rises with slope k_x until it reaches F_s (first slip at F_s/k_x), drops to F_c and "
        "rises again: the period is (F_s - F_c)/k_x, set by the friction levels and the cantilever, "
        "not by the lattice. With Table 2.1 the first slip needs "
        f"{sL['first_slip_m'] * 1e9:.1f} nm of base travel, so the source's 10 nm scan is pure pre-sliding "
        f"(maximum force {s10['max_force_n'] * 1e9:.3f} nN = k_x x 10 nm); the period is "
        f"{sL['period_m'] * 1e9:.3f} nm, about five mica lattice constants. Table 2.2 gives slips of "
        f"{sV['period_m'] * 1e6:.3f} um after a first stick of {sV['first_slip_m'] * 1e6:.3f} um on a 1 um scan, "
        f"and they are abrupt ({sV['regime']}), not reverse. Parameters were not tuned.", ""]

    # 2. full 2D model vs 1D
    L2 = 80e-9
    full = F.line_scan_2d(F.FFM.from_preset("mica"), L2, n_out=3000)
    one = F.line_scan(F.FFM.from_preset("mica"), L2)
    dev = float(np.max(np.abs(np.interp(full["base"], one.base, one.lateral_force) - full["lateral_force"])))
    md += [f"Full 2D model (2.10)–(2.12), (2.14), (2.16) against the 1D reduction over {L2 * 1e9:.0f} nm: "
           f"max difference of the lateral force {dev:.3g} N (the y-motion relaxes to -F_cy/k_y in ~c_y/k_y = 70 ns "
           "and then leaves x alone).", ""]

    # 3. alpha sweep
    s0s = np.logspace(1, 5, 9) if not quick else np.logspace(1, 5, 5)
    rows = F.alpha_sweep(s0s, length=120e-9)
    md += ["#### Regime vs alpha = sigma0^2 / k_x (Fig 2.10)", "",
           "Shape measures: slip fraction (share of each cycle's base travel with falling force; < 1/2 regular, "
           ">= 1/2 reverse) and abruptness (steepest |dF/dX| over the median; a slip is a fold, so it is large).", "",
           markdown_table(rows, [("sigma0", "sigma0 [N/m]", ".3g"), ("alpha", "alpha [N/m]", ".3g"),
                                 ("regime", "regime", ""), ("n_slips", "slips", "d"),
                                 ("slip_fraction", "slip fraction", ".4f"), ("abruptness", "abruptness", ".3g"),
                                 ("period_m", "period [m]", ".4g"), ("max_force_n", "max force [N]", ".5g")]),
           "",
           "With the source's model the measure does not reach the reverse side: small alpha gives smooth "
           "sliding at F_s (the soft bristle creeps), large alpha the regular sawtooth; no alpha in this range "
           "gives reverse stick-slip.", ""]

    # 4. PT 1D
    etas = (0.3, 0.6, 0.9, 1.2, 2.0, 4.0) if not quick else (0.5, 2.0)
    pr = F.pt_eta_sweep(etas)
    fig, ax = plt.subplots(figsize=(7, 3.2), constrained_layout=True)
    a = MICA_LATTICE
    for eta in (0.6, 2.0):
        U0 = eta * 0.2 * a * a / (4 * math.pi**2)
        r = F.line_scan(F.FFM.from_preset("mica", "pt", {"U0": U0}), 6 * a)
        ax.plot(r.base / a, r.lateral_force * 1e12, lw=1, label=f"eta = {eta}")
    ax.set_xlabel("base position / a")
    ax.set_ylabel("lateral force [pN]")
    ax.set_title("Prandtl-Tomlinson (mica lattice, Table 2.1 cantilever)")
    ax.legend(fontsize=8)
    _savefig(fig, outdir / "friction_pt1d.png")
    md += ["#### Prandtl–Tomlinson (lattice period emerges)", "", "![PT 1D](friction_pt1d.png)", "",
           markdown_table(pr, [("eta", "eta", ".2f"), ("regime", "regime", ""), ("n_slips", "force maxima", "d"),
                               ("period_over_a", "period / a", ".5f"), ("abruptness", "abruptness", ".3g"),
                               ("smooth_abruptness_qs", "(1+eta)/(1-eta)", ".3g")]), ""]

    # 5. PT 2D zigzag
    fig, ax = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for axi, (lat, ang) in zip(ax, (("hex", 15.0), ("square", 20.0))):
        rr = pt2d_scan(lat, eta=4.0, angle_deg=ang, length=10 * a)
        st = lattice_sites(lat, a, (-a, 11 * a), (-2 * a, 5 * a))
        axi.plot(st[:, 0] / a, st[:, 1] / a, "o", ms=4, c="lightgray")
        axi.plot(rr.tip[0] / a, rr.tip[1] / a, lw=1, label="tip")
        axi.plot(rr.base[0] / a, rr.base[1] / a, "--", lw=0.8, label="base (scan line)")
        axi.set_aspect("equal")
        axi.set_xlim(-0.5, 10.5)
        axi.set_ylim(-1, 4.5)
        axi.set_title(f"{lat} lattice, scan {ang:g} deg off a1, eta = 4")
        axi.set_xlabel("x / a")
        axi.legend(fontsize=7)
    _savefig(fig, outdir / "friction_pt2d.png")
    md += ["2D Prandtl–Tomlinson: scanning off a lattice axis the tip hops from site to site and zigzags "
           "around the scan line.", "", "![PT 2D](friction_pt2d.png)", ""]

    # 6. fit recovery
    true = dict(F_s=13.4e-9, F_c=12.6e-9)
    rS = F.line_scan(F.FFM.from_preset("mica", overrides=true), 90e-9)
    b = np.linspace(0, 90e-9, 1500)
    rng = np.random.default_rng(1)
    fn = np.interp(b, rS.base, rS.lateral_force) + rng.normal(0, 0.05e-9, b.size)
    fr = FT.fit_trace(FT.Trace(base=b, force=fn, meta=dict(speed=2e-6, k_x=0.2)), noise=None)
    frow = [dict(name=n, true=true[n], fit=fr["values"][n], err=fr["uncertainties"][n],
                 rel=(fr["values"][n] - true[n]) / true[n]) for n in ("F_s", "F_c")]
    md += ["#### Fit recovery (synthetic mica trace, 1500 points, Gaussian noise 0.05 nN)", "",
           markdown_table(frow, [("name", "parameter", ""), ("true", "true [N]", ".5g"), ("fit", "fit [N]", ".6g"),
                                 ("err", "1-sigma [N]", ".2g"), ("rel", "relative error", ".2e")]),
           "", f"Residual rms {fr['residual_rms_n']:.3g} N (noise 5e-11 N), {fr['n_evaluations']} model evaluations.", ""]
    return "\n".join(md)
