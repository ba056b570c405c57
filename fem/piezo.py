"""Coupled piezoelectric FEM: displacement u and electric potential phi on P2 tetrahedra.

Formulation (linear piezoelectricity, e-form, quasi-electrostatics, no free volume charge)
-----------------------------------------------------------------------------------------
``T = c^E S - e^T E``, ``D = e S + eps^S E``, ``E = -grad phi``.  Find (u, phi) such that for
all (v, psi)::

    int S(v)^T c^E S(u) + int S(v)^T e^T grad(phi) = f(v)                (momentum, static)
    int grad(psi)^T e S(u) - int grad(psi)^T eps^S grad(phi) = -q(psi)   (Gauss's law)

with ``q`` the charge on electrode surfaces (zero on every free surface: the natural condition
``D . n = 0``).  Discretised with the same P2 functions for u (vector) and phi (scalar, only on
the nodes of piezoelectric elements)::

    [ K_uu       K_uphi  ] [u  ]   [ f ]          K_uu   = int B_u^T c^E B_u
    [ K_uphi^T  -K_phiphi] [phi] = [-q ],         K_uphi = int B_u^T e^T B_phi
                                                  K_phiphi = int B_phi^T eps^S B_phi

(Allik & Hughes, Int. J. Numer. Meth. Eng. 2 (1970) 151).  ``B_phi`` is the 3 x 10 gradient
matrix of the scalar P2 functions.  ``K_uu`` (and the mass, springs, point masses and a lumped
tip) come from the mechanical model, an :class:`~probedyn.fem.model.ElasticModel`; the coupling
blocks are assembled here element-chunk-wise by batched matrix products like
:func:`probedyn.fem.elasticity.assemble_stiffness` (degree-2 rule: exact for a constant
material; a poling that varies in space, e.g. radial, is sampled at the quadrature points).

Electrodes (boundary conditions on phi)
---------------------------------------
An electrode is a tagged mesh surface (``mesh.boundaries``).  A model has a *layout*: a list
of electrodes that do not overlap (e.g. the four quarters and the inner electrode of a tube).
Each electrode of the layout is, for one solve,

* **driven** at a voltage V (``ground`` is V = 0): its phi nodes are prescribed;
* **floating** (open circuit): its phi nodes share **one** unknown and its net charge is zero
  (the Gauss equations of its nodes are summed).

A node on the common edge of k electrodes of the layout (adjacent sectors) takes the mean of
their k potentials: an inter-electrode gap of vanishing width, linear in the voltages and
without any gap between electrodes at the same potential.  Everything else is free
(``D . n = 0``).

Elimination: with ``phi = T phi_r + P V`` (``T``: free and floating unknowns -> nodes, ``P``:
driven voltages -> nodes) the system in (u, phi_r) is symmetric indefinite::

    [ K_uu     K_ur ] [u    ]   [ f - K_uphi P V    ]       K_ur = K_uphi T
    [ K_ur^T  -K_rr ] [phi_r] = [ T^T K_phiphi P V  ]       K_rr = T^T K_phiphi T

Solvers (``solver=``; measured in docs/piezo.md):

* ``"indefinite"`` (default): MKL PARDISO symmetric indefinite (``mtype = -2``) on the whole
  system after scaling phi by ``alpha = sqrt(mean diag K_uu / mean diag K_rr)`` (the blocks
  differ by ~19 orders of magnitude in SI units), with residual check and iterative refinement;
* ``"schur"``: static condensation of the potential, ``S = K_uu + K_ur K_rr^-1 K_ur^T`` (never
  formed: it is dense in each piezo region), solved by conjugate gradients preconditioned with
  the factorised ``K_uu`` (both factorisations SPD).  The spectrum of ``K_uu^-1 S`` lies in
  ``[1, 1/(1 - k^2)]`` with k the largest coupling factor, so CG needs ~10-20 iterations.

Modes: the potential has no inertia, so the modes are those of the condensed stiffness
``K_eff = K_uu + K_ur K_rr^-1 K_ur^T`` with the mass ``M``: shift-invert ARPACK with
``(K_eff - sigma M)^-1 x`` = the u-part of a coupled solve with right-hand side ``[x; 0]``.
Short circuit (all electrodes grounded) and open circuit (electrodes floating, one reference
grounded) give ``f_sc <= f_oc`` and ``k_eff^2 = (f_oc^2 - f_sc^2) / f_oc^2``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence, Union

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from probedyn.core.errors import GeometryError, MaterialError, ParameterError, SolverError
from probedyn.fem import elasticity as el
from probedyn.fem.eigen import factorize
from probedyn.fem.materials import rotate_voigt
from probedyn.fem.modes import classify_shapes
from probedyn.fem.piezo_materials import PiezoMaterial, get_piezo_material, poling_rotation

SOLVERS = ("indefinite", "schur")
State = Union[float, str]  # a voltage, "ground" or "float"/"open"

Poling = Union[str, Sequence[float], np.ndarray, Callable[[np.ndarray], np.ndarray], None]


# ---------------------------------------------------------------------------------------------
# poling
# ---------------------------------------------------------------------------------------------

def _poling_spec(region: str, poling: Poling):
    """Normalise a poling: None -> error; str/vector -> constant rotation; (3, 3) -> checked
    rotation; callable -> itself (evaluated at quadrature points)."""
    if poling is None:
        raise MaterialError(f"piezoelectric region '{region}' has no poling direction (give '+z', '-z', a vector, "
                            f"a rotation or radial_poling())")
    if callable(poling):
        return poling
    if isinstance(poling, str):
        return poling_rotation(poling)
    a = np.asarray(poling, dtype=float)
    if a.shape == (3,):
        return poling_rotation(a)
    if a.shape == (3, 3):
        if not np.allclose(a @ a.T, np.eye(3), atol=1e-9) or np.linalg.det(a) < 0:
            raise MaterialError(f"poling of region '{region}': not a proper rotation matrix")
        return a
    raise MaterialError(f"poling of region '{region}': expected '+z', a 3-vector, a 3x3 rotation or a callable")


def _eval_rotation(R, x_qp: np.ndarray) -> np.ndarray:
    """Rotations (nel, nq, 3, 3) at quadrature points ``x_qp`` (3, nel, nq)."""
    nel, nq = x_qp.shape[1], x_qp.shape[2]
    if callable(R):
        Rq = np.asarray(R(x_qp), dtype=float)
        if Rq.shape != (nel, nq, 3, 3):
            raise MaterialError(f"poling callable returned shape {Rq.shape}, expected {(nel, nq, 3, 3)}")
        return Rq
    return np.broadcast_to(np.asarray(R, dtype=float), (nel, nq, 3, 3))


# ---------------------------------------------------------------------------------------------
# assembly of the coupling blocks
# ---------------------------------------------------------------------------------------------

def assemble_piezo_blocks(mesh, elem_piezo: np.ndarray, materials: Sequence[PiezoMaterial],
                          polings: Sequence[Any], chunk: int = 4096) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """``K_uphi`` (3N x N) and ``K_phiphi`` (N x N) in the global scalar P2 numbering (N nodes;
    u interleaved ``3 s + c``), from the elements with ``elem_piezo >= 0`` (index into
    ``materials``/``polings``).  Batched element matrices, one COO -> CSR conversion."""
    from skfem import ElementTetP2
    from skfem.quadrature import get_quadrature

    elem = ElementTetP2()
    X, W = get_quadrature(elem.refdom, el.STIFFNESS_INTORDER)
    nq = W.size
    mapping = mesh._mapping()
    dref = np.stack([elem.lbasis(X, i)[1] for i in range(10)])  # (10, 3, nq)
    basis0 = el.scalar_basis(mesh, 1)
    edofs = basis0.element_dofs  # (10, nel)
    N = basis0.N
    ldof = np.arange(30)
    a_idx, c_idx = ldof // 3, ldof % 3
    pel = np.nonzero(elem_piezo >= 0)[0]
    ru, cu, du, rp, cp, dp = [], [], [], [], [], []
    for a0 in range(0, pel.size, chunk):
        sel = pel[a0:a0 + chunk]
        invDF = mapping.invDF(X, tind=sel)
        detDF = np.abs(mapping.detDF(X, tind=sel))
        g = np.einsum("akq,kjeq->eqaj", dref, invDF, optimize=True)  # (e, q, 10, 3)
        B = el.strain_operator(g)  # (e, q, 6, 30)
        Bp = np.swapaxes(g, 2, 3)  # (e, q, 3, 10): grad phi = Bp @ phi_e
        x_qp = mapping.F(X, tind=sel)
        E = np.empty((sel.size, nq, 3, 6))
        P = np.empty((sel.size, nq, 3, 3))
        reg = elem_piezo[sel]
        for i, (mat, R) in enumerate(zip(materials, polings)):
            s = np.nonzero(reg == i)[0]
            if s.size == 0:
                continue
            Rq = _eval_rotation(R, x_qp[:, s, :])
            _, e_g, eps_g = mat.rotated(Rq)
            E[s] = e_g
            P[s] = eps_g
        wq = detDF * W[None, :]
        # K_uphi^e = sum_q w B^T e^T Bp ; K_phiphi^e = sum_q w Bp^T eps Bp
        eBp = np.matmul(np.swapaxes(E, 2, 3), Bp) * wq[:, :, None, None]  # (e, q, 6, 10)
        Kup = np.einsum("eqIa,eqIb->eab", B, eBp, optimize=True)  # (e, 30, 10)
        epsBp = np.matmul(P, Bp) * wq[:, :, None, None]
        Kpp = np.einsum("eqia,eqib->eab", Bp, epsBp, optimize=True)  # (e, 10, 10)
        gu = (3 * edofs[a_idx][:, sel] + c_idx[:, None]).T  # (e, 30)
        gp = edofs[:, sel].T  # (e, 10)
        ru.append(np.repeat(gu, 10, axis=1).ravel())
        cu.append(np.tile(gp, (1, 30)).ravel())
        du.append(Kup.ravel())
        rp.append(np.repeat(gp, 10, axis=1).ravel())
        cp.append(np.tile(gp, (1, 10)).ravel())
        dp.append(Kpp.ravel())
    if not du:
        raise MaterialError("no piezoelectric elements")
    Kup = sp.coo_matrix((np.concatenate(du), (np.concatenate(ru), np.concatenate(cu))), shape=(3 * N, N)).tocsr()
    Kpp = sp.coo_matrix((np.concatenate(dp), (np.concatenate(rp), np.concatenate(cp))), shape=(N, N)).tocsr()
    Kup.sum_duplicates()
    Kpp.sum_duplicates()
    return Kup, Kpp


def _columnwise(fac):
    """Wrap a factorisation so that 2-D right-hand sides are solved column by column."""
    solve1 = fac.solve

    def solve(b):
        b = np.asarray(b, dtype=float)
        if b.ndim == 1:
            return solve1(b)
        return np.column_stack([solve1(np.ascontiguousarray(b[:, j])) for j in range(b.shape[1])])
    fac.solve = solve
    return fac


# ---------------------------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------------------------

@dataclass
class PiezoStatic:
    """A static coupled solution.

    ``u``: full displacement vector (interleaved, clamped DOFs zero) [m]; ``extra``: the lumped
    tip DOFs (3,) of a model with a lumped tip (else empty); ``phi``: potential at the nodes
    ``phi_nodes`` (global scalar P2 indices) [V]; ``potentials`` / ``charges``: per electrode of
    the layout [V] / [C] (the charge on a floating electrode is zero by construction)."""

    u: np.ndarray = field(repr=False)
    extra: np.ndarray = field(repr=False)
    phi: np.ndarray = field(repr=False)
    phi_nodes: np.ndarray = field(repr=False)
    potentials: dict[str, float]
    charges: dict[str, float]
    dofs: int
    solver: str
    timings: dict[str, float]
    model: Any = field(repr=False, default=None)

    def displacement_at(self, where) -> np.ndarray:
        """Displacement (3,) [m] at an attachment of the mechanical model (face name: area average)."""
        return np.asarray(self.model.mech.attachment(where) @ self.u).ravel()

    def phi_full(self) -> np.ndarray:
        """Potential on all scalar P2 nodes (NaN off the piezoelectric elements)."""
        out = np.full(self.model.mech.n_nodes, np.nan)
        out[self.phi_nodes] = self.phi
        return out

    def write_vtu(self, path) -> Any:
        """VTU (quadratic tetrahedra, VTK tetra10 order) with point fields ``displacement`` [m]
        and ``potential`` [V] (0 off the piezoelectric regions), written atomically."""
        import meshio

        from probedyn.core.io import atomic_path
        from probedyn.fem.io import tetra10_connectivity

        mech = self.model.mech
        conn = tetra10_connectivity(mech.mesh, mech.basis)
        phi = np.nan_to_num(self.phi_full(), nan=0.0)
        m = meshio.Mesh(mech.basis.doflocs.T, [("tetra10", conn)],
                        point_data={"displacement": self.u.reshape(mech.n_nodes, 3), "potential": phi},
                        cell_data={"piezo_region": [self.model.elem_piezo.astype(np.int32)]})
        from pathlib import Path

        path = Path(path)
        with atomic_path(path) as tmp:
            meshio.write(tmp, m, file_format="vtu")
        return path


@dataclass
class PiezoModes:
    """Modes of the coupled model with given electrical conditions.

    ``frequencies_hz`` (k,); ``shapes`` (ndofs_total, k) M-orthonormal displacement fields;
    ``extra`` (k, n_extra) lumped-tip DOFs; ``phi`` (n_phi, k) modal potentials [V per unit
    modal amplitude]; ``floating`` {electrode: (k,) modal potential}; ``families``."""

    frequencies_hz: np.ndarray
    shapes: np.ndarray = field(repr=False)
    extra: np.ndarray = field(repr=False)
    phi: np.ndarray = field(repr=False)
    families: list[str]
    family_shares: list[dict[str, float]]
    tip_displacement: np.ndarray = field(repr=False)
    electrodes: dict[str, str]
    floating: dict[str, np.ndarray]
    dofs: int
    solver: str
    timings: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        return {"frequencies_hz": self.frequencies_hz, "families": self.families, "electrodes": self.electrodes,
                "dofs": self.dofs, "solver": self.solver, "timings": self.timings,
                "tip_displacement": self.tip_displacement}


def match_modes(Ma: sp.spmatrix, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """For every column of ``A`` the index of the column of ``B`` with the largest modal
    assurance |a^T M b| (both M-orthonormal)."""
    C = np.abs(A.T @ (Ma @ B))
    return np.argmax(C, axis=1)


def coupling_factors(f_sc: np.ndarray, f_oc: np.ndarray) -> np.ndarray:
    """``k_eff^2 = (f_oc^2 - f_sc^2) / f_oc^2`` per mode (IEEE Std 176 effective coupling)."""
    f_sc, f_oc = np.asarray(f_sc, dtype=float), np.asarray(f_oc, dtype=float)
    return (f_oc**2 - f_sc**2) / f_oc**2


# ---------------------------------------------------------------------------------------------
# the model
# ---------------------------------------------------------------------------------------------

class PiezoModel:
    """Electromechanical model on top of a mechanical model ``mech``.

    ``piezo_regions``: {mesh subdomain: (piezo material or name, poling)}; the poling is '+z',
    '-z', a vector, a 3x3 rotation (third column = poling) or a callable ``R(x)`` such as
    :func:`probedyn.fem.materials.radial_poling`.  The elastic tensor that ``mech`` uses in
    these elements must be the material's c^E in that orientation (checked; the density may
    differ).  ``electrodes``: the layout (non-overlapping electrode surfaces; default: every
    boundary whose name starts with ``electrode``).  ``reference``: the electrode grounded in
    open-circuit solves.  ``tip``: the attachment reported as the tip (default ``mech.tip``).
    ``fixed_dofs``: extra fixed mechanical DOFs (full interleaved indices), e.g. a 3-2-1
    support of a free body.
    """

    def __init__(self, mech, piezo_regions: Mapping[str, tuple], electrodes: Sequence[str] | None = None,
                 reference: str | None = None, tip: Any = None, fixed_dofs: Sequence[int] = ()) -> None:
        self.mech = mech
        self.mesh = mech.mesh
        if self.mesh.t.shape[0] != 4:
            raise SolverError(f"the piezoelectric FEM assembles P2 tetrahedra; this mesh has {self.mesh.t.shape[0]}-node "
                              f"elements (build the probe with a tetrahedral mesh)")
        subs = self.mesh.subdomains or {}
        bnd = self.mesh.boundaries or {}
        if not piezo_regions:
            raise MaterialError("piezo model needs at least one piezoelectric region")
        nel = self.mesh.t.shape[1]
        self.elem_piezo = np.full(nel, -1, dtype=np.int64)
        self.region_names: list[str] = []
        self.materials: list[PiezoMaterial] = []
        self.polings: list[Any] = []
        for i, (rname, spec) in enumerate(piezo_regions.items()):
            if rname not in subs:
                raise MaterialError(f"piezo region '{rname}' is not a mesh subdomain (known: {', '.join(subs)})")
            if not isinstance(spec, tuple) or len(spec) != 2:
                raise MaterialError(f"piezo region '{rname}': give (material, poling)")
            mat, pol = spec
            mat = get_piezo_material(mat) if not isinstance(mat, PiezoMaterial) else mat
            els = np.asarray(subs[rname])
            if np.any(self.elem_piezo[els] >= 0):
                raise MaterialError(f"piezo region '{rname}' overlaps another piezo region")
            self.elem_piezo[els] = i
            self.region_names.append(rname)
            self.materials.append(mat)
            self.polings.append(_poling_spec(rname, pol))
        self._check_elastic()
        # potential DOFs: nodes of piezoelectric elements
        basis = mech.basis
        pel = np.nonzero(self.elem_piezo >= 0)[0]
        self.phi_nodes = np.unique(basis.element_dofs[:, pel])
        self.n_phi = int(self.phi_nodes.size)
        self._node_to_phi = np.full(basis.N, -1, dtype=np.int64)
        self._node_to_phi[self.phi_nodes] = np.arange(self.n_phi)
        # electrodes
        if electrodes is None:
            electrodes = sorted(b for b in bnd if b.startswith("electrode"))
        self.electrodes: list[str] = list(electrodes)
        if not self.electrodes:
            raise GeometryError("piezo model has no electrodes (no boundary named electrode*)")
        nodes = {}
        for name in self.electrodes:
            if name not in bnd:
                raise GeometryError(f"unknown electrode '{name}' (surfaces: "
                                    f"{', '.join(b for b in bnd if b.startswith('electrode')) or 'none'})")
            nn = np.unique(basis.get_dofs(facets=bnd[name]).all())
            loc = self._node_to_phi[nn]
            if np.any(loc < 0):
                raise MaterialError(f"electrode '{name}' lies on a material without piezoelectric constants "
                                    f"({np.count_nonzero(loc < 0)} of its nodes are on no piezoelectric region)")
            nodes[name] = loc
        count = np.zeros(self.n_phi, dtype=np.int64)
        for loc in nodes.values():
            count[loc] += 1
        self.electrode_nodes: dict[str, np.ndarray] = {}  # every node of the electrode
        for name, loc in nodes.items():
            own = loc[count[loc] == 1]
            if own.size < 0.5 * loc.size:
                others = [o for o, l2 in nodes.items() if o != name and np.intersect1d(l2, loc).size > 0.25 * loc.size]
                raise GeometryError(f"electrode '{name}' overlaps {', '.join(others) or 'other electrodes'}: "
                                    f"a layout needs disjoint electrodes")
            self.electrode_nodes[name] = loc
        # incidence with shares: a node on k electrodes (their common edge) takes the mean of their
        # potentials, so W[node, e] = 1/k  (phi_node = sum_e W[node, e] phi_e)
        r = np.concatenate([nodes[n] for n in self.electrodes])
        c = np.concatenate([np.full(nodes[n].size, i) for i, n in enumerate(self.electrodes)])
        self._W = sp.csr_matrix((1.0 / count[r], (r, c)), shape=(self.n_phi, len(self.electrodes)))
        self._on_electrode = count > 0
        if reference is not None and reference not in self.electrode_nodes:
            raise GeometryError(f"reference electrode '{reference}' is not in the layout ({', '.join(self.electrodes)})")
        self.reference = reference
        self.tip = mech.tip if tip is None else tip
        self.fixed_dofs = np.asarray(fixed_dofs, dtype=np.int64)
        self._blocks = None
        self._mechsys = None
        self.timings: dict[str, float] = {}

    # ---- checks and blocks -------------------------------------------------------------------
    def _check_elastic(self) -> None:
        """The mechanical model's tensor in each piezo region equals the material's rotated c^E."""
        mech = self.mech
        mesh = self.mesh
        xc = mesh.p[:, mesh.t].mean(axis=1)  # (3, nel) centroids
        for i, name in enumerate(self.region_names):
            els = np.nonzero(self.elem_piezo == i)[0]
            if els.size > 64:
                els = els[np.linspace(0, els.size - 1, 64).astype(int)]
            x = xc[:, els][:, :, None]  # (3, m, 1)
            Cm = el.stiffness_field(mech.elem_region, mech.materials, mech.orientations, x, elements=els)
            Rq = _eval_rotation(self.polings[i], x)
            Cp = rotate_voigt(self.materials[i].cE, Rq)
            err = np.abs(Cm - Cp).max() / np.abs(Cp).max()
            if err > 1e-6:
                mnames = sorted({mech.materials[j].name for j in np.unique(mech.elem_region[els])})
                raise MaterialError(
                    f"region '{name}': the elastic tensor of '{', '.join(mnames)}' is not the c^E of piezo material "
                    f"'{self.materials[i].name}' with this poling (relative difference {err:.2g}); use the same "
                    f"material in the mechanical model")

    def blocks(self) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(K_uphi restricted to the phi nodes (3N x n_phi), K_phiphi (n_phi x n_phi))."""
        if self._blocks is None:
            t0 = time.perf_counter()
            Kup, Kpp = assemble_piezo_blocks(self.mesh, self.elem_piezo, self.materials, self.polings)
            Kup = Kup[:, self.phi_nodes].tocsr()
            Kpp = Kpp[self.phi_nodes][:, self.phi_nodes].tocsr()
            self._blocks = (Kup, Kpp)
            self.timings["assemble_piezo_s"] = time.perf_counter() - t0
        return self._blocks

    def mechanical_system(self):
        """(K, M, free, n_extra): the mechanical stiffness and mass on the unknowns ``free``
        (indices into the full u vector) followed by ``n_extra`` lumped-tip DOFs."""
        if self._mechsys is None:
            mech = self.mech
            t0 = time.perf_counter()
            if getattr(mech, "lumped_tip", None) is not None and hasattr(mech, "augmented"):
                Ka, Ma, free, _ = mech.augmented()
                n_extra = Ka.shape[0] - free.size
            else:
                K, M = mech.assemble()
                free = mech.free_dofs
                Ka, Ma = K[free][:, free].tocsr(), M[free][:, free].tocsr()
                n_extra = 0
            if self.fixed_dofs.size:
                keep_u = ~np.isin(free, self.fixed_dofs)
                keep = np.concatenate([keep_u, np.ones(n_extra, dtype=bool)])
                idx = np.nonzero(keep)[0]
                Ka, Ma, free = Ka[idx][:, idx].tocsr(), Ma[idx][:, idx].tocsr(), free[keep_u]
            self._mechsys = (Ka, Ma, free, int(n_extra))
            self.timings["assemble_mech_s"] = time.perf_counter() - t0
        return self._mechsys

    # ---- electrical configuration ---------------------------------------------------------------
    def _states(self, states: Mapping[str, State] | None, others: State) -> dict[str, State]:
        states = dict(states or {})
        for name in states:
            if name not in self.electrode_nodes:
                raise GeometryError(f"unknown electrode '{name}' (electrodes: {', '.join(self.electrodes)})")
        out: dict[str, State] = {}
        for name in self.electrodes:
            s = states.get(name, others)
            if isinstance(s, str):
                key = s.strip().lower()
                if key in ("ground", "gnd", "short"):
                    s = 0.0
                elif key in ("float", "open", "floating"):
                    s = "float"
                else:
                    raise ParameterError(f"electrode '{name}': state must be a voltage, 'ground' or 'float', got {s!r}")
            else:
                s = float(s)
                if not np.isfinite(s):
                    raise ParameterError(f"electrode '{name}': voltage must be finite, got {s}")
            out[name] = s
        return out

    def _operators(self, states: dict[str, State]):
        """(T, P, driven names, floating names): ``phi = T phi_r + P V_driven``.

        Free nodes (on no electrode) are unknowns of their own; an electrode node takes the
        potential of its electrode, and a node on the common edge of k electrodes the mean of
        their k potentials (a vanishing inter-electrode gap: linear in the voltages, symmetric,
        no gap between electrodes at the same potential).  Floating electrodes add one unknown
        each (the last columns of T)."""
        names = list(self.electrodes)
        driven = [n for n in names if states[n] != "float"]
        floating = [n for n in names if states[n] == "float"]
        n = self.n_phi
        free = np.nonzero(~self._on_electrode)[0]
        Tfree = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(n, free.size))
        W = self._W.tocsc()
        Tfl = W[:, [names.index(e) for e in floating]] if floating else sp.csr_matrix((n, 0))
        T = sp.hstack([Tfree, Tfl], format="csr")
        P = W[:, [names.index(e) for e in driven]].tocsr() if driven else sp.csr_matrix((n, 0))
        if T.shape[1] and not driven:
            raise ParameterError("at least one electrode must be driven or grounded (the potential needs a reference)")
        return T, P, driven, floating

    # ---- linear algebra -----------------------------------------------------------------------
    def _coupled(self, T: sp.csr_matrix, sigma: float = 0.0):
        """Scaled coupled matrix A(sigma) on (u_free+extra, phi_r / alpha) and the pieces."""
        K, M, free, n_extra = self.mechanical_system()
        Kup, Kpp = self.blocks()
        Kur = Kup[free] @ T  # rows: free u DOFs
        if n_extra:
            Kur = sp.vstack([Kur, sp.csr_matrix((n_extra, T.shape[1]))]).tocsr()
        Krr = (T.T @ Kpp @ T).tocsr()
        alpha = float(np.sqrt(np.mean(np.abs(K.diagonal())) / max(np.mean(np.abs(Krr.diagonal())), 1e-300)))
        Kuu = K if sigma == 0.0 else (K - sigma * M).tocsr()
        A = sp.bmat([[Kuu, alpha * Kur], [alpha * Kur.T, -(alpha**2) * Krr]], format="csr")
        return A, Kuu, Kur, Krr, alpha

    @staticmethod
    def _refined_solver(A: sp.csr_matrix, fac, tol: float = 1e-8, max_refine: int = 5):
        """Solve with residual check and iterative refinement (pivot perturbation of the
        indefinite factorisation can leave a residual above round-off).  Several right-hand
        sides are solved column by column (the factorisation's multi-RHS path expects
        column-major storage)."""
        def solve1(b: np.ndarray) -> np.ndarray:
            x = fac.solve(b)
            nb = np.linalg.norm(b) + 1e-300
            for _ in range(max_refine):
                r = b - A @ x
                if np.linalg.norm(r) <= tol * nb:
                    return x
                x = x + fac.solve(r)
            rel = float(np.linalg.norm(b - A @ x) / nb)
            if rel > 1e-6:
                raise SolverError(f"coupled solve did not converge (relative residual {rel:.2g})")
            return x

        def solve(b: np.ndarray) -> np.ndarray:
            b = np.asarray(b, dtype=float)
            if b.ndim == 1:
                return solve1(b)
            return np.column_stack([solve1(np.ascontiguousarray(b[:, j])) for j in range(b.shape[1])])
        return solve

    def _schur_solver(self, Kuu: sp.csr_matrix, Kur: sp.csr_matrix, Krr: sp.csr_matrix, tol: float = 1e-8):
        """``S^-1 b`` for ``S = Kuu + Kur Krr^-1 Kur^T`` by PCG with the factorised Kuu."""
        fu = factorize(Kuu, spd=True)
        fr = _columnwise(factorize(Krr, spd=True))
        n = Kuu.shape[0]
        S = spla.LinearOperator((n, n), matvec=lambda x: Kuu @ x + Kur @ fr.solve(Kur.T @ x), dtype=float)
        Pinv = spla.LinearOperator((n, n), matvec=fu.solve, dtype=float)
        iters = []

        def solve_u(b: np.ndarray) -> np.ndarray:
            b = np.asarray(b, dtype=float)
            cols = b.reshape(n, -1)
            out = np.empty_like(cols)
            for j in range(cols.shape[1]):
                it = [0]

                def cb(_x):
                    it[0] += 1
                x, info = spla.cg(S, cols[:, j], M=Pinv, rtol=tol, atol=0.0, maxiter=500, callback=cb)
                if info != 0:
                    raise SolverError(f"Schur-complement CG did not converge (info {info})")
                iters.append(it[0])
                out[:, j] = x
            return out.reshape(b.shape)

        def release():
            fu.release()
            fr.release()

        return solve_u, fr, release, iters

    # ---- static -----------------------------------------------------------------------------
    def static(self, voltages: Mapping[str, State] | None = None, forces: Mapping[Any, Sequence[float]] | None = None,
               others: State = "ground", solver: str = "indefinite") -> PiezoStatic:
        """Static solution for electrode ``voltages`` ({electrode: volts | 'ground' | 'float'};
        the other electrodes of the layout take ``others``) and mechanical ``forces``
        ({attachment: (Fx, Fy, Fz)} [N], as :meth:`ElasticModel.static_displacement`)."""
        return self.static_many([voltages or {}], [forces or {}], others=others, solver=solver)[0]

    def static_many(self, voltages: Sequence[Mapping[str, State]], forces: Sequence[Mapping[Any, Sequence[float]]]
                    | None = None, others: State = "ground", solver: str = "indefinite") -> list[PiezoStatic]:
        """Several load cases with one factorisation.  Every case must drive (or float) the
        same electrodes; only the voltage values and the forces differ."""
        if solver not in SOLVERS:
            raise SolverError(f"unknown piezo solver '{solver}' (known: {', '.join(SOLVERS)})")
        cases = [self._states(v, others) for v in voltages]
        if not cases:
            return []
        forces = list(forces) if forces is not None else [{}] * len(cases)
        if len(forces) != len(cases):
            raise ParameterError("static_many: one force dict per voltage case")
        pattern = [s == "float" for s in cases[0].values()]
        for st in cases[1:]:
            if [s == "float" for s in st.values()] != pattern:
                raise ParameterError("static_many: all cases must float the same electrodes")
        st0 = cases[0]
        T, P, driven, floating = self._operators(st0)
        K, M, free, n_extra = self.mechanical_system()
        Kup, Kpp = self.blocks()
        t0 = time.perf_counter()
        nu = free.size + n_extra
        rhs_u, rhs_r, phiDs = [], [], []
        for st, fc in zip(cases, forces):
            V = np.array([st[n] for n in driven], dtype=float)
            f = np.zeros(self.mech.ndofs_total)
            for where, F in fc.items():
                f += np.asarray(self.mech.attachment(where).T @ np.asarray(F, dtype=float).reshape(3)).ravel()
            phiD = P @ V
            rhs_u.append(np.concatenate([f[free] - Kup[free] @ phiD, np.zeros(n_extra)]))
            rhs_r.append(T.T @ (Kpp @ phiD))
            phiDs.append(phiD)
        A, Kuu, Kur, Krr, alpha = self._coupled(T)
        t1 = time.perf_counter()
        sols = []
        extra_t: dict[str, float] = {}
        if solver == "indefinite":
            fac = factorize(A, spd=False)
            try:
                solve = self._refined_solver(A, fac)
                for fu, gr in zip(rhs_u, rhs_r):
                    x = solve(np.concatenate([fu, alpha * gr]))
                    sols.append((x[:nu], alpha * x[nu:]))
            finally:
                fac.release()
            backend = fac.backend
        else:
            solve_u, fr, release, iters = self._schur_solver(Kuu, Kur, Krr)
            try:
                for fu, gr in zip(rhs_u, rhs_r):
                    # phi_r = Krr^-1 (Kur^T u - gr);  S u = fu + Kur Krr^-1 gr
                    uu = solve_u(fu + Kur @ fr.solve(gr))
                    sols.append((uu, fr.solve(Kur.T @ uu - gr)))
            finally:
                release()
            backend = f"schur-pcg({iters[0] if iters else 0} it)"
            extra_t = {"cg_iterations": float(sum(iters))}
        t2 = time.perf_counter()
        out = []
        for st, phiD, (uu, phir) in zip(cases, phiDs, sols):
            u = np.zeros(self.mech.ndofs_total)
            u[free] = uu[: free.size]
            phi = T @ phir + phiD
            if not (np.all(np.isfinite(u)) and np.all(np.isfinite(phi))):
                raise SolverError("coupled static solve produced non-finite values")
            q = Kpp @ phi - Kup.T @ u  # nodal charge; a shared node's charge is split like its potential
            Q = self._W.T @ q
            charges = {n: float(Q[i]) for i, n in enumerate(self.electrodes)}
            pots = {}
            for i, n in enumerate(self.electrodes):
                pots[n] = float(st[n]) if st[n] != "float" else float(phir[T.shape[1] - len(floating) +
                                                                         floating.index(n)])
            for n in floating:
                charges[n] = 0.0
            timings = dict(self.timings)
            timings.update(setup_s=t1 - t0, solve_s=t2 - t1, n_cases=float(len(cases)), **extra_t)
            out.append(PiezoStatic(u, uu[free.size:], phi, self.phi_nodes, pots, charges, int(nu + phir.size),
                                   backend, timings, self))
        return out

    # ---- actuation loads ---------------------------------------------------------------------
    def actuation_loads(self, driven: Sequence[str], others: State = "ground") -> tuple[np.ndarray, np.ndarray]:
        """Equivalent mechanical load per volt of each electrode in ``driven`` (the others of the
        layout at ``others``), on the mechanical unknowns (free u DOFs + lumped-tip DOFs):
        ``F[:, j] = -K_uphi P e_j + K_ur K_rr^-1 T^T K_phiphi P e_j`` [N/V], such that the
        static displacement is ``K_eff^-1 F V`` with the condensed (short-circuit for the
        driven electrodes) stiffness ``K_eff``.  Returns (F (n_mech, n_driven), free)."""
        st = self._states({n: 0.0 for n in driven}, others)
        for n in driven:
            if n not in self.electrode_nodes:
                raise GeometryError(f"unknown electrode '{n}' (electrodes: {', '.join(self.electrodes)})")
        T, P, dnames, _ = self._operators(st)
        K, M, free, n_extra = self.mechanical_system()
        Kup, Kpp = self.blocks()
        idx = [dnames.index(n) for n in driven]
        PD = P[:, idx].toarray()
        Kur = Kup[free] @ T
        Krr = (T.T @ Kpp @ T).tocsr()
        fr = _columnwise(factorize(Krr, spd=True))
        try:
            F = -(Kup[free] @ PD) + Kur @ fr.solve(T.T @ (Kpp @ PD))
        finally:
            fr.release()
        F = np.vstack([F, np.zeros((n_extra, len(driven)))])
        return np.asarray(F), free

    # ---- modes ------------------------------------------------------------------------------
    def electrical_condition(self, electrodes: str | Mapping[str, str]) -> dict[str, State]:
        """'short': every electrode grounded; 'open': every electrode floating except the
        reference (grounded); or an explicit {electrode: 'ground'|'float'}."""
        if isinstance(electrodes, str):
            key = electrodes.strip().lower()
            if key == "short":
                return self._states({}, "ground")
            if key == "open":
                if self.reference is None:
                    raise ParameterError("open circuit needs a reference electrode (PiezoModel(reference=...))")
                return self._states({self.reference: "ground"}, "float")
            raise ParameterError(f"electrodes must be 'short' or 'open', got {electrodes!r}")
        return self._states(electrodes, "ground")

    def modes(self, n_modes: int = 6, electrodes: str | Mapping[str, str] = "short", sigma: float | None = None,
              solver: str = "indefinite") -> PiezoModes:
        """The lowest ``n_modes`` modes with the given electrical condition (see
        :meth:`electrical_condition`); voltages of driven electrodes are irrelevant (zero)."""
        if int(n_modes) != n_modes or n_modes < 1:
            raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
        if solver not in SOLVERS:
            raise SolverError(f"unknown piezo solver '{solver}' (known: {', '.join(SOLVERS)})")
        st = self.electrical_condition(electrodes)
        st = {k: (0.0 if v != "float" else "float") for k, v in st.items()}
        T, P, driven, floating = self._operators(st)
        K, M, free, n_extra = self.mechanical_system()
        n = K.shape[0]
        if n < 10 * n_modes:
            raise SolverError(f"mesh too coarse for {n_modes} modes: {n} free DOFs")
        if sigma is None:
            clamped = bool(self.mech.clamp) or self.fixed_dofs.size >= 6
            # a free body: shift below zero by ~1e-6 of the element-level eigenvalue scale (far below
            # the first elastic mode, far enough from the rigid modes for an accurate factorisation)
            sigma = 0.0 if clamped else -1e-6 * float(np.mean(np.abs(K.diagonal())) / np.mean(np.abs(M.diagonal())))
        t0 = time.perf_counter()
        A, Kuu, Kur, Krr, alpha = self._coupled(T, sigma)
        nr = Krr.shape[0]
        count = [0]
        if solver == "indefinite":
            fac = factorize(A, spd=False)
            solve_full = self._refined_solver(A, fac)
            release = fac.release
            backend = fac.backend

            def opinv(x):
                count[0] += 1
                return solve_full(np.concatenate([x, np.zeros(nr)]))[:n]
        else:
            solve_u, fr, release, iters = self._schur_solver(Kuu, Kur, Krr)
            backend = "schur-pcg"

            def opinv(x):
                count[0] += 1
                return solve_u(x)
        t1 = time.perf_counter()
        op = spla.LinearOperator((n, n), matvec=opinv, dtype=float)
        k_int = min(n - 2, n_modes + max(3, n_modes // 2))
        rng = np.random.default_rng(12345)
        try:
            w, Vv = spla.eigsh(M, k=k_int, M=M, sigma=sigma, OPinv=op, which="LM", v0=rng.standard_normal(n),
                               ncv=min(n - 1, max(2 * k_int + 1, 20)))
            order = np.argsort(np.abs(w - sigma))[:n_modes]  # the n nearest the shift ...
            order = order[np.argsort(w[order])]  # ... in ascending order
            w, Vv = w[order], Vv[:, order]
            # modal potentials: phi_r = Krr^-1 Kur^T u (Gauss law with zero charge on free nodes)
            if solver == "indefinite":
                y = solve_full(np.vstack([M @ Vv, np.zeros((nr, Vv.shape[1]))]))
                phir = alpha * y[n:] * (w - sigma)[None, :]
            else:
                phir = fr.solve(Kur.T @ Vv)
        except spla.ArpackNoConvergence as exc:
            raise SolverError(f"coupled eigen-solver did not converge ({len(exc.eigenvalues)} of {n_modes})") from None
        finally:
            release()
        t2 = time.perf_counter()
        if np.any(w < -1e-8 * np.max(np.abs(w))):
            raise SolverError(f"negative eigenvalue {w.min():.3g}: the coupled stiffness is not positive")
        w = np.maximum(w, 0.0)
        shapes = np.zeros((self.mech.ndofs_total, w.size))
        shapes[free] = Vv[: free.size]
        extra = Vv[free.size:].T
        phi = T @ phir
        weights = el.lumped_weights(self.mesh, self.mech.elem_density)
        fams, shares = classify_shapes(self.mech.basis.doflocs, weights,
                                       shapes.reshape(self.mech.n_nodes, 3, w.size), axis=self.mech.beam_axis)
        if n_extra:
            tipd = extra[:, :3]
        else:
            try:
                tipd = np.asarray(self.mech.attachment(self.tip) @ shapes).T
            except GeometryError:
                tipd = np.full((w.size, 3), np.nan)
        fl = {name: phir[T.shape[1] - len(floating) + j] for j, name in enumerate(floating)} if floating else {}
        # floating unknowns are the last columns of T
        timings = dict(self.timings)
        timings.update(factor_s=t1 - t0, eigen_s=t2 - t1, n_opinv=float(count[0]))
        cond = {k: ("float" if v == "float" else "ground") for k, v in st.items()}
        return PiezoModes(np.sqrt(w) / (2 * np.pi), shapes, extra, phi, fams, shares, tipd, cond, fl,
                          int(n + nr), backend, timings)

    def describe(self) -> dict[str, Any]:
        K, M, free, n_extra = self.mechanical_system()
        return {"piezo_regions": {n: {"material": m.name, "poling": "field" if callable(p) else
                                      np.asarray(p)[:, 2].round(12).tolist()}
                                  for n, m, p in zip(self.region_names, self.materials, self.polings)},
                "electrodes": self.electrodes, "reference": self.reference,
                "mechanical_dofs": int(K.shape[0]), "potential_nodes": self.n_phi}


__all__ = ["PiezoModel", "PiezoStatic", "PiezoModes", "assemble_piezo_blocks", "coupling_factors", "match_modes",
           "SOLVERS"]
