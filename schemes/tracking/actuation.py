"""Actuation gains of the smart probes for the tracking plants: free stroke of the holder per
volt, from the analytic formulas of :mod:`probedyn.lumped.actuation` (issue 12: eqs 3.31-3.36
as settled, the corrected eccentric-tube map 3.38-3.44), carried to the tracking plant's
reference point and axes. The piezoelectric FEM's strokes replace them through
``probedyn.probes.tracking`` (``gains="fem"``); every plant records which gains it uses.

Conventions (probedyn axes; source axes in brackets): the tube axis is x [source z], the
lateral axes y [y] and z [x]. The tracking plant names its inputs after the axis they drive:
``V_x`` = all four outer quadrants (axial extension) [source u_z, pattern "V_z" of
``probes/piezo.py``]; ``V_y`` = -y quadrant at +V, +y quadrant at -V [u_y, "V_y"]; ``V_z`` = the
-z/+z pair likewise [u_x, "V_x"]. With d31 < 0 (PZT, outward poling) a positive input moves the
holder towards the positive axis (the signs of :class:`~probedyn.lumped.actuation.GammaMatrix`).

* duo-bimorph: lateral ``3 |d31| L^2 (w^2 - w0^2) / (h w^3)`` (3.31), vertical
  ``3 |d31| L^2 (w - w0) / (h^2 w)`` (3.32), beam theory (confirmed by the piezo FEM within
  1 % at w0 = 5 um, departure 20);
* tube: axial ``|d31| L / (Re - Ri)`` (3.35); lateral from ``gamma_matrix`` (uniform field V/t in
  the wall, exact annulus integrals: ``(4 sqrt(2)/(3 pi)) |d31| L^2 (Re^3 - Ri^3) / (t (Re^4 - Ri^4))``
  for a centred tube), half the printed 3.34 (departure 17);
* eccentric tube: ``gamma_matrix`` (departure 21), whose axial row is the displacement of the end
  section's centroid - the face average the FEM's holder attachment sees;
* the holder end face (a rigid holder of length L_h beyond the tube/beam end) adds the end
  rotation: lateral strokes times ``1 + 2 L_h / L`` (uniform piezo moment).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.lumped.actuation import (GammaMatrix, duo_bimorph_range, gamma_matrix, tube_axial_per_volt,
                                       tube_lateral_per_volt)

SQRT2 = math.sqrt(2.0)
#: probedyn (x axial, y, z) <- source (x = probedyn z, y, z = probedyn x): index map for rows and columns
SOURCE_INDEX = [2, 1, 0]


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
    r = duo_bimorph_range(L, w, h, w0, -abs(float(d31)))
    return {"y": abs(r["dy"]), "z": abs(r["dz"])}


def tube_strokes(L: float, Re: float, Ri: float, d31: float) -> dict[str, float]:
    """Free end stroke per volt [m/V] of a centred tube: ``x`` axial (3.35), ``lateral`` (uniform
    field, exact annulus: the centred ``gamma_matrix``), ``lateral_thin`` and ``lateral_thick``
    (1/r field) of :func:`~probedyn.lumped.actuation.tube_lateral_per_volt`, ``lateral_printed``
    (3.34 as printed)."""
    L, Re = _pos("L", L), _pos("Re", Re)
    if not (0 < Ri < Re):
        raise GeometryError(f"tube: inner radius Ri = {Ri:g} m must be in (0, Re = {Re:g} m)")
    d = -abs(float(d31))
    t = Re - Ri
    return {"x": tube_axial_per_volt(L, Re, Ri, d),
            "lateral": 4 * SQRT2 / (3 * math.pi) * abs(d) * L**2 * (Re**3 - Ri**3) / (t * (Re**4 - Ri**4)),
            "lateral_thin": tube_lateral_per_volt(L, Re, Ri, d, "thin"),
            "lateral_thick": tube_lateral_per_volt(L, Re, Ri, d, "thick"),
            "lateral_printed": tube_lateral_per_volt(L, Re, Ri, d, "printed")}


def to_probedyn(g: GammaMatrix | np.ndarray) -> np.ndarray:
    """A tube's voltage-to-displacement map in the source frame (rows x, y lateral, z axial;
    columns u_x, u_y, u_z) as the tracking plant's stroke matrix (rows probedyn x axial, y, z;
    columns V_x axial, V_y, V_z)."""
    D = g.displacement if isinstance(g, GammaMatrix) else np.asarray(g, dtype=float)
    return D[np.ix_(SOURCE_INDEX, SOURCE_INDEX)]


def eccentric_tube_stroke(Re: float, Ri: float, L: float, d31: float, delta_y: float = 0.0, delta_z: float = 0.0,
                          holder_length: float = 0.0, n_theta: int = 8192) -> np.ndarray:
    """3x3 free stroke per volt [m/V] of the holder end face (rows x, y, z; columns V_x, V_y,
    V_z) of a tube whose bore is offset by (delta_y, delta_z) (probedyn; source delta_y,
    delta_x): the corrected 3.38-3.44 (``gamma_matrix``) in probedyn axes, lateral rows times
    the holder factor. For delta = 0: ``diag(3.35, lateral (1 + 2 L_h/L), same)``."""
    L = _pos("L", L)
    G = to_probedyn(gamma_matrix(Re, Ri, L, delta_x=delta_z, delta_y=delta_y, d31=-abs(float(d31)), n_theta=n_theta))
    G = G.copy()
    G[1:, :] *= holder_factor(L, holder_length)
    return G


def gamma_normalised(G: np.ndarray, G0: np.ndarray) -> np.ndarray:
    """Dimensionless coupling ``diag(G0)^-1 G``: the identity for a centred tube; off-diagonal
    entries are the strokes along one axis per unit stroke commanded along another."""
    return G / np.diag(G0)[:, None]
