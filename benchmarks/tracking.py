"""Path tracking: the exponential integrator (exact for the linear part) vs plain solve_ivp.

One 1-second conic path (Fig 3.21's cone, R = H = 0.5 um, 2 turns) at the stiffest holder of
section 3.4.1 (k_t = 100 N/m), piezotube with delta_x = delta_y = 5 um, composite control
(kappa = 0, zeta_s = 0.7, zeta_f = 1.0: the stable design at this stiffness), analytic gains.
Runs in the same process, so the ratios are meaningful on a shared machine:

* ETD2 (probedyn, default step 250 us: only the path has to be resolved);
* solve_ivp RK45, no Jacobian (scipy's default method), rtol 1e-6;
* solve_ivp Radau with the analytic Jacobian A_cl, rtol 1e-6;
* reference: solve_ivp Radau with the analytic Jacobian, rtol 1e-9, atol 1e-10 of the path size
  (an earlier rtol 1e-11 / atol 1e-24 m asked for digits below round-off and never finished).

Accuracy = max |y - y_ref| over 201 common times, relative to the path size.
The reference needs ~10^6 Radau steps on the 1 s path (the 45.7 kHz mode is resolved at rtol 1e-9)
and did not finish within 25 minutes on the shared machine; `--duration 0.05` runs the same cone
(two turns, 20x faster) for the accuracy column.
Run: .venv/bin/python benchmarks/tracking.py [--with-kbr] [--with-rk45] [--duration T]   (RK45 without a
Jacobian takes ~1000 s: it is run only when asked.)
"""

from __future__ import annotations

import sys
import time

import numpy as np

from probedyn.probes.tracking import control_plant
from probedyn.schemes.tracking import controllers as ctl
from probedyn.schemes.tracking import simulate as S
from probedyn.schemes.tracking import studies
from probedyn.schemes.tracking.disturbance import kbr


def main() -> None:
    kb = "--with-kbr" in sys.argv
    rk45 = "--with-rk45" in sys.argv
    T = float(sys.argv[sys.argv.index("--duration") + 1]) if "--duration" in sys.argv else 1.0
    plant = control_plant(k_t=100.0)
    law = ctl.CompositeControl(0.0, 0.7, 1.0).design(plant)
    st = ctl.stability(plant, law)
    path = studies.build_path("cone", "piezotube", duration=T)
    surf = kbr(1.0) if kb else None
    t_eval = np.linspace(0.0, T, 201)
    print(f"plant modes [Hz]: {np.round(plant.frequencies_hz(), 1)}; closed loop stable: {st['stable']} "
          f"(min damping {st['min_damping_ratio']:.3g}); KBr disturbance: {kb}; path duration {T} s")

    S.simulate(plant, law, studies.build_path("cone", "piezotube", duration=0.01))  # compile the kernel
    t0 = time.perf_counter()
    r_e = S.simulate(plant, law, path, surface=surf, max_points=10**6)
    t_etd = time.perf_counter() - t0
    print(f"  ... ETD2: {t_etd:.3f} s", flush=True)

    def at(res):
        return np.array([np.interp(t_eval, res.t, res.y[:, j]) for j in range(res.y.shape[1])]).T

    runs = {}
    REF = "reference: Radau + Jacobian, rtol 1e-9"
    cases = ((("RK45, no Jacobian", {"method": "RK45", "rtol": 1e-6}),) if rk45 else ()) + (
        ("Radau, analytic Jacobian", {"method": "Radau", "jac": True, "rtol": 1e-6}),
        (REF, {"method": "Radau", "jac": True, "rtol": 1e-9, "atol": 1e-10 * 0.5e-6}))
    for name, kw in cases:
        t0 = time.perf_counter()
        r = S.simulate_ivp(plant, law, path, surface=surf, t_eval=t_eval, **kw)
        runs[name] = (time.perf_counter() - t0, r)
        print(f"  ... {name}: {runs[name][0]:.3f} s", flush=True)
    ref = runs[REF][1].y
    size = 0.5e-6
    print(f"{'integrator':42s} {'wall [s]':>9s} {'/ ETD2':>8s} {'max|y - y_ref| / size':>22s} {'RHS calls':>10s}")
    print(f"{'ETD2 exponential (h = %.3g s, %d steps)' % (r_e.info['step_s'], r_e.info['steps']):42s} "
          f"{t_etd:9.3f} {1.0:8.1f} {np.max(np.abs(at(r_e) - ref)) / size:22.3e} {'-':>10s}")
    for name, (w, r) in runs.items():
        acc = np.max(np.abs(r.y - ref)) / size
        print(f"{name:42s} {w:9.3f} {w / t_etd:8.1f} {acc:22.3e} {r.info['nfev']:10d}")
    print("(timings on a shared machine: compare the ratios)")


if __name__ == "__main__":
    main()
