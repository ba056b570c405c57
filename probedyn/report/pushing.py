"""Report section: nano-pushing of a sphere on mica / HOPG (source sections 4.1.1-4.1.2,
Figs 4.2-4.6). Figures ``push_stairs_sliding.png``, ``push_presliding.png``,
``push_zigzag.png``, ``push_viscous.png``; :func:`plot_push` is the figure of
``probedyn simulate push --out``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from probedyn.core.io import make_dirs
from probedyn.core.presets import preset
from probedyn.plotting import axis_label, pyplot, savefig
from probedyn.report._tables import markdown_table
from probedyn.schemes import pushing as P
from probedyn.schemes.pushing_studies import (PRESLIDING_LATTICES, PRESLIDING_ZETA0, hop_counts, presliding_study,
                                              stairs_and_sliding, viscous_study)


def plot_push(res, r: dict, path: Path, title: str) -> Path:
    """One push: sample position and friction vs base travel (and the sample path in 2D)."""
    F = res.friction()
    xy = res.sample_xy
    nrow = 3 if res.model.dim == 2 else 2
    plt = pyplot()
    fig, ax = plt.subplots(nrow, 1, figsize=(7, 2.6 * nrow), constrained_layout=True)
    b = res.base * 1e9
    ax[0].plot(b, xy[0] * 1e9, lw=1, label="sample x")
    a = res.model.p["a"] * 1e9
    ax[0].set_ylabel(axis_label("sample x", "nm"))
    ax[0].set_title(f"{title}: a = {a:.3f} nm, mean step = "
                    + (f"{r['mean_step_m'] * 1e9:.3f} nm" if r.get("mean_step_m") else "– (sliding)"))
    ax[0].legend(fontsize=7)
    ax[1].plot(b, F[0] * 1e9, lw=1, label="substrate friction on the sample")
    ax[1].axhline(res.model.p["F_s"] * 1e9, ls="--", c="gray", lw=0.8, label="F_s (static)")
    ax[1].axhline(res.model.p["F_c"] * 1e9, ls=":", c="gray", lw=0.8, label="F_c (kinetic)")
    ax[1].set_ylabel(axis_label("friction", "nN"))
    ax[1].legend(fontsize=7)
    if nrow == 3:
        ax[2].plot(xy[0] * 1e9, xy[1] * 1e9, lw=1, label="sample path")
        ax[2].set_xlabel(axis_label("sample x", "nm"))
        ax[2].set_ylabel(axis_label("sample y", "nm"))
        ax[2].set_aspect("equal")
        ax[2].legend(fontsize=7)
    for a in ax[:2]:
        a.set_xlabel(axis_label("base travel", "nm"))
    return savefig(fig, path)


def plot_stairs(runs: dict, speeds: tuple[float, float], path: Path) -> Path:
    """Figs 4.2 / 4.3: sample position and friction vs base travel at a slow and a fast speed."""
    plt = pyplot()
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), constrained_layout=True)
    for j, V in enumerate(speeds):
        for (sub, VV), (res, _r) in runs.items():
            if VV != V:
                continue
            ax[0, j].plot(res.base * 1e9, res.sample_xy[0] * 1e9, lw=1, label=sub)
            ax[1, j].plot(res.base * 1e9, res.friction()[0] * 1e9, lw=1, label=sub)
        ax[0, j].set_title(f"V = {V * 1e6:g} µm/s")
        ax[0, j].set_ylabel(axis_label("sample x", "nm"))
        ax[1, j].set_ylabel(axis_label("friction", "nN"))
        ax[1, j].set_xlabel(axis_label("base travel", "nm"))
        ax[0, j].legend(fontsize=8)
        ax[1, j].legend(fontsize=8)
    return savefig(fig, path)


def plot_presliding(study: dict, path: Path) -> Path:
    """Fig 4.4: friction during pre-sliding for several lattice constants and zeta0."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.5), constrained_layout=True)
    for what, val, res in study["runs"]:
        k = 0 if what == "a" else 1
        ax[k].plot(res.base * 1e9, res.friction()[0] * 1e9, lw=1, label=f"{what} = {val * 1e9:.3g} nm")
    for k in (0, 1):
        ax[k].set_xlabel(axis_label("base travel", "nm"))
        ax[k].set_ylabel(axis_label("friction", "nN"))
        ax[k].legend(fontsize=8)
    ax[0].set_title("pre-sliding vs lattice constant (mica F_s, F_c)")
    ax[1].set_title("pre-sliding vs DMT inter-atomic distance")
    return savefig(fig, path)


