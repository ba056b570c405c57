"""Discretisation error of the diagnosis' FEM mesh on a thin lever, against a converged mesh.

Usage: ``python benchmarks/diagnose_thin_lever_mesh.py [LENGTH WIDTH THICKNESS]`` (SI; default the
200 x 30 x 2 um silicon lever of the session-6 ``thermal_psd_air``). Prints the relative frequency error of
flapwise 1-4, lateral 1 and torsion 1 for: the diagnosis' mesh (``thickness_stretch``: meshed
``s`` times thicker and stretched back), its Richardson companion (1 layer, the same stretch), the
same stretch with an axial element size of 2 t, against an unstretched mesh with 4 layers (the
truth mesh of ``tests/diagnose_truth.py``; checked against 3 layers unstretched). ~90 s CPU.

Measured (session 7, 200 x 30 x 2 um, s = 6.27): the diagnosis mesh (6.4k DOFs) is stiff by
+0.075 / +0.32 / +0.71 / +1.28 % (flapwise 1-4), +0.02 % (lateral), +0.57 % (torsion), while
its Richardson estimate (3 -> 1 layers) reports 0.03-0.13 %: the layers through the thickness are
halved but the axial size (t s, 6x the thickness) is not, and the error is axial. With
element_size = 2 t the flapwise errors are <= 0.1 %; torsion stays +0.57 % (the width elements are
s times coarser too). Levers with t = 10 um (the rate studies, s <= 1.5) are not affected.
"""

from __future__ import annotations

import sys
import time

from probedyn.diagnose.modal_model import build_within_budget, thickness_stretch
from probedyn.probes import get_probe

MODES = {"flapwise": 4, "lateral": 1, "torsion": 1}


def freqs(probe, values, s):
    t0 = time.process_time()
    m = build_within_budget(probe, values, s)
    out: dict[str, list[float]] = {}
    for md in m.modes(10).modes:
        out.setdefault(md.family, []).append(md.frequency_hz)
    return {fa: out[fa][:n] for fa, n in MODES.items()}, m.dofs, time.process_time() - t0


def main(argv: list[str]) -> int:
    L, w, t = (float(x) for x in argv[:3]) if len(argv) >= 3 else (200e-6, 30e-6, 2e-6)
    p = get_probe("cantilever")[0]
    base = p.resolve(dict(length=L, width=w, thickness=t, elements_through_thickness=3))
    s = thickness_stretch(base)
    ref, n_ref, c_ref = freqs(p, dict(base, elements_through_thickness=4), 1.0)
    print(f"reference: 4 layers unstretched, {n_ref} DOFs, {c_ref:.1f} s CPU")
    for label, vals, st in (("3 layers unstretched", base, 1.0), ("diagnosis mesh", base, s),
                            ("Richardson companion (1 layer)", dict(base, elements_through_thickness=1), s),
                            ("diagnosis mesh, element_size 2 t", dict(base, element_size=2 * t), s)):
        f, n, c = freqs(p, vals, st)
        err = {fa: [round(100 * (a / b - 1), 3) for a, b in zip(f[fa], ref[fa])] for fa in MODES}
        print(f"{label} (s = {st:.2f}, {n} DOFs, {c:.1f} s CPU): error % {err}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
