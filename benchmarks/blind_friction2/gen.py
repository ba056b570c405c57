"""Blind friction test set, generation 2: `python gen.py OUT_DIR`.

Writes OUT_DIR/cases/gNN.csv + gNN.toml (docs/diagnose.md sec. 1 (c) format) and OUT_DIR/KEY.json with the
true hidden cause of each record (catalog key and parameters, docs sec. 3) or "none".  Physics in
physics.py (independent of probedyn).  Fixed seed, reproducible.
"""
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
os.environ.setdefault("NUMBA_CACHE_DIR", "/tmp/bf2gen/numba")
import physics as ph  # noqa: E402

SEED = 20240611
KB = ph.KB

# --------------------------------------------------------------------------------------------------
# case table.  Atomic: lever (k, f_res, Q), lattice a, eta at the reference corrugation, T, scans
# [(speed, load)], n_periods per scan line, samples per period, sampling, noise.  Loops: spring-block.
# --------------------------------------------------------------------------------------------------
ATOMIC = [
    # ---- hidden effects
    dict(name="visc1", effect="viscous-friction", gamma=3e-5, k=1.2, f=80e3, Q=2.0, decl_damp="Q_x",
         a=0.40e-9, eta=4.0, T=10.0, scans=[(2e-7, 5e-9), (2e-6, 5e-9), (2e-7, 1e-8)], nper=14, nsub=20,
         noise=8e-12, part="detector", time="run", scan_ids=0),
    dict(name="visc2", effect="viscous-friction", gamma=1e-4, k=4.0, f=200e3, Q=10.0, decl_damp="c_x",
         a=0.28e-9, eta=6.0, T=295.0, scans=[(1.5e-7, 8e-9), (1.5e-6, 8e-9), (5e-7, 1.2e-8)], nper=16,
         nsub=14, noise=15e-12, part="detector", time="run", scan_ids=1),
    dict(name="adh1", effect="adhesion-load", n_adh=3e-9, k=2.0, f=150e3, Q=1.0, decl_damp=None,
         a=0.50e-9, eta=4.0, T=295.0, scans=[(2e-8, 4e-9), (2e-7, 4e-9), (2e-8, 1.2e-8)], nper=12,
         nsub=16, noise=10e-12, part="detector", time="run", scan_ids=0),
    dict(name="drift1", effect="force-offset-drift", offset=35e-12, drift=30e-12, k=0.8, f=50e3, Q=3.0,
         decl_damp="Q_x", a=0.246e-9, eta=3.0, T=77.0, scans=[(3e-8, 2e-9), (3e-7, 2e-9), (3e-8, 6e-9)],
         nper=16, nsub=12, noise=6e-12, part="detector", time="run", scan_ids=1),
    dict(name="cal1", effect="force-calibration", g=1.22, k=1.5, f=120e3, Q=1.5, decl_damp="Q_x",
         a=0.42e-9, eta=2.5, T=4.5, scans=[(5e-8, 3e-9), (5e-7, 3e-9), (5e-8, 6e-9)], nper=12, nsub=20,
         noise=5e-12, part="total", time="run", scan_ids=0),
    dict(name="cal2", effect="force-calibration", g=0.84, k=5.0, f=250e3, Q=0.5, decl_damp="c_x",
         a=0.30e-9, eta=3.5, T=8.0, scans=[(1e-7, 1e-8), (1e-6, 1e-8), (1e-7, 2e-8)], nper=14, nsub=6,
         sampling="point", noise=20e-12, part="detector", time="run", scan_ids=1),
    dict(name="bow1", effect="scanner-nonlinearity", bow=0.04, k=2.5, f=180e3, Q=4.0, decl_damp="c_x",
         a=0.35e-9, eta=5.0, T=297.0, scans=[(5e-8, 3e-9), (5e-7, 3e-9), (5e-8, 6e-9)], nper=40,
         nsub=10, noise=10e-12, part="detector", time="run", scan_ids=0, X0=1.5e-7),
    dict(name="mis1", effect="lattice-misalignment", theta_deg=18.0, ky_ratio=1.0, k=1.0, f=60e3, Q=2.0,
         decl_damp="Q_x", a=0.40e-9, eta=4.0, T=5.0, scans=[(4e-8, 2e-9), (4e-7, 2e-9), (4e-8, 4e-9)],
         nper=24, nsub=16, noise=6e-12, part="detector", time=None, scan_ids=0),
    dict(name="mis2", effect="lattice-misalignment", theta_deg=27.0, ky_ratio=2.5, k=3.0, f=140e3, Q=1.0,
         decl_damp=None, a=0.45e-9, eta=5.0, T=294.0, scans=[(6e-8, 5e-9), (6e-7, 5e-9), (6e-8, 1e-8)],
         nper=24, nsub=14, noise=15e-12, part="detector", time="run", scan_ids=1),
    dict(name="therm1", effect="thermal-activation", k=1.0, f=90e3, Q=1.2, decl_damp="Q_x", a=0.40e-9,
         eta=5.0, T=296.0, T_declared=False, scans=[(1e-8, 3e-9), (1e-7, 3e-9), (1e-6, 3e-9)], nper=14,
         nsub=12, noise=8e-12, part="detector", time="run", scan_ids=0),
    # ---- nulls
    dict(name="null1", effect="none", k=0.6, f=35e3, Q=0.4, decl_damp="c_x", a=0.45e-9, eta=7.0, T=298.0,
         scans=[(5e-9, 2e-9), (5e-8, 2e-9), (5e-9, 4e-9)], nper=10, nsub=12, noise=5e-12,
         part="detector", time="run", scan_ids=0),
    dict(name="null2", effect="none", k=8.0, f=280e3, Q=15.0, decl_damp="Q_x", a=0.50e-9, eta=3.0, T=80.0,
         scans=[(5e-7, 1e-8), (2e-6, 1e-8), (5e-7, 2e-8)], nper=12, nsub=10, noise=30e-12, part="total",
         time="run", scan_ids=1),
    dict(name="null3", effect="none", k=1.0, f=100e3, Q=1.0, decl_damp=None, decl_mass=False, a=0.40e-9,
         eta=4.5, T=4.2, scans=[(2.5e-8, 1e-9), (2.5e-7, 1e-9), (2.5e-8, 3e-9)], nper=12, nsub=16,
         noise=4e-12, part="total", time="run", scan_ids=0),
    dict(name="null4", effect="none", k=2.0, f=130e3, Q=6.0, decl_damp="Q_x", a=0.36e-9, eta=3.2, T=293.0,
         scans=[(5e-8, 5e-9), (1.5e-7, 5e-9), (5e-7, 5e-9)], nper=14, nsub=5, sampling="point",
         noise=12e-12, part=None, time=None, scan_ids=1),
    dict(name="null5", effect="none", k=6.0, f=220e3, Q=0.8, decl_damp="c_x", a=0.30e-9, eta=2.4, T=300.0,
         scans=[(2e-7, 1.5e-8), (2e-6, 1.5e-8), (2e-7, 2.5e-8)], nper=14, nsub=12, noise=18e-12,
         part="detector", corr=0.4, time="reset", scan_ids=0, retrace=False),
]

