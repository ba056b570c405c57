"""How a beam section's thickness changes its hydrodynamic functions: Gamma(Re, t/w) / Gamma(Re, 0) - 1 for flexure
(Sader's Gamma_rect is the zero-thickness limit) and torsion (Green & Sader's), from probedyn's own 2D oscillatory
Stokes solver (:mod:`probedyn.fem.stokes2d`; conventions in ``benchmarks/torsional_gamma_table.py``).

For each Re = 10^k, k = -1 .. 4 and t/w in THICKNESS_RATIOS: the zero-thickness limit (three thin solves and
Richardson extrapolation, :func:`~probedyn.fem.stokes2d.thin_limit`) and one solve of the section at t/w, on the
same default mesh (the mesh error largely cancels in the ratio). Reported per point: the relative change of
Gamma_r (added mass) and of Gamma_i (damping) for each motion.

Checks printed: (i) the change vanishes linearly as t/w -> 0 (Re <= 100: the ratio of the changes at 0.05 and 0.02
against 2.5); (ii) at large Re the flexural added mass tends to the inviscid added mass of a rectangle (potential
flow; DNV-RP-C205 (2010) Table A-1, rectangle of sides 2a along the motion and 2b across it: C_A = 1.14, 1.21, 1.36
at a/b = 0.1, 0.2, 0.5), which it approaches from below as the boundary layer thins.

Used by :func:`probedyn.diagnose.hydrodynamics.section_thickness_change` (the table, copied there) and the modal
diagnosis' section-thickness model-form direction (docs/diagnose.md section 9.22).

Run:  .venv/bin/python benchmarks/section_thickness_table.py   (about 10 min on a shared 2-core machine)
Output: benchmarks/results/section_thickness_table.json and a printed table.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # complex SuperLU is ~100x slower with OpenBLAS threads

from probedyn.diagnose.hydrodynamics import THICKNESS_LOG10_RE, THICKNESS_RATIOS  # noqa: E402
from probedyn.fem.stokes2d import build_section_system, thin_limit  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "section_thickness_table.json"
LOG10_RE = tuple(float(x) for x in THICKNESS_LOG10_RE)  # the grid the diagnosis interpolates on
#: inviscid added-mass coefficients of a rectangle (DNV-RP-C205, Table A-1) at a/b = t/w
DNV_CA = {0.1: 1.14, 0.2: 1.21, 0.5: 1.36}


def main() -> dict:
    rows = []
    t0 = time.time()
    for k in LOG10_RE:
        re = 10.0**k
        zero = thin_limit(re, ("translate", "rotate"))
        g0 = {m: zero[m].gamma for m in zero}
        for h in (float(x) for x in THICKNESS_RATIOS):
            sol = build_section_system(re, h).solve(re, ("translate", "rotate"))
            row = {"log10_Re": k, "t_over_w": h}
            for m, key in (("translate", "flex"), ("rotate", "tor")):
                g = sol[m].gamma
                row[f"{key}_dr"] = g.real / g0[m].real - 1.0
                row[f"{key}_di"] = g.imag / g0[m].imag - 1.0
            rows.append(row)
            print(json.dumps(row), flush=True)
    checks = {"linear_in_t_ratio_005_002": {r["log10_Re"]: None for r in rows}}
    for k in LOG10_RE:
        a = next(r for r in rows if r["log10_Re"] == k and r["t_over_w"] == 0.05)
        b = next(r for r in rows if r["log10_Re"] == k and r["t_over_w"] == 0.02)
        checks["linear_in_t_ratio_005_002"][k] = a["flex_dr"] / b["flex_dr"]
    checks["inviscid_added_mass"] = {
        str(h): {"dnv_ca_minus_1": ca - 1.0,
                 "flex_dr_at_Re_1e4": next(r["flex_dr"] for r in rows if r["log10_Re"] == 4.0 and r["t_over_w"] == h)}
        for h, ca in DNV_CA.items()}
    out = {"rows": rows, "checks": checks, "seconds": time.time() - t0}
    tmp = OUT.with_suffix(".tmp")
    tmp.write_text(json.dumps(out, indent=1))
    os.replace(tmp, OUT)
    print(json.dumps(checks, indent=1))
    return out


if __name__ == "__main__":
    main()
