"""Independent checks of physics.py.  `python checks.py [OUT_DIR]` prints (and writes OUT_DIR/checks.txt)
each number next to its expected value."""
import math
import sys
import os

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import physics as ph  # noqa: E402

KB = ph.KB
LINES = []


def out(s):
    print(s)
    LINES.append(s)


def run_static(k, m, c, T, U0, a, X, dt, nsamp, n_per, F_ext=0.0, x0=None, seed=1):
    P, Lc = ph.ou_propagator(k, m, c, T, dt)
    segX0 = np.array([X])
    segV = np.array([0.0])
    segN = np.array([nsamp], dtype=np.int64)
    om = np.zeros(nsamp)
    op = np.zeros(nsamp)
    ot = np.zeros(nsamp)
    ev = np.zeros(10)
    evi = np.zeros(10, dtype=np.int64)
    ph.nb_seed(seed)
    x0 = X if x0 is None else x0
    x, v, _ = ph._run_1d(x0, 0.0, segX0, segV, segN, n_per, dt, P, Lc, k, m, c, 0.0, U0, a, 0.0, 0.0,
                         1.0, F_ext, om, op, ot, ev, ev.copy(), evi, evi.copy(), evi.copy(), 0)
    return x, om, op


def check_equipartition():
    out("1. Equipartition in a harmonic well (U0 = 0, support at rest): k<x^2>/kBT, expected 1")
    k, f0, T = 1.0, 1e5, 300.0
    m = k / (2 * math.pi * f0) ** 2
    for Q in (0.05, 1.0, 20.0):
        c = math.sqrt(k * m) / Q
        for nper_period in (60, 6):
            dt = 1 / f0 / nper_period
            # samples spaced by several correlation times
            tc = max(c / k, 2 * m / c)
            n_per = max(1, int(3 * tc / dt))
            _, _, op = run_static(k, m, c, T, 0.0, 4e-10, 0.0, dt, 20000, n_per)
            r = np.mean(op ** 2) / k / (KB * T)
            out(f"   Q = {Q:5.2f}, dt = T0/{nper_period:2d}: k<x^2>/kBT = {r:.4f} "
                f"(+- {math.sqrt(2 / 20000):.4f} statistical), expected 1")


def check_boltzmann():
    out("2. Boltzmann distribution in lattice + lever (eta = 0.8, U0 = 3 kBT, support at rest at X = 0.3 a):"
        " <F>, <F^2> of the lever force vs quadrature")
    T, a, k = 300.0, 4e-10, None
    U0 = 3 * KB * T
    eta = 0.8
    k = 2 * math.pi ** 2 * U0 / (eta * a * a)
    f0 = 1e5
    m = k / (2 * math.pi * f0) ** 2
    X = 0.3 * a
    xs = np.linspace(X - 8 * a, X + 8 * a, 200001)
    E = -(U0 / 2) * np.cos(2 * math.pi * xs / a) + 0.5 * k * (xs - X) ** 2
    w = np.exp(-(E - E.min()) / (KB * T))
    Fx = k * (X - xs)
    m1 = np.sum(w * Fx) / np.sum(w)
    m2 = np.sum(w * Fx ** 2) / np.sum(w)
    for Q in (0.1, 1.0, 20.0):
        c = math.sqrt(k * m) / Q
        dt = ph.choose_dt(k, m, U0, a, c, 0.0)
        tc = max(c / k, 2 * m / c) * 3
        n_per = max(1, int(3 * tc / dt))
        _, _, op = run_static(k, m, c, T, U0, a, X, dt, 20000, n_per)
        out(f"   Q = {Q:5.2f}: <F> = {op.mean()*1e12:8.3f} pN (expected {m1*1e12:8.3f}), "
            f"<F^2>^0.5 = {math.sqrt(np.mean(op**2))*1e12:8.3f} pN (expected {math.sqrt(m2)*1e12:8.3f}),"
            f" stat. 1 sigma of <F> ~ {math.sqrt((m2-m1**2)/20000)*1e12:.3f} pN")


def check_overdamped():
    out("3. Overdamped limit (Q = 0.003 of the lattice oscillation): T = 0 mobility in a tilted washboard,"
        " <v> vs sqrt(F^2 - Fc^2)/c; free diffusion D vs kBT/c")
    a = 4e-10
    U0 = 1e-20
    Fc = math.pi * U0 / a
    m = 1e-12
    curv = 2 * math.pi ** 2 * U0 / a ** 2
    c = math.sqrt(curv * m) / 0.003
    k = 1e-9  # effectively free
    tau_relax = c / curv
    dt = tau_relax / 20
    for ratio in (1.2, 2.0, 5.0):
        F = ratio * Fc
        vexp = math.sqrt(F * F - Fc * Fc) / c
        ttot = 40 * a / vexp
        n_per = 1000
        nsamp = int(ttot / dt / n_per) + 1
        xe, _, _ = run_static(k, m, c, 0.0, U0, a, 0.0, dt, nsamp, n_per, F_ext=F)
        vsim = xe / (nsamp * n_per * dt)
        out(f"   F/Fc = {ratio:3.1f}: <v> = {vsim:.5e} m/s, expected {vexp:.5e} (ratio {vsim/vexp:.4f})")
    T = 300.0
    D = KB * T / c
    dt = 100 * m / c
    n_per = 100
    _, _, op = run_static(k, m, c, T, 0.0, a, 0.0, dt, 20000, n_per)
    x = -op / k
    dx = np.diff(x)
    Dsim = np.var(dx) / (2 * n_per * dt)
    out(f"   free diffusion: D = {Dsim:.5e} m^2/s, expected kBT/c = {D:.5e} (ratio {Dsim/D:.4f}, "
        f"stat. +- {math.sqrt(2/len(dx)):.3f})")


