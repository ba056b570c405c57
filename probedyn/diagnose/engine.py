"""The diagnosis engine: the five steps of ``probedyn diagnose``.

1. **Calibrate** the baseline's free parameters (weighted least squares on whitened residuals).
2. **Residual structure**: chi-square test of the baseline against the stated noise
   (p-value of chi^2 with n - k degrees of freedom), trend against mode order / family or
   speed / load, periodicity and autocorrelation (the problem's ``structure``).
3. **Rank causes by out-of-sample evidence.** Every applicable cause of the catalog is fitted
   together with the baseline's free parameters, then *leave-one-group-out cross-validation*
   (groups = modes, or blocks of scans) refits it without each group and predicts the
   held-out group. The evidence is half the reduction of the held-out chi^2 against the
   baseline's own cross-validation, ``evidence = (CV_base - CV_cause) / 2`` (nats, Gaussian
   predictive log-likelihood). A parameter that only fits noise cannot predict data it has
   not seen, so it *raises* CV: extra parameters are not rewarded for free. With fewer than
   three groups cross-validation is impossible and the Akaike criterion is used instead,
   ``evidence = (chi^2_base - chi^2_cause) / 2 - k`` (each parameter costs one nat).
   A cause is only *claimed* when (a) the baseline fails the chi-square test at level alpha,
   (b) its in-sample improvement passes the likelihood-ratio test chi^2_k(1 - alpha / N_causes)
   (Bonferroni over the catalog) and (c) its evidence is positive.
4. **Extend** the baseline with the winner and refit; if the extended model still fails the
   chi-square test, the remaining causes are tried on top of it (greedy, up to ``max_causes``).
5. **Gain**: residual and held-out RMS before and after (in units of the stated noise, and
   physical), the parameters with 1-sigma uncertainties from the Jacobian (scaled by
   sqrt(chi^2/dof) when that exceeds 1). **Confounding**: causes whose evidence is within
   2 nats of the winner (a Bayes factor below e^2 ~ 7) and whose fitted predictions of the measured data
   differ by less than the noise (RMS < 1 sigma) are reported as confounded, with the extra
   measurement that separates them (largest predicted difference in units of the noise).
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2 as chi2_dist

from probedyn.diagnose.causes import Cause, CauseParam
from probedyn.core.errors import DataFormatError

__all__ = ["diagnose", "make_problem", "FitResult"]

ALPHA = 0.01


def make_problem(meas):
    """Measurement object -> problem (modal, friction; spectra go through peak extraction)."""
    from probedyn.diagnose.formats import read_measurement

    if isinstance(meas, (str, Path)):
        meas = read_measurement(meas)
    if meas.kind == "modal":
        from probedyn.diagnose.modal import ModalProblem

        return ModalProblem(meas)
    if meas.kind == "friction":
        from probedyn.diagnose.friction import FrictionProblem

        return FrictionProblem(meas)
    from probedyn.diagnose.spectrum import spectrum_to_modal
    from probedyn.diagnose.modal import ModalProblem

    modal, peaks = spectrum_to_modal(meas)
    prob = ModalProblem(modal)
    prob.extracted_peaks = peaks
    return prob


@dataclass
class FitResult:
    causes: tuple
    names: list[str]
    values: dict[str, float]
    sigma: dict[str, float]
    held: dict[str, float]
    chi2: float
    n: int
    k: int
    r: np.ndarray
    u: np.ndarray
    corr: np.ndarray | None = None
    cv: float | None = None
    cv_r: np.ndarray | None = None
    nfev: int = 0

    @property
    def dof(self) -> int:
        return max(self.n - self.k, 1)


def _to_u(p: CauseParam, v: float) -> float:
    return math.log10(v) if p.scale == "log" else v


def _from_u(p: CauseParam, u: float) -> float:
    return 10.0**u if p.scale == "log" else u


def _bounds(p: CauseParam) -> tuple[float, float]:
    return (_to_u(p, p.lo), _to_u(p, p.hi)) if p.scale == "log" else (p.lo, p.hi)


class _Fitter:
    def __init__(self, problem):
        self.problem = problem
        self.nfev = 0

    def params_for(self, causes, n_points: int) -> tuple[list[CauseParam], dict[str, float]]:
        plist = list(self.problem.base_params)
        held: dict[str, float] = {}
        for c in causes:
            for p in c.params:
                plist.append(p)
        if len(plist) >= n_points:  # not enough data: hold secondary parameters
            keep = []
            for p in plist:
                if p.secondary and p.hold is not None:
                    held[p.name] = p.hold
                else:
                    keep.append(p)
            plist = keep
        return plist, held

    def fit(self, causes=(), mask=None, u0=None, multistart=True) -> FitResult:
        prob = self.problem
        r_all = prob.residuals({**self._defaults(causes)}, causes)
        mask = np.ones(len(r_all), bool) if mask is None else mask
        n = int(mask.sum())
        plist, held = self.params_for(causes, n)
        lo = np.array([_bounds(p)[0] for p in plist]); hi = np.array([_bounds(p)[1] for p in plist])

        def vals(u):
            v = {p.name: _from_u(p, x) for p, x in zip(plist, u)}
            v.update(held)
            return v

        def fun(u):
            self.nfev += 1
            return prob.residuals(vals(u), causes)[mask]

        if not plist:
            r = prob.residuals(vals([]), causes)
            return FitResult(tuple(causes), [], vals([]), {}, held, float(np.sum(r[mask] ** 2)), n, 0, r, np.array([]))
        if u0 is not None:
            starts = [np.clip(u0, lo, hi)]
        else:
            combos = list(itertools.product(*[[_to_u(p, s) for s in p.starts] for p in plist]))[:8]
            starts = [np.clip(np.array(c, float), lo, hi) for c in combos]
            if not multistart:
                starts = starts[:1]
        best = None
        span = hi - lo
        for s in starts:
            s = np.minimum(np.maximum(s, lo + 1e-9 * span), hi - 1e-9 * span)
            try:
                res = least_squares(fun, s, bounds=(lo, hi), x_scale=span / 10.0, method="trf",
                                    max_nfev=60 * (len(plist) + 1), diff_step=1e-6)
            except ValueError:
                continue
            c2 = float(np.sum(res.fun**2))
            if best is None or c2 < best[0]:
                best = (c2, res)
        c2, res = best
        u = res.x
        v = vals(u)
        r = prob.residuals(v, causes)
        J = res.jac
        k = len(plist)
        dof = max(n - k, 1)
        scale = max(1.0, c2 / dof)
        sig_u, corr = _cov(J, scale)
        sigma = {}
        for p, x, su in zip(plist, u, sig_u):
            sigma[p.name] = (10.0**x) * math.log(10) * su if p.scale == "log" else su
        return FitResult(tuple(causes), [p.name for p in plist], v, sigma, held, c2, n, k, r, u, corr, nfev=res.nfev)

    def _defaults(self, causes) -> dict[str, float]:
        v = {p.name: p.starts[0] for p in self.problem.base_params}
        for c in causes:
            for p in c.params:
                v[p.name] = p.starts[0]
        return v

    def crossval(self, fit: FitResult, folds: list[np.ndarray]) -> tuple[float, np.ndarray]:
        """Held-out chi^2: refit without each fold (warm start), predict the fold."""
        prob = self.problem
        out = np.full(len(fit.r), np.nan)
        for fold in folds:
            mask = np.ones(len(fit.r), bool); mask[fold] = False
            plist, _ = self.params_for(fit.causes, int(mask.sum()))
            u0 = np.array([_to_u(p, fit.values[p.name]) for p in plist]) if plist else None
            ff = self.fit(fit.causes, mask=mask, u0=u0)
            out[fold] = ff.r[fold]
        return float(np.nansum(out**2)), out


def _cov(J: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Parameter standard deviations and correlations from the whitened Jacobian.

    Columns are normalised first (the covariance is invariant to parameter scaling, the
    rank decision is not); directions with singular values below 1e-10 of the largest are
    unidentifiable and get an infinite standard deviation.
    """
    cn = np.linalg.norm(J, axis=0)
    cn = np.where(cn > 0, cn, 1.0)
    s_, V_ = _cov_scaled(J / cn, scale)
    sd = s_ / cn
    return np.where(np.isfinite(s_), sd, np.inf), V_