def plot_zigzag(res, path: Path) -> Path:
    """Fig 4.5: sample displacement vs base travel and the sample path over the lattice sites."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.5), constrained_layout=True)
    xy = res.sample_xy
    ax[0].plot(res.base * 1e9, xy[0] * 1e9, label="x (push)")
    ax[0].plot(res.base * 1e9, xy[1] * 1e9, label="y")
    ax[0].set_xlabel(axis_label("base travel", "nm"))
    ax[0].set_ylabel(axis_label("sample displacement", "nm"))
    ax[0].legend(fontsize=8)
    ax[1].plot(xy[0] * 1e9, xy[1] * 1e9, label="sample path")
    A = P.lattice_vectors(res.model)
    n = np.arange(-3, 20)
    N1, N2 = np.meshgrid(n, n)
    pts = A @ np.vstack([N1.ravel(), N2.ravel()])
    sel = (pts[0] > -0.5e-9) & (pts[0] < xy[0].max() + 0.5e-9) & (abs(pts[1]) < 1.5e-9)
    ax[1].plot(pts[0, sel] * 1e9, pts[1, sel] * 1e9, "k.", ms=3, label="lattice sites")
    ax[1].set_aspect("equal")
    ax[1].set_xlabel(axis_label("x", "nm"))
    ax[1].set_ylabel(axis_label("y", "nm"))
    ax[1].legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.3), ncol=2)
    return savefig(fig, path)


def plot_viscous(study: dict, path: Path) -> Path:
    """Fig 4.6: friction vs base travel for several viscous coefficients F_v."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3), constrained_layout=True)
    for Fv, res in study["runs"]:
        ax.plot(res.base * 1e9, res.friction()[0] * 1e9, lw=1, label=f"F_v = {Fv:g} N s/m")
    ax.set_xlabel(axis_label("base travel", "nm"))
    ax.set_ylabel(axis_label("friction", "nN"))
    ax.legend(fontsize=8)
    return savefig(fig, path)


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    make_dirs(outdir)
    md = []
    slow, fast = 3e-6, 150e-6
    runs, rows = stairs_and_sliding(("mica", "hopg"), slow, fast)
    f1 = plot_stairs(runs, (slow, fast), outdir / "push_stairs_sliding.png").name
    md.append(f"Sphere (R_s = {preset('table-4.1')['R_s'] * 1e9:g} nm, Table 4.1) pushed by the probe tip on mica and "
              "HOPG (Table 4.2). The lattice enters as a hexagonal Prandtl–Tomlinson-type pinning potential carrying "
              "the excess F_s - F_c of static over kinetic friction, its amplitude fading with the Stribeck factor of "
              "eq 2.4 (departure 14, docs/pushing.md); the step length is not an input.")
    md.append(f"\n![stairs at {slow * 1e6:g} µm/s and sliding at {fast * 1e6:g} µm/s]({f1})\n")
    md.append(f"*Sample position and substrate friction vs base travel (1D push model of section 4.1.1) at "
              f"{slow * 1e6:g} µm/s (stairs) and {fast * 1e6:g} µm/s (sliding).*\n")
    md.append(markdown_table(
        [{**r, "a": r["a"] * 1e9, "step": r["step"] * 1e9, "std": r["std"] * 1e12,
          "fk": r["friction_fast"] * 1e9, "fke": r["kinetic_fast"] * 1e9} for r in rows],
        [("substrate", "substrate", ""), ("a", "a [nm]", ".4f"), ("step", "mean step [nm]", ".4f"),
         ("ratio", "step / a", ".4f"), ("std", "std [pm]", ".2f"), ("n", "steps", "d"),
         ("sliding", f"regime at {fast * 1e6:g} µm/s", ""), ("fk", f"friction at {fast * 1e6:g} µm/s [nN]", ".4f"),
         ("fke", "F_c + F_v V [nN]", ".4f")]))
    # pre-sliding vs lattice constant and vs zeta0 (Fig 4.4)
    pre = presliding_study(PRESLIDING_LATTICES[:2] if quick else PRESLIDING_LATTICES, PRESLIDING_ZETA0)
    f2 = plot_presliding(pre, outdir / "push_presliding.png").name
    zrows = [r for r in pre["rows"] if r["what"] == "zeta0"]
    adh = ", ".join(f"{r['adhesion'] * 1e9:.2f}" for r in zrows)
    zs = ", ".join(f"{r['value'] * 1e9:.3g}" for r in zrows)
    z_table = preset("table-4.4")["zeta0"]
    md.append(f"\n**Pre-sliding (Fig 4.4).** The sample creeps up its lattice well until the corrugation's fold, "
              f"a/4 + (a/2pi) asin(1/eta) from the site, so the pre-sliding displacement scales with the lattice "
              f"constant. The DMT inter-atomic distance zeta0 sets the adhesion H R / 6 zeta0^2 ({adh} nN "
              f"for {zs} nm; {z_table * 1e9:.3g} nm is the default, Table 4.4) and where contact starts: at "
              f"{zrows[0]['value'] * 1e9:.3g} nm the adhesion exceeds F_s and the jump into contact drags the sample "
              f"back across lattice sites before the push begins.\n\n![pre-sliding]({f2})\n")
    md.append("*Substrate friction during the first nanometres of a push from rest (1D push model, mica friction "
              "levels), left: lattice constant a varied; right: zeta0 varied.*\n")
    md.append(markdown_table(
        [{"case": f"{r['what']} = {r['value'] * 1e9:.3g} nm", "x": r["x"] * 1e12, "q": r["q"] * 1e12,
          "F": r["F"] * 1e9, "X": r["X"] * 1e9} for r in pre["rows"]],
        [("case", "case", ""), ("x", "sample pre-slide [pm]", ".1f"), ("q", "a/4 [pm]", ".1f"),
         ("F", "peak friction [nN]", ".3f"), ("X", "base travel to 1st slip [nm]", ".3f")]))
    # 2D zigzag (Fig 4.5)
    angle = 15.0
    res, r = P.push("mica", {"angle": angle})
    f3 = plot_zigzag(res, outdir / "push_zigzag.png").name
    h = hop_counts(r)
    md.append(f"\n**2D zigzag (Fig 4.5)**, mica, push at {angle:g}° to the lattice axis: {h['total']} hops, "
              f"{h['a1']} along the lattice axis ({-angle:g}° in the probe frame), "
              f"{h['a2']} along the 60° axis ({60 - angle:+g}°), mean direction "
              f"{r['mean_direction_deg']:.1f}° from the push; dots are lattice sites.\n\n![zigzag]({f3})\n")
    md.append("*2D push model on mica: sample displacement along and across the push vs base travel (left) and the "
              "sample path over the sites of the hexagonal lattice (right).*\n")
    # viscous term (Fig 4.6)
    vis = viscous_study()
    f4 = plot_viscous(vis, outdir / "push_viscous.png").name
    md.append(f"\n**Viscous term (Fig 4.6).** Raising F_v (units N s/m, departure 10) slows the overdamped slips "
              f"(duration ~ F_v/k): the friction stays high while the sample slips and the sawtooth's drop turns into "
              f"a rounded plateau. At the source's values (2e-5, 5e-5) the slip takes 5-8 % of the period; 2e-4 "
              f"(beyond the source) shows the trend towards a square wave.\n\n![viscous]({f4})\n")
    md.append("*Substrate friction vs base travel of the 1D push model on mica for four viscous coefficients F_v.*\n")
    md.append(markdown_table(vis["rows"], [("Fv", "F_v [N s/m]", ".1e"), ("frac", "slip time / period", ".3f"),
                                           ("step", "step / a", ".3f")]))
    if not quick:
        trs = [P.transition_speed(sub) for sub in ("mica", "hopg")]
        md.append("\n**Stick-slip to sliding** (bisection on pushes from rest, 2 % bracket): "
                  + "; ".join(f"{t['substrate']}: {t['V_transition_m_s'] * 1e6:.2f} µm/s" for t in trs) + ".")
    return "\n".join(md)
