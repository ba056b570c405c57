"""Blind thermal-noise PSD generator for `probedyn diagnose` (spectrum records with a known hidden effect).

Written blind in session 46 from the docs only (docs/diagnose.md sections 1 and 3 and the example
measurement files); it neither imports nor reads probedyn's code, tests or benchmarks. All physics is own:

* truth frequencies and mode shapes: a 3D FEM of the true lever (physics.py: 27-node triquadratic hexahedra on a
  graded tensor mesh, Kronecker-product assembly, anisotropic elasticity), mesh level rxyz=(2,1,1.5)
  (residual discretisation error ~2e-5 flapwise, ~5e-5 torsion, see checks.txt);
* hidden effects placed in the true lever's matrices: point mass (consistent, on the top surface centre line),
  thickness / length / modulus change, compliant clamp (normal and tangential Winkler springs per unit area on the
  clamp face), uniform axial prestress (geometric stiffness), <110> cubic silicon (Hopcroft 2010 constants), and a
  different medium (argon instead of air, glycerol-water instead of water, residual gas in a declared vacuum);
* fluid: Sader (1998) hydrodynamic function per flapwise mode (width-averaged mode shape); residual gas in the
  free-molecular regime (Christian-type momentum transfer) on all modes;
* PSD: fluctuation-dissipation per mode (mass-normalised modal coordinate), intrinsic Q per mode, a detector that
  sees u_z (and a little in-plane motion through a tilted beam) at one spot, white + 1/f background, a few narrow
  electronic spurs, chi-square (Gamma) scatter of an N-times averaged periodogram, a relative frequency jitter of
  each line with the declared [noise] frequency_rel (run-to-run reproducibility).

Usage: python gen.py OUT_DIR   (fixed seed; writes OUT_DIR/cases/sNN.{csv,toml}, OUT_DIR/KEY.json, OUT_DIR/checks.txt)
"""
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import physics as ph  # noqa: E402

SEED = 4646
E_SI, NU_SI, RHO_SI = 169e9, 0.28, 2330.0
MESH = (2.0, 1.0, 1.5)
MESH_CHEAP = (1.0, 1.0, 1.0)
FREL = 1e-4
um = 1e-6

# (effect, medium, L, w, t [um], params)
DESIGN = [
    ("none", "vacuum", 225, 40, 3, {}),
    ("point-mass", "vacuum", 160, 35, 4, {"mass_frac": 0.008, "xi": 0.95}),
    ("thickness-error", "vacuum", 125, 30, 4, {"t_ratio": 0.96}),
    ("none", "air", 225, 30, 3, {}),
    ("length-error", "vacuum", 200, 40, 3, {"dL": 4 * um}),
    ("modulus-error", "air", 300, 35, 2, {"e_ratio": 0.94}),
    ("clamp-compliance", "vacuum", 150, 40, 5, {"rot_frac": 0.02}),
    ("none", "vacuum", 350, 35, 2.5, {}),
    ("axial-prestress", "vacuum", 300, 40, 2, {"s_par": 0.15}),
    ("fluid-loading", "vacuum", 250, 35, 2.5, {"gas_p": 60.0}),
    ("none", "water", 200, 40, 2, {}),
    ("crystal-anisotropy", "vacuum", 225, 40, 3, {"a_crystal": 1.0}),
    ("point-mass", "air", 250, 35, 3, {"mass_frac": 0.025, "xi": 0.72}),
    ("none", "air", 130, 35, 4, {}),
    ("thickness-error", "air", 350, 35, 2, {"t_ratio": 1.07}),
    ("length-error", "water", 200, 30, 3, {"dL": -6 * um}),
    ("none", "vacuum", 100, 20, 1.5, {}),
    ("modulus-error", "vacuum", 180, 45, 3, {"e_ratio": 1.05}),
    ("clamp-compliance", "air", 240, 30, 4, {"rot_frac": 0.008}),
    ("axial-prestress", "air", 200, 30, 2, {"s_par": -0.08}),
    ("fluid-loading", "air", 225, 40, 3, {"true_medium": "argon"}),
    ("crystal-anisotropy", "vacuum", 125, 30, 4, {"a_crystal": 1.0}),
    ("fluid-loading", "water", 125, 35, 4, {"true_medium": "glycerol15"}),
    ("none", "water", 125, 30, 4, {}),
    ("none", "air", 400, 50, 2.5, {}),
]


