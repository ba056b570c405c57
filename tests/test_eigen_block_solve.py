"""A factorisation solves a block of right-hand sides exactly as it solves each column."""

import numpy as np
import scipy.sparse as sp

from probedyn.fem.eigen import factorize


def test_block_solve_equals_column_solves():
    n = 300
    A = sp.random(n, n, density=0.03, random_state=3)
    A = (A + A.T + 30.0 * sp.eye(n)).tocsr()  # symmetric positive definite (diagonally dominant)
    B = np.random.default_rng(1).standard_normal((n, 7))
    F = factorize(A)
    X = F.solve(B)
    cols = np.column_stack([F.solve(B[:, j]) for j in range(B.shape[1])])
    # both are backward-stable solves of a well-conditioned system: residuals at round-off
    assert np.abs(A @ X - B).max() < 1e-10
    assert np.allclose(X, cols, rtol=1e-12, atol=1e-13)
