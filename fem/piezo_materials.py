"""Piezoelectric ceramics: published constants, d-form -> e-form conversion, rotation to a poling.

Constitutive law (IEEE Std 176-1987 notation, Voigt order ``[11, 22, 33, 23, 13, 12]`` with
engineering shear strains, as in :mod:`probedyn.fem.materials`):

* d-form (strain-charge, the form of the data sheets)::

      S = s^E T + d^T E,        D = d T + eps^T E

* e-form (stress-charge, the form the FEM uses)::

      T = c^E S - e^T E,        D = e S + eps^S E

  with ``c^E = (s^E)^-1``, ``e = d c^E`` and ``eps^S = eps^T - d c^E d^T = eps^T - d e^T``
  (exact algebra: substitute ``T`` from the first d-form equation into the second).

For the 6mm (poled ceramic) class, poled along the local 3-axis::

      d = [[0,   0,   0,   0,   d15, 0],          eps = diag(eps11, eps11, eps33)
           [0,   0,   0,   d15, 0,   0],
           [d31, d31, d33, 0,   0,   0]]

Material data (Berlincourt, Curran & Jaffe, "Piezoelectric and piezomagnetic materials and their
function in transducers", in *Physical Acoustics* Vol. I-A, ed. W. P. Mason, Academic Press 1964;
the same numbers are the Vernitron/Morgan Electro Ceramics data-sheet values reproduced e.g. in
A. Erturk & D. J. Inman, *Piezoelectric Energy Harvesting*, Wiley 2011, Appendix E, and in the
COMSOL material library).  The d-form values are primary; the published e-form values
(``PUBLISHED_E_FORM``, same sources) are kept only to test the conversion: they were measured
and rounded separately, so they agree with the converted values to about 1 % (c^E), 3 % (e) and
5 % (eps^S; the clamped permittivities were measured at high frequency).

=======  ======  ======  ======  ======  ======  =====  =====  =====  ========  ========  =====
name     s11^E   s12^E   s13^E   s33^E   s44^E   d31    d33    d15    eps11^T   eps33^T   rho
         [1e-12 m^2/N]                           [1e-12 C/N]          [eps0]              kg/m^3
=======  ======  ======  ======  ======  ======  =====  =====  =====  ========  ========  =====
PZT-5H   16.5    -4.78   -8.45   20.7    43.5    -274   593    741    3130      3400      7500
PZT-4    12.3    -4.05   -5.31   15.5    39.0    -123   289    496    1475      1300      7500
=======  ======  ======  ======  ======  ======  =====  =====  =====  ========  ========  =====

(``s66 = 2 (s11 - s12)`` for the transversely isotropic ceramic.)  The mechanical part of
``pzt-5h`` equals :data:`probedyn.fem.materials.PZT5H_SE`, so the elastic-only probe models and
the coupled model describe the same solid.

Rotation: a poling orientation ``R`` (columns = local axes in global coordinates, local 3 = the
poling direction) gives ``c_glob = Q c Q^T``, ``e_glob = R e Q^T``, ``eps_glob = R eps R^T`` with
the Bond matrix ``Q`` of :func:`probedyn.fem.materials.bond_matrix` (from ``T_glob = Q T_loc``,
``E_loc = R^T E_glob``).  Opposite poling is a rotation by 180 degrees about an axis
perpendicular to the poling: c is unchanged (6mm symmetry), e changes sign.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence, Union

import numpy as np

from probedyn.core.errors import MaterialError
from probedyn.fem.materials import PZT5H_SE, Material, bond_matrix

EPS0 = 8.8541878128e-12  # vacuum permittivity [F/m]

Poling = Union[str, Sequence[float], np.ndarray, Callable[[np.ndarray], np.ndarray]]


@dataclass(frozen=True)
class PiezoMaterial:
    """A piezoelectric solid in its local axes (poled along local 3), e-form.

    ``cE`` (6, 6) [Pa], ``e`` (3, 6) [C/m^2], ``epsS`` (3, 3) [F/m], ``density`` [kg/m^3];
    ``d`` (3, 6) [C/N], ``sE`` (6, 6) [1/Pa] and ``epsT`` (3, 3) keep the d-form it came from.
    """

    name: str
    cE: np.ndarray = field(repr=False)
    e: np.ndarray = field(repr=False)
    epsS: np.ndarray = field(repr=False)
    density: float
    note: str = ""

    def __post_init__(self) -> None:
        cE = np.asarray(self.cE, dtype=float)
        e = np.asarray(self.e, dtype=float)
        eps = np.asarray(self.epsS, dtype=float)
        if cE.shape != (6, 6) or e.shape != (3, 6) or eps.shape != (3, 3):
            raise MaterialError(f"piezo material '{self.name}': need c^E 6x6, e 3x6, eps^S 3x3")
        if not (np.all(np.isfinite(cE)) and np.all(np.isfinite(e)) and np.all(np.isfinite(eps))):
            raise MaterialError(f"piezo material '{self.name}': non-finite constants")
        if not np.allclose(eps, eps.T) or np.linalg.eigvalsh(eps).min() <= 0:
            raise MaterialError(f"piezo material '{self.name}': eps^S must be symmetric positive definite")
        # the elastic part is validated by Material (symmetric, positive definite)
        object.__setattr__(self, "cE", Material(self.name, cE, float(self.density)).C)
        object.__setattr__(self, "e", e)
        object.__setattr__(self, "epsS", eps)

    # ---- d-form -----------------------------------------------------------------------------
    @classmethod
    def from_d_form(cls, sE: np.ndarray, d: np.ndarray, epsT: np.ndarray, density: float,
                    name: str = "piezo", note: str = "") -> "PiezoMaterial":
        """From compliances ``s^E`` (6, 6), charge constants ``d`` (3, 6) and free permittivity
        ``eps^T`` (3, 3): ``c^E = (s^E)^-1``, ``e = d c^E``, ``eps^S = eps^T - d c^E d^T``."""
        sE = np.asarray(sE, dtype=float)
        d = np.asarray(d, dtype=float)
        epsT = np.asarray(epsT, dtype=float)
        try:
            cE = np.linalg.inv(sE)
        except np.linalg.LinAlgError:
            raise MaterialError(f"piezo material '{name}': compliance s^E is singular") from None
        cE = 0.5 * (cE + cE.T)
        e = d @ cE
        epsS = epsT - d @ cE @ d.T
        epsS = 0.5 * (epsS + epsS.T)
        if np.linalg.eigvalsh(epsS).min() <= 0:
            raise MaterialError(f"piezo material '{name}': eps^T - d c^E d^T is not positive definite "
                                "(coupling factors >= 1: inconsistent data)")
        return cls(name, cE, e, epsS, float(density), note)

    @property
    def sE(self) -> np.ndarray:
        return np.linalg.inv(self.cE)

    @property
    def d(self) -> np.ndarray:
        """``d = e s^E`` [C/N]."""
        return self.e @ self.sE

    @property
    def epsT(self) -> np.ndarray:
        """``eps^T = eps^S + d e^T`` [F/m]."""
        return self.epsS + self.d @ self.e.T

    # ---- coupling factors (IEEE Std 176, 6mm) -------------------------------------------------
    def k31(self) -> float:
        """``k31^2 = d31^2 / (s11^E eps33^T)`` (length-extensional bar, field across)."""
        return float(np.sqrt(self.d[2, 0] ** 2 / (self.sE[0, 0] * self.epsT[2, 2])))

    def k33(self) -> float:
        """``k33^2 = d33^2 / (s33^E eps33^T)`` (long rod, field along)."""
        return float(np.sqrt(self.d[2, 2] ** 2 / (self.sE[2, 2] * self.epsT[2, 2])))

    def k15(self) -> float:
        return float(np.sqrt(self.d[0, 4] ** 2 / (self.sE[4, 4] * self.epsT[0, 0])))

    def kp(self) -> float:
        """Planar ``kp^2 = 2 d31^2 / ((s11^E + s12^E) eps33^T)``."""
        return float(np.sqrt(2 * self.d[2, 0] ** 2 / ((self.sE[0, 0] + self.sE[0, 1]) * self.epsT[2, 2])))

    def elastic(self, density: float | None = None) -> Material:
        """The mechanical part (short-circuit stiffness c^E) as a :class:`Material`."""
        rho = self.density if density is None else float(density)
        return Material(self.name, self.cE, rho, self.note + " (c^E, short circuit)")

    def with_density(self, rho: float) -> "PiezoMaterial":
        return PiezoMaterial(self.name, self.cE, self.e, self.epsS, float(rho), self.note + f"; density {rho:g}")

    # ---- rotation ----------------------------------------------------------------------------
    def rotated(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(c, e, eps) in global axes for orientation(s) ``R`` (3, 3) or (..., 3, 3)."""
        R = np.asarray(R, dtype=float)
        Q = bond_matrix(R)
        c = Q @ self.cE @ np.swapaxes(Q, -1, -2)
        e = R @ self.e @ np.swapaxes(Q, -1, -2)
        eps = R @ self.epsS @ np.swapaxes(R, -1, -2)
        return c, e, eps


