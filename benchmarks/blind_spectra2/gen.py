"""Blind thermal-spectrum set 2: `python gen.py OUT_DIR` -> OUT_DIR/cases/pNN.{csv,toml}, OUT_DIR/KEY.json.

Independent of probedyn (see physics.py).  Fixed seed; ids shuffled.  Each record: the TRUE lever (3D FEM with
the hidden effect), its lowest 12 modes, per-mode intrinsic Q, fluid loading (Sader) where the true medium is a
fluid, the thermal PSD an optical lever records (slope at the spot, calibrated as deflection by the true lever's
static end-load slope/deflection ratio, with a small quadrant-detector crosstalk of the twist), white + 1/f
background, Gamma scatter of an N-times averaged periodogram, optional electronic spurs.  The sidecar declares
the NOMINAL lever and the declared medium.
"""
import json
import os
import sys
import time

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import physics as ph  # noqa: E402

SEED = 20261206
E0, NU0, RHO0 = 169e9, 0.28, 2330.0
MESH = dict(nx=80, ny=10, nz=2, grade=0.6)
NMODES = 12


def air(T, p=101325.0):
    rho = p * 0.028965 / (8.314462 * T)
    eta = 1.716e-5 * (T / 273.15) ** 1.5 * (273.15 + 110.4) / (T + 110.4)
    return rho, eta


WATER = {293.15: (998.2, 1.002e-3), 298.15: (997.05, 0.890e-3)}
GLYCEROL20_293 = (1046.9, 1.769e-3)      # 20 wt% glycerol in water, 20 C


def medium_props(name, T, p=101325.0):
    if name == 'vacuum':
        return 0.0, 0.0
    if name == 'air':
        return air(T, p)
    if name == 'water':
        return WATER[T]
    raise ValueError(name)


def eb_tension_ratio():
    """int phi'^2 / int phi''^2 * L^2-free ratio for the cantilever's first EB mode (L = 1)."""
    lam = 1.8751040687
    x = np.linspace(0, 1, 4001)
    s = (np.cosh(lam) + np.cos(lam)) / (np.sinh(lam) + np.sin(lam))
    d1 = lam * (np.sinh(lam * x) + np.sin(lam * x) - s * (np.cosh(lam * x) - np.cos(lam * x)))
    d2 = lam ** 2 * (np.cosh(lam * x) + np.cos(lam * x) - s * (np.sinh(lam * x) + np.sin(lam * x)))
    return np.trapezoid(d1 ** 2, x) / np.trapezoid(d2 ** 2, x)


