"""The block eigen-solver's stopping rule and the free-DOF / mass-matrix construction.

Stopping rule (probedyn.fem.eigen.block_eigsh): a Ritz pair (theta, x) of the M-self-adjoint
OP = K^-1 M with residual rho = ||OP x - theta x||_M has an eigenvalue of OP within rho^2 / gap
(Kato-Temple), so the relative error of lambda = 1 / theta is at most (rho/theta)^2 theta / gap,
and the angle of x to its eigenvector at most rho / gap.  The solver stops when these bounds are
below ETOL and VTOL; the checks below compare against the same solver driven to the round-off
floor on the same factorisation (so the solves' own round-off is common to both) and against
ARPACK (an independent Krylov code)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from probedyn.fem.assembly import Pattern
from probedyn.fem.eigen import ETOL, TO_FLOOR, VTOL, block_eigsh, factorize, have_pardiso, shift_invert_eigsh
from probedyn.fem.materials import get_material
from probedyn.fem.model import ElasticModel, principal_submatrix
from probedyn.meshes.hexmeshes import HexDivisions, cantilever_hex

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def KM():
    b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(2), "hex-s2")
    return ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"]).free_matrices()


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
@pytest.mark.parametrize("n_modes", [1, 6, 10])
def test_stopping_rule_bounds_hold_against_the_round_off_floor(KM, n_modes):
    K, M = KM
    fac = factorize(K)
    try:
        w, V, n_solved, info = block_eigsh(K, M, n_modes, 0.0, fac)
        w_ref, V_ref, n_ref, _ = block_eigsh(K, M, n_modes, 0.0, fac, rtol=TO_FLOOR)
    finally:
        fac.release()
    bound = info["error_bounds"]
    rel_gap = bound / info["residuals"] ** 2
    assert np.all(bound < ETOL) and np.all(info["residuals"] * rel_gap < VTOL)
    # eigenvalues: within the bound + the round-off of the projected eigenproblem (eigh is
    # backward stable: absolute error ~ eps ||H|| = eps theta_1, relative eps lambda_i / lambda_1)
    assert np.all(np.abs(w / w_ref - 1) <= bound + 16 * EPS * w / w[0])
    # eigenvectors: sin(angle) = sqrt(1 - (x^T M x_ref)^2) within the angle bound rho / gap
    # (the M-norm of the part of x_ref orthogonal to x, which has no sqrt(eps) floor)
    c = np.einsum("ij,ij->j", V, M @ V_ref)
    D = V_ref - V * c
    sin = np.sqrt(np.abs(np.einsum("ij,ij->j", D, M @ D)))
    assert np.all(sin <= info["residuals"] * rel_gap + 1e-9)  # 1e-9: the reference's own angle error
    assert n_solved < n_ref  # the rule saves the blocks that only polish the vectors to the floor


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_default_path_matches_arpack_to_1e_8(KM):
    K, M = KM
    blk = shift_invert_eigsh(K, M, 10, sigma=0.0)
    arp = shift_invert_eigsh(K, M, 10, sigma=0.0, method="arpack")
    assert blk.method == "block"
    np.testing.assert_allclose(np.sqrt(blk.eigenvalues), np.sqrt(arp.eigenvalues), rtol=1e-8)


def test_principal_submatrix_equals_scipy_indexing():
    rng = np.random.default_rng(5)
    for n in (1, 7, 60):
        A = sp.random(n, n, density=0.2, random_state=n, format="csr")
        A = (A + A.T).tolil()
        A[n - 1, :] = 0  # an empty row
        A = A.tocsr()
        A.eliminate_zeros()
        keep = np.sort(rng.choice(n, size=max(1, n // 2), replace=False))
        B = principal_submatrix(A, keep)
        assert B.has_sorted_indices
        np.testing.assert_array_equal(B.toarray(), A[keep][:, keep].toarray())


def test_vector_mass_is_kron_with_identity_without_zeros():
    S = sp.random(40, 40, density=0.2, random_state=2, format="csr")
    S = (S + S.T + sp.identity(40)).tocsr()
    S.sort_indices()
    pat = Pattern(S.indptr.astype(np.int64), S.indices.astype(np.int64), np.zeros((0, 0, 0), np.int64),
                  np.zeros((0, 0), np.int64), 40)
    V = pat.vector_from_scalar(S.data)
    assert V.nnz == 3 * S.nnz and V.has_sorted_indices
    assert abs(V - sp.kron(S, sp.identity(3))).max() == 0
