"""Blind test-data generator for `probedyn diagnose` friction records (FFM stick-slip and friction loops).

Written blind in session 46 from the docs only (docs/diagnose.md sections 1 and 3, the example
measurement files, and the thesis' PT chapter); no probedyn code, tests or benchmarks were read or
imported.  Usage:  python gen.py OUT_DIR   (fixed seeds, reproducible).

What it models (see physics.py):
  * atomic stick-slip: a Prandtl-Tomlinson tip with inertia and thermal Langevin noise,
    m x'' = -U'(x) + k (X - x) + c (X' - x') - gamma x' + xi,  U = -(U0/2) cos(2 pi x/a),
    eta = 2 pi^2 U0/(k a^2), integrated by BAOAB; recorded force k (X - x) as interval means
    (or centre-time point samples) at <= a/16 spacing, trace and retrace (a few trace-only);
    corrugation proportional to the load, U0 = u_N (N + N_adh) (N_adh = 0 unless hidden);
  * 2-D square lattice scanned at an angle theta (hidden lattice-misalignment);
  * mesoscale friction loops: a Coulomb spring-block (k_x lever, kinetic friction
    F_k = mu (N + N_adh)) recorded as interval means over >= 20 lattice periods;
  * instrument effects after the physics: calibration factor g, detector offset + linear drift
    on the record's one clock, scanner bow X_true = X_rec + bow (X_rec-X0)(X1-X_rec)/(X1-X0),
    and white detector noise.
Writes OUT_DIR/cases/fNN.csv + .toml, OUT_DIR/KEY.json, OUT_DIR/checks.txt.
"""
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import physics as ph  # noqa: E402

KB = ph.KB
SEED = 4646


def U0_from_eta(eta, k, a):
    return eta * k * a * a / (2 * math.pi ** 2)


# ----------------------------------------------------------------------------------------------
# case table (hand-chosen physics; ids shuffled with a fixed seed below)

def atomic(**kw):
    d = dict(kind="atomic", T=1.0, k=1.0, a=0.4e-9, eta=4.0, fres=100e3, Q=1.0, gamma=0.0,
             n_adh=0.0, offset=0.0, drift_over=0.0, g=1.0, bow_dev=0.0, theta_deg=0.0, ky_ratio=15.0,
             det=5e-12, declare_noise=True, sampling="interval-mean", spp=24, n_per=10,
             both=True, scans=[(50e-9, 5e-9), (500e-9, 5e-9), (50e-9, 10e-9)], effect="none")
    d.update(kw)
    return d


def loop(**kw):
    d = dict(kind="loop", k=5.0, a=0.4e-9, mu=0.15, n_adh=0.0, offset=0.0, drift_over=0.0, g=1.0,
             det=30e-12, declare_noise=True, npix=128, line=5e-6, T=295.0,
             scans=[(5e-6, 20e-9)] * 3, effect="none")
    d.update(kw)
    return d


