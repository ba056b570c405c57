"""Report section and figures of path tracking and probe control (source sections 3.2.3,
3.3.3, 3.4, 3.5). The command ``probedyn track --out`` draws :func:`tracking_figure`; the
report's :func:`section` runs the fast studies on the analytic-body plants (a few seconds)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from probedyn.plotting import axis_label, pyplot, savefig
from probedyn.report._tables import markdown_table
from probedyn.probes.tracking import control_plant, plant_factory
from probedyn.schemes.tracking import studies as S

AX_COLORS = {"x": "C0", "y": "C1", "z": "C2"}


def tracking_figure(res, path: str | Path, title: str = "") -> Path:
    """Desired vs simulated tip path, control effort and tracking error of one run (a
    :class:`~probedyn.schemes.tracking.simulate.TrackingResult`)."""
    plt = pyplot()
    fig = plt.figure(figsize=(11, 3.6), constrained_layout=True)
    d = len(res.outputs)
    if d == 3:
        ax0 = fig.add_subplot(1, 3, 1, projection="3d")
        ax0.plot(*(res.r.T * 1e6), "k--", lw=1, label="desired")
        ax0.plot(*(res.y.T * 1e6), "C3", lw=0.8, label="simulated")
        for setl, a in zip((ax0.set_xlabel, ax0.set_ylabel, ax0.set_zlabel), res.outputs):
            setl(axis_label(a, "um"))
    else:
        ax0 = fig.add_subplot(1, 3, 1)
        ax0.plot(res.r[:, 0] * 1e6, res.r[:, 1] * 1e6, "k--", lw=1, label="desired")
        ax0.plot(res.y[:, 0] * 1e6, res.y[:, 1] * 1e6, "C3", lw=0.8, label="simulated")
        ax0.set_xlabel(axis_label(res.outputs[0], "um"))
        ax0.set_ylabel(axis_label(res.outputs[1], "um"))
        ax0.set_aspect("equal")
    ax0.legend(loc="upper left")
    ax0.set_title("(a) tip path")
    ax1 = fig.add_subplot(1, 3, 2)
    for j, n in enumerate(res.inputs):
        ax1.plot(res.t, res.u[:, j], lw=1, label=n, color=AX_COLORS.get(n[-1], None))
    ax1.set_xlabel(axis_label("time", "s"))
    ax1.set_ylabel(axis_label("electrode voltage", "V"))
    ax1.legend()
    ax1.set_title("(b) control effort")
    ax2 = fig.add_subplot(1, 3, 3)
    for j, a in enumerate(res.outputs):
        ax2.plot(res.t, res.e[:, j] * 1e9, lw=0.8, label=f"{a} error", color=AX_COLORS.get(a))
    ax2.set_xlabel(axis_label("time", "s"))
    ax2.set_ylabel(axis_label("tip error", "nm"))
    ax2.legend()
    ax2.set_title("(c) tracking error")
    if title:
        fig.suptitle(title)
    return savefig(fig, path)


def holder_figure(study: dict, path: str | Path) -> Path:
    """Residual oscillation (relative to the path size) vs holder stiffness, one line per path rate."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8), constrained_layout=True)
    rows = study["rows"]
    for fp in sorted({r["path_hz"] for r in rows}):
        rr = [r for r in rows if r["path_hz"] == fp]
        ax.loglog([r["k_t"] for r in rr], [r["residual_rel"] for r in rr], "o-", label=f"{fp:g} turns/s (residual)")
        ax.loglog([r["k_t"] for r in rr], [r["predicted_residual_m"] / study["size_m"] for r in rr], ":", color="gray")
    ax.axhline(0.01, color="k", lw=0.7, ls="--", label="1 % of the path size")
    ax.plot([], [], ":", color="gray", label="v_jump / omega_lowest")
    ax.set_xlabel(axis_label("holder stiffness k_t", "N/m"))
    ax.set_ylabel("residual oscillation / path size")
    ax.set_title(f"{study['probe']}: {study['path']}, quasi-static inverse, abrupt start")
    ax.legend(fontsize="x-small")
    return savefig(fig, path)


