"""The kernels under a force-curve diagnosis and the noise model, each timed against the form it replaced
(session 40), in one process, as ratios, with the agreement of the two.

Usage: ``python benchmarks/forcecurve_kernels.py [OUT.json]`` (default
``benchmarks/results/forcecurve_kernels.json``).

1. **Blunted cone on a lever** (600 + 600 samples, R = 20 nm, a soft 0.2 MPa sample indented ~100 nm, k =
   0.5 N/m, half-angles 0.1-60 deg): :func:`~probedyn.diagnose.forcecurve.lever_curve` with the law's force at
   a penetration (a root in the contact radius per penetration, :meth:`ContactModel.nd_state`) against
   :func:`~probedyn.diagnose.forcecurve.lever_curve_registry` (the law's polyline in the contact radius refined
   by bracket-guarded Newton steps on its exact curve), the path the diagnosis now takes.
2. **Maugis-Dugdale curve** (599 radii in (0, 5], lambda = 1): the vectorised numpy bracketed Newton of
   sessions <= 39 (kept here as the reference, :func:`_md_curve_numpy`) against the compiled
   :func:`~probedyn.schemes.contact.maugis_dugdale.md_curve`.
3. **White-plus-AR(1) likelihood** (300 samples): a dense Cholesky factor of the covariance
   (:func:`~probedyn.diagnose.noise._mix_cov`) against the banded factor of
   :func:`~probedyn.diagnose.noise._mix_quad_logdet`.
4. **2D Stokes section mesh** at Re = 3e4 (thinnest of the three extrapolation thicknesses, refine 0.7, the
   torsion truths' mesh): gmsh's Frontal-Delaunay (6, before) against Delaunay (5), and the torsional
   function on each.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import probedyn  # noqa: F401  (before numpy: thread settings)

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _best(f, repeat: int = 5) -> float:
    """Least wall time of ``repeat`` calls of ``f`` [s]."""
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t)
    return best


def cone_lever() -> dict:
    from probedyn.diagnose.forcecurve import lever_curve, lever_curve_registry
    from probedyn.schemes.contact import get_contact_model

    z = np.concatenate([np.linspace(-100e-9, 150e-9, 600), np.linspace(150e-9, -100e-9, 600)])
    seg = np.r_[np.zeros(600, int), np.ones(600, int)]
    rows = []
    for deg in (0.1, 5.0, 18.0, 35.0, 60.0):
        cone = get_contact_model("cone", E_t=160e9, nu_t=0.27, E_s=2e5, nu_s=0.3, R_t=20e-9, R_s=0.0,
                                 alpha=math.radians(deg))
        a = lever_curve(z, seg, cone.force, cone.force, 0.5, 250e-9)
        b = lever_curve_registry(z, seg, cone, 0.5, 250e-9)
        t_a = _best(lambda: lever_curve(z, seg, cone.force, cone.force, 0.5, 250e-9))
        t_b = _best(lambda: lever_curve_registry(z, seg, cone, 0.5, 250e-9))
        rows.append(dict(alpha_deg=deg, root_per_penetration_ms=1e3 * t_a, contact_radius_ms=1e3 * t_b,
                         ratio=t_a / t_b, max_abs_diff_over_max_force=float(np.max(np.abs(a - b)) / np.max(np.abs(a)))))
    return dict(rows=rows, median_ratio=float(np.median([r["ratio"] for r in rows])))


def _md_curve_numpy(A, lam: float, tol: float = 1e-14, maxiter: int = 200):
    """The vectorised Maugis-Dugdale curve of sessions <= 39: bracketed Newton on ln(rhs) in ln s for all radii at
    once (until every one converged), then the curve by :func:`g_functions`."""
    from probedyn.schemes.contact.maugis_dugdale import g_functions

    A = np.atleast_1d(np.asarray(A, float))
    c1, c2 = 0.5 * lam * A * A, 4.0 / 3.0 * lam * lam * A
    lo, hi = np.full(A.shape, -60.0), np.full(A.shape, 60.0)

    def F(x):
        s = np.exp(x)
        g1, g2, dg1, dg2 = g_functions(s)
        rhs = c1 * g1 + c2 * g2
        return np.log(rhs), s * (c1 * dg1 + c2 * dg2) / rhs

    F(lo), F(hi)  # the bracket's check, as it was
    x = np.clip(np.log(np.minimum(np.sqrt(1.5 / (lam * lam * A)), 2.0 / (A * np.sqrt(math.pi * lam)))),
                lo + 1e-3, hi - 1e-3)
    for _ in range(maxiter):
        f, df = F(x)
        lo, hi = np.where(f < 0, x, lo), np.where(f > 0, x, hi)
        xn = x - f / df
        xn = np.where(~((xn >= lo) & (xn <= hi)) | ~np.isfinite(xn), 0.5 * (lo + hi), xn)
        if np.all(np.abs(xn - x) <= tol):
            x = xn
            break
        x = xn
    s = np.exp(x)
    g1, g2, dg1, dg2 = g_functions(s)
    t = np.arctan(s)
    ds = -(lam * A * g1 + 4.0 / 3.0 * lam * lam * g2) / (0.5 * lam * A * A * dg1 + 4.0 / 3.0 * lam * lam * A * dg2)
    h, dh = s + (1.0 + s * s) * t, 2.0 + 2.0 * s * t
    return (A * A - 4.0 / 3.0 * lam * A * s, A**3 - lam * A * A * h, 2 * A - 4.0 / 3.0 * lam * (s + A * ds),
            3 * A * A - 2 * lam * A * h - lam * A * A * dh * ds)


def md_curve() -> dict:
    from probedyn.schemes.contact.maugis_dugdale import md_curve as compiled

    A = np.linspace(0.0, 5.0, 600)[1:]
    compiled(A, 1.0)  # compile (or load from numba's cache)
    a, b = _md_curve_numpy(A, 1.0), compiled(A, 1.0)[:4]
    t_a = _best(lambda: _md_curve_numpy(A, 1.0), 20)
    t_b = _best(lambda: compiled(A, 1.0), 20)
    diff = max(float(np.max(np.abs(x - y)) / np.max(np.abs(x))) for x, y in zip(a[:2], b[:2]))
    return dict(points=len(A), numpy_ms=1e3 * t_a, compiled_ms=1e3 * t_b, ratio=t_a / t_b,
                max_diff_D_P_over_max=diff)


def mixture_likelihood() -> dict:
    from scipy.linalg import cho_factor, cho_solve

    from probedyn.diagnose.noise import _mix_cov, _mix_quad_logdet

    x = np.random.default_rng(1).standard_normal(300)

    def dense():
        cf = cho_factor(_mix_cov(300, 0.4, 0.9), lower=True, check_finite=False)
        return float(x @ cho_solve(cf, x)), 2.0 * float(np.sum(np.log(np.diag(cf[0]))))

    q_a, l_a = dense()
    q_b, l_b = _mix_quad_logdet(x, 0.4, 0.9)
    t_a, t_b = _best(dense, 20), _best(lambda: _mix_quad_logdet(x, 0.4, 0.9), 20)
    return dict(samples=300, dense_ms=1e3 * t_a, banded_ms=1e3 * t_b, ratio=t_a / t_b,
                rel_diff_quadratic=abs(q_b - q_a) / abs(q_a), rel_diff_logdet=abs(l_b - l_a) / abs(l_a))


def section_mesh() -> dict:
    import gmsh

    from probedyn.fem.stokes2d import default_r_out, thin_thicknesses, zero_thickness_gamma
    from probedyn.meshes.section2d import default_sizes
    from probedyn.meshes.section2d import section_mesh as mesh

    re = 3e4
    t = 2 * thin_thicknesses(re)[2]
    sizes = default_sizes(t, math.sqrt(2 / re), 0.7)
    set_number = gmsh.option.setNumber
    out = {}
    try:
        for alg in (6, 5):
            gmsh.option.setNumber = lambda name, v, alg=alg: set_number(name, alg if name == "Mesh.Algorithm" else v)
            t0 = time.perf_counter()
            m = mesh(t, default_r_out(re), **sizes)
            dt = time.perf_counter() - t0
            g = complex(zero_thickness_gamma(re, "rotate", refine=0.7))
            out[f"algorithm_{alg}"] = dict(seconds=dt, triangles=int(m.t.shape[1]), gamma_rotate=[g.real, g.imag])
    finally:
        gmsh.option.setNumber = set_number
    g6, g5 = (complex(*out[f"algorithm_{a}"]["gamma_rotate"]) for a in (6, 5))
    out["ratio"] = out["algorithm_6"]["seconds"] / out["algorithm_5"]["seconds"]
    out["gamma_rel_diff"] = abs(g5 - g6) / abs(g6)
    return out


def main(argv: list[str]) -> dict:
    out = Path(argv[1]) if len(argv) > 1 else ROOT / "benchmarks" / "results" / "forcecurve_kernels.json"
    res = dict(cone_lever=cone_lever(), md_curve=md_curve(), mixture_likelihood=mixture_likelihood(),
               section_mesh=section_mesh())
    tmp = out.with_suffix(".tmp")
    tmp.write_text(json.dumps(res, indent=1))
    tmp.replace(out)
    print(json.dumps(res, indent=1))
    return res


if __name__ == "__main__":
    main(sys.argv)
