#!/usr/bin/env python3
"""Blind generator of synthetic AFM force-distance curves (independent of probedyn's models).

Usage: python gen.py OUT_DIR    -> writes OUT_DIR/cases/fNN.csv + fNN.toml, OUT_DIR/KEY.json, OUT_DIR/checks.txt

Written in session 44 by a helper from docs/diagnose.md section 1 (formats) and the catalog table only, not
from probedyn's models or tests (docs/diagnose.md 9.30); kept so that the third blind force-curve set can be
regenerated (fixed seed) and the diagnosis rerun on it: ``python benchmarks/blind_curves/run.py OUT_DIR``.
Physics in physics.py (same directory).  See the module docstring there for conventions.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from physics import (estar, hertz_force, hertz_delta, path_hertz, path_dmt, path_jkr, path_md,
                     md_sigma0, simulate)

HERE = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 and not sys.argv[1].startswith('--') else os.getcwd()
CASES = os.path.join(HERE, 'cases')
E_TIP, NU_TIP = 169e9, 0.27          # silicon tip (true; declared wherever the sample E is declared)
Z0_TABOR = 0.3e-9


def logu(rng, a, b):
    return float(np.exp(rng.uniform(np.log(a), np.log(b))))


def tabor(R, W, Es, z0=Z0_TABOR):
    return (R * W ** 2 / (Es ** 2 * z0 ** 3)) ** (1 / 3)


# ------------------------------------------------------------------ physical draw of one case
def draw_physics(rng, effect):
    for attempt in range(20000):
        p = dict(effect=effect)
        R_decl = logu(rng, 5e-9, 40e-9)
        r_ratio = 1.0
        if effect == 'tip-radius-error':
            r_ratio = rng.uniform(1.5, 3.0) if rng.random() < 0.5 else rng.uniform(0.4, 0.6)
        R = R_decl * r_ratio
        if effect == 'jump-to-contact':
            k = logu(rng, 0.05, 0.3)
        elif effect == 'adhesion-dmt':
            k = logu(rng, 0.5, 40)
        else:
            k = logu(rng, 0.1, 40)
        nu_s = float(rng.choice([0.25, 0.3, 0.33, 0.4, 0.45, 0.5]))
        sig = logu(rng, 20e-12, 60e-12) if effect == 'jump-to-contact' else logu(rng, 20e-12, 200e-12)
        W = logu(rng, 0.01, 0.2) if effect.startswith('adhesion') or effect == 'jump-to-contact' else 0.0
        lam = D0 = h0 = None
        if effect in ('adhesion-dmt', 'jump-to-contact'):
            E_s = logu(rng, 2e9, 150e9)
            D0 = rng.uniform(0.165e-9, 0.4e-9)
        elif effect == 'adhesion-jkr':
            E_s = logu(rng, 5e6, 3e9)
        elif effect == 'adhesion-md':
            lam = logu(rng, 0.3, 3.0)
            h0 = logu(rng, 0.2e-9, 1.0e-9)
            K = ((2 * W / lam) * (R / (np.pi * W)) ** (1 / 3) / h0) ** 1.5
            Es_target = 0.75 * K
            inv_s = 1 / Es_target - (1 - NU_TIP ** 2) / E_TIP
            if inv_s <= 0:
                continue
            E_s = (1 - nu_s ** 2) / inv_s
            if not (5e6 <= E_s <= 150e9):
                continue
        else:
            E_s = logu(rng, 5e6, 150e9)
        Es = estar(E_s, nu_s, E_TIP, NU_TIP)
        P_trig = logu(rng, 2e-9, 100e-9)
        if P_trig > k * 250e-9 or P_trig < 15 * sig:
            continue
        # adhesion magnitudes
        if effect in ('adhesion-dmt', 'jump-to-contact'):
            F_ad = 2 * np.pi * W * R
        elif effect == 'adhesion-jkr':
            F_ad = 1.5 * np.pi * W * R
        elif effect == 'adhesion-md':
            F_ad = 1.75 * np.pi * W * R
        else:
            F_ad = 0.0
        if F_ad:
            if F_ad < 4 * sig or F_ad / k > 400e-9:
                continue
            mu = tabor(R, W, Es)
            if effect == 'adhesion-dmt' and mu > 0.5:
                continue
            if effect == 'jump-to-contact' and mu > 1.0:
                continue
            if effect == 'adhesion-jkr':
                if mu < 2.0:
                    continue
                a0 = (9 * np.pi * W * R ** 2 / (2 * Es)) ** (1 / 3)
                if a0 / R > 0.8:
                    continue
        d_trig = hertz_delta(P_trig + F_ad, R, Es)
        if d_trig > 1.0 * R:
            continue
        if effect == 'jump-to-contact':
            # snap-in must be visible: force step ~ k * snap distance >= 4 sigma
            H = 12 * np.pi * W * D0 ** 2
            s_snap = (H * R / (3 * k)) ** (1 / 3)
            if k * s_snap < 4 * sig:
                continue
        p.update(R_decl=R_decl, R_true=R, r_ratio=r_ratio, k=k, E_s=E_s, nu_s=nu_s, E_tip=E_TIP,
                 nu_tip=NU_TIP, E_star=Es, W=W, lam=lam, D0=D0, sigma_F=sig, P_trig=P_trig,
                 tabor_mu_z0_0p3nm=(tabor(R, W, Es) if W else None), attempts=attempt + 1)
        if effect == 'adhesion-md':
            p['h0'] = W / md_sigma0(R, Es, W, lam)
            p['sigma0'] = md_sigma0(R, Es, W, lam)
        if D0 is not None:
            p['H'] = 12 * np.pi * W * D0 ** 2
        return p
    raise RuntimeError('no draw for ' + effect)


def build_path(p, L):
    R, Es, e = p['R_true'], p['E_star'], p['effect']
    Pm = p['P_trig'] * 1.05
    if e in ('none', 'tip-radius-error'):
        return path_hertz(R, Es, hertz_delta(Pm, R, Es), L)
    if e in ('adhesion-dmt', 'jump-to-contact'):
        return path_dmt(R, Es, p['W'], p['D0'], hertz_delta(Pm + 2 * np.pi * p['W'] * R, R, Es), L)
    if e == 'adhesion-jkr':
        return path_jkr(R, Es, p['W'], Pm, L)
    if e == 'adhesion-md':
        return path_md(R, Es, p['W'], p['lam'], Pm, L)
    raise ValueError(e)


def trigger_z(path, k, P_trig):
    """z_rel on the final (loading) contact branch where P = P_trig."""
    z = path['delta'] + path['P'] / k
    P = path['P']
    i = np.where(P >= P_trig)[0][0]
    t = (P_trig - P[i - 1]) / (P[i] - P[i - 1])
    return float(z[i - 1] + t * (z[i] - z[i - 1])), float(path['delta'][i - 1] + t * (path['delta'][i] - path['delta'][i - 1]))


def ar1(rng, n, sigma, rho):
    e = np.empty(n)
    w = rng.normal(0, sigma * np.sqrt(1 - rho ** 2), n)
    e[0] = rng.normal(0, sigma)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + w[i]
    return e


# ------------------------------------------------------------------ plan of the 32 cases
def plan(rng):
    effects = (['adhesion-dmt', 'adhesion-jkr', 'adhesion-md', 'jump-to-contact', 'tip-radius-error'] * 4
               + ['none'] * 12)
    order = rng.permutation(len(effects))
    effects = [effects[i] for i in order]
    n = len(effects)
    cols = ['force_N'] * 11 + ['deflection_m'] * 11 + ['deflection_V'] * 10
    cols = [cols[i] for i in rng.permutation(n)]
    noseg = np.zeros(n, bool); noseg[rng.choice(n, 4, replace=False)] = True
    has_time = np.zeros(n, bool); has_time[rng.choice(n, 15, replace=False)] = True
    ar = np.zeros(n, bool); ar[rng.choice(n, 8, replace=False)] = True
    ndecl = np.zeros(n, bool); ndecl[rng.choice(n, 16, replace=False)] = True
    edecl = np.zeros(n, bool); edecl[rng.choice(n, 16, replace=False)] = True
    tip_idx = [i for i, e in enumerate(effects) if e == 'tip-radius-error']
    for j, i in enumerate(tip_idx):          # radius error identifiable only with a declared E: 3 of 4
        edecl[i] = j < 3
    return [dict(id='f%02d' % i, effect=effects[i], column=cols[i], segment_col=not noseg[i],
                 time_col=bool(has_time[i]), noise_kind='ar1' if ar[i] else 'white',
                 noise_declared=bool(ndecl[i]), E_declared=bool(edecl[i])) for i in range(n)]


def fmt(x):
    return '%.10g' % x


def make_case(rng, c):
    p = draw_physics(rng, c['effect'])
    k = p['k']
    # geometry: path far enough, piezo range
    path0 = build_path(p, 1e-6)
    zt, d_trig = trigger_z(path0, k, p['P_trig'])
    zp = path0['delta'] + path0['P'] / k
    z_lo = float(min(0.0, zp[path0['branch'] >= 0.5].min()))
    if p['effect'] in ('adhesion-dmt', 'jump-to-contact'):
        z_lo = min(z_lo, -2 * np.pi * p['W'] * p['R_true'] / k)
    free = max(rng.uniform(1.2, 3.5) * zt, rng.uniform(1.5, 3.0) * abs(z_lo) + rng.uniform(5e-9, 30e-9),
               rng.uniform(15e-9, 40e-9))
    path = build_path(p, free + 100e-9) if free + 100e-9 > 1e-6 else path0
    n_a = int(rng.integers(300, 2001))
    n_r = n_a if rng.random() < 0.55 else int(rng.integers(300, 2001))
    z_a = np.linspace(-free, zt, n_a)
    z_r = np.linspace(zt, -free, n_r + 1)[1:]
    sim = simulate(path, k, z_a, z_r)
    # instrument
    z_abs0 = rng.uniform(0, 1.5e-6)
    z_c = z_abs0 + free
    sens = rng.uniform(20e-9, 100e-9) if c['column'] == 'deflection_V' else None
    offset_d = rng.uniform(-20e-9, 20e-9)                      # deflection offset (m)
    tilt_tot = rng.choice([-1, 1]) * rng.uniform(0.02, 0.10) * p['P_trig'] / k   # virtual deflection over range
    tilt = tilt_tot / (free + zt)                              # m of deflection per m of z
    sig = p['sigma_F']
    rho = rng.uniform(0.5, 0.9) if c['noise_kind'] == 'ar1' else 0.0
    sig_r = sig
    rate_noise = False
    if n_r != n_a and not c['noise_declared'] and rng.random() < 0.5:
        sig_r = sig * np.sqrt(n_r / n_a)        # same duration, other sampling rate: other bandwidth
        rate_noise = True
    if rho:
        nF_a, nF_r = ar1(rng, n_a, sig, rho), ar1(rng, n_r, sig_r, rho)
    else:
        nF_a, nF_r = rng.normal(0, sig, n_a), rng.normal(0, sig_r, n_r)
    zA, zR = z_c + z_a, z_c + z_r
    defl_a = sim['P_a'] / k + offset_d + tilt * (zA - z_abs0) + nF_a / k
    defl_r = sim['P_r'] / k + offset_d + tilt * (zR - z_abs0) + nF_r / k
    z = np.r_[zA, zR]
    defl = np.r_[defl_a, defl_r]
    seg = np.r_[np.zeros(n_a, int), np.ones(n_r, int)]
    col = c['column']
    if col == 'force_N':
        val, unit_per_N = defl * k, 1.0
    elif col == 'deflection_m':
        val, unit_per_N = defl, 1.0 / k
    else:
        val, unit_per_N = defl / sens, 1.0 / (k * sens)
    # time
    v_a = logu(rng, 0.1e-6, 5e-6)
    T_a = (free + zt) / v_a
    T_r = T_a if (n_r != n_a and rng.random() < 0.6) or rng.random() < 0.5 else T_a * rng.uniform(0.3, 3)
    t0 = rng.uniform(0, 2.0) if rng.random() < 0.4 else 0.0
    t_a = t0 + np.linspace(0, T_a, n_a)
    t_r = t_a[-1] + np.linspace(0, T_r, n_r + 1)[1:]
    t = np.r_[t_a, t_r]
    # ---- write CSV
    header = ['z_m', col]
    cols = [z, val]
    if c['segment_col']:
        header.append('segment'); cols.append(seg)
    if c['time_col']:
        header.append('time_s'); cols.append(t)
    comment = rng.random() < 0.4
    with open(os.path.join(CASES, c['id'] + '.csv'), 'w') as f:
        if comment:
            f.write('# force curve export, %d + %d points\n' % (n_a, n_r))
        f.write(','.join(header) + '\n')
        for r in range(z.size):
            row = ['%.9e' % cols[0][r], '%.9e' % cols[1][r]]
            ci = 2
            if c['segment_col']:
                row.append('%d' % cols[ci][r]); ci += 1
            if c['time_col']:
                row.append('%.7f' % cols[ci][r])
            f.write(','.join(row) + '\n')
    # ---- write TOML
    lines = ['[measurement]', 'kind = "force"', 'data = "%s.csv"' % c['id'],
             'description = "AFM force curve %s"' % c['id'], '', '[lever]', 'k = %s' % fmt(k)]
    if sens is not None:
        lines.append('sensitivity = %s' % fmt(sens))
    lines += ['', '[tip]', 'radius = %s' % fmt(p['R_decl'])]
    if c['E_declared']:
        lines += ['E = %s' % fmt(E_TIP), 'nu = %s' % fmt(NU_TIP), '', '[sample]',
                  'E = %s' % fmt(p['E_s']), 'nu = %s' % fmt(p['nu_s'])]
    noise_decl = None
    corr_decl = False
    if c['noise_declared']:
        lines += ['', '[noise]']
        if col != 'force_N' and rng.random() < 0.5:
            noise_decl = ('deflection', sig * unit_per_N)
        else:
            noise_decl = ('force', sig)
        lines.append('%s = %s' % (noise_decl[0], fmt(noise_decl[1])))
        if rho and rng.random() < 0.6:
            lines.append('correlation = %s' % fmt(round(rho, 3)))
            corr_decl = True
    with open(os.path.join(CASES, c['id'] + '.toml'), 'w') as f:
        f.write('\n'.join(lines) + '\n')
    # ---- key
    jumps = []
    for j in sim['jumps']:
        jj = dict(j)
        jj['z_abs'] = j['z_rel'] + z_c
        jumps.append(jj)
    key = dict(c)
    key.update({kk: (float(v) if isinstance(v, (float, np.floating)) else v) for kk, v in p.items()})
    key.update(dict(
        z_contact_abs=z_c, z_start_abs=z_abs0, z_trigger_abs=z_c + zt, delta_trigger=d_trig,
        free_span=free, n_approach=n_a, n_retract=n_r, retract_excludes_turn_point=True,
        sensitivity=sens, deflection_offset_m=offset_d, force_offset_N=offset_d * k,
        tilt_deflection_per_z=tilt, tilt_force_per_z_N_per_m=tilt * k, tilt_reference_z=z_abs0,
        noise_rho=rho, sigma_F_retract=sig_r, rate_dependent_noise=rate_noise,
        sigma_column_unit=sig * unit_per_N, noise_declared_as=noise_decl, correlation_declared=corr_decl,
        speed_approach=v_a, T_approach=T_a, T_retract=T_r, time_start=t0, csv_comment_line=comment,
        min_force_retract_noiseless=float(sim['P_r'].min()), min_force_approach_noiseless=float(sim['P_a'].min()),
        jumps=jumps, identifiable_note=(
            'radius error degenerate with E* (no [sample] E declared)' if c['effect'] == 'tip-radius-error'
            and not c['E_declared'] else None)))
    key['adhesion_ideal_pulloff'] = {'adhesion-dmt': 2, 'jump-to-contact': 2, 'adhesion-jkr': 1.5}.get(
        c['effect'], None)
    if key['adhesion_ideal_pulloff']:
        key['adhesion_ideal_pulloff'] *= np.pi * p['W'] * p['R_true']
    # internal consistency: lever equilibrium and Hertz in contact
    zrel_a = sim['delta_a'] + sim['P_a'] / k
    key['check_equilibrium_max_abs_m'] = float(np.max(np.abs(zrel_a - z_a)))
    return key, sim, (z_a, z_r)


# ------------------------------------------------------------------ self-checks
def self_checks():
    out = []
    R, W, D0 = 20e-9, 0.1, 0.3e-9
    Es_h = estar(50e9, 0.3, E_TIP, NU_TIP)
    Es_s = estar(1e9, 0.3, E_TIP, NU_TIP)

    def run(path, k, zlo=-60e-9, n=4000, fine=(-3e-6, 3e-9)):
        zt = 0.9 * (path['delta'][-1] + path['P'][-1] / k)
        za = np.unique(np.r_[np.linspace(zlo, zt, n), np.linspace(max(fine[0], zlo), min(fine[1], zt), 200000)])
        zr = za[::-1][1:]
        res = simulate(path, k, za, zr)
        res['za'] = za
        return res

    out.append('Self-checks of the blind generator (physics.py), R = 20 nm, W = 0.1 J/m^2')
    out.append('Pull-off = most negative force along the quasi-static retract (dense z grid, noiseless).')
    for k in (1e4, 40.0):
        s = run(path_dmt(R, Es_h, W, D0, 2e-9, 200e-9), k)
        r = -s['P_r'].min() / (2 * np.pi * W * R)
        out.append('DMT (E*=%.3g GPa, D0=0.3 nm) k=%g N/m: pull-off / (2 pi W R) = %.5f  [%s, tol 1%%]'
                   % (Es_h / 1e9, k, r, 'PASS' if abs(r - 1) < 0.01 else 'FAIL'))
    for k in (1e4, 1.0):
        s = run(path_jkr(R, Es_s, W, 20e-9, 200e-9), k, fine=(-3e-8, 3e-9))
        r = -s['P_r'].min() / (1.5 * np.pi * W * R)
        jin = [j for j in s['jumps'] if j['kind'] == 'snap-in'][0]
        jout = [j for j in s['jumps'] if j['kind'] == 'pull-off'][0]
        out.append('JKR (E*=%.3g GPa) k=%g N/m: pull-off / (1.5 pi W R) = %.5f  [%s, tol 1%%]; '
                   'contact jump lands at P/(pi W R) = %.4f (stiff limit -4/3), retract fold at P/(pi W R) = %.4f '
                   '(stiff limit -5/6, soft limit -3/2)'
                   % (Es_s / 1e9, k, r, 'PASS' if abs(r - 1) < 0.01 else 'FAIL', jin['P_to'] / (np.pi * W * R),
                      jout['P_from'] / (np.pi * W * R)))
    for lam in (0.1, 0.3, 1.0, 3.0, 5.0):
        pth = path_md(R, Es_s, W, lam, 20e-9, 200e-9)
        s = run(pth, 1e3, fine=(-3e-8, 3e-9))
        pb = -s['P_r'].min() / (np.pi * W * R)
        line = 'MD lambda=%.1f (k=1e3 N/m): pull-off/(pi W R) = %.4f' % (lam, pb)
        if lam == 0.1:
            line += '  vs DMT 2: %.2f%% [%s, tol 3%%]' % (100 * (pb / 2 - 1), 'PASS' if abs(pb / 2 - 1) < 0.03 else 'FAIL')
        if lam == 5.0:
            line += '  vs JKR 1.5: %.2f%% [%s, tol 3%%]' % (100 * (pb / 1.5 - 1), 'PASS' if abs(pb / 1.5 - 1) < 0.03 else 'FAIL')
        j = pth['join']
        line += '; Dugdale non-contact/contact join: d_delta=%.2e m, dP=%.2e N' % (j[2] - j[0], j[3] - j[1])
        out.append(line)
    # JKR limit of MD at large lambda, and the known lambda=1 value of the transition
    # Hertz
    ph = path_hertz(R, Es_h, 3e-9, 100e-9)
    s = run(ph, 2.0, n=3000, fine=(0, 0))
    m = s['delta_a'] > 0.05e-9
    ref = 4 / 3 * Es_h * np.sqrt(R) * s['delta_a'][m] ** 1.5
    err = np.max(np.abs(s['P_a'][m] - ref) / ref)
    out.append('Hertz (k=2 N/m): simulated contact force vs (4/3) E* sqrt(R) delta^1.5: max rel. error %.2e [%s]'
               % (err, 'PASS' if err < 1e-3 else 'FAIL'))
    zrel = s['delta_a'] + s['P_a'] / 2.0
    out.append('  lever equilibrium: max |delta + P/k - z_rel| = %.2e m' % np.max(np.abs(zrel - s['za'])))
    # snap-in
    for k in (0.05, 0.1, 0.3, 40.0):
        pd = path_dmt(R, Es_h, W, D0, 2e-9, 200e-9)
        s = run(pd, k, fine=(-8e-9, 1e-9))
        jin = [j for j in s['jumps'] if j['kind'] == 'snap-in']
        H = pd['H']
        s_an = (H * R / (3 * k)) ** (1 / 3) - D0
        if s_an <= 0:
            out.append('snap-in k=%g: analytic fold inside contact (k > 4 pi W R / D0 = %.3g): %s' % (
                k, 4 * np.pi * W * R / D0, 'no snap-in PASS' if not jin else 'jump found (at s=%.3e)' % -jin[0]['delta_from']))
            continue
        s_sim = -jin[0]['delta_from']
        grad = H * R / (3 * (s_sim + D0) ** 3)
        out.append('snap-in k=%g N/m: simulated separation %.4f nm, analytic (HR/3k)^(1/3)-D0 = %.4f nm; '
                   'attraction gradient there dF/dD = %.4g N/m (k = %g): rel %.2e [%s]'
                   % (k, s_sim * 1e9, s_an * 1e9, grad, k, grad / k - 1, 'PASS' if abs(grad / k - 1) < 0.01 else 'FAIL'))
    return out


def main():
    os.makedirs(CASES, exist_ok=True)
    rng = np.random.default_rng(20240644)
    keys = []
    for c in plan(rng):
        key, sim, _ = make_case(rng, c)
        keys.append(key)
        print(c['id'], c['effect'], '%.3g' % key['k'], c['noise_kind'], c['noise_declared'], c['column'],
              'jumps=%d' % len(key['jumps']), flush=True)

    def clean(o):
        if isinstance(o, dict):
            return {k: clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        if isinstance(o, (np.floating,)):
            return float(o)
        if isinstance(o, (np.integer,)):
            return int(o)
        if isinstance(o, np.bool_):
            return bool(o)
        return o
    with open(os.path.join(HERE, 'KEY.json'), 'w') as f:
        json.dump(clean(dict(generator='benchmarks/blind_curves/gen.py', seed=20240644,
                             conventions='force/deflection > 0 repulsive; z increases towards the sample; '
                                         'recorded deflection = P/k + offset + tilt*(z - z_start) + noise/k',
                             cases=keys)), f, indent=1)
    if '--no-checks' not in sys.argv:
        lines = self_checks()
        with open(os.path.join(HERE, 'checks.txt'), 'w') as f:
            f.write('\n'.join(lines) + '\n')
        print('\n'.join(lines))


if __name__ == '__main__':
    main()