def medium_props(name, T):
    if name == "vacuum":
        return 0.0, 0.0
    if name == "air":
        return ph.air(T)
    if name == "argon":
        return ph.argon(T)
    if name == "water":
        return ph.water(T)
    if name == "glycerol15":   # 15 wt% glycerol in water at 20 C (Cheng 2008 tables)
        return 1034.5, 1.52e-3
    raise ValueError(name)


def build(L, w, t, C, rho, mesh, eff, prm, E_ref):
    kw = {}
    if eff == "point-mass":
        mlever = rho * L * w * t
        kw["point_mass"] = (prm["mass_frac"] * mlever, (prm["xi"] * L, 0.0, t / 2))
    if eff == "clamp-compliance":
        # static end-compliance fraction of the rotation spring: 3E/(k_n L) = rot_frac
        kn = 3 * E_ref / (prm["rot_frac"] * L)
        kt = kn / (2 * (1 + NU_SI))
        kw["clamp"] = (kn, kt)
    if eff == "axial-prestress":
        kw["sigma"] = prm["sigma"]
    return ph.Lever(L, w, t, C, rho, rxyz=mesh, **kw)


def label_modes(fam):
    cnt, out = {}, []
    for a in fam:
        cnt[a] = cnt.get(a, 0) + 1
        out.append((a, cnt[a]))
    return out


def solve_labeled(lv, fmax):
    f, V = lv.solve(fmax)
    lab = label_modes(lv.classify(V))
    return f, V, lab


