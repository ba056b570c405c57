"""Report section: vibrational nano-placing (source section 4.2, Figs 4.18-4.28).

Numbers come from :mod:`probedyn.schemes.placing.studies`; this module draws the figures and
writes the prose. Default mode: the Table 4.4 cantilever's FEM reduced to a Ritz basis (one
eigen-solve), 8 x 8 outcome maps on threads; quick mode: the Euler-Bernoulli beam of
the same geometry, same maps. The 64 x 64 map is computed on demand
(``probedyn place release fem --map omega_A --n 64 --out DIR``, ``benchmarks/placing.py``).

One figure per phase (also written by ``probedyn place ... --out``): :func:`plot_approach`
(Fig 4.20, frequency shift), :func:`plot_capture` (Figs 4.21, 4.18), :func:`plot_release` (Fig 4.22,
outcome maps), :func:`plot_landing` (Figs 4.23, 4.27, 4.28), :func:`plot_multi` (Rayleigh-Ritz,
Figs 4.25, 4.26); :func:`plot_release_map`, :func:`plot_release_run` for single maps and runs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.plotting import axis_label, fmt_hz, pyplot, savefig
from probedyn.report._tables import markdown_table
from probedyn.schemes.placing.probe import TABLE

OUTCOME_COLORS = {0: "#d9d9d9", 1: "#fdae61", 2: "#2b83ba", 3: "#d7191c", 4: "#000000", 5: "#8c510a",
                  -1: "#7b3294"}
OUTCOME_NAMES = {0: "attached", 1: "recaptured", 2: "released", 3: "undecided", 4: "tip reaches substrate",
                 5: "weight exceeds adhesion", -1: "failed"}


def _a(v, *_args) -> np.ndarray:
    """A float array of study data (JSON nulls become NaN)."""
    return np.array(v, dtype=float)


def _plain(fig) -> None:
    """Plain tick labels on every axis (``1e-06`` instead of mathtext ``10^-6``: the mathtext parser
    cost most of this section's drawing time) and no minor-tick labels."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    def fmt(v, _pos):
        if v == 0:
            return "0"
        a = abs(v)
        return f"{v:.0e}".replace("e+0", "e").replace("e-0", "e-") if (a >= 1e4 or a < 1e-2) else f"{v:g}"

    for ax in fig.axes:
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale in ("log", "symlog"):
                axis.set_major_formatter(FuncFormatter(fmt))
                axis.set_minor_formatter(NullFormatter())
            else:
                axis.set_major_formatter(FuncFormatter(lambda v, _p: f"{v:g}"))


def _save(fig, path: Path) -> Path:
    """Plain tick labels, fixed margins (``tight_layout`` measured every tick label once more:
    a second of CPU per figure here), atomic save through :func:`probedyn.plotting.savefig`."""
    _plain(fig)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.09, top=0.94, wspace=0.3, hspace=0.35)
    return savefig(fig, path)


def _md(rows: list[dict[str, Any]], cols: list[tuple[str, str, str]]) -> str:
    """:func:`probedyn.report._tables.markdown_table` with NaN shown as missing."""
    clean = [{k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()} for r in rows]
    return markdown_table(clean, cols)


# ------------------------------------------------------------------------------------------
# Figures: panels drawn on given axes, composed into one figure per phase
# ------------------------------------------------------------------------------------------


def _fig_4_18(cap: dict[str, Any], a, b) -> None:
    c4 = cap["pl_curves"]
    ref = c4["uniform_8"]
    a.plot(_a(ref["delta_m"]) * 1e9, _a(ref["force_n"]) * 1e9, "k-", lw=2, label="MD, exact (registry)")
    for key, st, lab in (("uniform_4", "C1--", "4 segments, uniform"), ("uniform_8", "C0--", "8 segments, uniform"),
                         ("graded_8", "C2:", "8 segments, graded (j/N)^4")):
        c = c4[key]
        a.plot(_a(c["nodes_m"]) * 1e9, _a(c["node_forces_n"]) * 1e9, st, marker="o", ms=3, label=lab)
    md = cap["md"]
    a.plot([md["penetration_m"] * 1e9], [0.0], "rs", label=f"zero load: k1 = {md['k1_n_per_m']:.3g} N/m")
    a.set_xlabel(axis_label("penetration", "nm"))
    a.set_ylabel(axis_label("contact force", "nN"))
    a.set_title("Fig 4.18: MD (lambda = 2), piecewise linear", fontsize=9)
    a.legend(fontsize=6.5)
    for sp, st in (("uniform", "o-"), ("graded", "s-")):
        rows = cap["pl_errors"][sp]
        b.loglog([r["n_segments"] for r in rows], [r["max_error_n"] * 1e9 for r in rows], st,
                 label=f"{sp} nodes: order {cap['pl_orders'][sp]:.2f}")
    b.set_xlabel("number of linear segments N")
    b.set_ylabel(axis_label("max. error", "nN"))
    b.set_title("error of the piecewise-linear contact", fontsize=9)
    b.legend(fontsize=7)


