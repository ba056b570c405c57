"""An elastic FE model of a probe: mesh + per-region materials + clamps + point masses + springs.

Attachments ("where" a mass, spring or force acts) are named:

* a name in ``bundle.points`` (or a coordinate triple): the displacement is **interpolated**
  at that point (P2 shape functions).  Beware that a concentrated force or spring on a single
  point of a 3D continuum is singular (the point displacement diverges logarithmically under
  mesh refinement), so prefer
* a name in ``mesh.boundaries`` (e.g. ``"free_end"``): the **area-averaged** displacement of
  that face.  A mass attached this way is a point mass moving with the face's mean
  displacement (no rotary inertia); a force is applied as the uniform traction F/area; the
  pair is work-conjugate, so ``static_stiffness`` of a face is ``F / <u>``.

Matrices (:meth:`ElasticModel.assemble`): ``K = K_el + sum_springs k A^T D A`` and
``M = M_el + sum_masses m A^T A`` with ``A`` the (3, ndofs) attachment operator
(``A = A_a - A_b`` for a spring between two attachments; ``D = I`` for an isotropic spring,
``D = d d^T`` along a unit direction d).  Clamped DOFs (all three components of every P2 node
on a clamped boundary) are eliminated before solving.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Mapping, Sequence, Union

import numpy as np
import scipy.sparse as sp

from probedyn.core import progress
from probedyn.core.errors import GeometryError, MaterialError, ParameterError, SolverError
from probedyn.fem import elasticity as el
from probedyn.fem.assembly import element_kind, element_volumes
from probedyn.fem.eigen import Analysis, auto_method, factorize, have_pardiso, in_threads, matmat_threads, shift_invert_eigsh
from probedyn.fem.kernels import free_upper_pattern as _free_upper_pattern
from probedyn.fem.kernels import principal_submatrix as _principal_submatrix
from probedyn.fem.materials import Material, get_material
from probedyn.fem.modes import DIRS, ModalResult, Mode, classify_shapes
from probedyn.fem.size import check_model

Where = Union[str, Sequence[float], np.ndarray]


#: ElasticModel.free_matrices takes K's and M's free-DOF submatrices in two threads from this
#: many non-zeros of K (~60k DOFs; 0.55 s of compiled copying at 265k DOFs), as fem.eigen.MATMAT_MIN_WORK
FREE_THREADS_MIN_NNZ = 5_000_000


def principal_submatrix(A: sp.spmatrix, keep: np.ndarray) -> sp.csr_matrix:
    """``A[keep][:, keep]`` for sorted, unique ``keep`` as canonical CSR (sorted, no duplicates)
    by one compiled pass with a column map (:func:`probedyn.fem.kernels.principal_submatrix`;
    scipy's general column indexing took 1.2 s for K at 265k DOFs)."""
    A = sp.csr_matrix(A)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    keep = np.ascontiguousarray(keep, dtype=np.int64)
    new = np.full(A.shape[1], -1, dtype=np.int64)
    new[keep] = np.arange(keep.size)
    ptr, ind, val = _principal_submatrix(A.indptr.astype(np.int64, copy=False), A.indices, A.data, keep, new)
    out = sp.csr_matrix((val, ind, ptr), shape=(keep.size, keep.size))
    out.has_canonical_format = True
    return out


@dataclass(frozen=True)
class PointMass:
    """A rigid mass ``mass`` [kg] attached at ``point`` (a named point, a boundary name for a
    face-averaged attachment, or coordinates [m])."""

    point: Where
    mass: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.mass) and self.mass >= 0):
            raise ParameterError(f"point mass must be non-negative, got {self.mass} kg")


@dataclass(frozen=True)
class Spring:
    """A linear spring of ``stiffness`` [N/m] from ``point_a`` to ``point_b`` (None: to the
    ground).  ``direction`` None: isotropic (3 x 3 identity); else a unit vector along which the
    spring acts (only the relative displacement along it is resisted)."""

    point_a: Where
    point_b: Where | None
    stiffness: float
    direction: Sequence[float] | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.stiffness) and self.stiffness >= 0):
            raise ParameterError(f"spring stiffness must be non-negative, got {self.stiffness} N/m")
        if self.direction is not None and not np.linalg.norm(self.direction) > 0:
            raise ParameterError("spring direction must be a non-zero vector")


