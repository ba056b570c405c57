"""Force curves and spectra as instruments record them (truths: tests/diagnose_truth_curves.py).

Default run: one hidden adhesion law, a deflection drift, a conical tip and a piezo hysteresis on force
curves (nested fits from the baseline optimum: the cause recovers its parameter), the parsimony rule between
nested adhesion laws, and a thermal spectrum of the probe's FEM modes
with an electronic spur (class 6: the spur is rejected and reported, the modes identified). The
rate study over 50 + 50 curves is ``benchmarks/diagnose_rates_curves.py`` (slow test below).
"""

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_truth_curves import make_curve_case, make_fem_spectrum_case  # noqa: E402

from probedyn.diagnose.engine import Fitter  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.problems import make_problem  # noqa: E402
from probedyn.diagnose.spectrum import spectrum_problem  # noqa: E402


def _nested(path, key):
    prob = make_problem(path)
    F = Fitter(prob)
    base = F.baseline()
    cause = next(c for c in prob.causes if c.key == key)
    return prob, base, F.nested(base, (cause,))


def _chi2_bound(n):  # a fit consistent with the noise: chi2 below n + 4 standard deviations of chi2_n
    return n + 4.0 * math.sqrt(2.0 * n)


def test_force_curve_jkr_recovered_from_instrument_record(tmp_path):
    """JKR truth (registry law, continuation with snap-in and pull-off, deflection as recorded): the
    nested JKR fit reaches the noise and recovers W to the pull-off's noise-limited accuracy."""
    path, truth = make_curve_case(tmp_path, 6, "adhesion-jkr")
    prob, base, fit = _nested(path, "adhesion-jkr")
    assert base.chi2 > _chi2_bound(base.n)  # the baseline (Hertz) cannot explain the adhesion
    assert fit.chi2 < _chi2_bound(fit.n)
    W = truth["params"]["W"]
    # W is read mostly from the pull-off 3/2 pi W R: 5 noise levels of it, plus 2 % for the law's
    # discretisation in the diagnosis (polylines refined by Newton steps)
    tol = 0.02 + 5 * truth["noise"] / (1.5 * math.pi * W * truth["R_nom"])
    assert abs(fit.values["W"] / W - 1) < tol


def test_force_curve_drift_separated_from_tilt(tmp_path):
    """A drift of the deflection in time (not in z) is recovered besides the calibrated tilt."""
    path, truth = make_curve_case(tmp_path, 5, "deflection-drift")
    prob, base, fit = _nested(path, "deflection-drift")
    assert fit.chi2 < _chi2_bound(fit.n) < base.chi2
    n = prob.n
    # least squares on tau in [-1/2, 1/2]: sigma_d = sigma sqrt(12 / n); x2 for its correlation with the tilt
    tol = 5 * 2 * truth["noise"] * math.sqrt(12.0 / n)
    assert abs(fit.values["drift"] - truth["params"]["drift"]) < tol


def test_force_curve_cone_tip_recovered(tmp_path):
    """A soft sample indented by a blunted cone (the registry's ``cone`` law, truth by bisection on the
    monotone lever equation) deeper than its cap: the Hertz baseline fails, the nested tip-shape fit
    reaches the noise and recovers the half-angle within 5 of its own standard deviations (the law
    is evaluated exactly, so the noise is the only error)."""
    from probedyn.diagnose.engine import parameter_report

    path, truth = make_curve_case(tmp_path, 2006, "tip-shape")
    prob, base, fit = _nested(path, "tip-shape")
    assert base.chi2 > _chi2_bound(base.n)
    assert fit.chi2 < _chi2_bound(fit.n)
    rep = parameter_report(Fitter(prob), fit, ["alpha"])["alpha"]
    assert abs(fit.values["alpha"] - truth["params"]["alpha"]) < 5 * rep["sigma"]


def test_a_single_strong_direction_is_claimed_when_the_noise_is_declared(tmp_path):
    """The targeted route (docs/diagnose.md 9.30). Rate-study seed 2046: a blunted cone (alpha 19 deg) on a stiff
    sample, noise declared. The Hertz baseline's chi-square over 600 points passes (p 0.10: the omnibus test has
    little power against one direction among 600), while the cone's likelihood-ratio test passes by far (Delta
    chi2 ~ 48 against chi2_1(1 - alpha / N) ~ 11; the noise-free record's own gain is 39). With the noise
    declared the likelihood is complete (the contact branch is solved exactly), so that test alone shows the
    discrepancy and the cone is named, its half-angle within 5 of its sigma; read from the record the noise's
    model is a guess and the route stays closed (a problem property: an unstated flicker null passes such tests)."""
    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.forcecurve import ForceCurveProblem

    path, truth = make_curve_case(tmp_path, 2046, "tip-shape")
    meas = read_measurement(path)
    assert meas.noise_stated and ForceCurveProblem(meas).model_error_in_likelihood
    assert not ForceCurveProblem(replace(meas, noise_stated=False)).model_error_in_likelihood
    res = diagnose(make_problem(path))
    assert res["baseline"]["p_value"] > 0.01 and res["baseline"]["targeted_test"] == ["tip-shape"]
    assert [f["cause"] for f in res["findings"]] == ["tip-shape"] and res["verdict"] == "explained", res["verdict_reasons"]
    a = res["findings"][0]["parameters"]["alpha"]
    assert abs(a["value"] - truth["params"]["alpha"]) < 5 * a["sigma"]


def test_force_curve_piezo_hysteresis_recovered(tmp_path):
    """The retract's true piezo position offset by dz from the recorded one (truth: the continuation
    on the shifted positions): the nested piezo-hysteresis fit reaches the noise and recovers dz within
    5 of its own standard deviations."""
    from probedyn.diagnose.engine import parameter_report

    path, truth = make_curve_case(tmp_path, 2015, "piezo-hysteresis")
    prob, base, fit = _nested(path, "piezo-hysteresis")
    assert fit.chi2 < _chi2_bound(fit.n) < base.chi2
    rep = parameter_report(Fitter(prob), fit, ["dz"])["dz"]
    assert abs(fit.values["dz"] - truth["params"]["dz"]) < 5 * rep["sigma"]