LOOPS = [
    dict(name="adhL", effect="adhesion-load", n_adh=6e-9, k=0.8, kc=20.0, f=45e3, Q=2.0, decl_damp="Q_x",
         a=0.40e-9, mu=0.25, T=296.0, L=2.0e-6, n=100, scans=[(1e-6, 5e-9), (1e-6, 1.5e-8), (1e-6, 3e-8)],
         noise=30e-12, time="run", topo="flat", scan_ids=1),
    dict(name="driftL", effect="force-offset-drift", offset=-0.12e-9, drift=0.25e-9, k=2.5, kc=30.0,
         f=120e3, Q=1.0, decl_damp=None, a=0.30e-9, mu=0.2, T=295.0, L=3.0e-6, n=120,
         scans=[(1.5e-6, 1.5e-8)] * 4, noise=20e-12, time="run", topo="flat", scan_ids=1),
    dict(name="slopeL", effect="surface-slope", k=1.8, kc=25.0, f=70e3, Q=3.0, decl_damp="Q_x", a=0.30e-9,
         mu=0.22, T=295.0, L=3.0e-6, n=150, scans=[(2e-6, 1.5e-8)] * 3, noise=25e-12, time="run",
         topo="grating", scan_ids=1),
    dict(name="contL", effect="friction-contrast", contrast=0.6, k=0.6, kc=15.0, f=40e3, Q=1.5,
         decl_damp="Q_x", a=0.50e-9, mu=0.15, T=294.0, L=5.0e-6, n=200, scans=[(1.5e-6, 8e-9)] * 4,
         noise=10e-12, time="run", topo="blend", scan_ids=1),
    dict(name="nullL1", effect="none", k=1.2, kc=20.0, f=60e3, Q=1.0, decl_damp=None, a=0.40e-9, mu=0.3,
         T=295.0, L=2.0e-6, n=100, scans=[(1e-6, 1e-8)] * 4, noise=15e-12, time="run", topo="none",
         scan_ids=0),
    dict(name="nullL2", effect="none", k=9.0, kc=40.0, f=250e3, Q=8.0, decl_damp="c_x", a=0.25e-9, mu=0.12,
         T=293.0, L=4.0e-6, n=128, scans=[(2e-6, 3e-8)] * 3, noise=25e-12, noise_decl=False, time=None,
         topo="flatnoise", scan_ids=1),
]


