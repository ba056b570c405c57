"""The block eigen-solver's stopping rule and the free-DOF / mass-matrix construction.

Stopping rule (probedyn.fem.eigen.block_eigsh): a Ritz pair (theta, x) of the M-self-adjoint
OP = K^-1 M with residual rho = ||OP x - theta x||_M has an eigenvalue of OP within rho^2 / gap
(Kato-Temple), so the relative error of lambda = 1 / theta is at most (rho/theta)^2 theta / gap,
and the angle of x to its eigenvector at most rho / gap.  The solver stops when these bounds are
below ETOL and VTOL; the checks below compare against the same solver driven to the round-off
floor on the same factorisation (so the solves' own round-off is common to both) and against
ARPACK (an independent Krylov code).

The mixed-precision solver (probedyn.fem.eigen.mixed_eigsh: a float32 factor of K only as the
preconditioner of a block Davidson method, Rayleigh-Ritz and residuals r = K x - theta M x with the
double K and M) stops on the same bounds for the pencil, ||r||^2_{M^-1} / gap and ||r||_{M^-1} / gap;
it is checked against the double-precision block solver run to the floor."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from probedyn.fem.assembly import Pattern
from probedyn.core.errors import SolverError
from probedyn.fem.eigen import (ETOL, MINV_RTOL, TO_FLOOR, VTOL, _minv_norms, block_eigsh, factorize, have_pardiso,
                                mixed_eigsh, shift_invert_eigsh)
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


def _rayleigh_round_off(K, V):
    """Relative round-off of the Rayleigh quotients x^T K x / x^T M x of the columns of V: the
    products with K sum terms of size |x|^T |K| |x|, which exceeds x^T K x by ~cond(K) for the
    lowest modes (eps * that ratio, with a factor 16 for the accumulation in the sparse products and
    the dot products; the solves of the shift-invert path have the same eps cond(K) floor)."""
    absK = abs(K)
    num = np.einsum("ij,ij->j", np.abs(V), absK @ np.abs(V))
    return 16 * EPS * num / np.abs(np.einsum("ij,ij->j", V, K @ V))


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
@pytest.mark.parametrize("n_modes", [1, 6])
def test_mixed_solver_bounds_hold_against_the_double_solver_at_the_floor(KM, n_modes):
    K, M = KM
    f32, fac = factorize(K, options={"single": 1}), factorize(K)
    try:
        assert f32.approximate is not None and fac.approximate is None
        w, V, n_solved, info = mixed_eigsh(K, M, n_modes, f32.approximate)
        w_ref, V_ref, _, _ = block_eigsh(K, M, n_modes, 0.0, fac, rtol=TO_FLOOR)
    finally:
        f32.release()
        fac.release()
    bound = info["error_bounds"]
    rel_gap = bound / info["residuals"] ** 2
    assert np.all(bound < ETOL) and np.all(info["residuals"] * rel_gap < VTOL)
    assert info["cg_evaluations"] >= 1  # the stop was certified with CG's M^-1 norms
    # the Kato-Temple bound plus the round-off floor of both paths (eps cond(K), see above)
    assert np.all(np.abs(w / w_ref - 1) <= bound + 2 * _rayleigh_round_off(K, V))
    np.testing.assert_allclose(V.T @ (M @ V), np.eye(n_modes), atol=1e-10)  # M-orthonormal
    c = np.einsum("ij,ij->j", V, M @ V_ref)
    D = V_ref - V * c
    sin = np.sqrt(np.abs(np.einsum("ij,ij->j", D, M @ D)))
    assert np.all(sin <= info["residuals"] * rel_gap + 1e-9)  # 1e-9: the reference's own angle error


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_mixed_method_matches_the_default_block_solver_to_1e_8(KM):
    K, M = KM
    mix = shift_invert_eigsh(K, M, 10, sigma=0.0, method="mixed")
    blk = shift_invert_eigsh(K, M, 10, sigma=0.0)
    assert mix.method == "mixed" and "mixed_failed" not in mix.info
    np.testing.assert_allclose(np.sqrt(mix.eigenvalues), np.sqrt(blk.eigenvalues), rtol=1e-8)


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_mixed_solver_without_a_useful_preconditioner_raises_and_the_method_falls_back(KM, monkeypatch):
    K, M = KM
    with pytest.raises(SolverError, match="did not converge"):
        mixed_eigsh(K, M, 6, lambda R: R, max_vectors=24)  # identity "preconditioner": no K^-1 at all
    import probedyn.fem.eigen as E

    def refuse(*args, **kwargs):
        raise SolverError("refused")

    monkeypatch.setattr(E, "mixed_eigsh", refuse)
    res = shift_invert_eigsh(K, M, 4, sigma=0.0, method="mixed")
    assert res.method == "block" and res.info["mixed_failed"] == "refused"


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_auto_method_is_mixed_for_large_positive_definite_models_only(KM, monkeypatch):
    import probedyn.fem.eigen as E

    n = KM[0].shape[0]
    assert E.auto_method(n, 0.0) == "block"  # a small model: the block solver
    monkeypatch.setattr(E, "MIXED_MIN_DOFS", n)
    assert E.auto_method(n, 0.0) == "mixed"
    assert E.auto_method(n, -1.0) == "block"  # a shifted (free-floating) model
    assert E.auto_method(n, 0.0, tol=TO_FLOOR) == "block"  # vectors to the floor: the double factor
    assert E.auto_method(n, 0.0, solver="superlu") == "block"
    K, M = KM
    res = shift_invert_eigsh(K, M, 4, sigma=0.0)
    assert res.method == "mixed"


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_model_modes_take_the_mixed_path_with_its_single_precision_analysis(monkeypatch):
    import probedyn.fem.eigen as E

    def model():
        b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(2), "hex-s2")
        return ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"])

    ref = model().modes(6)
    taken = []
    take = E.Analysis.take

    def spy(self, upper, mtype, opts):
        ps = take(self, upper, mtype, opts)
        taken.append((opts["single"], ps is not None))
        return ps

    monkeypatch.setattr(E.Analysis, "take", spy)
    monkeypatch.setattr(E, "MIXED_MIN_DOFS", 0)
    mix = model().modes(6)
    assert mix.solver.endswith("+mixed") and not ref.solver.endswith("+mixed")
    assert taken == [(1, True)]  # the analysis beside the assembly was the single-precision one, and used
    np.testing.assert_allclose([m.frequency_hz for m in mix.modes], [m.frequency_hz for m in ref.modes], rtol=1e-8)


def test_cg_m_inverse_norm_equals_the_direct_solve(KM):
    import scipy.sparse.linalg as spla

    K, M = KM
    R = K @ np.random.default_rng(0).standard_normal((K.shape[0], 3))  # rough: all of M's spectrum
    exact = np.einsum("ij,ij->j", R, spla.splu(M.tocsc()).solve(R))
    est = _minv_norms(M, R, 1.0 / M.diagonal())
    # CG's r^T x_k is within rtol^2 ||r||^2_{D^-1} / mu_min of r^T M^-1 r, and the estimate of that
    # remainder is added: relative error well below rtol
    assert np.all(np.abs(est / exact - 1) < MINV_RTOL)


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
