"""An extension of a claimed cause is held to the plain held-out error (engine ``_evidence``, module
docstring step 6; problems with ``heldout_predictive``: modal and spectra).

The predictive held-out density forgives a parameter that only the held-out group informs
(``tests/test_diagnose_heldout.py``). Against the baseline that is right: the baseline's model error
is in the noise model (discretisation, model form). After a claimed cause it is not: that cause's own
model error has no stated size, and a second cause whose folds predict their held-out groups worse
than the chain without it -- forgiven only by its own parameter spread -- is not separable from that
error. Session 14's predictive score claimed such second causes on single-effect truths (modal 1008,
1015; spectra 3008, 3039: plain held-out evidence -400, -50, -870, -31 nats, predictive +34, +22,
+115, +25).
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from probedyn.diagnose.causes import Cause, CauseParam
from probedyn.diagnose.engine import Fit, _evidence


def _cause(key: str) -> Cause:
    cls = type(f"_{key.title()}", (Cause,), {"key": key, "kind": "toy",
                                             "params": (CauseParam(key, "1", -1.0, 1.0, 0.0, key),),
                                             "effect": lambda self, values, state: None})
    return cls()


A, B = _cause("a"), _cause("b")


def _fit(causes, cv_r, cv_fold, chi2):
    f = Fit(causes=causes, plist=[c.params[0] for c in causes], u=np.zeros(len(causes)), values={}, r=np.zeros(4),
            chi2=chi2, n=4)
    f.cv_r, f.cv_fold = np.asarray(cv_r, float), np.asarray(cv_fold, float)
    f.cv = float(np.sum(f.cv_fold))
    return f


def _cv(predictive: bool):
    """The engine's CrossValidation as _evidence uses it, with the folds already scored."""
    return SimpleNamespace(F=SimpleNamespace(problem=SimpleNamespace(heldout_predictive=predictive)),
                           winning_start={}, full_fits={}, heldout=lambda fit: None)


# held-out residuals of the chain and of chain + cause (one group per fold) and their predictive scores:
# the cause's fold predictions are worse (plain e^T e 3 + 36 = 39 -> 3 + 100 = 103), but its parameter
# spread forgives them (predictive 40 -> 20)
REF = dict(cv_r=[1.0, 1.0, 1.0, 6.0], cv_fold=[1.0, 1.0, 1.0, 37.0])
EXT = dict(cv_r=[1.0, 1.0, 1.0, 10.0], cv_fold=[1.0, 1.0, 1.0, 17.0])


def test_an_extension_takes_the_lower_of_the_predictive_and_the_plain_heldout_evidence():
    ref = _fit((A,), chi2=50.0, **REF)
    d = {"cause": B, "fit": _fit((A, B), chi2=20.0, **EXT), "k": 1, "dchi2": 30.0}
    _evidence(d, ref, _cv(True), True)
    assert d["evidence_cv"] == pytest.approx(0.5 * (40.0 - 20.0))  # predictive: +10 nats
    assert d["evidence_plain"] == pytest.approx(0.5 * (39.0 - 103.0))  # plain: -32 nats
    assert d["evidence"] == pytest.approx(-32.0)  # not claimed (evidence <= 0)
    # where the plain error agrees, the capped predictive evidence stands
    d2 = {"cause": B, "fit": _fit((A, B), chi2=20.0, cv_r=[1.0, 1.0, 1.0, 2.0], cv_fold=[1.0, 1.0, 1.0, 17.0]),
          "k": 1, "dchi2": 30.0}
    _evidence(d2, ref, _cv(True), True)
    assert d2["evidence"] == pytest.approx(10.0) and d2["evidence_plain"] == pytest.approx(0.5 * (39.0 - 7.0))


def test_the_first_cause_and_non_predictive_problems_keep_their_score():
    # against the baseline (no claimed cause) the predictive score stands alone
    base = _fit((), chi2=50.0, **REF)
    d = {"cause": A, "fit": _fit((A,), chi2=20.0, **EXT), "k": 1, "dchi2": 30.0}
    _evidence(d, base, _cv(True), True)
    assert d["evidence"] == pytest.approx(10.0) and "evidence_plain" not in d
    # friction and force curves score e^T e already: nothing changes
    ref = _fit((A,), chi2=50.0, **REF)
    d = {"cause": B, "fit": _fit((A, B), chi2=20.0, **EXT), "k": 1, "dchi2": 30.0}
    _evidence(d, ref, _cv(False), True)
    assert d["evidence"] == pytest.approx(10.0) and "evidence_plain" not in d


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="known since before session 33 (failing on b215658 too): a second cause (thickness "
                   "error, or a point mass) absorbs the difference between the truth's uniform-beam fluid loading and the "
                   "diagnosis' 3D Rayleigh loading of lever B's higher flapwise modes, which a declared fluid carries as "
                   "model form (session 33) but a fitted one does not; docs/diagnose.md section 8")
def test_a_fluid_loaded_lever_is_fluid_loading_alone():
    """Seed 1015 of the modal rate study (lever B, 100 x 40 x 10 um, in ethanol, medium not declared;
    truth: probedyn's FEM on a finer mesh plus the test module's own uniform-beam Sader relation). The
    fluid model here (Rayleigh quotient with the FEM mode shape) and the truth's differ by ~1 % of the
    fluid shift (residual chi^2 48 for 10 dof after the fluid cause); a thickness error then took
    Delta chi^2 30 by trading against the fluid density (rho_f 805 -> 1046 kg/m^3, truth 789) and its
    predictive held-out evidence was +22 nats, the plain held-out -50: it is no longer a finding."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import tempfile

    from diagnose_truth import make_modal_case

    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.modal import ModalProblem

    with tempfile.TemporaryDirectory() as tmp:
        path, truth = make_modal_case(Path(tmp), 1015, "fluid-loading", "B", truth_kind="fem", declared_medium=None)
        res = diagnose(ModalProblem(read_measurement(path)))
    assert [f["cause"] for f in res["findings"]] == ["fluid-loading"]
    rho = res["findings"][0]["parameters"]["rho_f"]
    assert abs(rho["value"] - truth["params"]["rho_f"]) < 0.05 * truth["params"]["rho_f"]  # ethanol, 789 kg/m^3