def epsilon_figure(study: dict, path: str | Path) -> Path:
    """Tracking error vs eps (log-log) with the observed slopes."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8), constrained_layout=True)
    for name, p in study["observed_order"].items():
        rr = [r for r in study["rows"] if r["control"] == name and "max_error_m" in r]
        ax.loglog([r["eps"] for r in rr], [r["max_error_m"] for r in rr], "o-", label=f"{name}: slope {p:.2f}")
    e = np.array(sorted({r["eps"] for r in study["rows"]}))
    ax.set_xlabel("eps (stiffness scaling K -> K / eps^2, eq 3.46)")
    ax.set_ylabel(axis_label("max tracking error", "m"))
    ax.set_title("Tikhonov's O(eps) (3.56): observed orders")
    ax.legend(fontsize="x-small")
    ax.set_xlim(e.min() / 1.3, e.max() * 1.3)
    return savefig(fig, path)


def range_figure(study: dict, path: str | Path) -> Path:
    """Figs 3.17 and 3.18: stroke per volt from the formulas vs w0, h (duo-bimorph) and L, Re
    (piezotube), with the simulated plants' strokes at the default geometry."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(11, 3.8), constrained_layout=True)
    f17 = study["fig_3_17"]
    for i, h in enumerate(f17["h_m"]):
        ax[0].plot(np.asarray(f17["w0_m"]) * 1e6, np.asarray(f17["y_m_per_V"][i]) * 1e9, "-", color=f"C{i}",
                   label=f"y (3.31), h = {h * 1e6:g} µm")
        ax[0].plot(np.asarray(f17["w0_m"]) * 1e6, np.asarray(f17["z_m_per_V"][i]) * 1e9, "--", color=f"C{i}",
                   label=f"z (3.32), h = {h * 1e6:g} µm")
    for r in study["duo-bimorph"]["rows"]:
        ax[0].plot([5.0], [r["formula_m_per_V"] * 1e9], "ko", ms=4)
    ax[0].plot([], [], "ko", ms=4, label="default probe (formula at the beam end)")
    ax[0].set_yscale("log")
    ax[0].set_xlabel(axis_label("electrode gap w0", "um"))
    ax[0].set_ylabel(axis_label("stroke per volt", "nm/V"))
    ax[0].set_title("duo-bimorph (Fig 3.17)")
    ax[0].legend(fontsize="x-small", ncol=2)
    f18 = study["fig_3_18"]
    for i, Re in enumerate(f18["Re_m"]):
        L = np.asarray(f18["L_m"]) * 1e3
        ax[1].plot(L, np.asarray(f18["lateral_m_per_V"][i]) * 1e9, "-", color=f"C{i}",
                   label=f"lateral, 3.34 corrected, Re = {Re * 1e3:g} mm")
        ax[1].plot(L, np.asarray(f18["lateral_printed_m_per_V"][i]) * 1e9, ":", color=f"C{i}",
                   label=f"lateral, 3.34 printed, Re = {Re * 1e3:g} mm")
        ax[1].plot(L, np.asarray(f18["axial_m_per_V"][i]) * 1e9, "--", color=f"C{i}", label=f"axial 3.35, Re = {Re * 1e3:g} mm")
    ax[1].set_yscale("log")
    ax[1].set_xlabel(axis_label("tube length L", "mm"))
    ax[1].set_ylabel(axis_label("stroke per volt", "nm/V"))
    ax[1].set_title(f"piezotube (Fig 3.18), wall {f18['wall_m'] * 1e6:g} µm")
    ax[1].legend(fontsize="xx-small", ncol=1)
    return savefig(fig, path)


