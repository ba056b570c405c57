"""Analytic actuation formulas for the smart probes (source sections 3.4.2 and 3.5.1), checked
against the coupled piezoelectric FEM (:mod:`probedyn.fem.piezo`; numbers in docs/piezo.md).

Sign conventions (probedyn axes: x along the probe/tube, z up; PZT has d31 < 0):

* a layer poled along +p, in a field E, has the free in-plane strain ``d31 (E . p)``: it
  **contracts** when the field is parallel to the poling (d31 < 0) and extends when it opposes
  it; the field points from the higher to the lower potential;
* bimorph deflections are **signed** and per volt of the named drive; the duo-bimorph and tube
  formulas return the deflection per volt of a drive pattern whose positive command moves the
  tip along the positive axis (:mod:`probedyn.probes.piezo`), i.e. they use ``|d31|``.

Bimorph cantilever (laminate theory, two equal PZT layers of total thickness h)
-------------------------------------------------------------------------------
Free strain ``Lambda = d E``, curvature ``kappa = 3 Lambda / h`` ("classic", linear potential
in each layer), tip deflection ``kappa L^2 / 2``.  Series (opposite poling, V across both
layers): E = V/h; parallel (same poling, middle electrode at V): E = 2V/h.  So
``delta_series = 3/2 d L^2 V / h^2`` and ``delta_parallel = 3 d L^2 V / h^2`` (signs: see
:func:`bimorph_tip_deflection`).

The electrodes hold the *mean* field of each layer; bending makes the strain vary through
the layer, and Gauss's law (dD3/dz = 0) then makes the potential quadratic in each layer (the
"induced potential").  Its field stiffens each layer's own bending by ``1/(1 - k^2)``; the two
layers' own parts are a quarter of the bimorph's bending stiffness, so

    delta = delta_classic / (1 + k^2 / (4 (1 - k^2)))

with the coupling factor of the stress state in the layers:

* ``"narrow"`` (width << thickness: T2 = T3 = 0): ``d = d31``, ``k^2 = k31^2 = d31^2/(s11 eps33^T)``;
* ``"plane_strain"`` (slice of a wide plate in cylindrical bending, S2 = 0: classical laminate
  theory): ``d = d31 (s11 - s12)/s11``, ``s = (s11^2 - s12^2)/s11``,
  ``eps = eps33^T - d31^2/s11``, ``k^2 = d^2 / (s eps)``;
* ``"plate"`` (wide plate with free sides, equibiaxial spherical bending): ``d = d31``,
  ``k^2 = kp^2 = 2 d31^2 / ((s11 + s12) eps33^T)``.

For PZT-5H the factor is 1.045 (narrow), 1.120 (plane strain), 1.185 (plate).

Duo-bimorph (3.31-3.33)
-----------------------
Both layers poled alike, middle electrode grounded, electrodes of width (w - w0)/2 on each side
of the gap w0 (parallel drive: E = V/(h/2)).  Lateral (left half extending, right contracting):
``Delta_y = 3 d31 L^2 (w^2 - w0^2) V_y / (h w^3)`` (3.31); vertical: ``Delta_z = 3 d31 L^2 (w -
w0) V_z / (h^2 w)`` (3.32); equal ranges for ``V_z = h (w + w0) V_y / w^2`` (3.33).  All three
are confirmed by beam theory (classic, linear potential); the FEM's deviations (induced
potential, plate-like layers, fringing at the gap) are measured in docs/piezo.md.

Piezotube (3.34-3.36)
---------------------
Thin tube (mean radius R, wall t = Re - Ri, quarters at -V / +V, inner grounded, outward
poling: the +V quarter extends, the -V quarter contracts, the tube bends towards -V): the moment
of the free strain ``d31 V / t`` over the two quarters is ``2 sqrt(2) Y d31 V R^2`` and
``EI = Y pi R^3 t``, so

    Delta_lateral = sqrt(2) d31 L^2 V / (pi R t) = 2 sqrt(2) d31 L^2 V / (pi D t),   D = 2R.

The print's 3.34 has ``R_e`` where the standard form (Chen, J. Vac. Sci. Technol. A 10 (1992)
3204) has the diameter D: it is **twice** too large (SOURCE-NOTES item 8; the FEM decides,
docs/piezo.md).  Thick wall (radial field ``V / (r ln(Re/Ri))``, exact annulus):
``Delta = 2 sqrt(2) d31 L^2 V / (pi (Re^2 + Ri^2) ln(Re/Ri))``.  Axial (all outer electrodes
at +V: inward field against the poling, extension): 3.35 ``Delta_z = d31 L V / t`` (thin) or ``2 d31 L V / ((Re + Ri) ln(Re/Ri))`` (thick).
3.36 ``V_z = 0.9 (L/Re) V_x`` follows from the printed 3.34; with the corrected 3.34 it is
``V_z = sqrt(2) L V_x / (pi R) = 0.45 (L/R) V_x``.

Eccentric tube (3.38-3.44): :func:`gamma_matrix` (module section below).

Electromechanical coupling (IEEE Std 176-1987)
----------------------------------------------
Length-extensional bar, field across (k31): ``f_r = 1/(2 L sqrt(rho s11^E))`` and
``k31^2/(1 - k31^2) = (pi/2)(f_a/f_r) tan((pi/2)(f_a - f_r)/f_r)``.  Rod, field along (k33):
``f_a = 1/(2 L sqrt(rho s33^D))``, ``s33^D = s33^E (1 - k33^2)`` and
``k33^2 = (pi/2)(f_r/f_a) tan((pi/2)(f_a - f_r)/f_a)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.optimize import brentq

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.fem.piezo_materials import PiezoMaterial, get_piezo_material

STATES = ("narrow", "plane_strain", "plate")


def _pos(name: str, v: float) -> float:
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{name} must be positive and finite, got {v:g}")
    return v


def _mat(material) -> PiezoMaterial:
    return get_piezo_material(material)


# ---------------------------------------------------------------------------------------------
# Bimorph laminate theory
# ---------------------------------------------------------------------------------------------

def layer_constants(material="pzt-5h", state: str = "narrow") -> dict[str, float]:
    """Effective ``d`` [m/V], compliance ``s`` [1/Pa], permittivity ``eps`` [F/m] and ``k2``
    of a layer poled through its thickness in the given stress ``state`` (module docstring)."""
    m = _mat(material)
    s11, s12 = float(m.sE[0, 0]), float(m.sE[0, 1])
    d31, e33T = float(m.d[2, 0]), float(m.epsT[2, 2])
    if state == "narrow":
        d, s, eps = d31, s11, e33T
        k2 = d * d / (s * eps)
    elif state == "plane_strain":
        d = d31 * (s11 - s12) / s11
        s = (s11 * s11 - s12 * s12) / s11
        eps = e33T - d31 * d31 / s11
        k2 = d * d / (s * eps)
    elif state == "plate":
        d, s, eps = d31, s11 + s12, e33T
        k2 = 2 * d31 * d31 / ((s11 + s12) * e33T)
    else:
        raise ParameterError(f"state must be one of {', '.join(STATES)}, got {state!r}")
    return {"d": d, "s": s, "eps": eps, "k2": k2}


def induced_potential_factor(material="pzt-5h", state: str = "narrow") -> float:
    """``1 + k^2 / (4 (1 - k^2))``: the bimorph's bending stiffening by the quadratic potential
    in its voltage-held layers (module docstring)."""
    k2 = layer_constants(material, state)["k2"]
    return 1.0 + k2 / (4.0 * (1.0 - k2))


def bimorph_tip_deflection(length: float, thickness: float, material="pzt-5h", config: str = "series",
                           state: str = "narrow", induced_potential: bool = True) -> float:
    """Tip deflection per volt [m/V] of a symmetric PZT bimorph cantilever (two layers of
    ``thickness/2``), laminate theory.

    Drives (as :func:`probedyn.fem.piezo_benchmarks.bimorph_drive`): ``series`` - upper layer
    poled +z, lower -z, top electrode at +V, bottom grounded: ``3/2 d L^2 / h^2`` (negative:
    towards -z for d31 < 0); ``parallel`` - both poled +z, middle electrode at +V, outer grounded:
    ``-3 d L^2 / h^2``.  ``induced_potential=False`` gives the classic (linear potential) value.
    """
    L, h = _pos("length", length), _pos("thickness", thickness)
    c = layer_constants(material, state)
    if config == "series":
        delta = 1.5 * c["d"] * L * L / (h * h)
    elif config == "parallel":
        delta = -3.0 * c["d"] * L * L / (h * h)
    else:
        raise ParameterError(f"bimorph config must be 'series' or 'parallel', got {config!r}")
    if induced_potential:
        delta /= 1.0 + c["k2"] / (4.0 * (1.0 - c["k2"]))
    return float(delta)


def bimorph_tip_stiffness(length: float, width: float, thickness: float, material="pzt-5h",
                          state: str = "narrow", induced_potential: bool = True) -> float:
    """End-load stiffness ``3 EI / L^3`` [N/m] of the bimorph with its electrodes held (short
    circuit), ``EI = w h^3 / (12 s) (1 + k^2/(4(1-k^2)))``; the blocked force per volt is this
    times :func:`bimorph_tip_deflection`."""
    L, w, h = _pos("length", length), _pos("width", width), _pos("thickness", thickness)
    c = layer_constants(material, state)
    EI = w * h**3 / (12.0 * c["s"])
    if induced_potential:
        EI *= 1.0 + c["k2"] / (4.0 * (1.0 - c["k2"]))
    return 3.0 * EI / L**3


# ---------------------------------------------------------------------------------------------
# Duo-bimorph range (3.31-3.33)
# ---------------------------------------------------------------------------------------------

def duo_bimorph_range(length: float, width: float, thickness: float, gap: float, d31: float) -> dict[str, float]:
    """Eqs 3.31-3.33 (verified by beam theory, classic linear potential): tip deflection per volt
    ``dy`` (lateral, pattern V_y) and ``dz`` (vertical, pattern V_z) [m/V] and the voltage ratio
    ``vz_over_vy`` for equal ranges.  ``d31`` signed [m/V]."""
    L, w, h = _pos("length", length), _pos("width", width), _pos("thickness", thickness)
    w0 = float(gap)
    if not (0 <= w0 < w):
        raise GeometryError(f"electrode gap w0 = {w0:g} m must lie in [0, w = {w:g} m)")
    dy = 3 * d31 * L**2 * (w**2 - w0**2) / (h * w**3)
    dz = 3 * d31 * L**2 * (w - w0) / (h**2 * w)
    return {"dy": dy, "dz": dz, "vz_over_vy": h * (w + w0) / w**2}


# ---------------------------------------------------------------------------------------------
# Piezotube (3.34-3.36)
# ---------------------------------------------------------------------------------------------

def _tube(Re: float, Ri: float) -> tuple[float, float]:
    Re, Ri = _pos("Re", Re), _pos("Ri", Ri)
    if Ri >= Re:
        raise GeometryError(f"inner radius Ri = {Ri:g} m must be below Re = {Re:g} m")
    return Re, Ri


def tube_lateral_per_volt(length: float, Re: float, Ri: float, d31: float, form: str = "thin") -> float:
    """Lateral tip deflection per volt [m/V] of a tube poled radially outward with quarters at
    -V and +V (inner grounded): towards the -V quarter (the +V quarter extends for d31 < 0);
    returned positive (``|d31|``).

    ``form``: ``"printed"`` = 3.34 as printed, ``2 sqrt(2) |d31| L^2 / (pi Re t)``;
    ``"thin"`` = ``sqrt(2) |d31| L^2 / (pi R t)`` (R mean radius; = the standard form with the
    diameter); ``"thick"`` = ``2 sqrt(2) |d31| L^2 / (pi (Re^2 + Ri^2) ln(Re/Ri))`` (radial
    field ~ 1/r, exact annulus)."""
    L = _pos("length", length)
    Re, Ri = _tube(Re, Ri)
    t, R = Re - Ri, 0.5 * (Re + Ri)
    a = -float(d31)
    if form == "printed":
        return 2 * math.sqrt(2) * a * L**2 / (math.pi * Re * t)
    if form == "thin":
        return math.sqrt(2) * a * L**2 / (math.pi * R * t)
    if form == "thick":
        return 2 * math.sqrt(2) * a * L**2 / (math.pi * (Re**2 + Ri**2) * math.log(Re / Ri))
    raise ParameterError(f"form must be printed, thin or thick, got {form!r}")


def tube_axial_per_volt(length: float, Re: float, Ri: float, d31: float, form: str = "thin") -> float:
    """Axial extension per volt [m/V] with all outer electrodes at +V (inner grounded): the
    inward field opposes the outward poling, the tube extends (d31 < 0): 3.35 ``|d31| L / t`` (``"thin"`` =
    ``"printed"``) or ``2 |d31| L / ((Re + Ri) ln(Re/Ri))`` (``"thick"``)."""
    L = _pos("length", length)
    Re, Ri = _tube(Re, Ri)
    a = -float(d31)
    if form in ("thin", "printed"):
        return a * L / (Re - Ri)
    if form == "thick":
        return 2 * a * L / ((Re + Ri) * math.log(Re / Ri))
    raise ParameterError(f"form must be printed, thin or thick, got {form!r}")


def tube_voltage_ratio(length: float, Re: float, Ri: float, form: str = "thin") -> float:
    """``V_z / V_x`` for equal lateral and axial ranges (3.36): printed ``2 sqrt(2) L/(pi Re)``
    (= 0.9 L/Re), corrected ``sqrt(2) L / (pi R)``."""
    return tube_lateral_per_volt(length, Re, Ri, -1.0, form) / tube_axial_per_volt(
        length, Re, Ri, -1.0, "thick" if form == "thick" else "thin")


def tube_sector_deflection(length: float, Re: float, Ri: float, d31: float, voltages: Sequence[float],
                           edges_deg: Sequence[float]) -> np.ndarray:
    """Lateral tip deflection (2,) [m] along (e_0, e_90) of a tube whose outer electrode is cut
    into sectors ``[edges[k], edges[k+1]]`` (degrees, the last one wrapping to edges[0] + 360)
    at ``voltages[k]`` (inner grounded, outward poling, thick-wall radial field).  Each sector
    contributes ``d31 L^2 (Re^2 - Ri^2) / (4 I ln(Re/Ri)) V_k int (cos, sin) dtheta`` (a sector at
    +V extends and the tube bends away from it); quarters at -+V give
    :func:`tube_lateral_per_volt` ("thick")."""
    L = _pos("length", length)
    Re, Ri = _tube(Re, Ri)
    e = np.radians(np.asarray(edges_deg, dtype=float))
    e2 = np.append(e[1:], e[0] + 2 * math.pi)
    V = np.asarray(voltages, dtype=float)
    if V.shape != e.shape:
        raise ParameterError("one voltage per sector")
    I = math.pi * (Re**4 - Ri**4) / 4
    c = d31 * L**2 * (Re**2 - Ri**2) / (4 * I * math.log(Re / Ri))
    return c * np.array([np.sum(V * (np.sin(e2) - np.sin(e))), np.sum(V * (np.cos(e) - np.cos(e2)))])


# ---------------------------------------------------------------------------------------------
# Eccentric tube: the coupling matrix Gamma (3.38-3.44)
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class GammaMatrix:
    """Voltage-to-tip-displacement map of a piezotube, in the **source's frame** (x, y lateral,
    z along the tube axis; probedyn's tube axis is x, source x = probedyn z, source y = probedyn y).

    ``displacement[i, j]`` [m/V]: tip (tube end) displacement along i for a unit input u_j with
    the electrode voltages ``Q+x: -u_x + u_z, Q-x: u_x + u_z, Q+y: -u_y + u_z, Q-y: u_y + u_z``,
    inner electrode grounded (quarters Q centred on the axes; PZT, d31 < 0, poled radially
    outward): the signs make every diagonal entry positive (u_x moves the tip along +x, u_z
    extends the tube), so that positive definiteness means what 3.52 needs.
    ``reference`` = the diagonal of the concentric tube (same model), so that
    ``normalised = displacement / reference[:, None]`` is dimensionless and equal to the identity
    without eccentricity.  ``source`` says where it comes from.

    The source's Gamma (``U = Gamma u`` in 3.37) is a force map: with the piezotube stiffness
    ``K2 = diag(k_px, k_py, k_pz)``, ``Gamma = K2 @ displacement`` (:meth:`force`).
    """

    displacement: np.ndarray = field(repr=False)
    reference: np.ndarray = field(repr=False)
    source: str = ""

    @property
    def normalised(self) -> np.ndarray:
        """``displacement`` with each row divided by the concentric tube's diagonal entry of that
        row (dimensionless; the identity for a concentric tube)."""
        return self.displacement / self.reference[:, None]

    def force(self, K2: Sequence[float] | np.ndarray) -> np.ndarray:
        """``K2 @ displacement`` [N/V] (the source's Gamma in 3.37-3.38); K2 (3,) or (3, 3) [N/m]."""
        K = np.asarray(K2, dtype=float)
        K = np.diag(K) if K.ndim == 1 else K
        return K @ self.displacement

    def eigenvalues(self, normalised: bool = True) -> np.ndarray:
        """Eigenvalues (complex in general) of the normalised (or raw) map, by ascending real part."""
        A = self.normalised if normalised else self.displacement
        w = np.linalg.eigvals(A)
        return w[np.argsort(w.real)]

    def lambda_min(self, normalised: bool = True) -> float:
        """Smallest real part of the eigenvalues (Fig 3.20)."""
        return float(self.eigenvalues(normalised)[0].real)

    def symmetric_part_min(self, normalised: bool = True) -> float:
        """Smallest eigenvalue of the symmetric part: > 0 means x^T Gamma x > 0 for all x
        (positive definite in the sense 3.52 needs)."""
        A = self.normalised if normalised else self.displacement
        return float(np.linalg.eigvalsh(0.5 * (A + A.T))[0])

    def to_dict(self) -> dict:
        return {"displacement_m_per_V": self.displacement.tolist(), "normalised": self.normalised.tolist(),
                "reference_m_per_V": self.reference.tolist(), "lambda_min": self.lambda_min(),
                "symmetric_part_min": self.symmetric_part_min(), "source": self.source}


def eccentric_radii(theta: np.ndarray, Ro: float, Ri: float, dx: float, dy: float) -> dict[str, np.ndarray]:
    """Radii of the eccentric annulus along the ray at angle ``theta`` (outer circle of radius
    ``Ro`` centred at the origin c1, bore of radius ``Ri`` centred at (dx, dy)).

    Seen from a pole ``p``, a circle of radius R centred at ``c`` is met at
    ``r = (c - p).e + sqrt(R^2 - |c - p|^2 + ((c - p).e)^2)
       = |c - p| cos(theta - theta_c) + sqrt(R^2 - |c - p|^2 sin^2(theta - theta_c))``.
    Returns, from c1: ``outer`` = Ro, ``inner`` (bore); from the centroid
    ``c = -Ri^2 delta / (Ro^2 - Ri^2)``: ``R1`` (outer) and ``R2`` (bore) - the corrected 3.43,
    3.44 with ``R_o_bar = |c|`` (sqrt(x^2 + y^2), not sqrt((x + y)^2)) and ``R_i_bar = |delta - c|``,
    both **squared** under the root.  Also the local wall thickness ``t = Ro - inner``."""
    th = np.asarray(theta, dtype=float)
    d = np.array([dx, dy], dtype=float)
    c = -Ri**2 * d / (Ro**2 - Ri**2)

    def hit(center, pole, R):
        v = center - pole
        a = v[0] * np.cos(th) + v[1] * np.sin(th)
        disc = R**2 - (v @ v) + a**2
        if np.any(disc < 0):
            raise GeometryError("eccentric tube: the pole lies outside the circle")
        return a + np.sqrt(disc)

    inner = hit(d, np.zeros(2), Ri)
    return {"outer": np.full_like(th, Ro), "inner": inner, "t": Ro - inner,
            "R1": hit(np.zeros(2), c, Ro), "R2": hit(d, c, Ri), "centroid": c}


def _quarter_voltages(j: int) -> np.ndarray:
    """Voltages of the quarters (+x, +y, -x, -y) for a unit input u_j (GammaMatrix docstring)."""
    return [np.array([-1.0, 0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0, 1.0]), np.ones(4)][j]


def gamma_matrix(Re: float, Ri: float, length: float, delta_x: float = 0.0, delta_y: float = 0.0,
                 d31: float | None = None, material="pzt-5h", n_theta: int = 2048) -> GammaMatrix:
    """The corrected Rifai-Youcef-Toumi coupling (3.38-3.44) as a voltage -> tube-end
    displacement map [m/V] (:class:`GammaMatrix`, source frame).

    Model (thin-wall field, Euler-Bernoulli beam about the **centroid**):

    * quarters are angular sectors about the outer circle's centre c1 (where the electrodes
      are); along the ray at angle theta the wall spans ``inner(theta) <= r <= Re`` and the
      field is ``V / t(theta)`` inward, ``t = Re - inner`` (:func:`eccentric_radii`);
    * free strain ``Lambda = -d31 V / t`` (outer electrode at V, outward poling); its first moment about the centroid c,
      ``m = int Lambda (r - c) dA``, and its resultant ``n = int Lambda dA``, with
      ``int_{inner}^{Re} r^2 dr = (Re^3 - inner^3)/3`` (the f1, f2 of 3.40-3.41 with the shift
      of the pole to c1 and the term -c (Re^2 - inner^2)/2) and ``int r dr = (Re^2 - inner^2)/2``
      (3.42's f3 = Re + inner, halved);
    * curvature ``kappa = I_c^-1 m`` (``I_c`` the centroidal second-moment tensor, exact for the
      eccentric annulus), tip deflection ``-kappa L^2 / 2`` (towards the contracting side);
      extension ``n L / A``.

    Differences from the print: R_o_bar = sqrt(x^2 + y^2) and squared radii under the roots
    (SOURCE-NOTES 14); the cos(theta + theta_delta) of 3.40-3.41 is cos(theta) (a moment arm in
    fixed axes); the poles of R1/R2 (centroid) and of the electrode angles (c1) made consistent;
    f3 halved; the moments divided by I_c and the force by A to give displacements (the print's
    Gamma is a force map: see :meth:`GammaMatrix.force`).  Checked against the FEM in docs/piezo.md.
    """
    L = _pos("length", length)
    Re, Ri = _tube(Re, Ri)
    dlt = math.hypot(delta_x, delta_y)
    if dlt >= Re - Ri:
        raise GeometryError(f"eccentricity {dlt:g} m breaks the wall (Re - Ri = {Re - Ri:g} m)")
    if d31 is None:
        d31 = float(_mat(material).d[2, 0])
    D = _gamma_displacement(Re, Ri, L, delta_x, delta_y, d31, n_theta)
    D0 = _gamma_displacement(Re, Ri, L, 0.0, 0.0, d31, n_theta)
    return GammaMatrix(D, np.diag(D0).copy(),
                       f"formula: corrected Rifai & Youcef-Toumi (3.38-3.44), thin-wall field, "
                       f"Re={Re:g} Ri={Ri:g} L={L:g} delta=({delta_x:g}, {delta_y:g}) m, d31={d31:g}")


def _gamma_displacement(Re, Ri, L, dx, dy, d31, n_theta) -> np.ndarray:
    # midpoint rule per quarter (each quarter [c - 45, c + 45] deg, c = 0, 90, 180, 270)
    D = np.zeros((3, 3))
    rad = None
    Ao, Ai = math.pi * Re**2, math.pi * Ri**2
    A = Ao - Ai
    d = np.array([dx, dy])
    I0 = math.pi * (Re**4 - Ri**4) / 4
    Ic = I0 * np.eye(2) - (Ai * Ao / A) * np.outer(d, d)
    nq = max(16, n_theta // 4)
    m_q, n_q = [], []
    for q in range(4):
        a0 = math.radians(90 * q - 45)
        th = a0 + (np.arange(nq) + 0.5) * (math.pi / 2) / nq
        rad = eccentric_radii(th, Re, Ri, dx, dy)
        ri, t, c = rad["inner"], rad["t"], rad["centroid"]
        w = (math.pi / 2) / nq
        r3 = (Re**3 - ri**3) / 3.0
        r2 = (Re**2 - ri**2) / 2.0
        mx = np.sum((r3 * np.cos(th) - c[0] * r2) / t) * w
        my = np.sum((r3 * np.sin(th) - c[1] * r2) / t) * w
        m_q.append(-d31 * np.array([mx, my]))  # Lambda = -d31 V / t per volt
        n_q.append(-d31 * np.sum(r2 / t) * w)
    m_q, n_q = np.array(m_q), np.array(n_q)
    Icinv = np.linalg.inv(Ic)
    for j in range(3):
        V = _quarter_voltages(j)
        m = V @ m_q
        n = V @ n_q
        D[:2, j] = -0.5 * L**2 * (Icinv @ m)
        D[2, j] = L * n / A
    return D


def gamma_matrix_printed(Re: float, Ri: float, delta_x: float, delta_y: float, n_theta: int = 2048,
                         squared: bool = True) -> np.ndarray:
    """Eq 3.39 evaluated as printed (f1, f2, f3 of 3.40-3.42 with R1, R2 of 3.43-3.44), a
    geometric matrix in m^2 (rows 1-2) and m (row 3).  The printed R_o_bar = sqrt((x+y)^2) and the
    unsquared R_bar under the roots are dimensionally wrong; ``squared=True`` (default) uses
    R_o_bar = sqrt(x^2 + y^2) and squares R_bar so that it can be evaluated at all.  For the
    comparison of its *structure* (which entries couple, their sign and size relative to the
    diagonal) with the FEM; it has no u_z sign convention (column 3 as printed)."""
    Re, Ri = _tube(Re, Ri)
    d = np.array([delta_x, delta_y], dtype=float)
    c = -Ri**2 * d / (Re**2 - Ri**2)  # centroid relative to c1
    Rob = float(np.hypot(*c)) if squared else abs(c[0] + c[1])
    Rib = float(np.hypot(*(c - d)))
    thd = math.atan2(delta_y, delta_x) if np.any(d) else 0.0
    p = 2 if squared else 1

    def R12(th):
        R1 = Rob * np.cos(th - thd) + np.sqrt(Re**2 - Rob**p * np.sin(th - thd) ** 2)
        R2 = Rib * np.cos(th - thd) + np.sqrt(Ri**2 - Rib**p * np.sin(th - thd) ** 2)
        return R1, R2

    def integral(f, a, b):
        n = max(16, n_theta // 4)
        th = a + (np.arange(n) + 0.5) * (b - a) / n
        return float(np.sum(f(th)) * (b - a) / n)

    def f1(th):
        R1, R2 = R12(th)
        return (R1**3 - R2**3) * np.cos(th + thd) / (3 * (R1 - R2))

    def f2(th):
        R1, R2 = R12(th)
        return (R1**3 - R2**3) * np.sin(th + thd) / (3 * (R1 - R2))

    def f3(th):
        dd = math.hypot(delta_x, delta_y)
        return Re + dd * np.cos(th - thd) + np.sqrt(Ri**2 - dd**2 * np.sin(th - thd) ** 2)

    pi = math.pi
    G = np.zeros((3, 3))
    for i, f in enumerate((f1, f2, f3)):
        G[i, 0] = integral(f, -pi / 4, pi / 4) - integral(f, 3 * pi / 4, 5 * pi / 4)
        G[i, 1] = integral(f, pi / 4, 3 * pi / 4) - integral(f, 5 * pi / 4, 7 * pi / 4)
        G[i, 2] = integral(f, 0, 2 * pi)
    return G


# ---------------------------------------------------------------------------------------------
# Resonators (IEEE Std 176)
# ---------------------------------------------------------------------------------------------

def bar31_frequencies(length: float, material="pzt-5h", density: float | None = None) -> dict[str, float]:
    """First resonance ``f_r`` (short circuit) and antiresonance ``f_a`` (open circuit) [Hz] of
    a free length-extensional bar poled and electroded through its thickness, and
    ``k_eff^2 = (f_a^2 - f_r^2)/f_a^2`` (module docstring)."""
    m = _mat(material)
    rho = m.density if density is None else float(density)
    L = _pos("length", length)
    s11, d31, e33 = float(m.sE[0, 0]), float(m.d[2, 0]), float(m.epsT[2, 2])
    k2 = d31**2 / (s11 * e33)
    fr = 1.0 / (2 * L * math.sqrt(rho * s11))
    g = lambda fa: (math.pi / 2) * (fa / fr) * math.tan((math.pi / 2) * (fa - fr) / fr) - k2 / (1 - k2)  # noqa: E731
    fa = brentq(g, fr * (1 + 1e-12), fr * 1.999)
    return {"f_r": fr, "f_a": fa, "k_eff2": (fa**2 - fr**2) / fa**2, "k31_2": k2}


def rod33_frequencies(length: float, material="pzt-5h", density: float | None = None) -> dict[str, float]:
    """First resonance ``f_r`` (short circuit) and antiresonance ``f_a`` (open circuit) [Hz] of a
    free rod poled along its length with end electrodes, and ``k_eff^2``."""
    m = _mat(material)
    rho = m.density if density is None else float(density)
    L = _pos("length", length)
    s33, d33, e33 = float(m.sE[2, 2]), float(m.d[2, 2]), float(m.epsT[2, 2])
    k2 = d33**2 / (s33 * e33)
    fa = 1.0 / (2 * L * math.sqrt(rho * s33 * (1 - k2)))
    g = lambda fr: (math.pi / 2) * (fr / fa) * math.tan((math.pi / 2) * (fa - fr) / fa) - k2  # noqa: E731
    fr = brentq(g, fa * 0.3, fa * (1 - 1e-12))
    return {"f_r": fr, "f_a": fa, "k_eff2": (fa**2 - fr**2) / fa**2, "k33_2": k2}


__all__ = ["layer_constants", "induced_potential_factor", "bimorph_tip_deflection", "bimorph_tip_stiffness",
           "duo_bimorph_range", "tube_lateral_per_volt", "tube_axial_per_volt", "tube_voltage_ratio",
           "tube_sector_deflection", "GammaMatrix", "gamma_matrix", "gamma_matrix_printed", "eccentric_radii",
           "bar31_frequencies", "rod33_frequencies", "STATES"]