def lever_params(c):
    k = c["k"]
    m = k / (2 * math.pi * c["f"]) ** 2
    cx = math.sqrt(k * m) / c["Q"]
    return k, m, cx


def fmt(x):
    return f"{x:.6e}"


def write_toml(path, csvname, c, k, m, cx, scans_tbl, lattice, sampling, noise_tbl, T_decl):
    L = ["# Synthetic FFM lateral-force record (blind_friction2).", "[measurement]", 'kind = "friction"',
         f'data = "{csvname}"']
    if sampling:
        L.append(f'sampling = "{sampling}"')
    L += ["", "[lever]", f"k_x = {k!r}"]
    if c.get("decl_mass", True):
        L.append(f"m_x = {m:.6e}")
    if c.get("decl_damp") == "Q_x":
        L.append(f"Q_x = {c['Q']!r}")
    elif c.get("decl_damp") == "c_x":
        L.append(f"c_x = {cx:.6e}")
    L += ["", "[sample]", f"lattice = {lattice:.6e}"]
    if T_decl is not None:
        L += ["", "[medium]", f"temperature = {T_decl!r}"]
    if noise_tbl:
        L += ["", "[noise]"] + [f"{kk} = {vv}" for kk, vv in noise_tbl]
    for sid, sp, load in scans_tbl:
        L += ["", "[[scans]]", f"id = {sid}", f"speed = {sp:.6e}", f"load = {load:.6e}"]
    with open(path, "w") as fh:
        fh.write("\n".join(L) + "\n")


def write_csv(path, cols, names):
    with open(path, "w") as fh:
        fh.write("# lateral-force channel export\n")
        fh.write(",".join(names) + "\n")
        n = len(cols[0])
        for i in range(n):
            row = []
            for j, col in enumerate(cols):
                if names[j] == "scan":
                    row.append(str(int(col[i])))
                else:
                    row.append(fmt(col[i]))
            fh.write(",".join(row) + "\n")


def detector_noise(rng, n, sigma, corr):
    e = rng.standard_normal(n) * sigma
    if corr:
        out = np.empty(n)
        out[0] = e[0]
        s = math.sqrt(1 - corr * corr)
        for i in range(1, n):
            out[i] = corr * out[i - 1] + s * e[i]
        return out
    return e


