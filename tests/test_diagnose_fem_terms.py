"""The stiffness projected on a basis and split by derivative directions
(:func:`probedyn.diagnose.fem_terms.reduced_stiffness_split`), against the assembled FEM stiffness.

``Ks[j, l] = int (d_j Phi)^T C (d_l Phi) dV`` sums to ``Phi^T K Phi`` when integrated with the assembly's own
rule (3 x 3 x 3 points on the serendipity hexahedra, ``intorder=5``), to rounding, on any basis; with the default
2 x 2 x 2 rule exactly on displacement fields of degree <= 2 (strains linear: the rule is exact for the cubic
integrands), not on rough fields. ``Ks[j, l] = Ks[l, j]^T`` (``C`` symmetric). A positive definite ``C`` takes
the factored path (one symmetric product), any other the six-block path: a negated material gives exactly
the negated split.
"""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.diagnose.fem_terms import reduced_stiffness_split
from probedyn.diagnose.modal_model import _StiffnessPart, build_within_budget
from probedyn.probes import get_probe


@pytest.fixture(scope="module")
def model():
    probe = get_probe("cantilever")[0]
    values = probe.resolve({"length": 120e-6, "width": 30e-6, "thickness": 4e-6})
    m = build_within_budget(probe, values, 1.0)
    assert str(m.bundle.element).startswith("hex")  # the default mesh: the case where the rules differ
    return m


def _quadratic_fields(model) -> np.ndarray:
    """Displacement fields of degree <= 2 in the coordinates (bending, twist, stretch, shear), at the DOFs."""
    x, y, z = (c / np.ptp(c) for c in model.basis.doflocs)
    cols = []
    for f in (x**2, x * y, y * z, x * z, z**2, x, y):
        for comp in range(3):
            u = np.zeros((model.n_nodes, 3))
            u[:, comp] = f
            cols.append(u.ravel())
    return np.column_stack(cols)


def test_the_split_sums_to_the_projected_stiffness(model):
    K, _ = model.assemble()
    Phi = np.random.default_rng(3).standard_normal((3 * model.n_nodes, 7))  # rough: every element's own shapes
    Kr = Phi.T @ (K @ Phi)
    Ks, G = reduced_stiffness_split(model, Phi, chunk=97, intorder=5)  # several chunks
    assert np.abs(Ks.sum(axis=(0, 1)) - Kr).max() <= 1e-10 * np.abs(Kr).max()
    assert np.allclose(Ks, Ks.transpose(1, 0, 3, 2), rtol=0, atol=1e-12 * np.abs(Ks).max())
    assert np.all(np.linalg.eigvalsh(G) > -1e-12 * np.abs(G).max())  # sums of squares
    # the default (reduced) rule: wrong on rough fields, exact on fields of degree <= 2
    Ks2, _ = reduced_stiffness_split(model, Phi)
    assert np.abs(Ks2.sum(axis=(0, 1)) - Kr).max() > 1e-3 * np.abs(Kr).max()
    Q = _quadratic_fields(model)
    Kq = Q.T @ (K @ Q)
    assert np.abs(reduced_stiffness_split(model, Q)[0].sum(axis=(0, 1)) - Kq).max() <= 1e-10 * np.abs(Kq).max()


def test_an_indefinite_material_takes_the_six_block_path_with_the_same_result(model):
    Phi = np.random.default_rng(4).standard_normal((3 * model.n_nodes, 5))
    Ks, _ = reduced_stiffness_split(model, Phi, chunk=97)
    neg = [_StiffnessPart(-np.asarray(mat.C)) for mat in model.materials]  # negative definite: no Cholesky factor
    Ks_neg, _ = reduced_stiffness_split(model, Phi, chunk=97, materials=neg)
    assert np.abs(Ks_neg + Ks).max() <= 1e-12 * np.abs(Ks).max()
