"""Compiled assembly of the elasticity and mass matrices for quadratic tetrahedra and hexahedra.

Element kinds (:data:`ELEMENTS`, chosen per mesh by :func:`element_kind`):

========== ============ ================================ ===== ======= ==========
key        mesh         scalar element (scikit-fem)      nodes K rule  VTK cell
========== ============ ================================ ===== ======= ==========
``tet-p2`` ``MeshTet``  ``ElementTetP2`` (Lagrange P2)    10    4 pts   tetra10
``hex-s2`` ``MeshHex``  ``ElementHexS2`` (serendipity)    20    3^3     hexahedron20
``hex-q2`` ``MeshHex``  ``ElementHex2`` (Lagrange Q2)     27    3^3     hexahedron27
========== ============ ================================ ===== ======= ==========

Quadrature: P2 gradients are linear on a straight tetrahedron, so the 4-point degree-2 rule
integrates ``eps : C : eps`` exactly (piecewise-constant C) and the 11-point degree-4 rule the
mass.  On a hexahedron with a trilinear map (exactly a parallelepiped for the box meshes of
``meshes/structured.py``) products of Q2 / serendipity functions and of their gradients are of
degree <= 4 per reference direction: the 3 x 3 x 3 Gauss rule (exact to degree 5) integrates
K and M exactly for an affine map ("full integration": no spurious zero-energy modes).

Algorithm (numba, ``cache=True``): the scalar node adjacency (block-CSR pattern, 3 x 3 blocks
in the interleaved numbering ``3 * node + component``) is built once per mesh and element
kind together with the position of every element block in it; the element kernels compute
``K_e = sum_q w_q G_q^T C_q G_q`` block by block (``G`` the 6 x 3 strain operator of one scalar
function, only its non-zeros touched) and add each 3 x 3 block in place, so there is no COO
triplet list and no sort.  The geometry map is generic (the mesh's own P1 / trilinear vertex
functions), so curved-sided hexahedra (the tube's sectors) are integrated with their true
Jacobian at every point.  The stiffness C enters per element (one 6 x 6) or per quadrature
point (an orientation field ``R(x)``); per-point fields are processed in element chunks so
the memory stays bounded.

The scikit-fem ``BilinearForm`` path of :mod:`probedyn.fem.elasticity` is the readable
reference; the two agree to round-off (tests/test_fem_assembly.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
from numba import njit
from skfem import ElementHex2, ElementHexS2, ElementTetP2, MeshHex, MeshHex2, MeshTet
from skfem.quadrature import get_quadrature

from probedyn.core.errors import MaterialError
from probedyn.meshes._gmsh import element_volumes


@dataclass(frozen=True)
class ElementKind:
    """A quadratic solid element: its mesh type, scalar scikit-fem element and quadrature."""

    key: str
    mesh_type: type
    factory: Callable
    k_intorder: int
    m_intorder: int
    vtk: str
    title: str

    def element(self):
        return self.factory()

    @property
    def nodes(self) -> int:
        return int(self.factory().doflocs.shape[0])


ELEMENTS: dict[str, ElementKind] = {
    "tet-p2": ElementKind("tet-p2", MeshTet, ElementTetP2, 2, 4, "tetra10",
                          "P2 tetrahedra (ElementTetP2, 10 nodes, straight-sided)"),
    "hex-s2": ElementKind("hex-s2", MeshHex, ElementHexS2, 5, 5, "hexahedron20",
                          "serendipity hexahedra (ElementHexS2, 20 nodes)"),
    "hex-q2": ElementKind("hex-q2", MeshHex, ElementHex2, 5, 5, "hexahedron27",
                          "Lagrange Q2 hexahedra (ElementHex2, 27 nodes)"),
}

#: element kind used for a mesh type when none is named
DEFAULT_ELEMENT = {MeshTet: "tet-p2", MeshHex: "hex-s2", MeshHex2: "hex-s2"}


def element_kind(mesh, key: str | None = None) -> ElementKind:
    """The :class:`ElementKind` ``key`` (checked against the mesh type) or the mesh's default."""
    if key is None or key == "auto":
        for mt, k in DEFAULT_ELEMENT.items():
            if isinstance(mesh, mt):
                return ELEMENTS[k]
        raise MaterialError(f"no quadratic solid element for a {type(mesh).__name__}")
    if key not in ELEMENTS:
        raise MaterialError(f"unknown element '{key}' (known: {', '.join(ELEMENTS)})")
    kind = ELEMENTS[key]
    if not isinstance(mesh, kind.mesh_type):
        raise MaterialError(f"element '{key}' needs a {kind.mesh_type.__name__}, the mesh is a {type(mesh).__name__}")
    return kind