def _cov_scaled(J: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    tol = s.max() * 1e-10 if s.size else 0
    inv = np.where(s > tol, 1.0 / np.maximum(s, tol if tol > 0 else 1e-300) ** 2, 1e30)  # 1e30: unidentifiable
    with np.errstate(invalid="ignore", over="ignore"):
        cov = (Vt.T * inv) @ Vt * scale
    sd = np.sqrt(np.maximum(np.diag(cov), 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    sd = np.where(sd > 1e14, np.inf, sd)
    return sd, corr


def _folds(problem) -> list[np.ndarray]:
    """Leave-one-group-out for up to 10 groups, else K-fold (K = problem.n_folds or 8) over groups."""
    g = np.asarray(problem.groups)
    ug = list(dict.fromkeys(g.tolist()))
    if len(ug) <= 10:
        return [np.nonzero(g == x)[0] for x in ug]
    k = getattr(problem, "n_folds", 8)
    return [np.nonzero(np.isin(g, ug[i::k]))[0] for i in range(k)]


def _rms(x) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x**2))) if x.size else float("nan")


def diagnose(meas, *, alpha: float = ALPHA, max_causes: int = 2, only: list[str] | None = None) -> dict[str, Any]:
    """Run the five steps on a measurement (path or object); return the JSON-able result."""
    t0 = time.perf_counter()
    problem = meas if hasattr(meas, "residuals") else make_problem(meas)
    F = _Fitter(problem)
    folds = _folds(problem)
    use_cv = len(folds) >= 3
    causes = [c for c in problem.causes if only is None or c.id in only]
    # 1. baseline
    base = F.fit(())
    p_base = float(chi2_dist.sf(base.chi2, base.dof))
    significant = p_base < alpha
    structure = problem.structure(base.r)
    # 3. candidates: full fits and the likelihood-ratio test for all; cross-validation only
    # where a claim is possible (significant baseline, LR test passed) -- the others cannot be
    # claimed whatever their held-out error, and CV is the expensive part.
    cands = []
    for c in causes:
        fit = F.fit((c,))
        if fit.k == base.k:  # all cause parameters held: nothing identifiable
            continue
        kc = fit.k - base.k
        dchi2 = base.chi2 - fit.chi2
        thr = float(chi2_dist.ppf(1 - alpha / max(len(causes), 1), kc))
        cands.append({"cause": c, "fit": fit, "evidence": 0.5 * dchi2 - kc, "dchi2": dchi2, "k": kc,
                      "lr_pass": bool(dchi2 > thr), "lr_threshold": thr, "cv": False})
    if use_cv and significant and any(d["lr_pass"] for d in cands):
        base.cv, base.cv_r = F.crossval(base, folds)
        for d in cands:
            if d["lr_pass"]:
                fit = d["fit"]
                fit.cv, fit.cv_r = F.crossval(fit, folds)
                d["evidence"] = 0.5 * (base.cv - fit.cv)
                d["cv"] = True
    for d in cands:
        if use_cv and not d["cv"]:
            d["evidence"] = None
    cands.sort(key=lambda d: -(d["evidence"] if d["evidence"] is not None else -1e300))
    eligible = [d for d in cands if significant and d["lr_pass"] and d["evidence"] is not None and d["evidence"] > 0]
    findings = []
    confounded = []
    current = base
    chosen: list[Cause] = []
    if eligible:
        best = eligible[0]
        # confounding with the winner
        group = []
        for d in eligible[1:]:
            close = d["evidence"] >= best["evidence"] - 2.0
            sep = _rms(best["fit"].r - d["fit"].r)
            if close and sep < 1.0:
                group.append((d, sep))
        if group:
            seps = []
            sa = problem.state(best["fit"].values, best["fit"].causes)
            for d, sep in group:
                sb = problem.state(d["fit"].values, d["fit"].causes)
                cm = problem.candidate_measurements(sa, sb)
                seps.append({"cause": d["cause"].id, "evidence": d["evidence"], "prediction_difference_rms_sigma": sep,
                             "separating_measurement": cm[0] if cm else None})
            confounded.append({"causes": [best["cause"].id] + [d["cause"].id for d, _ in group], "pairs": seps,
                               "group_measurement": _group_measurement(problem, best, [d for d, _ in group])})
        chosen.append(best["cause"])
        current = best["fit"]
        findings.append(_finding(problem, F, base, best, folds, use_cv, confounded[0] if confounded else None))
        # 4. greedy extension while the chi-square test still fails
        while len(chosen) < max_causes and chi2_dist.sf(current.chi2, current.dof) < alpha:
            ext = []
            for d in eligible[1:4]:
                if d["cause"] in chosen:
                    continue
                if confounded and d["cause"].id in confounded[0]["causes"]:
                    continue
                fit = F.fit(tuple(chosen) + (d["cause"],))
                kc = fit.k - current.k
                if kc <= 0:
                    continue
                dchi2 = current.chi2 - fit.chi2
                thr = float(chi2_dist.ppf(1 - alpha / max(len(causes), 1), kc))
                if dchi2 <= thr:
                    continue
                if use_cv:
                    fit.cv, fit.cv_r = F.crossval(fit, folds)
                    ev = 0.5 * (current.cv - fit.cv)
                else:
                    ev = 0.5 * dchi2 - kc
                thr = float(chi2_dist.ppf(1 - alpha / max(len(causes), 1), kc))
                if dchi2 > thr and ev > 0:
                    ext.append({"cause": d["cause"], "fit": fit, "evidence": ev, "dchi2": dchi2, "k": kc, "lr_pass": True, "lr_threshold": thr})
            if not ext:
                break
            ext.sort(key=lambda d: -d["evidence"])
            nxt = ext[0]
            findings.append(_finding(problem, F, current, nxt, folds, use_cv, None))
            chosen.append(nxt["cause"])
            current = nxt["fit"]
    p_after = float(chi2_dist.sf(current.chi2, current.dof))
    if not significant:
        verdict = "no-significant-discrepancy"
    elif not findings:
        verdict = "unexplained"
    else:
        verdict = "explained" if p_after >= alpha else "partly-explained"
    result = {
        "measurement": str(getattr(problem.data, "path", "")),
        "kind": problem.kind,
        "data": problem.describe_data(),
        "method": {
            "evidence": "leave-one-group-out cross-validation (held-out chi^2)" if use_cv else "Akaike information criterion (fewer than 3 groups)",
            "groups": len(folds), "alpha": alpha,
            "claim_rule": "baseline chi-square p < alpha AND likelihood-ratio test at alpha/N_causes AND evidence > 0",
        },
        "baseline": {
            "parameters": _params(base, problem.base_params),
            "chi2": base.chi2, "dof": base.dof, "p_value": p_base,
            "residual_rms": _rms(base.r), "residual_rms_physical": problem.physical_residual_rms(base.r),
            "residual_unit": f"noise sigma (physical: {problem.unit})",
            "heldout_rms": _rms(base.cv_r) if base.cv_r is not None else None,
            "residuals": base.r, "structure": structure,
        },
        "candidates": [
            {"cause": d["cause"].id, "evidence": d["evidence"], "delta_chi2": d["dchi2"], "k": d["k"],
             "lr_threshold": d["lr_threshold"], "lr_pass": bool(d["lr_pass"]), "chi2": d["fit"].chi2,
             "heldout_rms": _rms(d["fit"].cv_r) if d["fit"].cv_r is not None else None,
             "evidence_method": ("cross-validation" if d.get("cv") else ("not cross-validated (fails the LR test or no significant discrepancy)" if use_cv else "AIC")),
             "parameters": _params(d["fit"], d["cause"].params)}
            for d in cands
        ],
        "findings": findings,
        "confounded": confounded,
        "verdict": verdict,
        "final": {"causes": [c.id for c in chosen], "chi2": current.chi2, "dof": current.dof, "p_value": p_after,
                  "residual_rms": _rms(current.r), "residuals": current.r},
        "runtime_s": time.perf_counter() - t0,
        "model_evaluations": F.nfev,
    }
    if hasattr(problem, "extracted_peaks"):
        result["extracted_peaks"] = problem.extracted_peaks
    result["summary"] = _summary(result)
    return result


