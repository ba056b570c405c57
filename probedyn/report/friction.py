"""Report section: nano-friction and FFM line scans (source sections 2.1.4-2.1.5).

Figures: ``friction_mica.png`` (the mica scan, zoom on the sawtooth), ``friction_pt1d.png``
(1D Prandtl–Tomlinson), ``friction_pt2d.png`` (2D zigzag); the figure functions of
``probedyn simulate ffm --out`` (:func:`plot_scan`) and ``probedyn fit-ffm --out``
(:func:`plot_fit`) live here too."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from probedyn.core.io import make_dirs
from probedyn.core.presets import preset as table
from probedyn.plotting import axis_label, pyplot, savefig
from probedyn.report._tables import markdown_table
from probedyn.schemes import ffm as F
from probedyn.schemes.ffm_studies import deviation_2d_1d, fit_recovery, pt_trace
from probedyn.schemes.friction.prandtl_tomlinson import lattice_sites, pt2d_scan


def _levels(ax, F_s: float, F_c: float, label: bool = True) -> None:
    """Dashed F_s and dotted F_c lines (nN), each with a legend entry."""
    ax.axhline(F_s * 1e9, ls="--", c="gray", lw=0.8, label="F_s (static friction level)" if label else None)
    ax.axhline(F_c * 1e9, ls=":", c="gray", lw=0.8, label="F_c (kinetic friction level)" if label else None)


def plot_scan(res, summary: dict, path: Path, title: str = "") -> Path:
    """Lateral force vs base position of one FFM line scan, with the F_s / F_c levels."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.4), constrained_layout=True)
    ax.plot(res.base * 1e9, res.lateral_force * 1e9, lw=1, label="lateral force k_x (V t - x)")
    if summary.get("F_s"):
        _levels(ax, summary["F_s"], summary["F_c"])
    ax.set_xlabel(axis_label("base position", "nm"))
    ax.set_ylabel(axis_label("lateral force", "nN"))
    ax.set_title(title or f"{summary['preset']} / {summary['model']}: {summary['regime']}")
    ax.legend(fontsize=8, loc="lower right")
    return savefig(fig, path)


def plot_fit(fit: dict, trace, path: Path) -> Path:
    """A measured trace, the fitted model and the residuals (``probedyn fit-ffm --out``)."""
    plt = pyplot()
    fig, ax = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True, constrained_layout=True)
    ax[0].plot(fit["base"] * 1e9, trace.force * 1e9, ".", ms=2, label="data")
    ax[0].plot(fit["base"] * 1e9, fit["model_force"] * 1e9, lw=1, label=f"fit ({fit['model']} model)")
    ax[0].set_ylabel(axis_label("lateral force", "nN"))
    ax[0].legend(fontsize=8)
    ax[1].plot(fit["base"] * 1e9, fit["residuals"] * 1e9, ".", ms=2, label="data - fit")
    ax[1].set_ylabel(axis_label("residual", "nN"))
    ax[1].set_xlabel(axis_label("base position", "nm"))
    ax[1].legend(fontsize=8)
    return savefig(fig, path)