# ---------------------------------------------------------------------------------------
# sparsity pattern
# ---------------------------------------------------------------------------------------

@njit(cache=True)
def _pattern(ed, n):  # pragma: no cover - compiled
    """Node adjacency of ``ed`` (nel, nb) as CSR (indptr, indices sorted per row) and the
    position ``pos[e, a, b]`` of block (ed[e, a], ed[e, b]) in ``indices``."""
    nel, nb = ed.shape
    # node -> elements
    cnt = np.zeros(n + 1, np.int64)
    for e in range(nel):
        for a in range(nb):
            cnt[ed[e, a] + 1] += 1
    for i in range(n):
        cnt[i + 1] += cnt[i]
    n2e = np.empty(cnt[n], np.int64)
    fill = cnt[:n].copy()
    for e in range(nel):
        for a in range(nb):
            s = ed[e, a]
            n2e[fill[s]] = e
            fill[s] += 1
    # rows: unique neighbours, sorted
    mark = np.full(n, -1, np.int64)
    indptr = np.zeros(n + 1, np.int64)
    for s in range(n):
        c = 0
        for k in range(cnt[s], cnt[s + 1]):
            e = n2e[k]
            for b in range(nb):
                t = ed[e, b]
                if mark[t] != s:
                    mark[t] = s
                    c += 1
        indptr[s + 1] = indptr[s] + c
    indices = np.empty(indptr[n], np.int64)
    mark[:] = -1
    for s in range(n):
        p = indptr[s]
        for k in range(cnt[s], cnt[s + 1]):
            e = n2e[k]
            for b in range(nb):
                t = ed[e, b]
                if mark[t] != s:
                    mark[t] = s
                    indices[p] = t
                    p += 1
        indices[indptr[s]:indptr[s + 1]] = np.sort(indices[indptr[s]:indptr[s + 1]])
    pos = np.empty((nel, nb, nb), np.int64)
    for e in range(nel):
        for a in range(nb):
            s = ed[e, a]
            lo = indptr[s]
            hi = indptr[s + 1]
            for b in range(nb):
                t = ed[e, b]
                # binary search of t in indices[lo:hi]
                i0, i1 = lo, hi
                while i1 - i0 > 1:
                    mid = (i0 + i1) // 2
                    if indices[mid] <= t:
                        i0 = mid
                    else:
                        i1 = mid
                pos[e, a, b] = i0
    return indptr, indices, pos


