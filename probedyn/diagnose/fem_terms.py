"""FEM matrices the diagnosis adds to a probe's model, and their projections on a Ritz basis.

All act on the interleaved DOF vector of :class:`probedyn.fem.model.ElasticModel`
(``3 * node + component``, the nodes of ``model.basis``: P2 tetrahedra or quadratic hexahedra;
nothing here depends on the element type).

* :func:`face_mass_scalar` -- ``S_ab = int_face phi_a phi_b dA`` (scalar P2 functions on a
  boundary); with a direction it gives the **elastic foundation** matrices of a clamp face,
  ``K_n = k_n (n n^T) (x) S`` (normal springs per unit area, resisting axial translation and
  the rotations that bend the root) and ``K_t = k_t (I - n n^T) (x) S`` (tangential springs per
  unit area, resisting shear translation and twist), and the flapwise **surface mass** of the
  fluid loading.
* :func:`axial_gradient_matrix` -- ``G_a = int (d_a u) . (d_a v) dV``, the geometric stiffness
  of a uniform axial stress sigma along axis a: ``K_G = sigma G_a`` (the second-order work of
  the prestress, e.g. Bathe, Finite Element Procedures, eq 6.46 for a uniaxial stress).
* :func:`reduced_stiffness_split` -- the stiffness projected on a basis ``Phi`` and split by the
  coordinate directions of the two derivatives, ``K_jl = int (d_j Phi)^T C (d_l Phi) dV``: under
  an affine stretch ``x_i -> s_i x_i`` of the mesh the P2 stiffness of the stretched body is
  *exactly* ``sum_jl s_x s_y s_z / (s_j s_l) K_jl`` and its mass ``s_x s_y s_z M`` (every
  derivative ``d_j`` scales by ``1 / s_j``, the volume by ``s_x s_y s_z``). Thickness, width and
  length errors of a prismatic probe are therefore exact parametric updates of the reduced model.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from probedyn.core.errors import GeometryError
from probedyn.fem import elasticity as el

__all__ = ["face_mass_scalar", "face_normal", "directional", "axial_gradient_matrix", "reduced_stiffness_split"]


def face_mass_scalar(model, face: str) -> sp.csr_matrix:
    """``int_face phi_a phi_b dA`` over the boundary ``face`` (scalar P2, N x N)."""
    from skfem import BilinearForm, FacetBasis

    mesh = model.mesh
    if face not in (mesh.boundaries or {}):
        raise GeometryError(f"boundary '{face}' not in the mesh (known: {', '.join(mesh.boundaries or {})})")
    fb = FacetBasis(mesh, model.basis.elem, facets=np.asarray(mesh.boundaries[face]), intorder=4)

    @BilinearForm
    def mass(u, v, w):
        return u * v

    S = mass.assemble(fb).tocsr()
    if S.shape[0] != model.n_nodes:  # pragma: no cover - same element, same numbering
        raise GeometryError("face matrix and model basis disagree on the node numbering")
    return S


def face_normal(model, face: str) -> np.ndarray:
    """Area-weighted unit normal of a (planar) boundary face."""
    mesh = model.mesh
    f = np.asarray(mesh.boundaries[face])
    tri = mesh.p[:, mesh.facets[:, f]]  # (3, 3 vertices, nf)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0], axis=0)
    # orient all facets alike before summing
    ref = n[:, np.argmax(np.linalg.norm(n, axis=0))]
    n = n * np.sign(ref @ n)[None, :]
    s = n.sum(axis=1)
    return s / np.linalg.norm(s)


def directional(S: sp.spmatrix, D: np.ndarray) -> sp.csr_matrix:
    """Interleaved 3N x 3N matrix ``S (x) D`` (a 3 x 3 directional weight per node pair)."""
    return sp.kron(S, sp.csr_matrix(np.asarray(D, float)), format="csr")


def axial_gradient_matrix(model, axis: int) -> sp.csr_matrix:
    """``int sum_i (d_a u_i)(d_a v_i) dV`` along ``axis`` a (3N x 3N, interleaved)."""
    from skfem import BilinearForm

    basis = model.basis  # the model's own scalar element (tetrahedra or hexahedra)

    @BilinearForm
    def lap(u, v, w):
        return u.grad[axis] * v.grad[axis]

    G = lap.assemble(basis)
    return sp.kron(G, sp.identity(3), format="csr")


def _chunk_size(nq: int, per_point: int, chunk: int | None) -> int:
    """Elements per chunk: ``chunk`` if given, else as many as keep one chunk's largest work array
    (``nq`` quadrature points x ``per_point`` doubles per element) near 1 M doubles (8 MB). Larger
    chunks gain nothing in the batched products and pay the page faults of fresh ~100 MB arrays
    (measured on the default cantilever, 840 hexahedra x 8 points, a 143-shape basis: 1.38 s for the
    first split in one chunk, 0.29 s in the chunks of 50 elements this gives; the sums agree to 5e-16)."""
    if chunk is not None:
        return max(1, int(chunk))
    return max(16, int(2 ** 20 // max(1, nq * per_point)))


def reduced_stiffness_split(model, Phi: np.ndarray, chunk: int | None = None,
                            elements: np.ndarray | None = None, materials=None,
                            intorder: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Projected stiffness split by derivative directions, and the projected axial gradients.

    Returns ``Ks`` of shape (3, 3, r, r), ``Ks[j, l] = int (d_j Phi)^T C (d_l Phi) dV`` (so that
    ``Phi^T K Phi = sum_jl Ks[j, l]``), and ``G`` of shape (3, r, r),
    ``G[a] = int sum_i (d_a Phi_i)^T (d_a Phi_i) dV``. The material field of
    :func:`probedyn.fem.elasticity.assemble_stiffness`; the quadrature ``intorder`` (default
    ``STIFFNESS_INTORDER`` = 2: exact for P2 tetrahedra, the 2 x 2 x 2 Gauss rule on hexahedra). On
    hexahedra the assembly integrates with 3 x 3 x 3 points (``intorder`` 5, ~4x the cost here); the 2 x 2 x 2 rule
    is exact for displacement fields of degree <= 2 (strains linear) and on the FEM modes of the default
    cantilever differs from the assembled stiffness by 3e-5 to 7e-4 of their Rayleigh quotients (up to 15 % on
    the Ritz basis's rough correction shapes). The reduced model uses only the split's *change* under a stretch
    (``ReducedModal.matrices``: ``K(s) = sum_jl w_jl(s) Ks[j, l] + (K - sum_jl Ks[j, l])``, exact at s = 1),
    so a stretch moves those modes' frequencies with a relative error below ~1e-3 of the shift.
    ``elements``: integrate over these elements
    only (e.g. a meshed tip, which a geometric stretch maps differently). ``materials``: per-region
    objects with a Voigt ``C`` in the material's own axes to integrate instead of the model's (e.g.
    a crystal's difference from its isotropic model, :func:`probedyn.diagnose.modal_model.crystal_parts`).
    """
    from skfem.quadrature import get_quadrature

    mesh = model.mesh
    elem = model.basis.elem  # the model's own scalar element (tetrahedra or hexahedra)
    X, W = get_quadrature(elem.refdom, el.STIFFNESS_INTORDER if intorder is None else intorder)
    mapping = mesh._mapping()
    nloc = model.basis.element_dofs.shape[0]
    dref = np.stack([elem.lbasis(X, i)[1] for i in range(nloc)])  # (nloc, 3, nq)
    edofs = model.basis.element_dofs  # (nloc, nel)
    nel = mesh.t.shape[1]
    r = Phi.shape[1]
    U = np.asarray(Phi).reshape(model.n_nodes, 3, r)
    Ks = np.zeros((3, 3, r, r))
    G = np.zeros((3, r, r))
    # Voigt rows (engineering shear) of the strain of a gradient H[i, j] = d_j u_i
    pairs = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    # Voigt row I of the strain picks H[a, b] + H[b, a] (a != b) or H[a, a]; the part with
    # derivative direction j keeps the entries whose second index is j
    sel_rows = [[(I, a) for I, (a, b) in enumerate(pairs) if b == j] + [(I, b) for I, (a, b) in enumerate(pairs)
                if a != b and a == j] for j in range(3)]
    els = np.arange(nel) if elements is None else np.asarray(elements, int)
    chunk = _chunk_size(len(W), 6 * 3 * r, chunk)  # F of _add_split: (e, q, 6, 3r)
    for start in range(0, els.size, chunk):
        sel = els[start:start + chunk]
        ne = sel.size
        invDF = mapping.invDF(X, tind=sel)
        detDF = np.abs(mapping.detDF(X, tind=sel))
        g = np.einsum("akq,kjeq->eqja", dref, invDF, optimize=True)  # (e, q, 3, nloc)
        Ue = U[edofs[:, sel].T].reshape(ne, 1, nloc, 3 * r)  # (e, 1, nloc, 3r)
        H = np.matmul(g, Ue).reshape(ne, -1, 3, 3, r)  # H[e, q, j, i, r] = d_j u_i
        x_qp = mapping.F(X, tind=sel)
        C = el.stiffness_field(model.elem_region, model.materials if materials is None else materials,
                               model.orientations, x_qp, elements=sel)
        sw = np.sqrt(detDF * W[None, :])[:, :, None, None]
        E = []
        for j in range(3):
            Ej = np.zeros((ne, H.shape[1], 6, r))
            for I, i in sel_rows[j]:
                Ej[:, :, I] += H[:, :, j, i]
            E.append(Ej * sw)
            Hj = H[:, :, j] * sw  # (e, q, i, r)
            Hj2 = Hj.reshape(-1, r)
            G[j] += Hj2.T @ Hj2
        _add_split(Ks, C, E, r)
    return Ks, G


