"""An elastic model augmented by a lumped mass on springs: degrees of freedom off the mesh.

The source models the cantilever tip of the smart probes as a mass ``m`` on the holder spring
``k_t`` (eqs 3.4, 3.20). :class:`~probedyn.fem.model.ElasticModel` has point masses and springs
between mesh attachments only, so :class:`AugmentedModel` extends it by three extra degrees of
freedom ``q_t`` (the lumped mass's displacement) coupled to an attachment of the mesh ``A`` (a
face average, e.g. the holder end face) by a diagonal spring ``K_t = diag(k_tx, k_ty, k_tz)``::

    K_aug = [[K + A^T K_t A, -A^T K_t], [-K_t A, K_t]],   M_aug = [[M, 0], [0, m I]].

Modes of the augmented system are returned as ordinary :class:`~probedyn.fem.modes.Mode` s:
``shape`` is the mesh part (for rendering and VTU), ``tip_displacement`` the tip DOFs,
``effective_mass_tip[d] = 1 / q_t,d^2`` (the augmented shape is mass-normalised),
``kinetic_energy_share`` has one entry per region, ``point_masses`` and ``tip`` (the lumped
tip, m |q_t|^2), and ``strain_energy_share_holder_spring`` = ``(q_t - A phi)^T K_t (q_t - A phi)
/ omega^2`` is stored in ``family_shares['holder_spring_strain']``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from probedyn.core.errors import ParameterError
from probedyn.fem import elasticity as el
from probedyn.fem.eigen import shift_invert_eigsh
from probedyn.fem.model import ElasticModel
from probedyn.fem.modes import DIRS, ModalResult, Mode, classify_shapes


@dataclass(frozen=True)
class LumpedTip:
    """Tip mass ``mass`` [kg] on a diagonal spring ``stiffness`` (k_x, k_y, k_z) [N/m] to the
    attachment ``attach`` (a boundary name: face-averaged, or a named point)."""

    mass: float
    stiffness: tuple[float, float, float]
    attach: str

    def __post_init__(self) -> None:
        if not (np.isfinite(self.mass) and self.mass > 0):
            raise ParameterError(f"lumped tip mass must be positive, got {self.mass:g} kg")
        k = np.asarray(self.stiffness, dtype=float)
        if k.shape != (3,) or not np.all(np.isfinite(k)) or np.any(k <= 0):
            raise ParameterError(f"lumped tip stiffnesses must be three positive values, got {self.stiffness}")


class AugmentedModel(ElasticModel):
    """:class:`ElasticModel` plus an optional :class:`LumpedTip` (module docstring); without one
    it is the plain elastic model."""

    def __init__(self, *args, lumped_tip: LumpedTip | None = None, **kw) -> None:
        super().__init__(*args, **kw)
        self.lumped_tip = lumped_tip

    def describe(self) -> dict[str, Any]:
        d = super().describe()
        if self.lumped_tip is not None:
            d["lumped_tip"] = {"mass": self.lumped_tip.mass, "stiffness": list(self.lumped_tip.stiffness),
                               "attach": self.lumped_tip.attach}
        return d

    def vertex_displacement(self, shape: np.ndarray) -> np.ndarray:
        """(n_vertices, 3) displacement of a full DOF vector at the mesh vertices (the P2
        vertex nodes; interleaved numbering ``3 * node + component``)."""
        U = np.asarray(shape)[: self.ndofs_total].reshape(self.n_nodes, 3)
        return U[np.asarray(self.basis.nodal_dofs[0])]

    def augmented(self) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray, sp.csr_matrix]:
        """(K_aug, M_aug) restricted to the free mesh DOFs + 3 tip DOFs, the free DOF index
        array and the attachment operator A (3, ndofs_total)."""
        lt = self.lumped_tip
        K, M = self.assemble()
        free = self.free_dofs
        A = self.attachment(lt.attach).tocsr()
        Kt = sp.diags(np.asarray(lt.stiffness, dtype=float))
        Af = A[:, free]
        Kf, Mf = self.free_matrices()
        Kff = Kf + Af.T @ Kt @ Af
        Ka = sp.bmat([[Kff, -Af.T @ Kt], [-Kt @ Af, Kt]], format="csr")
        Ma = sp.bmat([[Mf, None], [None, sp.identity(3) * lt.mass]], format="csr")
        for X in (Ka, Ma):
            X.sum_duplicates()
            X.sort_indices()
        return Ka, Ma, free, A

    def modes(self, n_modes: int = 8, sigma: float | None = None, solver: str = "auto"):
        if self.lumped_tip is None:
            return super().modes(n_modes, sigma=sigma, solver=solver)
        if int(n_modes) != n_modes or n_modes < 1:
            raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
        Ka, Ma, free, A = self.augmented()
        res = shift_invert_eigsh(Ka, Ma, int(n_modes), sigma=sigma, solver=solver)
        timings = dict(factor_s=res.factor_s, solve_s=res.factor_s + res.solve_s, arpack_s=res.solve_s,
                       n_opinv=res.n_opinv)
        return self.result_from(res.eigenvalues, res.vectors, timings, res.backend)

    def result_from(self, eigenvalues: np.ndarray, vectors: np.ndarray, timings: dict | None = None,
                    solver: str = "") -> ModalResult:
        """The :class:`ModalResult` of eigenpairs ``(eigenvalues [rad^2/s^2], vectors)`` of the
        augmented system (vectors in its unknowns: free mesh DOFs + 3 tip DOFs, M-normalised),
        e.g. from a reduced model (:mod:`probedyn.lumped.ritz`); same post-processing as
        :meth:`modes`."""

        class _Res:  # the fields of an EigenResult the post-processing reads
            pass

        res = _Res()
        res.eigenvalues, res.vectors = np.asarray(eigenvalues, dtype=float), np.asarray(vectors, dtype=float)
        Ka, Ma, free, A = self.augmented()
        t0 = time.perf_counter()
        nf = free.size
        k = res.vectors.shape[1]
        Phi = np.zeros((self.ndofs_total, k))
        Phi[free] = res.vectors[:nf]
        qt = res.vectors[nf:].T  # (k, 3)
        _, M = self.assemble()
        weights = el.lumped_weights(self.mesh, self.elem_density, self.element, self.basis)
        fams, shares = classify_shapes(self.basis.doflocs, weights, Phi.reshape(self.n_nodes, 3, k), axis=self.beam_axis)
        ke = self.energy_shares(Phi, qt)
        uh = (A @ Phi).T  # holder attachment displacement (k, 3)
        kt = np.asarray(self.lumped_tip.stiffness, dtype=float)
        Ma_r = Ma @ res.vectors
        modes = []
        for i in range(k):
            lam = max(float(res.eigenvalues[i]), 0.0)
            omega = float(np.sqrt(lam))
            meff, keff, gam, frac = {}, {}, {}, {}
            big = float(np.max(np.abs(qt[i])))
            for c, d in enumerate(DIRS):
                u = float(qt[i, c])
                if abs(u) <= 1e-6 * max(big, 1e-300):
                    meff[d] = keff[d] = float("inf")
                else:
                    meff[d] = 1.0 / u**2
                    keff[d] = lam / u**2
                r = np.zeros(nf + 3)
                r[np.nonzero((free % 3) == c)[0]] = 1.0
                r[nf + c] = 1.0
                g = float(r @ Ma_r[:, i])
                mt = float(r @ (Ma @ r))
                gam[d], frac[d] = g, g * g / mt
            sh = dict(shares[i])
            dq = qt[i] - uh[i]
            sh["holder_spring_strain"] = float((kt * dq**2).sum() / lam) if lam > 0 else float("nan")
            modes.append(Mode(
                index=i + 1, frequency_hz=omega / (2 * np.pi), omega=omega, family=fams[i],
                shape=Phi[:, i], tip_displacement=qt[i].copy(), effective_mass_tip=meff,
                effective_stiffness_tip=keff, participation=gam, effective_mass_fraction=frac,
                kinetic_energy_share=ke[i], family_shares=sh,
            ))
        all_t = dict(self.timings)
        all_t.update(timings or {})
        all_t.update(postprocess_s=time.perf_counter() - t0)
        return ModalResult(modes, int(nf + 3), self, all_t, self.ndofs_total + 3, solver,
                           self.total_mass() + self.lumped_tip.mass, "tip")

    def energy_shares(self, Phi: np.ndarray, qt: np.ndarray | None = None) -> list[dict[str, float]]:
        """Kinetic-energy shares (``phi^T M_region phi`` / total) per region, of the point
        masses and of the lumped tip, for mesh shapes ``Phi`` (ndofs, k) and tip DOFs ``qt``."""
        k = Phi.shape[1]
        parts: dict[str, np.ndarray] = {}
        for r, name in enumerate(self.region_names):
            dens = np.where(self.elem_region == r, self.elem_density, 0.0)
            Mr = el.assemble_mass(self.mesh, dens, element=self.element, basis=self.basis)
            parts[name] = np.einsum("ik,ik->k", Phi, Mr @ Phi)
        if self.point_masses:
            e = np.zeros(k)
            for pm in self.point_masses:
                u = self.attachment(pm.point) @ Phi
                e += pm.mass * (np.asarray(u) ** 2).sum(axis=0)
            parts["point_masses"] = e
        if qt is not None and self.lumped_tip is not None:
            parts["tip"] = self.lumped_tip.mass * (qt**2).sum(axis=1)
        tot = sum(parts.values())
        return [{n: float(v[i] / tot[i]) if tot[i] > 0 else float("nan") for n, v in parts.items()} for i in range(k)]
