"""Self-checks of the blind friction generator's integrator (session 46)."""
import math

import numpy as np

import physics as ph

KB = ph.KB


def _buf(n=1):
    return (np.zeros(n), np.zeros(n), np.zeros(100), np.zeros(100), np.zeros(100, np.int64))


def energy_check():
    k, a, eta = 1.0, 0.4e-9, 4.0
    U0 = eta * k * a * a / (2 * math.pi ** 2)
    m = k / (2 * math.pi * 1e5) ** 2
    w = math.sqrt(k * (1 + eta) / m)
    dt = 0.1 / w
    x, v = 0.3 * a, 0.0
    E = lambda x, v: 0.5 * m * v * v - 0.5 * U0 * math.cos(2 * math.pi * x / a) + 0.5 * k * x * x
    E0 = E(x, v)
    f, t, eX, et, en = _buf()
    Es = []
    for _ in range(200):
        x, v, _, _, _ = ph.run_1d(x, v, 0.0, 0.0, 0.0, 0.0, 1, 1000, dt, m, k, 0.0, 0.0, U0, a, 0.0, 0.0,
                                  0.0, 1.0, 0, f, t, eX, et, en, 0)
        Es.append(E(x, v))
    Es = np.array(Es)
    scale = U0
    return (f"energy (no damping, no noise, 2e5 steps at omega_max dt = 0.1): max |E - E0| / U0 = "
            f"{np.max(np.abs(Es - E0)) / scale:.2e}, net drift {(Es[-1] - E0) / scale:+.2e} U0")


def equipartition_check():
    k, a, eta, T = 1.0, 0.4e-9, 4.0, 300.0
    U0 = eta * k * a * a / (2 * math.pi ** 2)
    m = k / (2 * math.pi * 1e5) ** 2
    c = math.sqrt(k * m)
    dt = 0.1 / math.sqrt(k * (1 + eta) / m)
    ph.seed_rng(11)
    n = 20000
    f = np.zeros(n)
    tt = np.zeros(n)
    _, _, eX, et, en = _buf()
    x, v, *_ = ph.run_1d(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1, 20000, dt, m, k, c, 0.0, U0, a, KB * T, 0.0, 0.0,
                         1.0, 1, f[:1], tt[:1], eX, et, en, 0)
    x, v, *_ = ph.run_1d(x, v, 0.0, 0.0, 0.0, 0.0, n, 50, dt, m, k, c, 0.0, U0, a, KB * T, 0.0, 0.0, 1.0, 1,
                         f, tt, eX, et, en, 0)
    # force k(X-x) = -k x, x variance ~ kT / k_eff, k_eff = k (1 + eta) (harmonic; anharmonic correction small)
    var_x = np.var(f / k)
    # exact for the full potential by quadrature of the Boltzmann weight
    xs = np.linspace(-a / 2, a / 2, 20001)
    Uw = -0.5 * U0 * np.cos(2 * math.pi * xs / a) + 0.5 * k * xs ** 2
    wgt = np.exp(-(Uw - Uw.min()) / (KB * T))
    var_b = np.sum(wgt * xs ** 2) / np.sum(wgt)
    vs = []
    ph.seed_rng(12)
    for _ in range(3000):
        x, v, *_ = ph.run_1d(x, v, 0.0, 0.0, 0.0, 0.0, 1, 40, dt, m, k, c, 0.0, U0, a, KB * T, 0.0, 0.0, 1.0, 1,
                             f[:1], tt[:1], eX, et, en, 0)
        vs.append(v)
    kin = m * np.mean(np.square(vs)) / (KB * T)
    return (f"equipartition at 300 K (eta 4, fixed support): <x^2> sim {var_x:.4g} m^2 vs Boltzmann "
            f"{var_b:.4g} (ratio {var_x / var_b:.3f}); m<v^2>/kT = {kin:.3f} (3000 samples, expect 1 +- 0.03)")