def _group_measurement(problem, best, others) -> dict[str, Any] | None:
    """The extra measurements that separate *all* confounded causes.

    Each fitted model predicts every candidate observable (other modes, Q; for friction, scans at
    other speeds and loads); a pair of causes is separated by an observable when the two
    predictions differ by more than 3 noise sigma. Observables are chosen greedily (set cover)
    until every pair is separated (at most four).
    """
    sa = problem.state(best["fit"].values, best["fit"].causes)
    preds: dict[str, dict[str, float]] = {}
    sig: dict[str, float] = {}
    unit: dict[str, str] = {}
    for d in others:
        sb = problem.state(d["fit"].values, d["fit"].causes)
        for m in problem.candidate_measurements(sa, sb):
            key = m["measure"]
            preds.setdefault(key, {})[best["cause"].id] = m["a"]
            preds[key][d["cause"].id] = m["b"]
            unit[key] = m["unit"]
            if m["separation_sigma"] > 0 and abs(m["a"] - m["b"]) > 0:
                sig[key] = abs(m["a"] - m["b"]) / m["separation_sigma"]
    # greedy set cover: pick measurements until every pair is > 3 sigma apart in at least one
    names = [best["cause"].id] + [d["cause"].id for d in others]
    pairs = {(i, j) for i in range(len(names)) for j in range(i + 1, len(names))}
    sep_pairs: dict[str, set] = {}
    for key, pr in preds.items():
        if key not in sig or any(n not in pr or not np.isfinite(pr[n]) for n in names):
            continue
        sep_pairs[key] = {(i, j) for i, j in pairs if abs(pr[names[i]] - pr[names[j]]) / sig[key] > 3.0}
    chosen, left = [], set(pairs)
    while left and sep_pairs:
        key = max(sep_pairs, key=lambda k: len(sep_pairs[k] & left))
        gain = sep_pairs[key] & left
        if not gain:
            break
        chosen.append({"measure": key, "unit": unit[key], "predictions": preds[key], "separates_pairs": len(gain)})
        left -= gain
        if len(chosen) == 4:
            break
    if not chosen:
        return None
    return {"measurements": chosen, "pairs_total": len(pairs),
            "pairs_left_unseparated": [[names[i], names[j]] for i, j in sorted(left)]}


