"""Report section: the two-mass stick-slip model (source section 4.1.3, eqs 4.2-4.12,
Figs 4.8-4.13). Figures ``stickslip_portraits.png``, ``stickslip_basins_u0_*.png``,
``stickslip_limit_cycles.png``, ``stickslip_branches.png``, ``stickslip_regime_map.png``; the
figure functions of ``probedyn stickslip portrait|limit-cycles|regime-map`` and
``probedyn sweep basins`` live here."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.io import make_dirs
from probedyn.plotting import category_colormap, fmt_um, pyplot, savefig
from probedyn.report._tables import markdown_table
from probedyn.schemes.regimes import limit_cycles_result, run_basins, run_regime_map
from probedyn.schemes.stickslip import DEFAULT_MODEL, REGIMES, equilibria, phase_portrait, steady_branches


def plot_basins(ds, path: Path, title: str = "") -> Path:
    """Basin map of a basins Dataset (Fig 4.9) with the nodes and saddles marked."""
    plt = pyplot()
    lab = ds["label"].values
    nodes = np.asarray(ds.attrs.get("nodes", []), dtype=float).ravel()
    n = max(int(lab.max()) + 1, 1)
    fig, ax = plt.subplots(figsize=(6.2, 4.6))
    cmap = plt.get_cmap("tab20", max(n, 2))
    im = ax.pcolormesh(ds["x3_0"].values, ds["x4_0"].values, np.ma.masked_less(lab, 0), cmap=cmap, vmin=-0.5,
                       vmax=max(n, 2) - 0.5, shading="nearest")
    if nodes.size:
        ax.plot(nodes, np.zeros_like(nodes), "k*", ms=9, label="nodes (eq 4.11)")
        for i, xn in enumerate(nodes):
            ax.annotate(str(i + 1), (xn, 0), textcoords="offset points", xytext=(4, 6), fontsize=9, weight="bold")
    unstable = np.asarray(ds.attrs.get("saddles", []), dtype=float).ravel()
    if unstable.size:
        ax.plot(unstable, np.zeros_like(unstable), "wx", ms=7, mew=2, label="saddles")
    cb = fig.colorbar(im, ax=ax, ticks=range(n))
    cb.ax.set_yticklabels([str(i + 1) for i in range(n)])
    cb.set_label("node reached")
    ax.set_xlabel("$x_3(0)$ (sample, moving frame, non-dimensional)")
    ax.set_ylabel("$x_4(0)$ (sample velocity, non-dimensional)")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return savefig(fig, path)


def plot_regime_map(ds, path: Path, bis: dict[str, Any] | None = None) -> Path:
    """Regime map (Fig 4.13) over (v, u0), the period contours and the bisected boundary."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    cmap, _ = category_colormap(["#9ecae1", "#fd8d3c", "#d62728", "#74c476", "#6a51a3"])
    ax.pcolormesh(ds["v"].values, ds["u0"].values, ds["regime"].values, cmap=cmap, vmin=-0.5, vmax=4.5, shading="nearest")
    ax.set_xscale("log")
    ax.set_xlabel("non-dimensional speed v (eq 4.6)")
    ax.set_ylabel("$u_0$ (non-dimensional potential amplitude)")
    fold = ax.axhline(1.0, color="k", lw=0.8, ls="--")
    if "period" in ds:
        per = ds["period"].values.astype(float)
        cs = ax.contour(ds["v"].values, ds["u0"].values, per, levels=[1.5, 2.5, 3.5, 4.5], colors="k", linewidths=0.6)
        ax.clabel(cs, fmt=lambda x: f"period {x - 0.5:.0f}|{x + 0.5:.0f}", fontsize=6)
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(k)) for k in REGIMES] + [fold]
    labels = list(REGIMES.values()) + ["quasi-static fold u0 = 1"]
    if bis and bis.get("v_star"):
        h, = ax.plot([r["v_star"] for r in bis["v_star"]], [r["u0"] for r in bis["v_star"]], "k^-", ms=5, lw=1)
        handles.append(h)
        labels.append("end of stick (bisection)")
    ax.legend(handles, labels, loc="upper left", fontsize=7, framealpha=0.9)
    ax.set_title("regime map (Fig 4.13); thin lines: attractor period contours")
    fig.tight_layout()
    return savefig(fig, path)