def section(outdir: Path, quick: bool) -> str:
    """Open-loop tracking of both probes, the holder-stiffness residual, the 3.5 control problem
    (stability of the four laws, conic path), the frequency-response check of the simulator.
    Analytic-body plants with analytic gains (fast); docs/tracking.md has the FEM-body numbers."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    md = ["Plants: the two-body model (3.37) with the body from beam/tube formulas and the holder as a point "
          "mass, **analytic gains** (3.31, 3.32, 3.35; 3.34 with its factor 2 removed; the eccentric tube from the "
          "free piezo strain on the eccentric annulus). Simulator: exponential integrator, exact for the linear part. "
          "Details and the FEM-body numbers: docs/tracking.md.", ""]
    rows = []
    for probe in ("duo-bimorph", "piezotube"):
        st = S.open_loop_study(plant_factory("analytic"), probe, durations=(0.05,))
        for r in st["rows"]:
            rows.append({"probe": probe, **{k: r[k] for k in ("path", "duration_s", "inverse")},
                         "err": r["max_error_m"] * 1e9, "rel": r["relative_max_error"],
                         "v": ", ".join(f"{k} {v:.3g}" for k, v in r["voltage_peak_V"].items())})
    md += ["**Open-loop tracking (Figs 3.8, 3.14)**: reference paths of size 0.5 µm in 50 ms, quasi-static and "
           "exact dynamic inverse of the plant (1 s paths: docs/tracking.md).", "",
           markdown_table(rows, [("probe", "probe", ""), ("path", "path", ""), ("duration_s", "duration [s]", "g"),
                            ("inverse", "inverse", ""), ("err", "max error [nm]", ".3g"), ("rel", "max error / size", ".2e"),
                            ("v", "voltage peaks [V]", "")]), ""]
    hs = S.holder_stiffness_study(plant_factory("analytic"), "piezotube", stiffnesses=(1, 10, 100), path_hz=(10.0,) if quick else (10.0, 100.0))
    holder_figure(hs, outdir / "tracking_holder.png")
    md += ["**Holder stiffness (Fig 3.16)**: sphere, quasi-static inverse started at full speed; the residual "
           "oscillation scales as v_jump / omega_lowest.", "",
           markdown_table([{**r, "res": r["residual_rel"], "forced": r["forced_rel"]} for r in hs["rows"]],
                     [("k_t", "k_t [N/m]", "g"), ("path_hz", "turns/s", "g"), ("f_lowest_hz", "lowest mode", "hz4"),
                      ("res", "residual / size", ".2e"), ("forced", "forced error / size", ".2e")]), "",
           "![holder stiffness](tracking_holder.png)", ""]
    plant = control_plant()
    cp = S.control_problem(plant)
    srows = [{"law": k, "stable": "yes" if v["stable"] else "**no**", "rate": v["max_real_per_s"],
              "zeta": v["min_damping_ratio"], "f": v["least_damped_hz"]} for k, v in cp["stability"].items()]
    md += ["**Control problem (3.5)**: piezotube, k_t = 10 N/m, delta_x = delta_y = 5 µm. Stability on the full model:", "",
           markdown_table(srows, [("law", "law", ""), ("stable", "stable", ""), ("rate", "max Re(lambda) [1/s]", ".3g"),
                             ("zeta", "min damping ratio", ".3g"), ("f", "least damped mode", "hz4")]), ""]
    cmp_ = S.controller_comparison(plant, paths=("cone",), disturbances=(0.0,), keep=True)
    crow = []
    for r in cmp_["rows"]:
        if r["stable"]:
            m = r["metrics"]
            crow.append({"law": r["control"], "d": r["disturbance_scale"], "max": m["max_error_m"] * 1e9,
                         "rel": m["relative_max_error_after_transient"], "v": max(m["voltage_peak_V"].values())})
        else:
            crow.append({"law": r["control"], "d": r["disturbance_scale"], "max": None, "rel": None, "v": None})
    run = cmp_["runs"].get(("cone", 0.0, "composite (3.50-3.54)"))
    if run is not None:
        tracking_figure(run, outdir / "tracking_cone.png", "piezotube, conic path, composite control (3.50-3.54)")
    md += ["**Conic path (Fig 3.21)** (unstable laws not simulated; the KBr disturbance runs are in "
           "docs/tracking.md):", "",
           markdown_table(crow, [("law", "law", ""), ("d", "KBr scale", "g"), ("max", "max error [nm]", ".3g"),
                            ("rel", "max error / extent after 5 %", ".2e"), ("v", "peak voltage [V]", ".3g")]), "",
           "![conic path](tracking_cone.png)", ""]
    rg = S.range_study(plant_factory("analytic"))
    range_figure(rg, outdir / "tracking_range.png")
    rrows = [{"probe": p, **r} for p in ("duo-bimorph", "piezotube") for r in rg[p]["rows"]]
    md += ["**Range per volt (Figs 3.17, 3.18)**: formulas (SOURCE-NOTES 8: 3.34 halved) and the simulated plants' "
           "static tip stroke (analytic body: at the beam/tube end); the piezo FEM will replace the formulas.", "",
           markdown_table([{**r, "f": r["formula_m_per_V"] * 1e9, "p": r["plant_m_per_V"] * 1e9} for r in rrows],
                     [("probe", "probe", ""), ("axis", "axis", ""), ("formula", "formula", ""), ("f", "formula [nm/V]", ".4g"),
                      ("p", "plant [nm/V]", ".4g"), ("plant_over_formula", "plant / formula", ".4f")]), "",
           "![range per volt](tracking_range.png)", ""]
    if not quick:
        es = S.epsilon_study(plant, eps=(1.0, 0.5, 0.25, 0.125), printed=False, holder_only=False)
        epsilon_figure(es, outdir / "tracking_epsilon.png")
        md += ["**Tikhonov's O(eps) (3.55-3.56)**: stiffness scaling K -> K/eps^2 (3.46), fast cone (20 ms); observed "
               "orders " + ", ".join(f"{k}: {v:.2f}" for k, v in es["observed_order"].items()) + " (composite: O(eps^3) "
               "with the slow model's feedforward; see docs/tracking.md).", "", "![epsilon study](tracking_epsilon.png)", ""]
    fr = S.frequency_response_check(plant, h=1e-5)
    md += [f"**Simulator check**: circle at {fr['f_path_hz']:g} turns/s, composite control: simulated vs "
           f"transfer-function steady-state error differ by {fr['max_abs_difference_m']:.3g} m (tolerance from the "
           f"first-order hold {fr['tolerance_m']:.3g} m; forced error amplitude {fr['forced_error_amplitude_m']:.3g} m).",
           "", f"Section time {time.perf_counter() - t0:.1f} s."]
    return "\n".join(md)
