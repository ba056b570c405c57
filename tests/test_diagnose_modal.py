"""The modal diagnosis' model-form floor (probedyn/diagnose/modal.py) against independent references.

* The FEM's shear-energy share of each mode (the direction of the shear-modulus nuisance) against
  Timoshenko beam theory (``probedyn.lumped.beam``, Cowper's kappa): ``d ln f / d ln (kappa G)``
  of the beam must equal half the FEM's share. Tolerance 25 %: Cowper's kappa differs from the
  effective shear coefficient of a 3D rectangle with w/t = 2 by up to ~10 %, and the clamp's 3D
  boundary layer adds shear energy of relative size ~ t / (half wavelength) (7-15 % for modes
  2-4 of a lever with L/t = 15). Mode 1 is not compared: its beam shear share (0.5 %) is smaller
  than the boundary layer's.
* The profiled model-form amplitudes use the fitted (training) modes only, never leave their
  bounds, and their prior pseudo-residuals are never held out.
* A noise-only measurement from the Timoshenko beam (another model form of the same lever) is
  not explained by a catalog cause (issue 11: the plate/shear model-form difference, 0.5-0.8 %
  on lever C, is 5-8 times the stated noise).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_truth import E_SI, LEVERS, NU_SI, RHO_SI, make_modal_case  # noqa: E402

from probedyn.diagnose.engine import diagnose, folds_of  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.modal import MF_BOUND, ModalProblem  # noqa: E402
from probedyn.diagnose.modal_model import FEMBaseline  # noqa: E402
from probedyn.lumped import beam as bm  # noqa: E402
from probedyn.probes import get_probe  # noqa: E402


@pytest.fixture(scope="module")
def base_C():
    probe = get_probe("cantilever")[0]
    return FEMBaseline(probe, probe.resolve(dict(LEVERS["C"])), {"flapwise": 4, "lateral": 1, "torsion": 1})


def test_shear_share_matches_timoshenko(base_C):
    g = LEVERS["C"]
    k0 = bm.cowper_kappa(NU_SI)

    def freqs(kappa, fam, n):
        return bm.timoshenko_frequencies(bm.RectBeam(g["length"], g["width"], g["thickness"], E_SI, NU_SI, RHO_SI,
                                                     kappa=kappa), fam, n)

    for fam, orders in (("flapwise", (2, 3, 4)), ("lateral", (1,))):
        n = max(orders)
        sens = np.log(freqs(1.01 * k0, fam, n) / freqs(k0, fam, n)) / np.log(1.01)
        for o in orders:
            fem = 0.5 * base_C.shear_share[base_C.index(fam, o)]
            assert 0.8 < fem / sens[o - 1] < 1.25, (fam, o, fem, sens[o - 1])


def test_model_form_floor_on_a_timoshenko_null(tmp_path, base_C):
    path, _ = make_modal_case(tmp_path, 7002, None, "C", truth_kind="timoshenko")
    prob = ModalProblem(read_measurement(path), bases={None: base_C})
    n = prob.n
    # the two prior pseudo-residuals are the last entries and belong to no fold
    assert list(prob.groups[-2:]) == [-1, -1]
    for fold in folds_of(prob.groups):
        assert not np.any(fold >= len(prob.groups) - 2)
    vals = {p.name: p.null for p in prob.base_params}
    f, _ = prob.predict(vals)
    r = (prob.data.freq - f) / prob.sigma_f
    a_all = prob.model_form(r, f)
    assert np.all(np.abs(a_all) <= MF_BOUND)
    # with mode 0 held out, its datum does not move the profile
    mask = np.ones(len(prob.groups), bool)
    mask[0] = False
    prob.train_mask = mask
    try:
        r2 = r.copy()
        r2[0] += 50.0
        assert np.allclose(prob.model_form(r, f), prob.model_form(r2, f))
        assert not np.allclose(prob.model_form(r, f), a_all)
    finally:
        prob.train_mask = None
    # a 100-sigma uniform shift is far outside the model-form range: the profile stops at its bound
    big = prob.model_form(r + 100.0 * (f / prob.sigma_f) * 1e-3 * 100, f)
    assert np.max(np.abs(big)) == pytest.approx(MF_BOUND)
    res = diagnose(prob)
    assert res["findings"] == [], (res["verdict"], res["findings"])
    assert res["verdict"] == "no-significant-discrepancy"
    assert n == 5


def test_reduced_model_reproduces_the_fem_on_a_very_thin_stretched_lever():
    """The aluminium beam of the worked example at 60 cm (L/t = 300, meshed ~14 times thicker and
    stretched back): the Ritz basis contains the FEM's modes, so the reduced model of the baseline
    state must return the FEM frequencies; tolerance 1e-4 relative (the basis is orthonormal in the
    energy norm K + lambda_1 M of condition ~1e12, round-off ~1e-16 x 1e12 in the worst shape
    direction, 1e-6 to 1e-5 in the frequencies). Before session 4 it returned 12.8 Hz for 4.60 Hz."""
    from probedyn.diagnose.modal import _probe_overrides
    from probedyn.diagnose.modal_model import ModalState, ReducedModal

    d = read_measurement(Path(__file__).resolve().parents[1] / "examples" / "measurements"
                         / "al_cantilever_length_sweep.toml")
    vals = dict(d.probe_values, length=0.6)
    b = FEMBaseline(d.probe, d.probe.resolve(_probe_overrides(d.probe, vals)), {"flapwise": 2}, estimate_error=False)
    assert b.stretch > 5
    red = ReducedModal(b)
    s = ModalState(axes={"length": b.length_axis, "width": b.width_axis, "thickness": b.thickness_axis}, length=b.L)
    need = [("flapwise", 1), ("flapwise", 2), ("lateral", 1)]
    f, _ = red.solve(s, need)
    ref = np.array([b.freqs[b.index(fa, o)] for fa, o in need])
    assert np.allclose(f, ref, rtol=1e-4), (f, ref)
