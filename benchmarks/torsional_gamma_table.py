"""Torsional hydrodynamic function Gamma_tor(Re) of a thin rectangular beam section, from our own
finite-element solver (:mod:`probedyn.fem.stokes2d`), validated by the flexural function against
Sader's Gamma_rect (:func:`probedyn.diagnose.hydrodynamics.sader_gamma`).

Conventions (fem/stokes2d.py): Re = rho omega b^2 / (4 eta); Gamma = Gamma_r + i Gamma_i with
Gamma_i > 0 the dissipative part; flexure normalised as Sader (1998) (-> 1 at large Re); torsion by the
inviscid added moment of inertia of a flat plate pi rho b^4 / 128 (-> 1 at large Re; a function defined
with the prefactor (pi/8) rho omega^2 b^4, b the full width, is ours / 16).

For each Re = 10^k, k = -1 .. 4 in steps of 0.25:

* zero thickness: solves at h/b = h0, h0/2, h0/4 (h0 = min(0.005, 0.04 delta/b),
  :func:`~probedyn.fem.stokes2d.thin_thicknesses`) and quadratic Richardson extrapolation in h
  (the dependence is linear once h << a and h < ~0.04 delta; error = |quadratic - linear|);
* mesh: the whole extrapolation on the default mesh (refine 1) and on a sqrt(2)-times finer one; the
  table gives the finer, with |fine - default| as its mesh error (convergence studies: the error of the
  finer mesh is 2-3x smaller than this difference, order ~3 in the mesh size);
* error estimate = mesh + thickness-extrapolation + outer-radius error (1e-4 |Gamma| for translation,
  whose dipole far field feels the outer circle; the rotational flow does not).

Then: the large-Re asymptote fitted on Re >= 10^2.5 (for Re > 1e4), with the boundary-layer log term
fixed by theory, Gamma - 1 = k (1 + i) sqrt(2)/(2 pi) ln(Re)/sqrt(Re) + c/sqrt(Re) + e/Re + f ln(Re)/Re
(k = 1 flexure, 2 torsion; :data:`LOG_COEF`), and with a free log coefficient to compare; the low-Re
behaviour (Re Gamma_tor -> 16 i: steady Stokes torque of a plate 2 pi eta Omega a^2); the check of the
reaction force against the direct stress integral.

Run:  .venv/bin/python benchmarks/torsional_gamma_table.py [--step 0.25] [--refine 1.0 1.4142] [--refit]
Output: a printed table and benchmarks/results/torsional_gamma_table.json (16 min on a shared 2-core
machine; ``--refit`` redoes only the analysis of the stored rows).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # complex SuperLU is ~100x slower with OpenBLAS threads

import numpy as np  # noqa: E402

from probedyn.diagnose.hydrodynamics import TORSION_LOG_COEF, sader_gamma  # noqa: E402
from probedyn.fem.stokes2d import (MOTIONS, build_section_system, stress_integral, thin_limit,  # noqa: E402
                                   thin_thicknesses)

OUT = Path(__file__).resolve().parent / "results" / "torsional_gamma_table.json"
R_OUT_REL_ERROR = 1e-4  # translation only (fem.stokes2d.default_r_out)


def sader(re: float) -> complex:
    """Sader's Gamma_rect at our Re (half-width 1, rho = eta = 1: omega = Re)."""
    return complex(sader_gamma(re, 2.0, 1.0, 1.0))


def point(re: float, refines) -> dict:
    t0 = time.time()
    lims = [thin_limit(re, MOTIONS, refine=r) for r in refines]
    fine = lims[-1]
    row = {"Re": re, "thickness_ratios": list(fine["rotate"].thickness_ratios), "refine": list(refines)}
    for m, key in (("rotate", "tor"), ("translate", "flex")):
        g = fine[m].gamma
        mesh_err = abs(g - lims[-2][m].gamma) if len(lims) > 1 else float("nan")
        thin_err = fine[m].error
        r_err = R_OUT_REL_ERROR * abs(g) if m == "translate" else 0.0
        row.update({f"{key}_r": g.real, f"{key}_i": g.imag, f"{key}_err": mesh_err + thin_err + r_err,
                    f"{key}_err_mesh": mesh_err, f"{key}_err_thin": thin_err,
                    f"{key}_at_h": [[v.real, v.imag] for v in fine[m].values],
                    f"{key}_coarse": [lims[0][m].gamma.real, lims[0][m].gamma.imag]})
    s = sader(re)
    row.update({"sader_r": s.real, "sader_i": s.imag, "rel_diff_r": row["flex_r"] / s.real - 1.0,
                "rel_diff_i": row["flex_i"] / s.imag - 1.0,
                "rel_diff_abs": abs(complex(row["flex_r"], row["flex_i"]) / s - 1.0), "seconds": time.time() - t0})
    return row


