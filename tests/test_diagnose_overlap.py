"""A lever bonded to its chip over an overlap (``bonded-overlap``, :mod:`probedyn.diagnose.overlap`).

Checks, each against an independent reference:

* the bonded segment on a normal bond is Hetenyi's semi-infinite beam on a Winkler foundation (closed-form
  root compliances) when the overlap is long, and converges to it under refinement;
* a stiff bond is a clamp ``1/beta`` further back: every flapwise mode drops by ~``2 lam_n``, linearly, and the
  model tends to the baseline's rigid clamp;
* the Ritz reduction (segment condensed on the clamp face's rigid motion) equals the full FEM re-solve (every
  segment DOF kept), also in a stretched geometry, and so do the static end stiffnesses;
* the signature that separates it from a compliant clamp face: a thin isotropic bond lowers the lateral mode
  several times more than the flapwise ones, the face support less;
* a 3D truth with the bond meshed (springs on the overlap's bottom face of a lever meshed through the
  overlap; ``tests/diagnose_truth.py``) is diagnosed as the bonded overlap.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from probedyn.diagnose.modal_model import (LAMBDA_MIN, FEMBaseline, ModalState, ReducedModal, full_solve,  # noqa: E402
                                           full_static_stiffness)
from probedyn.diagnose.overlap import bond_stiffness, hetenyi_root_compliance, segment_matrices  # noqa: E402
from probedyn.probes import get_probe  # noqa: E402

E, NU, RHO = 169e9, 0.28, 2330.0
NEEDED = [("flapwise", 1), ("flapwise", 2), ("flapwise", 3), ("flapwise", 4), ("lateral", 1), ("torsion", 1)]


@pytest.fixture(scope="module")
def lever_a():
    probe = get_probe("cantilever")[0]
    b = FEMBaseline(probe, probe.resolve(dict(length=300e-6, width=30e-6, thickness=10e-6)),
                    {"flapwise": 4, "lateral": 1, "torsion": 1}, estimate_error=False)
    return b, ReducedModal(b)


@pytest.mark.parametrize("lam", [1e-3, 1e-2])
def test_segment_is_hetenyis_semi_infinite_beam(lam):
    """Overlap 0.3 L >= 30 Winkler lengths: the segment's root compliances (w/P, theta/M, w/M) equal Hetenyi's
    closed forms; the cubic elements converge to them (the default mesh within 5e-4, twice the elements within
    1e-4)."""
    b, t, L = 30e-6, 10e-6, 300e-6
    kn = bond_stiffness(lam, E, t, L)
    H = hetenyi_root_compliance(E, b, t, kn)
    errs = []
    for n_el in (8, 16, 32):
        K, _ = segment_matrices(E, NU, RHO, b, t, 0.3 * L, kn, kn * 1e-9, n_el=n_el)
        C = np.linalg.inv(K)[np.ix_([2, 4], [2, 4])]
        errs.append(max(abs(C[0, 0] / H[0, 0] - 1), abs(C[1, 1] / H[1, 1] - 1), abs(abs(C[0, 1] / H[0, 1]) - 1)))
    assert errs[1] < 5e-4 and errs[2] < min(errs[1], 1e-4) and errs[0] > errs[1], errs
    # the root rotation compliance is lam L / EI: the bond length is the clamp's set-back
    K, _ = segment_matrices(E, NU, RHO, b, t, 0.3 * L, kn, kn * 1e-9)
    assert np.linalg.inv(K)[4, 4] * E * b * t**3 / 12 / L == pytest.approx(lam, rel=1e-3)


def test_stiff_bond_is_a_clamp_further_back(lever_a):
    """A normal bond of lam_n = 0.01 and 0.03 (a soft shear bond, lam_t = 1): every flapwise mode drops by
    2 lam_n (1 +- 5 %) -- Hetenyi's root rotation compliance lam L / EI is a clamp lam L further back,
    ``f ~ 1 / L^2`` -- nearly linearly in lam_n; a shear bond as stiff as the normal one holds the root's
    rotation too (the bonded face's axial slip ``t w' / 2``): the drop is then smaller. At the smallest bond
    lengths the model is the rigid clamp within 3 LAMBDA_MIN."""
    b, red = lever_a
    f0, _ = red.solve(ModalState(), NEEDED)
    shifts = {}
    for lam in (0.01, 0.03):
        f, _ = red.solve(ModalState(overlap=(lam, 1.0, 0.3)), NEEDED)
        shifts[lam] = f[:4] / f0[:4] - 1
        assert np.all(np.abs(shifts[lam] / (-2 * lam) - 1) < 0.05), shifts[lam]
        f, _ = red.solve(ModalState(overlap=(lam, lam, 0.3)), NEEDED)
        assert np.all(f[:4] / f0[:4] - 1 > shifts[lam]), (f / f0 - 1, shifts[lam])
    assert np.allclose(shifts[0.03] / shifts[0.01], 3.0, rtol=0.05)
    f, _ = red.solve(ModalState(overlap=(1.01 * LAMBDA_MIN, 1.01 * LAMBDA_MIN, 0.3)), NEEDED)
    assert np.all(np.abs(f / f0 - 1) < 3 * LAMBDA_MIN)


@pytest.mark.parametrize("scale", [(1.0, 1.0, 1.0), (1.0, 1.05, 0.97)])
def test_reduced_equals_full_resolve(lever_a, scale):
    """The Ritz model (segment condensed on the face's rigid motion) against the full FEM with every segment
    DOF (``_BondedSystem``): frequencies within 2e-4 (the stretch reduction's own error is 1.1e-4 on flapwise 4),
    static end stiffness within 1e-5."""
    b, red = lever_a
    s = ModalState(overlap=(0.01, 0.03, 0.2), scale=np.array(scale))
    f, _ = red.solve(s, NEEDED)
    ff, _, info = full_solve(b, s, NEEDED)
    assert np.all(np.abs(f / ff - 1) < 2e-4), f / ff - 1
    if scale == (1.0, 1.0, 1.0):
        assert red.static_stiffness(s) / full_static_stiffness(b, s) == pytest.approx(1.0, abs=1e-5)


def test_bond_lowers_lateral_more_than_a_face_support(lever_a):
    """At the same flapwise 1 shift (-1.6 %), a thin isotropic bond (nu = 0.45: k_t / k_n = 0.09, lam_t =
    lam_n (k_n / k_t)^(1/4)) lowers lateral 1 more than flapwise 1 (1.9x; 1.4x at nu = 0.3, 3.2x at 0.49), a
    compliant clamp face (normal springs only) less: the two supports do not imitate each other."""
    b, red = lever_a
    f0, _ = red.solve(ModalState(), NEEDED)
    ratio = (2 * (1 - 0.45) / (1 - 2 * 0.45)) ** 0.25
    f_b, _ = red.solve(ModalState(overlap=(0.01, 0.01 * ratio, 0.3)), NEEDED)
    d_b = f_b / f0 - 1
    c = 0.0
    for _ in range(30):  # the face's rotation compliance with the same flapwise 1 shift (secant on c)
        f_c, _ = red.solve(ModalState(clamp=(max(c, 1e-7), 0.0)), NEEDED)
        g = f_c[0] / f0[0] - 1 - d_b[0]
        if abs(g) < 1e-6:
            break
        c = c - g / 0.5 if c == 0.0 else c * (d_b[0] / (f_c[0] / f0[0] - 1))
    d_c = f_c / f0 - 1
    assert d_b[4] / d_b[0] > 1.5, d_b
    assert d_c[4] / d_c[0] < 1.0, d_c


@pytest.mark.parametrize("seed,lever", [
    (9510, {"length": 150e-6, "width": 50e-6, "thickness": 8e-6}),
    pytest.param(9511, {"length": 250e-6, "width": 40e-6, "thickness": 6e-6}, marks=pytest.mark.slow),
    pytest.param(9500, "A", marks=pytest.mark.slow), pytest.param(9501, "B", marks=pytest.mark.slow)])
def test_a_bonded_lever_is_diagnosed_as_such(tmp_path, seed, lever):
    """The 3D truth (lever meshed through the overlap, springs on its bottom face; a glue layer drawn by
    ``draw_modal_effect``) with 1e-3 frequency noise: the bonded overlap is named first, its flapwise bond
    length within 2x of the truth's (the rate study's median error is 10 %: the segment is a beam, the truth
    3D; lam_n trades against the overlap length) and its shear bond softer than its normal one."""
    from diagnose_truth import make_modal_case

    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.modal import ModalProblem

    path, truth = make_modal_case(tmp_path, seed, "bonded-overlap", lever)
    res = diagnose(ModalProblem(read_measurement(path)))
    assert res["findings"] and res["findings"][0]["cause"] == "bonded-overlap", res["verdict"]
    p = {k: v["value"] for k, v in res["findings"][0]["parameters"].items()}
    assert 0.5 < p["lam_n"] / truth["params"]["lam_n"] < 2.0, p
    assert p["lam_t"] > p["lam_n"], p