def gen_atomic(c, rng, seed):
    k, m, cx = lever_params(c)
    a = c["a"]
    T = c["T"]
    eff = c["effect"]
    g = c.get("g", 1.0) if eff == "force-calibration" else 1.0
    gam = c.get("gamma", 0.0) if eff == "viscous-friction" else 0.0
    bow = c.get("bow", 0.0) if eff == "scanner-nonlinearity" else 0.0
    U0ref = ph.U0_of(c["eta"], k, a)
    loads = [s[1] for s in c["scans"]]
    Nref = float(np.mean(loads))
    nsub = c["nsub"]
    sampling = c.get("sampling", "interval-mean")
    L = c["nper"] * a
    n_samp = c["nper"] * nsub
    retrace = c.get("retrace", True)
    X0rec = c.get("X0", 0.0)
    rows = dict(scan=[], pos=[], F=[], t=[])
    scans_tbl = []
    per_scan = []
    t_clock = 0.0
    nsteps = 0
    id0 = c["scan_ids"]
    sim_results = []
    for si, (V, N) in enumerate(c["scans"]):
        if eff == "adhesion-load":
            U0 = U0ref * (N + c["n_adh"]) / (Nref + c["n_adh"])
        else:
            U0 = U0ref
        phase = rng.uniform(0, 1) * a
        p = dict(k=k, m=m, c=cx, gam_s=gam, U0=U0, a=a, T=T, bow=bow)
        theta = math.radians(c["theta_deg"]) if eff == "lattice-misalignment" else 0.0
        kyr = c["ky_ratio"] if eff == "lattice-misalignment" else None
        r = ph.simulate_atomic_scan(p, V, phase, L, n_samp, seed * 100 + si, ky_ratio=kyr, theta=theta,
                                    with_retrace=retrace)
        nsteps += r["nsteps"]
        sim_results.append((V, U0, r))
        if sampling == "point":
            F = r["point"]
            pos = r["ptpos"] - phase + X0rec
            tt = r["t_end"]
        else:
            F = r["mean"]
            pos = r["centre"] - phase + X0rec
            tt = r["t_end"] - 0.5 * r["tau_s"]
        dur = 2 * L / V if retrace else L / V
        rows["scan"].append(np.full(len(F), si + id0))
        rows["pos"].append(pos)
        rows["F"].append(g * F)
        rows["t"].append(tt + (t_clock if c.get("time") == "run" else 0.0))
        per_scan.append(dict(id=si + id0, speed=V, load=N, U0_J=U0, eta=ph.eta_of(U0, k, a),
                             peak_force_qs_N=math.pi * U0 / a, t_start_s=t_clock, duration_s=dur,
                             sample_interval_s=r["tau_s"], dt_s=r["dt"]))
        scans_tbl.append((si + id0, V, N))
        t_clock += 1.2 * dur  # the next scan starts after a pause of 20 % of this one (set-point change)
    Fall = np.concatenate(rows["F"])
    tall = np.concatenate(rows["t"])
    n = len(Fall)
    info = {}
    if eff == "force-offset-drift":
        Tlong = max(s["duration_s"] for s in per_scan)
        rate = c["drift"] / Tlong
        Fall = Fall + c["offset"] + rate * tall
        info.update(drift_rate_N_per_s=rate, longest_scan_s=Tlong,
                    offset_at_record_middle_N=c["offset"] + rate * 0.5 * (tall.min() + tall.max()),
                    offset_reference="offset = the added force at time_s = 0 (the record clock's start); "
                                     "drift = added force change over the longest scan's duration")
    sig = c["noise"]
    Fall = Fall + detector_noise(rng, n, sig, c.get("corr"))
    # the tip's interval-averaged thermal force noise estimate (for the 'total' declarations)
    th = []
    for V, U0, r in sim_results:
        if sampling == "point":
            th.append(math.sqrt(k * KB * T))
        else:
            th.append(math.sqrt(2 * KB * T * (cx + gam) / r["tau_s"]))
    th_max = max(th) * g
    noise_tbl = []
    decl_noise = None
    if c.get("noise_decl", True) and c.get("part") is not None:
        if c["part"] == "total":
            decl_noise = math.sqrt(sig ** 2 + th_max ** 2)
            noise_tbl.append(("force", f"{decl_noise:.4e}"))
        else:
            decl_noise = sig
            noise_tbl.append(("force", f"{sig:.4e}"))
            noise_tbl.append(("force_part", '"detector"'))
        if c.get("corr"):
            noise_tbl.append(("correlation", f"{c['corr']}"))
    # effective activation prefactor of the quasi-static hazard model, from the simulated slips
    act = None
    if T >= 50 and eff != "lattice-misalignment":
        act = activation_summary(sim_results, k, m, cx + gam, a, T)
    T_decl = T if c.get("T_declared", True) else None
    cols = [np.concatenate(rows["scan"]), np.concatenate(rows["pos"]), Fall]
    names = ["scan", "position_m", "lateral_force_N"]
    if c.get("time"):
        cols.append(tall)
        names.append("time_s")
    key = dict(effect=eff, regime="atomic stick-slip", sampling=sampling,
               samples_per_period=nsub, lattice_m=a, eta_ref=c["eta"], U0_ref_J=U0ref,
               U0_ref_over_kBT=(U0ref / (KB * T) if T > 0 else None), N_ref_mean_load_N=Nref,
               temperature_K=T, temperature_declared=c.get("T_declared", True), k_x=k, m_x=m,
               f_res_Hz=c["f"], Q_x=c["Q"], c_x=cx, damping_declared=c.get("decl_damp"),
               mass_declared=c.get("decl_mass", True), noise_detector_N=sig,
               noise_declared_N=decl_noise, noise_force_part=c.get("part") if decl_noise else None,
               noise_correlation=c.get("corr"), thermal_force_noise_est_N=th_max,
               trace_and_retrace=retrace, time_column=c.get("time"), scans=per_scan, seed=seed,
               steps=int(nsteps))
    key.update(info)
    if act:
        key["activation_effective"] = act
    if eff == "viscous-friction":
        key["gamma"] = c["gamma"]
        key["gamma_force_at_fastest_N"] = c["gamma"] * max(s[0] for s in c["scans"])
    elif eff == "adhesion-load":
        key["n_adh"] = c["n_adh"]
        key["adhesion_definition"] = "U0(N) = U0_ref (N + n_adh)/(N_ref + n_adh), N_ref = mean of the scans' loads"
    elif eff == "force-offset-drift":
        key["offset"] = c["offset"]
        key["drift"] = c["drift"]
    elif eff == "force-calibration":
        key["g"] = g
    elif eff == "scanner-nonlinearity":
        key["bow"] = bow
        key["bow_definition"] = ("true support X = X_rec + bow (X_rec - X0)(X1 - X_rec)/L, X0, X1 the "
                                 "scan's recorded ends, L = X1 - X0; same map in trace and retrace")
        key["bow_mid_deviation_m"] = bow * L / 4
    elif eff == "lattice-misalignment":
        key["theta_deg"] = c["theta_deg"]
        key["ky_ratio"] = c["ky_ratio"]
        key["slip_period_along_scan_m"] = a / math.cos(math.radians(c["theta_deg"]))
    elif eff == "thermal-activation":
        if act:
            key["log10_f0"] = act["log10_f0_fit"]
            key["log10 f0"] = act["log10_f0_fit"]
        key["note"] = "temperature NOT declared; true T = %.1f K" % T
    if eff == "none" and len(set(loads)) > 1:
        key["note"] = "null with two loads: corrugation independent of load (no adhesion-load effect)"
    if not retrace:
        key["note"] = key.get("note", "") + " trace only"
    return cols, names, scans_tbl, noise_tbl, T_decl, sampling, key