#: boundary-layer theory: a Stokes layer under the potential flow's slip velocity u_s adds (1 + i) (delta / 2)
#: int |u_s|^2 ds / (added mass or moment of inertia / rho) to Gamma; the slip ~ 1/sqrt(distance to the edge) of a
#: flat plate makes the integral logarithmic, cut off at ~delta: Gamma - 1 = k (1 + i) sqrt(2) / (2 pi) ln(Re) /
#: sqrt(Re) + O(1/sqrt(Re)), k = 1 for translation (u_s = U x / sqrt(a^2 - x^2)), k = 2 for rotation
#: (u_s = Omega (x^2 - a^2/2) / sqrt(a^2 - x^2))
LOG_COEF = {"flex": TORSION_LOG_COEF / 2.0, "tor": TORSION_LOG_COEF}
FORMS = {  # name: (columns of the fitted terms, whether the theoretical log term is subtracted first)
    "theory_log": (lambda re: [1 / np.sqrt(re), 1 / re, np.log(re) / re], True),
    "free_log": (lambda re: [1 / np.sqrt(re), np.log(re) / np.sqrt(re), 1 / re], False),
}
TERMS = {"theory_log": ("/sqrt(Re)", "/Re", "ln(Re)/Re"), "free_log": ("/sqrt(Re)", "ln(Re)/sqrt(Re)", "/Re")}


def fit_asymptote(rows, key: str, re_min: float = 10**2.5) -> dict:
    """Least-squares fits (real and imaginary parts separately) on Re >= re_min of
    ``theory_log``: Gamma - 1 = LOG_COEF (1 + i) ln(Re) / sqrt(Re) + c / sqrt(Re) + e / Re + f ln(Re) / Re, and
    ``free_log``: Gamma - 1 = (c + d ln Re) / sqrt(Re) + e / Re (the log coefficient d fitted, to compare)."""
    sel = [r for r in rows if r["Re"] >= re_min * (1 - 1e-9)]
    re = np.array([r["Re"] for r in sel])
    g = np.array([complex(r[f"{key}_r"], r[f"{key}_i"]) for r in sel]) - 1.0
    out = {"Re_range": [float(re.min()), float(re.max())], "points": len(sel), "log_coef_theory": LOG_COEF[key]}
    for name, (cols, theory) in FORMS.items():
        X = np.column_stack(cols(re))
        base = LOG_COEF[key] * np.log(re) / np.sqrt(re) if theory else 0.0 * re
        coef = [np.linalg.lstsq(X, part - base, rcond=None)[0] for part in (g.real, g.imag)]
        res = [np.abs(X @ c + base - part).max() for c, part in zip(coef, (g.real, g.imag))]
        out[name] = {"terms": TERMS[name], "coef_r": coef[0].tolist(), "coef_i": coef[1].tolist(),
                     "max_residual_r": float(res[0]), "max_residual_i": float(res[1])}
    return out


def asymptote(fit: dict, key: str, re: float, form: str = "theory_log") -> complex:
    """The fitted large-Re form at ``re`` (for Re > 1e4)."""
    cols, theory = FORMS[form]
    x = np.array(cols(np.array(float(re))), dtype=float)
    base = LOG_COEF[key] * math.log(re) / math.sqrt(re) if theory else 0.0
    return 1.0 + complex(base + x @ fit[form]["coef_r"], base + x @ fit[form]["coef_i"])


def stress_check(re: float = 10.0) -> dict:
    """Reaction vs direct stress integral, at the thinnest h of the table and three meshes."""
    hb = thin_thicknesses(re)[2]
    out = {"Re": re, "thickness_ratio": hb, "rows": []}
    for ref in (1.0, math.sqrt(2.0), 2.0):
        sol = build_section_system(re, hb, refine=ref).solve(re)
        for m in MOTIONS:
            f = sol[m]
            out["rows"].append({"motion": m, "refine": ref, "reaction": [f.load.real, f.load.imag],
                                "stress_integral": [stress_integral(f).real, stress_integral(f).imag]})
    return out


