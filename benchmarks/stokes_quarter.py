"""The 2D oscillatory Stokes section solved on one quadrant with the motions' mirror conditions (session 41)
against the whole disc, in one process, as ratios, with the agreement of the hydrodynamic functions.

Usage: ``python benchmarks/stokes_quarter.py [OUT.json]`` (default ``benchmarks/results/stokes_quarter.json``).

For each Re (0.01, 10, 1e3, 1.3e4: the thinnest of the zero-thickness extrapolation's three sections, refine 0.7,
the tests' and the truths' mesh), both forms are meshed, assembled and solved for both motions
(:class:`~probedyn.fem.stokes2d.StokesSection`; the whole disc factorises once for both motions, the quadrant
once per motion: their constrained velocity components differ). Reported: the wall time of each (best of
``REPEAT``), their ratio, the unknowns, and the relative difference of each part of Gamma per motion. The two
meshes are different meshes of the same sizes, so the difference is the discretisation's, not the symmetry's:
both are within ~1e-4 of the converged value at Re <= 1e3 (:mod:`probedyn.fem.stokes2d`).
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import probedyn  # noqa: F401  (before numpy: thread settings)
from probedyn.core.io import write_json

ROOT = Path(__file__).resolve().parents[1]
REPEAT = 2
REFINE = 0.7


def one(re: float, quarter: bool) -> tuple[float, dict, int]:
    """(best wall time [s], {motion: Gamma}, unknowns) of mesh + assembly + both solves."""
    from probedyn.fem.stokes2d import StokesSection, default_r_out, thin_thicknesses
    from probedyn.meshes.section2d import default_sizes, section_mesh

    t = 2.0 * thin_thicknesses(re)[2]
    sizes = default_sizes(t, math.sqrt(2.0 / re), REFINE)
    best, sol, n = math.inf, None, 0
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        system = StokesSection(section_mesh(t, default_r_out(re), quarter=quarter, **sizes))
        sol = system.solve(re)
        best = min(best, time.perf_counter() - t0)
        n = int(system.nu + system.npr)
    return best, {m: f.gamma for m, f in sol.items()}, n


def main(argv: list[str]) -> dict:
    out = Path(argv[1]) if len(argv) > 1 else ROOT / "benchmarks" / "results" / "stokes_quarter.json"
    rows = []
    for re in (0.01, 10.0, 1e3, 1.3e4):
        t_w, g_w, n_w = one(re, False)
        t_q, g_q, n_q = one(re, True)
        rows.append(dict(re=re, whole_s=t_w, quarter_s=t_q, ratio=t_w / t_q, unknowns_whole=n_w, unknowns_quarter=n_q,
                         rel_diff={m: [abs(g_q[m].real / g_w[m].real - 1), abs(g_q[m].imag / g_w[m].imag - 1)]
                                   for m in g_w},
                         gamma_quarter={m: [g.real, g.imag] for m, g in g_q.items()}))
    res = dict(refine=REFINE, rows=rows,
               ratio_min=min(r["ratio"] for r in rows), ratio_max=max(r["ratio"] for r in rows),
               worst_rel_diff=max(max(v) for r in rows for v in r["rel_diff"].values()))
    write_json(out, res, defer=False)
    print(json.dumps(res, indent=1))
    return res


if __name__ == "__main__":
    main(sys.argv)