def test_force_curve_hydrodynamic_drag_recovered(tmp_path):
    """A fast ramp in water (truth: the drag law of Alcaraz et al. 2002 at the piezo velocity, written in the
    generator): the baseline fails (approach and retract baselines split by ``b (v_a + v_r)``), the nested
    hydrodynamic-drag fit reaches the noise and recovers the drag coefficient at contact within 5 of its own
    standard deviations; the piezo velocity the problem derives from the record's times is the ramp's."""
    from probedyn.diagnose.engine import parameter_report

    path, truth = make_curve_case(tmp_path, 2202, "hydrodynamic-drag")
    prob, base, fit = _nested(path, "hydrodynamic-drag")
    v = truth["params"]["velocity"]
    seg = prob.data.segment
    assert np.allclose(prob.velocity, np.where(seg == 0, v, -v), rtol=1e-6)
    assert fit.chi2 < _chi2_bound(fit.n) < base.chi2
    rep = parameter_report(Fitter(prob), fit, ["b_drag"])["b_drag"]
    assert abs(fit.values["b_drag"] - truth["params"]["b_drag"]) < 5 * rep["sigma"]


def test_force_curve_drag_needs_times_and_a_fluid(tmp_path):
    """No velocity without a time column, no fluid in a declared vacuum: the drag is then not offered (and
    the problem says why when the column is missing)."""
    path, _ = make_curve_case(tmp_path, 2202, "hydrodynamic-drag")
    csv = path.with_suffix(".csv")
    lines = csv.read_text().splitlines()
    csv.write_text("\n".join(",".join(x.split(",")[:3]) for x in lines) + "\n")  # drop time_s
    prob = make_problem(path)
    assert "hydrodynamic-drag" not in [c.key for c in prob.causes]
    assert "time_s" in prob.not_offered["hydrodynamic-drag"]
    path, _ = make_curve_case(tmp_path, 2202, "hydrodynamic-drag")
    path.write_text(path.read_text().replace('name = "water"', 'name = "vacuum"') if "[medium]" in path.read_text()
                    else path.read_text() + '\n[medium]\nname = "vacuum"\n')
    assert "hydrodynamic-drag" not in [c.key for c in make_problem(path).causes]


def test_force_curve_optical_interference_recovered(tmp_path):
    """The optical lever's interference (truth: ``A cos(4 pi s cos(theta) / lambda + phi)`` with an AFM
    laser's wavelength over a 0.4-1.5 um baseline): the periodogram start finds the period, the nested fit
    reaches the noise and recovers the period and the amplitude within 5 of their own standard deviations."""
    from probedyn.diagnose.engine import parameter_report

    path, truth = make_curve_case(tmp_path, 2201, "optical-interference")
    prob, base, fit = _nested(path, "optical-interference")
    assert fit.chi2 < _chi2_bound(fit.n) < base.chi2
    rep = parameter_report(Fitter(prob), fit, ["period"])["period"]
    assert abs(fit.values["period"] - truth["params"]["period"]) < 5 * rep["sigma"]
    amp = math.hypot(fit.values["a_c"], fit.values["a_s"])
    # each quadrature's least-squares error is sigma sqrt(2 / n_far); the far baseline is most of the record
    assert abs(amp - truth["params"]["amplitude"]) < 5 * truth["noise"] * math.sqrt(2.0 / (0.5 * prob.n))