def analyse(rows) -> dict:
    """Large-Re fits, low-Re limit and the flexural comparison's summary, printed."""
    fits = {key: fit_asymptote(rows, key) for key in ("tor", "flex")}
    for key, fit in fits.items():
        print(f"{key}: large Re, fitted on Re {fit['Re_range'][0]:.4g} .. {fit['Re_range'][1]:.4g}"
              f" (theory: ln(Re)/sqrt(Re) coefficient {LOG_COEF[key]:.4f} (1 + i))")
        for form in FORMS:
            f = fit[form]
            terms = " + ".join(f"({a:+.4f}{b:+.4f}j) {t}" for a, b, t in zip(f["coef_r"], f["coef_i"], f["terms"]))
            print(f"  {form:10s}: Gamma - 1 = {'theory log + ' if FORMS[form][1] else ''}{terms}"
                  f"   max residual {f['max_residual_r']:.1e}, {f['max_residual_i']:.1e}")
        fit["extrapolated"] = {}
        for re in (1e5, 1e6):
            vals = {form: asymptote(fit, key, re, form) for form in FORMS}
            fit["extrapolated"][f"{re:g}"] = {form: [v.real, v.imag] for form, v in vals.items()}
            print(f"  Re = {re:g}: " + ", ".join(f"{form} {v.real:.6f}{v.imag:+.6f}j" for form, v in vals.items()))
    low = rows[0]
    lowre = {"Re": low["Re"], "Re_Gtor_i": low["Re"] * low["tor_i"], "Gtor_r": low["tor_r"],
             "steady_Stokes_Re_Gtor_i": 16.0}
    print(f"low Re: Re Gamma_tor,i = {lowre['Re_Gtor_i']:.4f} at Re = {low['Re']:g} (steady Stokes limit 16: "
          f"torque 2 pi eta Omega a^2 of a plate); Gamma_tor,r = {low['tor_r']:.4f}, growing slowly as Re -> 0")
    summary = {
        "max_rel_diff_flex_vs_sader_r": max(abs(r["rel_diff_r"]) for r in rows),
        "max_rel_diff_flex_vs_sader_i": max(abs(r["rel_diff_i"]) for r in rows),
        "max_rel_diff_flex_vs_sader_i_re_le_100": max(abs(r["rel_diff_i"]) for r in rows if r["Re"] <= 100.0001),
        "max_rel_err_tor": max(r["tor_err"] / abs(complex(r["tor_r"], r["tor_i"])) for r in rows),
    }
    print(f"flexural vs Sader: max |rel diff| real {summary['max_rel_diff_flex_vs_sader_r']:.1e}, imag "
          f"{summary['max_rel_diff_flex_vs_sader_i']:.1e} ({summary['max_rel_diff_flex_vs_sader_i_re_le_100']:.1e} "
          f"for Re <= 100); max relative error estimate of Gamma_tor {summary['max_rel_err_tor']:.1e}")
    return {"asymptote": fits, "low_re": lowre, "summary": summary}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.25, help="step in log10(Re) (default 0.25)")
    ap.add_argument("--refine", type=float, nargs="+", default=[1.0, math.sqrt(2.0)],
                    help="mesh refinements; the table uses the last, the error the last two")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--refit", action="store_true", help="no solves: redo the analysis of the rows in --out")
    args = ap.parse_args(argv)
    t_start = time.time()
    old = json.loads(args.out.read_text()) if args.refit else None
    rows = old["rows"] if old else []
    hdr = (f"{'Re':>10} {'Gtor_r':>10} {'Gtor_i':>11} {'err':>8} | {'Gflex_r':>9} {'Gflex_i':>9} {'err':>8}"
           f" | {'Sader_r':>9} {'Sader_i':>9} {'dr':>9} {'di':>9} | {'s':>5}")
    print(hdr)
    for k in ([] if old else np.round(np.arange(-1.0, 4.0 + 1e-9, args.step), 6)):
        rows.append(point(10.0**k, args.refine))
    for r in rows:
        print(f"{r['Re']:10.4g} {r['tor_r']:10.6g} {r['tor_i']:11.6g} {r['tor_err']:8.1e} | {r['flex_r']:9.6g}"
              f" {r['flex_i']:9.6g} {r['flex_err']:8.1e} | {r['sader_r']:9.6g} {r['sader_i']:9.6g}"
              f" {r['rel_diff_r']:+9.1e} {r['rel_diff_i']:+9.1e} | {r['seconds']:5.0f}", flush=True)
    result = analyse(rows)
    check = old["stress_check"] if old else stress_check()
    for c in check["rows"]:
        rx, st = complex(*c["reaction"]), complex(*c["stress_integral"])
        print(f"check Re=10 {c['motion']:9s} refine {c['refine']:.3f}: reaction {rx:.6f}  stress integral {st:.6f}"
              f"  rel diff {abs(st / rx - 1):.1e}")
    seconds = old["summary"]["seconds"] if old else time.time() - t_start
    result["summary"]["seconds"] = seconds
    print(f"run time {seconds:.0f} s")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    doc = {"description": __doc__.splitlines()[0], "conventions": {
        "Re": "rho omega b^2 / (4 eta)", "Gamma": "Gamma_r + i Gamma_i, Gamma_i > 0 dissipative",
        "tor_normalisation": "pi rho b^4 / 128 (-> 1 at large Re); with a (pi/8) rho omega^2 b^4 prefactor: tor / 16",
        "flex_normalisation": "Sader 1998, (pi/4) rho b^2 (-> 1 at large Re)",
        "errors": "absolute, on the complex value: mesh + thickness extrapolation (+ 1e-4 |Gamma| outer radius, "
                  "translation)"},
        "rows": rows, **result, "stress_check": check}
    args.out.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