@dataclass
class Pattern:
    """Block-CSR pattern of one mesh + element kind: ``indptr``, ``indices`` (scalar node
    adjacency), ``pos`` (nel, nb, nb) block positions, ``element_dofs`` (nel, nb), ``n`` nodes."""

    indptr: np.ndarray
    indices: np.ndarray
    pos: np.ndarray
    element_dofs: np.ndarray
    n: int

    @property
    def nnz_blocks(self) -> int:
        return int(self.indices.size)

    def scalar(self, data: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def vector(self, blocks: np.ndarray) -> sp.csr_matrix:
        """(3n, 3n) CSR from 3 x 3 blocks (nnz_blocks, 3, 3) in the interleaved numbering."""
        B = sp.bsr_matrix((blocks, self.indices, self.indptr), shape=(3 * self.n, 3 * self.n))
        return B.tocsr()

    def vector_from_scalar(self, data: np.ndarray) -> sp.csr_matrix:
        """``kron(S, I3)`` of the scalar matrix with values ``data`` (interleaved numbering)."""
        blocks = np.zeros((data.size, 3, 3))
        for c in range(3):
            blocks[:, c, c] = data
        return self.vector(blocks)


_PATTERNS: dict = {}


def pattern(mesh, kind: ElementKind, element_dofs: np.ndarray, n: int) -> Pattern:
    """The (cached per mesh object and element kind) :class:`Pattern`."""
    key = (id(mesh), kind.key)
    hit = _PATTERNS.get(key)
    if hit is not None and hit[0] is mesh:
        return hit[1]
    ed = np.ascontiguousarray(np.asarray(element_dofs).T, dtype=np.int64)
    indptr, indices, pos = _pattern(ed, int(n))
    pat = Pattern(indptr, indices, pos, ed, int(n))
    if len(_PATTERNS) > 8:
        _PATTERNS.clear()
    _PATTERNS[key] = (mesh, pat)
    return pat


# ---------------------------------------------------------------------------------------
# element kernels
# ---------------------------------------------------------------------------------------

@njit(cache=True)
def _jacobian(X, dNg, q, J):  # pragma: no cover - compiled
    """J[i, j] = dx_i / dxi_j at quadrature point q; returns det and fills J with J^-1."""
    for i in range(3):
        for j in range(3):
            s = 0.0
            for v in range(X.shape[0]):
                s += X[v, i] * dNg[v, j, q]
            J[i, j] = s
    a, b, c = J[0, 0], J[0, 1], J[0, 2]
    d, e, f = J[1, 0], J[1, 1], J[1, 2]
    g, h, k = J[2, 0], J[2, 1], J[2, 2]
    A = e * k - f * h
    B = -(d * k - f * g)
    C = d * h - e * g
    det = a * A + b * B + c * C
    inv = 1.0 / det
    J[0, 0] = A * inv
    J[0, 1] = -(b * k - c * h) * inv
    J[0, 2] = (b * f - c * e) * inv
    J[1, 0] = B * inv
    J[1, 1] = (a * k - c * g) * inv
    J[1, 2] = -(a * f - c * d) * inv
    J[2, 0] = C * inv
    J[2, 1] = -(a * h - b * g) * inv
    J[2, 2] = (a * e - b * d) * inv
    return det


@njit(cache=True)
def _stiffness_kernel(Xe, dNg, dN, W, C, pos, out):  # pragma: no cover - compiled
    """Add the element stiffness blocks of elements Xe (ne, nvg, 3) into ``out`` (nnzb, 3, 3).

    ``dNg`` (nvg, 3, nq) reference gradients of the geometry functions, ``dN`` (nb, 3, nq) of
    the scalar element; ``C`` (ne, nqc, 6, 6), nqc = 1 (per element) or nq; ``pos`` (ne, nb, nb).
    Voigt order [11, 22, 33, 23, 13, 12]: the strain of u = phi_a e_c is
    G_a[:, c] with G_a = [[gx,0,0],[0,gy,0],[0,0,gz],[0,gz,gy],[gz,0,gx],[gy,gx,0]].
    """
    ne = Xe.shape[0]
    nb = dN.shape[0]
    nq = W.shape[0]
    nqc = C.shape[1]
    J = np.empty((3, 3))
    g = np.empty((nb, 3))
    D = np.empty((nb, 6, 3))  # C G_b
    Ke = np.empty((nb, nb, 3, 3))
    for e in range(ne):
        Ke[:] = 0.0
        for q in range(nq):
            det = _jacobian(Xe[e], dNg, q, J)
            w = W[q] * abs(det)
            for a in range(nb):
                for i in range(3):
                    s = 0.0
                    for j in range(3):
                        s += dN[a, j, q] * J[j, i]
                    g[a, i] = s
            qc = q if nqc > 1 else 0
            Cq = C[e, qc]
            for b in range(nb):
                gx, gy, gz = g[b, 0], g[b, 1], g[b, 2]
                for I in range(6):
                    D[b, I, 0] = w * (Cq[I, 0] * gx + Cq[I, 4] * gz + Cq[I, 5] * gy)
                    D[b, I, 1] = w * (Cq[I, 1] * gy + Cq[I, 3] * gz + Cq[I, 5] * gx)
                    D[b, I, 2] = w * (Cq[I, 2] * gz + Cq[I, 3] * gy + Cq[I, 4] * gx)
            for a in range(nb):
                gx, gy, gz = g[a, 0], g[a, 1], g[a, 2]
                for b in range(a, nb):
                    for k in range(3):
                        Ke[a, b, 0, k] += gx * D[b, 0, k] + gz * D[b, 4, k] + gy * D[b, 5, k]
                        Ke[a, b, 1, k] += gy * D[b, 1, k] + gz * D[b, 3, k] + gx * D[b, 5, k]
                        Ke[a, b, 2, k] += gz * D[b, 2, k] + gy * D[b, 3, k] + gx * D[b, 4, k]
        for a in range(nb):
            for b in range(a, nb):
                p = pos[e, a, b]
                for i in range(3):
                    for k in range(3):
                        out[p, i, k] += Ke[a, b, i, k]
                if b != a:
                    p = pos[e, b, a]
                    for i in range(3):
                        for k in range(3):
                            out[p, i, k] += Ke[a, b, k, i]


@njit(cache=True)
def _mass_kernel(Xe, dNg, N, W, rho, pos, out):  # pragma: no cover - compiled
    """Add the scalar element masses ``int rho N_a N_b`` into ``out`` (nnzb,)."""
    ne = Xe.shape[0]
    nb = N.shape[0]
    nq = W.shape[0]
    J = np.empty((3, 3))
    Me = np.empty((nb, nb))
    for e in range(ne):
        Me[:] = 0.0
        for q in range(nq):
            det = _jacobian(Xe[e], dNg, q, J)
            w = W[q] * abs(det) * rho[e]
            for a in range(nb):
                wa = w * N[a, q]
                for b in range(a, nb):
                    Me[a, b] += wa * N[b, q]
        for a in range(nb):
            for b in range(a, nb):
                out[pos[e, a, b]] += Me[a, b]
                if b != a:
                    out[pos[e, b, a]] += Me[a, b]


# ---------------------------------------------------------------------------------------
# drivers
# ---------------------------------------------------------------------------------------

def _reference(kind: ElementKind, mesh, intorder: int):
    elem = kind.element()
    X, W = get_quadrature(elem.refdom, intorder)
    nb = elem.doflocs.shape[0]
    N = np.stack([elem.lbasis(X, i)[0] for i in range(nb)])  # (nb, nq)
    dN = np.stack([elem.lbasis(X, i)[1] for i in range(nb)])  # (nb, 3, nq)
    gel = mesh.elem()  # the geometry's element: P1 tet, trilinear hex or (curved) Q2 hex
    nvg = gel.doflocs.shape[0]
    dNg = np.stack([gel.lbasis(X, i)[1] for i in range(nvg)])  # (nvg, 3, nq)
    return X, np.ascontiguousarray(W), np.ascontiguousarray(N), np.ascontiguousarray(dN), np.ascontiguousarray(dNg)


def _vertex_coords(mesh, sel=None) -> np.ndarray:
    """Geometry node coordinates (ne, nvg, 3): the vertices, or all 27 nodes of a MeshHex2."""
    if mesh.elem().doflocs.shape[0] > mesh.t.shape[0]:
        t, x = mesh.dofs.element_dofs, mesh.doflocs
    else:
        t, x = mesh.t, mesh.p
    t = t if sel is None else t[:, sel]
    return np.ascontiguousarray(np.transpose(x[:, t], (2, 1, 0)))  # (ne, nvg, 3)


def quadrature_points(mesh, X: np.ndarray, sel: np.ndarray) -> np.ndarray:
    """Physical coordinates (3, ne, nq) of reference points X of elements ``sel``."""
    return np.asarray(mesh._mapping().F(X, tind=sel))


def stiffness(mesh, kind: ElementKind, pat: Pattern, C_of: Callable, chunk: int = 4096) -> sp.csr_matrix:
    """Global stiffness (3N x 3N). ``C_of(sel, x_qp)`` returns (ne, nqc, 6, 6) for elements
    ``sel`` with quadrature points ``x_qp`` (3, ne, nq) (evaluated lazily: None when the
    stiffness does not depend on the point)."""
    X, W, _, dN, dNg = _reference(kind, mesh, kind.k_intorder)
    out = np.zeros((pat.nnz_blocks, 3, 3))
    nel = mesh.t.shape[1]
    for a in range(0, nel, chunk):
        sel = np.arange(a, min(a + chunk, nel))
        C = np.ascontiguousarray(C_of(sel, lambda: quadrature_points(mesh, X, sel)), dtype=float)
        _stiffness_kernel(_vertex_coords(mesh, sel), dNg, dN, W, C, pat.pos[sel], out)
    return pat.vector(out)


def scalar_mass(mesh, kind: ElementKind, pat: Pattern, density: np.ndarray) -> sp.csr_matrix:
    """Scalar mass ``int rho N_a N_b`` (N x N) with a per-element density."""
    X, W, N, _, dNg = _reference(kind, mesh, kind.m_intorder)
    out = np.zeros(pat.nnz_blocks)
    _mass_kernel(_vertex_coords(mesh), dNg, N, W, np.ascontiguousarray(density, dtype=float), pat.pos, out)
    return pat.scalar(out)


__all__ = ["ELEMENTS", "ElementKind", "element_kind", "Pattern", "pattern", "stiffness", "scalar_mass",
           "element_volumes", "quadrature_points"]