def threshold_check():
    out = []
    k, a = 1.0, 0.4e-9
    m = k / (2 * math.pi * 1e5) ** 2
    c = math.sqrt(k * m)
    for eta in (0.7, 1.5, 3.0, 6.0):
        U0 = eta * k * a * a / (2 * math.pi ** 2)
        V = 1e-9
        d = a / 40
        dt = 0.1 / math.sqrt(k * (1 + eta) / m)
        nsub = int(math.ceil(d / V / dt))
        dt = d / V / nsub
        ns = 40 * 6
        f = np.zeros(ns)
        tt = np.zeros(ns)
        eX = np.zeros(100)
        et = np.zeros(100)
        en = np.zeros(100, np.int64)
        x, v, t, ne, nw = ph.run_1d(0.0, 0.0, 0.0, 0.0, 1.0, V, ns, nsub, dt, m, k, c, 0.0, U0, a, 0.0, 0.0,
                                    0.0, 1.0, 1, f, tt, eX, et, en, 0)
        Fs, Xs = ph.critical_force(U0, k, a)
        xr = eX[1:ne] - (en[1:ne] - 1) * a
        f2 = np.zeros(ns)
        x, v, t, ne2, nw = ph.run_1d(x, v, t, ns * d, -1.0, V, ns, nsub, dt, m, k, c, 0.0, U0, a, 0.0, 0.0,
                                     0.0, 1.0, 1, f2, tt, eX, et, en, nw)
        loop = 0.5 * (np.mean(f[80:]) - np.mean(f2[80:]))
        pk = np.max(f[80:])
        A = math.pi * U0 / a
        # support position of the slips relative to the old well vs the spinodal X*
        sl = (f"slip support position rel. to old well {np.mean(xr) * 1e12:.2f} pm vs spinodal X* "
              f"{Xs * 1e12:.2f} pm" if Xs else "no spinodal (eta < 1): continuous sliding")
        out.append(f"eta {eta}: well changes {ne}, trace peak {pk:.4g} N vs branch maximum pi U0/a {A:.4g}; "
                   f"{sl}; half loop {loop:.3g} N")
    return "quasi-static threshold (T = 0, V = 1 nm/s, point samples every a/40):\n   " + "\n   ".join(out)


def kramers_check():
    k, a, eta, T = 1.0, 0.4e-9, 4.0, 300.0
    U0 = eta * k * a * a / (2 * math.pi ** 2)
    m = k / (2 * math.pi * 1e5) ** 2
    c = math.sqrt(k * m)
    kT = KB * T
    Fs, Xs = ph.critical_force(U0, k, a)
    grid = np.linspace(0, Xs, 4001)
    dE, pmin, _ = ph.forward_barrier(grid, U0, k, a)
    i = int(np.nanargmin(np.abs(dE - 5.0 * kT)))
    X = grid[i]
    dEx = dE[i]
    pref = float(ph.kramers_prefactor(X, U0, k, a, m, c)[0])
    # the backward barrier must be much higher (single forward exit)
    dt = 0.1 / math.sqrt(k * (1 + eta) / m)
    ph.seed_rng(21)
    f = np.zeros(1)
    tt = np.zeros(1)
    eX = np.zeros(10)
    et = np.zeros(10)
    en = np.zeros(10, np.int64)
    xmin = a * pmin[i] / (2 * math.pi)
    times = []
    for trial in range(300):
        x, v, t = xmin, 0.0, 0.0
        while True:
            x, v, t, ne, nw = ph.run_1d(x, v, t, X, 0.0, 0.0, 1, 2000, dt, m, k, c, 0.0, U0, a, kT, 0.0, 0.0,
                                        1.0, 0, f, tt, eX, et, en, 0)
            if ne > 0:
                times.append(et[0])
                break
    tau = np.mean(times)
    rate = 1 / tau
    theory = pref * math.exp(-dEx / kT)
    return (f"Kramers escape (eta 4, 300 K, Q 1, support fixed where the forward barrier is {dEx / kT:.2f} kT): "
            f"simulated rate {rate:.4g} /s +- {rate / math.sqrt(len(times)):.2g} (300 escapes) vs Kramers "
            f"(moderate damping) {theory:.4g} /s, ratio {rate / theory:.3f}; prefactor {pref:.3g} Hz")


def run_checks():
    return ["# integrator checks (physics.py)", energy_check(), equipartition_check(), threshold_check(),
            kramers_check()]


if __name__ == "__main__":
    print("\n".join(run_checks()))