def activation_summary(sim_results, k, m, ctot, a, T):
    """Fit the quasi-static hazard model's prefactor f0 to the simulated median slip points (support
    position within its well, trace and retrace pooled), per corrugation group."""
    groups = {}
    for V, U0, r in sim_results:
        ev = r["events"]
        if ev is None:
            continue
        br = groups.setdefault(U0, dict(br=ph.pt_barrier_branch(U0, k, a), V=[], Xmed=[], Fmed=[]))["br"]
        sel = ((ev["seg"] == 1) & (ev["dir"] > 0)) | ((ev["seg"] == 2) & (ev["dir"] < 0))
        # support position relative to the well left (j a); retrace mirrored (U is even in x)
        Xrel = (ev["X"][sel] - ev["j"][sel] * a) * ev["dir"][sel]
        if len(Xrel) < 5:
            continue
        Xm = float(np.median(Xrel))
        g = groups[U0]
        g["V"].append(V)
        g["Xmed"].append(Xm)
        g["Fmed"].append(float(np.interp(Xm, br["X"], br["F"])))
    res = {}
    fits = []
    for U0, g in groups.items():
        br = g["br"]
        if not g["V"]:
            continue
        grid = np.linspace(4, 16, 481)
        best = None
        for lg in grid:
            rr = 0.0
            for V, Xm in zip(g["V"], g["Xmed"]):
                rate = 10 ** lg * np.exp(-br["dE"] / (KB * T))
                H = np.concatenate([[0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(br["X"]))]) / V
                Xmod = br["X"][-1] if H[-1] < math.log(2) else float(np.interp(math.log(2), H, br["X"]))
                rr += (Xmod - Xm) ** 2
            if best is None or rr < best[0]:
                best = (rr, lg)
        per_speed = []
        for V, Xm in zip(g["V"], g["Xmed"]):
            bb = None
            for lg in grid:
                rate = 10 ** lg * np.exp(-br["dE"] / (KB * T))
                H = np.concatenate([[0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(br["X"]))]) / V
                Xmod = br["X"][-1] if H[-1] < math.log(2) else float(np.interp(math.log(2), H, br["X"]))
                if bb is None or abs(Xmod - Xm) < bb[0]:
                    bb = (abs(Xmod - Xm), lg)
            per_speed.append(bb[1])
        fits.append(dict(U0_J=U0, speeds=g["V"], log10_f0_per_speed=per_speed, median_slip_X_in_well_m=g["Xmed"],
                         spinodal_X_m=br["Xc"], median_slip_force_qs_N=g["Fmed"], log10_f0=best[1],
                         rms_misfit_m=math.sqrt(best[0] / len(g["V"])),
                         log10_kramers_f0_at_median=math.log10(ph.kramers_f0(br, g["Fmed"][0], m, ctot))))
    if not fits:
        return None
    res["groups"] = fits
    res["log10_f0_fit"] = float(np.mean([f["log10_f0"] for f in fits]))
    res["definition"] = ("hazard f0 exp(-dE(X)/kB T) on the quasi-static PT barrier dE, X = V t; f0 fitted "
                         "so that the model's median slip point matches the simulated slips' median")
    return res