def _add_split(Ks: np.ndarray, C: np.ndarray, E: list[np.ndarray], r: int) -> None:
    """``Ks[l, j] += E_l^T C E_j`` over the rows of one chunk. Where ``C`` is positive definite at every
    quadrature point (a material's stiffness) it is factored, ``C = L L^T``, and the nine blocks are one
    symmetric product ``F^T F`` of ``F = [L^T E_0, L^T E_1, L^T E_2]`` (half the operations of nine
    products); otherwise (a difference of two materials' stiffnesses) the six blocks ``l <= j`` are
    formed and the others are their transposes (``C`` is symmetric)."""
    try:
        L = np.linalg.cholesky(C)
    except np.linalg.LinAlgError:
        L = None
    if L is not None:
        LT = np.swapaxes(L, -1, -2)
        F = np.concatenate([np.matmul(LT, Ej) for Ej in E], axis=-1).reshape(-1, 3 * r)
        Ks += (F.T @ F).reshape(3, r, 3, r).transpose(0, 2, 1, 3)
        return
    for j in range(3):
        CE = np.matmul(C, E[j]).reshape(-1, r)
        for l in range(j + 1):
            B = E[l].reshape(-1, r).T @ CE
            Ks[l, j] += B
            if l != j:
                Ks[j, l] += B.T


