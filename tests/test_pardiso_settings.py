"""PARDISO settings of ``probedyn.fem.eigen`` and the block eigen-solver's restart path, on the
stiffness of a small clamped cantilever (ill-conditioned like the production models:
cond(K) ~ 1e9, so single precision alone is not enough).

Independent checks: the backward error of a solve (``||K x - b|| / (||K|| ||x||)``, which a
backward-stable double-precision solve keeps at O(eps64) and a float32 one at O(eps32)),
and ARPACK for the eigenpairs.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from probedyn.fem.eigen import block_eigsh, factorize, have_pardiso, shift_invert_eigsh
from probedyn.fem.materials import get_material
from probedyn.fem.model import ElasticModel, Spring
from probedyn.meshes.hexmeshes import HexDivisions, cantilever_hex

pytestmark = pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")

EPS64, EPS32 = np.finfo(np.float64).eps, np.finfo(np.float32).eps


@pytest.fixture(scope="module")
def KM():
    b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(2), "hex-s2")
    return ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"]).free_matrices()


def _backward_error(K, X, B):
    nK = spla.norm(K, 1)
    return float(np.max(np.abs(K @ X - B).sum(axis=0) / (nK * np.abs(X).sum(axis=0))))


def test_vbsr_csr_and_mixed_precision_solve_to_double_accuracy(KM):
    K, _ = KM
    B = np.random.default_rng(4).standard_normal((K.shape[0], 5))
    ref = factorize(K, options={"vbsr": 0})  # plain CSR, double
    X0 = ref.solve(B)
    ref.release()
    # a backward-stable double solve: backward error a modest multiple of eps64 (n-dependent growth)
    assert _backward_error(K, X0, B) < 1e3 * EPS64
    for opts in ({}, {"vbsr": -80}, {"single": 1}):
        f = factorize(K, options=opts)
        try:
            X = f.solve(B)
        finally:
            f.release()
        # the same double-precision backward error, whatever the internal format / precision
        assert _backward_error(K, X, B) < 1e3 * EPS64, opts
    # one sweep only: the float32 factor's backward error is at the float32 level (far from
    # eps64): refinement is what makes the mixed-precision path exact, not the factor
    f = factorize(K, options={"single": 1, "refinement": 1})
    try:
        X1 = f.solve(B)
        assert f.info["refinement_sweeps"] == 1
    finally:
        f.release()
    assert _backward_error(K, X1, B) > 1e3 * EPS64


def test_block_solver_with_thick_restarts_matches_arpack(KM):
    """Few Krylov blocks per cycle force thick restarts; the converged pairs still agree with
    ARPACK to 1e-8 (eigenvalue error ~ residual^2 << 1e-8 for residuals below 1e-8)."""
    K, M = KM
    ref = shift_invert_eigsh(K, M, 6, sigma=0.0, method="arpack")
    fac = factorize(K)
    try:
        w, V, n_solved, info = block_eigsh(K, M, 6, 0.0, fac, block=7, steps=1, rtol=1e-8)
    finally:
        fac.release()
    assert info["restarts"] >= 1
    assert info["residuals"].max() < 1e-8 or info.get("floor")
    np.testing.assert_allclose(w, ref.eigenvalues, rtol=1e-8)
    assert np.abs(V.T @ (M @ V) - np.eye(6)).max() < 1e-10


def test_upper_triangle_is_scipy_triu_one_based(KM):
    """PARDISO's input (compiled pass) equals scipy's triu with 1-based int32 indices, also for
    a row whose diagonal is not stored and for an empty row."""
    import scipy.sparse as sp

    from probedyn.fem.kernels import upper_triangle

    K, _ = KM
    R = sp.random(60, 60, density=0.1, random_state=np.random.default_rng(2), format="csr")
    R = (R + R.T).tolil()
    R[7, 7] = 0.0
    R[11, :] = 0.0
    R[:, 11] = 0.0
    for A in (K, sp.csr_matrix(R)):
        A = sp.csr_matrix(A)
        A.eliminate_zeros()
        A.sort_indices()
        U = sp.triu(A, format="csr")
        U.sort_indices()
        ia, ja, val = upper_triangle(A.indptr, A.indices, A.data)
        assert ia.dtype == ja.dtype == np.int32
        np.testing.assert_array_equal(ia, U.indptr + 1)
        np.testing.assert_array_equal(ja, U.indices + 1)
        np.testing.assert_array_equal(val, U.data)


def _hex_model(**kw):
    b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(2), "hex-s2")
    return ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"], **kw)


def test_analysis_from_the_mesh_pattern_is_the_same_factorisation():
    """PARDISO's analysis started from the pattern the mesh implies (before assembly, in a
    background thread) is taken for K_ff and gives the solutions of the plain path bit for bit
    (same ordering, same numeric factorisation); the predicted pattern is K_ff's upper triangle."""
    from probedyn.fem.kernels import upper_triangle

    model = _hex_model()
    an = model.start_analysis()
    K, _ = model.free_matrices()
    ia, ja, _ = upper_triangle(K.indptr, K.indices, K.data)
    np.testing.assert_array_equal(an.ia, ia)
    np.testing.assert_array_equal(an.ja, ja)
    f1 = factorize(K, analysis=an)
    f0 = factorize(K)
    B = np.random.default_rng(5).standard_normal((K.shape[0], 3))
    try:
        assert f1.info["analysis_overlapped"] and not f0.info["analysis_overlapped"]
        np.testing.assert_array_equal(f1.solve(B), f0.solve(B))
    finally:
        f0.release()
        f1.release()
    assert an.ps is None  # taken (and the factorisation owns it)


def test_analysis_not_fitting_the_matrix_is_released_and_redone():
    """A spring on a face couples nodes the mesh does not: K_ff's pattern differs from the
    predicted one, the background analysis is dropped and the matrix analysed as usual, with
    the same eigenvalues as the plain path; modes() with and without the overlap agree exactly."""
    spring = Spring("free_end", None, 5.0, (0, 0, 1))
    model = _hex_model(springs=[spring])
    an = model.start_analysis()
    K, M = model.free_matrices()
    r1 = shift_invert_eigsh(K, M, 4, sigma=0.0, analysis=an)
    r0 = shift_invert_eigsh(K, M, 4, sigma=0.0)
    assert not r1.info["analysis_overlapped"]
    assert an.ps is None
    np.testing.assert_array_equal(r1.eigenvalues, r0.eigenvalues)
    plain = _hex_model()
    K, M = plain.free_matrices()
    ref = shift_invert_eigsh(K, M, 4, sigma=0.0)
    np.testing.assert_array_equal(_hex_model().modes(4).frequencies_hz, np.sqrt(ref.eigenvalues) / (2 * np.pi))