def topo_fn(kind, L, rng, line):
    if kind in ("none", "flat", "flatnoise"):
        return (lambda x: np.zeros_like(np.asarray(x, float))), 0.0
    if kind == "grating":
        # trapezoid grating, 12 nm high, 600 nm pitch, flanks 200 nm wide (max slope 0.09), shifted per line
        pitch, hgt, flank = 600e-9, 12e-9, 200e-9
        shift = line * 137e-9

        def h(x):
            u = np.mod(np.asarray(x, float) + shift, pitch)
            top = pitch / 2 - flank
            y = np.where(u < flank, u / flank,
                         np.where(u < flank + top, 1.0,
                                  np.where(u < 2 * flank + top, 1 - (u - flank - top) / flank, 0.0)))
            # round the corners a little (tip radius): smoothstep of the ramps
            return hgt * (3 * y ** 2 - 2 * y ** 3)
        return h, hgt * 1.5 / flank
    if kind == "blend":
        # islands 1.5 nm above the matrix, smooth edges (erf, 400 nm wide), random per line
        cents = np.sort(rng.uniform(0, L, 4))
        widths = rng.uniform(0.5e-6, 1.0e-6, 4)
        hgt, edge = 1.5e-9, 400e-9
        from scipy.special import erf

        def zeta(x):
            x = np.asarray(x, float)
            z = np.zeros_like(x)
            for c0, w in zip(cents, widths):
                z = np.maximum(z, 0.25 * (1 + erf((x - (c0 - w / 2)) / (edge / 4))) *
                               (1 + erf(((c0 + w / 2) - x) / (edge / 4))))
            return z
        return (lambda x: hgt * zeta(x)), zeta
    raise ValueError(kind)