def plot_limit_cycles(lc: dict[str, Any], u0: float, path: Path) -> Path:
    """Limit cycles in the sample's phase plane for each speed, and their amplitude and centre
    vs v with the linear-response limit (Figs 4.10-4.11)."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    cm = plt.get_cmap("viridis")
    for j, (v, orb) in enumerate(zip(lc["v"], lc["orbits"])):
        a1.plot(orb[:, 1], orb[:, 2], color=cm(j / max(1, len(lc["v"]) - 1)), lw=1, label=f"v={v:.3g}")
    a1.set_xlabel("$x_3$ (sample, moving frame)")
    a1.set_ylabel("$x_4$ (sample velocity)")
    a1.set_title(f"limit cycles, u0 = {u0:g} (Fig 4.11)")
    a1.legend(fontsize=7, ncol=2)
    a2.semilogx(lc["v"], lc["amplitude"], "o-", label="amplitude (half x3 range)")
    a2.semilogx(lc["v"], lc["centre"], "s-", label="centre (mean x3)")
    a2.semilogx(lc["v"], lc["linear_amplitude"], "k--", lw=0.8, label="linear response (high-v limit)")
    a2.set_xlabel("non-dimensional speed v")
    a2.set_ylabel("$x_3$ (non-dimensional)")
    a2.set_ylim(min(-0.2, float(np.nanmin(lc["centre"])) - 0.2), float(np.nanmax(lc["amplitude"])) + 0.5)
    a2.legend(fontsize=8)
    a2.set_title("amplitude and centre vs speed")
    fig.tight_layout()
    return savefig(fig, path)


def plot_portraits(u0_list, psi: float, path: Path, v: float = 0.0, model=None, title: str | None = None) -> Path:
    """Fig 4.8: solutions of eq 4.11 vs psi (stable / unstable) and phase portraits at ``psi``
    (``model``: the two-mass model of the trajectories, default Table 4.3)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, len(u0_list), figsize=(4.2 * len(u0_list), 7))
    axes = np.atleast_2d(axes).reshape(2, len(u0_list))
    psis = np.linspace(-2 * math.pi, 2 * math.pi, 1201)
    for j, u0 in enumerate(u0_list):
        ax = axes[0, j]
        pts: dict[str, tuple[list[float], list[float]]] = {"s": ([], []), "u": ([], [])}
        for p in psis[::3]:  # one line per kind (not one per psi: 800 artists drew slowly, same points)
            e = equilibria(u0, p)
            pts["s"][0].extend([p] * e.n_stable)
            pts["s"][1].extend(e.stable)
            pts["u"][0].extend([p] * e.n_unstable)
            pts["u"][1].extend(e.unstable)
        ax.plot(*pts["s"], "b.", ms=1.5, label="stable (node)")
        ax.plot(*pts["u"], "r.", ms=0.8, label="unstable (saddle)")
        ax.set_xlabel(r"phase $\psi$ [rad]")
        ax.set_ylabel("X (eq 4.11)")
        ax.set_title(f"u0 = {u0:g}: equilibria of eq 4.11")
        ax.legend(fontsize=7, loc="upper right", markerscale=6)
        ax = axes[1, j]
        pp = phase_portrait(u0, psi, v=v, n_ic=18, t_end=40.0, **({"model": model} if model is not None else {}))
        for k, tr in enumerate(pp["trajectories"]):
            ax.plot(tr[:, 3], tr[:, 4], lw=0.6, color="0.35", label="trajectories" if k == 0 else None)
        e = equilibria(u0, psi)
        ax.plot(e.stable, np.zeros(e.n_stable), "bo", ms=5, label=f"{e.n_stable} nodes")
        ax.plot(e.unstable, np.zeros(e.n_unstable), "rx", ms=6, mew=2, label=f"{e.n_unstable} saddles")
        ax.set_xlabel("$x_3$ (sample, moving frame)")
        ax.set_ylabel("$x_4$ (sample velocity)")
        ax.legend(fontsize=8, loc="upper right")
        ax.set_title(f"phase portrait, psi = {psi:g}" + (f"\n{title}" if title else ""), fontsize=9 if title else None)
    fig.tight_layout()
    return savefig(fig, path)


