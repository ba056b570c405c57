"""The parameter studies of section 4.2.4, as plain data (no plotting, no prose): what the
report (:mod:`probedyn.report.placing`), the command line (``probedyn place``), the docs and
the benchmarks show. Every function returns a JSON-able dict of SI numbers and arrays.

The reference scenario is Table 4.4 (sample ``M = 2e-18 kg``, ``lambda = 2``, radii, Hamaker
constants, ``zeta_0``, ``D = 5 um``, ``omega = 2.5 krad/s``, ``F0 = 5e-7 N``) on the probe
given. Where Table 4.4's operating point cannot release the sample at all (inertia nine orders
of magnitude below the adhesion, :mod:`.release`), the release, landing and selective-release
studies are run where release happens (``omega = 1e8 rad/s`` for the 2e-18 kg sample, or a
heavier sample near the probe's modes) and say so.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.lumped.ritz import RitzBasis

from . import capture as cap
from . import landing as ld
from . import multi as mu
from . import release as rel
from .approach import Approach
from .probe import TABLE, PlacingProbe, mass_plausibility

#: the released reference point of the landing studies (2e-18 kg sample, 0.5 um tip amplitude)
RELEASE_OMEGA = 1e8
RELEASE_A = 0.5e-6
#: frequency of the H_sb study: releases the sample for H_sb up to twice the table's
H_STUDY_OMEGA = 3e8


# ------------------------------------------------------------------------------------------
# Approach (4.13-4.21, Fig 4.20)
# ------------------------------------------------------------------------------------------


def approach_study(probe: PlacingProbe, amplitudes: Sequence[float] = (0.05e-9, 0.2e-9, 0.5e-9),
                   speeds: Sequence[float] = (1e-5, 1e-6), n_gaps: int = 12, simulate_shift: bool | int = 3,
                   n_freq: int = 300) -> dict[str, Any]:
    """Jump into contact (force balance and slow-approach simulations at ``speeds``), Fig 4.20a-c
    data, a time-domain check of (4.19)-(4.20), and the frequency shift vs gap."""
    ap = Approach.from_probe(probe)
    js = ap.jump_in()
    z_star = js["z0_star_m"]
    sims = [ap.simulate_approach(v) for v in speeds]
    expo = [math.log(sims[i]["delay_m"] / sims[i + 1]["delay_m"]) / math.log(speeds[i] / speeds[i + 1])
            for i in range(len(sims) - 1)]
    # Fig 4.20a
    fb = ap.force_balance_curves([1.6 * z_star, 1.25 * z_star, z_star, 0.85 * z_star])
    # Figs 4.20b, c
    w0 = ap.omega0
    om = np.linspace(0.02 * w0, 1.6 * w0, n_freq)
    gaps = [50 * z_star, 2.5 * z_star, 1.5 * z_star, 1.2 * z_star, 1.05 * z_star]
    resp = []
    for z0 in gaps:
        r = ap.response(z0, om)
        resp.append({"z0_m": z0, "gain": r["gain"], "phase_rad": r["phase_rad"],
                     "omega_n_rad_s": r["omega_n_rad_s"], "amplitude_per_force_m_per_n": r["compliance_m_per_n"]})
    # time-domain check of the linearised response at one gap, at its resonance
    z_chk = 1.5 * z_star
    lin = ap.linearised(z_chk)
    F0 = 1e-4 * lin["k_star_n_per_m"] * (lin["s_eq_m"])  # amplitude ~ 1e-4 s / (2 zeta)
    sim_f = ap.simulate_forced(z_chk, lin["omega_n_rad_s"], F0)
    lin_f = ap.response(z_chk, lin["omega_n_rad_s"])
    forced = {"z0_m": z_chk, "omega_rad_s": lin["omega_n_rad_s"], "F0_n": F0,
              "amplitude_sim_m": sim_f["amplitude_m"], "amplitude_linear_m": F0 * float(lin_f["compliance_m_per_n"]),
              "phase_sim_rad": sim_f["phase_rad"], "phase_linear_rad": float(lin_f["phase_rad"])}
    # frequency shift
    z0s = z_star * np.geomspace(1.03, 6.0, n_gaps)
    rows = ap.frequency_shift_table(z0s, amplitudes, simulate=simulate_shift)
    return {"probe": probe.describe(), "C_n_m2": ap.C, "H_j": ap.H, "R_m": ap.R, "zeta0_m": ap.zeta0,
            "k_n_per_m": ap.k, "m_kg": ap.m, "f0_hz": ap.omega0 / (2 * math.pi), "jump": js,
            "jump_simulations": sims, "jump_delay_exponents": expo,
            "force_balance": fb, "response_gaps_m": gaps, "response_omega_rad_s": om, "response": resp,
            "forced_check": forced, "shift_rows": rows, "amplitudes_m": list(amplitudes)}


# ------------------------------------------------------------------------------------------
# Capture (4.22-4.41, Figs 4.18, 4.21)
# ------------------------------------------------------------------------------------------


def capture_ritz_basis(model, n_modes: int = 8):
    """FEM-mode Ritz basis with static correction shapes (z) at the free end: exact in the
    static limit for a spring and a mass there (:mod:`probedyn.lumped.ritz`)."""
    return RitzBasis.from_model(model, int(n_modes), attachments=[("free_end", "z")])


def _ritz_capture(basis, probe: PlacingProbe, K: float, muv: float, n: int):
    k1 = K * probe.EI / probe.L**3
    M = muv * probe.rhoA * probe.L / float(probe.provenance.get("mass_scale", 1.0))
    sol = basis.solve(point_masses=[("free_end", M)] if M > 0 else [],
                      springs=[("free_end", None, k1, (0.0, 0.0, 1.0))] if k1 > 0 else [])
    return sol, mu.flapwise_indices(sol, basis.model)


def capture_study(probe: PlacingProbe, K_values: Sequence[float] = (0.0, 3.0, 30.0, 300.0, 3000.0),
                  mu_values: Sequence[float] = (0.0, 0.1, 1.0), n: int = 3, basis=None,
                  fem_check: bool = False, n_x: int = 101, n_eval: int = 2001) -> dict[str, Any]:
    """Frequency equation (corrected and printed) for a grid of ``K = k1 L^3/EI`` and
    ``mu = M/(rho A L)``; the check against the FEM (``fem_check``: full re-solves; else against
    the FEM-mode Ritz model with static shapes at the tip, ``basis``); mode shapes for increasing
    ``beta`` (Fig 4.21); the MD linearisation and its piecewise-linear error (Fig 4.18); and the
    frequency shift a Table 4.4 sample causes."""
    rows = []
    for K in K_values:
        for m_ in mu_values:
            c = cap.Capture(probe.L, probe.EI, probe.rhoA, K * probe.EI / probe.L**3, m_ * probe.rhoA * probe.L)
            x = c.roots(n)
            xp = cap.capture_roots(K, m_, n, form="printed")
            for i in range(n):
                rows.append({"K": K, "mu": m_, "mode": i + 1, "bL": float(x[i]), "bL_printed": float(xp[i]),
                             "beta_L3": float(cap.end_stiffness(float(x[i]), K, m_)),
                             "beta_L3_printed": float(cap.end_stiffness(float(xp[i]), K, m_, form="printed")),
                             "omega_rad_s": float(x[i] ** 2 * c.omega_scale)})
    # heavier sample: frequency vs mu (Fig: an attached mass lowers the frequency)
    mus = np.linspace(0.0, 2.0, 41)
    mass_curve = {"mu": mus}
    for K in (0.0, 3.0):
        mass_curve[f"K{K:g}_corrected"] = np.array([cap.capture_roots(K, m_, 1)[0] for m_ in mus])
        mass_curve[f"K{K:g}_printed"] = np.array([cap.capture_roots(K, m_, 1, form="printed")[0] for m_ in mus])
    # check against the FEM
    checks = []
    shapes = {"x_over_L": np.linspace(0, 1, n_x), "K": list(K_values), "analytic": [], "fem_x_over_L": None,
              "fem": []}
    if fem_check and probe.model is not None:
        cases = [(K, m_) for K in K_values for m_ in mu_values]
        checks = cap.capture_check(probe, cases, n)
        method = "FEM (full re-solve)"
    elif basis is not None:
        method = "FEM-mode Ritz basis with static shapes at the tip"
        for K in K_values:
            for m_ in mu_values:
                c = cap.Capture(probe.L, probe.EI, probe.rhoA, K * probe.EI / probe.L**3, m_ * probe.rhoA * probe.L)
                an = c.frequencies(n)
                sol, flap = _ritz_capture(basis, probe, K, m_, n)
                for i in range(min(n, len(flap))):
                    om = float(sol.omega[flap[i]]) / math.sqrt(float(probe.provenance.get("mass_scale", 1.0)))
                    checks.append({"K": K, "mu": m_, "mode": i + 1, "bL": float(c.roots(n)[i]),
                                   "beta_L3": float(cap.end_stiffness(float(c.roots(n)[i]), K, m_)),
                                   "omega_eq": float(an[i]), "omega_fem": om, "rel_diff": om / float(an[i]) - 1.0})
    else:
        method = "none"
    x = shapes["x_over_L"] * probe.L
    for K in K_values:
        c = cap.Capture(probe.L, probe.EI, probe.rhoA, K * probe.EI / probe.L**3, 0.0)
        shapes["analytic"].append({"K": K, "bL": c.roots(n), "beta_L3": c.betas(n), "shapes": c.shapes(x, n)})
    if basis is not None:
        for K in K_values:
            sol, flap = _ritz_capture(basis, probe, K, 0.0, n)
            fx, fs = cap.centreline_shapes(basis.model, [basis.expand(sol.shapes[:, i]) for i in flap[:n]])
            shapes["fem_x_over_L"] = fx / probe.L
            shapes["fem"].append({"K": K, "shapes": fs})
    # MD linearisation and the piecewise-linear approximation
    contact = rel.placing_contact()
    lin = cap.md_linearisation(contact, 0.0)
    ns = [2, 4, 8, 16, 32, 64]
    ref = cap._pl_reference(contact, None, int(n_eval))
    pl = {sp: [cap.piecewise_linear_error(contact, k, sp, reference=ref) for k in ns] for sp in ("uniform", "graded")}
    orders = {sp: cap.convergence_order(ns[2:], [r["max_error_n"] for r in pl[sp][2:]]) for sp in pl}
    curves = {f"{sp}_{r['n_segments']}": {"delta_m": r["delta_m"], "force_n": r["force_n"], "force_pl_n": r["force_pl_n"],
                                          "nodes_m": r["nodes_m"], "node_forces_n": r["node_forces_n"]}
              for sp in pl for r in pl[sp] if r["n_segments"] in (4, 8)}
    # a Table 4.4 sample on the tip: the frequency shift it causes
    k1 = lin["k1_n_per_m"]
    M = float(TABLE["M1"])
    sample = {}
    for src in ("geometric", "table"):
        try:
            pr = probe.with_mass_source(src)
        except ParameterError:
            continue
        base = cap.Capture.from_probe(pr, 0.0, 0.0).frequencies(1)[0]
        hang = cap.Capture.from_probe(pr, k1, M, "hanging").frequencies(1)[0]
        grd = cap.Capture.from_probe(pr, k1, M, "grounded").frequencies(1)[0]
        sample[src] = {"mu": M / (pr.rhoA * pr.L), "K_contact": k1 * pr.L**3 / pr.EI,
                       "f1_bare_hz": base / (2 * math.pi), "df_rel_hanging": hang / base - 1.0,
                       "df_rel_grounded": grd / base - 1.0,
                       "df_rel_first_order": -0.5 * M / pr.modal_masses[0]}
    err = [abs(r["rel_diff"]) for r in checks]
    return {"rows": rows, "mass_curve": mass_curve, "check": checks, "check_method": method,
            "check_max_abs_rel": max(err) if err else math.nan,
            "check_bL_range": [min(r["bL"] for r in checks), max(r["bL"] for r in checks)] if checks else None,
            "check_beta_range": [min(r["beta_L3"] for r in checks), max(r["beta_L3"] for r in checks)] if checks else None,
            "shapes": shapes, "md": lin, "pl_errors": {sp: [{k: v for k, v in r.items() if not isinstance(v, np.ndarray)}
                                                            for r in pl[sp]] for sp in pl},
            "pl_orders": orders, "pl_curves": curves, "sample_on_tip": sample}


# ------------------------------------------------------------------------------------------
# Release (4.42, Figs 4.22, 4.23)
# ------------------------------------------------------------------------------------------


def release_examples(probe: PlacingProbe, A: float = RELEASE_A, omega: float = RELEASE_OMEGA,
                     n_scan: int = 60) -> dict[str, Any]:
    """Fig 4.22: the three outcomes at fixed tip amplitude and frequency for three sample masses
    (found by scanning the mass around the pull-off threshold ``|F_po| / (omega^2 A)``),
    with their trajectories; plus the Table 4.4 operating point."""
    tabs = rel._tables(float(TABLE["lambda"]))
    M_th = abs(tabs.pull_off_force) / (omega**2 * A)
    # recapture lives in a narrow band just above the threshold: scan it densely
    k = max(n_scan - 8, 4)
    Ms = M_th * np.concatenate([np.geomspace(0.7, 0.9, 4, endpoint=False), np.linspace(0.9, 1.1, k),
                                np.geomspace(1.2, 3.0, 4)])
    codes = []
    for M in Ms:
        st = rel.setup_release(probe, M=float(M), A=A, omega=omega, tables=tabs)
        codes.append(rel.simulate(st).code)
    codes = np.array(codes)
    picks = {}
    for code, name in ((0, "attached"), (1, "recaptured"), (2, "released")):
        idx = np.nonzero(codes == code)[0]
        if idx.size:
            picks[name] = float(Ms[idx[len(idx) // 2]] if name != "released" else Ms[idx[-1]])
    runs = {}
    for name, M in picks.items():
        st = rel.setup_release(probe, M=M, A=A, omega=omega, tables=tabs)
        r = rel.simulate(st, record=True)
        runs[name] = {"result": r.to_dict(), "trajectory": r.trajectory}
    table_pt = rel.simulate(rel.setup_release(probe, tables=tabs))
    return {"A_m": A, "omega_rad_s": omega, "M_threshold_kg": M_th, "mass_scan_kg": Ms, "mass_scan_outcome": codes,
            "runs": runs, "table_point": table_pt.to_dict()}


def release_maps(probe: PlacingProbe, n: int = 16, workers: int = 2, out_dir=None, processes: bool = True,
                 which: Sequence[str] = ("omega_A", "M_omega", "D_omega"), progress: bool = False) -> dict[str, Any]:
    """Outcome maps on Dask (NetCDF under ``out_dir`` if given):

    * ``omega_A``: drive frequency 1e6-1e10 rad/s x tip amplitude 0.1 nm-2 um at ``M = 2e-18 kg``;
    * ``M_omega``: sample mass 1e-19-1e-9 kg x frequency 1e3-1e10 rad/s at ``A = 0.5 um`` (samples
      heavier than ``|F_po| / g = 4.8e-10 kg`` fall under their own weight);
    * ``D_omega``: release height 0.6-10 um x frequency around the threshold at ``A = 0.5 um``."""
    if not (isinstance(workers, int) and workers >= 1):
        raise ParameterError(f"workers must be a positive integer, got {workers}")
    specs = {
        "omega_A": ({"omega": np.geomspace(1e6, 1e10, n), "A": np.geomspace(1e-10, 2e-6, n)}, {"M": float(TABLE["M1"])}),
        "M_omega": ({"M": np.geomspace(1e-19, 1e-9, n), "omega": np.geomspace(1e3, 1e10, n)}, {"A": RELEASE_A}),
        "D_omega": ({"D": np.geomspace(0.6e-6, 10e-6, n), "omega": np.geomspace(5e7, 1.5e8, n)},
                    {"A": RELEASE_A, "M": float(TABLE["M1"])}),
    }
    out = {}
    for key in which:
        grid, fixed = specs[key]
        path = None if out_dir is None else Path(out_dir) / f"placing_map_{key}_{n}x{n}.nc"
        res = rel.outcome_map(probe, grid, fixed=fixed, out=path, workers=workers, processes=processes,
                              progress=progress, chunk_size=max(16, (n * n) // (4 * workers)))
        ds = res.dataset
        names = list(grid)
        out[key] = {"axes": names, "x": grid[names[0]], "y": grid[names[1]], "fixed": fixed,
                    "outcome": ds["outcome"].transpose(*names).values, "cpu_s": ds["cpu_s"].transpose(*names).values,
                    "elapsed_s": res.elapsed, "path": str(path) if path else None,
                    "counts": {v: int((ds["outcome"].values == k).sum()) for k, v in rel.OUTCOMES.items()}}
    tabs = rel._tables(float(TABLE["lambda"]))
    out["F_pull_off_n"] = tabs.pull_off_force
    out["k1_n_per_m"] = tabs.k1_bar * tabs.P / tabs.l
    return out


# ------------------------------------------------------------------------------------------
# Landing (4.43-4.44, Figs 4.23, 4.27, 4.28)
# ------------------------------------------------------------------------------------------


def _landing(probe, M, A, omega, D=None, law="derjaguin", H_sb=None, tilt="amplitude", near_field=True):
    tabs = rel._tables(float(TABLE["lambda"])) if H_sb is None else rel._tables_H(float(H_sb))
    st = rel.setup_release(probe, M=M, A=A, omega=omega, D=D, tables=tabs)
    r = rel.simulate(st)
    return ld.land(r, tilt=tilt, law=law, H_sb=H_sb, near_field=near_field)


def landing_study(probe: PlacingProbe, n: int = 9, law: str = "derjaguin") -> dict[str, Any]:
    """What dominates the flight (force budget, gravity cross-over), the sample's height and
    lateral position after release for several ``D`` (Fig 4.23) and ``H_sb`` (Fig 4.27), and the
    landing radius against amplitude and frequency (Fig 4.28a) and mass (Fig 4.28b)."""
    M0 = float(TABLE["M1"])
    budget = {lw: ld.force_budget(law=lw) for lw in ld.LAWS}
    cross = {lw: ld.gravity_crossover(law=lw) for lw in ld.LAWS}
    v_escape = math.sqrt(2 * abs(rel._tables(float(TABLE["lambda"])).pull_off_force) * float(TABLE["zeta0"]) / M0)
    ref = _landing(probe, M0, RELEASE_A, RELEASE_OMEGA, law=law)
    traj_D = []
    for D in (3e-6, 5e-6, 7e-6):
        L_ = _landing(probe, M0, RELEASE_A, RELEASE_OMEGA, D=D, law=law)
        traj_D.append({"D_m": D, "outcome": L_.release.outcome, "t_s": L_.flight["t_s"] if L_.flight else None,
                       "y_m": L_.flight["y_m"] if L_.flight else None, "x_m": L_.flight["x_m"] if L_.flight else None,
                       "t_flight_s": L_.flight["t_flight_s"] if L_.flight else math.nan, "R_L_m": L_.R_L})
    traj_H = []
    for f in (0.5, 1.0, 2.0):
        H = f * float(TABLE["H_sb"])
        L_ = _landing(probe, M0, RELEASE_A, H_STUDY_OMEGA, law=law, H_sb=H)
        tb = rel._tables_H(H)
        traj_H.append({"H_sb_j": H, "lambda": tb.contact.lam, "F_pull_off_n": tb.pull_off_force,
                       "outcome": L_.release.outcome, "t_s": L_.flight["t_s"] if L_.flight else None,
                       "x_m": L_.flight["x_m"] if L_.flight else None, "R_L_m": L_.R_L,
                       "t_flight_s": L_.flight["t_flight_s"] if L_.flight else math.nan})
    As = np.geomspace(0.1e-6, 1.5e-6, n)
    oms = (1e8, 3e8, 1e9)
    RL_A = {f"{om:g}": np.array([_landing(probe, M0, float(A), om, law=law).R_L for A in As]) for om in oms}
    Ms = np.geomspace(0.5e-18, 2e-16, n)
    RL_M = {f"{om:g}": np.array([_landing(probe, float(M), RELEASE_A, om, law=law).R_L for M in Ms]) for om in oms}
    tilt_cmp = {t: _landing(probe, M0, RELEASE_A, RELEASE_OMEGA, law=law, tilt=t).R_L for t in ld.TILTS}
    no_nf = _landing(probe, M0, RELEASE_A, RELEASE_OMEGA, law=law, near_field=False).R_L
    law_cmp = {lw: _landing(probe, M0, RELEASE_A, RELEASE_OMEGA, law=lw).R_L for lw in ld.LAWS}
    return {"law": law, "force_budget": budget, "gravity_crossover_m": cross, "escape_speed_estimate_m_s": v_escape,
            "reference": {**ref.to_dict(), "M_kg": M0, "A_m": RELEASE_A, "omega_rad_s": RELEASE_OMEGA,
                          "release_velocity_m_s": ref.release.sample_velocity_m_s},
            "vs_D": traj_D, "vs_H_sb": traj_H, "H_study_omega_rad_s": H_STUDY_OMEGA, "A_m": As, "R_L_vs_A": RL_A, "M_kg": Ms, "R_L_vs_M": RL_M,
            "omegas_rad_s": list(oms), "tilt_rules": tilt_cmp, "R_L_without_near_field": no_nf, "laws": law_cmp}


# ------------------------------------------------------------------------------------------
# Several samples (4.45-4.55, Figs 4.24-4.26)
# ------------------------------------------------------------------------------------------


def multi_study(probe: PlacingProbe, model=None, ns: Sequence[int] = (2, 3, 4, 6, 8, 12, 16),
                mode_counts: Sequence[int] = (6, 8, 12, 16), ratios: Sequence[float] = (0.1, 1.0),
                fem_reference: bool = True, selective_mass: float = 1e-13, verify: bool = True,
                inverse_starts: int = 8, basis=None, drive: str = "tip") -> dict[str, Any]:
    """Rayleigh-Ritz convergence (polynomial and FEM-mode bases) against the exact beam and the
    FEM with two masses at L/2 and L; the printed 2-term matrices; identifiability and one
    inverse solution; selective release by frequency and by amplitude. ``basis``: a Ritz basis
    of ``model`` with static shapes at L/2 and L (sub-bases by truncation, no eigen-solve);
    else one is built per mode count. ``drive``: ``"tip"`` (a force F0 at the tip, 4.13; amplitudes
    in N) or ``"base"`` (clamp motion, in m) for the selective release."""
    L, EI, rA = probe.L, probe.EI, probe.rhoA
    mb = rA * L
    scale = float(probe.provenance.get("mass_scale", 1.0))
    conv = []
    for r in ratios:
        ms = [(0.5 * L, r * mb), (L, r * mb)]
        ex = mu.exact_frequencies(L, EI, rA, ms, 4)
        fem = mu.fem_frequencies(model, ms, 4, mass_scale=scale) if (model is not None and fem_reference) else None
        for n_ in ns:
            om = mu.PolynomialRitz(L, EI, rA, n_).solve(ms)["omega"][:4]
            k = min(4, n_)
            conv.append({"basis": "polynomial", "ratio": r, "n": n_, "rel_err_exact": list(om[:k] / ex[:k] - 1),
                         "rel_err_fem": list(om[:k] / fem[:k] - 1) if fem is not None else None})
        if model is not None:
            for nm in mode_counts:
                for static in (False, True):
                    if basis is not None:
                        nm_ = min(nm, basis.n_modes)
                        if hasattr(basis, "truncate"):
                            b = basis.truncate(nm_, static=static)
                        elif static:
                            if nm_ != basis.n_modes:
                                continue
                            b = basis
                        else:
                            b = basis.leading(nm_)
                    else:
                        b = mu.ritz_basis(model, nm, [0.5 * L, L], static=static)
                    om = mu.ritz_flapwise(b, [(l, m / scale) for l, m in ms], 3) / math.sqrt(scale)
                    conv.append({"basis": "FEM modes" + (" + static shapes" if static else ""), "ratio": r, "n": nm,
                                 "rel_err_exact": list(om / ex[:3] - 1),
                                 "rel_err_fem": list(om / fem[:3] - 1) if fem is not None else None})
        conv.append({"basis": "FEM (full re-solve)", "ratio": r, "n": None,
                     "rel_err_exact": list(fem / ex - 1) if fem is not None else None, "rel_err_fem": None})
    # frequencies against the position of one sample (mass 0.1 rho A L): exact, polynomial, FEM
    xs = np.linspace(0.1, 1.0, 10)
    pos = {"x_over_L": xs, "exact": [], "polynomial": [], "ritz_modes": []}
    Mp = 0.1 * mb
    for f in xs:
        ms1 = [(f * L, Mp)]
        pos["exact"].append(mu.exact_frequencies(L, EI, rA, ms1, 3))
        pos["polynomial"].append(mu.PolynomialRitz(L, EI, rA, 12).solve(ms1)["omega"][:3])
        if basis is not None:
            b_ = basis.leading(basis.n_modes)
            pos["ritz_modes"].append(mu.ritz_flapwise(b_, [(f * L, Mp / scale)], 3) / math.sqrt(scale))
    pos["bare"] = mu.exact_frequencies(L, EI, rA, [], 3)
    pos = {k: np.asarray(v) for k, v in pos.items()}
    # printed 2-term matrices against the Legendre basis with n = 2
    ms_t = [(0.5 * L, float(TABLE["M1"])), (L, float(TABLE["M2"]))]
    K2, M2 = mu.printed_matrices(EI, rA, L, ms_t)
    printed = {"omega_printed": mu.matrices_frequencies(K2, M2), "omega_legendre2": mu.PolynomialRitz(L, EI, rA, 2).solve(ms_t)["omega"]}
    # identifiability: Table 4.4 masses, and 1 % of the beam mass
    ident = {"table": mu.identifiability(probe, M=[TABLE["M1"], TABLE["M2"]]),
             "heavy": mu.identifiability(probe, M=[0.01 * mb, 0.01 * mb])}
    # one inverse solution: both positions from two frequencies (heavy masses, 1e-6 noise),
    # synthetic data from the exact beam (independent of the Ritz model)
    Mh = 0.01 * mb
    ex0 = mu.exact_frequencies(L, EI, rA, [], 2)
    exm = mu.exact_frequencies(L, EI, rA, [(0.5 * L, Mh), (L, Mh)], 2)
    rng = np.random.default_rng(1)
    sig = 1e-6
    meas = exm / ex0 - 1 + sig * rng.standard_normal(2)
    inv = mu.solve_inverse(probe, meas, ["l1", "l2"], {"M1": Mh, "M2": Mh}, sig, starts=inverse_starts)
    # selective release
    Msel = float(selective_mass)
    ms_sel = [(0.5 * L, Msel), (L, Msel)]
    w1 = probe.omega1
    tabs0 = rel._tables(float(TABLE["lambda"]))
    w_c = math.sqrt(tabs0.k1_bar * tabs0.P / tabs0.l / Msel)  # the sample's contact resonance
    w_hi = min(40 * w1, 0.3 * w_c)  # quasi-static contact: the threshold formula holds
    om = np.geomspace(0.2 * w1, w_hi, 600)
    thr = mu.release_thresholds(probe, ms_sel, om, drive)
    ratio = thr[:, 1] / thr[:, 0]
    i1 = int(np.argmax(ratio))  # sample 1 (L/2) easiest relative to sample 2
    i2 = int(np.argmin(ratio))
    thr_tab = mu.release_thresholds(probe, [(0.5 * L, float(TABLE["M1"])), (L, float(TABLE["M2"]))], om, drive)
    other = "base" if drive == "tip" else "tip"
    thr_o = mu.release_thresholds(probe, ms_sel, om, other)
    sel = {"drive": drive, "M_kg": Msel, "omega_c_rad_s": w_c, "omega_rad_s": om, "Y_threshold": thr,
           "Y_threshold_table_masses": thr_tab,
           "best_for_sample1": {"omega_rad_s": float(om[i1]), "Y1": float(thr[i1, 0]), "Y2": float(thr[i1, 1]),
                                "ratio": float(ratio[i1])},
           "best_for_sample2": {"omega_rad_s": float(om[i2]), "Y1": float(thr[i2, 0]), "Y2": float(thr[i2, 1]),
                                "ratio": float(ratio[i2])},
           "other_drive": other, "other_drive_max_ratio": float(np.max(thr_o[:, 1] / thr_o[:, 0])),
           "other_drive_min_ratio": float(np.min(thr_o[:, 1] / thr_o[:, 0]))}
    # amplitude-based selection at a fixed frequency below the first mode
    w_amp = 0.8 * w1
    Ys = np.geomspace(0.2, 5.0, 25) * float(np.min(mu.release_thresholds(probe, ms_sel, [w_amp], drive)))
    T = np.abs(mu.local_response(probe, ms_sel, [w_amp], drive))[0]
    amp = {"drive": drive, "omega_rad_s": w_amp, "Y": Ys, "local_per_Y": T,
           "Y_threshold": mu.release_thresholds(probe, ms_sel, [w_amp], drive)[0]}
    if verify:
        tabs = rel._tables(float(TABLE["lambda"]))
        checks = []
        cases = [("frequency, sample 1 alone" if ratio[i1] > 1 else "frequency, best for sample 1", float(om[i1]),
                  float(np.sqrt(thr[i1, 0] * thr[i1, 1]))),
                 ("frequency, sample 2 alone", float(om[i2]), float(np.sqrt(thr[i2, 0] * thr[i2, 1]))),
                 ("amplitude, low", w_amp, float(np.sqrt(amp["Y_threshold"][0] * amp["Y_threshold"][1]))),
                 ("amplitude, high", w_amp, float(1.5 * max(amp["Y_threshold"])))]
        for label, wv, Y in cases:
            Tl = np.abs(mu.local_response(probe, ms_sel, [wv], drive))[0]
            thr_l = mu.release_thresholds(probe, ms_sel, [wv], drive)[0]
            outs = []
            for k, (l, Mk) in enumerate(ms_sel):
                pk = mu.probe_at(probe, l, ms_sel)
                Ak = float(Y * Tl[k])
                st = rel.setup_release(pk, M=Mk, A=Ak, omega=wv, tables=tabs, D=max(50e-6, 10 * float(np.max(Tl * Y))))
                outs.append(rel.simulate(st).outcome)
            pred = ["released" if Y > thr_l[k] else "attached" for k in range(2)]
            checks.append({"case": label, "omega_rad_s": wv, "Y": Y, "local_amplitudes_m": list(Tl * Y),
                           "predicted_sample1": pred[0], "predicted_sample2": pred[1],
                           "outcome_sample1": outs[0], "outcome_sample2": outs[1]})
        sel["checks"] = checks
    return {"convergence": conv, "positions": pos, "printed": printed, "identifiability": ident,
            "inverse": {"true": {"l1": 0.5 * L, "l2": L}, "M_kg": Mh, "sigma": sig, "measured": meas, **inv},
            "selective_frequency": sel, "selective_amplitude": amp}


# ------------------------------------------------------------------------------------------
# Table 4.4 plausibility (departure 35)
# ------------------------------------------------------------------------------------------


def plausibility_study(probe: PlacingProbe) -> dict[str, Any]:
    """Table 4.4's ``m`` against the geometry, and the key numbers of every phase with either
    mass: which conclusions change."""
    mp = mass_plausibility(probe)
    rows = []
    tabs = rel._tables(float(TABLE["lambda"]))
    for src in ("geometric", "table"):
        pr = probe.with_mass_source(src)
        ap = Approach.from_probe(pr)
        js = ap.jump_in()
        z = 1.5 * js["z0_star_m"]
        df = ap.shift_small_amplitude(z)
        st = rel.setup_release(pr, tables=tabs)
        r = rel.simulate(st)
        st8 = rel.setup_release(pr, A=RELEASE_A, omega=RELEASE_OMEGA, tables=tabs)
        r8 = rel.simulate(st8)
        hang = cap.Capture.from_probe(pr, tabs.k1_bar * tabs.P / tabs.l, float(TABLE["M1"]), "hanging").frequencies(1)[0]
        base = cap.Capture.from_probe(pr, 0.0, 0.0).frequencies(1)[0]
        idn = mu.identifiability(pr, n_modes_list=(2,), unknown_sets=(("l1", "l2"),))[0]
        rows.append({"mass_source": src, "m_equivalent_kg": pr.m, "f1_hz": pr.f1, "jump_z0_m": js["z0_star_m"],
                     "df_at_1.5z_hz": df, "df_rel_at_1.5z": df / pr.f1,
                     "table_point_outcome": r.outcome, "tip_amplitude_table_F0_m": st.A,
                     "F0_for_0.5um_at_1e8_n": st8.F0, "outcome_at_1e8": r8.outcome,
                     "sample_df_rel": hang / base - 1.0,
                     "l_sd_per_unit_noise": max(idn["sd_per_unit_noise"].values()) if idn["identifiable"] else math.inf})
    return {"masses": mp, "rows": rows}


__all__ = ["approach_study", "capture_study", "capture_ritz_basis", "release_examples", "release_maps",
           "landing_study", "multi_study", "plausibility_study", "RELEASE_OMEGA", "RELEASE_A"]
