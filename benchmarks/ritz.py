"""Ritz reduction (probedyn.lumped.ritz) against full FEM re-solves: the numbers of
docs/reduced-probes.md, section "Verification".

Model: the default cantilever (300 x 30 x 10 um, silicon) on the coarse mesh of the tests (one
P2 layer through the thickness, 6.2k DOFs) or, with ``--fine``, on the default mesh (two
layers, 23k DOFs).  Every reference is a full FEM model re-assembled with the same
``PointMass`` / ``Spring`` (``ElasticModel.assemble``) and solved by shift-invert.

Prints, for n = 2, 4, 8, 16 retained modes, the relative error of the first frequency

* (b) at the tip apex point: a mass of a quarter of the beam mass, a 50 N/m spring along z,
  a stiff isotropic spring (1e5 N/m), without and with the static correction shapes of the tip;
* (c) a quarter-beam mass at an interior point (0.6 L on the mid-plane), modes only, with the
  observed rate d log(err) / d log(n);

and the wall time of a Ritz solve against the FEM re-solve (same process; the machine may be
shared).  Usage: ``.venv/bin/python benchmarks/ritz.py [--fine]``.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from probedyn.fem.model import ElasticModel, PointMass, Spring  # noqa: E402
from probedyn.lumped.ritz import RitzBasis  # noqa: E402
from probedyn.probes import get_probe  # noqa: E402


def variant(model, point_masses=(), springs=()):
    regions = {n: (m, R) for n, m, R in zip(model.region_names, model.materials, model.orientations)}
    return ElasticModel(model.bundle, regions, clamp=model.clamp, point_masses=list(point_masses),
                        springs=list(springs), tip=model.tip, beam_axis=model.beam_axis)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--fine", action="store_true", help="default mesh (2 layers) instead of 1 layer")
    args = ap.parse_args()
    p, _ = get_probe("cantilever")
    v = p.resolve({"elements_through_thickness": 2 if args.fine else 1})
    model = p.build(v)
    mb = p.beam(v).mass
    print(f"cantilever, {model.dofs} DOFs")
    ns = (2, 4, 8, 16)
    bases = {}
    t_ritz_build = {}
    for n in ns:
        for att in ((), ("tip",)):
            t0 = time.perf_counter()
            bases[(n, att)] = RitzBasis.from_model(model, n, attachments=att)
            t_ritz_build[(n, att)] = time.perf_counter() - t0
    cases = {
        "tip mass m_b/4": dict(point_masses=[PointMass("tip", 0.25 * mb)]),
        "tip spring 50 N/m (z)": dict(springs=[Spring("tip", None, 50.0, (0, 0, 1))]),
        "stiff tip spring 1e5 N/m": dict(springs=[Spring("tip", None, 1e5, None)]),
    }
    print("\n(b) relative error of f1, Ritz vs full FEM re-solve")
    print("| addition | f1 FEM [Hz] | " + " | ".join(f"n={n} modes / + static" for n in ns) + " |")
    print("|---|---|" + "---|" * len(ns))
    for name, add in cases.items():
        t0 = time.perf_counter()
        ref = variant(model, **add).modes(2).frequencies_hz
        t_fem = time.perf_counter() - t0
        cells = []
        for n in ns:
            e = []
            for att in ((), ("tip",)):
                t0 = time.perf_counter()
                f = bases[(n, att)].solve(n=1, **add).frequencies_hz[0]
                t_solve = time.perf_counter() - t0
                e.append(f / ref[0] - 1)
            cells.append(f"{e[0]:.1e} / {e[1]:.1e}")
        print(f"| {name} | {ref[0]:.0f} | " + " | ".join(cells) + " |")
        print(f"   (FEM re-solve {t_fem:.2f} s, Ritz solve {t_solve * 1e3:.2f} ms, ratio {t_fem / t_solve:.0f})")
    print("\n(c) quarter-beam mass at (0.6 L, 0, 0), modes only")
    pm = [PointMass((0.6 * v["length"], 0.0, 0.0), 0.25 * mb)]
    ref = variant(model, point_masses=pm).modes(1).frequencies_hz[0]
    full = RitzBasis.from_model(model, 32)
    ns2 = (2, 4, 8, 16, 32)
    errs = np.array([full.leading(n).solve(pm, n=1).frequencies_hz[0] / ref - 1 for n in ns2])
    rates = np.log(errs[1:] / errs[:-1]) / np.log(np.array(ns2[1:]) / np.array(ns2[:-1]))
    for n, e in zip(ns2, errs):
        print(f"  n={n:2d}: {e:.2e}")
    print("  observed rates:", ", ".join(f"{a}->{b}: {r:.2f}" for a, b, r in zip(ns2[:-1], ns2[1:], rates)))
    print("\nRitz build times [s]:", {f"{n}{'+tip' if att else ''}": round(t, 2) for (n, att), t in t_ritz_build.items()})


if __name__ == "__main__":
    main()
