"""Linear elastic materials: 6x6 Voigt stiffness, density, rotation to a global frame.

Conventions
-----------
* Voigt order ``[11, 22, 33, 23, 13, 12]`` with **engineering** shear strains
  (``gamma_23 = 2 eps_23``), so ``sigma = C @ eps_voigt`` and the strain energy density is
  ``eps_voigt @ C @ eps_voigt / 2``.
* An *orientation* ``R`` is a proper rotation whose **columns are the material (local) axes
  expressed in global coordinates**: a vector with local components ``v_loc`` has global
  components ``R @ v_loc``.  The global stiffness is then
  ``C_glob_ijkl = R_ia R_jb R_kc R_ld C_loc_abcd`` (:func:`rotate_voigt`).  A piezoceramic
  poled along its local 3-axis with ``R[:, 2] = e_r`` is radially poled.
* Orientation per region is either a constant 3x3 matrix or a callable ``R(x)`` that takes
  global coordinates of shape ``(3, ...)`` and returns rotations of shape ``(..., 3, 3)``; the
  FEM evaluates it at the quadrature points (see :mod:`probedyn.fem.elasticity`).

Material table (values and sources are listed in ``docs/fem.md``):

=================  ============================================================  ==========
name               stiffness                                                      density
=================  ============================================================  ==========
silicon            isotropic, E = 169 GPa (Young's modulus along <110>), nu = 0.28  2330
silicon-110        cubic C11 = 165.7, C12 = 63.9, C44 = 79.6 GPa, local x || [110]   2330
silicon-nitride    isotropic, E = 250 GPa, nu = 0.23 (LPCVD Si3N4)                   3100
pzt-5h             transversely isotropic (6mm), s^E compliances, poled along 3      7500
pzt-5h-iso         isotropic with E = 1/s11^E, nu = -s12^E/s11^E (the source's      7500
                   assumption, eqs 3.13/3.18 use 1/s11)
=================  ============================================================  ==========
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Union

import numpy as np

from probedyn.core.errors import MaterialError

#: Voigt index pairs in the order used throughout probedyn.
VOIGT_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))

Orientation = Union[None, np.ndarray, Callable[[np.ndarray], np.ndarray]]


def _check_C(C: np.ndarray, name: str) -> np.ndarray:
    C = np.asarray(C, dtype=float)
    if C.shape != (6, 6) or not np.all(np.isfinite(C)):
        raise MaterialError(f"material '{name}': stiffness must be a finite 6x6 Voigt matrix")
    if not np.allclose(C, C.T, rtol=1e-10, atol=1e-12 * np.abs(C).max()):
        raise MaterialError(f"material '{name}': stiffness matrix is not symmetric")
    ev = np.linalg.eigvalsh(mandel(C))
    if ev.min() <= 1e-12 * ev.max():
        raise MaterialError(
            f"material '{name}': stiffness is not positive definite (smallest eigenvalue {ev.min():.3g} Pa)"
        )
    return C


def mandel(C: np.ndarray) -> np.ndarray:
    """Voigt (engineering shear) stiffness -> Mandel (Kelvin) form whose eigenvalues are
    rotation invariants of the 4th-order tensor.  Works on stacks ``(..., 6, 6)``."""
    s = np.array([1.0, 1.0, 1.0, np.sqrt(2), np.sqrt(2), np.sqrt(2)])
    return np.asarray(C) * s[:, None] * s[None, :]


def voigt_to_tensor(C: np.ndarray) -> np.ndarray:
    """6x6 Voigt stiffness -> 3x3x3x3 tensor ``C_ijkl`` with all minor symmetries."""
    T = np.zeros((3, 3, 3, 3))
    for I, (i, j) in enumerate(VOIGT_PAIRS):
        for J, (k, l) in enumerate(VOIGT_PAIRS):
            for a, b in ((i, j), (j, i)):
                for c, d in ((k, l), (l, k)):
                    T[a, b, c, d] = C[I, J]
    return T


def tensor_to_voigt(T: np.ndarray) -> np.ndarray:
    C = np.zeros((6, 6))
    for I, (i, j) in enumerate(VOIGT_PAIRS):
        for J, (k, l) in enumerate(VOIGT_PAIRS):
            C[I, J] = T[i, j, k, l]
    return C


def bond_matrix(R: np.ndarray) -> np.ndarray:
    """Bond stress-transformation matrix ``Q`` (Auld) for rotations ``R`` of shape (..., 3, 3).

    With engineering shear strains, ``C_glob = Q C_loc Q^T`` where
    ``Q_IJ = R_ik R_jl`` for a normal component ``J = (k, k)`` and
    ``Q_IJ = R_ik R_jl + R_il R_jk`` for a shear component ``J = (k, l)``, ``I = (i, j)``.
    """
    R = np.asarray(R, dtype=float)
    i = np.array([p[0] for p in VOIGT_PAIRS])
    j = np.array([p[1] for p in VOIGT_PAIRS])
    Q = R[..., i[:, None], i[None, :]] * R[..., j[:, None], j[None, :]]
    shear = R[..., i[:, None], j[None, :]] * R[..., j[:, None], i[None, :]]
    Q[..., :, 3:] += shear[..., :, 3:]
    return Q


def rotate_voigt(C: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Stiffness ``C`` (6x6, local axes) expressed in global axes for rotation(s) ``R``.

    ``R`` has shape (3, 3) or (..., 3, 3); its columns are the local axes in global
    coordinates.  Returns (6, 6) or (..., 6, 6).  Equivalent to
    ``C'_ijkl = R_ia R_jb R_kc R_ld C_abcd`` (tested against the tensor form).
    """
    Q = bond_matrix(R)
    return Q @ np.asarray(C, dtype=float) @ np.swapaxes(Q, -1, -2)