def plot_mica(resL, sL: dict, pre: np.ndarray, source_range_nm: float, path: Path) -> Path:
    """The long mica scan with the quasi-static pre-sliding branch, and a zoom on the sawtooth."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6), constrained_layout=True)
    b = resL.base * 1e9
    ax[0].plot(b, resL.lateral_force * 1e9, lw=1, label="FFM model (2.13-2.15, 2.7-2.9)")
    ax[0].plot(b, pre * 1e9, "--", lw=1, label="quasi-static pre-sliding")
    _levels(ax[0], sL["F_s"], sL["F_c"])
    ax[0].axvspan(0, source_range_nm, color="orange", alpha=0.15, label=f"source's {source_range_nm:g} nm scan range")
    ax[0].set_xlabel(axis_label("base position", "nm"))
    ax[0].set_ylabel(axis_label("lateral force", "nN"))
    ax[0].set_title("mica preset (Table 2.1)")
    ax[0].legend(fontsize=7)
    w = resL.base > 60e-9
    ax[1].plot(b[w], resL.lateral_force[w] * 1e9, lw=1, label="FFM model")
    _levels(ax[1], sL["F_s"], sL["F_c"])
    ax[1].set_xlabel(axis_label("base position", "nm"))
    ax[1].set_ylabel(axis_label("lateral force", "nN"))
    ax[1].set_title("zoom: regular sawtooth between F_c and F_s")
    ax[1].legend(fontsize=7, loc="lower right")
    return savefig(fig, path)


def plot_pt1d(etas, path: Path, n_lattice: float = 6) -> Path:
    """Lateral force of 1D Prandtl–Tomlinson scans over the mica lattice for a few eta."""
    a = table("table-4.2-mica")["a"]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.2), constrained_layout=True)
    for eta in etas:
        r = pt_trace(eta, n_lattice)
        ax.plot(r.base / a, r.lateral_force * 1e12, lw=1, label=f"eta = {eta}")
    ax.set_xlabel("base position / a")
    ax.set_ylabel(axis_label("lateral force", "pN"))
    ax.set_title("Prandtl-Tomlinson (mica lattice a, Table 2.1 cantilever)")
    ax.legend(fontsize=8)
    return savefig(fig, path)


def plot_pt2d(path: Path, cases=(("hex", 15.0), ("square", 20.0)), eta: float = 4.0, n_lattice: int = 10) -> Path:
    """2D Prandtl–Tomlinson: tip path over the lattice sites, scanned off the lattice axis."""
    a = table("table-4.2-mica")["a"]
    plt = pyplot()
    fig, ax = plt.subplots(1, len(cases), figsize=(10, 4), constrained_layout=True)
    for axi, (lat, ang) in zip(np.atleast_1d(ax), cases):
        rr = pt2d_scan(lat, eta=eta, angle_deg=ang, length=n_lattice * a)
        st = lattice_sites(lat, a, (-a, (n_lattice + 1) * a), (-2 * a, 5 * a))
        axi.plot(st[:, 0] / a, st[:, 1] / a, "o", ms=4, c="lightgray", label="lattice sites")
        axi.plot(rr.tip[0] / a, rr.tip[1] / a, lw=1, label="tip")
        axi.plot(rr.base[0] / a, rr.base[1] / a, "--", lw=0.8, label="base (scan line)")
        axi.set_aspect("equal")
        axi.set_xlim(-0.5, n_lattice + 0.5)
        axi.set_ylim(-1, 4.5)
        axi.set_title(f"{lat} lattice, scan {ang:g}° off a1, eta = {eta:g}")
        axi.set_xlabel("x / a")
        axi.set_ylabel("y / a")
        axi.legend(fontsize=7, loc="upper left")
    return savefig(fig, path)


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    make_dirs(outdir)
    md = ["### Nano-friction and FFM line scans (sections 2.1.4–2.1.5)", ""]

    # 1. mica: the 10 nm scan of the source and a long scan; VAMWCNT
    res10, s10 = F.run_ffm("mica")
    resL, sL = F.run_ffm("mica", length=100e-9)
    pre = F.presliding_force(F.FFM.from_preset("mica"), resL.base)
    plot_mica(resL, sL, pre, s10["scan_length_m"] * 1e9, outdir / "friction_mica.png")
    resV, sV = F.run_ffm("vamwcnt", length=4e-6)
    md += [
        "![mica](friction_mica.png)", "",
        "*Lateral force of the FFM model (generalised bristle, Table 2.1 mica) over a 100 nm scan; dashed: "
        "quasi-static pre-sliding branch; grey: the friction levels F_s and F_c; right: zoom on the sawtooth.*", "",
        markdown_table([
            dict(case="mica, 10 nm (source's scan)", **s10), dict(case="mica, 100 nm", **sL),
            dict(case="VAMWCNT, 4 µm", **sV)],
            [("case", "scan", ""), ("regime", "regime", ""), ("n_slips", "slips", "d"),
             ("static_friction_n", "static [N]", ".5g"), ("kinetic_friction_n", "kinetic [N]", ".5g"),
             ("F_s", "F_s [N]", ".5g"), ("F_c", "F_c [N]", ".5g"), ("period_m", "period [m]", ".4g"),
             ("period_estimate_m", "(F_s-F_c)/k_x [m]", ".4g"), ("first_slip_m", "first slip [m]", ".4g"),
             ("first_slip_estimate_m", "F_s/k_x [m]", ".4g"), ("wall_time_s", "wall [s]", ".3f")]),
        "",
        "What sets the sawtooth in the source's model (departure 11, checked with the model): the "
        "lateral force rises with slope k_x until it reaches F_s (first slip at F_s/k_x), drops to F_c and "
        "rises again: the period is (F_s - F_c)/k_x, set by the friction levels and the cantilever, "
        "not by the lattice. With Table 2.1 the first slip needs "
        f"{sL['first_slip_m'] * 1e9:.1f} nm of base travel, so the source's 10 nm scan is pure pre-sliding "
        f"(maximum force {s10['max_force_n'] * 1e9:.3f} nN = k_x x 10 nm); the period is "
        f"{sL['period_m'] * 1e9:.3f} nm, about five mica lattice constants. Table 2.2 gives slips of "
        f"{sV['period_m'] * 1e6:.3f} µm after a first stick of {sV['first_slip_m'] * 1e6:.3f} µm on a 1 µm scan, "
        f"and they are abrupt ({sV['regime']}), not reverse. Parameters were not tuned.", ""]

    # 2. full 2D model vs 1D
    L2 = 80e-9
    dev = deviation_2d_1d("mica", L2)
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
           "gives reverse stick-slip (departure 12).", ""]

    # 4. PT 1D
    etas = (0.3, 0.6, 0.9, 1.2, 2.0, 4.0) if not quick else (0.5, 2.0)
    pr = F.pt_eta_sweep(etas)
    plot_pt1d((0.6, 2.0), outdir / "friction_pt1d.png")
    md += ["#### Prandtl–Tomlinson (lattice period emerges)", "", "![PT 1D](friction_pt1d.png)", "",
           "*Lateral force of the FFM model with the registry's Prandtl–Tomlinson friction (Table 2.1 "
           "cantilever, mica lattice a of Table 4.2) for eta = 0.6 (smooth sliding) and 2 (stick-slip at the lattice period).*", "",
           markdown_table(pr, [("eta", "eta", ".2f"), ("regime", "regime", ""), ("n_slips", "force maxima", "d"),
                               ("period_over_a", "period / a", ".5f"), ("abruptness", "abruptness", ".3g"),
                               ("smooth_abruptness_qs", "(1+eta)/(1-eta)", ".3g")]), ""]

    # 5. PT 2D zigzag
    plot_pt2d(outdir / "friction_pt2d.png")
    md += ["2D Prandtl–Tomlinson: scanning off a lattice axis the tip hops from site to site and zigzags "
           "around the scan line.", "", "![PT 2D](friction_pt2d.png)", "",
           "*Tip path (2D Prandtl–Tomlinson, eta = 4, Table 2.1 cantilever) over the sites of a hexagonal and a "
           "square lattice of constant a, base moving along the dashed scan line.*", ""]

    # 6. fit recovery
    fr = fit_recovery()
    md += [f"#### Fit recovery (synthetic mica trace, {fr['n_points']} points, Gaussian noise {fr['noise_n'] * 1e9:g} nN)", "",
           markdown_table(fr["rows"], [("name", "parameter", ""), ("true", "true [N]", ".5g"), ("fit", "fit [N]", ".6g"),
                                       ("err", "1-sigma [N]", ".2g"), ("rel", "relative error", ".2e")]),
           "", f"Residual rms {fr['residual_rms_n']:.3g} N (noise {fr['noise_n']:.3g} N), "
           f"{fr['n_evaluations']} model evaluations.", ""]
    return "\n".join(md)