CASES = [
    # --- thermal activation (room temperature; f0 is what the Langevin dynamics gives, measured)
    atomic(effect="thermal-activation", T=300.0, k=2.0, a=0.40e-9, eta=5.0, fres=80e3, Q=1.0,
           det=10e-12, spp=20, n_per=10, scans=[(3e-9, 5e-9), (30e-9, 5e-9)]),
    atomic(effect="thermal-activation", T=300.0, k=4.0, a=0.45e-9, eta=6.0, fres=150e3, Q=2.0,
           det=12e-12, spp=20, n_per=9, scans=[(4e-9, 8e-9), (40e-9, 8e-9), (4e-9, 10e-9)]),
    atomic(effect="thermal-activation", T=50.0, k=1.2, a=0.50e-9, eta=7.0, fres=40e3, Q=0.7,
           det=8e-12, spp=24, n_per=8, scans=[(2e-9, 6e-9), (20e-9, 6e-9)]),
    # --- viscous tip-substrate friction
    atomic(effect="viscous-friction", T=1.0, k=1.5, a=0.35e-9, eta=4.0, fres=100e3, gamma_frac=0.15,
           det=5e-12, spp=24, n_per=10, scans=[(0.1e-6, 5e-9), (1e-6, 5e-9), (10e-6, 5e-9)]),
    atomic(effect="viscous-friction", T=1.5, k=3.0, a=0.30e-9, eta=3.0, fres=120e3, Q=1.5, gamma_frac=0.05,
           det=4e-12, spp=20, n_per=12, scans=[(0.02e-6, 4e-9), (0.2e-6, 4e-9), (2e-6, 4e-9)]),
    # --- adhesion offset in the corrugation's load dependence
    atomic(effect="adhesion-load", T=0.5, k=1.0, a=0.40e-9, eta=2.5, fres=90e3, n_adh=3e-9,
           det=5e-12, spp=24, n_per=10, scans=[(50e-9, 2e-9), (50e-9, 5e-9), (50e-9, 10e-9)]),
    atomic(effect="adhesion-load", T=1.5, k=2.5, a=0.30e-9, eta=3.0, fres=110e3, Q=1.2, n_adh=1.5e-9,
           det=6e-12, spp=20, n_per=12,
           scans=[(30e-9, 4e-9), (30e-9, 8e-9), (30e-9, 12e-9), (300e-9, 8e-9)]),
    loop(effect="adhesion-load", k=8.0, mu=0.15, n_adh=8e-9, det=40e-12,
         scans=[(5e-6, 10e-9), (5e-6, 20e-9), (5e-6, 40e-9)]),
    # --- detector offset and drift
    atomic(effect="force-offset-drift", T=1.0, k=1.8, a=0.45e-9, eta=5.0, fres=100e3, offset=60e-12,
           drift_over=40e-12, det=6e-12, spp=20, n_per=10,
           scans=[(40e-9, 6e-9), (400e-9, 6e-9), (40e-9, 9e-9)]),
    loop(effect="force-offset-drift", k=3.0, mu=0.2, offset=-0.4e-9, drift_over=0.25e-9, det=30e-12,
         scans=[(4e-6, 15e-9), (4e-6, 15e-9), (4e-6, 15e-9)]),
    # --- lateral calibration factor
    atomic(effect="force-calibration", T=1.5, k=1.0, a=0.40e-9, eta=4.5, fres=100e3, g=1.25,
           det=5e-12, spp=24, n_per=10, scans=[(30e-9, 5e-9), (300e-9, 5e-9)]),
    atomic(effect="force-calibration", T=0.5, k=3.5, a=0.28e-9, eta=3.0, fres=150e3, Q=1.3, g=0.90,
           det=5e-12, spp=20, n_per=12, scans=[(40e-9, 6e-9), (400e-9, 6e-9), (40e-9, 12e-9)]),
    # --- scanner bow (max deviation of the support path as a fraction of a period)
    atomic(effect="scanner-nonlinearity", T=1.2, k=1.2, a=0.40e-9, eta=4.0, fres=100e3, bow_dev=0.25,
           det=5e-12, spp=24, n_per=12, scans=[(50e-9, 5e-9), (500e-9, 5e-9)]),
    atomic(effect="scanner-nonlinearity", T=2.0, k=2.0, a=0.36e-9, eta=4.5, fres=90e3, bow_dev=-0.10,
           det=5e-12, spp=20, n_per=14, scans=[(30e-9, 6e-9), (300e-9, 6e-9), (30e-9, 10e-9)]),
    # --- 2-D lattice scanned at an angle
    atomic(effect="lattice-misalignment", T=1.5, k=1.5, a=0.40e-9, eta=4.0, fres=100e3, theta_deg=15.0,
           det=5e-12, spp=24, n_per=12, scans=[(40e-9, 5e-9), (400e-9, 5e-9)]),
    atomic(effect="lattice-misalignment", T=0.5, k=2.5, a=0.30e-9, eta=5.0, fres=120e3, theta_deg=8.0,
           det=5e-12, spp=20, n_per=14, scans=[(30e-9, 6e-9), (300e-9, 6e-9), (30e-9, 9e-9)]),
    # --- nulls
    atomic(T=1.5, k=1.0, a=0.40e-9, eta=3.0, fres=100e3, det=5e-12, spp=24, n_per=10,
           scans=[(30e-9, 5e-9), (300e-9, 5e-9), (30e-9, 10e-9)]),
    atomic(T=1.5, k=2.5, a=0.30e-9, eta=6.0, fres=130e3, Q=1.5, det=6e-12, sampling="point", spp=20,
           n_per=12, scans=[(20e-9, 8e-9), (200e-9, 8e-9)]),
    atomic(T=0.3, k=0.6, a=0.50e-9, eta=2.2, fres=60e3, det=3e-12, declare_noise=False, spp=24, n_per=9,
           scans=[(20e-9, 4e-9), (200e-9, 4e-9), (20e-9, 8e-9)]),
    atomic(T=2.0, k=4.5, a=0.25e-9, eta=7.5, fres=200e3, det=8e-12, spp=16, n_per=14, both=False,
           scans=[(50e-9, 10e-9), (500e-9, 10e-9)]),
    atomic(T=0.5, k=1.5, a=0.45e-9, eta=4.0, fres=100e3, det=5e-12, spp=20, n_per=10,
           scans=[(40e-9, 5e-9), (400e-9, 5e-9), (40e-9, 10e-9), (400e-9, 10e-9)]),
    atomic(T=1.0, k=3.0, a=0.35e-9, eta=2.5, fres=100e3, det=4e-12, declare_noise=False, sampling="point",
           spp=20, n_per=12, scans=[(50e-9, 6e-9), (500e-9, 6e-9)]),
    atomic(T=2.0, k=0.9, a=0.42e-9, eta=8.0, fres=70e3, Q=3.0, det=6e-12, spp=24, n_per=10,
           scans=[(30e-9, 6e-9), (300e-9, 6e-9)]),
    loop(k=6.0, mu=0.12, det=30e-12, scans=[(5e-6, 15e-9), (5e-6, 30e-9), (5e-6, 15e-9)]),
]