def make_case(i, design, rng, log):
    eff, med, Lu, wu, tu, prm = design
    prm = dict(prm)
    L, w, t = Lu * um, wu * um, tu * um
    T = float(np.round(rng.uniform(293.0, 299.0), 1))
    Ctrue = ph.c_isotropic(E_SI, NU_SI)
    Cdecl = Ctrue
    Lt, wt, tt = L, w, t
    if eff == "thickness-error":
        tt = t * prm["t_ratio"]
    if eff == "length-error":
        Lt = L + prm["dL"]
    if eff == "modulus-error":
        Ctrue = Ctrue * prm["e_ratio"]
    if eff == "crystal-anisotropy":
        Ctrue = ph.c_silicon_110()
    if eff == "axial-prestress":
        prm["sigma"] = float(prm["s_par"] * E_SI * t**2 / (12 * L**2))
    true_med = prm.get("true_medium", med)
    rho_d, eta_d = medium_props(med, T)
    rho_f, eta_f = medium_props(true_med, T) if true_med != "vacuum" else (0.0, 0.0)
    eb = ph.euler_bernoulli_flap(Lt, wt, tt, E_SI, RHO_SI)
    fmax_solve = 1.25 * max(eb[2], 1.0) if eb[2] < 8e6 else 1.3 * eb[1]
    fmax_solve = max(fmax_solve, 1.3 * eb[1])
    t0 = time.time()
    lv = build(Lt, wt, tt, Ctrue, RHO_SI, MESH, eff, prm, E_SI)
    f, V, lab = solve_labeled(lv, min(fmax_solve, 12e6))
    # effect size at the cheap level: true vs declared lever
    shifts = {}
    if eff != "none":
        lvc = build(Lt, wt, tt, Ctrue, RHO_SI, MESH_CHEAP, eff, prm, E_SI)
        fc, _, labc = solve_labeled(lvc, min(fmax_solve, 12e6))
        lvb = ph.Lever(L, w, t, Cdecl, RHO_SI, rxyz=MESH_CHEAP)
        fb, _, labb = solve_labeled(lvb, min(fmax_solve, 12e6) * 1.1)
        db = dict(zip(labb, fb))
        for l_, f_ in zip(labc, fc):
            if l_ in db:
                shifts["%s%d" % l_] = f_ / db[l_] - 1
    log.append("case s%02d: %s %s %gx%gx%g um, %d dof, solve %.1fs" % (i, eff, med, Lu, wu, tu, lv.K.shape[0],
                                                                     time.time() - t0))
    # ---- band: vacuum sees flap, torsion, lateral (off-axis spot, tilted beam); fluids: centre line, flap only
    fam_f = {l_: f_ for l_, f_ in zip(lab, f)}
    f1 = fam_f[("flap", 1)]
    vac = (med == "vacuum")
    cand = [fam_f[("flap", 2)]]
    if ("flap", 3) in fam_f and fam_f[("flap", 3)] < (6e6 if vac else 3e6):
        cand.append(fam_f[("flap", 3)])
    if vac and ("torsion", 1) in fam_f and fam_f[("torsion", 1)] < 8e6:
        cand.append(fam_f[("torsion", 1)])
    fhi = 1.12 * max(cand)
    flo = 0.1 * f1
    # ---- detector
    if vac:
        spot = np.array([[Lt], [wt / 4], [tt / 2]])
        th = np.deg2rad(8.0)
        U = lv.disp(V, spot)[:, 0, :]
        sig = U[2] * np.cos(th) + U[1] * np.sin(th)
    else:
        spot = np.array([[Lt], [0.0], [tt / 2]])
        th = np.deg2rad(5.0)
        U = lv.disp(V, spot)[:, 0, :]
        sig = U[2] * np.cos(th) + U[0] * np.sin(th)
    # ---- per-mode damping and fluid terms
    kT = ph.KB * T
    modes = []
    gas_c = None
    if eff == "fluid-loading" and vac:
        p = prm["gas_p"]
        M_air = 0.0289647
        rho_g = p * M_air / (ph.R_GAS * T)
        vbar = np.sqrt(8 * ph.R_GAS * T / (np.pi * M_air))
        Cg = lv.gas_damping_matrix(rho_g * vbar, rho_g * vbar / 4)
        gas_c = np.einsum('in,in->n', V, Cg @ V)
        rho_f, eta_f = rho_g, 1.83e-5
        prm.update(rho_gas=rho_g, mean_free_path_m=float(ph.KB * T / (np.sqrt(2) * np.pi * (3.7e-10)**2 * p)))
    xq, wq, W = lv.width_avg_w(V)
    J = (W**2 * wq[:, None]).sum(0)
    for n, (l_, fn) in enumerate(zip(lab, f)):
        if fn > fhi * 1.3:
            continue
        fam, order = l_
        if fam == "axial":
            continue
        if not vac and fam != "flap":
            continue  # centre-line spot: torsion/lateral/axial give no signal by symmetry
        jit = rng.normal(0, FREL)
        wn = 2 * np.pi * fn * (1 + jit)
        Qint = float(10 ** rng.uniform(3.7, 4.7))
        modes.append(dict(family=fam, order=order, f_solid=fn * (1 + jit), f_model=fn, jitter=jit, Qint=Qint,
                          wn=wn, s=sig[n], J=J[n], gas=(gas_c[n] if gas_c is not None else 0.0)))
    b = wt
    use_fluid = (true_med not in ("vacuum",)) and not vac

    def mode_psd(md, fr):
        om = 2 * np.pi * fr
        c = md["wn"] / md["Qint"] + md["gas"]
        meff = 1.0
        if use_fluid:
            G = ph.gamma_rect(om, b, rho_f, eta_f)
            a = np.pi / 4 * rho_f * b**2 * md["J"]
            meff = 1 + a * G.real
            c = c + a * om * G.imag
        D = (md["wn"]**2 - om**2 * meff)**2 + (om * c)**2
        return 4 * kT * md["s"]**2 * c / D

    # loaded resonance and Q per mode
    for md in modes:
        if use_fluid:
            from scipy.optimize import brentq
            a = np.pi / 4 * rho_f * b**2 * md["J"]
            g = lambda om: md["wn"]**2 - om**2 * (1 + a * ph.gamma_rect(om, b, rho_f, eta_f).real)
            om0 = brentq(g, md["wn"] * 0.05, md["wn"])
            G = ph.gamma_rect(om0, b, rho_f, eta_f)
            md["f0"] = om0 / (2 * np.pi)
            md["Q"] = om0 * (1 + a * G.real) / (md["wn"] / md["Qint"] + a * om0 * G.imag)
            ff = np.linspace(0.3, 1.5, 6001) * md["f0"]
            md["f_peak"] = float(ff[np.argmax(mode_psd(md, ff))])
        else:
            md["f0"] = md["wn"] / (2 * np.pi)
            md["Q"] = md["wn"] / (md["wn"] / md["Qint"] + md["gas"])
            md["f_peak"] = md["f0"] * np.sqrt(max(1 - 1 / (2 * md["Q"]**2), 0))
        md["peak"] = float(mode_psd(md, np.array([md["f_peak"]]))[0])
        if eff == "fluid-loading":   # what the declared medium would give (effect size)
            if vac:
                md["f0_decl"], md["Q_decl"] = md["f0"], md["Qint"]
            else:
                from scipy.optimize import brentq
                a = np.pi / 4 * rho_d * b**2 * md["J"]
                g = lambda om: md["wn"]**2 - om**2 * (1 + a * ph.gamma_rect(om, b, rho_d, eta_d).real)
                om0 = brentq(g, md["wn"] * 0.05, md["wn"])
                G = ph.gamma_rect(om0, b, rho_d, eta_d)
                md["f0_decl"] = om0 / (2 * np.pi)
                md["Q_decl"] = om0 * (1 + a * G.real) / (md["wn"] / md["Qint"] + a * om0 * G.imag)
    inband = [m for m in modes if flo < m["f0"] < fhi]
    # ---- background level from the weakest line we want visible
    want = [m for m in inband if (m["family"], m["order"]) in (("flap", 2), ("torsion", 1))]
    Sw = min(m["peak"] for m in want) / rng.uniform(30, 300) if vac else \
        min(m["peak"] for m in want) / rng.uniform(20, 120)
    fc = rng.uniform(0.2, 1.0) * f1
    # ---- frequency grid: coarse uniform + fine windows around narrow lines
    Nc = 12000
    grid = np.linspace(flo, fhi, Nc)
    dfc = grid[1] - grid[0]
    wins = []
    for m in inband:
        lw = m["f0"] / m["Q"]
        if lw < 10 * dfc:
            wins.append((m["f0"] - 15 * lw, m["f0"] + 15 * lw, lw / 5))
    keep = np.ones(Nc, bool)
    fine = []
    for a0, a1, d in wins:
        keep &= ~((grid > a0) & (grid < a1))
        fine.append(np.arange(a0, a1, d))
    fr = np.sort(np.concatenate([grid[keep]] + fine)) if fine else grid
    S = Sw * (1 + fc / fr)
    for m in modes:
        S = S + mode_psd(m, fr)
    # ---- spurs
    spurs = []
    if rng.uniform() < 0.3:
        for _ in range(int(rng.integers(1, 3))):
            for _try in range(100):
                fs = rng.uniform(flo * 2, fhi * 0.95)
                if all(abs(fs - m["f0"]) > max(40 * m["f0"] / m["Q"], 0.03 * m["f0"]) for m in inband):
                    break
            amp = rng.uniform(20, 200) * Sw * (1 + fc / fs)
            width = 0.6 * dfc
            S = S + amp * np.exp(-0.5 * ((fr - fs) / width)**2)
            spurs.append(dict(f_Hz=float(fs), peak_psd=float(amp), gaussian_sigma_Hz=float(width)))
    Navg = int(rng.choice([16, 32, 64, 100, 256]))
    val = S * rng.gamma(Navg, 1.0 / Navg, size=S.shape)
    # ---- key entry
    lines = []
    for m in sorted(inband, key=lambda m: m["f0"]):
        bg = Sw * (1 + fc / m["f_peak"])
        lines.append(dict(family=m["family"], order=m["order"], f0_Hz=float(m["f0"]), Q=float(m["Q"]),
                          f_peak_Hz=float(m["f_peak"]), f_solid_Hz=float(m["f_solid"]),
                          jitter_rel=float(m["jitter"]), Q_intrinsic=float(m["Qint"]),
                          peak_over_background=float(m["peak"] / bg), visible=bool(m["peak"] / bg > 3)))
        if "f0_decl" in m:
            lines[-1].update(f0_declared_medium_Hz=float(m["f0_decl"]), Q_declared_medium=float(m["Q_decl"]),
                             rel_shift_vs_declared_medium=float(m["f0"] / m["f0_decl"] - 1))
    entry = dict(id="s%02d" % i, effect=eff, declared=dict(length=L, width=w, thickness=t, E=E_SI, rho=RHO_SI,
                                                            nu=NU_SI, medium=med, temperature=T),
                 true_lever=dict(length=Lt, width=wt, thickness=tt), averages=Navg,
                 band_Hz=[float(flo), float(fhi)], background=dict(white=float(Sw), one_over_f_corner_Hz=float(fc)),
                 spurs=spurs, lines=lines,
                 effect_rel_shift_vs_declared={k: float(v) for k, v in shifts.items()},
                 note_shift="solid-model shift of the true vs the declared lever (no jitter, mesh (1,1,1)); "
                            "for fluid-loading see lines[].rel_shift_vs_declared_medium and Q_declared_medium",
                 detector=("vacuum: spot at x=L, y=w/4, top face, beam tilted 8 deg in y-z: u_z cos + u_y sin"
                           if vac else "fluid: spot at x=L, y=0, top face, beam tilted 5 deg in x-z; flapwise only"))
    lever_mass = RHO_SI * Lt * wt * tt
    if eff == "point-mass":
        entry.update(mass=prm["mass_frac"] * lever_mass, mass_frac=prm["mass_frac"], xi=prm["xi"],
                     position="top surface, centre line")
    elif eff == "thickness-error":
        entry.update(t_ratio=prm["t_ratio"])
    elif eff == "length-error":
        entry.update(dL=prm["dL"], dL_rel=prm["dL"] / L, L_true=Lt)
    elif eff == "modulus-error":
        entry.update(e_ratio=prm["e_ratio"])
    elif eff == "clamp-compliance":
        kn = 3 * E_SI / (prm["rot_frac"] * L)
        kt = kn / (2 * (1 + NU_SI))
        entry.update(k_n_N_per_m3=kn, k_t_N_per_m3=kt, K_rot_Nm_per_rad=kn * w * t**3 / 12,
                     K_trans_N_per_m=kt * w * t, rot_compliance_frac=prm["rot_frac"],
                     trans_compliance_frac=E_SI * t**2 / (4 * kt * L**3),
                     E_over_knL=E_SI / (kn * L), G_over_ktL=E_SI / (2 * (1 + NU_SI)) / (kt * L),
                     model="Winkler springs per unit area on the clamp face: normal k_n on u_x, tangential k_t on "
                           "u_y,u_z; *_compliance_frac = added static end compliance / Euler-Bernoulli L^3/(3EI)")
    elif eff == "axial-prestress":
        entry.update(sigma=prm["sigma"], sigma_AL2_over_EI=12 * prm["sigma"] * L**2 / (E_SI * t**2),
                     sign="positive = tension")
    elif eff == "fluid-loading":
        if vac:
            entry.update(p_gas_Pa=prm["gas_p"], rho_f=prm["rho_gas"], eta_f=1.83e-5, gas="air",
                         mean_free_path_m=prm["mean_free_path_m"],
                         model="free-molecular (Knudsen >> 1) damping on all faces, no added mass")
        else:
            entry.update(true_medium=true_med, rho_f=rho_f, eta_f=eta_f, declared_rho_f=rho_d,
                         declared_eta_f=eta_d, load_factor_rho=rho_f / rho_d, load_factor_eta=eta_f / eta_d)
    elif eff == "crystal-anisotropy":
        entry.update(a_crystal=1.0, crystal="cubic Si C11=165.7 C12=63.9 C44=79.6 GPa, x || [110], z || [001]")
    if not vac:
        entry["declared_medium_props"] = dict(rho=rho_d, eta=eta_d)
    return entry, fr, val, dict(T=T, Navg=Navg, med=med)


