"""FEM vs analytic references, mode by mode (a probe's FEM result against the formulas of
lumped/: the reduction layer reads the FEM result, the FEM layer knows no formula).

:func:`comparison_rows` joins the probe's own references (beam formulas per mode family, see
``Probe.references``) with the Rayleigh quotient (2.46) evaluated on the FEM mode itself:
the cross-section-averaged deflection of each flapwise or lateral bending mode is sampled along the beam and
put into ``omega^2 = int EI (w'')^2 dx / int rho A w^2 dx``. On an exact Euler–Bernoulli mode it
returns the Euler–Bernoulli frequency, so the row separates what the 3D FEM adds (shear, rotary
inertia, Poisson clamping) from a difference in the mode *shape*.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.interpolate import make_interp_spline

from probedyn.lumped.beam import rayleigh_quotient

#: centreline samples per bending mode for the Rayleigh quotient
N_SAMPLES = 81


def rayleigh_rows(probe: Any, values: dict[str, Any], result: Any) -> list[dict[str, Any]]:
    """Rayleigh quotient (2.46) rows for the bending modes of a rectangular cantilever
    (probes with a ``beam(values)`` method returning a :class:`probedyn.lumped.beam.RectBeam`).
    A tip mass enters the denominator as ``m w(L)^2`` (the standard energy of a point mass)."""
    if not hasattr(probe, "beam"):
        return []
    b = probe.beam(values)
    model = result.model
    x = np.linspace(0.0, b.L, N_SAMPLES)
    tip_mass = float(values.get("tip_mass") or 0.0)
    rows = []
    count: dict[str, int] = {}
    # cross-section average on a 3x3 Gauss grid (the centreline alone carries the 3D
    # anticlastic / Poisson deformation of the section, which is not beam deflection)
    g3 = np.array([-np.sqrt(0.6), 0.0, np.sqrt(0.6)]) / 2.0
    w3 = np.array([5.0, 8.0, 5.0]) / 18.0
    pts = [(xi, gy * b.w, gz * b.t) for gy in g3 for gz in g3 for xi in x]
    A = None  # one interpolation operator for all samples and modes (built when a bending mode needs it)
    for m in result.modes:
        count[m.family] = count.get(m.family, 0) + 1
        if m.family not in ("flapwise", "lateral"):
            continue
        comp = 2 if m.family == "flapwise" else 1
        EI = b.E * (b.w * b.t**3 if comp == 2 else b.t * b.w**3) / 12.0
        rhoA = b.rho * b.w * b.t
        if A is None:
            A = model.points_operator(np.array(pts).T)
        u = (A @ m.shape[: A.shape[1]]).reshape(3, 3, x.size, 3)[..., comp]  # (gy, gz, x)
        w = np.einsum("i,j,ijx->x", w3, w3, u)
        if tip_mass > 0:
            # point mass at x = L: add m w(L)^2 to the kinetic integral via an equivalent
            # distributed term would bias the spline; evaluate the two parts separately instead
            spl = make_interp_spline(x, w, k=5)
            g, wg = np.polynomial.legendre.leggauss(8)
            a, bb = x[:-1, None], x[1:, None]
            xq = (0.5 * (bb - a) * g + 0.5 * (a + bb)).ravel()
            wq = (0.5 * (bb - a) * wg).ravel()
            V = np.sum(wq * EI * spl.derivative(2)(xq) ** 2)
            T = np.sum(wq * rhoA * spl(xq) ** 2) + tip_mass * w[-1] ** 2
            omega2 = V / T
        else:
            omega2 = rayleigh_quotient(x, w, EI, rhoA)
        f = float(np.sqrt(omega2) / (2 * np.pi))
        rows.append({"mode": m.index, "family": m.family, "order": count[m.family],
                     "formula": "Rayleigh quotient (2.46) on the FEM mode shape",
                     "fem_hz": m.frequency_hz, "value_hz": f, "rel_diff": (m.frequency_hz - f) / f})
    return rows


def comparison_rows(probe: Any, values: dict[str, Any], result: Any) -> list[dict[str, Any]]:
    """All comparison rows, ordered by mode: the probe's references, then the Rayleigh quotient."""
    rows = list(probe.references(values, result)) + rayleigh_rows(probe, values, result)
    return sorted(rows, key=lambda r: (r["mode"], r["formula"]))
