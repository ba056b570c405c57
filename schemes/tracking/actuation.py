"""Actuation gains of the smart probes: free stroke of the holder per volt (analytic), and the
eccentric piezotube's voltage-to-stroke map (the physics of the source's Gamma, eqs 3.38-3.44).

These are the **analytic gains** that drive the tracking plants until the piezoelectric FEM
(issue 12) supplies its own; every plant records which gains it uses (``provenance``).

Conventions (probedyn axes; source axes in brackets): the tube axis is x [source z], the
lateral axes y [y] and z [x]; electrode quadrants are centred on +y, +z, -y, -z (theta from +y
towards +z). Input ``V_x`` drives all four outer electrodes (axial extension) [source u_z];
``V_y`` drives the -y quadrant with +V and the +y quadrant with -V [source u_y]; ``V_z`` the
-z/+z pair likewise [source u_x]. The wiring (and the sign of d31, negative for PZT) is chosen so
that a positive voltage moves the holder towards the positive axis: the gains below use |d31|.

Formulas (thin-wall uniform radial field ``E = V / t`` in the wall, free piezo strain
``d31 E`` along the axis, Euler-Bernoulli statics; all checked in tests against limits):

* duo-bimorph (two layers of thickness h/2 each with field V/(h/2), electrodes split by the gap
  w0): lateral ``3 d31 L^2 (w^2 - w0^2) / (h w^3)`` (3.31), vertical ``3 d31 L^2 (w - w0) / (h^2 w)``
  (3.32), both as printed (the piezo-moment derivation gives them exactly);
* tube axial ``d31 L / (Re - Ri)`` (3.35, as printed);
* tube lateral, antisymmetric drive of a quadrant pair: the piezo moment
  ``M = 2 sqrt(2) d31 V (Re^3 - Ri^3) / (3 s11 t)`` bends the tube by
  ``M L^2 / (2 EI)``: ``(4 sqrt(2) / (3 pi)) d31 L^2 (Re^3 - Ri^3) / (t (Re^4 - Ri^4))``, which is
  ``sqrt(2) d31 L^2 / (pi R t)`` for a thin wall (R mean radius) - **half the printed (3.34)**
  with R_e in place of the diameter (SOURCE-NOTES 8; the piezo FEM decides);
* the holder end face (a rigid holder of length L_h beyond the tube/beam end) adds the end
  rotation: lateral strokes are multiplied by ``1 + 2 L_h / L`` (uniform piezo moment);
* eccentric tube (bore offset delta): :func:`eccentric_tube_stroke` integrates the free piezo
  strain over the exact eccentric annulus (local wall thickness along each ray from the outer
  centre, ``t(theta) = Re - R2(theta)``, ``R2 = delta.e + sqrt(Ri^2 - (delta x e)^2)``: eq 3.44
  with the corrections of SOURCE-NOTES 14) and takes the axial force and the bending moments
  about the **section centroid** (``c = -A_i delta / A``), which is where the printed
  3.40-3.42 measure their radii R1, R2 from. Beam statics give the 3x3 stroke matrix at the
  holder end face; the printed Gamma's rows are these force and moment integrals without the
  factor d31/s11 and the beam compliances (its rows have different units).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError, ParameterError

SQRT2 = math.sqrt(2.0)


def _pos(name: str, v: float) -> float:
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{name} must be positive and finite, got {v:g}")
    return v


def holder_factor(L: float, L_h: float) -> float:
    """Lateral stroke at a rigid holder's end face (length ``L_h``) over the stroke at the end of
    a beam bent by a uniform moment: ``(L^2/2 + L L_h) / (L^2/2) = 1 + 2 L_h / L``."""
    return 1.0 + 2.0 * L_h / L


def duo_bimorph_strokes(L: float, w: float, w0: float, h: float, d31: float) -> dict[str, float]:
    """Free end stroke per volt [m/V] of the duo-bimorph: ``y`` (3.31) and ``z`` (3.32)."""
    L, w, h, d = _pos("L", L), _pos("w", w), _pos("h", h), abs(float(d31))
    if not (0 <= w0 < w):
        raise GeometryError(f"electrode gap w0 = {w0:g} m must be in [0, w = {w:g} m)")
    return {"y": 3 * d * L**2 * (w**2 - w0**2) / (h * w**3), "z": 3 * d * L**2 * (w - w0) / (h**2 * w)}


def tube_strokes(L: float, Re: float, Ri: float, d31: float, exact: bool = True) -> dict[str, float]:
    """Free end stroke per volt [m/V] of a centred tube: ``x`` axial (3.35) and ``lateral``
    (3.34 corrected, exact annulus or thin wall), and ``lateral_printed`` (3.34 as printed)."""
    L, Re, d = _pos("L", L), _pos("Re", Re), abs(float(d31))
    if not (0 < Ri < Re):
        raise GeometryError(f"tube: inner radius Ri = {Ri:g} m must be in (0, Re = {Re:g} m)")
    t = Re - Ri
    if exact:
        lat = 4 * SQRT2 / (3 * math.pi) * d * L**2 * (Re**3 - Ri**3) / (t * (Re**4 - Ri**4))
    else:
        lat = SQRT2 * d * L**2 / (math.pi * 0.5 * (Re + Ri) * t)
    return {"x": d * L / t, "lateral": lat, "lateral_printed": 2 * SQRT2 * d * L**2 / (math.pi * Re * t)}


def _quadrant_patterns() -> dict[str, np.ndarray]:
    """Voltage per unit input on the quadrants centred at 0, 90, 180, 270 degrees (+y, +z, -y, -z)."""
    return {"V_x": np.array([1.0, 1.0, 1.0, 1.0]), "V_y": np.array([-1.0, 0.0, 1.0, 0.0]),
            "V_z": np.array([0.0, -1.0, 0.0, 1.0])}


def eccentric_section_loads(Re: float, Ri: float, delta_y: float, delta_z: float, n_quad: int = 96) -> dict[str, Any]:
    """Free-strain resultants per unit (d31 V) of each input pattern on the eccentric annulus.

    For input pattern j with quadrant voltages v_q: ``eps_p(theta) = v_q / t(theta)`` (times
    d31 V), ``N_j = int eps_p dA`` and ``m_j = int eps_p (r - c) dA`` (2-vector in (y, z)) about
    the centroid ``c``. In polar coordinates about the outer centre the radial integrals are
    exact: ``int r dr = (Re^2 - R2^2)/2``, ``int r^2 dr = (Re^3 - R2^3)/3``; the angular ones use
    Gauss-Legendre per quadrant (smooth integrand inside a quadrant).
    Returns A, centroid c, centroidal second-moment tensor I_c (2x2) and per input (N, m)."""
    Re, Ri = _pos("Re", Re), _pos("Ri", Ri)
    d = np.array([float(delta_y), float(delta_z)])
    if np.linalg.norm(d) + Ri >= Re:
        raise GeometryError(f"eccentric tube: offset {np.linalg.norm(d):g} m + Ri = {Ri:g} m reaches the outer radius {Re:g} m")
    x, wq = np.polynomial.legendre.leggauss(n_quad)
    Ao, Ai = math.pi * Re**2, math.pi * Ri**2
    A = Ao - Ai
    c = -Ai * d / A
    I0 = math.pi * (Re**4 - Ri**4) / 4
    Ic = I0 * np.eye(2) - (Ai * Ao / A) * np.outer(d, d)
    out: dict[str, Any] = {"A": A, "centroid": c, "I_c": Ic, "loads": {}}
    pats = _quadrant_patterns()
    res = {k: [0.0, np.zeros(2)] for k in pats}
    for q in range(4):
        a0 = (q * 90.0 - 45.0) * math.pi / 180
        th = a0 + (x + 1) * (math.pi / 4)
        w = wq * (math.pi / 4)
        e = np.stack([np.cos(th), np.sin(th)], axis=1)
        de = e @ d
        cross = d[0] * e[:, 1] - d[1] * e[:, 0]
        R2 = de + np.sqrt(Ri**2 - cross**2)
        t = Re - R2
        i1 = (Re**2 - R2**2) / 2
        i2 = (Re**3 - R2**3) / 3
        for k, v in pats.items():
            if v[q] == 0:
                continue
            f = v[q] / t
            res[k][0] += float(np.sum(w * f * i1))
            res[k][1] += np.sum((w * f * i2)[:, None] * e, axis=0) - c * float(np.sum(w * f * i1))
    out["loads"] = {k: {"N": v[0], "m": v[1]} for k, v in res.items()}
    return out


def eccentric_tube_stroke(Re: float, Ri: float, L: float, d31: float, delta_y: float = 0.0, delta_z: float = 0.0,
                          holder_length: float = 0.0, n_quad: int = 96) -> np.ndarray:
    """3x3 free stroke per volt [m/V] of the holder end face (rows x, y, z; columns V_x, V_y, V_z).

    Statics of the free tube under its piezo strain (module docstring): axial strain at the
    centroid ``eps0 = N / A``, gradient ``kappa = I_c^-1 m`` (the elastic modulus cancels);
    lateral deflection ``-kappa (L^2/2 + L L_h)`` (end deflection + holder rotation), axial
    displacement ``L eps0`` of the end section's centroid - the face average of a plane section,
    as the FEM's face-averaged holder attachment sees it (the outer axis, 4.3 delta away, would
    add ``-L kappa . c``). For ``delta = 0`` this is ``diag(tube_strokes x, lateral (1 + 2 L_h/L),
    same)``."""
    L = _pos("L", L)
    s = eccentric_section_loads(Re, Ri, delta_y, delta_z, n_quad)
    dd = abs(float(d31))
    Icinv = np.linalg.inv(s["I_c"])
    G = np.zeros((3, 3))
    for j, k in enumerate(("V_x", "V_y", "V_z")):
        N, m = s["loads"][k]["N"], s["loads"][k]["m"]
        eps0 = dd * N / s["A"]
        kap = dd * (Icinv @ m)
        G[0, j] = L * eps0
        G[1:, j] = -kap * (L**2 / 2 + L * holder_length)
    return G


def gamma_normalised(G: np.ndarray, G0: np.ndarray) -> np.ndarray:
    """Dimensionless coupling ``diag(G0)^-1 G``: the identity for a centred tube; off-diagonal
    entries are the strokes along one axis per unit stroke commanded along another."""
    return G / np.diag(G0)[:, None]
