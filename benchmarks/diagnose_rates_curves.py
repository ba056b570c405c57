"""Correct-cause, false-discovery and parameter-recovery rates of the force-curve diagnosis.

Usage: ``python benchmarks/diagnose_rates_curves.py N_HIDDEN N_NULL [OUT.json]`` (default 50 50
``benchmarks/results/diagnose_rates_curves.json``); ``... spectra N_HIDDEN N_NULL [OUT.json]`` for the
spectrum peak-identification study (:func:`run_spectrum_case`). Resumable: the JSON is rewritten after every
case and cases already in it are skipped. ``... visco N_VISCO OUT.json NULL_SEEDS HIDDEN_SEEDS`` (seed lists
comma-separated): the viscoelastic-sample study (:func:`visco_cases`; session 11: ``visco 12
benchmarks/results/diagnose_rates_curves_visco.json`` with the 12 first time-column nulls and the 9 detectable
time-column hidden cases of the 2000-series whose effect changes the contact branch). ``... calibration N_CAL
N_NULL N_HIDDEN OUT.json [PART PARTS]`` (session 29): the deflection-sensitivity cases (seeds 2300 + i) with the
nulls and the 2000-series rerun (:func:`calibration_cases`; parts merged with ``merge``).

Truth (``tests/diagnose_truth_curves.py``, independent of the diagnosis): approach and retract of
a lever over one of probedyn's contact registry laws (DMT with its van der Waals tail, JKR,
Maugis-Dugdale with lambda drawn in [0.3, 3], its Dugdale zone out of contact since session 45) or Hertz, followed by continuation with the jumps
where the force gradient exceeds k; recorded as an instrument does (z piezo; deflection in V with
the sidecar's sensitivity, in m, or force; tilted and offset baseline; white noise 0.05-0.2 nN;
sample modulus declared in half of the cases). Hidden effects cycle through
``CURVE_EFFECTS`` (seeds 2000 + i); noise-only cases are Hertz + the linear lever (seeds 6000 + i);
cases run interleaved (hidden, null, hidden, ...) so that a partial run is balanced.

Detectability (stated, applied to every hidden case the same way, never by hand): the effect's
*signal* is the chi-square the baseline leaves on the **noise-free** record (the baseline fitted to it
by the diagnosis' own fitter, residuals in units of the stated noise). The baseline test can only
see an effect whose signal reaches the test's own threshold: with ``dof`` degrees of freedom the
noisy baseline chi-square is about ``dof + signal`` (a non-central chi-square), which exceeds the
``1 - alpha`` quantile with at least even odds only when ``signal >= chi2_dof(1 - alpha) - dof``
(about 80 for 600 points at alpha = 1 %). Cases below it are reported as *below detectability*
(with their signal) and left out of the correct-first rate, which is also given over all cases.

Identifiability (stated the same way; evaluated between the contact registry's adhesion laws, for the
cases whose effect is one of them, and between the tip-radius error and the deflection sensitivity,
``SCALE_RIVALS``, for theirs): each adhesion law is fitted, nested in the baseline as the diagnosis
does, to the noise-free record; if a rival's noise-free chi-square is within twice the
evidence margin (2 ln 10 = 4.6) of the expected cause's, no amount of data at this noise can name the
expected cause rather than that rival (the diagnosis should say *confounded*): the correct-first rate is
also reported over the identifiable cases. A law that contains the expected one as a limit with fewer
parameters (Maugis-Dugdale for JKR) is not a rival: it reproduces its limit by construction, and the
diagnosis' parsimony rule names the contained law. Since session 26 Maugis-Dugdale is a rival of DMT (whose
tail's range is fitted: as many parameters). ``python benchmarks/diagnose_rates_curves.py summary [OUT.json]`` rewrites the
summary of a results file with the current rules.

Reported: correct cause first (the first finding is the expected cause; ``jump-to-contact`` is
explained by DMT's van der Waals tail), correct within the confounded group, false discoveries
on the nulls (any finding), the median relative error of the main parameter (W, R/R_nom,
drift) when the cause is right, every miss with its class, wall and CPU time per case (the
machine was shared: CPU time is the better measure).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from diagnose_truth_curves import (CALIBRATION_EFFECTS, CURVE_EFFECTS, DETECTOR_EFFECTS, EXPECTED,  # noqa: E402
                                   VISCO_EFFECT, make_curve_case, make_visco_case)

from probedyn.diagnose.engine import run  # noqa: E402


def cases(n_hidden: int, n_null: int) -> list[tuple[int, str | None]]:
    hid = [(2000 + i, CURVE_EFFECTS[i % len(CURVE_EFFECTS)]) for i in range(n_hidden)]
    nul = [(6000 + i, None) for i in range(n_null)]
    out = []
    for i in range(max(n_hidden, n_null)):
        out += hid[i:i + 1] + nul[i:i + 1]
    return out


def visco_cases(n_visco: int, null_seeds: list[int], hidden_seeds: list[int] = ()) -> list[tuple[int, str | None]]:
    """The viscoelastic study: ``n_visco`` viscoelastic-sample cases (seeds 2100 + i, their own generator
    :func:`make_visco_case`), interleaved with the given null seeds (6000-series, unchanged generator) and
    existing hidden seeds (2000-series, their effect from ``CURVE_EFFECTS`` as in :func:`cases`) rerun to
    check that the new cause neither steals their findings nor is discovered on noise."""
    vis = [(2100 + i, VISCO_EFFECT) for i in range(n_visco)]
    other = [(s, None) for s in null_seeds] + [(s, CURVE_EFFECTS[(s - 2000) % len(CURVE_EFFECTS)]) for s in hidden_seeds]
    out = []
    for i in range(max(len(vis), len(other))):
        out += vis[i:i + 1] + other[i:i + 1]
    return out


def detector_cases(n_each: int, n_null: int, n_hidden: int, part: int = 0, parts: int = 1) -> list[tuple[int, str | None]]:
    """The detector-effect study (session 17): ``2 n_each`` cases of the detector effects (seeds 2200 + i,
    ``DETECTOR_EFFECTS`` alternating), interleaved with the ``n_null`` noise-only cases (6000-series), then the
    ``n_hidden`` hidden cases of the 2000-series rerun (do the new causes steal their findings?); ``part`` of
    ``parts`` takes every ``parts``-th case of that order (processes of one run)."""
    det = [(2200 + i, DETECTOR_EFFECTS[i % len(DETECTOR_EFFECTS)]) for i in range(2 * n_each)]
    return _with_nulls_and_hidden(det, n_null, n_hidden, part, parts)


def _with_nulls_and_hidden(new: list, n_null: int, n_hidden: int, part: int, parts: int) -> list[tuple[int, str | None]]:
    """A new effect's cases interleaved with the noise-only ones, then the 2000-series hidden cases; every
    ``parts``-th from ``part``."""
    nul = [(6000 + i, None) for i in range(n_null)]
    out = []
    for i in range(max(len(new), len(nul))):
        out += new[i:i + 1] + nul[i:i + 1]
    out += [(2000 + i, CURVE_EFFECTS[i % len(CURVE_EFFECTS)]) for i in range(n_hidden)]
    return out[part::parts]


def calibration_cases(n_cal: int, n_null: int, n_hidden: int, part: int = 0, parts: int = 1) -> list[tuple[int, str | None]]:
    """The calibration study (session 29): ``n_cal`` cases of a miscalibrated deflection sensitivity (seeds
    2300 + i, ``CALIBRATION_EFFECTS``), interleaved with the ``n_null`` noise-only cases, then the ``n_hidden``
    hidden cases of the 2000-series rerun with the new cause in the catalog; ``part`` of ``parts`` as
    :func:`detector_cases`."""
    cal = [(2300 + i, CALIBRATION_EFFECTS[i % len(CALIBRATION_EFFECTS)]) for i in range(n_cal)]
    return _with_nulls_and_hidden(cal, n_null, n_hidden, part, parts)


#: causes that scale the contact force alike: a tip radius (Hertz ``sqrt R``) and the deflection sensitivity
#: (``g P``, told apart only by the lever's compliance): identifiability is evaluated between them as between the
#: contact laws
SCALE_RIVALS = ("tip-radius-error", "deflection-sensitivity")


class CovarianceWhitener:
    """``r -> L^-1 r`` over the record's sequences (one chain in recording order, as the truth draws it) for a
    noise of known covariance ``C = L L^T`` in units of its marginal sigma (the benchmark's power-law noise,
    :func:`diagnose_truth_curves.power_law_covariance`): the generalised chi-square ``r^T C^-1 r`` of the
    detectability criterion. Dense, for the truth's few hundred samples only (not the diagnosis')."""

    def __init__(self, cov: np.ndarray, sequences) -> None:
        self.rows = np.concatenate([np.asarray(s, int) for s in sequences])
        self.L = np.linalg.cholesky(cov[np.ix_(self.rows, self.rows)])

    def __call__(self, r: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        from scipy.linalg import solve_triangular

        if mask is not None and not mask.all():
            raise ValueError("the covariance whitener scores whole records only")
        out = np.array(r, float, copy=True)
        out[self.rows] = solve_triangular(self.L, r[self.rows], lower=True)
        return out


def signal_chi2(path: Path, clean: np.ndarray, expected: str | None = None, rho: float = 0.0,
                alpha: float | None = None, targeted: bool = False) -> dict:
    """The effect's signal: the chi-square of the diagnosis' baseline fitted to the noise-free record
    (stated noise), and the detection threshold ``chi2_dof(1 - alpha) - dof`` of the baseline test.
    ``targeted`` (the record itself states its noise, so the diagnosis has the targeted route, session 44):
    the expected cause's gain on the noise-free record against its likelihood-ratio threshold
    ``chi2_k(1 - alpha / N) - k`` is a second way to be detectable, as in the modal study.
    With AR(1) noise of correlation ``rho`` (the sidecar at ``path`` states its marginal sigma) every
    chi-square is the generalised one, ``r^T Sigma^-1 r`` on the true noise covariance (the fits on AR(1)
    innovations, :class:`probedyn.diagnose.noise.AR1Whitener`): a smooth signal's is about
    ``(1 - rho) / (1 + rho)`` of its white value, since correlated noise has that much more power at low
    frequencies. With power-law noise (``alpha``, :func:`diagnose_truth_curves.power_law`) the same on its
    exact covariance (:class:`CovarianceWhitener`)."""
    from dataclasses import replace

    from scipy.stats import chi2 as chi2_dist

    from probedyn.diagnose.engine import ALPHA, EVIDENCE_MARGIN, Fitter, lr_threshold
    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.forcecurve import ForceCurveProblem
    from probedyn.diagnose.noise import AR1Whitener

    meas = read_measurement(path)
    prob = ForceCurveProblem(replace(meas, force=np.asarray(clean, float)))
    prob.noise_free = True  # the diagnosis' escape starts, which it offers on a noisy record that misfits
    F = Fitter(prob)
    if alpha is not None:
        from diagnose_truth_curves import power_law_covariance

        F.white = CovarianceWhitener(power_law_covariance(len(clean), alpha), prob.sequences)
    elif rho:
        F.white = AR1Whitener(rho, prob.sequences, len(clean))
    base = F.baseline()
    thr = float(chi2_dist.ppf(1 - ALPHA, base.dof)) - base.dof
    out = {"signal_chi2": base.chi2, "threshold": thr, "detectable": bool(base.chi2 >= thr)}
    cause = [c for c in prob.causes if c.key == expected]
    if targeted and cause:
        k = len(cause[0].params)
        out["targeted_signal"] = float(base.chi2 - F.nested(base, (cause[0],)).chi2)
        out["targeted_threshold"] = lr_threshold(k, len(prob.causes)) - k
        out["detectable"] = out["detectable"] or out["targeted_signal"] >= out["targeted_threshold"]
    if expected is not None and out["detectable"]:
        # identifiability of the cause: every cause fitted (nested, as the diagnosis does) to the
        # noise-free record; a rival whose noise-free chi-square is within 2 x the evidence margin of
        # the expected cause's cannot be told from it by any amount of such data at this noise
        laws = [c for c in prob.causes if "adhesion" in c.changes]
        if expected in SCALE_RIVALS:
            laws = [c for c in prob.causes if c.key in SCALE_RIVALS]
        if expected not in {c.key for c in laws}:
            return out  # identifiability evaluated between the registry's contact laws and the scale rivals only
        chi = {c.key: F.nested(base, (c,)).chi2 for c in laws}
        containers = containers_of(laws, expected)
        out.update(cause_chi2=chi, containers=containers, **identifiability(chi, expected, containers))
    return out


def containers_of(laws, expected: str) -> list[str]:
    """The laws that contain ``expected`` as a limit *with fewer parameters* (the engine's parsimony rule,
    :func:`probedyn.diagnose.engine._parsimony`): Maugis-Dugdale for JKR; not for DMT since its tail's
    range is fitted (session 26: then a rival of equal size)."""
    n = {c.key: len(c.params) for c in laws}
    return [c.key for c in laws if expected in getattr(c, "limits", ()) and n[c.key] > n.get(expected, n[c.key])]


def identifiability(chi: dict, expected: str, containers: list[str]) -> dict:
    """Rival gap on the noise-free record: the smallest chi-square of a rival law minus the expected
    law's. A law that contains the expected one as a limit (Maugis-Dugdale for JKR and DMT) is not a
    rival: it reproduces its limit by construction, and the diagnosis' parsimony rule names the
    contained law when the container is within the margin."""
    from probedyn.diagnose.engine import EVIDENCE_MARGIN

    rivals = {k: v for k, v in chi.items() if k != expected and k not in containers}
    gap = min(rivals.values()) - chi[expected] if rivals else float("inf")
    return {"rival_gap_chi2": gap, "identifiable": bool(gap >= 2 * EVIDENCE_MARGIN)}


def run_case(folder: Path, seed: int, effect: str | None, rho: float = 0.0, stated: bool = True,
             alpha: float | None = None) -> dict:
    """One case. ``rho``: the noise is AR(1) of that lag-one correlation (one chain over the approach and the
    retract, :func:`diagnose_truth_curves.correlated`; the marginal sigma as drawn); ``stated = False``: the
    sidecar states no noise (most exports). Detectability and identifiability are then evaluated on the true
    noise (its sigma and correlation), from a twin of the record whose sidecar states the sigma. ``alpha``:
    1/f^alpha noise instead of AR(1) (:func:`diagnose_truth_curves.power_law`; session 23)."""
    if effect == VISCO_EFFECT:
        path, truth = make_visco_case(folder, seed)
    else:
        path, truth = make_curve_case(folder, seed, effect, noise_rho=rho, state_noise=stated, noise_alpha=alpha)
    clean = truth.pop("force_clean")
    twin = path
    if effect and not stated:  # the same draws (the sidecar's text is the only difference)
        twin, _ = make_curve_case(folder / "stated", seed, effect, noise_rho=rho, state_noise=True, noise_alpha=alpha)
    det = signal_chi2(twin, clean, EXPECTED[effect][0], rho, alpha, targeted=stated) if effect else None
    t0, c0 = time.perf_counter(), time.process_time()
    res = run(path)
    row = {"seed": seed, "effect": effect, "truth": truth, "detectability": det, "verdict": res["verdict"],
           "findings": [f["cause"] for f in res["findings"]], "wall_s": time.perf_counter() - t0,
           "cpu_s": time.process_time() - c0, "baseline_p": res["baseline"]["p_value"],
           "noise": {k: v for k, v in res["method"]["noise"].items()
                     if k in ("model", "rho", "rho_scatter", "rho_lag1", "rho_marginal", "innovation_sd", "reason",
                              "white_scale", "sequence_scales", "share", "mixture_lr", "mixture_rho_scatter")},
           "candidates": [{"cause": c["cause"], "evidence": c["evidence"], "delta_chi2": c["delta_chi2"]}
                          for c in res["candidates"]]}
    if res["findings"]:
        f0 = res["findings"][0]
        group = [f0["cause"], *f0.get("confounded_with", [])]
        if f0.get("parsimony"):
            row["parsimony"] = f0["parsimony"]
        row.update(first=f0["cause"], group=group, flags=f0["flags"],
                   fitted={k: v["value"] for k, v in f0["parameters"].items()})
    if effect:
        cause, main = EXPECTED[effect]
        row["expected"] = cause
        row["correct_first"] = row.get("first") == cause
        row["correct_in_group"] = cause in row.get("group", [])
        if row["correct_first"]:
            fit = row["fitted"][main]
            true = truth["params"][main]
            row["recovery_error"] = abs(fit / true - 1.0)
            if "tau" in truth["params"] and "tau" in row["fitted"]:
                row["tau_error"] = abs(row["fitted"]["tau"] / truth["params"]["tau"] - 1.0)
            if "lam" in truth["params"] and "lam" in row["fitted"]:
                row["lam_error"] = abs(row["fitted"]["lam"] / truth["params"]["lam"] - 1.0)
    return row


def _refresh_identifiability(r: dict) -> None:
    """Recompute the stored rows' identifiability from their noise-free chi-squares (rows written before
    containers were excluded from the rivals carry no ``containers`` list: derived from the catalog)."""
    det = r.get("detectability") or {}
    if "cause_chi2" not in det:
        return
    if "containers" not in det:
        from probedyn.diagnose.causes import catalog

        det["containers"] = containers_of(catalog("force"), r["expected"])
    det.update(identifiability(det["cause_chi2"], r["expected"], det["containers"]))


def detectable(r: dict) -> bool:
    return r.get("detectability") is None or r["detectability"]["detectable"]


def miss_class(r: dict) -> str:
    if not detectable(r):
        return f"below detectability (signal chi2 {r['detectability']['signal_chi2']:.1f} < {r['detectability']['threshold']:.1f})"
    if r.get("detectability") and r["detectability"].get("identifiable") is False:
        return (f"not identifiable (a rival law within {r['detectability']['rival_gap_chi2']:.1f} of chi2 on the noise-free "
                f"record): {r.get('first')} first")
    if r["verdict"] == "no-significant-discrepancy":
        return "not detected (baseline chi-square test passed)"
    if not r["findings"]:
        return "detected, no cause claimed (unexplained)"
    if r.get("correct_in_group"):
        return f"confounded: {r['first']} first, expected cause in the group"
    return f"wrong cause first: {r['first']}"


def summarize(rows: list[dict]) -> dict:
    for r in rows:
        if r["effect"]:
            _refresh_identifiability(r)
    eff_all = [r for r in rows if r["effect"]]
    eff = [r for r in eff_all if detectable(r)]
    nul = [r for r in rows if not r["effect"]]
    rec = [r["recovery_error"] for r in eff if "recovery_error" in r]
    per = {}
    for e in CURVE_EFFECTS + [VISCO_EFFECT] + DETECTOR_EFFECTS + CALIBRATION_EFFECTS:
        rr = [r for r in eff if r["effect"] == e]
        if rr:
            re = [r["recovery_error"] for r in rr if "recovery_error" in r]
            per[e] = {"n": len(rr), "correct_first": sum(r["correct_first"] for r in rr),
                      "median_recovery_error": float(np.median(re)) if re else None}
    ident = [r for r in eff if r["detectability"].get("identifiable", True)]
    return {
        "n_hidden": len(eff_all), "n_hidden_detectable": len(eff), "n_null": len(nul),
        "n_hidden_identifiable": len(ident),
        "correct_first_rate_identifiable": sum(r["correct_first"] for r in ident) / len(ident) if ident else None,
        "not_identifiable": [{"seed": r["seed"], "effect": r["effect"], "rival_gap_chi2": r["detectability"]["rival_gap_chi2"],
                              "first": r.get("first"), "group": r.get("group")} for r in eff if r not in ident],
        "correct_first_rate_all_cases": sum(r["correct_first"] for r in eff_all) / len(eff_all) if eff_all else None,
        "below_detectability": [{"seed": r["seed"], "effect": r["effect"], **r["detectability"], "verdict": r["verdict"],
                                 "findings": r["findings"]} for r in eff_all if not detectable(r)],
        "correct_first_rate": sum(r["correct_first"] for r in eff) / len(eff) if eff else None,
        "correct_in_group_rate": sum(r["correct_in_group"] for r in eff) / len(eff) if eff else None,
        "false_discovery_rate": sum(bool(r["findings"]) for r in nul) / len(nul) if nul else None,
        "median_recovery_error": float(np.median(rec)) if rec else None,
        "median_tau_error": float(np.median([r["tau_error"] for r in eff if "tau_error" in r]))
        if any("tau_error" in r for r in eff) else None,
        "median_lam_error": float(np.median([r["lam_error"] for r in eff if "lam_error" in r]))
        if any("lam_error" in r for r in eff) else None,
        "per_effect": per,
        "misses": [{"seed": r["seed"], "effect": r["effect"], "class": miss_class(r), "verdict": r["verdict"],
                    "findings": r["findings"]} for r in eff if not r["correct_first"]],
        "parsimony_applied": [r["seed"] for r in rows if r.get("parsimony")],
        "false_discoveries": [{"seed": r["seed"], "verdict": r["verdict"], "findings": r["findings"]}
                              for r in nul if r["findings"]],
        "noise_correlation_estimated": {
            "whitened": sum(r["noise"].get("model") == "AR(1)" for r in rows if "noise" in r),
            "of": sum("noise" in r for r in rows),
            "rho_median": float(np.median([r["noise"].get("rho", 0.0) for r in rows if "noise" in r]))
            if any("noise" in r for r in rows) else None},
        "median_cpu_s": float(np.median([r["cpu_s"] for r in rows])) if rows else None,
        "median_wall_s": float(np.median([r["wall_s"] for r in rows])) if rows else None,
    }


def main(argv: list[str], todo: list | None = None, rho: float = 0.0, stated: bool = True,
         alpha: float | None = None) -> dict:
    n_h = int(argv[1]) if len(argv) > 1 else 50
    n_n = int(argv[2]) if len(argv) > 2 else 50
    out = Path(argv[3]) if len(argv) > 3 else ROOT / "benchmarks" / "results" / "diagnose_rates_curves.json"
    data = json.loads(out.read_text()) if out.exists() else {"rows": []}
    if rho or not stated or alpha is not None:
        noise = {"rho": rho, "noise_stated": stated} | ({"alpha": alpha} if alpha is not None else {})
        if data.setdefault("noise", noise) != noise:
            raise SystemExit(f"{out} holds a run with noise {data['noise']}, not {noise}")
    done = {r["seed"] for r in data["rows"]}
    with tempfile.TemporaryDirectory() as tmp:
        for seed, effect in (cases(n_h, n_n) if todo is None else todo):
            if seed in done:
                continue
            row = run_case(Path(tmp), seed, effect, rho, stated, alpha)
            data["rows"].append(row)
            data["summary"] = summarize(data["rows"])
            data["machine"] = "2 cores shared with other jobs (wall times inflated; CPU time is per process)"
            out.parent.mkdir(parents=True, exist_ok=True)
            tmpf = out.with_suffix(".tmp")
            tmpf.write_text(json.dumps(data, indent=1, default=float))
            os.replace(tmpf, out)
            print(seed, effect, row["verdict"], row["findings"], f"{row['cpu_s']:.1f} s cpu", flush=True)
    return data["summary"]


# ------------------------------------------------------------------------------------------
# Spectra: peak identification against the probe's FEM (class 6)
# ------------------------------------------------------------------------------------------

SPEC_LEVERS = {"A": dict(length=150e-6, width=20e-6, thickness=10e-6, elements_through_thickness=1),
               "B": dict(length=300e-6, width=30e-6, thickness=10e-6, elements_through_thickness=1),
               "C": dict(length=200e-6, width=40e-6, thickness=5e-6, elements_through_thickness=1)}
SPEC_EFFECTS = ["spur", "calibration-error", "frequency-shift"]
_MODES: dict = {}


def run_spectrum_case(folder: Path, seed: int, effect: str | None) -> dict:
    """One thermal spectrum (truth: FEM with 2 elements through the thickness; diagnosis: 1) and its
    peak identification: hidden effects ``spur`` (a one-bin line at 0.15-0.9 f1 or between f1 and
    f2), ``calibration-error`` (the PSD scaled by 0.3-3: the thermal-area factor must find it),
    ``frequency-shift`` (all modes by 0.9-0.97 or 1.03-1.1: the common frequency scale must find
    it); noise-only: thermal modes + background only. Every case has a random lever, Q and averages."""
    from diagnose_truth_curves import fem_thermal_modes, make_fem_spectrum_case

    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.spectrum import spectrum_problem

    rng = np.random.default_rng(seed)
    lever = "ABC"[int(rng.integers(3))]
    ov = SPEC_LEVERS[lever]
    if lever not in _MODES:
        _MODES[lever] = fem_thermal_modes(dict(ov, elements_through_thickness=2))
    Q = float(10 ** rng.uniform(2.0, 3.0))
    averages = int(rng.choice([16, 32, 64]))
    kw = dict(Q=Q, averages=averages, modes=_MODES[lever], spur_rel=None)
    if effect == "spur":
        kw["spur_rel"] = float(rng.choice([rng.uniform(0.15, 0.9), rng.uniform(1.2, 0.8 * _MODES[lever][1]["f"] / _MODES[lever][0]["f"])]))
    elif effect == "calibration-error":
        kw["calibration"] = float(10 ** (rng.choice([-1, 1]) * rng.uniform(0.1, 0.5)))
    elif effect == "frequency-shift":
        kw["freq_scale"] = float(rng.choice([rng.uniform(0.9, 0.97), rng.uniform(1.03, 1.1)]))
    path, truth = make_fem_spectrum_case(folder, seed, ov, **kw)
    t0, c0 = time.perf_counter(), time.process_time()
    prob = spectrum_problem(read_measurement(path))
    pk = prob.peaks
    acc = [p for p in pk["peaks"] if p["accepted"]]
    rej = [p for p in pk["peaks"] if not p["accepted"]]
    ident_ok = [(p["family"], p["order"]) for p in acc] == [("flapwise", 1), ("flapwise", 2)] and all(
        abs(p["f0_Hz"] / m["f"] - 1) < 0.01 for p, m in zip(acc, truth["modes"]))
    row = {"seed": seed, "effect": effect, "lever": lever, "Q": Q, "averages": averages,
           "accepted": [(p["family"], p["order"], p["f0_Hz"]) for p in acc],
           "rejected": [(p["f0_Hz"], p["reasons"]) for p in rej], "identified": ident_ok,
           "frequency_scale": pk["frequency_scale"], "thermal_area_factor": pk["thermal_area_factor"],
           "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    spur_found = [p for p in rej if "spur_Hz" in truth and abs(p["f0_Hz"] - truth["spur_Hz"]) < 3 * pk["resolution_Hz"]
                  and any("spur" in r for r in p["reasons"])]
    if effect == "spur":
        row["correct"] = ident_ok and len(spur_found) == 1 and len(rej) == 1
        row["recovery_error"] = abs(spur_found[0]["f0_Hz"] / truth["spur_Hz"] - 1) if spur_found else None
    elif effect == "calibration-error":
        c = pk["thermal_area_factor"]
        row["recovery_error"] = abs(c / truth["calibration"] - 1) if c else None
        row["correct"] = ident_ok and not rej and row["recovery_error"] is not None and row["recovery_error"] < 0.1
    elif effect == "frequency-shift":
        row["recovery_error"] = abs((pk["frequency_scale"] - truth["freq_scale"]) / (truth["freq_scale"] - 1))
        row["correct"] = ident_ok and not rej and row["recovery_error"] < 0.1
    else:
        c = pk["thermal_area_factor"]
        # a false discovery: a peak rejected (a spur or implausible line claimed where there is none),
        # a wrong identification, or a calibration error claimed (area factor off 1 by > 10 %)
        row["false_discovery"] = bool(rej) or not ident_ok or (c is not None and abs(c - 1) > 0.1)
    return row


def main_spectra(argv: list[str]) -> dict:
    n_h = int(argv[1]) if len(argv) > 1 else 50
    n_n = int(argv[2]) if len(argv) > 2 else 50
    out = Path(argv[3]) if len(argv) > 3 else ROOT / "benchmarks" / "results" / "diagnose_rates_spectra.json"
    data = json.loads(out.read_text()) if out.exists() else {"rows": []}
    done = {r["seed"] for r in data["rows"]}
    hid = [(3000 + i, SPEC_EFFECTS[i % len(SPEC_EFFECTS)]) for i in range(n_h)]
    nul = [(8000 + i, None) for i in range(n_n)]
    with tempfile.TemporaryDirectory() as tmp:
        for seed, effect in [x for i in range(max(n_h, n_n)) for x in (hid[i:i + 1] + nul[i:i + 1])]:
            if seed in done:
                continue
            data["rows"].append(run_spectrum_case(Path(tmp), seed, effect))
            rows = data["rows"]
            eff = [r for r in rows if r["effect"]]
            nul_r = [r for r in rows if not r["effect"]]
            rec = [r["recovery_error"] for r in eff if r.get("recovery_error") is not None and r["effect"] != "spur"]
            data["summary"] = {
                "n_hidden": len(eff), "n_null": len(nul_r),
                "correct_rate": sum(r["correct"] for r in eff) / len(eff) if eff else None,
                "false_discovery_rate": sum(r["false_discovery"] for r in nul_r) / len(nul_r) if nul_r else None,
                "median_recovery_error": float(np.median(rec)) if rec else None,
                "misses": [{k: r[k] for k in ("seed", "effect", "lever", "accepted", "rejected", "frequency_scale",
                                              "thermal_area_factor")} for r in eff if not r["correct"]],
                "false_discoveries": [{k: r[k] for k in ("seed", "lever", "accepted", "rejected", "thermal_area_factor")}
                                      for r in nul_r if r["false_discovery"]],
                "median_cpu_s": float(np.median([r["cpu_s"] for r in rows])),
            }
            data["machine"] = "2 cores shared with other jobs"
            tmpf = out.with_suffix(".tmp")
            tmpf.write_text(json.dumps(data, indent=1, default=float))
            os.replace(tmpf, out)
            r = data["rows"][-1]
            print(r["seed"], r["effect"], r.get("correct", not r.get("false_discovery")), f"{r['cpu_s']:.1f} s cpu", flush=True)
    return data["summary"]


def resummarize(path: Path) -> dict:
    """Rewrite the summary of a (partial) results file with this file's summarize()."""
    data = json.loads(Path(path).read_text())
    data["summary"] = summarize(data["rows"])
    Path(path).write_text(json.dumps(data, indent=1, default=float))
    return data["summary"]


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "summary":
        print(json.dumps(resummarize(Path(sys.argv[2]) if len(sys.argv) > 2 else
                                     ROOT / "benchmarks" / "results" / "diagnose_rates_curves.json"), indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "merge":
        # merge OUT.json PART.json ...: the rows of a run's parts in one file, summarised
        parts = [json.loads(Path(f).read_text()) for f in sys.argv[3:]]
        merged = {k: v for k, v in parts[0].items() if k not in ("rows", "summary")}
        merged["rows"] = sorted({r["seed"]: r for d in parts for r in d["rows"]}.values(), key=lambda r: r["seed"])
        merged["summary"] = summarize(merged["rows"])
        Path(sys.argv[2]).write_text(json.dumps(merged, indent=1, default=float))
        print(json.dumps(merged["summary"], indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "visco":
        # visco N_VISCO OUT.json [NULL_SEEDS (comma-separated)] [HIDDEN_SEEDS (comma-separated)]
        seeds = lambda i: [int(x) for x in sys.argv[i].split(",") if x] if len(sys.argv) > i else []  # noqa: E731
        todo = visco_cases(int(sys.argv[2]), seeds(4), seeds(5))
        print(json.dumps(main(["", "0", "0", sys.argv[3]], todo), indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "detector":
        # detector N_EACH N_NULL N_HIDDEN OUT.json [PART PARTS]: one process of a run (merge the parts' rows)
        part, parts = (int(sys.argv[6]), int(sys.argv[7])) if len(sys.argv) > 7 else (0, 1)
        todo = detector_cases(int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), part, parts)
        print(json.dumps(main(["", "0", "0", sys.argv[5]], todo), indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "calibration":
        # calibration N_CAL N_NULL N_HIDDEN OUT.json [PART PARTS]: one process of a run (merge the parts' rows)
        part, parts = (int(sys.argv[6]), int(sys.argv[7])) if len(sys.argv) > 7 else (0, 1)
        todo = calibration_cases(int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), part, parts)
        print(json.dumps(main(["", "0", "0", sys.argv[5]], todo), indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "correlated":
        # correlated N_HIDDEN N_NULL RHO OUT.json [--unstated] [--alpha=A] [PART PARTS]: the rate study with AR(1) noise
        # (session 22); PART of PARTS takes every PARTS-th (hidden, null) pair of the interleaved list (merge
        # the parts' rows)
        # ``--alpha=A``: 1/f^A noise instead (RHO ignored; session 23)
        a = [x for x in sys.argv[2:] if x != "--unstated" and not x.startswith("--alpha=")]
        alpha = next((float(x.split("=", 1)[1]) for x in sys.argv if x.startswith("--alpha=")), None)
        part, parts = (int(a[4]), int(a[5])) if len(a) > 5 else (0, 1)
        todo = [c for i, c in enumerate(cases(int(a[0]), int(a[1]))) if (i // 2) % parts == part]
        print(json.dumps(main(["", a[0], a[1], a[3]], todo, 0.0 if alpha is not None else float(a[2]),
                              "--unstated" not in sys.argv, alpha), indent=1, default=float))
    elif len(sys.argv) > 1 and sys.argv[1] == "spectra":
        print(json.dumps(main_spectra(sys.argv[1:]), indent=1, default=float))
    else:
        print(json.dumps(main(sys.argv), indent=1, default=float))