def gen_loop(c, rng, seed):
    k, m, cx = lever_params(c)
    a, T = c["a"], c["T"]
    eff = c["effect"]
    rows = dict(scan=[], pos=[], F=[], t=[], h=[])
    scans_tbl = []
    per_scan = []
    t_clock = 0.0
    id0 = c["scan_ids"]
    loads = [s[1] for s in c["scans"]]
    Nref = float(np.mean(loads))
    max_slope_term = 0.0
    for si, (V, N) in enumerate(c["scans"]):
        res = topo_fn(c["topo"], c["L"], rng, si)
        h = res[0]
        if c["topo"] == "blend":
            zeta = res[1]
            beta = c["contrast"] if eff == "friction-contrast" else 0.0
            mu_fn = lambda x, z=zeta, b=beta: c["mu"] * (1 + b * z(x))
            hfn = h
        else:
            mu_fn = lambda x: np.full_like(np.asarray(x, float), c["mu"])
            hfn = h
        Nad = c["n_adh"] if eff == "adhesion-load" else 0.0
        # null loops: friction independent of load (all at one load here anyway)
        p = dict(k_x=k, k_c=c["kc"], N=N, N_adh=Nad, a=a, T=T, c=cx, saw=0.3, jitter=0.08)
        r = ph.friction_loop_scan(p, 0.0, c["L"], c["n"], V, hfn, mu_fn, rng)
        xx = np.linspace(0, c["L"], 4001)
        slope = np.gradient(hfn(xx), xx)
        max_slope_term = max(max_slope_term, float(np.max(np.abs(slope))) * N)
        dur = 2 * c["L"] / V
        rows["scan"].append(np.full(len(r["mean"]), si + id0))
        rows["pos"].append(r["centre"])
        rows["F"].append(r["mean"])
        rows["t"].append(r["t_end"] - 0.5 * r["tau_s"] + t_clock)
        hh = r["height"]
        if c["topo"] == "flatnoise":
            hh = hh + 1e-9 * 0.6  # a flat terrace at some height
        rows["h"].append(hh + 0.05e-9 * rng.standard_normal(len(hh)) - 20e-9 * (si % 2))
        per_scan.append(dict(id=si + id0, speed=V, load=N, F_k_trace_median_N=r["Fk_trace"],
                             F_k_retrace_median_N=r["Fk_retrace"],
                             friction_half_loop_N=0.5 * (r["Fk_trace"] - r["Fk_retrace"]),
                             t_start_s=t_clock, duration_s=dur, sample_interval_s=r["tau_s"],
                             periods_per_sample=c["L"] / c["n"] / a))
        scans_tbl.append((si + id0, V, N))
        t_clock += dur + 0.3
    Fall = np.concatenate(rows["F"])
    tall = np.concatenate(rows["t"])
    info = {}
    if eff == "force-offset-drift":
        Tlong = max(s["duration_s"] for s in per_scan)
        rate = c["drift"] / Tlong
        Fall = Fall + c["offset"] + rate * tall
    sig = c["noise"]
    Fall = Fall + detector_noise(rng, len(Fall), sig, None)
    noise_tbl = []
    if c.get("noise_decl", True):
        noise_tbl.append(("force", f"{sig:.4e}"))
    cols = [np.concatenate(rows["scan"]), np.concatenate(rows["pos"]), Fall]
    names = ["scan", "position_m", "lateral_force_N"]
    if c.get("time"):
        cols.append(tall)
        names.append("time_s")
    if c["topo"] != "none":
        cols.append(np.concatenate(rows["h"]))
        names.append("height_m")
    key = dict(effect=eff, regime="mesoscale friction loop", sampling="interval-mean",
               model="quasi-static spring-block (k_x in series with contact stiffness k_c), Coulomb "
                     "friction mu (N + N_adh) with Ogletree slope balance, atomic sawtooth averaged",
               lattice_m=a, periods_per_sample=c["L"] / c["n"] / a, mu=c["mu"], k_c=c["kc"],
               temperature_K=T, temperature_declared=True, k_x=k, m_x=m, f_res_Hz=c["f"], Q_x=c["Q"],
               c_x=cx, damping_declared=c.get("decl_damp"), noise_detector_N=sig,
               noise_declared_N=(sig if c.get("noise_decl", True) else None), time_column=c.get("time"),
               topography=c["topo"], N_ref_mean_load_N=Nref, scans=per_scan, seed=seed,
               max_abs_N_slope_N=max_slope_term)
    if eff == "adhesion-load":
        key["n_adh"] = c["n_adh"]
        key["adhesion_definition"] = "F_k(N) = mu (N + n_adh) (Derjaguin)"
    elif eff == "force-offset-drift":
        key["offset"] = c["offset"]
        key["drift"] = c["drift"]
        key["drift_rate_N_per_s"] = c["drift"] / max(s["duration_s"] for s in per_scan)
        key["offset_reference"] = ("offset = added force at time_s = 0; on a loop it is degenerate with the "
                                   "loop baseline's zero; drift = change over the longest scan's duration")
    elif eff == "surface-slope":
        key["c_slope"] = 1.0
        key["g"] = 1.0
        key["slope_definition"] = ("recorded F = N (t + d mu)/(1 - d mu t), t = dh/dx of the true surface "
                                   "under the tip, lateral force correctly calibrated (g = 1): the load "
                                   "component enters with coefficient 1")
        key["max_slope"] = max_slope_term / max(loads)
    elif eff == "friction-contrast":
        key["contrast"] = c["contrast"]
        key["friction_ratio_high_to_low"] = 1 + c["contrast"]
        key["contrast_definition"] = ("mu(x) = mu (1 + contrast zeta(x)), zeta the true relief normalised "
                                      "0 (matrix) .. 1 (islands 1.5 nm high)")
        key["secondary"] = ("the islands' edges carry the physical load-on-slope term too "
                            "(max |N t| = %.1f pN), not the hidden cause" % (max_slope_term * 1e12))
    return cols, names, scans_tbl, noise_tbl, T, "interval-mean", key


