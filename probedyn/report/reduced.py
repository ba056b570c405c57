"""Report section: probes reduced from their FEM drive the schemes (docs/reduced-probes.md).

``section(outdir, quick)``: the default FFM cantilever (the registry's cantilever with its
pyramid tip) reduced from its FEM; its apex springs against beam theory; the modal truncation
check; the FFM scheme run from the Table 2.1 / 2.2 probes and from the FEM-reduced one side by
side; the geometry study (predicted from the reduced stiffness, confirmed by simulation); the
higher-modes study.  Quick mode: one P2 layer through the thickness (6.5k DOFs; apex stiffness
within 3.5 % of the default mesh, the rest within 0.5 %), two geometries, the slow scan only.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from probedyn.lumped import apex as ax
from probedyn.lumped.reduced import ReducedProbe
from probedyn.plotting import axis_label, fmt_hz, pyplot, savefig
from probedyn.probes import get_probe
from probedyn.probes.reduce import reduce_probe
from probedyn.report._tables import markdown_table as _table
from probedyn.studies import reduced as st


def _ffm_figure(outdir: Path, runs: list[tuple[str, object]], name: str, title: str) -> str:
    plt = pyplot()
    fig, axs = plt.subplots(1, len(runs), figsize=(5.2 * len(runs), 3.4))
    axs = np.atleast_1d(axs)
    for a, (label, tr) in zip(axs, runs):
        a.plot(tr.base * 1e9, tr.lateral_force * 1e9, lw=0.8, label=label)
        a.set_xlabel(axis_label("base position", "nm"))
        a.set_ylabel(axis_label("lateral force", "nN"))
        a.legend(loc="lower right")
    fig.suptitle(title, fontsize="medium")
    savefig(fig, outdir / name)
    return name


def section(outdir: Path, quick: bool) -> str:
    outdir = Path(outdir)
    t_start = time.perf_counter()
    mesh = st.COARSE if quick else {}
    ov = dict(st.FFM_CANTILEVER, **mesh)
    p, _ = get_probe("cantilever")
    v = p.resolve(ov)
    t0 = time.perf_counter()
    rp = reduce_probe("cantilever", ov, n_modes=6, Q=st.STUDY_Q, cache=False)
    t_build = time.perf_counter() - t0
    out = ["Every scheme can run on a probe reduced from its FEM (`probedyn.lumped.reduced.ReducedProbe`, "
           "built by `probedyn.probes.reduce.reduce_probe`): per direction of the scheme frame (scan = across "
           "the beam, lateral = along it, normal) the retained modes referred to the tip apex, the static "
           "stiffness of a FEM static solve, the static residual of the discarded modes, the validity limit "
           "and the Ritz basis for attached masses and springs. Model here: the default FFM cantilever "
           f"(300 x 30 x 10 µm silicon, pyramid tip 10 µm), {rp.provenance['dofs']} DOFs"
           + (" (one P2 layer: quick mode)" if quick else "") + f", 6 retained modes, damping Q = {st.STUDY_Q:g}; "
           f"validity limit {fmt_hz(rp.validity_hz)} (mode 7). Build from geometry {t_build:.1f} s."]
    # ---- apex springs vs beam theory
    beam = p.beam(v)
    x_a = float(p.tip_point(v)[0])
    pr = ax.scan_stiffness(beam, v["tip_height"])
    rf = ax.scan_stiffness(beam, v["tip_height"], x=x_a, shear=True)
    rows = [dict(q="scan (y) stiffness at the apex [N/m]", fem=rp.static_stiffness("scan"), printed=pr["series"],
                 refined=rf["series"]),
            dict(q="normal (z) stiffness at the apex [N/m]", fem=rp.static_stiffness("normal"),
                 printed=ax.bending_stiffness(beam, "flapwise"),
                 refined=ax.bending_stiffness(beam, "flapwise", x=x_a, shear=True)),
            dict(q="effective mass, normal (1st flapwise mode) [kg]", fem=rp.effective_mass("normal"),
                 printed=0.25 * beam.mass, refined=ax.first_mode_effective_mass(beam, x=x_a)),
            dict(q="effective mass, scan (1st lateral mode) [kg]", fem=rp.effective_mass("scan"),
                 printed=0.25 * beam.mass, refined=ax.first_mode_effective_mass(beam, x=x_a))]
    out += ["", "**Springs and masses at the apex.** FEM vs beam theory: printed form (force at x = L: torsion "
            "G J/(L (h + t/2)^2) in series with lateral bending 3 E I/L^3; rho A L/4) and refined (at the apex, "
            f"x_a = {x_a * 1e6:.1f} µm, with Timoshenko shear; Euler–Bernoulli mode shape at x_a, bare beam):", "",
            _table(rows, [("q", "quantity", ""), ("fem", "FEM", ".4g"), ("printed", "printed form", ".4g"),
                          ("refined", "refined", ".4g")]), "",
            "The scan stiffness is torsion (" f"{rf['torsion']:.0f} N/m) in series with lateral bending "
            f"({rf['lateral_bending']:.0f} N/m): this stubby beam (w = 3t) is soft laterally. The FEM apex value is "
            "below the refined formula by the tip's own compliance at its sharp apex, which grows like 1/h_apex under "
            "refinement (docs/reduced-probes.md, section 3); 2 µm up the tip FEM and formula agree to 0.3 %."]
    # ---- truncation
    tr = st.truncation_check(rp, directions=("scan", "normal") if quick else ("scan", "lateral", "normal"))
    out += ["", f"**Modal truncation** (6 modes, validity {fmt_hz(rp.validity_hz)}): apex compliance of the reduced "
            "probe (undamped) vs the FEM's direct frequency response (K - w^2 M) u = f. Errors are given as fractions "
            "of the static compliance C (relative errors blow up where the compliance itself passes through zero "
            "between a resonance and an anti-resonance; the H_FEM / C column shows where):", "",
            _table([dict(r, w=f"{100 * r['err_over_static_corrected']:+.3f} %",
                         n=f"{100 * r['err_over_static_modes_only']:+.2f} %",
                         b=f"{100 * r['bound_over_static']:.2f} %") for r in tr],
                   [("direction", "direction", ""), ("fraction", "f / validity", ".1f"), ("frequency_hz", "f", "hz"),
                    ("H_fem_over_static", "H_FEM / C", ".3f"), ("w", "error with static residual", ""),
                    ("b", "bound R x^2/(1-x^2)", ""), ("n", "error without", "")])]
    # ---- table vs FEM side by side
    sides = []
    figs = []
    for preset, table in (("mica", "table-2.1"), ("vamwcnt", "table-2.2")):
        tp = ReducedProbe.from_preset(table)
        a = st.ffm_scan(tp, preset)
        b = st.ffm_scan(rp, preset)
        for lab, s_ in ((tp.source, a), ("FEM-reduced", b)):
            sides.append(dict(probe=f"{lab} ({preset})", k=s_["k_scan"], m=(tp if lab != "FEM-reduced" else rp).effective_mass("scan"),
                              pp=s_["predicted_period_m"] * 1e9, period=None if s_["period_m"] is None else s_["period_m"] * 1e9,
                              amp=None if s_["amplitude_n"] is None else s_["amplitude_n"] * 1e9,
                              pamp=s_["predicted_amplitude_n"] * 1e9, regime=s_["regime"]))
        if preset == "vamwcnt":
            figs = [(f"{tp.source}: k = {a['k_scan']:.3g} N/m", a["trace"]),
                    (f"FEM-reduced: k = {b['k_scan']:.4g} N/m", b["trace"])]
    name = _ffm_figure(outdir, figs, "reduced-ffm-table-vs-fem.png",
                       "FFM line scan, Table 2.2 friction (VAMWCNT), one-mode model: Table 2.2 probe vs FEM-reduced probe")
    out += ["", "**The same FFM scheme from the table probe and from the FEM-reduced probe** (bristle friction of the "
            "table, 2 µm/s, one-mode model: static scan stiffness, effective mass and damping of the dominant mode):", "",
            _table(sides, [("probe", "probe (friction)", ""), ("k", "k_scan [N/m]", ".4g"), ("m", "m_eff [kg]", ".3g"),
                           ("pp", "(F_s-F_c)/k [nm]", ".4g"), ("period", "period [nm]", ".4g"),
                           ("pamp", "predicted amplitude [nN]", ".4g"), ("amp", "amplitude [nN]", ".4g"),
                           ("regime", "regime", "")]), "",
            f"![FFM table vs FEM]({name})", "",
            "*Left: the Table 2.2 probe; right: the FEM-reduced default FFM cantilever, same friction (Table 2.2), "
            "one-mode FFM model (2.13).* The difference is the probe: Table 2.1/2.2's k_x = 0.2/0.1 N/m and "
            "m_x ~ 1e-18 kg describe no cantilever mode (a 50 MHz oscillator); a real tip's lateral spring is the "
            "beam's torsion and lateral bending seen at the apex, hundreds of N/m here, and its mass the lateral "
            "mode's effective mass (~5e-11 kg). With Table 2.1's mica friction the stiff FEM probe slides smoothly "
            "(stick-slip needs k below a few N/m for these friction levels); with Table 2.2's it keeps a regular "
            "sawtooth whose period shrinks with k. The period exceeds (F_s - F_c)/k because the lightly damped "
            "(Q = 100) slip overshoots: the amplitude is (F_s - F_c)(1 + exp(-pi zeta)) (predicted column); a "
            "critically damped probe gives the quasi-static period (docs/reduced-probes.md)."]
    # ---- geometry study
    variants = st.QUICK_VARIANTS[:1] + (("tip_height", 20e-6),) if quick else st.GEOMETRY_VARIANTS
    geo = st.geometry_study(variants, n_modes=4, base_probe=rp if quick else None)
    grow = []
    for r in geo:
        f = r["ffm_vamwcnt"]
        c = r["contact"]
        pu = r["pushing"]
        grow.append(dict(v="default" if r["value"] is None else f"{r['variant']} = {r['value'] * 1e6:g} µm",
                         ks=r["k_scan"], kn=r["k_normal"], pp=f["predicted_period_m"] * 1e9,
                         P=None if f["period_m"] is None else f["period_m"] * 1e9,
                         ratio=None if f["period_m"] is None else f["period_m"] / f["predicted_period_m"],
                         amp=f"{f['predicted_amplitude_n'] * 1e9:.1f} / " + ("–" if f["amplitude_n"] is None else f"{f['amplitude_n'] * 1e9:.1f}"),
                         jump=f"{c['predicted_gap_m'] * 1e9:.3f} / " + (f"{c['jump_in_gap_m'] * 1e9:.3f}" if c["jump_in"] else "none"),
                         push=f"{pu['predicted_transition_m_s'] * 1e6:.2f}"))
    out += ["", "**Geometry matters** (one parameter of the default FFM cantilever changed at a time; predictions "
            "from the reduced probe, then the simulation; one P2 layer through the thickness for every geometry: "
            "stiffnesses within 3.5 % of the default mesh, the same way for all). FFM: Table 2.2 friction, one-mode model; period predicted "
            "(F_s - F_c)/k_scan (its ratio to the simulation is the overshoot factor, the same for every geometry of "
            "the same damping); amplitude predicted / simulated. Jump-to-contact (DMT, Table 4.1 tip and sample): gap "
            "predicted d* = (H R/3 k_n)^(1/3) (no jump when d* is below the tail's end at zeta_0 = 0.375 nm) / "
            "force-curve simulation. Pushing on mica: stick-slip -> sliding speed predicted by the Prandtl–Tomlinson "
            "criterion with the tip spring in series with the Hertz contact (the contact, ~3 N/m, dominates: the "
            "cantilever geometry hardly moves it).", "",
            _table(grow, [("v", "geometry", ""), ("ks", "k_scan [N/m]", ".4g"), ("kn", "k_normal [N/m]", ".4g"),
                          ("pp", "(F_s-F_c)/k [nm]", ".4g"), ("P", "FFM period [nm]", ".4g"),
                          ("ratio", "ratio", ".3f"), ("amp", "FFM amplitude pred / sim [nN]", ""),
                          ("jump", "jump gap pred / sim [nm]", ""), ("push", "push V* pred [µm/s]", "")])]
    # ---- higher modes
    hm = st.higher_modes_study(rp, speeds=(2e-6,) if quick else (2e-6, 2e-5, 2e-4),
                               n_list=(None, 1) if quick else (None, 1, 2), reference=2 if quick else 4)
    hrows = [dict(V=r["V"] * 1e6, n="one-mode (lumped)" if r["n_modes"] is None else f"{r['n_modes']} + residual",
                  P=None if r["period_m"] is None else r["period_m"] * 1e9,
                  dP=None if r["rel_diff"]["period_m"] is None else 100 * r["rel_diff"]["period_m"],
                  dA=None if r["rel_diff"]["amplitude_n"] is None else 100 * r["rel_diff"]["amplitude_n"],
                  ts=None if r["slip_time_s"] is None else r["slip_time_s"] * 1e6,
                  Tn=None if r["next_mode_period_s"] is None else r["next_mode_period_s"] * 1e6,
                  vr=r["next_mode_velocity_ratio"], regime=r["regime"]) for r in hm["runs"]]
    part = ", ".join(f"mode {q['mode']} {q['family']} {fmt_hz(q['frequency_hz'])} ({100 * q['participation']:.1f} %)"
                     for q in hm["participation"][:5])
    out += ["", f"**Higher modes.** Scan-direction modes of the apex (share of the static compliance): {part}. "
            "FFM scans (Table 2.2 friction) with the one-mode model, N modes + static residual, and the reference "
            f"({hm['runs'][-1]['n_modes']} modes); slip time = time per slip with the tip faster than twice the base; "
            "T_next = period of the first scan mode left out, r_next = its velocity response to a force step "
            "relative to the dominant mode's:", "",
            _table(hrows, [("V", "V [µm/s]", ".3g"), ("n", "model", ""), ("P", "period [nm]", ".4g"),
                           ("dP", "period vs ref [%]", "+.2f"), ("dA", "amplitude vs ref [%]", "+.2f"),
                           ("ts", "slip time [µs]", ".3g"), ("Tn", "T_next [µs]", ".3g"), ("vr", "r_next", ".3f"),
                           ("regime", "regime", "")]), "",
            "A slip in the bristle model drops the friction within nanoseconds, a step for every mode: each scan mode "
            "rings with a velocity r_i relative to the dominant one. With the static residual, one mode gives the "
            "amplitude within 1 % and the period within a few per cent (the first mode left out has a period of about "
            "a third of the slip time and r_next = 0.27); two modes within 2.5 %. The lumped one-mode model (static "
            "stiffness with the mode's effective mass, what the one-mode schemes use) also shifts the slip dynamics: "
            "its frequency sqrt(k_s/m_eff) is 8 % below the mode's, which matters as soon as the slip takes a visible "
            "part of the stick-slip cycle - on the fast scan (200 µm/s, slips 25 % of the cycle) its period is 12 % and "
            "its amplitude 25 % off, against < 2 % for the mode with its residual."]
    # ---- pushing boundary vs geometry, mesh-independent apex stiffness (minutes: only on request)
    if quick or os.environ.get("PROBEDYN_REPORT_LONG") != "1":
        out += ["", "*Long studies (about four minutes on two cores), run with `PROBEDYN_REPORT_LONG=1 ./dev report`:* "
                "the pushing stick-slip -> sliding speed predicted from the reduced stiffness and confirmed by "
                "bisection for three geometries, and the apex stiffness under a spread (patch) load with its mesh "
                "convergence (docs/reduced-probes.md sections 11, 12; slow tests "
                "`test_pushing_boundary_moves_with_the_geometry_as_predicted`, `test_apex_patch_stiffness_converges`)."]
    else:
        pb = st.pushing_boundary_study()
        prow = [dict(g=r["label"], dofs=r["dofs"], kt=r["tip"]["k_tx"], ks=r["prediction"]["k_series"],
                     vp=r["prediction"]["predicted_transition_m_s"] * 1e6, vs=r["V_sim_m_s"] * 1e6,
                     ratio=r["ratio_sim_over_pred"], shp=r["pred_shift"], shs=r["sim_shift"], step=r["step_over_a"])
                for r in pb]
        out += ["", "**Pushing regime boundary vs geometry** (mica; tip = the reduced probe's scan spring, mass and "
                "damping at the apex): stick-slip -> sliding speed predicted by the quasi-static Prandtl–Tomlinson "
                "criterion with the tip in series with the Hertz contact, and found by bisection on simulated pushes "
                "(2 % bracket); the shifts are relative to the default geometry; step / a from a push at 3 µm/s.", "",
                _table(prow, [("g", "geometry", ""), ("dofs", "DOFs", ""), ("kt", "k_tip [N/m]", ".4g"),
                              ("ks", "k_series [N/m]", ".4g"), ("vp", "V* pred [µm/s]", ".4g"),
                              ("vs", "V* sim [µm/s]", ".4g"), ("ratio", "sim / pred", ".3f"),
                              ("shp", "shift pred", ".3f"), ("shs", "shift sim", ".3f"), ("step", "step / a", ".3f")])]
        ac = st.apex_patch_convergence()
        arow = [dict(h=r["h"] * 1e6, dofs=r["dofs"], ks=r["k_scan"], kn=r["k_normal"], kp=r["k_scan_point"])
                for r in ac["rows"]]
        out += ["", f"**Apex stiffness under a spread load** (Hertz-like weight over the tip surface within "
                f"{ac['radius'] * 1e6:g} µm of the apex) against a point load at the apex, on refined meshes: the patch "
                f"value converges (observed order {ac['order_k_scan']:.2f}, limit {ac['limit_k_scan']:.4g} N/m), the "
                "point value falls like 1/h (the sharp apex's singular compliance).", "",
                _table(arow, [("h", "h [µm]", ".3g"), ("dofs", "DOFs", ""), ("ks", "scan, patch [N/m]", ".5g"),
                              ("kn", "normal, patch [N/m]", ".5g"), ("kp", "scan, point [N/m]", ".5g")])]
    out += ["", f"*Section computed in {time.perf_counter() - t_start:.1f} s.*"]
    return "\n".join(out)
