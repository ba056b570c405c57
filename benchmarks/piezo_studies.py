"""The numbers of docs/piezo.md on the default meshes of both smart probes (slow: ~15 min on a
shared 2-core machine).  Output: benchmarks/results/piezo_studies.txt.

1. drive patterns: tip displacement per volt (duo-bimorph parallel and series poling; piezotube
   quarters and 12 sectors), blocked force at the tip attachment;
2. short/open-circuit modes and k_eff^2 of the first modes (default probes);
3. Gamma from the FEM vs the corrected formula for delta_x = delta_y = 1..5 um, lambda_min;
4. modal actuation (8 modes): static truncation at the tip;
5. duo-bimorph mesh convergence of the per-volt deflection at x = L (bare actuator).

Usage: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/piezo_studies.py [part ...]``
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from probedyn.lumped import actuation as act  # noqa: E402
from probedyn.probes import piezo as P  # noqa: E402

np.set_printoptions(precision=5, suppress=True, linewidth=150)


def patterns() -> None:
    for name, kw in (("duo-bimorph", {"poling": "parallel"}), ("duo-bimorph", {"poling": "series"}),
                     ("piezotube", {"layout": "quarters"}), ("piezotube", {"layout": "sectors"})):
        t0 = time.perf_counter()
        probe, values, pm, setup = P.piezo_model(name, {}, **kw)
        pts = ["holder_end", "tube_end"] if name == "piezotube" else ["holder_end", "free_end_centre"]
        rows = P.actuation_table(pm, setup, kw.get("layout"), points=pts)
        print(f"\n{name} {kw}: {rows[0]['dofs']} DOFs ({time.perf_counter() - t0:.1f} s)")
        for r in rows:
            print(f"  {r['pattern']:8s} tip [nm/V] {np.array(r['tip_m_per_V']) * 1e9}  "
                  + "  ".join(f"{p} {np.array(r[p + '_m_per_V']) * 1e9}" for p in pts[1:]))
        if kw.get("poling", "parallel") == "parallel" and kw.get("layout", "quarters") == "quarters":
            for pat in setup.patterns[setup.default_layout]:
                t0 = time.perf_counter()
                b = P.blocked_force(pm, setup.pattern(None, pat), "holder_end")
                print(f"  blocked force at holder_end, {pat}: along {b['axis']} only {b['blocked_force_axis'] * 1e9} nN/V, "
                      f"all components held {b['blocked_force'] * 1e9} nN/V, "
                      f"free {b['free_displacement'] * 1e9} nm/V, compliance diag {np.diag(b['compliance'])} m/N "
                      f"({time.perf_counter() - t0:.1f} s)")


def coupling() -> None:
    for name in ("duo-bimorph", "piezotube"):
        for ov in ({}, {"holder": "point", "tip": "none"}):
            probe, values, pm, setup = P.piezo_model(name, ov)
            t = P.coupling_table(pm, 6)
            print(f"\n{name} {ov or 'default'}: {t['dofs']} DOFs; modal sc {t['modal_s_short']:.1f} s, "
                  f"oc {t['modal_s_open']:.1f} s ({t['solver']}); reference {pm.reference}")
            for r in t["rows"]:
                print(f"  mode {r['mode']} {r['family']:9s} f_sc {r['f_sc_hz']:12.4f}  f_oc {r['f_oc_hz']:12.4f}  "
                      f"shift {100 * r['shift']:8.4f} %  k_eff^2 {r['k_eff2']:.5f}")


def gamma() -> None:
    rows = P.gamma_study([1e-6, 2e-6, 3e-6, 4e-6, 5e-6], {})
    for r in rows:
        G, F = r["fem"], r["formula"]
        print(f"\ndelta_x = delta_y = {r['delta'] * 1e6:g} um (FEM {r['fem_s']:.1f} s)")
        print("  FEM normalised\n", G.normalised)
        print("  formula normalised\n", F.normalised)
        print(f"  lambda_min FEM {G.lambda_min():.5f} formula {F.lambda_min():.5f}; sym. part min FEM "
              f"{G.symmetric_part_min():.5f} formula {F.symmetric_part_min():.5f}; raw lambda_min FEM "
              f"{G.lambda_min(False) * 1e9:.4f} nm/V formula {F.lambda_min(False) * 1e9:.4f} nm/V")
        print("  FEM reference diag [nm/V]", G.reference * 1e9, " formula", F.reference * 1e9)
    print("\nprinted 3.39 with minimal fixes at delta 5 um (rows 1-2 m^2, row 3 m):\n",
          act.gamma_matrix_printed(0.5e-3, 0.45e-3, 5e-6, 5e-6))


def modal() -> None:
    for name in ("duo-bimorph", "piezotube"):
        probe, values, pm, setup = P.piezo_model(name, {})
        t0 = time.perf_counter()
        ma = P.modal_actuation(pm, 8)
        print(f"\n{name}: modal actuation, 8 modes ({time.perf_counter() - t0:.1f} s)")
        for j, e in enumerate(ma.electrodes):
            print(f"  {e:24s} static tip {ma.static_tip[j] * 1e9} nm/V, 8-mode sum {ma.modal_static_tip[j] * 1e9}, "
                  f"truncation {ma.truncation[j]:.2e}")
        print("  modal force per volt [N/V] (modes x electrodes):\n", ma.modal_force)


def duo_convergence() -> None:
    for es in (15e-6, 10e-6, 7.5e-6, 5e-6, 3.75e-6):
        r = P.range_point("duo-bimorph", {"element_size": es})
        pv = r["per_volt"]
        print(f"element {es * 1e6:5.2f} um  {r['dofs']:7d} DOFs  V_z {pv['V_z'][2] * 1e9:.4f}  V_y {pv['V_y'][1] * 1e9:.4f} nm/V "
              f"({r['solve_s']:.1f} s)")


PARTS = {"patterns": patterns, "coupling": coupling, "gamma": gamma, "modal": modal, "convergence": duo_convergence}

if __name__ == "__main__":
    for part in sys.argv[1:] or list(PARTS):
        print(f"\n===== {part}", flush=True)
        PARTS[part]()
        sys.stdout.flush()