def rotation_about(axis: str | np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` [rad] about ``axis`` ('x', 'y', 'z' or a vector)."""
    if isinstance(axis, str):
        axis = {"x": [1.0, 0, 0], "y": [0, 1.0, 0], "z": [0, 0, 1.0]}[axis]
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def radial_poling(axis_point=(0.0, 0.0, 0.0), axis_dir=(0.0, 0.0, 1.0)) -> Callable[[np.ndarray], np.ndarray]:
    """Orientation callable for a tube poled radially about the line through ``axis_point``
    along ``axis_dir``: local 3 = radial unit vector e_r, local 1 = e_theta, local 2 = axis
    (so (e_theta, e_axis, e_r) is right-handed).  Use it as ``regions={"tube": (pzt, radial_poling())}``."""
    p0 = np.asarray(axis_point, dtype=float)
    d = np.asarray(axis_dir, dtype=float)
    d = d / np.linalg.norm(d)

    def R(x: np.ndarray) -> np.ndarray:
        x = np.moveaxis(np.asarray(x, dtype=float), 0, -1) - p0  # (..., 3)
        r = x - (x @ d)[..., None] * d
        n = np.linalg.norm(r, axis=-1, keepdims=True)
        if np.any(n == 0):
            raise MaterialError("radial poling is undefined on the tube axis")
        er = r / n
        dd = np.broadcast_to(d, er.shape)
        et = np.cross(dd, er)
        return np.stack([et, dd, er], axis=-1)  # columns = local axes 1, 2, 3

    return R



def transversely_isotropic_compliance(s11: float, s12: float, s13: float, s33: float, s44: float) -> np.ndarray:
    """6x6 Voigt compliance [1/Pa] of hexagonal / 6mm symmetry about the local 3-axis,
    ``s66 = 2 (s11 - s12)`` (engineering shear strains)."""
    S = np.zeros((6, 6))
    S[0, 0] = S[1, 1] = s11
    S[2, 2] = s33
    S[0, 1] = S[1, 0] = s12
    S[0, 2] = S[2, 0] = S[1, 2] = S[2, 1] = s13
    S[3, 3] = S[4, 4] = s44
    S[5, 5] = 2 * (s11 - s12)
    return S

@dataclass(frozen=True)
class Material:
    """A linear elastic material in its own (local) axes.

    ``C``: 6x6 Voigt stiffness [Pa] (engineering shear strains); ``density`` [kg/m^3];
    ``note``: provenance of the numbers.
    """

    name: str
    C: np.ndarray = field(repr=False)
    density: float
    note: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "C", _check_C(self.C, self.name))
        if not (np.isfinite(self.density) and self.density > 0):
            raise MaterialError(f"material '{self.name}': density must be positive, got {self.density}")

    # ---- constructors --------------------------------------------------------------
    @classmethod
    def isotropic(cls, E: float, nu: float, rho: float, name: str = "isotropic", note: str = "") -> "Material":
        """Isotropic Hooke law, ``lambda = E nu/((1+nu)(1-2nu))``, ``G = E/(2(1+nu))``.
        Requires ``E > 0`` and ``-1 < nu < 1/2`` (positive definiteness)."""
        if not (np.isfinite(E) and E > 0):
            raise MaterialError(f"material '{name}': Young's modulus must be positive, got {E}")
        if not (-1.0 < nu < 0.5):
            raise MaterialError(f"material '{name}': Poisson ratio must lie in (-1, 0.5), got {nu}")
        lam = E * nu / ((1 + nu) * (1 - 2 * nu))
        G = E / (2 * (1 + nu))
        C = np.zeros((6, 6))
        C[:3, :3] = lam
        C[[0, 1, 2], [0, 1, 2]] = lam + 2 * G
        C[[3, 4, 5], [3, 4, 5]] = G
        return cls(name, C, float(rho), note)

    @classmethod
    def cubic(cls, C11: float, C12: float, C44: float, rho: float, name: str = "cubic", note: str = "") -> "Material":
        """Cubic crystal in its crystal axes (x || [100], y || [010], z || [001])."""
        C = np.zeros((6, 6))
        C[:3, :3] = C12
        C[[0, 1, 2], [0, 1, 2]] = C11
        C[[3, 4, 5], [3, 4, 5]] = C44
        return cls(name, C, float(rho), note)

    @classmethod
    def from_compliance(cls, S: np.ndarray, rho: float, name: str = "anisotropic", note: str = "") -> "Material":
        """From a 6x6 Voigt compliance ``S`` [1/Pa] (engineering shear): ``C = S^-1``."""
        S = np.asarray(S, dtype=float)
        if S.shape != (6, 6):
            raise MaterialError(f"material '{name}': compliance must be 6x6")
        try:
            C = np.linalg.inv(S)
        except np.linalg.LinAlgError:
            raise MaterialError(f"material '{name}': compliance matrix is singular") from None
        return cls(name, 0.5 * (C + C.T), float(rho), note)

    @classmethod
    def transversely_isotropic(
        cls, s11: float, s12: float, s13: float, s33: float, s44: float, rho: float,
        name: str = "transversely-isotropic", note: str = "",
    ) -> "Material":
        """Hexagonal / 6mm symmetry about the local 3-axis from compliances [1/Pa]
        (``s66 = 2 (s11 - s12)``), e.g. a piezoceramic at constant electric field (s^E)."""
        return cls.from_compliance(transversely_isotropic_compliance(s11, s12, s13, s33, s44), rho, name, note)

    # ---- derived quantities ----------------------------------------------------------
    @property
    def S(self) -> np.ndarray:
        """Compliance ``C^-1`` [1/Pa]."""
        return np.linalg.inv(self.C)

    def youngs_modulus(self, direction=(1.0, 0.0, 0.0)) -> float:
        """Young's modulus along a unit direction ``n`` in local axes: ``1/E = n n : S : n n``."""
        n = np.asarray(direction, dtype=float)
        n = n / np.linalg.norm(n)
        e = np.array([n[0] ** 2, n[1] ** 2, n[2] ** 2, n[1] * n[2], n[0] * n[2], n[0] * n[1]])
        # stress sigma = n n (unit uniaxial); Voigt stress vector:
        return float(1.0 / (e @ self.S @ e))

    def with_overrides(self, E: float | None = None, nu: float | None = None, rho: float | None = None) -> "Material":
        """An isotropic copy with ``E``/``nu``/``rho`` replaced where given.

        Only meaningful for isotropic materials (an anisotropic one raises if E or nu is
        given); ``rho`` alone may be overridden for any material.
        """
        if E is None and nu is None:
            if rho is None:
                return self
            return Material(self.name, self.C, float(rho), self.note + f"; density overridden to {rho:g}")
        if not self.is_isotropic():
            raise MaterialError(
                f"material '{self.name}' is anisotropic: youngs_modulus/poisson_ratio cannot override it"
            )
        E0, nu0 = self.isotropic_constants()
        return Material.isotropic(
            E0 if E is None else float(E), nu0 if nu is None else float(nu),
            self.density if rho is None else float(rho), name=self.name,
            note=self.note + "; overridden",
        )

    def is_isotropic(self, rtol: float = 1e-9) -> bool:
        E, nu = self.isotropic_constants()
        if not (-1 < nu < 0.5):
            return False
        iso = Material.isotropic.__func__(Material, E, nu, self.density).C  # type: ignore[attr-defined]
        return bool(np.allclose(self.C, iso, rtol=rtol, atol=rtol * np.abs(self.C).max()))

    def isotropic_constants(self) -> tuple[float, float]:
        """(E, nu) from C11 and C12 (exact for an isotropic material)."""
        C11, C12 = self.C[0, 0], self.C[0, 1]
        nu = C12 / (C11 + C12)
        E = (C11 - C12) * (C11 + 2 * C12) / (C11 + C12)
        return float(E), float(nu)


# ---- the table -------------------------------------------------------------------------

# PZT-5H short-circuit compliances s^E [1/Pa] (Morgan Electro Ceramics / Berlincourt data,
# as tabulated in e.g. IEEE Std 176 examples): s11, s12, s13, s33, s44.
PZT5H_SE = dict(s11=16.5e-12, s12=-4.78e-12, s13=-8.45e-12, s33=20.7e-12, s44=43.5e-12)

_SI_C11, _SI_C12, _SI_C44 = 165.7e9, 63.9e9, 79.6e9  # Hopcroft, Nix, Kenny, JMEMS 19 (2010) 229


def _silicon_110() -> Material:
    cub = Material.cubic(_SI_C11, _SI_C12, _SI_C44, 2330.0)
    # Beam (global) axes in crystal coordinates: x || [110], y || [-110], z || [001].
    # The columns of R must be the crystal axes in beam coordinates, i.e. R's rows are the
    # beam axes in crystal coordinates.
    R = np.array([[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, np.sqrt(2.0)]]) / np.sqrt(2.0)
    C = rotate_voigt(cub.C, R)
    return Material(
        "silicon-110", C, 2330.0,
        "single-crystal Si, C11=165.7, C12=63.9, C44=79.6 GPa (Hopcroft et al. 2010), local x || [110], "
        "y || [-110], z || [001] (E_x = 169 GPa)",
    )


_TABLE: dict[str, Callable[[], Material]] = {
    "silicon": lambda: Material.isotropic(
        169e9, 0.28, 2330.0, "silicon",
        "isotropic approximation: E = 169 GPa (Si along <110>, Hopcroft et al. 2010), nu = 0.28, "
        "rho = 2330 kg/m^3",
    ),
    "silicon-110": _silicon_110,
    "silicon-nitride": lambda: Material.isotropic(
        250e9, 0.23, 3100.0, "silicon-nitride",
        "LPCVD Si3N4, typical E = 250 GPa (reported 200-310 GPa), nu = 0.23, rho = 3100 kg/m^3",
    ),
    "pzt-5h": lambda: Material.transversely_isotropic(
        **PZT5H_SE, rho=7500.0, name="pzt-5h",
        note="PZT-5H short-circuit compliances s^E (Morgan Electro Ceramics), poled along local 3; "
        "mechanical part only (no piezoelectric coupling)",
    ),
    "pzt-5h-iso": lambda: Material.isotropic(
        1.0 / PZT5H_SE["s11"], -PZT5H_SE["s12"] / PZT5H_SE["s11"], 7500.0, "pzt-5h-iso",
        "isotropic PZT-5H with E = 1/s11^E = 60.6 GPa and nu = -s12/s11 = 0.29, as the source assumes "
        "(eqs 3.13, 3.18 use 1/s11)",
    ),
}


def material_names() -> list[str]:
    return list(_TABLE)


def get_material(name: str | Material) -> Material:
    """A material from the table by name (case-insensitive); a :class:`Material` passes through."""
    if isinstance(name, Material):
        return name
    key = str(name).strip().lower()
    if key not in _TABLE:
        raise MaterialError(f"unknown material '{name}' (known: {', '.join(_TABLE)})")
    return _TABLE[key]()
