"""The previous (issue 2) vectorised numpy assembly of P2 tetrahedra, kept only as the
reference of benchmarks/modal.py ("compiled vs vectorised"): per element chunk, batched
``K_e = sum_q w_q B_q^T C_q B_q`` by matmul/einsum, then one COO -> CSR conversion."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTetP2
from skfem.quadrature import get_quadrature

from probedyn.fem.elasticity import stiffness_field, strain_operator

STIFFNESS_INTORDER = 2
MASS_INTORDER = 4


def scalar_basis(mesh, intorder: int):
    return Basis(mesh, ElementTetP2(), intorder=intorder)


def _chunks(n: int, size: int):
    for a in range(0, n, size):
        yield np.arange(a, min(a + size, n))


def assemble_stiffness_numpy(
    mesh,
    elem_region: np.ndarray,
    materials: Sequence,
    orientations: Sequence,
    chunk: int = 8192,
) -> sp.csr_matrix:
    """Global stiffness (3N x 3N, interleaved DOFs) by batched element matrices.

    Per element chunk: scalar P2 gradients ``g`` (nel, nq, 10, 3) -> strain-displacement
    matrices ``B`` (nel, nq, 6, 30) -> ``K_e = sum_q w_q B^T (C_q B)`` -> COO triplets.
    """
    elem = ElementTetP2()
    X, W = get_quadrature(elem.refdom, STIFFNESS_INTORDER)
    nq = W.size
    mapping = mesh._mapping()
    # reference gradients of the 10 scalar functions: (10, 3, nq)
    dref = np.stack([elem.lbasis(X, i)[1] for i in range(10)])
    basis0 = scalar_basis(mesh, 1)  # for element_dofs only (cheap: 1-point rule)
    edofs = basis0.element_dofs  # (10, nel)
    nel = mesh.t.shape[1]
    N = basis0.N
    ldof = np.arange(30)
    a_idx, c_idx = ldof // 3, ldof % 3
    rows_all, cols_all, data_all = [], [], []
    for sel in _chunks(nel, chunk):
        invDF = mapping.invDF(X, tind=sel)  # (3, 3, nel, nq): d(ref)/d(x)
        detDF = np.abs(mapping.detDF(X, tind=sel))  # (nel, nq)
        # physical gradients g[e, q, a, j] = sum_k dref[a, k, q] invDF[k, j, e, q]
        g = np.einsum("akq,kjeq->eqaj", dref, invDF, optimize=True)
        B = strain_operator(g)  # (e, q, 6, 30)
        x_qp = mapping.F(X, tind=sel)  # (3, nel, nq)
        C = stiffness_field(elem_region, materials, orientations, x_qp, elements=sel)
        wq = detDF * W[None, :]  # (e, q)
        CB = np.matmul(C, B) * wq[:, :, None, None]
        Ke = np.einsum("eqIa,eqIb->eab", B, CB, optimize=True)
        gd = (3 * edofs[a_idx][:, sel] + c_idx[:, None]).T  # (e, 30)
        rows_all.append(np.repeat(gd, 30, axis=1).ravel().astype(np.int32))
        cols_all.append(np.tile(gd, (1, 30)).ravel().astype(np.int32))
        data_all.append(Ke.ravel())
    n = 3 * N
    K = sp.coo_matrix(
        (np.concatenate(data_all), (np.concatenate(rows_all), np.concatenate(cols_all))), shape=(n, n)
    ).tocsr()
    K.sum_duplicates()
    return K


def assemble_scalar_mass_numpy(mesh, elem_density: np.ndarray) -> sp.csr_matrix:
    """Scalar P2 mass ``int rho N_a N_b`` (N x N) with a per-element density."""
    basis = scalar_basis(mesh, MASS_INTORDER)
    vals = np.stack([np.asarray(basis.basis[a][0]) for a in range(10)], axis=-1)  # (nel, nq, 10)
    wq = basis.dx * elem_density[:, None]
    Me = np.einsum("eqa,eqb,eq->eab", vals, vals, wq, optimize=True)
    ed = basis.element_dofs.T  # (nel, 10)
    rows = np.repeat(ed, 10, axis=1).ravel()
    cols = np.tile(ed, (1, 10)).ravel()
    Ms = sp.coo_matrix((Me.ravel(), (rows, cols)), shape=(basis.N, basis.N)).tocsr()
    Ms.sum_duplicates()
    return Ms


def assemble_mass_numpy(mesh, elem_density: np.ndarray) -> sp.csr_matrix:
    """Vector mass ``kron(M_scalar, I3)`` in the interleaved numbering."""
    return sp.kron(assemble_scalar_mass_numpy(mesh, elem_density), sp.identity(3), format="csr")