def plot_branches(qs: dict[str, Any], fast: dict[str, Any], path: Path, qs2: dict[str, Any] | None = None) -> Path:
    """Fig 4.12: steady-state branches vs u0, quasi-static (a) and at a finite speed (b)."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    if qs2 is not None:
        for k, (u, xs) in enumerate(zip(qs2["u0"], qs2["x3"])):
            a1.plot([u] * len(xs), xs, ".", color="0.6", ms=2, label="psi = 5" if k == 0 else None)
    for k, (u, xs) in enumerate(zip(qs["u0"], qs["x3"])):
        a1.plot([u] * len(xs), xs, "k.", ms=2, label="psi = 0" if k == 0 else None)
    a1.set_title("(a) quasi-static (v = 0): nodes reached")
    a1.set_xlabel("$u_0$")
    a1.set_ylabel("$x_3^*$ (sample, moving frame)")
    a1.legend(fontsize=8, markerscale=4)
    first = True
    for u, arr in zip(fast["u0"], fast["x3"]):
        for lo, hi, mean in arr:
            a2.plot([u, u], [lo, hi], color="C1", lw=1.2, label="x3 range of an attractor" if first else None)
            a2.plot(u, mean, "k.", ms=2, label="its mean" if first else None)
            first = False
    a2.set_title(f"(b) fast, v = {fast['v']:g}: x3 range of each attractor")
    a2.set_xlabel("$u_0$")
    a2.legend(fontsize=8)
    fig.tight_layout()
    return savefig(fig, path)


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    make_dirs(outdir)
    md: list[str] = []
    m = DEFAULT_MODEL
    md.append(
        f"Two-mass model of Fig 4.7 with Table 4.3 (m1 = {m.m1:g} kg, m2 = {m.m2:g} kg, k1 = {m.k1:g} N/m, "
        f"k2 = {m.k2:g} N/m, zeta1 = {m.zeta1:g}, zeta2 = {m.zeta2:g}); non-dimensional form eq 4.7 "
        f"(time unit sqrt(m/k) = {m.time_scale:.3e} s). Speeds: v = 1 corresponds to V = {fmt_um(m.speed_from_v(1.0))}/s "
        f"for the potential period a = {m.a * 1e9:.0f} nm implied by the text (departure 16, docs/stickslip.md)."
    )
    rows = []
    for u0 in (0.5, 6.0, 8.0, 20.0, 25.0):
        e = equilibria(u0, 5.0)
        rows.append({"u0": u0, "s": e.n_stable, "u": e.n_unstable, "X": ", ".join(f"{x:.3f}" for x in e.stable)})
    md += ["", "**Quasi-static equilibria at psi = 5 (eqs 4.11-4.12).** For u0 = 25 the equation gives 8 nodes and "
           "7 saddles, not the 16/15 of the text (departure 15).", "",
           markdown_table(rows, [("u0", "u0", "g"), ("s", "stable", ""), ("u", "unstable", ""), ("X", "stable X", "")])]
    plot_portraits([0.5, 6.0, 25.0], 5.0, outdir / "stickslip_portraits.png")
    md += ["", "![eq 4.11 and phase portraits](stickslip_portraits.png)", "",
           "*Top: equilibria of eq 4.11 over the phase psi for u0 = 0.5, 6, 25; bottom: trajectories of the "
           "two-mass model at v = 0, psi = 5 settling on the nodes.*", ""]

    grid = 96 if quick else 256
    for u0 in (8.0, 20.0):
        t0 = time.perf_counter()
        r = run_basins(u0, 5.0, grid, outdir / f"stickslip_basins_u0_{u0:g}.nc", workers=2, processes=False,
                       progress=False, restart=True)
        plot_basins(r["dataset"], outdir / f"stickslip_basins_u0_{u0:g}.png", f"basins, u0 = {u0:g}, psi = 5 ({grid}x{grid})")
        dt = time.perf_counter() - t0
        frac = ", ".join(f"{i + 1}: {100 * f:.1f} %" for i, f in enumerate(r["basin_fraction"]))
        md += [f"Basins for u0 = {u0:g}, psi = 5 on a {grid} x {grid} grid ({dt:.1f} s on 2 Dask workers); "
               f"share of the grid per node: {frac}.", "",
               f"![basins u0={u0:g}](stickslip_basins_u0_{u0:g}.png)", ""]

    v = np.geomspace(0.02, 20, 9 if quick else 13)
    lc = limit_cycles_result(3.0, v)
    plot_limit_cycles(lc, 3.0, outdir / "stickslip_limit_cycles.png")
    rows = [dict(v=lc["v"][i], V=lc["speed_m_s"][i] * 1e6, a=lc["amplitude"][i], c=lc["centre"][i],
                 lin=lc["linear_amplitude"][i], st="stick-slip" if lc["stick"][i] else "smooth") for i in range(len(v))]
    md += ["**Limit cycles for u0 = 3 (Figs 4.10-4.11).** The amplitude shrinks and the centre moves to 0 as v "
           "rises; at high v the amplitude approaches the linear forced response (dashed), the independent limit.", "",
           markdown_table(rows, [("v", "v", ".3g"), ("V", "V [µm/s]", ".3g"), ("a", "amplitude", ".4f"),
                                 ("c", "centre", ".4f"), ("lin", "linear response", ".4f"), ("st", "motion", "")]),
           "", "![limit cycles](stickslip_limit_cycles.png)", ""]

    u0s = np.linspace(0.25, 12 if quick else 25, 24 if quick else 60)
    qs = steady_branches(u0s, 0.0, n_ic=16 if quick else 32, psi=0.0)
    qs5 = steady_branches(u0s, 0.0, n_ic=16 if quick else 32, psi=5.0)
    fast = steady_branches(u0s, 0.5, n_ic=8 if quick else 12)
    plot_branches(qs, fast, outdir / "stickslip_branches.png", qs5)
    md += ["**Steady-state branches vs u0 (Fig 4.12)**: (a) nodes reached quasi-statically from rest states "
           "spread over |x3(0)| <= u0 + pi, at psi = 0 (black: symmetric, equally spaced by about 2 pi, as in the "
           "text) and psi = 5 (grey); (b) x3 range (bars) and mean (dots) of the attractors at v = 0.5: stick-slip "
           "widens the branches and only negative separations (sample lagging the base) remain.", "",
           "![branches](stickslip_branches.png)", ""]

    vv = np.geomspace(0.05, 10, 12 if quick else 24)
    uu = np.linspace(0.25, 25, 10 if quick else 24)
    rm = run_regime_map(vv, uu, outdir / "stickslip_regime_map.nc", workers=2, processes=False, progress=False,
                        restart=True, n_ic=4 if quick else 6)
    plot_regime_map(rm["dataset"], outdir / "stickslip_regime_map.png", rm)
    fr = ", ".join(f"{k} {100 * f:.1f} %" for k, f in rm["fractions"].items())
    md += [f"**Regime map (Fig 4.13)** over {len(uu)} u0 x {len(vv)} v cells: {fr}. Classification "
           "(docs/stickslip.md): stick when the lab sample speed drops below v/2 (this puts the quasi-static "
           "boundary at the fold u0 = 1), steady sliding when its modulation is below 20 % of v, coexisting when "
           "several periodic attractors are reached from different initial conditions, irregular when a trajectory "
           "is not periodic (period <= 4) after the transient. Contours: period of the attractor in lattice "
           "periods (single, double, triple slips).", "",
           "![regime map](stickslip_regime_map.png)", ""]
    brows = [dict(u=r["u0"], v=r["v_star"], V=r["V_star_m_s"] * 1e6, w=r["v_star_over_well_frequency"]) for r in rm["v_star"]]
    md += [f"Boundaries by bisection: stick-slip starts above u0* = {rm['u0_star_at_vmin']:.4f} at v = {rm['vmin']:.3g} "
           "(the fold criterion u0 = 1 of eq 4.12 is the v -> 0 limit); stick ends (stick-slip gives way to sliding) above "
           "the speed v*(u0):", "",
           markdown_table(brows, [("u", "u0", ".2f"), ("v", "v*", ".3f"), ("V", "V* [µm/s]", ".0f"),
                                  ("w", "v* / sqrt(u0 m/m2)", ".2f")]),
           "", "The last column compares v* with the frequency of the sample in a substrate well: stick-slip ends "
           "when the washboard frequency v exceeds it by about 20 %.", ""]
    return "\n".join(md)