_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def _voigt_tensor(s: np.ndarray) -> np.ndarray:
    """(..., 6, r) Voigt stress -> (..., 3, 3, r) symmetric tensor."""
    T = np.empty(s.shape[:-2] + (3, 3, s.shape[-1]))
    for I, (a, b) in enumerate(_VOIGT):
        T[..., a, b, :] = s[..., I, :]
        T[..., b, a, :] = s[..., I, :]
    return T


def stretch_sensitivity(model, V: np.ndarray, chunk: int | None = None, elements: np.ndarray | None = None,
                        internal_force: bool = False):
    """``dK/ds_a V`` at s = 1 for the three axes a, shape (3, N, n): the first derivative of the
    stiffness under a stretch of the mesh along a, minus the volume term,
    ``sum_l (K_al + K_la) V``, whose difference with ``K V`` gives ``dK/ds_a V = (K - K_a. - K_.a) V``.

    Used for first-order shape corrections ``K^-1 (dK/ds_a - lambda dM/ds_a) phi`` (Fox & Kapoor) of
    the Ritz basis for thickness, width and length changes. Computed element by element (no
    split matrices are formed): ``f_i = int [ d_a N sigma_ia(V) + d_j N sigma^a_ij(V) ]`` where
    ``sigma^a`` is the stress of the strain built from the derivatives along a only.
    """
    from skfem.quadrature import get_quadrature

    mesh = model.mesh
    elem = model.basis.elem  # the model's own scalar element (tetrahedra or hexahedra)
    X, W = get_quadrature(elem.refdom, el.STIFFNESS_INTORDER)
    mapping = mesh._mapping()
    nloc = model.basis.element_dofs.shape[0]
    dref = np.stack([elem.lbasis(X, i)[1] for i in range(nloc)])
    edofs = model.basis.element_dofs
    nel = mesh.t.shape[1]
    n = V.shape[1]
    U = np.asarray(V).reshape(model.n_nodes, 3, n)
    out = np.zeros((3, model.n_nodes, 3, n))
    kv = np.zeros((model.n_nodes, 3, n)) if internal_force else None  # K V over the elements (``internal_force``)
    els = np.arange(nel) if elements is None else np.asarray(elements, int)  # ``elements``: these only
    chunk = _chunk_size(len(W), 9 * n, chunk)  # H and sig: (e, q, 3, 3, n)
    for start in range(0, els.size, chunk):
        sel = els[start:start + chunk]
        ne = sel.size
        invDF = mapping.invDF(X, tind=sel)
        detDF = np.abs(mapping.detDF(X, tind=sel))
        g = np.einsum("akq,kjeq->eqja", dref, invDF, optimize=True)  # (e, q, 3, nloc)
        Ue = U[edofs[:, sel].T].reshape(ne, 1, nloc, 3 * n)
        H = np.matmul(g, Ue).reshape(ne, -1, 3, 3, n)  # H[e, q, j, i, :] = d_j u_i
        x_qp = mapping.F(X, tind=sel)
        C = el.stiffness_field(model.elem_region, model.materials, model.orientations, x_qp, elements=sel)
        wq = (detDF * W[None, :])[:, :, None, None, None]
        eps = np.empty((ne, H.shape[1], 6, n))
        for I, (a, b) in enumerate(_VOIGT):
            eps[:, :, I] = H[:, :, a, a] if a == b else H[:, :, b, a] + H[:, :, a, b]
        sig = _voigt_tensor(np.matmul(C, eps)) * wq  # (e, q, 3, 3, n)
        nodes = edofs[:, sel].T  # (e, nloc)
        if kv is not None:
            np.add.at(kv, nodes, np.einsum("eqja,eqijn->eain", g, sig, optimize=True))
        for ax in range(3):
            ea = np.zeros_like(eps)
            for I, (a, b) in enumerate(_VOIGT):
                if a == b:
                    if a == ax:
                        ea[:, :, I] = H[:, :, ax, a]
                else:
                    if b == ax:
                        ea[:, :, I] += H[:, :, ax, a]  # d_ax u_a with b == ax
                    if a == ax:
                        ea[:, :, I] += H[:, :, ax, b]
            siga = _voigt_tensor(np.matmul(C, ea)) * wq
            # f[node, i] = sum_q g[node, ax] sig[i, ax] + sum_j g[node, j] siga[i, j]
            f = np.einsum("eqa,eqin->eain", g[:, :, ax, :], sig[:, :, :, ax, :], optimize=True)
            f += np.einsum("eqja,eqijn->eain", g, siga, optimize=True)
            np.add.at(out[ax], nodes, f)
    out = out.reshape(3, model.n_nodes * 3, n)
    return (out, kv.reshape(model.n_nodes * 3, n)) if internal_force else out
