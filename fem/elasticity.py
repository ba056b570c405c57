"""3D anisotropic linear elasticity with quadratic tetrahedra: forms and fast assembly.

Formulation (small strains, no body load): find u in V (P2 vector fields vanishing on the
clamped boundary) such that for all v in V

    a(u, v) = int_Omega eps(v) : C(x) : eps(u) dx,        m(u, v) = int_Omega rho(x) u . v dx,

with ``eps`` in Voigt form ``[e11, e22, e33, 2e23, 2e13, 2e12]`` and ``C(x)`` the material's
6x6 stiffness rotated into global axes at every quadrature point
(``C_glob = Q(R(x)) C_loc Q(R(x))^T``, :func:`probedyn.fem.materials.rotate_voigt`).

Discretisation: Lagrange P2 on straight 4-node tets (scikit-fem ``ElementTetP2``). The vector
DOF numbering is **interleaved**: global DOF ``3*s + c`` is component ``c`` (0=x, 1=y, 2=z)
of scalar P2 node ``s`` of the scalar basis (``basis.doflocs[:, s]`` is its position), so
``M = kron(M_scalar, I3)`` for a per-element density.

Quadrature: gradients of P2 functions are linear, so ``eps : C : eps`` is quadratic for a
piecewise-constant C and the 4-point degree-2 rule integrates it exactly; the mass needs
degree 4.  A spatially varying orientation is sampled at the same points.

Two assembly paths are provided and tested against each other:

* :func:`aniso_elasticity` / :func:`mass_form`: scikit-fem ``BilinearForm``s (reference,
  readable, slow for large meshes because scikit-fem evaluates the form for each of the
  30 x 30 local basis pairs);
* :func:`assemble_stiffness` / :func:`assemble_mass`: element matrices by batched matrix
  products ``K_e = sum_q w_q B_q^T C_q B_q`` over element chunks and one COO -> CSR
  conversion (the path the model uses; see benchmarks/modal.py for timings).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementVector, FacetBasis, LinearForm, MeshHex2

from probedyn.core.errors import GeometryError, MaterialError
from probedyn.fem import assembly as asm
from probedyn.fem.assembly import element_kind
from probedyn.fem.materials import rotate_voigt
from probedyn.meshes.entities import ensure_entities

STIFFNESS_INTORDER = 2
MASS_INTORDER = 4


# ---------------------------------------------------------------------------------------
# scikit-fem forms (reference implementation)
# ---------------------------------------------------------------------------------------

def _voigt_strain(grad):
    """Voigt engineering strain from a displacement gradient field ``grad[i][j] = du_i/dx_j``."""
    return [
        grad[0][0], grad[1][1], grad[2][2],
        grad[1][2] + grad[2][1], grad[0][2] + grad[2][0], grad[0][1] + grad[1][0],
    ]


def _make_forms():
    @BilinearForm
    def aniso_elasticity(u, v, w):
        """eps(v) : C : eps(u) with ``w.C`` of shape (6, 6, nel, nq) (global axes)."""
        eu, ev = _voigt_strain(u.grad), _voigt_strain(v.grad)
        out = 0.0
        for I in range(6):
            s = 0.0
            for J in range(6):
                s = s + w.C[I, J] * eu[J]
            out = out + ev[I] * s
        return out

    @BilinearForm
    def mass_form(u, v, w):
        """rho u . v with ``w.rho`` of shape (nel, nq)."""
        return w.rho * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])

    return aniso_elasticity, mass_form


aniso_elasticity, mass_form = _make_forms()


# ---------------------------------------------------------------------------------------
# material fields
# ---------------------------------------------------------------------------------------

def element_regions(mesh, regions: Sequence[str]) -> np.ndarray:
    """Index into ``regions`` for every element; '*' means "all elements not yet assigned".

    Raises :class:`MaterialError` for an unknown region name or elements without material.
    """
    nel = mesh.t.shape[1]
    reg = np.full(nel, -1, dtype=np.int64)
    subs = mesh.subdomains or {}
    for i, name in enumerate(regions):
        if name == "*":
            continue
        if name not in subs:
            raise MaterialError(f"region '{name}' is not a mesh subdomain (known: {', '.join(subs) or 'none'})")
        reg[subs[name]] = i
    if "*" in regions:
        reg[reg < 0] = list(regions).index("*")
    if np.any(reg < 0):
        missing = [n for n in subs if np.any(reg[subs[n]] < 0)]
        raise MaterialError(
            f"{np.count_nonzero(reg < 0)} elements have no material (regions without material: "
            f"{', '.join(missing) or 'elements outside all subdomains'})"
        )
    return reg



def strain_operator(g: np.ndarray) -> np.ndarray:
    """Voigt strain-displacement operator ``B`` (..., 6, 3 n) from physical shape-function gradients
    ``g`` (..., n, 3): strains (xx, yy, zz, yz, xz, xy) with engineering shears, element DOFs
    ordered (node, component)."""
    n = g.shape[-2]
    B = np.zeros(g.shape[:-2] + (6, 3 * n))
    gx, gy, gz = g[..., 0], g[..., 1], g[..., 2]
    B[..., 0, 0::3] = gx
    B[..., 1, 1::3] = gy
    B[..., 2, 2::3] = gz
    B[..., 3, 1::3] = gz
    B[..., 3, 2::3] = gy
    B[..., 4, 0::3] = gz
    B[..., 4, 2::3] = gx
    B[..., 5, 0::3] = gy
    B[..., 5, 1::3] = gx
    return B

def stiffness_field(
    elem_region: np.ndarray,
    materials: Sequence,
    orientations: Sequence,
    x_qp: np.ndarray,
    elements: np.ndarray | None = None,
) -> np.ndarray:
    """Global-axes stiffness at quadrature points, shape (nel, nq, 6, 6).

    ``x_qp``: quadrature point coordinates (3, nel, nq) of the chosen ``elements``;
    ``orientations[i]``: None, a 3x3 rotation or a callable ``R(x) -> (..., 3, 3)``.
    """
    reg = elem_region if elements is None else elem_region[elements]
    nel, nq = x_qp.shape[1], x_qp.shape[2]
    C = np.empty((nel, nq, 6, 6))
    for i, (mat, R) in enumerate(zip(materials, orientations)):
        sel = np.nonzero(reg == i)[0]
        if sel.size == 0:
            continue
        if R is None:
            C[sel] = mat.C
        elif callable(R):
            Rq = np.asarray(R(x_qp[:, sel, :]), dtype=float)
            if Rq.shape != (sel.size, nq, 3, 3):
                raise MaterialError(f"orientation callable returned shape {Rq.shape}, expected {(sel.size, nq, 3, 3)}")
            C[sel] = rotate_voigt(mat.C, Rq)
        else:
            C[sel] = rotate_voigt(mat.C, _check_rotation(np.asarray(R, dtype=float)))
    return C


def _check_rotation(R: np.ndarray) -> np.ndarray:
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise MaterialError("orientation must be a proper rotation matrix (R R^T = I, det R = +1)")
    return R


# ---------------------------------------------------------------------------------------
# fast assembly (compiled kernels of probedyn.fem.assembly)
# ---------------------------------------------------------------------------------------

def scalar_basis(mesh, intorder: int, element: str | None = None):
    """Scalar quadratic basis on ``mesh`` (its DOF numbering defines the vector numbering);
    ``element``: a key of :data:`probedyn.fem.assembly.ELEMENTS` (None: the mesh's default)."""
    ensure_entities(mesh)  # facets and edges by int64 keys: the same arrays as scikit-fem's, ~6x faster
    return Basis(mesh, element_kind(mesh, element).element(), intorder=intorder)


def pattern_of(mesh, element, basis):
    """(element kind, cached block-CSR :class:`~probedyn.fem.assembly.Pattern`) of a mesh."""
    kind = element_kind(mesh, element)
    if basis is None:
        basis = scalar_basis(mesh, 1, kind.key)
    return kind, asm.pattern(mesh, kind, basis.element_dofs, basis.N)


def assemble_stiffness(
    mesh,
    elem_region: np.ndarray,
    materials: Sequence,
    orientations: Sequence,
    chunk: int = 4096,
    element: str | None = None,
    basis=None,
) -> sp.csr_matrix:
    """Global stiffness (3N x 3N, interleaved DOFs) by the compiled element kernels of
    :mod:`probedyn.fem.assembly` (``K_e = sum_q w_q G_q^T C_q G_q`` added block by block into
    a precomputed block-CSR pattern).  ``C`` is evaluated per element, or per quadrature point
    in chunks where a region has an orientation field ``R(x)``."""
    kind, pat = pattern_of(mesh, element, basis)
    varying = np.array([callable(R) for R in orientations], dtype=bool)
    per_elem = np.empty((len(materials), 6, 6))
    for i, (mat, R) in enumerate(zip(materials, orientations)):
        if R is None:
            per_elem[i] = mat.C
        elif not callable(R):
            per_elem[i] = rotate_voigt(mat.C, _check_rotation(np.asarray(R, dtype=float)))

    def C_of(sel, x_of):
        reg = elem_region[sel]
        if varying[reg].any():
            return stiffness_field(elem_region, materials, orientations, x_of(), elements=sel)
        return per_elem[reg][:, None]

    return asm.stiffness(mesh, kind, pat, C_of, chunk=chunk)


def assemble_scalar_mass(mesh, elem_density: np.ndarray, element: str | None = None, basis=None) -> sp.csr_matrix:
    """Scalar mass ``int rho N_a N_b`` (N x N) with a per-element density."""
    kind, pat = pattern_of(mesh, element, basis)
    return asm.scalar_mass(mesh, kind, pat, elem_density)


def assemble_mass(mesh, elem_density: np.ndarray, element: str | None = None, basis=None) -> sp.csr_matrix:
    """Vector mass ``kron(M_scalar, I3)`` in the interleaved numbering."""
    kind, pat = pattern_of(mesh, element, basis)
    return pat.vector_from_scalar(asm.scalar_mass(mesh, kind, pat, elem_density).data)


def assemble_stiffness_skfem(mesh, elem_region, materials, orientations, element: str | None = None) -> sp.csr_matrix:
    """Reference assembly with scikit-fem's :data:`aniso_elasticity` form, permuted to the
    interleaved numbering (for tests; slow)."""
    kind = element_kind(mesh, element)
    vb = Basis(mesh, ElementVector(kind.element()), intorder=kind.k_intorder)
    x_qp = np.asarray(vb.global_coordinates())
    C = stiffness_field(elem_region, materials, orientations, x_qp)
    K = aniso_elasticity.assemble(vb, C=np.moveaxis(C, (2, 3), (0, 1)))
    perm = vector_dof_permutation(mesh, vb, kind.key)
    return K[perm][:, perm].tocsr()


def assemble_mass_skfem(mesh, elem_density, element: str | None = None) -> sp.csr_matrix:
    """Reference vector mass with scikit-fem's :data:`mass_form` (interleaved numbering)."""
    kind = element_kind(mesh, element)
    vb = Basis(mesh, ElementVector(kind.element()), intorder=kind.m_intorder)
    rho = np.repeat(np.asarray(elem_density, dtype=float)[:, None], vb.X.shape[1], axis=1)
    M = mass_form.assemble(vb, rho=rho)
    perm = vector_dof_permutation(mesh, vb, kind.key)
    return M[perm][:, perm].tocsr()


def vector_dof_permutation(mesh, vector_basis, element: str | None = None) -> np.ndarray:
    """``perm`` with ``perm[3*s + c]`` = scikit-fem vector DOF of component c at scalar node s."""
    sb = scalar_basis(mesh, 1, element)
    perm = np.empty(3 * sb.N, dtype=np.int64)
    ve = vector_basis.element_dofs  # (3 nb, nel) local i -> (scalar i//3, comp i%3)
    se = sb.element_dofs
    for i in range(ve.shape[0]):
        perm[3 * se[i // 3] + i % 3] = ve[i]
    return perm


def interpolation_operator(basis, x: np.ndarray) -> sp.csr_matrix:
    """(3 m, 3N) sparse matrix evaluating the displacement at points ``x`` (3, m);
    row ``3 j + c`` gives component c at point j."""
    x = np.asarray(x, dtype=float).reshape(3, -1)
    P = _scalar_probes(basis, x).tocoo()  # (m, N)
    rows = np.concatenate([3 * P.row + c for c in range(3)])
    cols = np.concatenate([3 * P.col + c for c in range(3)])
    data = np.concatenate([P.data] * 3)
    return sp.csr_matrix((data, (rows, cols)), shape=(3 * P.shape[0], 3 * P.shape[1]))


def _scalar_probes(basis, x: np.ndarray) -> sp.csr_matrix:
    """Scalar interpolation matrix (m, N).  A point that coincides with a P2 node (within
    1e-9 of the mesh extent, e.g. a tip apex that is a mesh vertex) takes that node's value
    exactly (Lagrange property), which avoids the element finder's round-off failures on
    vertices and edges; other points must lie inside the mesh.  All other points go to one
    call of the element finder (vectorised; per point it costs a search of the whole mesh)."""
    from scipy.spatial import cKDTree

    locs = basis.doflocs
    ext = float(np.ptp(locs, axis=1).max())
    d, near = cKDTree(locs.T).query(x.T)
    exact = d <= 1e-9 * ext
    rows, cols, data = [np.nonzero(exact)[0]], [near[exact]], [np.ones(int(exact.sum()))]
    rest = np.nonzero(~exact)[0]
    if rest.size:
        try:
            P = basis.probes(x[:, rest]).tocoo()
        except ValueError:
            for j in rest:  # name the first point outside the mesh
                try:
                    basis.probes(x[:, j : j + 1])
                except ValueError:
                    raise GeometryError(f"point {x[:, j].tolist()} lies outside the mesh") from None
            raise
        rows.append(rest[P.row])
        cols.append(P.col)
        data.append(P.data)
    return sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(x.shape[1], basis.N))


def face_average_operator(mesh, facets: np.ndarray, element: str | None = None) -> tuple[sp.csr_matrix, float]:
    """(3, 3N) operator giving the area-averaged displacement over ``facets``, and the area.

    Its transpose applied to a force F gives the consistent nodal loads of the uniform
    traction F / area, so the pair (F, averaged displacement) is work-conjugate.
    """
    kind = element_kind(mesh, element)
    if isinstance(mesh, MeshHex2):
        a = _hex_face_weights(mesh, kind, np.asarray(facets))
    else:
        # degree 2 on flat triangles; 2 x 2 Gauss on (bilinear, here flat) quadrilaterals is exact too
        fb = FacetBasis(mesh, kind.element(), facets=np.asarray(facets), intorder=2)

        @LinearForm
        def one(v, w):
            return v

        a = one.assemble(fb)
    area = float(a.sum())
    if area <= 0:
        raise MaterialError("face_average_operator: empty face")
    nz = np.nonzero(a)[0]
    rows = np.concatenate([np.full(nz.size, c) for c in range(3)])
    cols = np.concatenate([3 * nz + c for c in range(3)])
    data = np.concatenate([a[nz] / area] * 3)
    return sp.csr_matrix((data, (rows, cols)), shape=(3, 3 * a.size)), area


def _hex_face_weights(mesh, kind, facets: np.ndarray) -> np.ndarray:
    """``int_face N_a dA`` for every scalar DOF, on the faces ``facets`` of a curved hexahedral
    mesh, by 3 x 3 Gauss points on the element's own reference face (scikit-fem's FacetBasis
    inverts the curved map by a clipped Newton iteration, which fails to converge on some
    curved faces).  Surface element |dx/du x dx/dv| from the element map."""
    basis = scalar_basis(mesh, 1, kind.key)
    elem = kind.element()
    nb = elem.doflocs.shape[0]
    ref = mesh.elem().doflocs[:8] if mesh.elem().doflocs.shape[0] > 8 else mesh.elem().doflocs  # vertex reference coords
    g1, w1 = np.polynomial.legendre.leggauss(3)
    g1, w1 = 0.5 * (g1 + 1.0), 0.5 * w1
    U, V = np.meshgrid(g1, g1, indexing="ij")
    WQ = np.outer(w1, w1).ravel()
    out = np.zeros(basis.N)
    elems = mesh.f2t[0, facets]
    mp = mesh._mapping()
    groups: dict[tuple[int, float], list[int]] = {}
    for k, (f, e) in enumerate(zip(facets, elems)):
        loc = [int(np.nonzero(mesh.t[:, e] == v)[0][0]) for v in mesh.facets[:, f]]
        r = ref[loc]
        axis = int(np.nonzero(np.all(r == r[0], axis=0))[0][0])
        groups.setdefault((axis, float(r[0, axis])), []).append(k)
    for (axis, val), ks in groups.items():
        others = [i for i in range(3) if i != axis]
        X = np.zeros((3, WQ.size))
        X[axis] = val
        X[others[0]], X[others[1]] = U.ravel(), V.ravel()
        es = elems[ks]
        DF = np.asarray(mp.DF(X, tind=es))  # (3, 3, ne, nq): dx_i / dxi_j
        n = np.cross(DF[:, others[0]], DF[:, others[1]], axis=0)
        dA = np.linalg.norm(n, axis=0) * WQ[None, :]  # (ne, nq)
        Nv = np.stack([elem.lbasis(X, i)[0] for i in range(nb)])  # (nb, nq)
        contrib = dA @ Nv.T  # (ne, nb)
        np.add.at(out, basis.element_dofs[:, es].T.ravel(), contrib.ravel())
    return out


def lumped_weights(mesh, elem_density: np.ndarray, element: str | None = None, basis=None) -> np.ndarray:
    """Positive nodal masses per scalar node (HRZ lumping: diagonal of the consistent mass
    scaled to the element mass), used to weight the mode classification."""
    Ms = assemble_scalar_mass(mesh, elem_density, element, basis)
    d = Ms.diagonal()
    return d * (Ms.sum() / d.sum())


__all__: Sequence[str] = [
    "aniso_elasticity", "mass_form", "assemble_stiffness", "assemble_mass", "assemble_scalar_mass",
    "assemble_stiffness_skfem", "interpolation_operator", "face_average_operator", "element_regions",
    "stiffness_field", "scalar_basis", "lumped_weights", "vector_dof_permutation", "assemble_mass_skfem",
]
