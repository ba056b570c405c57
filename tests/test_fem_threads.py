"""The threaded kernels of the eigen-solvers and the compiled CSR conversions of the assembly.

probedyn.fem.eigen.matmat splits the rows of a CSR x dense-block product between plain Python
threads running a compiled kernel without the GIL; every entry is the same sum, in the same order,
as scipy's csr_matvecs, so the product must equal scipy's bit for bit.  rows_matmul splits a tall
dense product the same way; BLAS may pick another kernel for a row slice, so each entry can differ
by the round-off of its m-term sum: |dy| <= m eps sum_p |a_ip| |b_pj| (Higham, thm 3.5, times 2 for
the two evaluations).  Pattern.vector / vector_from_scalar build the interleaved CSR of a 3 x 3 block
matrix / of kron(S, I3) in one compiled pass: the same arrays (values, indices, index dtypes) as
scipy's bsr_matrix.tocsr() / a direct construction."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from probedyn.fem import eigen as E
from probedyn.fem.assembly import Pattern
from probedyn.fem.materials import get_material
from probedyn.fem.model import ElasticModel
from probedyn.meshes.hexmeshes import HexDivisions, cantilever_hex

EPS = np.finfo(float).eps


def _random_csr(n: int, per_row: int, seed: int) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    A = sp.csr_matrix((rng.standard_normal(n * per_row), (np.repeat(np.arange(n), per_row),
                                                          rng.integers(0, n, n * per_row))), shape=(n, n))
    A.sum_duplicates()
    return A


@pytest.mark.parametrize("threads", [2, 3])
def test_matmat_equals_scipy_bit_for_bit(threads, monkeypatch):
    monkeypatch.setattr(E, "MATMAT_MIN_WORK", 0)
    A = _random_csr(3001, 17, 1)
    for X in (np.random.default_rng(2).standard_normal((3001, 6)),
              np.asfortranarray(np.random.default_rng(3).standard_normal((3001, 10)))):
        Y = E.matmat(A, X, threads=threads)
        assert Y.shape == (3001, X.shape[1])
        np.testing.assert_array_equal(Y, A @ X)


def test_matmat_falls_back_to_scipy_where_it_does_not_apply(monkeypatch):
    monkeypatch.setattr(E, "MATMAT_MIN_WORK", 0)
    A = _random_csr(50, 5, 4)
    x = np.arange(50.0)
    np.testing.assert_array_equal(E.matmat(A, x, threads=2), A @ x)  # a vector
    np.testing.assert_array_equal(E.matmat(A.tocsc(), x[:, None], threads=2), A @ x[:, None])  # not CSR
    assert E.matmat(A, x[:, None].astype(np.float32), threads=2).dtype == (A @ x[:, None].astype(np.float32)).dtype


@pytest.mark.parametrize("threads", [2, 3])
def test_rows_matmul_equals_numpy_to_its_round_off(threads, monkeypatch):
    monkeypatch.setattr(E, "MATMAT_MIN_WORK", 0)
    rng = np.random.default_rng(6)
    for m, k in ((60, 6), (37, 10), (3, 1)):
        A = np.asfortranarray(rng.standard_normal((4001, m)))
        B = rng.standard_normal((m, k))
        Y = E.rows_matmul(A, B, threads=threads)
        bound = 2 * m * EPS * (np.abs(A) @ np.abs(B))
        assert np.all(np.abs(Y - A @ B) <= bound)


def test_block_to_csr_and_kron_equal_scipy_arrays():
    S = _random_csr(200, 9, 7)
    S = (S + S.T + sp.identity(200)).tocsr()
    S.sort_indices()
    pat = Pattern(S.indptr.astype(np.int64), S.indices.astype(np.int64), np.zeros((0, 0, 0), np.int64),
                  np.zeros((0, 0), np.int64), 200)
    blocks = np.random.default_rng(8).standard_normal((S.nnz, 3, 3))
    V = pat.vector(blocks)
    ref = sp.bsr_matrix((blocks, pat.indices, pat.indptr), shape=(600, 600)).tocsr()
    for a in ("indptr", "indices", "data"):
        np.testing.assert_array_equal(getattr(V, a), getattr(ref, a))
        assert getattr(V, a).dtype == getattr(ref, a).dtype
    assert V.has_sorted_indices
    Mv = pat.vector_from_scalar(S.data)
    kr = sp.kron(S, sp.identity(3), format="csr")
    kr.sort_indices()
    for a in ("indptr", "indices", "data"):
        np.testing.assert_array_equal(getattr(Mv, a), getattr(kr, a))
    assert Mv.indices.dtype == np.int32 and Mv.indptr.dtype == np.int32


@pytest.mark.skipif(not E.have_pardiso(), reason="pypardiso not installed")
def test_threaded_solvers_give_the_serial_frequencies(monkeypatch):
    """Both eigen-solvers with the threaded products (thresholds off, so this small model uses
    them) against one thread: the block solver's products are bit-identical, so its eigenvalues
    are; the mixed solver's dense products differ by round-off, so its frequencies agree far below
    the 1e-8 the solvers guarantee (their Kato-Temple bounds are 1e-11 on the eigenvalues)."""
    b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(1), "hex-s2")
    K, M = ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"]).free_matrices()
    monkeypatch.setattr(E, "MATMAT_MIN_WORK", 0)
    res = {}
    for t in (1, 2):
        monkeypatch.setattr(E, "matmat_threads", lambda t=t: t)
        res[t] = (E.shift_invert_eigsh(K, M, 8, sigma=0.0, method="block").eigenvalues,
                  E.shift_invert_eigsh(K, M, 8, sigma=0.0, method="mixed"))
    np.testing.assert_array_equal(res[1][0], res[2][0])
    assert res[2][1].method == "mixed"
    np.testing.assert_allclose(np.sqrt(res[2][1].eigenvalues), np.sqrt(res[1][1].eigenvalues), rtol=1e-10)


def test_free_matrices_in_two_threads_equal_the_serial_ones(monkeypatch):
    from probedyn.fem import model as fm

    b = cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(1), "hex-s2")
    got = {}
    for t in (1, 2):
        monkeypatch.setattr(fm, "matmat_threads", lambda t=t: t)
        monkeypatch.setattr(fm, "FREE_THREADS_MIN_NNZ", 0)
        got[t] = ElasticModel(b, {"body": get_material("silicon")}, clamp=["clamp"]).free_matrices()
    for A, B in zip(got[1], got[2]):
        for a in ("indptr", "indices", "data"):
            np.testing.assert_array_equal(getattr(A, a), getattr(B, a))
            assert getattr(A, a).dtype == getattr(B, a).dtype
        assert A.has_canonical_format and B.has_canonical_format
