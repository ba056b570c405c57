"""Own verification of physics.py (session 46, blind). run() returns the text written to checks.txt."""
import numpy as np
import physics as ph

E, NU, RHO = 169e9, 0.28, 2330.0


def run():
    out = []
    p = out.append
    C = ph.c_isotropic(E, NU)
    # 1 crystal
    Cx = ph.c_silicon_110()
    ec = ph.engineering_constants(Cx)
    p("1. <110> silicon in the lever frame (Hopcroft 2010: E[110]=169 GPa, G=79.6 GPa, nu_xy=0.064, nu_xz=0.36)")
    p("   " + ", ".join("%s=%.4g" % (k, v / 1e9 if k[0] in 'EG' else v) for k, v in ec.items()) + " (moduli GPa)")
    p("   isotropic declared: E=169 GPa, nu=0.28, G=%.2f GPa" % (E / (2 * (1 + NU)) / 1e9))
    # 2 FEM vs Euler-Bernoulli (slender square beam; Timoshenko correction ~ -(1+E/kG)(t/L)^2 * c)
    L, w, t = 200e-6, 3e-6, 4e-6
    lv = ph.Lever(L, w, t, C, RHO, rxyz=(2, 1, 1.5))
    f, V = lv.solve(3e6)
    fam = lv.classify(V)
    eb = ph.euler_bernoulli_flap(L, w, t, E, RHO, 3)
    ff = [x for x, a in zip(f, fam) if a == 'flap'][:3]
    p("2. FEM vs Euler-Bernoulli, slender 200x3x4 um beam (expect FEM/EB slightly < 1 from shear + rotary inertia,")
    p("   Timoshenko estimate for mode n: 1 - 0.5*(lambda_n t/L)^2*(1/12)*(1+E/(kG)) with k=5/6)")
    lam = np.array([1.8751, 4.6941, 7.8548])
    tim = 1 - 0.5 * (lam * t / L)**2 / 12 * (1 + E / (5 / 6 * E / (2 * (1 + NU)))) * np.array([0.5, 1.0, 1.0])
    for n in range(3):
        p("   flap %d: FEM %.2f Hz, EB %.2f Hz, ratio %.6f (Timoshenko-type estimate %.6f)"
          % (n + 1, ff[n], eb[n], ff[n] / eb[n], tim[n]))
    # 3 mesh convergence on the 225x40x3 lever
    p("3. Mesh convergence, 225x40x3 um isotropic lever (rxyz = refinement factors in x, y, z; generator uses (2,1,1.5))")
    L, w, t = 225e-6, 40e-6, 3e-6
    res = {}
    for r in [(1, 1, 1), (2, 1, 1.5), (3, 1.5, 2)]:
        lv = ph.Lever(L, w, t, C, RHO, rxyz=r)
        f, V = lv.solve(1.5e6)
        fam = lv.classify(V)
        res[r] = (f, fam)
        p("   %s dof %6d: " % (str(r), lv.K.shape[0]) + ", ".join("%s %.2f" % (a, b) for a, b in zip(fam, f)))
    f2, f3 = res[(2, 1, 1.5)][0], res[(3, 1.5, 2)][0]
    p("   relative change (2,1,1.5) -> (3,1.5,2): " + ", ".join("%.1e" % x for x in (f2 / f3 - 1)))
    p("   earlier study (same code): x-refinement 1,2,3,4 of mode 2: 515009.17, 514921.11, 514913.24, 514911.65 Hz"
      " (order ~3.3); z layers 2,3,4: 515009.2, 514996.6, 514992.9")
    eb = ph.euler_bernoulli_flap(L, w, t, E, RHO, 3)
    ebp = ph.euler_bernoulli_flap(L, w, t, E / (1 - NU**2), RHO, 3)
    p("   EB (E) %.1f / %.1f Hz; plate-strip (E/(1-nu^2)) %.1f / %.1f Hz: FEM in between (w/t=13, anticlastic)"
      % (eb[0], eb[1], ebp[0], ebp[1]))
    # torsion St Venant estimate
    G = E / (2 * (1 + NU))
    beta = 1 / 3 * (1 - 0.630 * t / w)
    J = beta * w * t**3
    Ip = w * t * (w**2 + t**2) / 12
    ft = 1 / (4 * L) * np.sqrt(G * J / (RHO * Ip))
    fts = [b for a, b in zip(res[(2, 1, 1.5)][1], res[(2, 1, 1.5)][0]) if a == 'torsion'][0]
    p("   torsion 1: FEM %.0f Hz vs St Venant (free warping) %.0f Hz, ratio %.4f (warping restraint at the clamp"
      " stiffens)" % (fts, ft, fts / ft))
    # 4 Sader
    p("4. Sader (1998) hydrodynamic function (own implementation)")
    for Re in [1e-2, 1e-1, 1, 10, 100, 1e3, 1e4, 1e6]:
        om = ph.omega_rect(np.array(Re))
        g = om * ph.gamma_circ(np.array(Re))
        p("   Re=%-8g Omega=%.4f%+.4fi  Gamma_rect=%.4f%+.4fi" % (Re, om.real, om.imag, g.real, g.imag))
    p("   limits: Omega -> 1 as Re -> inf (inviscid plate added mass pi rho b^2/4 per length): %.5f at Re=1e8"
      % ph.omega_rect(np.array(1e8)).real)
    Re = 1e4
    gc = ph.gamma_circ(np.array(Re))
    p("   circle high-Re asymptote 1 + 2 sqrt(2)(1+i)/sqrt(Re) at Re=1e4: %.5f%+.5fi vs exact %.5f%+.5fi"
      % (1 + 2 * np.sqrt(2) / np.sqrt(Re), 2 * np.sqrt(2) / np.sqrt(Re), gc.real, gc.imag))
    for (L, w, t, med, T) in [(225e-6, 40e-6, 3e-6, 'air', 295.0), (200e-6, 40e-6, 2e-6, 'water', 295.0),
                              (197e-6, 29e-6, 2e-6, 'water', 295.0)]:
        rho_f, eta = ph.air(T) if med == 'air' else ph.water(T)
        f1 = ph.euler_bernoulli_flap(L, w, t, E, RHO, 1)[0]
        om = 2 * np.pi * f1
        for _ in range(50):
            G = ph.gamma_rect(om, w, rho_f, eta)
            om = 2 * np.pi * f1 / np.sqrt(1 + np.pi * rho_f * w / (4 * RHO * t) * G.real)
        Q = (4 * RHO * t / (np.pi * rho_f * w) + G.real) / G.imag
        p("   %gx%gx%g um in %s: f1 %.0f -> %.0f Hz (ratio %.3f), Q %.1f  (Sader single-mode formulas)"
          % (L * 1e6, w * 1e6, t * 1e6, med, f1, om / 2 / np.pi, om / 2 / np.pi / f1, Q))
    p("   (typical published: air Q ~ 100-500 for such levers, water f ratio ~0.2-0.4 and Q ~ 2-6.)")
    # 5 modal projection J and FM gas
    L, w, t = 225e-6, 40e-6, 3e-6
    lv = ph.Lever(L, w, t, C, RHO, rxyz=(1, 1, 1))
    f, V = lv.solve(1.5e6)
    fam = lv.classify(V)
    xq, wq, W = lv.width_avg_w(V)
    Jn = (W**2 * wq[:, None]).sum(0)
    p("5. modal fluid projection: rho w t * int(wbar^2) dx (=1 for a mass-normalised Euler-Bernoulli mode): "
      + ", ".join("%s %.4f" % (a, j * RHO * w * t) for a, j in zip(fam, Jn)))
    T, pg = 295.0, 60.0
    M_air = 0.0289647
    rho_g = pg * M_air / (ph.R_GAS * T)
    vbar = np.sqrt(8 * ph.R_GAS * T / (np.pi * M_air))
    Cg = lv.gas_damping_matrix(rho_g * vbar, rho_g * vbar / 4)
    cg = np.einsum('in,in->n', V, Cg @ V)
    Qfem = 2 * np.pi * f / cg
    Qchr = (np.pi / 2)**1.5 * RHO * t * f * np.sqrt(ph.R_GAS * T / M_air) / pg
    p("6. free-molecular gas at 60 Pa: FEM-surface Q vs Christian (pi/2)^1.5 rho t f sqrt(RT/M)/p (faces only):")
    p("   " + ", ".join("%s %.0f/%.0f" % (a, q1, q2) for a, q1, q2 in zip(fam, Qfem, Qchr))
      + "  (edges add a little damping; lateral uses tangential rho vbar/4 per face + normal on the edges)")
    # 7 equipartition
    k1 = (2 * np.pi * f[0])**2
    Ue = lv.disp(V[:, :1], np.array([[L], [0], [0]]))[2, 0, 0]
    keff = k1 / Ue**2
    p("7. equipartition: FEM static-equivalent stiffness of mode 1 at the end, omega^2/phi(L)^2 = %.3f N/m;"
      " Euler-Bernoulli 3EI/L^3 = %.3f N/m (mode-1 value is 3EI/L^3 * 1.030 for EB: %.3f)"
      % (keff, 3 * E * w * t**3 / 12 / L**3, 3 * E * w * t**3 / 12 / L**3 * 1.0302))
    md_s, Q = Ue, 500.0
    fr = np.linspace(0.001, 20, 400001) * f[0]
    om = 2 * np.pi * fr
    wn = 2 * np.pi * f[0]
    S = 4 * 1.380649e-23 * T * md_s**2 * (wn / Q) / ((wn**2 - om**2)**2 + (om * wn / Q)**2)
    area = np.trapezoid(S, fr) if hasattr(np, 'trapezoid') else np.trapz(S, fr)
    p("   numerical integral of the mode-1 PSD (Q=500) %.4e m^2 vs kT/k_eff %.4e m^2"
      % (area, 1.380649e-23 * T / keff))
    return "\n".join(out)