# ----------------------------------------------------------------------------------------------

def peak_mean(f, spp_true):
    """mean of per-period maxima of a clean trace force (skipping the first 2 periods)."""
    n = int(round(spp_true))
    f = f[2 * n:]
    m = len(f) // n
    if m < 1:
        return float("nan")
    return float(np.mean(f[:m * n].reshape(m, n).max(axis=1)))


def f0_mle(events, U0, k, a, kT, V, x_ranges):
    """ML attempt frequency of the hazard f0 exp(-dE(X)/kT) on the quasi-static forward barrier,
    from simulated slip events. events: list of (X_slip_rel, X_entry_rel) per stick, in trace-like
    coordinates (forward motion)."""
    Fs, Xs = ph.critical_force(U0, k, a)
    grid = np.linspace(-Xs, Xs, 6001)
    dE, _, _ = ph.forward_barrier(grid, U0, k, a)
    w = np.exp(-np.nan_to_num(dE, nan=np.inf) / kT)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(grid))])
    expo = 0.0
    ns = 0
    for xs, xe, v in events:
        if xs > Xs or xs < -Xs:
            continue
        xe = max(xe, -Xs)
        expo += (np.interp(xs, grid, cum) - np.interp(xe, grid, cum)) / v
        ns += 1
    return ns / expo if expo > 0 else float("nan"), ns