def _params(fit: FitResult, plist) -> dict[str, Any]:
    out = {}
    for p in plist:
        if p.name in fit.values:
            out[p.name] = {"value": fit.values[p.name], "sigma": fit.sigma.get(p.name, 0.0 if p.name in fit.held else None),
                           "unit": p.unit, "held": p.name in fit.held}
    return out


def _finding(problem, F, before: FitResult, cand: dict, folds, use_cv: bool, conf) -> dict[str, Any]:
    fit = cand["fit"]
    c = cand["cause"]
    derived = c.derived(fit.values, problem) if hasattr(c, "derived") else {}
    corr_warn = []
    if fit.corr is not None and len(fit.names) > 1:
        for i, j in itertools.combinations(range(len(fit.names)), 2):
            cij = fit.corr[i, j]
            if np.isfinite(cij) and abs(cij) > 0.95:
                corr_warn.append({"a": fit.names[i], "b": fit.names[j], "correlation": float(cij)})
    return {
        "cause": c.id, "title": c.title, "evidence": cand["evidence"], "delta_chi2": cand["dchi2"],
        "parameters": _params(fit, c.params), "derived": derived,
        "status": "confounded" if conf else "identified",
        "confounded_with": conf["causes"][1:] if conf else [],
        "degenerate_parameters": corr_warn,
        "gain": {
            "residual_rms_before": _rms(before.r), "residual_rms_after": _rms(fit.r),
            "heldout_rms_before": _rms(before.cv_r) if use_cv else None,
            "heldout_rms_after": _rms(fit.cv_r) if use_cv else None,
            "residual_rms_physical_before": problem.physical_residual_rms(before.r),
            "residual_rms_physical_after": problem.physical_residual_rms(fit.r),
            "p_value_after": float(chi2_dist.sf(fit.chi2, fit.dof)),
        },
    }