def main():
    out = sys.argv[1]
    t0 = time.time()
    c0 = time.process_time()
    os.makedirs(os.path.join(out, "cases"), exist_ok=True)
    master = np.random.default_rng(SEED)
    allc = [("A", c) for c in ATOMIC] + [("L", c) for c in LOOPS]
    perm = master.permutation(len(allc))
    keys = []
    for idx, (kind, c) in enumerate(allc):
        cid = "g%02d" % (perm[idx] + 1)
        seed = SEED + 7919 * (idx + 1)
        rng = np.random.default_rng(seed)
        tt = time.time()
        if kind == "A":
            cols, names, scans_tbl, noise_tbl, T_decl, sampling, key = gen_atomic(c, rng, seed)
            lattice = c["a"]
        else:
            cols, names, scans_tbl, noise_tbl, T_decl, sampling, key = gen_loop(c, rng, seed)
            lattice = c["a"]
        k, m, cx = lever_params(c)
        write_csv(os.path.join(out, "cases", cid + ".csv"), cols, names)
        write_toml(os.path.join(out, "cases", cid + ".toml"), cid + ".csv", c, k, m, cx, scans_tbl,
                   lattice, sampling, noise_tbl, T_decl)
        key = dict(id=cid, name=c["name"], **key)
        keys.append(key)
        print(f"{cid} {c['name']:8s} {key['effect']:22s} {len(cols[0]):6d} rows  {time.time()-tt:6.1f} s",
              flush=True)
    keys.sort(key=lambda d: d["id"])
    with open(os.path.join(out, "KEY.json"), "w") as fh:
        json.dump(dict(generator="benchmarks/blind_friction2/gen.py", seed=SEED, cases=keys), fh, indent=1,
                  default=float)
    print(f"wall {time.time()-t0:.1f} s, cpu {time.process_time()-c0:.1f} s")


if __name__ == "__main__":
    main()