# ------------------------------------------------------------------ the case list
def case_list():
    um = 1e-6
    r1 = eb_tension_ratio()
    C = []
    # (declared lever L, w, t), declared medium, true medium override, effect, params
    C.append(dict(effect='point-mass', L=250 * um, w=35 * um, t=2.5 * um, medium='air', T=295.0,
                  mass_frac=0.010, xi=0.90, avg=64))
    C.append(dict(effect='point-mass', L=150 * um, w=30 * um, t=3.0 * um, medium='vacuum', T=295.0,
                  mass_frac=0.006, xi=0.62, avg=32))
    C.append(dict(effect='clamp-compliance', L=200 * um, w=40 * um, t=4.0 * um, medium='air', T=295.0,
                  c_rot=0.010, avg=128))
    C.append(dict(effect='clamp-compliance', L=120 * um, w=30 * um, t=2.0 * um, medium='vacuum', T=295.0,
                  c_rot=0.004, avg=64))
    C.append(dict(effect='thickness-error', L=350 * um, w=35 * um, t=2.0 * um, medium='air', T=295.0,
                  t_ratio=1.03, avg=32))
    C.append(dict(effect='width-error', L=225 * um, w=28 * um, t=2.0 * um, medium='vacuum', T=295.0,
                  w_ratio=1.05, avg=128))
    C.append(dict(effect='length-error', L=200 * um, w=30 * um, t=2.5 * um, medium='air', T=295.0,
                  dL=3.0 * um, avg=64))
    C.append(dict(effect='modulus-error', L=300 * um, w=30 * um, t=3.0 * um, medium='water', T=293.15,
                  e_ratio=0.97, avg=256))
    C.append(dict(effect='crystal-anisotropy', L=160 * um, w=40 * um, t=4.0 * um, medium='vacuum', T=295.0,
                  a_crystal=1.0, avg=32))
    for (L, w, t, med, df1, avg) in [(400 * um, 40 * um, 2.0 * um, 'vacuum', +0.012, 64),
                                     (250 * um, 30 * um, 1.5 * um, 'air', -0.006, 128)]:
        # EB Rayleigh: (f/f0)^2 = 1 + sigma A r1 L^2 / (E I)  ->  sigma for the target flap-1 shift
        sig = ((1 + df1) ** 2 - 1) * E0 * t ** 2 / (12 * r1 * L ** 2)
        C.append(dict(effect='axial-prestress', L=L, w=w, t=t, medium=med, T=295.0, sigma=float(sig), avg=avg))
    C.append(dict(effect='fluid-loading', L=300 * um, w=35 * um, t=2.0 * um, medium='vacuum', T=295.0,
                  true_fluid='air', p_gas=0.3e5, avg=64))
    C.append(dict(effect='fluid-loading', L=200 * um, w=40 * um, t=3.0 * um, medium='water', T=293.15,
                  true_fluid='water-glycerol 20 wt%', avg=256))
    # nulls
    for (L, w, t, med, T, avg) in [(100 * um, 20 * um, 1.5 * um, 'vacuum', 295.0, 16),
                                   (275 * um, 45 * um, 3.5 * um, 'vacuum', 295.0, 64),
                                   (300 * um, 30 * um, 2.0 * um, 'air', 295.0, 32),
                                   (180 * um, 25 * um, 2.5 * um, 'air', 298.0, 128),
                                   (125 * um, 50 * um, 5.0 * um, 'air', 295.0, 64),
                                   (225 * um, 40 * um, 3.0 * um, 'water', 298.15, 256),
                                   (400 * um, 35 * um, 4.0 * um, 'water', 293.15, 128)]:
        C.append(dict(effect='none', L=L, w=w, t=t, medium=med, T=T, avg=avg))
    return C


# ------------------------------------------------------------------ one record
def build_true_lever(c):
    L, w, t = c['L'], c['w'], c['t']
    E, C, clamp, sigma0, pm = E0, None, None, 0.0, None
    key = {}
    e = c['effect']
    if e == 'thickness-error':
        t = t * c['t_ratio']; key['t_ratio'] = c['t_ratio']
    elif e == 'width-error':
        w = w * c['w_ratio']; key['w_ratio'] = c['w_ratio']
    elif e == 'length-error':
        L = L + c['dL']; key['dL'] = c['dL']
    elif e == 'modulus-error':
        E = E0 * c['e_ratio']; key['e_ratio'] = c['e_ratio']
    elif e == 'crystal-anisotropy':
        a = c['a_crystal']
        C = ph.c_iso(E0, NU0) + a * (ph.c_cubic_110() - ph.c_iso(E0, NU0)); key['a_crystal'] = a
    elif e == 'axial-prestress':
        sigma0 = c['sigma']; key['sigma'] = sigma0
    elif e == 'clamp-compliance':
        kn = E0 / (c['c_rot'] * L)              # c_rot = E I / (K_rot L), K_rot = k_n w t^3 / 12
        kt = kn / (2 * (1 + NU0))               # tangential springs: the foundation's G/E ratio
        clamp = (kn, kt)
        key.update(c_rot=c['c_rot'], c_trans=E0 * t ** 2 / (4 * kt * L ** 3), k_n=kn, k_t=kt,
                   definition='springs per unit area on the clamp face x=0: k_n [N/m^3] normal (x), '
                              'k_t [N/m^3] on both tangential components (y, z); c_rot = E I/(K_rot L) '
                              'with K_rot = k_n w t^3/12 (= E/(k_n L)); c_trans = (3 E I/L^3)/K_trans with '
                              'K_trans = k_t w t (= E t^2/(4 k_t L^3)); E, L, w, t the declared values')
    elif e == 'point-mass':
        m = c['mass_frac'] * RHO0 * L * w * t
        pm = (m, c['xi'])
    lever = ph.Lever(L, w, t, E=E, nu=NU0, rho=RHO0, C=C, clamp=clamp, sigma0=sigma0, point_mass=pm, **MESH)
    if pm is not None:
        key.update(mass=pm[0], xi=float(lever.point_xi), mass_fraction_of_lever=c['mass_frac'],
                   where='on the top surface, centre line, one mesh vertex')
    return lever, key, (L, w, t)