def check_threshold():
    out("4. Athermal stick-slip (T = 0, Q = 1) vs quasi-static PT: the stick branch's peak force, expected"
        " pi U0/a (= max lattice force), and the support position of the slip relative to its well,"
        " expected the spinodal X_c (cos 2 pi x_c/a = -1/eta; the force there (pi U0/a) sqrt(1-1/eta^2))")
    a, k, f0 = 4e-10, 1.0, 1e5
    m = k / (2 * math.pi * f0) ** 2
    c = math.sqrt(k * m)
    for eta in (2.0, 5.0):
        U0 = ph.U0_of(eta, k, a)
        Fpk = math.pi * U0 / a
        phic = math.acos(-1 / eta)
        Xc = phic / (2 * math.pi) * a + Fpk * math.sin(phic) / k
        for V in (1e-6, 1e-7, 1e-8):
            p = dict(k=k, m=m, c=c, U0=U0, a=a, T=0.0)
            r = ph.simulate_atomic_scan(p, V, 0.0, 12 * a, 96, 5, with_retrace=True)
            ev = r["events"]
            sel = (ev["seg"] >= 1) & (ev["dir"] > 0)
            fp = ev["F"][sel]
            # well left: the one at round((X_s - Xc)/a)
            Xrel = ev["X"][sel] - ev["j"][sel] * a
            selm = (ev["seg"] >= 1) & (ev["dir"] < 0)
            out(f"   eta = {eta}, V = {V:.0e} m/s: peak {fp.mean()*1e12:8.3f} pN (retrace "
                f"{-ev['F'][selm].mean()*1e12:8.3f}), expected {Fpk*1e12:8.3f} pN; slip at X - ja = "
                f"{Xrel.mean()*1e12:8.2f} pm, spinodal X_c = {Xc*1e12:8.2f} pm (dynamic delay "
                f"{(Xrel.mean()-Xc)*1e12:6.2f} pm, expected > 0, shrinking with V)")


def check_energy():
    out("5. Energy balance, T = 0, slow scan: mean lever force over whole periods x a vs the quasi-static"
        " energy released per slip (spinodal state -> next minimum)")
    a, k, f0 = 4e-10, 1.0, 1e5
    m = k / (2 * math.pi * f0) ** 2
    c = math.sqrt(k * m)
    for eta in (3.0, 5.0):
        U0 = ph.U0_of(eta, k, a)
        q = 2 * math.pi / a
        phic = math.acos(-1 / eta)
        xc = phic / q
        Xc = xc + math.pi * U0 / a * math.sin(phic) / k
        E = lambda x: -(U0 / 2) * math.cos(q * x) + 0.5 * k * (x - Xc) ** 2
        xn = ph._relax(xc + 0.5 * a, Xc, k, U0, a)
        dE = E(xc) - E(xn)
        p = dict(k=k, m=m, c=c, U0=U0, a=a, T=0.0)
        n_periods = 20
        r = ph.simulate_atomic_scan(p, 1e-8, 0.0, n_periods * a, n_periods * 40, 7, with_retrace=False)
        f = r["mean"][r["dir"] > 0]
        # drop the first 4 periods (start-up) and average over whole periods
        Fm = f[4 * 40:].mean()
        jumps = (xn - xc) / a
        out(f"   eta = {eta}: <F> a = {Fm*a*1e21:8.4f} zJ, slip energy = {dE*1e21:8.4f} zJ (ratio "
            f"{Fm*a/dE:.4f}, expected ~1 + O(v^2/3)); slip length {jumps:.2f} a")


def check_2d():
    out("6. 2D lattice at theta (k_y = k_x, T = 0): dominant period of the trace's force vs a / cos(theta)")
    a, k, f0 = 4e-10, 1.0, 1e5
    m = k / (2 * math.pi * f0) ** 2
    c = math.sqrt(k * m)
    U0 = ph.U0_of(4.0, k, a)
    for th_deg in (0.0, 20.0):
        th = math.radians(th_deg)
        p = dict(k=k, m=m, c=c, U0=U0, a=a, T=0.0)
        L = 40 * a
        n = 40 * 32
        r = ph.simulate_atomic_scan(p, 1e-7, 0.0, L, n, 3, ky_ratio=1.0, theta=th, with_retrace=False)
        f = r["mean"][r["dir"] > 0]
        f = f - f.mean()
        spec = np.abs(np.fft.rfft(f * np.hanning(len(f)), 16 * len(f))) ** 2
        fr = np.fft.rfftfreq(16 * len(f), L / n)
        i = np.argmax(spec[1:]) + 1
        out(f"   theta = {th_deg:4.1f} deg: period {1/fr[i]*1e9:.4f} nm, expected {a/math.cos(th)*1e9:.4f} nm")


def main():
    check_equipartition()
    check_boltzmann()
    check_overdamped()
    check_threshold()
    check_energy()
    check_2d()
    if len(sys.argv) > 1:
        os.makedirs(sys.argv[1], exist_ok=True)
        with open(os.path.join(sys.argv[1], "checks.txt"), "w") as fh:
            fh.write("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