def _summary(res: dict[str, Any]) -> str:
    v = res["verdict"]
    b = res["baseline"]
    lines = [f"baseline: chi2 = {b['chi2']:.1f} for {b['dof']} dof (p = {b['p_value']:.2g}), residual RMS {b['residual_rms']:.2f} sigma"]
    if v == "no-significant-discrepancy":
        lines.append("no significant discrepancy: the residual is consistent with the stated noise; nothing is claimed")
    elif v == "unexplained":
        lines.append("significant discrepancy, but no catalog cause explains it out of sample")
    for f in res["findings"]:
        ps = ", ".join(f"{k} = {p['value']:.4g} ± {p['sigma']:.2g}" if p["sigma"] is not None else f"{k} = {p['value']:.4g}"
                       for k, p in f["parameters"].items())
        g = f["gain"]
        ho = (f", held-out {g['heldout_rms_before']:.2f} -> {g['heldout_rms_after']:.2f}" if g["heldout_rms_before"] is not None else "")
        lines.append(f"{f['status']}: {f['cause']} ({ps}); evidence {f['evidence']:.1f} nats; residual RMS "
                     f"{g['residual_rms_before']:.2f} -> {g['residual_rms_after']:.2f} sigma{ho}")
    for c in res["confounded"]:
        lines.append("CONFOUNDED: " + ", ".join(c["causes"]) + " explain the data equally well")
        gm = c.get("group_measurement")
        if gm:
            lines.append("  to separate them (every pair > 3 sigma apart), measure: "
                         + "; ".join(m["measure"] for m in gm["measurements"]))
            for m in gm["measurements"]:
                pv = ", ".join(f"{k} {v:.5g}" for k, v in m["predictions"].items())
                lines.append(f"    {m['measure']} predicted [{m['unit']}]: {pv}")
            if gm["pairs_left_unseparated"]:
                lines.append("  still indistinguishable: " + "; ".join(" vs ".join(p) for p in gm["pairs_left_unseparated"]))
        for p in c["pairs"]:
            m = p["separating_measurement"]
            if m:
                lines.append(f"  {c['causes'][0]} vs {p['cause']}: measure {m['measure']} "
                             f"({m['a']:.5g} vs {m['b']:.5g} {m['unit']}, {m['separation_sigma']:.1f} sigma apart)")
    lines.append(f"verdict: {v}")
    return "\n".join(lines)