def test_parsimony_prefers_the_contained_limit():
    """Occam between nested causes (engine._parsimony): Maugis-Dugdale (contains JKR and DMT as lambda
    limits) within the margin of JKR does not lead and is not a confounded rival; beyond the margin it
    leads; a rival that is not nested is left alone."""
    from probedyn.diagnose.causes.adhesion import AdhesionJKR, AdhesionMD
    from probedyn.diagnose.causes.deflection_drift import DeflectionDrift
    from probedyn.diagnose.engine import EVIDENCE_MARGIN, _parsimony

    class _F:
        values = {"W": 0.1, "lam": 10.0}

    def row(c, ev, dchi2=300.0):
        return {"cause": c(), "evidence": ev, "fit": _F(), "dchi2": dchi2, "k": len(c.params)}

    claimed = [row(AdhesionMD, 100.0), row(AdhesionJKR, 100.0 - 0.9 * EVIDENCE_MARGIN, 290.0)]
    note = _parsimony(claimed, EVIDENCE_MARGIN)
    assert claimed[0]["cause"].key == "adhesion-jkr" and claimed[1].get("contains_leader")
    assert note["container"] == "adhesion-md" and note["contains_leader"]
    # evidence beyond the margin but lambda not supported in sample (Delta chi2 below the boundary test's
    # threshold chi2_1(1 - 2 alpha) = 5.41: JKR is MD on the edge of lambda's range, engine.boundary_lr_threshold)
    claimed = [row(AdhesionMD, 100.0), row(AdhesionJKR, 100.0 - 10 * EVIDENCE_MARGIN, 300.0 - 5.0)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is not None and claimed[0]["cause"].key == "adhesion-jkr"
    # ... and supported above it, also below chi2_1(0.99) = 6.63, the threshold of an interior null (seed 2010:
    # an MD truth at lambda 1.0, 6.07 of chi^2 better than JKR, was named JKR with that threshold)
    claimed = [row(AdhesionMD, 100.0), row(AdhesionJKR, 100.0 - 10 * EVIDENCE_MARGIN, 300.0 - 6.07)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and claimed[0]["cause"].key == "adhesion-md"
    claimed = [row(AdhesionMD, 100.0), row(AdhesionJKR, 100.0 - 1.1 * EVIDENCE_MARGIN, 300.0 - 7.0)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and claimed[0]["cause"].key == "adhesion-md"
    claimed = [row(AdhesionMD, 100.0), row(DeflectionDrift, 99.9)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and claimed[0]["cause"].key == "adhesion-md"
    # the same pair the other way round: JKR leads, Maugis-Dugdale within the margin behind it and 2.7 of chi^2
    # worse (seed 2049 under AR(1) noise: lambda at its bound) -- the container is JKR again, not a rival, as
    # when it leads by as much; and as there, also when lambda is supported in sample only (MD 7 of chi^2
    # better, above chi2_1(0.99) = 6.63, but behind JKR held out); beyond the margin the rule does not act
    for md_chi2 in (297.3, 307.0):
        claimed = [row(AdhesionJKR, 100.0, 300.0), row(AdhesionMD, 99.0, md_chi2)]
        assert _parsimony(claimed, EVIDENCE_MARGIN) is not None
        assert claimed[0]["cause"].key == "adhesion-jkr" and claimed[1].get("contains_leader")
    claimed = [row(AdhesionJKR, 100.0, 300.0), row(AdhesionMD, 100.0 - 1.1 * EVIDENCE_MARGIN, 307.0)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and not claimed[1].get("contains_leader")
    assert claimed[0]["cause"].key == "adhesion-jkr"
    # the container's limits: JKR nested (one parameter fewer) and unsupported; DMT (W and its tail's
    # range: as many parameters as MD) not nested, but the better Akaike score among the limits takes
    # the lead (Akaike DMT 150.25 - 2 = 148.25, JKR 148 - 1 = 147), whatever the held-out evidence; MD
    # is then a rival like any other (it does not contain DMT), JKR a sibling within the margin
    from probedyn.diagnose.causes.adhesion import AdhesionDMT

    claimed = [row(AdhesionMD, 100.0, 300.0), row(AdhesionJKR, 99.0, 296.0), row(AdhesionDMT, 97.0, 300.5)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is not None and claimed[0]["cause"].key == "adhesion-dmt"
    jkr = next(d for d in claimed if d["cause"].key == "adhesion-jkr")
    md = next(d for d in claimed if d["cause"].key == "adhesion-md")
    assert jkr.get("sibling_limit") and not md.get("contains_leader")
    # ... and the other limit stays a rival while its in-sample Akaike score is within the margin (held-out
    # evidence 9 nats behind: a JKR truth under AR(1) noise, seed 2001), not when it is beyond it
    claimed = [row(AdhesionMD, 59.6, 129.3), row(AdhesionDMT, 59.2, 132.2), row(AdhesionJKR, 50.2, 129.8)]
    _parsimony(claimed, EVIDENCE_MARGIN)
    assert claimed[0]["cause"].key == "adhesion-dmt" and claimed[2].get("sibling_limit")
    # the same when DMT leads held out and Maugis-Dugdale is within the margin behind it (a JKR truth under
    # AR(1) noise, seed 2001, session 42's numbers: DMT 0.67 nats ahead of JKR held out, 1.86 behind it by
    # Akaike): JKR leads, DMT a sibling within the margin, MD its container
    from probedyn.diagnose.causes.adhesion import AdhesionDMT as _DMT

    claimed = [row(_DMT, 55.75, 133.41), row(AdhesionJKR, 55.08, 135.15), row(AdhesionMD, 54.90, 135.49)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is not None
    assert [d["cause"].key for d in claimed] == ["adhesion-jkr", "adhesion-md", "adhesion-dmt"]
    assert claimed[1].get("contains_leader") and claimed[2].get("sibling_limit")
    # ... not when the container is beyond the margin behind the leader
    claimed = [row(_DMT, 60.0, 133.41), row(AdhesionJKR, 55.08, 135.15), row(AdhesionMD, 54.90, 135.49)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and claimed[0]["cause"].key == "adhesion-dmt"
    # a JKR nested and unsupported with the better Akaike score leads, MD hidden as its container
    claimed = [row(AdhesionMD, 100.0, 300.0), row(AdhesionJKR, 99.5, 299.0), row(AdhesionDMT, 95.0, 294.0)]
    _parsimony(claimed, EVIDENCE_MARGIN)
    assert claimed[0]["cause"].key == "adhesion-jkr" and claimed[1]["cause"].key == "adhesion-md"
    assert claimed[1].get("contains_leader") and not claimed[2].get("sibling_limit")  # DMT 1.5 + 2.5 = 4 behind
    # DMT alone next to MD (JKR's lambda supported): two alternatives of equal size, the rule does not act --
    # an MD truth (seed 2058, lambda 0.73) was otherwise handed to a DMT at its shortest tail
    claimed = [row(AdhesionMD, 100.0, 300.0), row(AdhesionDMT, 99.0, 300.0), row(AdhesionJKR, 90.0, 292.0)]
    assert _parsimony(claimed, EVIDENCE_MARGIN) is None and claimed[0]["cause"].key == "adhesion-md"


def test_the_summary_names_a_container_that_is_not_a_rival():
    """The text layer states the parsimony rule's outcome: a container that is the finding plus an unsupported
    parameter is named as such, and not when it stays a confounded rival."""
    from probedyn.report.diagnose import summary

    note = {"container": "adhesion-md", "container_evidence": 6510.5, "container_parameters": {"W": 0.0939, "lam": 10.0},
            "contains_leader": True}
    res = {"baseline": {"chi2": 1.4e4, "dof": 600, "p_value": 0.0, "residual_rms": 4.8}, "method": {},
           "verdict": "explained", "verdict_reasons": [], "confounded": [],
           "findings": [{"status": "explained", "cause": "adhesion-jkr", "parameters": {}, "evidence": 6511.9, "flags": [],
                         "gain": {"residual_rms_before": 4.8, "residual_rms_after": 1.0}, "parsimony": note}],
           "final": {"chi2": 600.0, "dof": 599, "p_value": 0.5, "residual_rms": 1.0}}
    assert "adhesion-md (W = 0.0939, lam = 10; evidence 6510.5 nats) contains it as a limit" in summary(res)
    res["confounded"] = [{"margin_nats": 2.3, "causes": ["adhesion-dmt", "adhesion-md"], "evidence": [1.0, 0.5],
                          "separating_measurements": [], "pairs_left_unseparated": []}]
    assert "contains it as a limit" not in summary(res)
    # nor when the rule handed the lead to a limit of the container's own size (DMT: MD's lambda is no extra)
    res["confounded"], note["contains_leader"] = [], False
    assert "contains it as a limit" not in summary(res)


def test_a_contained_limit_is_never_pruned_before_the_parsimony_rule():
    """engine._score_in_order: a cause whose evidence cap is below the winner's evidence minus the margin
    is not cross-validated, except a limit of a passing container, which the parsimony rule's LR arm can
    still hand the lead (seed 2067, when DMT's tail was held: DMT 4.7 behind Maugis-Dugdale in chi^2, below
    chi2_1(0.99) = 6.63, its cap 0.07 nats below the pruning line). The same numbers with the nested JKR
    end with JKR first; with DMT of MD's size (its tail's range fitted, session 26) the rule does not act."""
    from probedyn.diagnose.causes.adhesion import AdhesionDMT, AdhesionJKR, AdhesionMD
    from probedyn.diagnose.causes.deflection_drift import DeflectionDrift
    from probedyn.diagnose.engine import EVIDENCE_MARGIN, _parsimony, _score_in_order

    class _F:
        values = {"W": 0.1, "lam": 0.26}

    def row(c, dchi2):
        return {"cause": c(), "fit": _F(), "dchi2": dchi2, "k": len(c.params), "lr_pass": True, "evidence": None}

    def score(d):  # evidence at its cap, as the rate study's held-out scores were
        scored.append(d["cause"].key)
        d["evidence"] = 0.5 * d["dchi2"]

    for limit, leader in ((AdhesionJKR, "adhesion-jkr"), (AdhesionDMT, "adhesion-md")):
        md, lim, drift = row(AdhesionMD, 24270.54), row(limit, 24265.79), row(DeflectionDrift, 24265.79)
        scored = []
        cands = [drift, lim, md]
        _score_in_order(cands, EVIDENCE_MARGIN, score)
        assert 0.5 * lim["dchi2"] < md["evidence"] - EVIDENCE_MARGIN  # below the pruning line ...
        assert limit.key in scored and not lim.get("pruned")  # ... and scored: a limit of the container
        assert drift.get("pruned") and drift["evidence"] is None  # the same cap, not a limit: pruned (exact)
        claimed = sorted([d for d in cands if d["evidence"] is not None], key=lambda d: -d["evidence"])
        note = _parsimony(claimed, EVIDENCE_MARGIN)
        assert claimed[0]["cause"].key == leader and (note is None) == (leader == "adhesion-md")


def test_a_container_never_fits_worse_than_a_limit_it_contains(tmp_path, monkeypatch):
    """Class 2 across causes, the converse of the limit re-fit (:func:`probedyn.diagnose.engine._container_refits`):
    Maugis-Dugdale contains JKR (lambda -> inf) and DMT (lambda -> 0), so its best fit can be no worse than theirs.
    On force-curve seed 2001 (a JKR truth) with AR(1) noise of rho = 0.8, fitted on the true noise's innovations,
    Maugis-Dugdale's multi-start stopped at an interior lambda ~ 2.8, chi^2 ~ 10 behind JKR (session 22). Since
    session 44 the jump mixture's residuals keep the point residual's sign away from the jump (docs 9.30), the
    innovations are no longer scrambled there and the multi-start reaches JKR's basin by itself (chi^2 608.9 against
    JKR's 609.6, lambda 2.8 too); a stalled fit is therefore made here (lambda held at 0.5, the DMT side) and handed
    to the candidates' re-fits, which must restart it from JKR's
    optimum with lambda at its bounds and end within the fitter's tolerance of JKR or better, lambda towards the JKR
    side (0.88 since departure 47; 2.8 with the source's grafted tail). The contact point's registration scan (session 42) is switched off: this test is of the re-fit alone."""
    from probedyn.diagnose.engine import _limit_refits
    from probedyn.diagnose.forcecurve import ForceCurveProblem
    from probedyn.diagnose.noise import AR1Whitener

    monkeypatch.setattr(ForceCurveProblem, "registration_starts", lambda self, *a: [])

    path, truth = make_curve_case(tmp_path, 2001, "adhesion-jkr", noise_rho=0.8)
    prob = ForceCurveProblem(read_measurement(path))
    F = Fitter(prob)
    F.white = AR1Whitener(0.8, prob.sequences, 2 * 300)
    base = F.baseline()
    laws = [c for c in prob.causes if "adhesion" in c.changes]
    fits = [F.nested(base, (c,)) for c in laws]
    i_md = [c.key for c in laws].index("adhesion-md")
    md_law = laws[i_md]
    stalled = F.fit(tuple(base.causes) + (md_law,), [{**fits[i_md].values, "lam": 0.5}], fixed={"lam": 0.5})
    chi_jkr = fits[[c.key for c in laws].index("adhesion-jkr")].chi2
    assert stalled.chi2 > chi_jkr + 1.0  # the case exercises the re-fit
    fits[i_md] = stalled
    fits = _limit_refits(F, laws, fits)
    chi = {f.causes[0].key: f.chi2 for f in fits}
    md = fits[i_md]
    assert chi["adhesion-md"] <= min(chi["adhesion-jkr"], chi["adhesion-dmt"]) + 1e-6 * chi["adhesion-jkr"]
    # off the held DMT-side value towards JKR's (with Maugis' own non-contact branch, departure 47, the Dugdale
    # hysteresis matches this JKR record from lambda ~ 0.9 on: chi^2 608.9 at 0.88), W within 10 %
    assert md.values["lam"] > 0.7 and abs(md.values["W"] / truth["params"]["W"] - 1) < 0.1


def test_a_whitened_adhesion_fit_is_registered_in_its_contact_point(tmp_path):
    """Under AR(1) noise the fits run on innovations, which weigh a predicted jump's position relative to the
    samples sharply: the misfit has minima a sample interval or two apart in the contact point. On seed 2001
    (a JKR truth, rho = 0.8, the true noise's innovations) DMT's best start ended at chi^2 635.7 and a re-fit
    with z_c two intervals on at 625.6 (session 41). The engine's registration scan (``Fitter.registered``)
    makes every whitened nested fit of an adhesion law a minimum over those moves: none of the four re-fits
    may lower its chi^2 by more than 0.05 (the fitter's tolerance on this rugged misfit: ~1e-3). Without the
    scan DMT ends at 632.75 and a move of one interval lowers it to 632.62 (this assertion fails); the scan's
    rounds walk on to 625.37."""
    from probedyn.diagnose.forcecurve import ForceCurveProblem
    from probedyn.diagnose.noise import AR1Whitener

    path, _ = make_curve_case(tmp_path, 2001, "adhesion-jkr", noise_rho=0.8)
    prob = ForceCurveProblem(read_measurement(path))
    F = Fitter(prob)
    F.white = AR1Whitener(0.8, prob.sequences, 2 * 300)
    base = F.baseline()
    dmt = next(c for c in prob.causes if c.key == "adhesion-dmt")
    f = F.nested(base, (dmt,))
    starts = prob.registration_starts(dict(f.values), f.causes, (dmt,))
    assert len(starts) == 4
    dz = float(np.median(prob.dz))
    assert sorted(round((s["z_c"] - f.values["z_c"]) / dz) for s in starts) == [-2, -1, 1, 2]
    moved = [F.fit(f.causes, [s]).chi2 for s in starts]
    assert min(moved) >= f.chi2 - 0.05, (f.chi2, moved)  # far below one unit (a parameter's 1-sigma)
    assert prob.registration_starts(dict(base.values), (), ()) == []  # no jump, no registration
    white = Fitter(prob)  # white residuals: no scan (none found needed on the rate cases, session 41)
    g = white.nested(white.baseline(), (dmt,))
    assert g.start != "registration"


def test_contact_laws_are_alternatives_not_extensions(tmp_path):
    """The adhesion laws select the contact law: a model with two of them is the later law alone (the force
    curve predicted with DMT then Maugis-Dugdale equals Maugis-Dugdale's), so one can never extend a model the
    other is in. They declare one ``alternative`` and the engine's greedy extension skips a cause whose
    alternative is already chosen (session 22: on an AR(1) DMT truth, seed 2032, parsimony named DMT and
    Maugis-Dugdale was then claimed as a second cause on top of it)."""
    path, _ = make_curve_case(tmp_path, 2032, "adhesion-dmt")
    prob = make_problem(path)
    laws = {c.key: c for c in prob.causes if "adhesion" in c.changes}
    assert {c.alternative for c in laws.values()} == {"contact law"}
    assert all(c.alternative is None for c in prob.causes if c.key not in laws)
    base = Fitter(prob).baseline()
    v = dict(base.values, W=0.05, lam=0.5)
    md = prob.predict(v, (laws["adhesion-md"],))
    assert np.array_equal(prob.predict(v, (laws["adhesion-dmt"], laws["adhesion-md"])), md)
    assert np.max(np.abs(prob.predict(v, (laws["adhesion-dmt"],)) - md)) > 1e-3 * np.ptp(md)  # DMT differs


@pytest.mark.slow
def test_no_second_contact_law_on_top_of_the_first(tmp_path):
    """Seed 2032 (DMT with its tail) under AR(1) noise of rho = 0.8, no noise stated: DMT first, and no other
    contact law as a second finding (before the rule: Maugis-Dugdale claimed on top of DMT, session 22). From
    session 33 to 41 Maugis-Dugdale was named first (an expected failure); with the contact point's
    registration scan of whitened fits (session 42, docs/diagnose.md 9.28) DMT is first again."""
    from probedyn.diagnose.engine import run

    path, _ = make_curve_case(tmp_path, 2032, "adhesion-dmt", noise_rho=0.8, state_noise=False)
    res = run(path)
    laws = [f["cause"] for f in res["findings"] if f["cause"].startswith("adhesion-")]
    assert laws == ["adhesion-dmt"], res["findings"]


def test_spectrum_spur_rejected_modes_identified(tmp_path):
    """Thermal PSD of the probe's FEM modes (a finer mesh than the diagnosis', equipartition with the
    FEM's modal stiffness at the tip, chi^2 periodogram scatter) with a one-bin spur below f1: the
    spur is rejected as a spur, the two flapwise modes are identified, and their areas agree with
    k_B T / k_n."""
    ov = dict(length=150e-6, width=20e-6, thickness=10e-6, elements_through_thickness=1)
    path, truth = make_fem_spectrum_case(tmp_path, 1, ov, truth_overrides=dict(ov, elements_through_thickness=2))
    prob = spectrum_problem(read_measurement(path))
    peaks = prob.peaks["peaks"]
    spur = [p for p in peaks if abs(p["f0_Hz"] - truth["spur_Hz"]) < 2 * prob.peaks["resolution_Hz"]]
    assert len(spur) == 1 and not spur[0]["accepted"] and any("spur" in r for r in spur[0]["reasons"])
    acc = [p for p in peaks if p["accepted"]]
    assert [(p["family"], p["order"]) for p in acc] == [("flapwise", 1), ("flapwise", 2)]
    for p, md in zip(acc, truth["modes"]):
        assert abs(p["f0_Hz"] / md["f"] - 1) < 0.03  # the matching tolerance (mesh 1 vs 2 layers: < 1 %)
        # the area of an averaged periodogram line: relative scatter ~ 1 / sqrt(averages x lines' bins);
        # 20 % covers the Q-area correlation of the line fit and the two meshes' k_n
        assert abs(p["thermal_ratio"] - 1) < 0.2


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason="issue 11 open: correct-first below 95 % on force curves (jump to contact on "
                   "very soft levers: DMT, JKR and MD fit alike; see docs/diagnose.md section 9)")
def test_force_curve_rates():
    """The rate study (benchmarks/diagnose_rates_curves.py) on 12 + 12 curves, against the issue's targets
    (correct cause first >= 95 %, false discoveries <= 5 %, median parameter error <= 10 %)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import tempfile

    from diagnose_rates_curves import main

    with tempfile.TemporaryDirectory() as tmp:
        s = main(["x", "12", "12", str(Path(tmp) / "rates.json")])
    assert s["correct_first_rate"] >= 0.95
    assert s["false_discovery_rate"] <= 0.05
    assert s["median_recovery_error"] <= 0.10


@pytest.mark.slow
def test_spectrum_identification_rates():
    """The spectrum peak-identification study (spurs, calibration error, frequency shift; noise-only
    spectra) on 12 + 12 FEM thermal spectra, against the issue's targets."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import tempfile

    from diagnose_rates_curves import main_spectra

    with tempfile.TemporaryDirectory() as tmp:
        s = main_spectra(["spectra", "12", "12", str(Path(tmp) / "spectra.json")])
    assert s["correct_rate"] >= 0.95
    assert s["false_discovery_rate"] <= 0.05
    assert s["median_recovery_error"] <= 0.10


def test_truth_continuation_pulls_off_however_far_the_lever_springs_back():
    """The truth generator's continuation (tests/diagnose_truth.py) on a soft lever with DMT adhesion: the
    retract's contact branch ends at delta = 0 (the Hertz slope vanishes there and the van der Waals tail's
    gradient H R / (3 z0^3) exceeds k), at the force -2 pi W R and the piezo position z_po = -2 pi W R / k
    (85 nm for 6 nN on 0.07 N/m: a jump longer than any fixed search window); the tip then lands on the
    tail's far root, so far from the sample the retract returns to the approach's force (no interaction
    hysteresis out of range: a record whose retract stays at the pull-off force is a drift, not adhesion)."""
    from diagnose_truth import _continuation_curve

    from probedyn.schemes.contact import get_contact_model

    k, W, R = 0.07, 0.0317, 30e-9
    model = get_contact_model("dmt", E_t=169e9, nu_t=0.28, E_s=1e9, nu_s=0.3, R_t=R, R_s=0.0, W=W)
    P = lambda d: model.force(d, "unloading")  # noqa: E731
    dz = 1e-9
    z = np.arange(20e-9, -200e-9, -dz)
    F_top = _continuation_curve(z[:1], P, k, 10e-9)[0]  # the equilibrium in contact at the top of the ramp
    F = _continuation_curve(z, P, k, z[0] - F_top / k)
    F_po = 2 * math.pi * W * R
    z_po = -F_po / k
    # the deepest force is the fold's, -2 pi W R, to within one piezo step along the contact branch (slope < k)
    assert abs(F.min() + F_po) <= k * dz
    j = int(np.argmax(np.abs(np.diff(F))))  # the jump: between the last contact sample and the first free one
    assert z[j + 1] - dz <= z_po <= z[j] + dz
    # after the jump: the tail's stable root, |F| = H R / (6 g^2) <= k g / 2 at a gap g beyond the fold's
    # (H R / (3 k))^(1/3) ~ 3 nm: a small fraction of the pull-off force, at every later sample
    assert np.all(np.abs(F[j + 1:]) < 0.05 * F_po)


def test_force_curve_misfit_continuous_where_a_jump_crosses_a_sample(tmp_path):
    """A DMT truth (snap-in and pull-off) refitted by the diagnosis, then its own noise-free record:
    moving the contact point sweeps each predicted jump across a sample. The point-sampled misfit
    changes there by the whole step squared ((jump / sigma)^2, hundreds), whatever the step in z_c:
    the class of stalled fits (a finite-difference Jacobian across it). The diagnosis' misfit (a
    sample stands for its piezo interval: two-branch mixture) is continuous: its largest increment
    over a sweep of +-1 sample step halves when the step in z_c halves (ratio 1/2 + O(h); a
    discontinuity keeps it at 1). On the model's own record the mixture costs at most 2 ln 2 per
    jump (the followed branch has probability >= 1/2)."""
    path, truth = make_curve_case(tmp_path, 2000, "adhesion-dmt")
    prob, base, fit = _nested(path, "adhesion-dmt")
    v, causes = dict(fit.values), fit.causes
    prob.data = replace(prob.data, force=prob.predict(v, causes))
    assert float(np.sum(prob.residuals(v, causes) ** 2)) <= 2 * 2 * math.log(2)

    def largest_increment(h, point):
        zc = v["z_c"] + h * np.arange(-round(float(np.median(prob.dz)) / h), round(float(np.median(prob.dz)) / h) + 1)
        if point:
            c = [np.sum(((prob.data.force - prob.predict({**v, "z_c": z}, causes)) / prob.sigma) ** 2) for z in zc]
        else:
            c = [np.sum(prob.residuals({**v, "z_c": z}, causes) ** 2) for z in zc]
        return float(np.abs(np.diff(c)).max())

    h = float(np.median(prob.dz)) / 50
    pt = largest_increment(h, True), largest_increment(h / 2, True)
    mix = largest_increment(h, False), largest_increment(h / 2, False)
    assert pt[1] > 100 and pt[1] / pt[0] > 0.9  # the point-sampled misfit jumps
    assert mix[1] / mix[0] < 0.6 and mix[1] < pt[1] / 10, (mix, pt)


def test_an_offset_larger_than_the_force_range_is_read(tmp_path):
    """A deflection's zero is the instrument's: an offset three times the whole force range (blind case
    c23 had -19 nN on a 15 nN curve; the offset's bound was the force range about zero, and the problem
    refused its own start with a traceback) is fitted like any other; the baseline of a null reaches the
    noise and the offset is recovered within 10 noise levels (the far line's intercept at z = 0 has a
    standard error of a few sigma / sqrt(n))."""
    path, truth = make_curve_case(tmp_path, 6001, None)
    csv = path.with_suffix(".csv")
    header = csv.read_text().splitlines()[0]
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    shift = 3.0 * float(np.ptp(data[:, 1]))
    data[:, 1] += shift
    np.savetxt(csv, data, delimiter=",", header=header, comments="")
    prob = make_problem(path)
    per_unit = float(np.ptp(prob.data.force)) / float(np.ptp(data[:, 1]))  # N per unit of the column
    base = Fitter(prob).baseline()
    assert base.chi2 < _chi2_bound(base.n)
    assert abs(base.values["b0"] - (truth["b0"] + shift * per_unit)) < 10 * truth["noise"]


def test_cached_maugis_dugdale_polylines_move_no_equilibrium():
    """The Maugis-Dugdale polylines are kept per lambda on a ladder of radii (:func:`forcecurve._contact_polyline`):
    they only bracket the equilibria that Newton steps on the exact curve refine, so the lever curve is the
    uncached construction's to round-off (1e-9 of a 0.1 nN noise allowed; measured 2e-12 over 40 laws) and the
    same samples carry a jump alternative; the alternative's value at a fold is read from the polyline (not
    refined) and moves by the polylines' own resolution, about 1e-3 of the law's force unit pi W R for 500
    points (5e-3 allowed; measured at most 3e-3 over 30 laws, 8 pN). A second law at the same lambda (another
    W) hits the cache."""
    from probedyn.diagnose import forcecurve as fc
    from probedyn.schemes.contact import get_contact_model

    rng = np.random.default_rng(3)
    E_t, nu_t, nu_s = 169e9, 0.27, 0.3
    for _ in range(6):
        lam, W, E = 10 ** rng.uniform(-0.5, 0.5), 10 ** rng.uniform(-2, -0.7), 10 ** rng.uniform(8.5, 10.5)
        R, k = float(rng.choice([8e-9, 20e-9, 30e-9])), 10 ** rng.uniform(-1.3, 1.0)
        K = 4 / 3 / ((1 - nu_t**2) / E_t + (1 - nu_s**2) / E)
        z0 = fc._z0_for_lambda(lam, W, R, K)
        if not 1.1e-11 < z0 < 0.9e-8:  # the registry's plausible range of z0
            continue
        m = get_contact_model("md", E_t=E_t, nu_t=nu_t, E_s=E, nu_s=nu_s, R_t=R, R_s=0.0, W=W, z0=z0)
        span = 60e-9 / k + 20e-9
        z = np.linspace(-span, 60e-9 / k + 5e-9, 300)
        zz, seg = np.r_[z, z[::-1]], np.r_[np.zeros(300, int), np.ones(300, int)]
        dz = np.full(600, z[1] - z[0])
        cached = fc.lever_curve_registry(zz, seg, m, k, span, dz)
        n_cached = len(fc._POLYLINES)
        W2 = W * 1.001  # the same lambda: z0 follows W
        m2 = get_contact_model("md", E_t=E_t, nu_t=nu_t, E_s=E, nu_s=nu_s, R_t=R, R_s=0.0, W=W2,
                               z0=fc._z0_for_lambda(lam, W2, R, K))
        fc.lever_curve_registry(zz, seg, m2, k, span, dz)
        assert len(fc._POLYLINES) == n_cached  # a hit
        m.nd_key = lambda: None  # the uncached construction
        plain = fc.lever_curve_registry(zz, seg, m, k, span, dz)
        assert np.max(np.abs(cached[0] - plain[0])) < 1e-19
        assert np.max(np.abs(cached[1] - plain[1])) < 5e-3 * m.scales.P_unit
        assert np.array_equal(np.isfinite(cached[2]), np.isfinite(plain[2]))


@pytest.mark.parametrize("law", ["dmt", "jkr", "md"])
def test_a_spring_constant_error_is_a_rescaled_radius_and_adhesion(law):
    """Why no spring-constant cause (:mod:`probedyn.diagnose.causes.deflection_sensitivity`): with the true lever
    ``k / h`` behind a declared ``k`` (sensitivity right), the recorded force ``h F`` is exactly the declared lever's
    curve on the law with ``R h^2`` and ``W / h`` (modulus declared) or with ``E* h`` and ``W h`` (modulus fitted):
    the laws' force unit ``pi W R`` scales by ``h``, their length unit ``(pi^2 W^2 R / K^2)^(1/3)``, Maugis' lambda
    and the DMT tail's range stay. Checked on the lever curves with snap-in and pull-off to 1e-6 of the force range
    (the equilibria are Newton-refined on the exact curves; a sample within round-off of a fold excepted)."""
    from probedyn.diagnose import forcecurve as fc
    from probedyn.schemes.contact import get_contact_model

    E_t, nu_t, nu_s, E_s, R, W, k = 169e9, 0.28, 0.3, 3e9, 20e-9, 0.05, 2.0
    K = 4 / 3 / ((1 - nu_t**2) / E_t + (1 - nu_s**2) / E_s)

    def model(R_, W_, K_):
        E_s_ = (1 - nu_s**2) / (4 / 3 / K_ - (1 - nu_t**2) / E_t)
        kw = dict(E_t=E_t, nu_t=nu_t, E_s=E_s_, nu_s=nu_s, R_t=R_, R_s=0.0, W=W_)
        if law == "md":
            kw["z0"] = fc._z0_for_lambda(1.0, W, R, K)  # lambda 1 for the reference law; the range then held
        if law == "dmt":
            kw["z0"] = 0.3e-9
        return get_contact_model(law, **kw)

    z = np.linspace(-40e-9, 25e-9, 400)
    zz, seg = np.r_[z, z[::-1]], np.r_[np.zeros(400, int), np.ones(400, int)]
    for h in (0.6, 1.5):
        rec = h * fc.lever_curve_registry(zz, seg, model(R, W, K), k / h, 70e-9)
        for other in (model(R * h * h, W / h, K), model(R, W * h, K * h)):
            alt = fc.lever_curve_registry(zz, seg, other, k, 70e-9)
            off = np.abs(rec - alt) > 1e-6 * np.ptp(rec)
            assert off.sum() <= 2, (h, law, np.max(np.abs(rec - alt)) / np.ptp(rec))


def test_deflection_sensitivity_is_a_stiffer_lever_on_a_scaled_law(tmp_path):
    """The cause's model (:mod:`probedyn.diagnose.causes.deflection_sensitivity`): a recorded force ``g F`` behind a
    lever deflected by ``F / k`` is the curve of a lever ``g k`` on the law ``g P`` (Hertz: ``g E*``) -- the
    prediction of the problem with the cause equals the baseline's of the same record declared with ``g k``."""
    path, truth = make_curve_case(tmp_path, 6001, None)
    meas = replace(read_measurement(path), E_sample=None)
    from probedyn.diagnose.forcecurve import ForceCurveProblem

    g = 1.3
    p1, p2 = ForceCurveProblem(meas), ForceCurveProblem(replace(meas, k=g * meas.k))
    cause = next(c for c in p1.causes if c.key == "deflection-sensitivity")
    v = {"z_c": truth["z_c"], "b0": truth["b0"], "b1": truth["b1"], "E_star": 2e9}
    a = p1.predict({**v, "s_ratio": g}, (cause,))
    b = p2.predict({**v, "E_star": g * v["E_star"]})
    assert np.max(np.abs(a - b)) < 1e-9 * np.ptp(a)
    assert np.max(np.abs(a - p1.predict(v))) > 100 * truth["noise"]  # and it is not the declared lever's


def test_deflection_sensitivity_found_and_recovered(tmp_path):
    """A hidden 8 % sensitivity miscalibration on a hard sample (seed 2300: k 8.2 N/m, E 4.5 GPa declared) is named
    first and explained; s_ratio within 4 of its own standard deviations and 1 % (the contact branch's slope
    carries it at a fraction of a per cent for 600 points at 0.05-0.2 nN)."""
    from probedyn.diagnose.engine import run

    path, truth = make_curve_case(tmp_path, 2300, "deflection-sensitivity")
    res = run(path)
    f = res["findings"][0]
    assert f["cause"] == "deflection-sensitivity" and res["verdict"] == "explained"
    p = f["parameters"]["s_ratio"]
    g = truth["params"]["s_ratio"]
    assert abs(p["value"] - g) < 4 * p["sigma"] and abs(p["value"] / g - 1) < 0.01


def test_a_noise_free_twin_is_offered_the_escape_starts(tmp_path):
    """The benchmark's identifiability fits each adhesion law to the noise-free record (``noise_free``): its
    chi-square is the effect's signal alone, below the noise's own ``n``, so the shortcut that spares the
    escape starts where the reference fits 'within the noise' must not apply (session 30: seed 2032 under
    AR(1) whitening, the DMT law that made the record stopped at chi^2 484 from its declared starts)."""
    from probedyn.diagnose.forcecurve import ForceCurveProblem
    from probedyn.diagnose.noise import AR1Whitener

    path, truth = make_curve_case(tmp_path, 2032, "adhesion-dmt", noise_rho=0.8)
    clean = np.asarray(truth["force_clean"], float)
    prob = ForceCurveProblem(replace(read_measurement(path), force=clean))
    F = Fitter(prob)
    F.white = AR1Whitener(0.8, prob.sequences, len(clean))
    base = F.baseline()
    dmt = next(c for c in prob.causes if c.key == "adhesion-dmt")
    assert prob.nested_starts(dict(base.values), (), (dmt,)) == []  # looks like noise: no escape starts
    prob.noise_free = True
    assert prob.nested_starts(dict(base.values), (), (dmt,))
    fit = F.nested(base, (dmt,))
    assert base.chi2 > 300 and fit.chi2 < 2.0  # the law that made it, to the record's 9 written digits
    assert fit.values["W"] == pytest.approx(truth["params"]["W"], rel=0.05)


@pytest.mark.parametrize("law, k", [("jkr", 0.3), ("jkr", 5.0), ("md", 1.0)])
def test_the_pull_off_alternative_is_the_exact_fold(law, k):
    """After the pull-off, a retract sample's alternative is the pre-jump branch held at its fold
    (:func:`forcecurve._jump_alternatives`). The fold is where the lever's equilibrium turns, ``dZ/dA = du D'(A)
    + Pu P'(A) / k = 0``: solved here independently by Brent's method on the law's analytic slopes. The
    diagnosis locates it on the exact curve between its polyline neighbours (``forcecurve._exact_extrema``: two
    rounds of 65 points, the radius to ~1e-5, so the force to ~P' 1e-5 < 1e-4 of pi W R); read off the polyline
    (session 40) it was up to 3.6e-2 of pi W R off. The soft lever's fold tends to the force-controlled pull-off
    -1.5 pi W R (JKR)."""
    from scipy.optimize import brentq

    from probedyn.diagnose import forcecurve as fc
    from probedyn.schemes.contact import get_contact_model

    E_t, nu_t, nu_s, E_s, R, W = 169e9, 0.27, 0.3, 3e9, 20e-9, 0.05
    kw = dict(E_t=E_t, nu_t=nu_t, E_s=E_s, nu_s=nu_s, R_t=R, R_s=0.0, W=W)
    if law == "md":
        K = 4 / 3 / ((1 - nu_t**2) / E_t + (1 - nu_s**2) / E_s)
        kw["z0"] = fc._z0_for_lambda(3.0, W, R, K)
    m = get_contact_model(law, **kw)
    du, Pu = m.scales.d_unit, m.scales.P_unit

    def slope(A):
        _, _, dD, dP = m.nd_curve(np.array([A]))
        return du * dD[0] + Pu * dP[0] / k

    grid = np.linspace(0.05, 5.0, 2000)
    s = np.array([slope(a) for a in grid])
    turns = np.flatnonzero(np.diff(np.sign(s)))
    assert len(turns) == 1  # one fold on the contact curve
    A_f = brentq(slope, grid[turns[0]], grid[turns[0] + 1], xtol=1e-15)
    P_f = m.nd_curve(np.array([A_f]))[1][0] * Pu
    span = 20e-9 + 5 * Pu / k
    z = np.linspace(-span, 10e-9 + 2 * Pu / k, 600)
    zz, seg = np.r_[z, z[::-1]], np.r_[np.zeros(600, int), np.ones(600, int)]
    F, alt, log_w = fc.lever_curve_registry(zz, seg, m, k, span, np.full(1200, z[1] - z[0]))
    # off contact after the jump (the tail, above the fold's force): the alternative is the fold force
    after = (seg == 1) & np.isfinite(log_w) & (alt < -0.5 * Pu) & (F > alt + 0.1 * Pu)
    assert after.sum() > 10
    assert np.max(np.abs(alt[after] - P_f)) < 1e-4 * Pu, (alt[after][:3] / Pu, P_f / Pu)
    if law == "jkr" and k < 1:
        assert P_f / Pu == pytest.approx(-1.5, abs=1e-3)


@pytest.mark.parametrize("law", ["adhesion-dmt", "adhesion-md"])
def test_the_adhesion_findings_state_where_the_lever_snaps_in(tmp_path, law):
    """The jump to contact of the issue's catalog is reported with the law that makes it: ``snap_in_gap_m`` of
    DMT is the gap where the van der Waals tail's gradient reaches k, of Maugis-Dugdale the Dugdale range h0 (its
    approach jumps there, departure 47). Checked against the registry's force curve of the same law, lever and tip
    (an equilibrium-path continuation, schemes.contact.force_curve), to the path's resolution (0.5 %)."""
    from probedyn.diagnose.forcecurve import ForceCurveProblem, _z0_for_lambda
    from probedyn.schemes.contact import get_contact_model
    from probedyn.schemes.contact.force_curve import force_curve

    path, truth = make_curve_case(tmp_path, 2003, "jump-to-contact")  # k 0.17 N/m: a long snap-in
    prob = ForceCurveProblem(read_measurement(path))
    cause = next(c for c in prob.causes if c.key == law)
    E_star = 2e9
    v = {"z_c": truth["z_c"], "b0": truth["b0"], "b1": truth["b1"], "E_star": E_star, "W": 0.03,
         ("z0" if law == "adhesion-dmt" else "lam"): 0.3e-9 if law == "adhesion-dmt" else 0.4}
    gap = cause.derived(v, prob)["snap_in_gap_m"]
    E_t, nu_t = prob.data.E_tip, prob.data.nu_tip
    E_s = (1 - 0.3**2) / (1 / E_star - (1 - nu_t**2) / E_t)
    R, K = prob.data.tip_radius, 4 / 3 * E_star
    z0 = v["z0"] if law == "adhesion-dmt" else _z0_for_lambda(0.4, 0.03, R, K)
    m = get_contact_model("dmt" if law == "adhesion-dmt" else "md", E_t=E_t, nu_t=nu_t, E_s=E_s, nu_s=0.3, R_t=R,
                          R_s=0.0, W=0.03, z0=z0)
    ji = force_curve(m, prob.data.k)["jump_in"]
    assert ji is not None and gap > 0
    assert gap == pytest.approx(ji["gap_before"], rel=5e-3)


def test_contact_laws_tied_in_sample_are_confounded_whatever_the_heldout_evidence():
    """engine._tied_alternative (docs/diagnose.md 9.31): two contact laws (one ``alternative`` component) whose
    in-sample Akaike scores ``dchi2 / 2 - k`` are within the evidence margin are confounded on a force curve, even
    where their held-out evidences are 8-12 nats apart (the held-out comparison next to a jump scatters: AR(1)
    seeds 2032 and 2048, laws within 0.3-0.5 nats in sample). Not beyond the margin; not between a law and a
    cause of another component; not on a problem that does not declare the scatter (modal records)."""
    from probedyn.diagnose.causes.adhesion import AdhesionDMT, AdhesionMD
    from probedyn.diagnose.causes.deflection_drift import DeflectionDrift
    from probedyn.diagnose.engine import EVIDENCE_MARGIN, _tied_alternative
    from probedyn.diagnose.forcecurve import ForceCurveProblem

    def row(c, dchi2):
        return {"cause": c(), "dchi2": dchi2, "k": len(c.params)}

    curve = ForceCurveProblem.__new__(ForceCurveProblem)  # the class attribute is all the rule reads
    md, dmt = row(AdhesionMD, 6537.98), row(AdhesionDMT, 6537.00)  # AR(1) 2048: 0.49 nats in sample
    assert _tied_alternative(curve, dmt, md, EVIDENCE_MARGIN)
    far = row(AdhesionDMT, 6537.98 - 2 * EVIDENCE_MARGIN - 0.1)
    assert not _tied_alternative(curve, far, md, EVIDENCE_MARGIN)
    drift = {"cause": DeflectionDrift(), "dchi2": 6537.98, "k": len(DeflectionDrift.params)}
    assert not _tied_alternative(curve, drift, md, EVIDENCE_MARGIN)
    assert not _tied_alternative(object(), dmt, md, EVIDENCE_MARGIN)