def sim_atomic(c, rng, seed, T_override=None):
    k, a, m = c["k"], c["a"], c["m"]
    kT = KB * (c["T"] if T_override is None else T_override)
    cx = math.sqrt(k * m) / c["Q"]
    gam = c["gamma"]
    twod = c["theta_deg"] != 0.0
    ph.seed_rng(seed)
    d = c["a_decl"] / c["spp"]
    ns = c["spp"] * c["n_per"]
    L = ns * d
    out = []
    t_clock = 0.0
    steps = 0
    events_fw = []
    Nref = c["scans"][0][1]
    for si, (V, N) in enumerate(c["scans"]):
        U0 = c["uN"] * (N + c["n_adh"])
        eta = ph.eta_of(U0, k, a)
        wmax = math.sqrt(k * (1 + eta) / m)
        if twod:
            wmax = math.sqrt((c["ky_ratio"] * k + eta * k) / m)
        dt_max = 0.1 / wmax
        n_sub = max(4, int(math.ceil(d / V / dt_max)))
        dt = d / V / n_sub
        X0 = c["X0"][si]
        X1 = X0 + L
        bow = c["bow"]
        # start: relax at rest at X0 + 1.5 a, then an unrecorded retrace-like run-in to X0
        pre = 1.5 * a
        npre = int(round(pre / d))
        Xs = X0 + npre * d
        tmpf = np.zeros(max(npre, 1))
        tmpt = np.zeros(max(npre, 1))
        evX = np.zeros(4000)
        evt = np.zeros(4000)
        evn = np.zeros(4000, np.int64)
        if twod:
            th = math.radians(c["theta_deg"])
            ky = c["ky_ratio"] * k
            cy = math.sqrt(ky * m) / c["Q"]
            x, y, vx, vy = Xs, c["Y0"][si], 0.0, 0.0
            x, y, vx, vy, t = ph.run_2d(x, y, vx, vy, 0.0, Xs, c["Y0"][si], 0.0, V, 1, 20000, dt, m, k, ky, cx,
                                        cy, U0, a, th, c["phx"], c["phy"], kT, 0, tmpf[:1], tmpt[:1])
            x, y, vx, vy, t = ph.run_2d(x, y, vx, vy, 0.0, Xs, c["Y0"][si], -1.0, V, npre, n_sub, dt, m, k, ky,
                                        cx, cy, U0, a, th, c["phx"], c["phy"], kT, 0, tmpf, tmpt)
        else:
            x, v = Xs, 0.0
            nw = int(math.floor(x / a + 0.5))
            x, v, t, ne, nw = ph.run_1d(x, v, 0.0, Xs, 0.0, V, 1, 20000, dt, m, k, cx, gam, U0, a, kT, bow,
                                        X0, X1, 0, tmpf[:1], tmpt[:1], evX, evt, evn, nw)
            x, v, t, ne, nw = ph.run_1d(x, v, 0.0, Xs, -1.0, V, npre, n_sub, dt, m, k, cx, gam, U0, a, kT, bow,
                                        X0, X1, 0, tmpf, tmpt, evX, evt, evn, nw)
        steps += 20000 + npre * n_sub
        point = 1 if c["sampling"] == "point" else 0
        dirs = [1.0, -1.0] if c["both"] else [1.0]
        for dirn in dirs:
            f = np.zeros(ns)
            tt = np.zeros(ns)
            Xstart = X0 if dirn > 0 else X1
            if twod:
                x, y, vx, vy, t1 = ph.run_2d(x, y, vx, vy, t_clock, Xstart, c["Y0"][si], dirn, V, ns, n_sub, dt,
                                             m, k, ky, cx, cy, U0, a, th, c["phx"], c["phy"], kT, point, f, tt)
            else:
                nw0 = nw
                x, v, t1, ne, nw = ph.run_1d(x, v, t_clock, Xstart, dirn, V, ns, n_sub, dt, m, k, cx, gam, U0, a,
                                             kT, bow, X0, X1, point, f, tt, evX, evt, evn, nw)
                # stick episodes in forward coordinates for the f0 estimate
                ne = min(ne, len(evX))
                # merge well entries closer than 50/omega_0 into one (multi-well) slip
                tmerge = 50.0 * math.sqrt(m / k)
                keep = []
                for e in range(ne):
                    if keep and evt[e] - evt[keep[-1][0]] < tmerge and (evn[e] - keep[-1][1]) * dirn > 0:
                        keep[-1] = (keep[-1][0], evn[e])
                    else:
                        keep.append((e, evn[e]))
                evX_m = np.array([evX[e] for e, _ in keep])
                evn_m = np.array([n for _, n in keep], np.int64)
                ne = len(keep)
                prev_X = None
                prev_n = nw0
                Xtrue0 = Xstart
                for e in range(ne):
                    n_new = evn_m[e]
                    if (n_new - prev_n) * dirn <= 0:       # thermal back-hop: restart exposure
                        prev_X, prev_n = evX_m[e], n_new
                        continue
                    xs_rel = dirn * (evX_m[e] - prev_n * a)
                    xe_rel = dirn * ((prev_X if prev_X is not None else Xtrue0) - prev_n * a)
                    if prev_X is not None:
                        events_fw.append((xs_rel, xe_rel, V, si))
                    prev_X, prev_n = evX_m[e], n_new
            steps += ns * n_sub
            pos = Xstart + dirn * (np.arange(ns) + 0.5) * d
            out.append(dict(scan=si, V=V, N=N, U0=U0, eta=eta, dirn=dirn, pos=pos, f=f.copy(), t=tt.copy(),
                            dt=dt, n_sub=n_sub))
            t_clock = t1
        t_clock += 0.2 * (2 * L / V) + 0.05          # pause before the next line
    return out, steps, events_fw