def true_fluid(c):
    T = c['T']
    if c['effect'] == 'fluid-loading':
        if c['true_fluid'] == 'air':
            r, e = air(T, c['p_gas'])
            return 'air at %.2f bar' % (c['p_gas'] / 1e5), r, e
        return c['true_fluid'], GLYCEROL20_293[0], GLYCEROL20_293[1]
    r, e = medium_props(c['medium'], T)
    return c['medium'], r, e


def bin_average(fc, df, total_fn, lines):
    """Bin-averaged PSD: the value of each bin is the mean of the true PSD over [f - df/2, f + df/2]
    (an unresolved line keeps its power); sub-sampled only near the lines."""
    S = total_fn(fc)
    for f0, gam in lines:
        wdt = 30 * max(gam, df)
        idx = np.nonzero(np.abs(fc - f0) < wdt)[0]
        if len(idx) == 0:
            continue
        nsub = int(np.clip(np.ceil(8 * df / gam), 1, 4000))
        if nsub == 1:
            continue
        off = (np.arange(nsub) + 0.5) / nsub - 0.5
        for chunk in np.array_split(idx, max(1, len(idx) * nsub // 200000 + 1)):
            ff = (fc[chunk, None] + df * off[None, :]).ravel()
            S[chunk] = total_fn(ff).reshape(len(chunk), nsub).mean(1)
    return S


def fit_sho(f, S):
    """SHO thermal-line fit (log space) of a noiseless line: A f0^4 / ((f0^2 - f^2)^2 + (f f0 / Q)^2)."""
    i = np.argmax(S)
    def res(p):
        A, f0, Q = np.exp(p[0]), p[1], np.exp(p[2])
        return np.log(A * f0 ** 4 / ((f0 ** 2 - f ** 2) ** 2 + (f * f0 / Q) ** 2)) - np.log(S)
    Q0 = 10.0
    p0 = [np.log(S[i] / Q0 ** 2), f[i], np.log(Q0)]
    r = least_squares(res, p0, x_scale=[1, f[i] * 0.01, 1])
    return float(r.x[1]), float(np.exp(r.x[2]))


def make_record(c, rng, out_cases, rid):
    t_start = time.process_time()
    lever, key, (Lt, wt, tt) = build_true_lever(c)
    freq = lever.solve_modes(NMODES)
    lever.classify()
    T = c['T']
    fname, rho_f, eta_f = true_fluid(c)
    if c['effect'] == 'fluid-loading':
        key.update(rho_f=rho_f, eta_f=eta_f, true_fluid=fname)
        if 'p_gas' in c:
            key['p_gas'] = c['p_gas']

    # intrinsic Q per mode: a lever-level value with per-mode scatter
    if c['medium'] == 'vacuum' and c['effect'] != 'fluid-loading':
        Qlev = np.exp(rng.uniform(np.log(1.5e3), np.log(2.0e4)))
    else:
        Qlev = np.exp(rng.uniform(np.log(2e3), np.log(3e4)))
    Qint = np.clip(Qlev * np.exp(rng.normal(0, 0.3, NMODES)), 1e3, 5e4)

    # optical lever: spot near the free end, off the centre line; calibration by the true static slope ratio
    xs_rel = rng.uniform(0.86, 0.94)
    ys_off = rng.uniform(0.12, 0.25) * rng.choice([-1, 1])
    x0, y0 = xs_rel * Lt, wt / 2 + ys_off * wt
    ust = lever.static_end_load()
    P = lever.probe_matrix(np.array([[Lt], [wt / 2], [tt / 2]]))
    delta = (P @ ust)[2]
    sx_st, _ = lever.slope_at(ust, x0, y0)
    G = delta / sx_st
    eps = rng.uniform(0.005, 0.03) * rng.choice([-1, 1])
    gains = []
    for n in range(NMODES):
        sx, sy = lever.slope_at(lever.modes[:, n], x0, y0)
        gains.append(G * (sx + eps * sy))
    gains = np.array(gains)

    # band and bins (an FFT grid: fs = 2.56 f_hi, N = 2^k)
    f1 = freq[0]
    f_lo = max(2e3, 0.1 * f1)
    f_hi = min(6e6, 0.95 * freq[-1])
    fs = 2.56 * f_hi
    Q1 = Qint[0]
    k = 12
    while True:
        df = fs / 2 ** k
        if (f_hi - f_lo) / (fs / 2 ** (k + 1)) > 131072 or fs / 2 ** (k + 1) < max(f1 / Q1 / 2, 5.0):
            break
        k += 1
    fc = np.arange(np.ceil(f_lo / df), np.floor(f_hi / df) + 1) * df

    def mu_of(ff):
        return ph.modal_fluid_mu(lever, ff, rho_f, eta_f)

    def lines_psd(ff, only=None):
        mu = mu_of(ff) if rho_f else None
        S = np.zeros_like(ff)
        for n in (range(NMODES) if only is None else [only]):
            S += ph.mode_psd(ff, freq[n], Qint[n], gains[n], T, None if mu is None else mu[n])
        return S

    # line parameters: vacuum -> f0 = eigenfrequency, Q = Q_int; fluid -> SHO fit of the noiseless line
    line_info = []
    widths = []
    for n in range(NMODES):
        if rho_f:
            fg = freq[n] * np.linspace(0.2, 1.3, 20001)
            Sg = lines_psd(fg, only=n)
            m = Sg > Sg.max() / 10
            f0n, Qn = fit_sho(fg[m], Sg[m])
        else:
            f0n, Qn = freq[n], Qint[n]
        area = gains[n] ** 2 * ph.KB * T / (2 * np.pi * freq[n]) ** 2   # equipartition (vacuum form)
        line_info.append(dict(family=lever.family[n], order=lever.order[n], f_vacuum_Hz=float(freq[n]),
                              f0_Hz=float(f0n), Q=float(Qn), Q_int=float(Qint[n]),
                              purity=float(lever.purity[n]), gain=float(gains[n]), area_m2=float(area)))
        widths.append((f0n, max(f0n / Qn, 1e-3)))

    # background: white + 1/f (detector / shot noise + laser, in deflection units)
    Bw = (10 ** rng.uniform(np.log10(15e-15), np.log10(80e-15))) ** 2
    fcor = 10 ** rng.uniform(np.log10(2e3), np.log10(2e4))

    def total(ff):
        return lines_psd(ff) + Bw * (1 + fcor / ff)

    S_true = bin_average(fc, df, total, widths)
    N = c['avg']
    S = S_true * rng.gamma(N, 1.0 / N, size=len(fc))
    spurs = []
    nsp = int(rng.choice([0, 1, 1, 2]))
    for _ in range(nsp):
        for _try in range(50):
            fsp = rng.uniform(f_lo * 1.2, min(f_hi * 0.9, 1.5e6))
            if all(abs(fsp - a) > 30 * max(df, b) for a, b in widths):
                break
        j = int(np.argmin(np.abs(fc - fsp)))
        amp = 10 ** rng.uniform(0.7, 1.7) * Bw * (1 + fcor / fc[j])
        S[j] += amp
        spurs.append(dict(f_Hz=float(fc[j]), added_psd=float(amp)))

    # visibility of each line: true peak (bin-averaged) over the background at the line
    for li, (f0n, gam) in zip(line_info, widths):
        j = int(np.argmin(np.abs(fc - f0n)))
        inband = fc[0] <= f0n <= fc[-1]
        li['in_band'] = bool(inband)
        li['peak_over_background'] = float(S_true[j] / (Bw * (1 + fcor / fc[j])) - 1) if inband else None

    # write the record
    csv = os.path.join(out_cases, rid + '.csv')
    with open(csv, 'w') as fh:
        fh.write('frequency_Hz,value\n')
        for a, b in zip(fc, S):
            fh.write('%.10g,%.5g\n' % (a, b))
    med = c['medium']
    frel = float(rng.choice([5e-5, 1e-4, 2e-4]))
    toml = ['# Thermal-noise deflection PSD of an AFM cantilever (optical-lever detector, InvOLS-calibrated).',
            '# Blind test record (benchmarks/blind_spectra2).',
            '[measurement]', 'kind = "spectrum"', 'data = "%s.csv"' % rid, 'quantity = "psd"',
            'averages = %d' % N, '',
            '[probe]', 'name = "cantilever"', 'length = %.6g' % c['L'], 'width = %.6g' % c['w'],
            'thickness = %.6g' % c['t'], 'E = %.6g' % E0, 'rho = %.6g' % RHO0, 'nu = %.6g' % NU0, '',
            '[medium]', 'name = "%s"' % med, 'temperature = %.2f' % T, '',
            '[noise]', 'frequency_rel = %g' % frel, '']
    with open(os.path.join(out_cases, rid + '.toml'), 'w') as fh:
        fh.write('\n'.join(toml))

    rec = dict(id=rid, effect=c['effect'], **key,
               declared=dict(length=c['L'], width=c['w'], thickness=c['t'], E=E0, rho=RHO0, nu=NU0,
                             medium=med, temperature=T),
               true_lever=dict(length=Lt, width=wt, thickness=tt),
               true_medium=dict(name=fname, rho_f=rho_f, eta_f=eta_f),
               averages=N, frequency_rel_declared=frel,
               detector=dict(spot_x_over_L=xs_rel, spot_y_offset_over_w=ys_off, crosstalk_twist=eps,
                             invols_factor_m_per_rad=G),
               band_Hz=[float(fc[0]), float(fc[-1])], bin_Hz=float(df), n_bins=int(len(fc)),
               background=dict(white_m2_per_Hz=Bw, one_over_f_corner_Hz=fcor), spurs=spurs,
               lines=line_info, fem=dict(ndof=int(lever.ndof), **MESH),
               cpu_s=time.process_time() - t_start)
    return rec


def main(out):
    t0 = time.time()
    cases_dir = os.path.join(out, 'cases')
    os.makedirs(cases_dir, exist_ok=True)
    rng = np.random.default_rng(SEED)
    C = case_list()
    ids = ['p%02d' % (i + 1) for i in rng.permutation(len(C))]
    recs = []
    for c, rid in zip(C, ids):
        r = make_record(c, rng, cases_dir, rid)
        vis = [(l['family'][0] + str(l['order']), round(l['peak_over_background'], 1))
               for l in r['lines'] if l['in_band']]
        print('%s %-19s f1=%9.1f Q1=%8.1f bins=%6d df=%6.1f cpu=%.1fs vis=%s' % (
            rid, r['effect'], r['lines'][0]['f0_Hz'], r['lines'][0]['Q'], r['n_bins'], r['bin_Hz'],
            r['cpu_s'], vis), flush=True)
        recs.append(r)
    recs.sort(key=lambda r: r['id'])
    with open(os.path.join(out, 'KEY.json'), 'w') as fh:
        json.dump(dict(generator='benchmarks/blind_spectra2/gen.py', seed=SEED, mesh=MESH,
                       cases=recs), fh, indent=1)
    print('wall %.1f s, cpu %.1f s' % (time.time() - t0, time.process_time()))


if __name__ == '__main__':
    main(sys.argv[1] if len(sys.argv) > 1 else 'out')