RegionSpec = Union[Material, str, tuple]


class ElasticModel:
    """Linear elastic P2 model on a :class:`~probedyn.meshes.cache.MeshBundle`.

    ``regions``: {subdomain name or '*': Material | material name | (Material, orientation)}
    with orientation None, a 3x3 rotation (columns = material axes in global coordinates) or
    a callable ``R(x)`` (x of shape (3, ...) -> (..., 3, 3)); '*' covers all elements not in a
    named region.  ``clamp``: boundary names whose P2 nodes are fixed (all components).
    ``tip``: the attachment whose displacement defines the effective mass (default "tip").
    ``beam_axis``: 0/1/2, the axis used by the mode classification.
    """

    def __init__(
        self,
        bundle,
        regions: Mapping[str, RegionSpec],
        clamp: Sequence[str] = (),
        point_masses: Sequence[PointMass] = (),
        springs: Sequence[Spring] = (),
        tip: Where = "tip",
        beam_axis: int = 0,
        name: str = "",
        element: str | None = None,
    ) -> None:
        self.bundle = bundle
        self.mesh = bundle.mesh
        self.name = name
        # the element kind: given, else the bundle's (its mesh builder chose it), else the
        # mesh type's default (tet-p2 on tetrahedra, hex-s2 on hexahedra)
        meta_el = (getattr(bundle, "meta", None) or {}).get("element")
        self.element_kind = element_kind(self.mesh, element or meta_el)
        self.element = self.element_kind.key
        self.region_names: list[str] = []
        self.materials: list[Material] = []
        self.orientations: list[Any] = []
        if not regions:
            raise MaterialError("model needs at least one region with a material")
        for rname, spec in regions.items():
            mat, R = spec if isinstance(spec, tuple) else (spec, None)
            self.region_names.append(rname)
            self.materials.append(get_material(mat))
            self.orientations.append(R)
        self.elem_region = el.element_regions(self.mesh, self.region_names)
        bnd = self.mesh.boundaries or {}
        for c in clamp:
            if c not in bnd:
                raise GeometryError(f"clamp '{c}' is not a boundary of the mesh (known: {', '.join(bnd) or 'none'})")
        self.clamp = list(clamp)
        self.point_masses = list(point_masses)
        self.springs = list(springs)
        self.tip = tip
        self.beam_axis = int(beam_axis)
        self._basis = None
        self._K = self._M = None
        self._Kel = self._Mel = None
        self.timings: dict[str, float] = {}
        self._anchor_cache: dict[Any, sp.csr_matrix] = {}

    # ---- discretisation -----------------------------------------------------------------
    @property
    def basis(self):
        """Scalar P2 basis (defines node numbering and positions ``basis.doflocs``)."""
        if self._basis is None:
            self._basis = el.scalar_basis(self.mesh, 1, self.element)
        return self._basis

    @property
    def n_nodes(self) -> int:
        return int(self.basis.N)

    @property
    def ndofs_total(self) -> int:
        return 3 * self.n_nodes

    @property
    def elem_density(self) -> np.ndarray:
        return np.array([m.density for m in self.materials])[self.elem_region]

    @property
    def clamped_dofs(self) -> np.ndarray:
        """Sorted clamped DOFs (read-only; found once per clamp list and basis: the facet-DOF
        search costs ~0.4 s at 265k DOFs)."""
        if not self.clamp:
            return np.zeros(0, dtype=np.int64)
        key = (tuple(self.clamp), id(self.basis))
        hit = getattr(self, "_clamped_cache", None)
        if hit is None or hit[0] != key or hit[1] is not self.basis:
            facets = np.concatenate([self.mesh.boundaries[c] for c in self.clamp])
            nodes = self.basis.get_dofs(facets=facets).all()
            dofs = np.sort((3 * nodes[:, None] + np.arange(3)[None, :]).ravel())
            mask = np.ones(self.ndofs_total, dtype=bool)
            mask[dofs] = False
            free = np.nonzero(mask)[0]
            dofs.setflags(write=False)
            free.setflags(write=False)
            self._clamped_cache = hit = (key, self.basis, dofs, free)
        return hit[2]

    @property
    def free_dofs(self) -> np.ndarray:
        """Sorted free DOFs (read-only)."""
        if not self.clamp:
            return np.arange(self.ndofs_total)
        self.clamped_dofs
        return self._clamped_cache[3]

    @property
    def dofs(self) -> int:
        """Number of unknowns after eliminating clamped DOFs."""
        return int(self.free_dofs.size)

    def attachment(self, where: Where) -> sp.csr_matrix:
        """(3, ndofs) operator giving the displacement at ``where`` (see module docstring)."""
        key = where if isinstance(where, str) else tuple(np.asarray(where, dtype=float).ravel())
        if key in self._anchor_cache:
            return self._anchor_cache[key]
        if isinstance(where, str):
            if where in self.bundle.points:
                A = el.interpolation_operator(self.basis, np.asarray(self.bundle.points[where], dtype=float))
            elif where in (self.mesh.boundaries or {}):
                A, _ = el.face_average_operator(self.mesh, self.mesh.boundaries[where], self.element)
            else:
                known = sorted(set(self.bundle.points) | set(self.mesh.boundaries or {}))
                raise GeometryError(f"unknown point or boundary '{where}' (known: {', '.join(known)})")
        else:
            x = np.asarray(where, dtype=float).reshape(3)
            A = el.interpolation_operator(self.basis, x)
        self._anchor_cache[key] = A
        return A

    def assemble(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """Full (unconstrained) K and M [N/m, kg] including springs and point masses."""
        if self._K is None:
            self._check_size()
            t0 = time.perf_counter()
            with progress.stage(f"assembling K and M ({self.dofs} DOFs)"):
                K = el.assemble_stiffness(self.mesh, self.elem_region, self.materials, self.orientations,
                                          element=self.element, basis=self.basis)
                t1 = time.perf_counter()
                M = el.assemble_mass(self.mesh, self.elem_density, element=self.element, basis=self.basis)
            t2 = time.perf_counter()
            self._Kel, self._Mel = K, M
            for pm in self.point_masses:
                if pm.mass > 0:
                    A = self.attachment(pm.point)
                    M = M + pm.mass * (A.T @ A)
            for s in self.springs:
                A = self.attachment(s.point_a)
                if s.point_b is not None:
                    A = A - self.attachment(s.point_b)
                if s.direction is None:
                    D = sp.identity(3)
                else:
                    d = np.asarray(s.direction, dtype=float)
                    d = d / np.linalg.norm(d)
                    D = sp.csr_matrix(np.outer(d, d))
                K = K + s.stiffness * (A.T @ D @ A)
            self._K, self._M = K.tocsr(), M.tocsr()
            self.timings.update(assemble_K_s=t1 - t0, assemble_M_s=t2 - t1,
                                assemble_s=time.perf_counter() - t0)
        return self._K, self._M

    def _check_size(self) -> None:
        """Announce a large model and refuse one too large (once per model: its DOFs are fixed)."""
        if not getattr(self, "_size_checked", False):
            check_model(self.dofs, self.name or "model", element=self.element)
            self._size_checked = True

    def start_analysis(self, options: dict | None = None) -> Analysis | None:
        """PARDISO's analysis of the free stiffness started in a background thread from the
        pattern the mesh implies (all 3 x 3 blocks of the node adjacency, clamped nodes removed),
        before any value is assembled (:class:`probedyn.fem.eigen.Analysis`; pass it to
        ``factorize`` / ``shift_invert_eigsh`` with ``K_ff``, which use it only if ``K_ff`` has
        exactly that pattern).  None without PARDISO.  The caller releases it."""
        if not have_pardiso():
            return None
        self._check_size()  # before any memory is committed to a model that cannot fit
        _, pat = el.pattern_of(self.mesh, self.element, self.basis)
        free_nodes = self.free_dofs[::3] // 3  # clamping fixes whole nodes: free DOFs come in triples
        node_new = np.full(self.n_nodes, -1, dtype=np.int64)
        node_new[free_nodes] = np.arange(free_nodes.size)
        ia, ja = _free_upper_pattern(pat.indptr, pat.indices, node_new, int(free_nodes.size))
        return Analysis(ia, ja, options)

    def free_matrices(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """K and M restricted to the free DOFs (clamped ones eliminated), kept until the model's
        matrices change; canonical CSR (sorted indices), so equal matrices have equal arrays."""
        K, M = self.assemble()
        if getattr(self, "_free_cache", None) is None or self._free_cache[0] is not K or self._free_cache[1] is not M:
            free = self.free_dofs
            out: list = [None, None]

            def take(i: int, A: sp.spmatrix) -> None:
                out[i] = principal_submatrix(A, free)

            if matmat_threads() > 1 and K.nnz >= FREE_THREADS_MIN_NNZ:  # K's and M's at once (nogil kernel)
                in_threads(take, [(0, K), (1, M)])
            else:
                take(0, K)
                take(1, M)
            Kf, Mf = out
            self._free_cache = (K, M, Kf, Mf)
        return self._free_cache[2], self._free_cache[3]

    def total_mass(self) -> float:
        K, M = self.assemble()
        r = np.zeros(self.ndofs_total)
        r[0::3] = 1.0
        return float(r @ (M @ r))

    def region_masses(self) -> dict[str, float]:
        vol = element_volumes(self.mesh)
        return {n: float((vol[self.elem_region == i] * self.materials[i].density).sum())
                for i, n in enumerate(self.region_names)}

    # ---- solutions ----------------------------------------------------------------------
    def modes(self, n_modes: int = 8, sigma: float | None = None, solver: str = "auto") -> ModalResult:
        """The lowest ``n_modes`` modes by shift-invert (see :mod:`probedyn.fem.eigen`)."""
        if int(n_modes) != n_modes or n_modes < 1:
            raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
        self.check_resolution(int(n_modes))
        if sigma is None and self.clamp:
            sigma = 0.0  # a clamped face removes all rigid motions: K_ff is positive definite
        # K_ff is factorised as it is (sigma = 0): its ordering can run while K and M are assembled
        # (with the single-precision setting when the size selects the mixed-precision solver)
        single = auto_method(int(self.free_dofs.size), sigma, solver=solver) == "mixed"
        analysis = (self.start_analysis({"single": 1} if single else None)
                    if (sigma == 0 and self._K is None and solver in ("auto", "pardiso")) else None)
        try:
            K, M = self.assemble()
            free = self.free_dofs
            Kf, Mf = self.free_matrices()
            with progress.stage(f"solving for {int(n_modes)} modes ({self.dofs} DOFs)"):
                res = shift_invert_eigsh(Kf, Mf, int(n_modes), sigma=sigma, solver=solver, analysis=analysis)
        finally:
            if analysis is not None:
                analysis.release()
        t0 = time.perf_counter()
        Phi = np.zeros((self.ndofs_total, res.vectors.shape[1]))
        Phi[free] = res.vectors
        modes = self._postprocess(res.eigenvalues, Phi, M, free)
        post_s = time.perf_counter() - t0
        timings = dict(self.timings)
        timings.update(factor_s=res.factor_s, solve_s=res.factor_s + res.solve_s, arpack_s=res.solve_s,
                       postprocess_s=post_s, n_opinv=res.n_opinv)
        return ModalResult(modes, self.dofs, self, timings, self.ndofs_total, res.backend,
                           self.total_mass(), self.tip if isinstance(self.tip, str) else "tip")

    def elements_along_axis(self) -> float:
        """Typical number of elements along ``beam_axis``: the body's extent along the axis over
        the edge of a regular tetrahedron (or of a cube, for hexahedra) of the mean element volume."""
        p = self.mesh.p
        vol = element_volumes(self.mesh)
        shape = 6.0 * np.sqrt(2.0) if self.element.startswith("tet") else 1.0
        h = (shape * vol.mean()) ** (1.0 / 3.0)
        extent = np.ptp(p[self.beam_axis])
        return float(extent / h)

    def check_resolution(self, n_modes: int) -> None:
        """Refuse a request the mesh cannot resolve.  The lowest ``n`` modes of a slender body
        contain bending modes with up to about ``n/2`` half-waves along its axis (flapwise and
        lateral families alternate, torsion and axial come in between); a P2 element per
        half-wave is the least that gives frequencies to a few per cent (Euler–Bernoulli beam
        elements need about the same), so at least ``n/2`` elements along the axis are required."""
        n_ax = self.elements_along_axis()
        need = 0.5 * n_modes
        if n_ax < need:
            raise SolverError(
                f"mesh too coarse for {n_modes} modes: about {n_ax:.0f} elements along the beam axis, "
                f"at least {need:.0f} needed; refine the mesh (element_size, elements_through_thickness) "
                f"or ask for fewer modes"
            )

    def _postprocess(self, lam: np.ndarray, Phi: np.ndarray, M: sp.csr_matrix, free: np.ndarray) -> list[Mode]:
        k = Phi.shape[1]
        # classification
        weights = el.lumped_weights(self.mesh, self.elem_density, self.element, self.basis)
        U = Phi.reshape(self.n_nodes, 3, k)
        fams, shares = classify_shapes(self.basis.doflocs, weights, U, axis=self.beam_axis)
        # tip displacement
        try:
            Atip = self.attachment(self.tip)
            tipd = (Atip @ Phi).T  # (k, 3)
        except GeometryError:
            tipd = np.full((k, 3), np.nan)
        # participation: rigid translation of the free DOFs (clamp moved as a base)
        MPhi = M @ Phi
        gam, frac = {}, {}
        for c, dname in enumerate(DIRS):
            r = np.zeros(self.ndofs_total)
            r[c::3] = 1.0
            r_f = np.zeros_like(r)
            r_f[free] = r[free]
            g = r_f @ MPhi
            mt = r_f @ (M @ r_f)
            gam[dname] = g
            frac[dname] = g**2 / mt if mt > 0 else np.full(k, np.nan)
        # kinetic energy per region (element-wise rho |phi|^2) and in point masses
        ke = self._region_kinetic(Phi)
        modes = []
        for i in range(k):
            omega = float(np.sqrt(max(lam[i], 0.0)))
            meff, keff = {}, {}
            for c, dname in enumerate(DIRS):
                u = tipd[i, c]
                big = np.max(np.abs(tipd[i])) if np.all(np.isfinite(tipd[i])) else 0.0
                if not np.isfinite(u) or abs(u) <= 1e-3 * max(big, 1e-300) or u == 0:
                    meff[dname] = float("inf")
                    keff[dname] = float("inf")
                else:
                    meff[dname] = float(1.0 / u**2)
                    keff[dname] = float(omega**2 / u**2)
            modes.append(Mode(
                index=i + 1, frequency_hz=omega / (2 * np.pi), omega=omega, family=fams[i],
                shape=Phi[:, i], tip_displacement=tipd[i].copy(),
                effective_mass_tip=meff, effective_stiffness_tip=keff,
                participation={d: float(gam[d][i]) for d in DIRS},
                effective_mass_fraction={d: float(frac[d][i]) for d in DIRS},
                kinetic_energy_share=ke[i], family_shares=shares[i],
            ))
        return modes

    def _region_kinetic(self, Phi: np.ndarray) -> list[dict[str, float]]:
        """Share of phi^T M phi in every region and in the point masses."""
        k = Phi.shape[1]
        out = [dict() for _ in range(k)]
        totals = np.einsum("ik,ik->k", Phi, self.assemble()[1] @ Phi)
        for r, name in enumerate(self.region_names):
            dens = np.where(self.elem_region == r, self.elem_density, 0.0)
            Mr = el.assemble_mass(self.mesh, dens, element=self.element, basis=self.basis)
            e = np.einsum("ik,ik->k", Phi, Mr @ Phi)
            for i in range(k):
                out[i][name] = float(e[i] / totals[i]) if totals[i] > 0 else float("nan")
        if self.point_masses:
            e = np.zeros(k)
            for pm in self.point_masses:
                u = self.attachment(pm.point) @ Phi
                e += pm.mass * (u**2).sum(axis=0)
            for i in range(k):
                out[i]["point_masses"] = float(e[i] / totals[i]) if totals[i] > 0 else float("nan")
        return out

    def static_displacement(self, force_at: Mapping[Any, Sequence[float]], solver: str = "auto") -> np.ndarray:
        """Full displacement vector [m] for static forces [N] at attachments
        (``{"free_end": (0, 0, 1e-6)}``: uniform traction over that face; keys may also be
        named points or coordinate tuples)."""
        if not self.clamp and not self.springs:
            raise SolverError("static solve needs a clamp or a grounded spring (the model floats freely)")
        K, _ = self.assemble()
        f = np.zeros(self.ndofs_total)
        for where, F in force_at.items():
            f += self.attachment(where).T @ np.asarray(F, dtype=float).reshape(3)
        free = self.free_dofs
        with progress.stage(f"factorising K for a static solve ({self.dofs} DOFs)"):
            fac = factorize(self.free_matrices()[0], spd=True, solver=solver)
        try:
            u = np.zeros(self.ndofs_total)
            u[free] = fac.solve(f[free])
        finally:
            fac.release()
        if not np.all(np.isfinite(u)):
            raise SolverError("static solve produced non-finite displacements (singular stiffness)")
        return u

    def vertex_displacement(self, u: np.ndarray) -> np.ndarray:
        """The P2 field ``u`` (full interleaved DOF vector) at the mesh vertices, (nverts, 3):
        the vertex DOFs of the scalar basis (Lagrange: nodal values are point values)."""
        U = np.asarray(u, dtype=float).reshape(self.n_nodes, 3)
        return U[self.basis.nodal_dofs[0]]

    def node_displacement(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(positions (N, 3), displacements (N, 3)) at all P2 nodes (vertices and edge midpoints)."""
        return self.basis.doflocs.T.copy(), np.asarray(u, dtype=float).reshape(self.n_nodes, 3)

    def points_operator(self, points: np.ndarray) -> sp.csr_matrix:
        """(3 m, 3 N) operator giving the displacement at the points (3, m) (row 3 j + c:
        component c at point j); one vectorised search of the mesh for all of them."""
        return el.interpolation_operator(self.basis, np.asarray(points, dtype=float).reshape(3, -1))

    def displacement_at(self, u: np.ndarray, where: Where) -> np.ndarray:
        """Displacement (3,) [m] of the full vector ``u`` at an attachment."""
        return np.asarray(self.attachment(where) @ u).ravel()

    def static_stiffness(self, point: Where = "tip", direction: Sequence[float] = (0, 0, 1),
                         solver: str = "auto") -> float:
        """``k = F / (d . u)`` [N/m] for a force F d at ``point`` along the unit ``direction`` d.

        With a boundary name the force is the uniform traction F/area and u the face-averaged
        displacement (work-conjugate, converges under refinement); at a single point the
        3D point-load displacement diverges slowly with refinement (use a face)."""
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        key = point if isinstance(point, str) else tuple(np.asarray(point, dtype=float).ravel())
        u = self.static_displacement({key: d}, solver=solver)
        ud = float(d @ self.displacement_at(u, point))
        if not ud > 0:
            raise SolverError(f"static stiffness at {point!r}: non-positive compliance {ud:g} m/N")
        return 1.0 / ud

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "regions": {n: {"material": m.name, "density": m.density, "oriented": R is not None}
                        for n, m, R in zip(self.region_names, self.materials, self.orientations)},
            "clamp": self.clamp,
            "point_masses": [{"point": p.point if isinstance(p.point, str) else list(map(float, p.point)),
                              "mass": p.mass} for p in self.point_masses],
            "springs": [{"a": s.point_a if isinstance(s.point_a, str) else list(map(float, s.point_a)),
                         "b": s.point_b if (s.point_b is None or isinstance(s.point_b, str)) else list(map(float, s.point_b)),
                         "stiffness": s.stiffness,
                         "direction": None if s.direction is None else list(map(float, s.direction))}
                        for s in self.springs],
            "vertices": int(self.mesh.p.shape[1]),
            "elements": int(self.mesh.t.shape[1]),
            "element": self.element_kind.title,
        }


__all__ = ["ElasticModel", "PointMass", "Spring"]