def sim_loop(c):
    """Coulomb spring-block: force k(X - x) clamped to +-F_k; interval means over pixels."""
    out = []
    t_clock = 0.0
    npix = c["npix"]
    d = c["line"] / npix
    nsub = 200
    for si, (V, N) in enumerate(c["scans"]):
        Fk = c["mu"] * (N + c["n_adh"])
        F = -Fk                                  # coming from a retrace
        for dirn in (1.0, -1.0):
            Xstart = 0.0 if dirn > 0 else c["line"]
            f = np.zeros(npix)
            tt = np.zeros(npix)
            dX = d / nsub
            for j in range(npix):
                acc = 0.0
                for i in range(nsub):
                    F = min(max(F + c["k"] * dirn * dX, -Fk), Fk)
                    acc += F
                f[j] = acc / nsub
                tt[j] = t_clock + (j + 0.5) * d / V
            pos = Xstart + dirn * (np.arange(npix) + 0.5) * d
            out.append(dict(scan=si, V=V, N=N, dirn=dirn, pos=pos, f=f, t=tt, Fk=Fk))
            t_clock += npix * d / V + 0.01
        t_clock += 0.05
    return out


def fmt(x):
    return f"{x:.6g}"


def main(outdir):
    t_start = time.time()
    rng = np.random.default_rng(SEED)
    os.makedirs(os.path.join(outdir, "cases"), exist_ok=True)
    order = rng.permutation(len(CASES))
    key = {"cases": [], "generator": "benchmarks/blind_friction/gen.py (session 46, blind)", "seed": SEED}
    checks = []
    total_steps = 0
    for idx, ci in enumerate(order):
        cid = f"f{idx + 1:02d}"
        c = dict(CASES[ci])
        crng = np.random.default_rng(SEED + 100 * ci)
        eff = c["effect"]
        truth = {"id": cid, "effect": eff}
        true = {}
        if c["kind"] == "atomic":
            k, a = c["k"], c["a"]
            c["m"] = k / (2 * math.pi * c["fres"]) ** 2
            Nref = c["scans"][0][1]
            U0ref = U0_from_eta(c["eta"], k, a)
            c["uN"] = U0ref / (Nref + c["n_adh"])
            if eff == "lattice-misalignment":
                c["a_decl"] = a
            else:
                c["a_decl"] = float(f"{a * (1 + crng.uniform(-0.01, 0.01)):.4g}")
            c["X0"] = [float(crng.uniform(0, a)) + 2e-9 for _ in c["scans"]]
            c["Y0"] = [float(crng.uniform(0, a)) for _ in c["scans"]]
            c["phx"] = float(crng.uniform(0, 2 * math.pi))
            c["phy"] = float(crng.uniform(0, 2 * math.pi))
            L = c["a_decl"] / c["spp"] * c["spp"] * c["n_per"]
            c["bow"] = 4 * c["bow_dev"] * a / L if c["bow_dev"] else 0.0
            Fstar, _ = ph.critical_force(U0ref, k, a)
            if eff == "viscous-friction":
                c["gamma"] = c["gamma_frac"] * Fstar / max(s[0] for s in c["scans"])
            seed = int(SEED + 7 * ci)
            res, steps, evs = sim_atomic(c, crng, seed)
            total_steps += steps
            # athermal twin: size of the thermal effect on the mean trace peak force
            twin = None
            if c["T"] > 0 and c["theta_deg"] == 0.0:
                twin, st2, _ = sim_atomic(c, crng, seed, T_override=0.0)
                total_steps += st2
            spp_true = c["spp"] * a / c["a_decl"]
            if c["theta_deg"]:
                spp_true = c["spp"] * a / math.cos(math.radians(c["theta_deg"])) / c["a_decl"]
            pk = []
            for r_i, r in enumerate(res):
                if r["dirn"] > 0:
                    p_th = peak_mean(r["f"], spp_true)
                    p_0 = peak_mean(twin[r_i]["f"], spp_true) if twin else float("nan")
                    pk.append((r["scan"], r["V"], r["N"], p_th, p_0))
            # thermal residual of the interval means: sqrt(2 G kB T / dt_sample)
            G = math.sqrt(k * c["m"]) / c["Q"] + c["gamma"]
            sig_th = []
            for s_i, (V, N) in enumerate(c["scans"]):
                if c["sampling"] == "point":
                    sig_th.append(math.sqrt(k * KB * c["T"]))
                else:
                    dts = c["a_decl"] / c["spp"] / V
                    sig_th.append(math.sqrt(k * KB * c["T"] * min(1.0, 2 * (G / k) / dts)))
            noise_decl = math.sqrt(c["det"] ** 2 + float(np.mean(np.square(sig_th))))
            noise_decl = float(f"{noise_decl:.2g}")
            true.update(k_x=k, m_x=c["m"], Q_x=c["Q"], c_x=math.sqrt(k * c["m"]) / c["Q"], lattice_true=a,
                        lattice_declared=c["a_decl"], U0_ref_J=U0ref, eta_ref=c["eta"], load_ref=Nref,
                        U0_per_N=c["uN"], temperature=c["T"], gamma_true=c["gamma"], n_adh_true=c["n_adh"],
                        detector_noise=c["det"], thermal_residual_noise_per_scan=sig_th,
                        critical_force_ref=Fstar, sampling=c["sampling"], both_directions=c["both"],
                        scans=[dict(id=i, speed=s[0], load=s[1], U0_J=c["uN"] * (s[1] + c["n_adh"]),
                                    eta=ph.eta_of(c["uN"] * (s[1] + c["n_adh"]), k, a), X0=c["X0"][i])
                               for i, s in enumerate(c["scans"])],
                        trace_peak_mean_vs_athermal=[dict(scan=p[0], speed=p[1], load=p[2], peak_T=p[3],
                                                          peak_T0=p[4],
                                                          rel_shift=(p[3] - p[4]) / p[4] if p[4] == p[4] else None)
                                                     for p in pk])
            if eff == "thermal-activation":
                # effective attempt frequency: ML estimate of the hazard f0 exp(-dE/kT) from the slips
                kT = KB * c["T"]
                f0s = []
                for s_i, (V, N) in enumerate(c["scans"]):
                    U0 = c["uN"] * (N + c["n_adh"])
                    ev = [(e[0], e[1], e[2]) for e in evs if e[3] == s_i]
                    f0, nsl = f0_mle(ev, U0, k, a, kT, V, None)
                    med = float(np.median([e[0] for e in ev])) if ev else float("nan")
                    fk = float(ph.kramers_prefactor(med, U0, k, a, c["m"], G)[0]) if ev else float("nan")
                    f0s.append(dict(scan=s_i, f0_mle=f0, n_slips=nsl, median_slip_Xrel=med,
                                    f0_kramers_at_median=fk,
                                    athermal_slip_Xrel=ph.critical_force(U0, k, a)[1]))
                allev = [(e[0], e[1], e[2]) for e in evs]
                # pooled estimate (loads differ: do per scan and combine by total slips / exposure)
                num = sum(d_["n_slips"] for d_ in f0s)
                den = sum(d_["n_slips"] / d_["f0_mle"] for d_ in f0s if d_["f0_mle"] > 0)
                f0p = num / den
                truth["log10_f0"] = math.log10(f0p)
                truth["temperature"] = c["T"]
                true["f0_per_scan"] = f0s
                checks.append(f"{cid} thermal: pooled ML f0 = {f0p:.3g} Hz (log10 {math.log10(f0p):.2f}); per scan "
                              + "; ".join(f"scan {d_['scan']}: ML {d_['f0_mle']:.3g} Hz from {d_['n_slips']} slips, "
                                          f"Kramers prefactor at median slip {d_['f0_kramers_at_median']:.3g} Hz, "
                                          f"median slip Xrel {d_['median_slip_Xrel']*1e12:.1f} pm vs athermal "
                                          f"{d_['athermal_slip_Xrel']*1e12:.1f} pm" for d_ in f0s))
            if eff == "viscous-friction":
                truth["gamma"] = c["gamma"]
                truth["gamma_times_vmax_over_Fstar"] = c["gamma_frac"]
            if eff == "adhesion-load":
                truth["n_adh"] = c["n_adh"]
            if eff == "scanner-nonlinearity":
                truth["bow"] = c["bow"]
                truth["bow_max_deviation_m"] = c["bow"] * L / 4
                truth["bow_max_deviation_periods"] = c["bow_dev"]
                truth["bow_definition"] = "X_true = X_rec + bow (X_rec - X0)(X1 - X_rec)/(X1 - X0), X0..X1 the recorded scan span"
            if eff == "lattice-misalignment":
                truth["theta_deg"] = c["theta_deg"]
                true.update(k_y=c["ky_ratio"] * k, lattice_model="square, U = -(U0/2)[cos(q x') + cos(q y')]",
                            phase_x=c["phx"], phase_y=c["phy"], Y0=c["Y0"])
            rows = res
        else:
            res = sim_loop(c)
            rows = res
            true.update(k_x=c["k"], mu=c["mu"], n_adh_true=c["n_adh"], detector_noise=c["det"],
                        lattice_declared=c["a"], line_length=c["line"], pixels=c["npix"],
                        model="Coulomb spring-block, F_k = mu (N + N_adh)",
                        scans=[dict(id=i, speed=s[0], load=s[1], F_k=c["mu"] * (s[1] + c["n_adh"]))
                               for i, s in enumerate(c["scans"])])
            noise_decl = c["det"]
            if eff == "adhesion-load":
                truth["n_adh"] = c["n_adh"]
            c["a_decl"] = c["a"]
            c["m"] = None
        # instrument: calibration, offset + drift on the one clock, noise
        tmax_scan = max(np.ptp(np.concatenate([r["t"] for r in rows if r["scan"] == s]))
                        for s in range(len(c["scans"])))
        rate = c["drift_over"] / tmax_scan if tmax_scan > 0 else 0.0
        nrng = np.random.default_rng(SEED + 1000 + ci)
        lines = []
        for r in rows:
            frec = c["g"] * r["f"] + c["offset"] + rate * r["t"] + nrng.normal(0, c["det"], len(r["f"]))
            for p, fv, tv in zip(r["pos"], frec, r["t"]):
                lines.append(f"{r['scan']},{fmt(p)},{fmt(fv)},{fmt(tv)}")
        if eff == "force-calibration":
            truth["g"] = c["g"]
        if eff == "force-offset-drift":
            truth["offset"] = c["offset"]
            truth["drift"] = c["drift_over"]
            truth["drift_rate_N_per_s"] = rate
            tall = np.concatenate([r["t"] for r in rows])
            truth["offset_at_record_mid"] = c["offset"] + rate * 0.5 * (tall.min() + tall.max())
            truth["offset_definition"] = ("recorded = g*F + offset + drift_rate * time_s (time_s one clock through "
                                          "the file from ~0); drift = drift_rate x duration of the longest scan")
        truth["true"] = true
        key["cases"].append(truth)
        # files
        with open(os.path.join(outdir, "cases", cid + ".csv"), "w") as fh:
            fh.write(f"# blind synthetic friction record {cid} (session 46 generator)\n")
            fh.write("scan,position_m,lateral_force_N,time_s\n")
            fh.write("\n".join(lines) + "\n")
        tm = ["[measurement]", 'kind = "friction"', f'data = "{cid}.csv"',
              f'sampling = "{c.get("sampling", "interval-mean")}"',
              f'description = "synthetic {"atomic stick-slip" if c["kind"] == "atomic" else "friction loop (image lines)"}, blind set 46"',
              "", "[lever]", f"k_x = {fmt(c['k'])}"]
        if c["kind"] == "atomic":
            tm += [f"m_x = {c['m']:.4g}", f"Q_x = {fmt(c['Q'])}"]
        tm += ["", "[sample]", f"lattice = {c['a_decl']:.4g}", "", "[medium]"]
        if c["kind"] == "loop":
            tm += ['name = "air"']
        tm += [f"temperature = {fmt(c['T'])}", ""]
        if c["declare_noise"]:
            tm += ["[noise]", f"force = {noise_decl:.2g}", ""]
        for i, (V, N) in enumerate(c["scans"]):
            tm += ["[[scans]]", f"id = {i}", f"speed = {V:.6g}", f"load = {N:.6g}", ""]
        with open(os.path.join(outdir, "cases", cid + ".toml"), "w") as fh:
            fh.write("\n".join(tm))
        checks.append(f"{cid} [{eff}] kind={c['kind']} T={c['T']} declared noise="
                      f"{noise_decl if c['declare_noise'] else 'omitted'} "
                      + ("peak shift vs athermal twin: " + ", ".join(
                          f"s{d_['scan']} {100 * d_['rel_shift']:+.2f}%" for d_ in true.get(
                              "trace_peak_mean_vs_athermal", []) if d_['rel_shift'] is not None)))
        print(cid, eff, f"{time.time() - t_start:.1f}s", flush=True)
    with open(os.path.join(outdir, "KEY.json"), "w") as fh:
        json.dump(key, fh, indent=1)
    checks.append(f"total integrator steps {total_steps:.3g}; wall {time.time() - t_start:.1f} s")
    from checks import run_checks  # noqa: E402
    checks = run_checks() + ["", "# per-case"] + checks
    with open(os.path.join(outdir, "checks.txt"), "w") as fh:
        fh.write("\n".join(checks) + "\n")
    print(f"done in {time.time() - t_start:.1f} s")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out")