def _fig_4_20(ap: dict[str, Any], a, b, c) -> None:
    fb = ap["force_balance"]
    for cv in fb["curves"]:
        a.plot(_a(cv["w_m"]) * 1e9, _a(cv["net_force_n"]) * 1e9, label=f"z0 = {cv['z0_m'] * 1e9:.3f} nm")
    js = fb["jump"]
    a.plot([js["w_star_m"] * 1e9], [0.0], "ks", label="jump into contact")
    a.axhline(0, color="0.5", lw=0.6)
    a.set_ylim(-1.5 * js["force_at_jump_n"] * 1e9, 1.5 * js["force_at_jump_n"] * 1e9)
    a.set_xlabel(axis_label("tip deflection towards the sample", "nm"))
    a.set_ylabel(axis_label("net force -k w + F_vdW", "nN"))
    a.set_title("Fig 4.20a: force balance", fontsize=9)
    a.legend(fontsize=6.5)
    wb = _a(ap["response_omega_rad_s"]) / (2 * math.pi * ap["f0_hz"])
    for r in ap["response"]:
        lab = f"z0 = {r['z0_m'] * 1e9:.3g} nm, f_n = {fmt_hz(r['omega_n_rad_s'] / (2 * math.pi), 4)}"
        b.plot(wb, r["gain"], label=lab)
        c.plot(wb, np.degrees(r["phase_rad"]), label=lab)
    for ax, t, yl in ((b, "Fig 4.20b: gain (4.19)", "gain |G|"), (c, "Fig 4.20c: phase (4.20)", axis_label("phase lag", "deg"))):
        ax.set_xlabel("omega / sqrt(k/m)")
        ax.set_ylabel(yl)
        ax.set_title(t, fontsize=9)
        ax.legend(fontsize=6)


def _shift(ap: dict[str, Any], ax) -> None:
    """Relative difference of each frequency-shift estimate from the exact orbit period."""
    rows = ap["shift_rows"]
    zs = ap["jump"]["z0_star_m"]
    for i, A in enumerate(ap["amplitudes_m"]):
        rr = [r for r in rows if r["A_m"] == A]
        z = np.array([r["z0_m"] for r in rr]) / zs
        ex = np.array([np.nan if r["df_exact_hz"] is None else r["df_exact_hz"] for r in rr], float)
        col = f"C{i}"
        for key, st, lab in (("df_small_hz", "-", "(4.21), small amplitude"), ("df_giessibl_hz", "--", "Giessibl"),
                             ("df_giessibl_sqrt_hz", ":", "Giessibl, sqrt form")):
            v = np.array([r[key] for r in rr], float)
            ax.semilogy(z, np.abs(v / ex - 1), st, color=col, label=f"A = {A * 1e9:.3g} nm: {lab}")
        sim = np.array([np.nan if r["df_sim_hz"] is None else r["df_sim_hz"] for r in rr], float)
        ok = np.isfinite(sim)
        ax.semilogy(z[ok], np.maximum(np.abs(sim[ok] / ex[ok] - 1), 1e-12), "o", color=col, mfc="none",
                    label=f"A = {A * 1e9:.3g} nm: time simulation")
        gone = ~np.isfinite(ex)
        if np.any(gone):
            ax.plot(z[gone], np.full(gone.sum(), 0.5), "x", color=col, ms=9, label=f"A = {A * 1e9:.3g} nm: no orbit (jump)")
    ax.set_xlabel("base distance z0 / static jump distance z0*")
    ax.set_ylabel("|Delta f / Delta f(exact orbit) - 1|")
    ax.set_title(f"frequency shift vs the exact orbit period, f0 = {fmt_hz(ap['f0_hz'])}", fontsize=9)
    ax.legend(fontsize=5.5, ncol=2)


def plot_approach(ap: dict[str, Any], path: Path) -> Path:
    """Fig 4.20 (a) net force vs deflection, (b) gain, (c) phase of (4.19)-(4.20), and (d) the
    frequency shift: small amplitude (4.21), Giessibl, exact orbit, time simulation."""
    plt = pyplot()
    fig, axs = plt.subplots(2, 2, figsize=(12, 8.5))
    _fig_4_20(ap, axs[0, 0], axs[0, 1], axs[1, 0])
    _shift(ap, axs[1, 1])
    return _save(fig, path)