def six_mm_tensors(s11: float, s12: float, s13: float, s33: float, s44: float, d31: float, d33: float,
                   d15: float, eps11T: float, eps33T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(s^E, d, eps^T) of a 6mm ceramic poled along 3 (SI units; ``s66 = 2 (s11 - s12)``)."""
    S = np.zeros((6, 6))
    S[0, 0] = S[1, 1] = s11
    S[2, 2] = s33
    S[0, 1] = S[1, 0] = s12
    S[0, 2] = S[2, 0] = S[1, 2] = S[2, 1] = s13
    S[3, 3] = S[4, 4] = s44
    S[5, 5] = 2 * (s11 - s12)
    d = np.zeros((3, 6))
    d[2, 0] = d[2, 1] = d31
    d[2, 2] = d33
    d[0, 4] = d[1, 3] = d15
    eps = np.diag([eps11T, eps11T, eps33T])
    return S, d, eps


#: d-form data [SI] (module docstring; Berlincourt et al. 1964).
D_FORM: dict[str, dict[str, float]] = {
    "pzt-5h": dict(**PZT5H_SE,  # the same s^E as the elastic material fem/materials.py 'pzt-5h'
                   d31=-274e-12, d33=593e-12, d15=741e-12, eps11T=3130 * EPS0, eps33T=3400 * EPS0,
                   rho=7500.0),
    "pzt-4": dict(s11=12.3e-12, s12=-4.05e-12, s13=-5.31e-12, s33=15.5e-12, s44=39.0e-12,
                  d31=-123e-12, d33=289e-12, d15=496e-12, eps11T=1475 * EPS0, eps33T=1300 * EPS0,
                  rho=7500.0),
}

#: Published e-form values from the same sources (for the conversion test only):
#: c^E [1e10 Pa] c11, c12, c13, c33, c44, c66; e [C/m^2] e31, e33, e15; eps^S [eps0] eps11, eps33;
#: published coupling factors k31, k33, k15, kp.
PUBLISHED_E_FORM: dict[str, dict[str, float]] = {
    "pzt-5h": dict(c11=12.6, c12=7.95, c13=8.41, c33=11.7, c44=2.30, c66=2.35, e31=-6.5, e33=23.3, e15=17.0,
                   eps11S=1700, eps33S=1470, k31=0.388, k33=0.752, k15=0.675, kp=0.65),
    "pzt-4": dict(c11=13.9, c12=7.78, c13=7.43, c33=11.5, c44=2.56, c66=3.06, e31=-5.2, e33=15.1, e15=12.7,
                  eps11S=730, eps33S=635, k31=0.334, k33=0.70, k15=0.71, kp=0.58),
}

_NOTES = {
    "pzt-5h": "PZT-5H, Berlincourt, Curran & Jaffe (1964) / Morgan Electro Ceramics data (d-form), "
              "converted to e-form",
    "pzt-4": "PZT-4, Berlincourt, Curran & Jaffe (1964) / Morgan Electro Ceramics data (d-form), "
             "converted to e-form",
}

#: Names of elastic materials (fem/materials.py) whose mechanical part is a piezo ceramic here.
ELASTIC_TWIN = {"pzt-5h": "pzt-5h"}


def piezo_material_names() -> list[str]:
    return list(D_FORM)


def get_piezo_material(name: str | PiezoMaterial, density: float | None = None) -> PiezoMaterial:
    """A piezoelectric material by name ('pzt-5h', 'pzt-4'); ``density`` overrides rho."""
    if isinstance(name, PiezoMaterial):
        return name if density is None else name.with_density(density)
    key = str(name).strip().lower()
    if key not in D_FORM:
        raise MaterialError(
            f"material '{name}' has no piezoelectric constants (piezoelectric materials: {', '.join(D_FORM)})")
    p = D_FORM[key]
    S, d, eps = six_mm_tensors(p["s11"], p["s12"], p["s13"], p["s33"], p["s44"], p["d31"], p["d33"], p["d15"],
                               p["eps11T"], p["eps33T"])
    rho = p["rho"] if density is None else float(density)
    return PiezoMaterial.from_d_form(S, d, eps, rho, key, _NOTES[key])


# ---------------------------------------------------------------------------------------------
# Poling orientations
# ---------------------------------------------------------------------------------------------

_AXES = {"x": 0, "y": 1, "z": 2}


def poling_rotation(direction: Sequence[float] | str) -> np.ndarray:
    """A proper rotation whose third column is the unit poling ``direction`` ('+z', '-z', 'x',
    or a vector).  The in-plane axes are arbitrary (the ceramic is transversely isotropic)."""
    if isinstance(direction, str):
        s = direction.strip().lower()
        sign = -1.0 if s.startswith("-") else 1.0
        ax = s.lstrip("+-")
        if ax not in _AXES:
            raise MaterialError(f"poling direction must be +x, -x, +y, -y, +z, -z or a vector, got {direction!r}")
        v = np.zeros(3)
        v[_AXES[ax]] = sign
    else:
        v = np.asarray(direction, dtype=float).reshape(3)
    n = np.linalg.norm(v)
    if not (np.isfinite(n) and n > 0):
        raise MaterialError(f"poling direction must be a non-zero vector, got {direction!r}")
    p = v / n
    # first local axis: the global axis least aligned with p, orthogonalised
    a = np.eye(3)[int(np.argmin(np.abs(p)))]
    t1 = a - (a @ p) * p
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(p, t1)
    return np.stack([t1, t2, p], axis=1)


__all__ = ["PiezoMaterial", "EPS0", "D_FORM", "PUBLISHED_E_FORM", "get_piezo_material", "piezo_material_names",
           "poling_rotation", "six_mm_tensors"]
