"""Modal results: classification, effective mass at the tip, participation, energy shares.

Classification (beam axis x, width y, thickness z)
--------------------------------------------------
The body is cut into ``n_slices`` slices along the beam axis.  In every slice the P2 nodal
displacements are fitted, in the mass-weighted least-squares sense (HRZ-lumped nodal
masses), by a rigid cross-section motion ``u = a + theta x (r - r_c)`` about the slice's
centre of mass ``r_c``.  The kinetic energy of the mode (with unit frequency) is then split
into the parts carried by

* ``flapwise``: ``a_z`` and ``theta_y`` (bending in the x-z plane),
* ``lateral``:  ``a_y`` and ``theta_z`` (bending in the x-y plane),
* ``torsion``:  ``theta_x`` (rotation about the beam axis),
* ``axial``:    ``a_x``,
* the residual (cross-section deformation, plate-like modes).

The family is the part with the largest share if that share exceeds ``threshold`` (0.5) and
``"other"`` otherwise.  The shares themselves are kept on the :class:`Mode` as
``family_shares`` so that callers can judge mixed modes.

Effective mass (source eqs 3.1–3.3 generalised)
-----------------------------------------------
With mass-normalised ``phi`` (``phi^T M phi = 1``) and the tip displacement component
``phi_d`` along direction d, ``m_eff,d = phi^T M phi / phi_d^2 = 1/phi_d^2`` and
``k_eff,d = omega^2 m_eff,d``: the mass and stiffness of a 1-DOF oscillator that has the
mode's kinetic and strain energy when its coordinate is the tip displacement along d.  A mode
that does not move the tip along d has ``m_eff,d = inf`` (JSON ``null``).

Participation (base excitation of the clamp along d)
----------------------------------------------------
``Gamma_d = phi^T M r_d`` with ``r_d`` the rigid translation along d of the free DOFs;
the effective modal mass is ``Gamma_d^2`` and its fraction ``Gamma_d^2 / (r_d^T M r_d)``
(the fractions over all modes sum to 1).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.fem.io import write_modes_json, write_modes_vtu

FAMILIES = ("flapwise", "lateral", "torsion", "axial", "other")
DIRS = ("x", "y", "z")


@dataclass
class Mode:
    """One eigenmode.  ``shape`` is the mass-normalised full DOF vector (interleaved
    ``3*node + component``, clamped DOFs zero)."""

    index: int
    frequency_hz: float
    omega: float
    family: str
    shape: np.ndarray = field(repr=False)
    tip_displacement: np.ndarray = field(default_factory=lambda: np.zeros(3))
    effective_mass_tip: dict[str, float] = field(default_factory=dict)
    effective_stiffness_tip: dict[str, float] = field(default_factory=dict)
    participation: dict[str, float] = field(default_factory=dict)
    effective_mass_fraction: dict[str, float] = field(default_factory=dict)
    kinetic_energy_share: dict[str, float] = field(default_factory=dict)
    family_shares: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "index": self.index,
            "frequency_hz": self.frequency_hz,
            "omega": self.omega,
            "family": self.family,
            "family_shares": self.family_shares,
            "tip_displacement": self.tip_displacement,
            "effective_mass_tip": self.effective_mass_tip,
            "effective_stiffness_tip": self.effective_stiffness_tip,
            "participation": self.participation,
            "effective_mass_fraction": self.effective_mass_fraction,
            "kinetic_energy_share": self.kinetic_energy_share,
        }


@dataclass
class ModalResult:
    """The lowest modes of an :class:`~probedyn.fem.model.ElasticModel`.

    ``dofs``: number of unknowns after eliminating clamped DOFs; ``total_dofs``: before;
    ``timings``: ``assemble_s``, ``factor_s``, ``solve_s`` [s]; ``solver``: backend name.
    """

    modes: list[Mode]
    dofs: int
    model: Any = field(repr=False, default=None)
    timings: dict[str, float] = field(default_factory=dict)
    total_dofs: int = 0
    solver: str = ""
    total_mass: float = 0.0
    tip_point: str = "tip"

    @property
    def frequencies_hz(self) -> np.ndarray:
        return np.array([m.frequency_hz for m in self.modes])

    def families(self) -> list[str]:
        return [m.family for m in self.modes]

    def first(self, family: str, n: int = 1) -> Mode | None:
        """The n-th (1-based) mode of a family, or None."""
        k = 0
        for m in self.modes:
            if m.family == family:
                k += 1
                if k == n:
                    return m
        return None

    def to_dict(self) -> dict[str, Any]:
        d = {
            "dofs": self.dofs,
            "total_dofs": self.total_dofs,
            "solver": self.solver,
            "timings": self.timings,
            "total_mass": self.total_mass,
            "tip_point": self.tip_point,
            "modes": [m.to_dict() for m in self.modes],
        }
        if self.model is not None and hasattr(self.model, "describe"):
            d["model"] = self.model.describe()
        return d

    def write_json(self, path: str | Path) -> Path:
        return write_modes_json(self, path)

    def write_vtu(self, path: str | Path) -> Path:
        return write_modes_vtu(self, path)


# ---------------------------------------------------------------------------------------


#: columns of the rigid-section fit (a_x, a_y, a_z, theta_x, theta_y, theta_z) per family
FAMILY_COLUMNS = {"flapwise": [2, 4], "lateral": [1, 5], "torsion": [3], "axial": [0]}


def section_slices(X: np.ndarray, weights: np.ndarray, n_slices: int = 24):
    """Slices of the body along ``X[0]`` (the beam axis first): yields ``(idx, sw, A)`` per slice
    with at least 4 nodes -- node indices, sqrt of their weights and the weighted rigid-section
    kinematic matrix ``A`` (3 m, 6) of ``u = a + theta x d`` (d from the slice's mass centre), so
    that ``lstsq(A, sw * u)`` is the mass-weighted rigid motion of the section."""
    s = X[0]
    edges = np.linspace(s.min(), s.max() + 1e-12 * (np.ptp(s) + 1), n_slices + 1)
    sl = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, n_slices - 1)
    for j in range(n_slices):
        idx = np.nonzero(sl == j)[0]
        if idx.size < 4:
            continue
        w = weights[idx]
        r = X[:, idx]
        d = r - ((r * w).sum(axis=1) / w.sum())[:, None]  # (3, m)
        m = idx.size
        G = np.zeros((m, 3, 6))
        G[:, 0, 0] = G[:, 1, 1] = G[:, 2, 2] = 1.0
        # theta x d = [ty dz - tz dy, tz dx - tx dz, tx dy - ty dx]
        G[:, 0, 4], G[:, 0, 5] = d[2], -d[1]
        G[:, 1, 3], G[:, 1, 5] = -d[2], d[0]
        G[:, 2, 3], G[:, 2, 4] = d[1], -d[0]
        sw = np.sqrt(w)
        yield idx, sw, (G * sw[:, None, None]).reshape(3 * m, 6)


def classify_shapes(
    coords: np.ndarray,
    weights: np.ndarray,
    U: np.ndarray,
    axis: int = 0,
    n_slices: int = 24,
    threshold: float = 0.5,
) -> tuple[list[str], list[dict[str, float]]]:
    """Classify displacement fields by cross-section kinematics (module docstring).

    ``coords`` (3, n) node positions; ``weights`` (n,) positive nodal masses; ``U`` (n, 3, k)
    nodal displacements of k modes.  ``axis``: the beam axis (0 = x; the other two axes are
    permuted so that "flapwise" is bending about the second transverse axis, i.e. for x:
    z-displacement).  Returns the family names and the energy shares per mode.
    """
    coords = np.asarray(coords, dtype=float)
    perm = [axis, (axis + 1) % 3, (axis + 2) % 3]
    X = coords[perm]  # (3, n): beam-axis, width, thickness
    Ub = U[:, perm, :]
    k = U.shape[2]
    parts = np.zeros((k, 5))  # flap, lat, tors, axial, residual
    total = np.einsum("n,nik->k", weights, Ub**2)
    for idx, sw, A in section_slices(X, weights, n_slices):
        m = idx.size
        b = (Ub[idx] * sw[:, None, None]).reshape(3 * m, k)
        coef, *_ = np.linalg.lstsq(A, b, rcond=None)  # (6, k)
        # kinetic-energy-like contributions of each kinematic group
        def energy(cols):
            c = np.zeros_like(coef)
            c[cols] = coef[cols]
            return ((A @ c) ** 2).sum(axis=0)

        e_flap = energy(FAMILY_COLUMNS["flapwise"])  # a_z, theta_y
        e_lat = energy(FAMILY_COLUMNS["lateral"])  # a_y, theta_z
        e_tor = energy(FAMILY_COLUMNS["torsion"])
        e_ax = energy(FAMILY_COLUMNS["axial"])
        e_fit = ((A @ coef) ** 2).sum(axis=0)
        e_all = (b**2).sum(axis=0)
        parts[:, 0] += e_flap
        parts[:, 1] += e_lat
        parts[:, 2] += e_tor
        parts[:, 3] += e_ax
        parts[:, 4] += np.maximum(e_all - e_fit, 0.0)
    fams, shares = [], []
    for i in range(k):
        tot = total[i] if total[i] > 0 else 1.0
        sh = parts[i] / tot
        names = ("flapwise", "lateral", "torsion", "axial", "deformation")
        shares.append({n: float(v) for n, v in zip(names, sh)})
        j = int(np.argmax(sh[:4]))
        fams.append(FAMILIES[j] if sh[j] >= threshold else "other")
    return fams, shares