def plot_capture(cap: dict[str, Any], path: Path) -> Path:
    """Fig 4.21: the first three mode shapes for increasing K = k1 L^3/EI (4.40 lines, FEM
    circles); the first frequency against the sample mass (corrected vs printed end
    condition); Fig 4.18: the MD contact and its piecewise-linear approximation with its error."""
    plt = pyplot()
    fig, axs = plt.subplots(2, 3, figsize=(14, 8))
    sh = cap["shapes"]
    x = _a(sh["x_over_L"])
    for j in range(3):
        ax = axs[0, j]
        for i, a in enumerate(sh["analytic"]):
            col = f"C{i}"
            ax.plot(x, a["shapes"][j], "-", color=col, lw=1.2, label=f"K = {a['K']:g}, bL = {a['bL'][j]:.3f}")
            if sh["fem"]:
                fx = _a(sh["fem_x_over_L"])
                fs = _a(sh["fem"][i]["shapes"][j])
                sel = slice(None, None, max(1, fx.size // 15))
                ax.plot(fx[sel], fs[sel], "o", color=col, ms=3, mfc="none")
        ax.set_title(f"Fig 4.21, mode {j + 1}" + (": lines (4.40), circles FEM" if sh["fem"] else ": (4.40)"), fontsize=9)
        ax.set_xlabel("x / L")
        ax.set_ylabel("normalised deflection")
        ax.legend(fontsize=6)
    mc = cap["mass_curve"]
    ax = axs[1, 0]
    for K, col in ((0.0, "C0"), (3.0, "C3")):
        ax.plot(mc["mu"], _a(mc[f"K{K:g}_corrected"]) ** 2 / 1.8751040687**2, "-", color=col,
                label=f"K = {K:g}: (k1 - M w^2), corrected")
        ax.plot(mc["mu"], _a(mc[f"K{K:g}_printed"]) ** 2 / 1.8751040687**2, "--", color=col,
                label=f"K = {K:g}: (k1 + M w^2), printed")
    ax.set_xlabel("sample mass M / (rho A L)")
    ax.set_ylabel("first frequency / bare cantilever's")
    ax.set_title("an attached mass lowers the frequency", fontsize=9)
    ax.legend(fontsize=6.5)
    _fig_4_18(cap, axs[1, 1], axs[1, 2])
    return _save(fig, path)


def _fig_4_22(rex: dict[str, Any], ax) -> None:
    T = 2 * math.pi / rex["omega_rad_s"]
    for i, (name, run) in enumerate(rex["runs"].items()):
        tr = run["trajectory"]
        M = run["result"]["inputs"]["M_kg"]
        ax.plot(_a(tr["t_s"]) / T, _a(tr["penetration_m"]) * 1e9, color=f"C{i}",
                label=f"({i + 1}) M = {M:.3g} kg: {name}")
    ax.set_yscale("symlog", linthresh=2.0)
    ax.set_xlabel("time / drive period")
    ax.set_ylabel(axis_label("penetration (negative: gap)", "nm"))
    ax.set_title(f"Fig 4.22: A = {rex['A_m'] * 1e6:.2g} µm, omega = {rex['omega_rad_s']:.3g} rad/s, full MD", fontsize=9)
    ax.legend(fontsize=7)


def _map(m: dict[str, Any], ax, title: str, F_po: float | None, k1: float | None) -> None:
    from matplotlib.colors import BoundaryNorm, ListedColormap

    from probedyn.schemes.placing.release import threshold_amplitude

    codes = sorted(OUTCOME_COLORS)
    cmap = ListedColormap([OUTCOME_COLORS[c] for c in codes])
    norm = BoundaryNorm(np.arange(codes[0] - 0.5, codes[-1] + 1.5), cmap.N)
    x, y = _a(m["x"]), _a(m["y"])
    o = _a(m["outcome"])
    ax.pcolormesh(x, y, o.T, cmap=cmap, norm=norm, shading="nearest")
    ax.set_xscale("log")
    ax.set_yscale("log")
    labels = {"omega": ("drive frequency omega", "rad/s"), "A": ("tip amplitude A", "m"),
              "M": ("sample mass M", "kg"), "D": ("release height D", "m")}
    ax.set_xlabel(axis_label(*labels[m["axes"][0]]))
    ax.set_ylabel(axis_label(*labels[m["axes"][1]]))
    fx = m["fixed"]
    if F_po is not None and k1 is not None:
        if list(m["axes"]) == ["omega", "A"]:
            w = np.geomspace(x[0], x[-1], 300)
            ax.plot(w, threshold_amplitude(fx["M"], w, F_po, k1), "k--", lw=1, label="linear pull-off threshold")
            ax.set_ylim(y[0], y[-1])
        elif list(m["axes"]) == ["M", "omega"]:
            Ms = np.geomspace(x[0], x[-1], 300)
            ax.plot(Ms, np.sqrt(abs(F_po) / (Ms * fx["A"])), "k--", lw=1, label="M omega^2 A = |F_po|")
            ax.plot(Ms, np.sqrt(k1 / Ms), "k:", lw=1, label="contact resonance sqrt(k1/M)")
            ax.plot([TABLE["M1"]], [TABLE["omega"]], "r*", ms=10, label="Table 4.4 point")
            ax.set_ylim(y[0], y[-1])
    for c in codes:
        if np.any(o == c):
            ax.plot([], [], "s", color=OUTCOME_COLORS[c], ms=8, label=OUTCOME_NAMES[c])
    ax.legend(fontsize=6.5, loc="best", framealpha=0.9)
    ax.set_title(title, fontsize=9)


def plot_release(rex: dict[str, Any], maps: dict[str, Any], path: Path) -> Path:
    """Fig 4.22 (three outcomes against time) and the outcome maps (full MD contact, Dask)."""
    plt = pyplot()
    keys = [k for k in ("omega_A", "M_omega", "D_omega") if k in maps]
    fig, axs = plt.subplots(1, 1 + len(keys), figsize=(5.2 * (1 + len(keys)), 4.6))
    _fig_4_22(rex, axs[0])
    titles = {"omega_A": "outcome map: M = 2e-18 kg", "M_omega": "outcome map: A = 0.5 µm",
              "D_omega": "outcome map: A = 0.5 µm, M = 2e-18 kg"}
    for ax, k in zip(axs[1:], keys):
        n = _a(maps[k]["outcome"]).shape[0]
        _map(maps[k], ax, f"{titles[k]} ({n} x {n})", maps.get("F_pull_off_n"), maps.get("k1_n_per_m"))
    return _save(fig, path)


def plot_release_map(m: dict[str, Any], path: Path, title: str = "", F_po: float | None = None,
                     k1: float | None = None) -> Path:
    """One outcome map (``probedyn place release --map``, the benchmark's 64 x 64 map)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.8, 5.2))
    _map(m, ax, title, F_po, k1)
    return _save(fig, path)


def plot_landing(land: dict[str, Any], path: Path) -> Path:
    """Fig 4.23 (height after release for three D), Fig 4.27 (lateral position for three H_sb,
    with the contact's adhesion W = H/(12 pi zeta0^2)), Fig 4.28 (landing radius against the tip
    amplitude and the sample mass for three frequencies; gaps: not released)."""
    plt = pyplot()
    fig, axs = plt.subplots(2, 2, figsize=(12, 8.5))
    ax = axs[0, 0]
    for i, d in enumerate(land["vs_D"]):
        if d["t_s"] is not None:
            ax.plot(_a(d["t_s"]) * 1e9, _a(d["y_m"]) * 1e6, color=f"C{i}",
                    label=f"D = {d['D_m'] * 1e6:.0f} µm: lands after {d['t_flight_s'] * 1e9:.1f} ns")
    ax.set_xlabel(axis_label("time after the release decision", "ns"))
    ax.set_ylabel(axis_label("sample height y", "um"))
    ax.set_title("Fig 4.23: M = 2e-18 kg, A = 0.5 µm, omega = 1e8 rad/s", fontsize=9)
    ax.legend(fontsize=7)
    ax = axs[0, 1]
    for i, d in enumerate(land["vs_H_sb"]):
        if d["t_s"] is not None:
            ax.plot(_a(d["t_s"]) * 1e9, _a(d["x_m"]) * 1e12, color=f"C{i}",
                    label=f"H_sb = {d['H_sb_j']:.3g} J: R_L = {d['R_L_m'] * 1e12:.3g} pm")
    ax.set_xlabel(axis_label("time after the release decision", "ns"))
    ax.set_ylabel(axis_label("lateral position x", "pm"))
    ax.set_title(f"Fig 4.27: omega = {land['H_study_omega_rad_s']:.2g} rad/s, A = 0.5 µm", fontsize=9)
    ax.legend(fontsize=7)
    for i, om in enumerate(land["omegas_rad_s"]):
        k = f"{om:g}"
        axs[1, 0].loglog(_a(land["A_m"]) * 1e6, _a(land["R_L_vs_A"][k]), "o-", color=f"C{i}",
                         label=f"omega = {om:.0e} rad/s")
        axs[1, 1].loglog(_a(land["M_kg"]), _a(land["R_L_vs_M"][k]), "o-", color=f"C{i}",
                         label=f"omega = {om:.0e} rad/s")
    axs[1, 0].set_xlabel(axis_label("tip amplitude A", "um"))
    axs[1, 0].set_title("Fig 4.28a: M = 2e-18 kg", fontsize=9)
    axs[1, 1].set_xlabel(axis_label("sample mass M", "kg"))
    axs[1, 1].set_title("Fig 4.28b: A = 0.5 µm", fontsize=9)
    for ax in (axs[1, 0], axs[1, 1]):
        ax.set_ylabel(axis_label("landing radius R_L", "m"))
        ax.legend(fontsize=7)
    return _save(fig, path)


def plot_multi(mul: dict[str, Any], path: Path) -> Path:
    """Rayleigh-Ritz error against the number of shape functions / FEM modes (two masses at L/2
    and L); the frequencies against the position of one sample (exact beam, polynomial Ritz,
    FEM modes); Fig 4.25 (drive amplitude releasing each sample against frequency); Fig 4.26
    (contact tension of each sample against the drive amplitude at one frequency)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    axs = [axes[0, 0], axes[1, 0], axes[1, 1]]
    ax = axes[0, 1]
    pos = mul["positions"]
    x = _a(pos["x_over_L"])
    for j in range(3):
        bare = float(_a(pos["bare"])[j])
        ax.plot(x, _a(pos["exact"])[:, j] / bare, "-", color=f"C{j}", label=f"mode {j + 1}: exact beam")
        ax.plot(x, _a(pos["polynomial"])[:, j] / bare, "o", color=f"C{j}", ms=4, mfc="none",
                label=f"mode {j + 1}: polynomial Ritz (12)")
        if len(pos["ritz_modes"]):
            ax.plot(x, _a(pos["ritz_modes"])[:, j] / bare, "x", color=f"C{j}", ms=5, label=f"mode {j + 1}: FEM modes")
    ax.set_xlabel("sample position l / L")
    ax.set_ylabel("frequency / bare probe's")
    ax.set_title("one sample of 0.1 rho A L against its position", fontsize=9)
    ax.legend(fontsize=6)
    ax = axs[0]
    ratio = sorted({r["ratio"] for r in mul["convergence"]})[0]
    for basis, mk in (("polynomial", "o-"), ("FEM modes", "s--"), ("FEM modes + static shapes", "^:")):
        rows = [r for r in mul["convergence"] if r["ratio"] == ratio and r["basis"] == basis]
        for mode in range(3):
            xs = [r["n"] for r in rows if len(r["rel_err_exact"]) > mode]
            ys = [max(abs(r["rel_err_exact"][mode]), 1e-16) for r in rows if len(r["rel_err_exact"]) > mode]
            if xs:
                ax.loglog(xs, ys, mk, color=f"C{mode}", ms=4, label=f"{basis}, mode {mode + 1}")
    ax.set_xlabel("shape functions / FEM modes")
    ax.set_ylabel("|f_RR / f_exact - 1|")
    ax.set_title(f"Rayleigh-Ritz, masses {ratio:g} rho A L at L/2 and L", fontsize=9)
    ax.legend(fontsize=6)
    s = mul["selective_frequency"]
    om = _a(s["omega_rad_s"])
    thr = _a(s["Y_threshold"])
    unit = ("tip force F0", "N") if s["drive"] == "tip" else ("base amplitude", "m")
    ax = axs[1]
    ax.loglog(om, thr[:, 0], "C0-", label=f"sample 1 at L/2 ({s['M_kg']:.2g} kg)")
    ax.loglog(om, thr[:, 1], "C3-", label=f"sample 2 at L ({s['M_kg']:.2g} kg)")
    for c in s.get("checks", []):
        if c["case"].startswith("frequency"):
            ax.plot([c["omega_rad_s"]], [c["Y"]], "k*", ms=9)
            ax.annotate(f"1 {c['outcome_sample1']}, 2 {c['outcome_sample2']}", (c["omega_rad_s"], c["Y"]),
                        fontsize=6.5, xytext=(4, 4), textcoords="offset points")
    ax.set_xlabel(axis_label("drive frequency omega", "rad/s"))
    ax.set_ylabel(axis_label(unit[0] + " releasing the sample", unit[1]))
    ax.set_title("Fig 4.25: frequency-based selective release", fontsize=9)
    ax.legend(fontsize=7)
    a = mul["selective_amplitude"]
    Y = _a(a["Y"])
    th = _a(a["Y_threshold"])
    ax = axs[2]
    for k, (lab, col) in enumerate((("sample 1 at L/2", "C0"), ("sample 2 at L", "C3"))):
        ax.loglog(Y, Y / th[k], "-", color=col, label=f"{lab}: releases at {th[k]:.3g} {unit[1]}")
    ax.axhline(1.0, color="k", lw=0.8, label="tension = pull-off force")
    for c in s.get("checks", []):
        if c["case"].startswith("amplitude"):
            ax.axvline(c["Y"], color="0.5", ls=":", lw=0.8)
            ax.annotate(f"sim: 1 {c['outcome_sample1']}, 2 {c['outcome_sample2']}", (c["Y"], 0.3),
                        rotation=90, fontsize=6.5)
    ax.set_xlabel(axis_label(unit[0], unit[1]))
    ax.set_ylabel("contact tension / pull-off force")
    ax.set_title(f"Fig 4.26: amplitude-based, omega = {a['omega_rad_s']:.3g} rad/s", fontsize=9)
    ax.legend(fontsize=7)
    return _save(fig, path)


def plot_release_run(res: dict[str, Any], path: Path) -> Path:
    """Penetration against time of one release run (``probedyn place release --out``)."""
    plt = pyplot()
    tr = res["trajectory"]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(_a(tr["t_s"]) * 1e6, _a(tr["penetration_m"]) * 1e9, label=f"outcome: {res['outcome']}")
    ax.set_yscale("symlog", linthresh=2.0)
    ax.set_xlabel(axis_label("time", "us"))
    ax.set_ylabel(axis_label("penetration (negative: gap)", "nm"))
    ax.set_title("release run, full Maugis-Dugdale contact", fontsize=9)
    ax.legend()
    return _save(fig, path)


def plot_for_command(kind: str, res: dict[str, Any], out: Path) -> list[Path]:
    """The figures of ``probedyn place KIND --out``."""
    out = Path(out)
    if kind == "approach":
        return [plot_approach(res, out / "place_approach.png")]
    if kind == "capture":
        return [plot_capture(res, out / "place_capture.png")]
    if kind == "release" and res.get("trajectory") is not None:
        return [plot_release_run(res, out / "place_release.png")]
    if kind == "release_map":
        return [plot_release_map(res[k], out / f"place_map_{k}.png", k, res.get("F_pull_off_n"), res.get("k1_n_per_m"))
                for k in ("omega_A", "M_omega", "D_omega") if k in res]
    if kind == "landing":
        return [plot_landing(res, out / "place_landing.png")]
    if kind == "multi" and "selective_frequency" in res:
        return [plot_multi(res, out / "place_multi.png")]
    return []


# ------------------------------------------------------------------------------------------
# The section
# ------------------------------------------------------------------------------------------


def _shift_text(ap: dict[str, Any]) -> str:
    def ok(v):
        return v is not None and math.isfinite(v)

    rows = [r for r in ap["shift_rows"] if ok(r["df_exact_hz"])]
    A0 = min(ap["amplitudes_m"])
    small = max(abs(r["df_exact_hz"] / r["df_small_hz"] - 1) for r in rows if r["A_m"] == A0)
    g1 = max(abs(r["df_giessibl_hz"] / r["df_exact_hz"] - 1) for r in rows)
    gs = max(abs(r["df_giessibl_sqrt_hz"] / r["df_exact_hz"] - 1) for r in rows)
    sims = [r for r in rows if ok(r["df_sim_hz"])]
    sim = max(abs(r["df_sim_hz"] / r["df_exact_hz"] - 1) for r in sims) if sims else math.nan
    gone = sum(1 for r in ap["shift_rows"] if not ok(r["df_exact_hz"]))
    return (f"Frequency shift: the exact orbit period agrees with (4.21) within {small:.1e} at A = {A0 * 1e9:.2g} nm "
            f"and with the time simulation within {sim:.1e}; Giessibl's first-order formula differs from it by up to "
            f"{g1 * 100:.0f} % (first order in k_ts/k), its sqrt form by up to {gs * 100:.1f} %. In {gone} case(s) "
            "the amplitude carries the tip over the barrier: no orbit exists (dynamic jump) while Giessibl's "
            "formulas still give a number; the time domain decides.")


def _selective_text(mul: dict[str, Any]) -> str:
    s = mul["selective_frequency"]
    a = mul["selective_amplitude"]
    u = "N (tip force)" if s["drive"] == "tip" else "m (base motion)"
    b1, b2 = s["best_for_sample1"], s["best_for_sample2"]
    agree = all(c["predicted_sample1"] == c["outcome_sample1"] and c["predicted_sample2"] == c["outcome_sample2"]
                for c in s.get("checks", []))
    return (f"Selective release ({s['M_kg']:.0e} kg samples; a 2e-18 kg sample needs MHz drives, see Release): "
            f"sample 1 (L/2) alone at omega = {b1['omega_rad_s']:.3g} rad/s ({b1['Y1']:.3g} against {b1['Y2']:.3g} "
            f"{u}), sample 2 (L) alone at {b2['omega_rad_s']:.3g} rad/s ({b2['Y2']:.3g} against {b2['Y1']:.3g}); at "
            f"{a['omega_rad_s']:.3g} rad/s the amplitude releases sample 2 first ({a['Y_threshold'][1]:.3g}) and "
            f"sample 1 at {a['Y_threshold'][0]:.3g} {u}. Release simulations at these points "
            + ("confirm every predicted outcome." if agree else "differ from the prediction (see docs/placing.md).")
            + f" With the other drive ({s['other_drive']}) the largest ratio of the two thresholds is "
            f"{s['other_drive_max_ratio']:.3g}.")


def section(outdir: Path, quick: bool) -> str:
    """Nano-placing: every phase of section 4.2 with its checks (see the module docstring)."""
    from probedyn.probes.placing import placing_probe
    from probedyn.schemes.placing import studies as S

    outdir = Path(outdir)
    probe = placing_probe("beam" if quick else "fem")
    n_map = 8
    ap = S.approach_study(probe, speeds=(1e-5, 1e-6), n_gaps=8, simulate_shift=4, amplitudes=(0.05e-9, 0.5e-9))
    cp = S.capture_study(probe, K_values=(0.0, 3.0, 30.0, 300.0, 3000.0), mu_values=(0.0, 1.0), basis=probe.ritz,
                         n_eval=801)
    rex = S.release_examples(probe, n_scan=20)
    maps = S.release_maps(probe, n=n_map, workers=2, processes=False, which=("omega_A", "M_omega"))
    land = S.landing_study(probe, n=4)
    mul = S.multi_study(probe, model=probe.model, ns=(2, 4, 8, 16), mode_counts=(8,), ratios=(0.1,),
                        fem_reference=False, inverse_starts=2, basis=probe.ritz)
    pl = S.plausibility_study(probe)
    plot_approach(ap, outdir / "placing_approach.png")
    plot_capture(cp, outdir / "placing_capture.png")
    plot_release(rex, maps, outdir / "placing_release.png")
    plot_landing(land, outdir / "placing_landing.png")
    plot_multi(mul, outdir / "placing_multi.png")
    js = ap["jump"]
    sims = ap["jump_simulations"]
    pr = probe.describe()
    parts = [
        f"Probe: {pr['source']} of the Table 4.4 cantilever (L = 2 mm, k = {pr['k_n_per_m']:.4g} N/m, silicon "
        f"30 µm x 18.48 µm{'; Euler-Bernoulli' if quick else '; FEM reduced to 8 modes + static shapes'}), "
        f"f1 = {fmt_hz(pr['f1_hz'])}, equivalent mass k/omega1^2 = {pr['m_equivalent_kg']:.3g} kg "
        f"({pl['masses']['ratio_equivalent_to_table']:.0f} x Table 4.4's m = 2e-12 kg: departure 35; the "
        "table value is available as `--mass-source table`). Damping ratio 0.1 (Table 4.4's mu read as a ratio: "
        "departure 24).",
        "",
        "**Approach (4.13-4.21).** Linearised at the static equilibrium (departure 23). Force balance: the tip "
        "jumps into contact at "
        f"z0* = zeta0 + 1.5 (H R / 3k)^(1/3) = {js['z0_star_m'] * 1e9:.4f} nm. Slow-approach simulations: "
        + "; ".join(f"{s['speed_m_s']:.0e} m/s -> {s['z0_jump_m'] * 1e9:.4f} nm" for s in sims)
        + f" (the delay falls as v^{ap['jump_delay_exponents'][0]:.2f} between these speeds; a slow passage through "
        "a fold gives v^(2/3) asymptotically). "
        f"Linearised response checked in the time domain at z0 = {ap['forced_check']['z0_m'] * 1e9:.3f} nm: "
        f"amplitude ratio {ap['forced_check']['amplitude_sim_m'] / ap['forced_check']['amplitude_linear_m']:.6f}.",
        "",
        _shift_text(ap),
        "",
        "![Approach: Fig 4.20 and the frequency shift](placing_approach.png)",
        "*One-DOF first mode (static stiffness k, mass k/omega1^2, zeta = 0.1) with the van der Waals force (4.14): (a) net force against deflection, (b, c) gain and phase of the linearised response (4.19)-(4.20) at five gaps, (d) relative difference of each frequency-shift estimate from the exact orbit period (circles: DOP853 simulation).*",
        "",
    ]
    chk = cp["check"]
    check = (f"Frequency equation vs the {cp['check_method']}: max |difference| {cp['check_max_abs_rel'] * 100:.3f} % "
             f"for bL in [{cp['check_bL_range'][0]:.3f}, {cp['check_bL_range'][1]:.3f}], beta L^3 in "
             f"[{cp['check_beta_range'][0]:.4g}, {cp['check_beta_range'][1]:.4g}]" if chk else
             "Quick mode (beam probe): no FEM comparison here")
    parts += [
        "**Capture (4.22-4.41).** End condition EI U''' = (k1 - M omega^2) U (SOURCE-NOTES 4; printed "
        "k1 + M omega^2; departure 25): an attached mass lowers every frequency. " + check
        + " (tests/test_placing_slow.py: full FEM re-solves over bL 1.25-10.0 within 0.12 %).",
        "",
        f"MD linearisation at zero load (4.28-4.29): k1 = {cp['md']['k1_n_per_m']:.4g} N/m, "
        f"k0 = {cp['md']['k0_n']:.4g} N; the piecewise-linear error decays as N^-{cp['pl_orders']['uniform']:.2f} "
        f"with uniform nodes (vertical tangent at the jump-out point) and N^-{cp['pl_orders']['graded']:.2f} with "
        "nodes graded as (j/N)^4 towards the jump-out point.",
        "",
        "![Capture: Fig 4.21, mass effect, Fig 4.18](placing_capture.png)",
        "*Euler-Bernoulli frequency equation (4.38) with the corrected end condition: mode shapes (4.40) for K = k1 L^3/EI from 0 to 3000 (lines) with the FEM probe's shapes where available (circles); first frequency against the sample mass, corrected and printed end condition; registry Maugis-Dugdale unloading branch (lambda = 2) with piecewise-linear approximations (4.29) and their maximum error.*",
        "",
    ]
    tp = rex["table_point"]
    parts += [
        "**Release (4.42), full Maugis-Dugdale contact (departure 27).** Table 4.4's point (M = 2e-18 kg, omega = 2.5 krad/s, "
        f"A = {tp['inputs']['A_m'] * 1e6:.3f} µm): {tp['outcome']}; inertia M omega^2 A = "
        f"{tp['physics']['inertial_force_n']:.2g} N against the pull-off force "
        f"{abs(tp['physics']['F_pull_off_n']):.3g} N (departure 28). The three outcomes of Fig 4.22 appear at omega = 1e8 rad/s "
        f"around M = |F_po| / (omega^2 A) = {rex['M_threshold_kg']:.3g} kg:",
        "",
                "Maps (Dask, NetCDF with `probedyn place release fem --map ... --out DIR`): below the sample's contact "
        "resonance omega_c = sqrt(k1/M) the boundary is the line M omega^2 A = |F_po| (slope -2); near omega_c the "
        "contact oscillator amplifies (release at sub-nm amplitudes); above it the sample no longer follows the "
        "tip: the contact is pulled apart by the displacement (about 2.3 nm, delta_0 - delta_min) but the sample gets "
        "no velocity and is recaptured.",
        "",
        "![Release: Fig 4.22 and outcome maps](placing_release.png)",
        "*Sample on the full Maugis-Dugdale contact (lambda = 2, hysteretic) under the probe's first mode, compiled ode23s: penetration against time for three sample masses; outcome maps (Dask) with the linear pull-off threshold and the contact resonance.*",
        "",
    ]
    ref = land["reference"]
    parts += [
        "**Flight and landing (4.43-4.44).** Tilt theta = atan(A_tip/L) (departure 31). A released sample leaves "
        f"at ~omega A ({abs(ref['release_velocity_m_s']):.3g} m/s at the reference point) and flies ballistically: "
        f"gravity changes its speed by g t ~ 1e-6 m/s over the flight; the substrate's pull exceeds gravity only "
        f"within {land['gravity_crossover_m']['hamaker'] * 1e6:.2g} µm (full Hamaker law; "
        f"{land['gravity_crossover_m']['derjaguin'] * 1e6:.3g} µm with the printed Derjaguin law). "
        f"R_L = {ref['R_L_m']:.3g} m, nearly all from the tip's lateral pull in the first nanometres "
        f"(without it {land['R_L_without_near_field']:.2g} m). Lighter samples and slower releases land farther.",
        "",
                "![Landing: Figs 4.23, 4.27, 4.28](placing_landing.png)",
        "*Flight model (4.43) with tilt atan(A/L), Derjaguin laws, started from the release simulation's decision state with the near-field lateral impulse: height for three release heights, lateral position for three H_sb (contact adhesion varied with it), landing radius against tip amplitude and sample mass.*",
        "",
    ]
    conv = [r for r in mul["convergence"] if r["n"] is not None]
    idn = [r for r in mul["identifiability"]["heavy"] if r["n_frequencies"] in (1, 2, 4)]
    parts += [
        "**Several samples (4.45-4.55).** Two masses 0.1 rho A L at L/2 and L; errors against the exact beam:",
        "",
        _md([{"basis": r["basis"], "n": r["n"], "e1": abs(r["rel_err_exact"][0]),
              "e2": abs(r["rel_err_exact"][1]) if len(r["rel_err_exact"]) > 1 else None,
              "e3": abs(r["rel_err_exact"][2]) if len(r["rel_err_exact"]) > 2 else None} for r in conv],
            [("basis", "basis", ""), ("n", "n", ""), ("e1", "mode 1", ".2e"), ("e2", "mode 2", ".2e"),
             ("e3", "mode 3", ".2e")]),
        "",
                "Identifiability (masses 1 % of the beam; sd per unit relative frequency noise; departure 34):",
        "",
        _md([{"u": r["unknowns"], "n": r["n_frequencies"], "ok": "yes" if r["identifiable"] else "no",
              "sd": max(r["sd_per_unit_noise"].values()) if r["identifiable"] else None} for r in idn],
            [("u", "unknowns", ""), ("n", "frequencies", ""), ("ok", "determined", ""), ("sd", "max sd", ".3g")]),
        "",
        "![Several samples: Rayleigh-Ritz, Figs 4.25, 4.26](placing_multi.png)",
        "*Rayleigh-Ritz (Legendre polynomials; FEM modes with and without static shapes) against the exact Euler-Bernoulli beam with point masses; frequencies against the position of one sample; selective release thresholds (quasi-static pull-off per sample, tip force drive) with release simulations at the starred points.*",
        "",
        _selective_text(mul),
        "",
    ]
    parts += ["**Table 4.4's mass (SOURCE-NOTES 10).**", "",
              _md(pl["rows"], [("mass_source", "mass", ""), ("m_equivalent_kg", "m [kg]", ".3g"), ("f1_hz", "f1", "hz"),
                               ("jump_z0_m", "z0* [m]", ".4g"), ("df_rel_at_1.5z", "df/f at 1.5 z0*", ".4f"),
                               ("F0_for_0.5um_at_1e8_n", "F0 for 0.5 µm at 1e8 rad/s [N]", ".3g"),
                               ("sample_df_rel", "df/f of one sample", ".3g")]), "",
              "Static and relative results do not depend on the mass; frequencies, drive forces and the "
              "detectability of a sample by its frequency shift do (docs/placing.md)."]
    return "\n".join(parts)