def write_case(out, entry, fr, val, meta):
    cid = entry["id"]
    d = entry["declared"]
    with open(os.path.join(out, "cases", cid + ".csv"), "w") as fh:
        fh.write("frequency_Hz,value\n")
        for a, v in zip(fr, val):
            fh.write("%.4f,%.6e\n" % (a, v))
    toml = ["# Blind synthetic thermal PSD (benchmarks/blind_spectra/gen.py, session 46). Truth in KEY.json.",
            "[measurement]", 'kind = "spectrum"', 'data = "%s.csv"' % cid, 'quantity = "psd"',
            "averages = %d" % meta["Navg"], "", "[probe]", 'name = "cantilever"',
            "length = %.6g" % d["length"], "width = %.6g" % d["width"], "thickness = %.6g" % d["thickness"],
            "E = %.6g" % E_SI, "rho = %.6g" % RHO_SI, "nu = %.6g" % NU_SI, "", "[medium]",
            'name = "%s"' % d["medium"], "temperature = %.1f" % d["temperature"], "", "[noise]",
            "frequency_rel = %.1e" % FREL, ""]
    with open(os.path.join(out, "cases", cid + ".toml"), "w") as fh:
        fh.write("\n".join(toml))


def main():
    out = sys.argv[1]
    os.makedirs(os.path.join(out, "cases"), exist_ok=True)
    rng = np.random.default_rng(SEED)
    order = rng.permutation(len(DESIGN))
    key, log = [], []
    t0 = time.time()
    for i, k in enumerate(order, start=1):
        entry, fr, val, meta = make_case(i, DESIGN[k], np.random.default_rng(SEED + 1000 * i), log)
        write_case(out, entry, fr, val, meta)
        key.append(entry)
        print(log[-1], flush=True)
    with open(os.path.join(out, "KEY.json"), "w") as fh:
        json.dump(dict(generator="benchmarks/blind_spectra/gen.py (session 46, blind)", seed=SEED,
                       frequency_rel=FREL, cases=key), fh, indent=1)
    log.append("total case time %.0fs" % (time.time() - t0))
    import checks
    txt = checks.run()
    with open(os.path.join(out, "checks.txt"), "w") as fh:
        fh.write(txt + "\n\nGeneration log\n" + "\n".join(log) + "\n")
    print(log[-1])


if __name__ == "__main__":
    main()
