"""The statistics of ``probedyn diagnose``: calibrate, test, rank, extend, measure the gain.

A *problem* (:mod:`.modal`, :mod:`.friction`, :mod:`.forcecurve`) turns a measurement into
whitened residuals ``r(theta) = (data - model(theta)) / sigma`` of probedyn's own simulation,
where sigma is the stated noise (plus the model's own numerical error, e.g. the FEM
discretisation estimate): a correct model with correctly stated noise gives ``r ~ N(0, I)``.

1. **Baseline.** The problem's calibration parameters (``base_params``; e.g. the intrinsic Q)
   are fitted by bounded least squares (trust-region reflective) from their starts. If the data
   cannot inform them (the Jacobian is rank-deficient) the diagnosis stops with a message that
   names the degenerate combination.
   **Baseline laws** (``problem.baseline_laws``, :func:`_baseline_law`): where the simulation runs a record under
   more than one law with the same parameters (a friction record at two loads: the corrugation proportional to the
   load, or independent of it), the baseline is fitted under each and the lowest chi^2 kept; the causes are then
   constrained about that law. The law is chosen again with the lead candidate of step 3 (:func:`_law_with_cause`):
   where under another law that cause lowers ``-2 ln L`` by more than a one-parameter threshold, the diagnosis is
   run again under it (a hidden effect missing from both baselines can make the wrong one fit better).
   **Declared conditions' terms** (``problem.declared_terms``, :func:`_declared_terms`): an effect the declared
   conditions imply (thermal activation at a declared temperature) is fitted nested in the baseline and joins it
   where it lowers ``-2 ln L`` by more than its likelihood-ratio threshold; its parameters are then baseline
   parameters, and no cause to be discovered.
   **Correlated noise** (:mod:`.noise`): a problem that declares its residuals' recording
   ``sequences`` has the noise's lag-one correlation estimated from the baseline residuals (a stated
   marginal sigma against the residuals' high-frequency scatter; without a stated noise the first
   against the second differences, judged on the best nested candidate's residuals after step 3,
   checked by their lag-one correlation); where both exceed their white-noise gates the noise is taken
   as AR(1) and every fit from there on, the baseline's included, uses the whitened (innovation)
   residuals: generalised least squares, so that steps 2-7 hold for correlated noise too.
2. **Is anything wrong?** Two routes. The *omnibus* test: ``chi2_base ~ chi2(n - k)`` under the baseline,
   p-value below ``alpha`` (1 %). The *targeted* test: some catalog cause's likelihood-ratio test (step 3,
   at ``alpha / N``) passes. A claim needs the targeted test in any case, and under the baseline the chance
   that any of the N causes passes it is at most ``alpha`` (Bonferroni): with correctly stated noise the
   false-discovery rate of the whole procedure is at most ``alpha`` per measurement, whatever the catalog.
   The omnibus test alone has little power against one strong direction among many degrees of freedom
   (session 34's own modal seed 1031: air undeclared on a long lever, fluid loading gaining ``Delta chi2`` 15 for
   2 parameters while the baseline's chi-square of 13 modes and Q had p = 0.018); a discrepancy the targeted test alone
   found, with no claim, is not reported as one (``no-significant-discrepancy``, the test named).
   The Bonferroni bound holds when the baseline's residuals are N(0, I) under the null, i.e. when the
   likelihood carries the model's own error; a model-form misfit concentrated in one direction passes a
   likelihood-ratio test as a cause would. Only a problem with ``model_error_in_likelihood`` opens the
   targeted route: the modal one (its FEM discretisation estimate, the 1D-3D and hydrodynamic model-form
   directions), so the modal records and the spectra's lines, and a force curve whose noise is declared (its
   contact mechanics solved on the exact branch; session 44). Elsewhere the omnibus test stays the gate
   (measured: with the route open, a Coulomb friction loop at two loads and a force curve under flicker noise
   read from the record, both nulls, were "explained" by a cause).
3. **Candidate causes (nested fits).** Every applicable cause is fitted *together with* the
   baseline parameters, **starting from the baseline optimum with its own parameters at their
   null values** (where the extended model *is* the baseline), plus its declared extra starts.
   The trust-region method only accepts steps that lower chi^2, and the best start is kept, so
   ``chi2_cause <= chi2_base`` by construction (checked: if round-off ever gives more, the
   null solution is returned). The likelihood-ratio test ``Delta chi2 > chi2_k(1 - alpha / N)``
   (Bonferroni over the N causes tried) must pass.
4. **Evidence out of sample.** Leave-one-group-out cross-validation (groups: modes, scan
   halves, curve segments; K-fold with K = 8 above 10 groups): every fold refits the baseline
   and the nested cause *from their null starts* on the training groups (no information of the
   held-out group enters) and predicts the held-out group. ``evidence = (CV_base - CV_cause)/2``
   nats, **capped at** ``Delta chi2 / 2``: the in-sample log likelihood ratio at the maximum is an
   upper bound of any Bayes factor for the cause (for every prior, the marginal likelihood is
   below the maximum likelihood), so held-out evidence can never exceed what the data carry.
   A problem with ``heldout_predictive`` (modal, spectra) scores a held-out group by its
   predictive density, the fold's parameter uncertainty included (:meth:`CrossValidation.heldout`):
   a group that alone informs a parameter is not held to a value the other groups' noise set.
   With fewer than three groups: ``evidence = Delta chi2 / 2 - k`` (Akaike).
   A cause whose cap is below the best evidence so far minus the margin is not cross-validated
   (it can neither win nor be confounded), except a limit of a passing container, which the
   parsimony rule below may still hand the lead (:func:`_score_in_order`).
   Claimed: the discrepancy of step 2, LR test passed, evidence > 0.
5. **Confounding.** Every claimed cause within ``EVIDENCE_MARGIN`` = ln 10 = 2.30 nats (a Bayes
   factor of 10, Jeffreys' "strong") of the winner is *confounded* with it; the problem
   predicts extra observables for each fitted model and the separating measurements are named.
   So is every cause with positive evidence within the margin that failed its own likelihood-ratio test
   (not claimed, named so in the group, never the leader; a cause containing the winner as a limit is not one).
   A problem with ``rank_by_heldout`` (modal) ranks the claimed causes and judges confounding by
   the uncapped held-out evidence: the cap bounds each cause against the baseline, and when
   several causes reach it, it would rank only their in-sample fits. A held-out difference is a
   sum over the folds and has a standard error (``sqrt(n_folds var)`` of the per-fold differences of
   the two causes' held-out chi^2, halved); a rival is also confounded while its held-out deficit is
   within ``HELDOUT_SE_FACTOR`` = 2 of those standard errors (the difference is not resolved by the
   folds: Vehtari, Gelman & Gabry 2017, LOO comparison by ``elpd_diff`` against its ``se_diff``)
   *and* its in-sample Akaike deficit is within the margin (with a handful of folds one badly
   predicted group inflates that standard error; then the in-sample fits must not separate them
   either). Between two limits of one container (JKR and DMT under Maugis-Dugdale), ranked in sample
   by the parsimony rule (:func:`_parsimony`; also when a limit leads with the container within the
   margin behind it), the other limit is also confounded while its in-sample Akaike score is within
   the margin (near a jump their held-out evidence scatters by several nats). A problem with
   ``occam_within_group`` (modal, spectra) names the group's cause with the fewest parameters first
   (:func:`_fewest_parameters_lead`): within the margin the order is the folds' scatter.
6. **Extend** greedily while the extended model still fails the chi^2 test (at most
   ``max_causes``, each nested in the current model and passing the same tests). On a
   ``heldout_predictive`` problem an extension's evidence is also capped by the **plain** held-out
   error ``(e^T e of the chain - e^T e of chain + cause) / 2``: the predictive density forgives a
   parameter that only the held-out group informs, which is right against the baseline (whose model
   error the noise model carries: discretisation, model form) but not after a claimed cause, whose
   own model error has no stated size -- a second cause supported by one group at a time is not
   separable from that error (session 15: it removes the four second findings the predictive score
   had added on single-effect truths; docs/diagnose.md §6.v).
7. **Gain.** The final model is re-solved with the full model where the fits used a reduced
   one (modal: the FEM; defect-corrected refit if the reduction's error exceeds 0.3 sigma), and
   the residual, held-out residual and chi^2 after are computed from that.

**Uncertainties.** From the Jacobian at the optimum (SVD with column scaling, scaled by
``sqrt(chi2/dof)`` when that exceeds 1) when it is well conditioned; for a parameter at a bound,
a parameter whose 1-sigma interval crosses a bound, or a poorly conditioned direction
(reciprocal condition below 1e-6), from the **profile likelihood** (the interval where
``Delta chi2 <= 1`` with all other parameters refitted). If the profile does not rise by 1 within
the bounds on either side the parameter is reported **not identifiable** (no number).

**Verdicts** (numbers, no judgement):

* ``no-significant-discrepancy``: nothing is claimed and the baseline's p >= alpha;
* ``unexplained``: baseline p < alpha, no cause claimed;
* ``confounded``: the winner has a claimed rival within the margin (never also "explained");
* ``explained``: winner unique, final model p >= alpha in sample **and** its held-out residuals
  consistent with the noise (leverage-corrected held-out statistic ``sum_g e_g^T (I - H_gg) e_g``,
  of expectation n under a correct model, below the chi2_n quantile 1 - alpha), no fitted
  parameter at a bound that binds and every parameter identifiable;
* ``partly-explained``: a cause is claimed but one of those conditions fails (each failure is
  listed in ``verdict_reasons``; a parameter at a bound is flagged on the finding).

A bound **binds** when lifting it would gain more than ``chi2_1(1 - alpha)`` (the score statistic of the
linearised fit, :func:`_bound_gain`): the data then push the parameter past the edge of its physical range,
and the verdict is lowered. A bound that does not bind is an estimate equal to the bound within the noise (a
clamp's translational compliance at its null value 0 on a truth without one; a point mass at the free end);
it is stated in the finding's ``notes`` with its gain and does not lower the verdict.
"""

from __future__ import annotations

import itertools
import math
import multiprocessing
import os
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np
from scipy.optimize import OptimizeWarning, brentq, least_squares
from probedyn.diagnose.tails import chi2 as chi2_dist, norm as norm_dist

from probedyn.core.errors import DataFormatError
from probedyn.core.registry import RegistryError
from probedyn.diagnose.causes import Cause, CauseParam
from probedyn.diagnose.noise import MIXTURE, AR1Whitener, MixtureWhitener, SequenceScale, noise_correlation

__all__ = ["diagnose", "Fit", "Fitter", "ALPHA", "EVIDENCE_MARGIN", "run"]

ALPHA = 0.01
EVIDENCE_MARGIN = math.log(10.0)
#: a rival whose held-out deficit is within this many standard errors of the paired per-fold
#: differences is confounded with the leader (``rank_by_heldout`` problems; module docstring, step 5)
HELDOUT_SE_FACTOR = 2.0
MAX_STARTS = 6
#: a profile sweep (Fitter.swept) gives up on a direction after this many steps without a new lowest chi^2
#: (blind f07's profile rises for two steps of 0.1 decade before its deeper basin), and takes at most SWEEP_MAX
SWEEP_PATIENCE = 4
SWEEP_MAX = 30
#: the least chi^2 gain for which a profile sweep's basin replaces the fit's own: the likelihood-ratio threshold
#: of one parameter at ALPHA (chi2_1 quantile 1 - ALPHA = 6.63)
SWEEP_GAIN = float(chi2_dist.isf(ALPHA, 1))


# ------------------------------------------------------------------------------------------
# Parameter coordinates
# ------------------------------------------------------------------------------------------


def _span(p: CauseParam) -> float:
    return (p.hi - p.lo) if p.scale == "lin" else 1.0


def _to_u(p: CauseParam, v: float) -> float:
    """Internal coordinate: lin -> value / span (order one), log -> log10(value)."""
    return math.log10(v) if p.scale == "log" else v / _span(p)


def _from_u(p: CauseParam, u: float) -> float:
    return 10.0**u if p.scale == "log" else u * _span(p)


def _u_bounds(p: CauseParam) -> tuple[float, float]:
    return _to_u(p, p.lo), _to_u(p, p.hi)


def _at_bound(p: CauseParam, u: float, rel: float = 1e-6) -> str | None:
    """``"lower"`` or ``"upper"`` where the internal coordinate ``u`` is within ``rel`` of the range of that bound."""
    lo_u, hi_u = _u_bounds(p)
    tol = rel * (hi_u - lo_u)
    return "lower" if u <= lo_u + tol else "upper" if u >= hi_u - tol else None


@dataclass
class Fit:
    """A least-squares fit of the baseline extended by ``causes``."""

    causes: tuple
    plist: list[CauseParam]
    u: np.ndarray
    values: dict[str, float]
    r: np.ndarray  # whitened residuals on all data
    chi2: float  # on the fitted mask
    n: int
    J: np.ndarray | None = None  # d r[mask] / d u at the optimum
    nfev: int = 0
    mask: np.ndarray | None = None
    cv: float | None = None
    cv_r: np.ndarray | None = None
    start: str = ""
    nuisance: Any = None
    cv_fold: np.ndarray | None = None  # per fold: -2 ln(held-out predictive density) + const
    #: the log-determinant of the variance the model carries of its own, relative to the noise's (``-2 ln L`` beyond
    #: chi^2 where it depends on the parameters: a friction record's activated slip scatter, Fitter.var_rows)
    logdet: float = 0.0
    #: that variance's rows (``Fitter.var_rows``) on all data at the optimum, their squares ``ln(1 + var / sigma^2)``
    #: (plus the record's constant): a held-out group's share of ``-2 ln`` its predictive density (CrossValidation)
    var_rows: np.ndarray | None = None
    #: per swept parameter (:meth:`Fitter.swept`), the profile points its walk evaluated: ``(value, -2 ln L)`` with the
    #: other parameters refitted (parameter_report's interval over them, where the profile is rugged)
    profile: dict[str, list[tuple[float, float]]] | None = None

    @property
    def k(self) -> int:
        return len(self.plist)

    @property
    def score(self) -> float:
        """``-2 ln L`` up to a constant: chi^2 and the model's own variance's log-determinant (:attr:`logdet`). Fits
        are compared, and their optima found, by it; the chi-square tests read :attr:`chi2`."""
        return self.chi2 + self.logdet

    @property
    def dof(self) -> int:
        return max(self.n - self.k, 1)

    @property
    def p_value(self) -> float:
        return float(chi2_dist.sf(self.chi2, self.dof))

    def as_start(self, **values: float) -> dict[str, Any]:
        """A start at this optimum (``values`` replacing some of it), its profiled nuisance included."""
        st: dict[str, Any] = {**self.values, **values}
        if self.nuisance is not None:
            st["__nuisance__"] = self.nuisance
        return st


def _score(fit) -> float:
    """A fit's ``-2 ln L`` up to a constant (:attr:`Fit.score`; chi^2 where the object carries no log-determinant)."""
    return float(fit.chi2) + float(getattr(fit, "logdet", 0.0))


def _inactive_rows(problem, values, causes) -> int:
    """Rows of the residual vector that are zero by construction in this model (a problem's
    ``inactive_rows``: e.g. the prior pseudo-residual of a model-form direction the model does not have,
    such as a fluid's in a model without one): neither data nor a fitted amplitude, so not counted in n."""
    f = getattr(problem, "inactive_rows", None)
    return int(f(values, causes)) if f is not None else 0


#: processes for a problem's independent fits (candidate causes, cross-validation folds, screened starts, a sweep's
#: two directions), forked from the diagnosis (``problem.workers``; :class:`Fitter`). Each job's result is the one the
#: parent computes in turn (the modal example: every number of the report equal, docs/diagnose.md 9.62); a machine with
#: fewer cores gets fewer.
WORKERS = 2


class Fitter:
    """Least-squares fits of a problem's baseline and its nested extensions.

    Independent fits go through a pool of ``problem.workers`` forked processes when the problem asks
    for one (friction: every evaluation is an integration), else one after the other: the candidate
    causes and the cross-validation folds (:meth:`map_nested`), a multi-start fit's screened starts and
    the starts it runs on (:meth:`map_fits`), a profile sweep's two directions (:meth:`swept`) and a
    problem's own independent evaluations (:meth:`map_calls`, ``problem.parallel``: friction's ridges
    of starts). A problem may remember what it profiled per model (friction: the lattice registry, so
    that a model gives the same residuals whichever fit reached it). Every map forks its pool from the
    parent as it stands (:meth:`_fresh_pool`), every job starts from the memory as its worker forked,
    and the parent merges what each job added in the jobs' order: a map's results do not depend on
    which worker ran which job. They can differ from the same fits made in one process only where a job
    meets a model that an earlier job of the same map profiled: the three-scan friction example and
    blind f05 give one process's results, and the 24 blind friction records session 64's
    (docs/diagnose.md 9.50)."""

    def __init__(self, problem) -> None:
        self.problem = problem
        self.nfev = 0
        self._pool = None
        self._pool_used = False
        self.white = None  # an AR1Whitener once the noise is found correlated (:mod:`.noise`)
        if hasattr(problem, "parallel"):  # a problem's independent evaluations go through the pool (map_calls)
            problem.parallel = self.map_calls

    def _workers(self) -> int:
        w = int(getattr(self.problem, "workers", 1) or 1)
        return max(1, min(w, os.cpu_count() or 1))

    def open_pool(self) -> None:
        """Fork the worker processes now (they inherit the problem as it is at this moment)."""
        global _POOL_FITTER
        if self._pool is None and self._workers() > 1 and "fork" in multiprocessing.get_all_start_methods():
            _POOL_FITTER = self
            self._pool = ProcessPoolExecutor(self._workers(), mp_context=multiprocessing.get_context("fork"),
                                             initializer=_pool_worker_init, initargs=(os.getpid(),))
            self._pool_used = False

    def close_pool(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def _fresh_pool(self):
        """The pool for the next map: forked again if it has run a map since it forked, so that every map's workers
        start from the parent as it stands (the problem's memory of what it profiled included; the pool forks at
        its first job). The fork costs a few tens of milliseconds."""
        if self._pool is not None and self._pool_used:
            self.close_pool()
            self.open_pool()
        self._pool_used = True
        return self._pool

    def map_nested(self, jobs: list[tuple]) -> list["Fit"]:
        """``jobs``: ``(ref, new_causes, mask[, warm[, only_starts]])`` (a nested fit) or ``(None, (), mask[, warm])``
        (the baseline), see :func:`_run_job`. Returns the fits in order."""
        if self._pool is None or len(jobs) < 2:
            return [_run_job(self, j) for j in jobs]
        by_key = _by_key(self.problem)
        # a full-data nested fit's data-derived starts are made here, where the problem can spread their ranking
        # over the workers (map_calls; the lattice misalignment's ridge and period profiles were a third of the
        # three-scan example's run time, in one worker while the other waited)
        extra = [self.nested_starts(j[0], tuple(j[1])) if (j[0] is not None and j[2] is None and
                 (len(j) < 4 or j[3] is None) and (len(j) < 5 or j[4] is None)) else None for j in jobs]
        packed = [(j[0], tuple(c.key for c in j[1]), j[2], j[3] if len(j) > 3 else None,
                   j[4] if len(j) > 4 else None, x) for j, x in zip(jobs, extra)]
        out = _merged(self, _longest_first(self._fresh_pool(), _pool_job, packed,
                                           [self._job_cost(j, x) for j, x in zip(jobs, extra)]))
        for fit in out:
            fit.causes = tuple(by_key.get(c.key, c) for c in fit.causes)  # the parent's cause objects
        return out

    def _job_cost(self, job: tuple, extra: list | None) -> float:
        """A :meth:`map_nested` job's cost, for the order the pool takes the jobs in (:func:`_longest_first`): the
        starts the fit will run (:meth:`nested`: the null start, the declared ones, the data-derived ones), each
        weighted by the free parameters it fits. The folds' warm-started jobs are costed alike (they are alike: their
        order matters little). A guess, which decides only when a job starts, not what it computes."""
        ref, new = job[0], tuple(job[1])
        if ref is None:
            return float(len(self.base_starts()) * (1 + len(self.problem.base_params)))
        new = tuple(c for c in new if c not in ref.causes)
        only = job[4] if len(job) > 4 else None
        n = 1 + (len(_start_sets(new, ref.values)[: getattr(self.problem, "max_starts", MAX_STARTS)])
                 if only is None else len(only)) + len(extra or ())
        return float(n * (1 + len(ref.plist) + sum(len(c.params) for c in new)))

    def map_fits(self, jobs: list[tuple]) -> list["Fit"]:
        """Least-squares runs ``(causes, starts, mask, fixed, max_nfev, rounds)`` (:meth:`_fit`): a fit's screened
        starts, the starts it then runs to convergence. In the pool where one is open (the parent's phases with one
        model: a declared term's test, the candidates), else in turn; the same fits either way."""
        if self._pool is None or len(jobs) < 2:
            return [self._run_fit(*j) for j in jobs]
        by_key = _by_key(self.problem)
        packed = [(tuple(c.key for c in j[0]), *j[1:]) for j in jobs]
        out = _merged(self, self._fresh_pool().map(_pool_fit, packed))
        for fit in out:
            fit.causes = tuple(by_key.get(c.key, c) for c in fit.causes)
        return out

    def _run_fit(self, causes, starts, mask, fixed, max_nfev, rounds) -> "Fit":
        """One :meth:`_fit` job of :meth:`map_fits`, the problem's training mask set as :meth:`fit` sets it."""
        plist = list(self.problem.base_params) + [p for c in causes for p in c.params]
        free = [p for p in plist if p.name not in fixed]
        had = hasattr(self.problem, "train_mask")
        old = self.problem.train_mask if had else None
        if had:
            self.problem.train_mask = mask
        try:
            return self._fit(tuple(causes), starts, mask, fixed, max_nfev, plist, free, rounds)
        finally:
            if had:
                self.problem.train_mask = old

    def map_calls(self, method: str, items: list[tuple], causes: tuple) -> list:
        """``problem.<method>(*item, causes)`` for every item: in the pool where one is open, else in turn. The
        problem's way to spread independent evaluations (a ridge of starts ranked by chi^2, the profiles of the
        kept ones: :meth:`FrictionProblem.nested_starts`) over the workers; set as ``problem.parallel``."""
        if self._pool is None or len(items) < 2:
            return [getattr(self.problem, method)(*it, tuple(causes)) for it in items]
        keys = tuple(c.key for c in causes)
        return _merged(self, self._fresh_pool().map(_pool_call, [(method, it, keys) for it in items]))

    def residuals(self, values: dict[str, float], causes, mask=None) -> np.ndarray:
        """The problem's whitened residuals; with correlated noise (``self.white``) whitened over the
        sequences, the rows in ``mask`` (a fit's training data) over their own samples only."""
        self.nfev += 1
        r = np.asarray(self.problem.residuals(values, tuple(causes)), float)
        r = np.where(np.isfinite(r), r, 1e6)
        return r if self.white is None else self.white(r, mask)

    def var_rows(self, mask=None) -> np.ndarray | None:
        """Where the model carries a variance of its own that its parameters set (``problem.variance_in_objective``:
        a friction record's activated slip scatter), the rows ``sqrt(ln(1 + var / sigma^2))`` of the model the last
        :meth:`residuals` evaluated (``problem.variance_rows``), on ``mask``; None elsewhere. Their squares' sum is the
        part of ``-2 ln L`` that chi^2 leaves out: a least-squares fit of chi^2 alone lowers it by widening the
        variance (blind friction set 2's g16: an overdamped tip's slip scatter, its viscous coefficient 1.3-2.3
        times the generator's on chi^2, within 0.7-1.3 on chi^2 with the log-determinant; docs/diagnose.md 9.57)."""
        prob = self.problem
        if not getattr(prob, "variance_in_objective", False):
            return None
        e = np.asarray(prob.variance_rows(), float)
        return e if mask is None else e[mask]

    def logdet(self, mask=None) -> float:
        """The sum of :meth:`var_rows`' squares (0 where there are none): :attr:`Fit.logdet` of the model the last
        :meth:`residuals` evaluated."""
        e = self.var_rows(mask)
        return float(np.sum(e**2)) if e is not None else 0.0

    def fit(self, causes, starts: list[dict[str, float]], mask=None, fixed: dict[str, float] | None = None,
            max_nfev: int | None = None) -> Fit:
        """Best of the least-squares fits from ``starts`` (each a full value dict)."""
        causes = tuple(causes)
        plist = list(self.problem.base_params) + [p for c in causes for p in c.params]
        fixed = dict(fixed or {})
        free = [p for p in plist if p.name not in fixed]
        best: Fit | None = None
        if hasattr(self.problem, "train_mask"):
            self.problem.train_mask = mask  # nuisance profiling (e.g. lattice registry) sees training data only
        try:
            return self._fit(causes, starts, mask, fixed, max_nfev, plist, free)
        finally:
            if hasattr(self.problem, "train_mask"):
                self.problem.train_mask = None

    def _fit(self, causes, starts, mask, fixed, max_nfev, plist, free, rounds: int = 3) -> Fit:
        """Least squares from every start. A problem with a nuisance that is profiled rather than
        fitted (``problem.nuisance(values, causes)``, e.g. the lattice registry of friction scans)
        holds it fixed during each least-squares run and re-profiles it between runs (at most three
        rounds; a re-profiled nuisance is kept only if it lowers chi^2).

        Screening (a problem declaring ``screen_nfev``, e.g. friction, where one evaluation is an
        integration): with several starts, each start first gets ``screen_nfev`` evaluations (one
        round), and the best of them is run to convergence; so is every runner-up, up to
        ``screen_keep`` starts in all, whose screened chi^2 is within the fraction ``screen_margin``
        of the best's (a screen of a few evaluations cannot rank starts that close: friction
        seed 2047). The null start is among the screened ones, so the nested-fit guarantee is
        unchanged."""
        prob = self.problem
        screen = getattr(prob, "screen_nfev", None)
        if screen and len(starts) > 1 and free and max_nfev is None:
            scored = self.map_fits([(causes, [st], mask, fixed, screen, 1) for st in starts])
            for si, f in enumerate(scored):
                f.start = str(si)
            ranked = sorted(scored, key=lambda f: f.score)
            margin = getattr(prob, "screen_margin", 0.0)
            kept = [f for f in ranked[: max(1, getattr(prob, "screen_keep", 1))]
                    if f.score <= (1.0 + margin) * ranked[0].score]
            best_g: Fit | None = None
            runs = self.map_fits([(causes, [f_s.as_start()], mask, fixed, None, rounds) for f_s in kept])
            for f_s, g in zip(kept, runs):
                g.start = f_s.start
                g = g if g.score <= f_s.score else f_s
                if best_g is None or g.score < best_g.score:
                    best_g = g
            return best_g
        has_nu = hasattr(prob, "nuisance")
        diff_step = getattr(prob, "diff_step", 1e-5)
        cap = max_nfev or getattr(prob, "nfev_per_param", 100) * (len(free) + 1)
        best: Fit | None = None
        lo = np.array([_u_bounds(p)[0] for p in free])
        hi = np.array([_u_bounds(p)[1] for p in free])
        m_all = None
        for si, st in enumerate(starts):
            # a start that leaves a parameter out (a problem's data-derived start written before the
            # cause gained it) starts it at its null value
            vals0 = {**{p.name: p.null for p in plist}, **st, **fixed}
            nu0 = st.get("__nuisance__") if isinstance(st, dict) else None
            vals0.pop("__nuisance__", None)
            if has_nu:
                prob.fixed_nuisance = nu0 if nu0 is not None else prob.nuisance(vals0, causes)
            if not free:
                r = self.residuals(vals0, causes, mask)
                ld = self.logdet(mask)
                vr = self.var_rows()
                m = np.ones(len(r), bool) if mask is None else mask
                f = Fit(causes, plist, np.array([]), dict(vals0), r, float(np.sum(r[m] ** 2)),
                        int(m.sum()) - _inactive_rows(prob, vals0, causes), np.zeros((int(m.sum()), 0)), 1, m,
                        logdet=ld, var_rows=vr)
                f.nuisance = prob.fixed_nuisance if has_nu else None
                if has_nu:
                    prob.fixed_nuisance = None
                return f
            u0 = np.clip(np.array([_to_u(p, vals0[p.name]) for p in free]), lo, hi)

            rows = {"n": None}  # the residuals' rows of the objective (the variance's follow them: var_rows)

            def fun(u, _free=free, _fixed=fixed, _m=mask):
                v = {p.name: _from_u(p, x) for p, x in zip(_free, u)}
                v.update(_fixed)
                r = self.residuals(v, causes, _m)
                r = r if _m is None else r[_m]
                rows["n"] = len(r)
                e = self.var_rows(_m)
                return r if e is None else np.concatenate([r, e])

            res = None
            for _round in range(rounds if has_nu else 1):
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", OptimizeWarning)
                        res = least_squares(fun, u0, bounds=(lo, hi), method="trf", x_scale="jac", diff_step=diff_step,
                                            max_nfev=cap, xtol=1e-10, ftol=1e-10)
                except ValueError:
                    res = None
                    break
                if not has_nu:
                    break
                c_old = float(np.sum(res.fun**2))
                old = prob.fixed_nuisance
                v = {p.name: _from_u(p, x) for p, x in zip(free, res.x)}
                v.update(fixed)
                prob.fixed_nuisance = prob.nuisance(v, causes)
                c_new = float(np.sum(fun(res.x) ** 2))
                if not c_new < c_old * (1 - 1e-6):
                    prob.fixed_nuisance = old
                    break
                u0 = res.x
            if res is None:
                continue
            c2 = float(np.sum(res.fun**2))
            if best is None or c2 < best.chi2 - 1e-12 * max(1.0, abs(c2)):
                v = {p.name: _from_u(p, x) for p, x in zip(free, res.x)}
                v.update(fixed)
                n = rows["n"] - _inactive_rows(prob, v, causes)
                best = Fit(causes, free, res.x.copy(), v, None, c2, n, res.jac[: rows["n"]].copy(), res.nfev, mask,
                           start=str(si))
                best.nuisance = prob.fixed_nuisance if has_nu else None
        if best is None:
            raise DataFormatError("the fit failed from every start (the model cannot be evaluated at the starting values)")
        if has_nu:
            prob.fixed_nuisance = best.nuisance
        try:
            best.r = self.residuals(best.values, causes, mask)
            ld = self.logdet(mask)
            best.var_rows = self.var_rows()
        finally:
            if has_nu:
                prob.fixed_nuisance = None
        m = np.ones(len(best.r), bool) if mask is None else mask
        best.mask = m
        best.chi2 = float(np.sum(best.r[m] ** 2))
        best.logdet = ld
        return best

    def jacobian(self, fit: Fit, step: float = 1e-4) -> np.ndarray:
        """``d r / d u`` on every row at ``fit``'s optimum, the problem seeing ``fit.mask`` as its
        training data (central differences, one-sided at a bound)."""
        prob = self.problem
        has_tm, has_nu = hasattr(prob, "train_mask"), hasattr(prob, "nuisance")
        if has_tm:
            prob.train_mask = fit.mask
        if has_nu:
            prob.fixed_nuisance = fit.nuisance
        try:
            cols = []
            for j, p in enumerate(fit.plist):
                lo, hi = _u_bounds(p)
                a, b = max(fit.u[j] - step, lo), min(fit.u[j] + step, hi)
                rs = []
                for x in (a, b):
                    v = dict(fit.values)
                    v[p.name] = _from_u(p, x)
                    rs.append(self.residuals(v, fit.causes, fit.mask))
                cols.append((rs[1] - rs[0]) / (b - a))
            return np.array(cols).T if cols else np.zeros((len(fit.r), 0))
        finally:
            if has_tm:
                prob.train_mask = None
            if has_nu:
                prob.fixed_nuisance = None

    # -- nested fits ------------------------------------------------------------------------
    def base_starts(self) -> list[dict[str, float]]:
        ps = list(self.problem.base_params)
        if not ps:
            return [{}]
        combos = itertools.product(*[[p.null, *p.starts] for p in ps])
        return [dict(zip([p.name for p in ps], c)) for c in itertools.islice(combos, MAX_STARTS)]

    def baseline(self, mask=None) -> Fit:
        return self.fit((), self.base_starts(), mask)

    def registered(self, f: Fit, new: tuple, rounds: int = 3) -> Fit:
        """A full-data fit re-fitted from the problem's ``registration_starts`` around its optimum (its
        optimum moved by whole sample intervals in a registration parameter, e.g. a force curve's contact
        point), from the best one again while that lowers chi^2 (at most ``rounds`` times). Called for
        whitened fits only: on AR(1) innovations a predicted jump's position relative to the samples is
        weighed sharply, and the misfit is rugged at the sample spacing (docs/diagnose.md 9.28); on white
        residuals a scan of the rate cases found no such minima (9.27)."""
        starts_of = getattr(self.problem, "registration_starts", None)
        if starts_of is None:
            return f
        for _ in range(rounds):
            starts = starts_of(dict(f.values), tuple(f.causes), tuple(new))
            if not starts:
                break
            g = self.fit(f.causes, starts)
            if not g.score < f.score - 1e-9 * max(1.0, f.score):
                break
            g.start = "registration"
            f = g
        return f

    def swept(self, f: Fit, new: tuple, claimed: bool = False) -> Fit:
        """A full-data fit walked along the profile of each new parameter that declares a ``sweep`` step
        (:class:`~probedyn.diagnose.causes.CauseParam`), then refitted free from the best point found. With
        ``claimed`` only the parameters whose sweep waits for a claim (``sweep_claimed``; :func:`_sweep_claim`),
        without it only the others (every candidate's full-data fit, :meth:`nested`).

        Where the misfit is rugged along a parameter (an attempt frequency moves every activated slip across
        the samples, so the chi^2 of a stick-slip record jumps between basins a few tenths of a decade apart),
        a local optimiser from the declared starts stops in the first basin: blind f07 (50 K) ended at
        log10 f0 3.47 with chi^2 655 where the profile has 611 at 4.27 (generator 4.67; docs/diagnose.md 9.42).
        The sweep steps away from the optimum both ways, each point a fit of the other parameters with this
        one held, started from the previous point's optimum (its nuisance included), and gives up on a
        direction after :data:`SWEEP_PATIENCE` steps without a new lowest chi^2 (at most :data:`SWEEP_MAX`
        steps). The free refit from the lowest point is kept only if it lowers chi^2 by more than
        :data:`SWEEP_GAIN`, so never worse than ``f``: a basin within it is inside the parameter's confidence
        region at the engine's alpha, as consistent with the data as the one the fit reached, and on a flat rugged
        profile the lowest basin is the noise's (blind f13: 0.4 decade for a chi^2 lower by 0.36, held out
        worse by 37).

        A declared term's sweep (``Cause.declared``, :func:`_test_term`) counts a point as a new lowest only when it
        is lower by more than ``SWEEP_GAIN (phi - 1)``, ``phi = chi^2 / dof`` of the fit being swept: the term is
        taken only where its gain exceeds the excess ``chi^2 - dof`` the model leaves, and where a hidden effect
        leaves the model ``phi`` times the noise, steps smaller than that are the model error's, not basins (the
        three-scan example at 0.01 K, a hidden viscous friction: chi^2 2.26e6 on 1735, the activation's profile fell by
        200-500 per 0.1 decade for 16 steps, 24 fits, 35 s, and the term was not taken). At ``phi <= 1`` the rule
        is the causes' own."""
        phi = f.chi2 / max(f.dof, 1)  # the misfit's excess over the noise (the chi-square's own)
        tol = SWEEP_GAIN * max(phi - 1.0, 0.0) if any(getattr(c, "declared", False) for c in new) else 0.0
        for p in [p for c in new for p in c.params if p.sweep > 0 and p.sweep_claimed == claimed]:
            # a relative sweep's step is the log of its factor (_sweep_points walks it geometrically)
            du = math.log1p(p.sweep) if p.sweep_relative else p.sweep if p.scale == "log" else p.sweep / _span(p)
            if self._pool is not None:
                # both directions at once: the second is walked with its own lowest, which walks at least as far as
                # the lowest of both would (a point that is a new lowest of both is one of its own), and the walk in
                # turn is replayed over the points (_sweep_replay): the same sweep, in the time of the longer walk
                keys, fk = tuple(c.key for c in f.causes), replace(f, causes=())  # causes by key
                jobs = [(keys, fk, p.name, step, tol, f.score) for step in (du, -du)]
                walks = _merged(self, self._fresh_pool().map(_pool_sweep, jobs))
                best_c, best_st = _sweep_replay(walks[1], *_sweep_replay(walks[0], f.score, None, tol), tol)
            else:
                walks = [self._sweep_points(f, p.name, du, tol, f.score)]
                best_c, best_st = _sweep_replay(walks[0], f.score, None, tol)
                walks.append(self._sweep_points(f, p.name, -du, tol, best_c))
                best_c, best_st = _sweep_replay(walks[1], best_c, best_st, tol)
            # every point walked is a point of the profile (the others refitted at the value held)
            f.profile = dict(f.profile or {}, **{p.name: [(float(f.values[p.name]), float(f.score))] + [
                (float(st[p.name]), float(c2)) for w in walks for c2, st in w]})
            if best_st is None:
                continue
            h = self.fit(f.causes, [best_st])
            if h.score < f.score - SWEEP_GAIN:
                h.start = f"{f.start}+sweep"
                h.profile = {**f.profile, p.name: f.profile[p.name] + [(float(h.values[p.name]), float(h.score))]}
                f = h
        return f

    def _sweep_points(self, f: Fit, name: str, step: float, tol: float, best_c: float) -> list[tuple[float, dict]]:
        """One direction of :meth:`swept`: the fits with parameter ``name`` held at ``step`` after ``step`` (in its
        fitting coordinate; for a ``sweep_relative`` parameter the log of the factor each step multiplies it by) from
        ``f``'s optimum, each started from the previous one's, until :data:`SWEEP_PATIENCE`
        points in a row are no new lowest below ``best_c`` (by more than ``tol``), :data:`SWEEP_MAX` steps or the
        bound. Returns ``(chi^2, start at the point)`` per point."""
        j = next(i for i, q in enumerate(f.plist) if q.name == name)
        p = f.plist[j]
        lo, hi = _u_bounds(p)
        out: list[tuple[float, dict]] = []
        g, u, misses, k = f, f.u[j], 0, 0
        if p.sweep_relative and not u > 0:  # at the null: no scale to walk by
            return out
        while misses < SWEEP_PATIENCE and k < SWEEP_MAX:
            u, k = (u * math.exp(step) if p.sweep_relative else u + step), k + 1
            if not lo <= u <= hi:
                break
            held = {p.name: _from_u(p, u)}
            g = self.fit(f.causes, [g.as_start(**held)], fixed=held)
            out.append((g.score, g.as_start()))
            if g.score < best_c - 1e-9 * max(1.0, best_c):
                misses = 0 if g.score < best_c - tol else misses + 1
                best_c = g.score
            else:
                misses += 1
        return out

    def nested_starts(self, ref: Fit, new: tuple, mask=None) -> list[dict]:
        """The problem's data-derived starts of ``new`` nested in ``ref`` (``problem.nested_starts``; none if it
        offers none)."""
        extra = getattr(self.problem, "nested_starts", None)
        new = tuple(c for c in new if c not in ref.causes)
        return [dict(x) for x in extra(dict(ref.values), tuple(ref.causes), new, mask)] if extra is not None else []

    def nested(self, ref: Fit, new: tuple, mask=None, only_starts: list[int] | None = None,
               extra_starts: list[dict] | None = None) -> Fit:
        """Fit ``ref.causes + new`` starting from ``ref`` with the new parameters at their null
        values, plus the new causes' declared starts (``only_starts``: indices of the declared
        start combinations to use); never worse than ``ref``. ``extra_starts``: the data-derived starts
        (:meth:`nested_starts`) if already made."""
        new = tuple(c for c in new if c not in ref.causes)
        causes = tuple(ref.causes) + new
        newp = [p for c in new for p in c.params]
        start0 = {**ref.values, **{p.name: p.null for p in newp}}
        starts = [dict(start0, __nuisance__=ref.nuisance) if ref.nuisance is not None else start0]
        for i, combo in enumerate(_start_sets(new, ref.values)[: getattr(self.problem, "max_starts", MAX_STARTS)], start=1):
            if only_starts is None or i in only_starts:
                starts.append({**ref.values, **combo})
        if only_starts is None:  # data-derived starts a problem may offer
            starts += self.nested_starts(ref, new, mask) if extra_starts is None else [dict(x) for x in extra_starts]
        f = self.fit(causes, starts, mask)
        if only_starts is not None and f.start != "0":
            f.start = str(only_starts[int(f.start) - 1])
        elif mask is None and self.white is not None:
            f = self.registered(f, new)
        if mask is None and only_starts is None:
            f = self.swept(f, new)
        if f.score > ref.score * (1 + 1e-9) + 1e-9:  # never worse than the model it contains
            if hasattr(self.problem, "nuisance"):
                self.problem.fixed_nuisance = ref.nuisance
            try:
                r = self.residuals(start0, causes, mask)
                ld = self.logdet(mask)
                vr = self.var_rows()
            finally:
                if hasattr(self.problem, "nuisance"):
                    self.problem.fixed_nuisance = None
            m = np.ones(len(r), bool) if mask is None else mask
            J = np.zeros((int(m.sum()), len(f.plist)))
            f = Fit(causes, f.plist, np.array([_to_u(p, start0[p.name]) for p in f.plist]), dict(start0), r,
                    float(np.sum(r[m] ** 2)), int(m.sum()) - _inactive_rows(self.problem, start0, causes), J, f.nfev,
                    m, start="null", logdet=ld, var_rows=vr)
            f.nuisance = ref.nuisance
        return f


_POOL_FITTER: "Fitter | None" = None


def _run_job(F: Fitter, job: tuple) -> "Fit":
    """``(ref, new, mask[, warm[, only_starts]])``: the baseline (``ref`` None, no ``new``) or a nested fit; with
    ``warm`` (full-data optimum values) the baseline starts there only, and a nested fit from the
    null start and from ``warm``'s values of the new parameters (the rest from ``ref``)."""
    ref, new, mask = job[:3]
    warm = job[3] if len(job) > 3 else None
    only = job[4] if len(job) > 4 else None
    extra = job[5] if len(job) > 5 else None
    new = tuple(new)
    if ref is None and not new:
        return F.fit((), [dict(warm)], mask) if warm is not None else F.baseline(mask)
    if warm is None:
        return F.nested(ref, new, mask, only_starts=only, extra_starts=extra)
    newp = [p.name for c in new for p in c.params]
    f0 = F.nested(ref, new, mask, only_starts=[])
    # ``cv_warm_all`` (a rugged chi^2 surface, e.g. stick-slip patterns): the second start is the full-data
    # optimum of every parameter, not only of the new ones, and of its profiled nuisance where it has one
    # (CrossValidation.fold_fits; the fold's own optimum is still fitted on its training data; the held-out data
    # only chose the basin)
    w = dict(warm) if getattr(F.problem, "cv_warm_all", False) else {**ref.values, **{q: warm[q] for q in newp}}
    f1 = F.fit(tuple(ref.causes) + new, [w], mask)
    return f1 if f1.score < f0.score else f0


def _pool_worker_init(parent: int) -> None:
    """In a forked worker: the default action for SIGINT, SIGTERM and SIGHUP, and no wakeup fd (the command line's
    handlers and its watchdog's pipe are the parent's: inherited, a worker caught SIGTERM and lived on), and a
    watch that ends the worker when its parent is gone (a parent killed outright leaves its workers blocked on the
    job queue for ever: found with `timeout` around `probedyn diagnose`)."""
    import signal
    import threading

    for name in ("SIGINT", "SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            try:
                signal.signal(sig, signal.SIG_DFL)
            except (OSError, ValueError):  # pragma: no cover
                pass
    try:
        signal.set_wakeup_fd(-1)
    except (OSError, ValueError):  # pragma: no cover
        pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(ORPHAN_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="probedyn-orphan-watch", daemon=True).start()
    # the worker's copy of the fitter runs its jobs in turn (the parent's pool is the parent's), and the problem's
    # per-fit state is set by each job (a pool forked within a fit inherits that fit's training mask)
    F = _POOL_FITTER
    if F is not None:
        F._pool = None
        for name in ("train_mask", "fixed_nuisance"):
            if hasattr(F.problem, name):
                setattr(F.problem, name, None)
        if hasattr(F.problem, "memo_fork"):
            F.problem.memo_fork()


#: how often a pool worker checks that its parent is alive [s]
ORPHAN_POLL_S = 0.5


def _by_key(problem) -> dict[str, Any]:
    """The problem's causes and declared terms by key (a pool job names them by key)."""
    return {c.key: c for c in (*problem.causes, *(getattr(problem, "declared_terms", ()) or ()))}


def _pool_job(packed: tuple) -> tuple:
    """In a worker: the fit of one :meth:`Fitter.map_nested` job (causes passed by key)."""
    ref, keys, mask, warm, only, extra = packed

    def run(F: Fitter) -> "Fit":
        by_key = _by_key(F.problem)
        if ref is not None:
            ref.causes = tuple(by_key.get(c.key, c) for c in ref.causes)
        return _run_job(F, (ref, tuple(by_key[k] for k in keys), mask, warm, only, extra))

    return _in_worker(run)


def _longest_first(pool, fn, items: list, cost: list[float]) -> list:
    """``[fn(item) for item in items]`` through ``pool``, the items submitted costliest first (ties in order), the
    results returned in the items' order. With fewer jobs than a few per worker, the order decides the wall time:
    the three-scan friction example's six candidates took 12.9 s with the lattice misalignment's fit (11 s, four
    data-derived starts of the 2D lattice model) taken third, 11 s with it first. The jobs do not depend on the
    order they run in (each starts from the memory as its worker forked, :func:`_in_worker`), so neither do the
    results. On an error the jobs not yet started are cancelled."""
    order = sorted(range(len(items)), key=lambda i: -cost[i])
    futures = {i: pool.submit(fn, items[i]) for i in order}
    try:
        return [futures[i].result() for i in range(len(items))]
    except BaseException:
        for f in futures.values():
            f.cancel()
        raise


def _sweep_replay(points: list[tuple[float, dict]], best_c: float, best_st, tol: float) -> tuple[float, Any]:
    """A sweep direction's points (:meth:`Fitter._sweep_points`) taken in turn from the lowest ``best_c`` so far,
    up to where the walk stops (:data:`SWEEP_PATIENCE` points without a new lowest): ``(lowest chi^2, its
    start)``."""
    misses = 0
    for c2, st in points:
        if misses >= SWEEP_PATIENCE:
            break
        if c2 < best_c - 1e-9 * max(1.0, best_c):
            misses = 0 if c2 < best_c - tol else misses + 1
            best_c, best_st = c2, st
        else:
            misses += 1
    return best_c, best_st


def _in_worker(run: Callable[[Fitter], Any]) -> tuple[Any, int, dict | None]:
    """A pool job in a worker: ``run(fitter)`` from the memory as forked (a problem's ``memo_reset``); returns its
    result, the evaluations it took and what it added to the memory (``memo_delta``), which the parent merges in
    the jobs' order (:func:`_merged`): a map's results do not depend on which worker ran which job."""
    F = _POOL_FITTER
    prob = F.problem
    if hasattr(prob, "memo_reset"):
        prob.memo_reset()
    n0 = F.nfev
    out = run(F)
    return out, F.nfev - n0, (prob.memo_delta() if hasattr(prob, "memo_delta") else None)


def _merged(F: "Fitter", results) -> list:
    """In the parent: the results of a pool map (:func:`_in_worker`), their evaluations counted and their memory
    merged in order."""
    out = []
    for res, nfev, delta in results:
        F.nfev += nfev
        if delta:
            F.problem.memo_merge(delta)
        out.append(res)
    return out


def _pool_fit(packed: tuple) -> tuple:
    """In a worker: one :meth:`Fitter.map_fits` job (causes by key)."""
    keys, *rest = packed
    return _in_worker(lambda F: F._run_fit(tuple(_by_key(F.problem)[k] for k in keys), *rest))


def _pool_call(packed: tuple) -> tuple:
    """In a worker: one :meth:`Fitter.map_calls` item (causes by key)."""
    method, item, keys = packed
    return _in_worker(lambda F: getattr(F.problem, method)(*item, tuple(_by_key(F.problem)[k] for k in keys)))


def _pool_sweep(packed: tuple) -> tuple:
    """In a worker: one direction of a profile sweep (:meth:`Fitter._sweep_points`; causes by key)."""
    keys, f, *rest = packed

    def run(F: Fitter) -> list:
        f.causes = tuple(_by_key(F.problem)[k] for k in keys)
        return F._sweep_points(f, *rest)

    return _in_worker(run)


def _start_sets(causes, ref_values: dict[str, float] | None = None) -> list[dict[str, float]]:
    """Declared (data-independent) starting points of the new causes' parameters besides the null
    start: a cause's own ``start_sets`` if it declares them, else the combinations of its
    parameters' starts (and nulls), those with the fewest parameters at their null first."""
    out: list[dict[str, float]] = []
    for c in causes:
        # a cause may declare its starts relative to the model it extends (``start_sets_from(ref_values)``:
        # e.g. a compensating change of a baseline parameter that the cause's effect trades off against)
        sets = (c.start_sets_from(dict(ref_values or {})) if hasattr(c, "start_sets_from")
                else c.start_sets() if hasattr(c, "start_sets") else None)
        if sets is None:
            ps = list(c.params)
            alts = [[p.null, *p.starts] for p in ps]
            combos = [dict(zip([p.name for p in ps], v)) for v in itertools.product(*alts)]
            combos = [cb for cb in combos if any(cb[p.name] != p.null for p in ps)]
            combos.sort(key=lambda cb: sum(cb[p.name] == p.null for p in ps))
            sets = combos
        out = sets if not out else [{**a, **b} for a in out for b in sets]
    return out


# ------------------------------------------------------------------------------------------
# Cross-validation, uncertainties
# ------------------------------------------------------------------------------------------


def folds_of(groups: np.ndarray, k_max: int = 10, k: int = 8) -> list[np.ndarray]:
    """Leave-one-group-out for up to ``k_max`` groups, else K-fold over interleaved groups. A
    negative numeric group label marks residuals that are never held out (prior pseudo-residuals)."""
    g = np.asarray(groups)
    ug = [x for x in dict.fromkeys(g.tolist()) if not (isinstance(x, (int, float)) and x < 0)]
    if len(ug) <= k_max:
        return [np.nonzero(g == x)[0] for x in ug]
    return [np.nonzero(np.isin(g, ug[i::k]))[0] for i in range(k)]


class CrossValidation:
    """Held-out residuals of nested models; the fold baselines are fitted once and shared."""

    def __init__(self, F: Fitter, folds: list[np.ndarray], n: int) -> None:
        self.F = F
        self.folds = folds
        self.n = n
        self._ref: dict[tuple, list[Fit]] = {}
        # the declared start (an index, data independent) that won the full-data fit of a cause:
        # the folds try the null start and that one
        self.winning_start: dict[tuple, int] = {}
        # full-data fits by cause tuple (warm starts of the folds when the groups are interleaved)
        self.full_fits: dict[tuple, Fit] = {}

    def fold_fits(self, causes: tuple) -> list[Fit]:
        """The fits of ``causes`` on every fold's training data, nested in the folds' fits of
        ``causes[:-1]``: from the declared (data-free) starts, or, for a problem with ``cv_warm``
        (interleaved groups), from the null start and the full-data optimum of the new cause only.
        Independent over the folds (in the worker pool when there is one)."""
        key = tuple(c.key for c in causes)
        hit = self._ref.get(key)
        if hit is None:
            warm = getattr(self.F.problem, "cv_warm", False) and key in self.full_fits
            wv = dict(self.full_fits[key].values) if warm else None
            if warm and getattr(self.F.problem, "cv_warm_all", False) and self.full_fits[key].nuisance is not None:
                # the whole full-data optimum, its profiled nuisance (a scan's registry) included: a fold that
                # re-profiles the registry from the warm values alone can end in another basin of it, its training
                # chi^2 far above the full optimum's on the same rows (blind f07: 719 against 473). The held-out
                # data still only choose the basin; the fold re-profiles on its own training data
                wv["__nuisance__"] = self.full_fits[key].nuisance
            masks = []
            for fold in self.folds:
                mask = np.ones(self.n, bool)
                mask[fold] = False
                masks.append(mask)
            refs = self.fold_fits(causes[:-1]) if causes else [None] * len(masks)
            # not warm: the null start and the declared (data-free) start that won the full-data fit
            ws = self.winning_start.get(key)
            only = None if ws is None else [ws]
            hit = self.F.map_nested([(r, causes[-1:] if causes else (), m, wv, only) for r, m in zip(refs, masks)])
            self._ref[key] = hit
        return hit

    def forget(self, key: tuple) -> None:
        """Drop the fold fits of ``key`` (cause keys) and of every chain that extends it: its full-data fit
        changed (:func:`_sweep_claim`), and the folds start from it."""
        for k in [k for k in self._ref if k[: len(key)] == key]:
            del self._ref[k]

    def heldout(self, fit: Fit) -> None:
        """Set ``fit.cv_r`` (each group's residuals predicted by the fit of ``fit.causes`` to the
        other groups), ``fit.cv_fold`` (per fold, -2 ln of the held-out group's predictive density
        up to a constant shared by every model) and their sum ``fit.cv``.

        The score is ``e^T e`` (the fold's optimum taken as exact), or -- a problem with
        ``heldout_predictive`` -- the linearised posterior predictive ``e^T (I + S)^-1 e +
        ln det(I + S)``, ``S = J_g C J_g^T``: the fold's parameter uncertainty carried to the
        held-out group, ``C = (J_-g^T J_-g + P)^-1`` from the whitened Jacobian at the fold's optimum
        (:meth:`Fitter.jacobian`; training rows ``J_-g``, held-out rows ``J_g``) and the prior
        precision ``P`` of the parameters' uniform bounds (``12 / span^2`` in the fit coordinates).
        Where a held-out group is the only one that informs a parameter (a torsion mode for an
        anisotropic shear modulus), the fold's value of it is whatever the other groups' noise makes
        it, and ``e^T e`` condemns the cause for predicting what nothing told it; the predictive
        density spreads that prediction over the prior instead and charges the Occam factor
        ``ln det(I + S) / 2`` (Laplace; Vehtari, Gelman & Gabry 2017 for LOO as a predictive
        density). Where the training groups determine the parameters, ``S`` is small and the score
        is ``e^T e``. A model that carries a variance of its own (:attr:`Fit.var_rows`: a friction record's slip
        scatter at a declared temperature) adds the held-out group's ``sum ln(1 + var / sigma^2)``, as its fits' objective
        does: without it (before session 74) a model widening its variance on the held-out group lowered ``e^T e``
        there free of charge."""
        out = np.full(self.n, np.nan)
        pred = bool(getattr(self.F.problem, "heldout_predictive", False))
        scores = []
        for fold, f in zip(self.folds, self.fold_fits(fit.causes)):
            out[fold] = f.r[fold]
            e = out[fold]
            ok = np.isfinite(e)
            e = e[ok]
            # a model that carries a variance of its own: the held-out group's log-determinant of it is part of -2 ln
            # its predictive density, as it is of the fit's objective (not shared by every model)
            ld = float(np.sum(f.var_rows[fold][ok] ** 2)) if f.var_rows is not None else 0.0
            if not (pred and f.k):
                scores.append(float(e @ e) + ld)
                continue
            J = self.F.jacobian(f)
            Jt, Jg = J[f.mask], J[fold][ok]
            P = np.diag([12.0 / (hi - lo) ** 2 for lo, hi in map(_u_bounds, f.plist)])
            C = np.linalg.pinv(Jt.T @ Jt + P, hermitian=True)
            A = np.eye(len(e)) + Jg @ C @ Jg.T
            _, logdet = np.linalg.slogdet(A)
            scores.append(float(e @ np.linalg.solve(A, e) + logdet) + ld)
        fit.cv_r, fit.cv_fold = out, np.array(scores)
        fit.cv = float(np.sum(fit.cv_fold))


#: the spread of ``ln(sum r^2 / (n sigma^2))`` times ``sqrt n`` when ``sigma`` is the robust (MAD) scale of the
#: record's own second differences over sqrt 6 (``friction._scatter``) and ``r`` is white noise, against sqrt 2 for
#: a known sigma. The MAD's efficiency is 37 %, so its own scatter adds to the chi-square's. A chi-square test taken
#: at face value on such a sigma rejects a true model in 10 % of records at alpha = 1 % (simulated). The standard
#: deviation is 2.43-2.48 (simulated, 4000-20 000 records each of 256-2048 samples in 2-6 segments), but the tail
#: is heavier than a normal's: 2.65 holds the level, with rejections of 0.7-1.3 % at alpha = 1 % and 4.1-5.2 % at
#: 5 %. A trimmed RMS of the residuals' second differences (the re-read sigma, :mod:`.noise`) scatters with the
#: residuals and needs no correction (1.38-1.41, simulated)
MAD_SCATTER_LOG_SD = 2.65


def gof_p(chi2: float, dof: int, problem=None, white=None) -> float:
    """The goodness-of-fit p-value of ``chi2`` on ``dof`` degrees of freedom. Where the problem's sigma is the
    robust scale of its own record (``problem.sigma_from_scatter``, no noise stated, not re-read and not
    whitened), the chi-square's normal score is shrunk by ``sqrt 2 / MAD_SCATTER_LOG_SD``. That is the test of
    ``ln(chi2 / n)`` against its spread with the sigma's own sampling error included (docs/diagnose.md 9.40)."""
    return _own_scatter_tail(float(chi2_dist.sf(chi2, max(dof, 1))), problem, white)


def gof_p_lower(chi2: float, dof: int, problem=None, white=None) -> float:
    """The lower tail of :func:`gof_p`: the probability of a chi-square this small or smaller (the same shrunk
    normal score where the sigma is the record's own robust scatter)."""
    return _own_scatter_tail(float(chi2_dist.cdf(chi2, max(dof, 1))), problem, white)


def _own_scatter_tail(p: float, problem, white) -> float:
    """A chi-square tail probability ``p``, its normal score shrunk by ``sqrt 2 / MAD_SCATTER_LOG_SD`` where the
    sigma is the record's own robust scatter (:func:`gof_p`)."""
    if problem is not None and white is None and getattr(problem, "sigma_from_scatter", False):
        p = float(norm_dist.sf(norm_dist.isf(p) * math.sqrt(2.0) / MAD_SCATTER_LOG_SD))
    return p


def slip_law_check(F: "Fitter", fit: "Fit") -> dict[str, Any] | None:
    """Where the model is a mixture and carries its own law (``problem.pit``: a friction record's activated slips at a
    declared temperature; white noise), each sample's probability integral transform through that law, its
    ``T = sum z^2`` tested as a scaled chi-square of its own variance under the model (:mod:`.mixture`). Reported,
    not used for the verdict: the transform reads every sample against the *support* of the model's slip law, and a
    slip one fiftieth of a sample from where the model's quantiles reach reads as a 12-sigma sample (blind g03 at
    4.2 K: p = 1e-4 on a null whose Gaussian chi-square reads p = 0.69, docs/diagnose.md 9.58). It locates where the
    slip law misses the record (the largest scores); the chi-square test stays the Gaussian one. None where there is
    no mixture."""
    problem = F.problem
    pit = getattr(problem, "pit", None)
    if pit is None or F.white is not None:
        return None
    t = pit(fit.values, fit.causes)
    if t is None:
        return None
    worst = np.argsort(-np.abs(t.z))[:3]
    return {"statistic": t.T, "n": t.n, "variance_ratio": t.var_ratio, "p_value": t.p_value(fit.dof),
            "largest_scores": [{"row": int(i), "z": float(t.z[i]), "gaussian_residual": float(fit.r[i])}
                               for i in worst if len(fit.r) == t.n]}


def heldout_statistic(fit: Fit, cv_r: np.ndarray, folds: list[np.ndarray], problem=None,
                      white=None) -> tuple[float, float, int]:
    """Leverage-corrected held-out statistic ``T = sum_g e_g^T (I - H_gg) e_g`` and its p-value
    against chi2_n (``E[T] = n`` for a correct linearised model; :func:`gof_p`)."""
    J = fit.J if fit.J is not None and fit.J.size else None
    n = int(np.sum(np.isfinite(cv_r)))
    if J is None or J.shape[0] != len(cv_r):
        T = float(np.nansum(cv_r**2))
        return T, gof_p(T, n, problem, white), n
    JtJ_pinv = np.linalg.pinv(J.T @ J, rcond=1e-12)
    T = 0.0
    for fold in folds:
        e = cv_r[fold]
        ok = np.isfinite(e)
        Jg = J[fold][ok]
        Hgg = Jg @ JtJ_pinv @ Jg.T
        eg = e[ok]
        T += float(eg @ eg - eg @ Hgg @ eg)
    return T, gof_p(T, n, problem, white), n


def _rms(x) -> float | None:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x**2))) if x.size else None


def _bound_gain(J: np.ndarray, r: np.ndarray, j: int, side: str, scale: float) -> float | None:
    """The chi^2 a fit would gain if the bound ``side`` of its parameter ``j`` were lifted, every other
    parameter refitted: the score statistic of the linearised model ``r + J du``,
    ``(j_perp . r)^2 / |j_perp|^2`` with ``j_perp`` the parameter's Jacobian column with the other columns
    projected out (divided by ``scale``, the chi^2 per degree of freedom where it exceeds one); zero when the
    unconstrained step points back into the range, and zero where that column vanishes (the model does not
    respond to the parameter at the bound, or only as the other parameters do: to first order nothing is gained
    by lifting it; a parameter that is nowhere informed is flagged not identifiable on its own). None where the
    Jacobian does not match the residuals."""
    if J is None or J.shape[0] != len(r) or not np.all(np.isfinite(J[:, j])):
        return None
    jc = J[:, j]
    Jo = np.delete(J, j, axis=1)
    if Jo.shape[1]:
        coef = np.linalg.lstsq(Jo, jc, rcond=1e-12)[0]
        jc = jc - Jo @ coef
    den = float(jc @ jc)
    if not den > 1e-20 * max(float(np.sum(J * J)), 1e-300):
        return 0.0
    step = -float(jc @ r) / den
    outward = step < 0 if side == "lower" else step > 0
    return float(jc @ r) ** 2 / den / scale if outward else 0.0


def parameter_report(F: Fitter, fit: Fit, names: list[str] | None = None, profile: bool = True,
                     alpha: float = ALPHA) -> dict[str, dict]:
    """Value, 1-sigma uncertainty (Jacobian or profile likelihood), bound and identifiability
    flags of the fitted parameters (``names``: the ones to report; default all).

    A parameter at a bound carries ``bound_gain_chi2`` (:func:`_bound_gain`: what lifting the bound would
    gain) and ``bound_binding``: the bound binds when that gain exceeds ``chi2_1(1 - alpha)``, the engine's
    own test of whether one parameter is supported (a gain below it is an estimate that equals the bound
    within the noise, e.g. a translational clamp compliance at its null value 0 where the truth has none)."""
    out: dict[str, dict] = {}
    plist = fit.plist
    if not plist:
        return out
    J = fit.J if fit.J is not None else np.zeros((fit.n, len(plist)))
    scale = max(1.0, fit.chi2 / fit.dof)
    r_fit = fit.r[fit.mask] if fit.mask is not None and fit.r is not None else fit.r
    thr_bound = float(chi2_dist.ppf(1 - alpha, 1))
    cn = np.linalg.norm(J, axis=0)
    ok_cols = cn > 0
    Jn = J / np.where(ok_cols, cn, 1.0)
    U_, s, Vt = np.linalg.svd(Jn, full_matrices=False)
    rcond = float(s.min() / s.max()) if s.size and s.max() > 0 else 0.0
    weak = s < 1e-6 * (s.max() if s.size else 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(weak, 0.0, 1.0 / np.maximum(s, 1e-300) ** 2)
        cov_n = (Vt.T * inv) @ Vt * scale
        sd_u = np.sqrt(np.maximum(np.diag(cov_n), 0.0)) / np.where(ok_cols, cn, np.inf)
    loads_weak = (np.abs(Vt[weak]) > 0.1).any(axis=0) if weak.any() else np.zeros(len(plist), bool)
    for j, p in enumerate(plist):
        if names is not None and p.name not in names:
            continue
        lo_u, hi_u = _u_bounds(p)
        rng = hi_u - lo_u
        u = fit.u[j]
        side = _at_bound(p, u)
        unidentified = (not ok_cols[j]) or bool(loads_weak[j])
        crosses = (u - sd_u[j] < lo_u) or (u + sd_u[j] > hi_u)
        item = {"value": fit.values[p.name], "unit": p.unit, "at_bound": side is not None, "bound": side}
        if side is not None:
            gain = _bound_gain(fit.J, r_fit, j, side, scale) if r_fit is not None else None
            item.update(bound_gain_chi2=gain, bound_threshold_chi2=thr_bound,
                        bound_binding=gain is None or gain > thr_bound)
        need_profile = side is not None or unidentified or crosses
        if need_profile and profile:
            lo_i, hi_i, ident = _profile(F, fit, j, sd_u[j] if np.isfinite(sd_u[j]) and sd_u[j] > 0 else 0.05 * rng,
                                         target=scale)
            item.update(method="profile likelihood", identifiable=ident)
            if ident:
                vlo, vhi = _from_u(p, lo_i), _from_u(p, hi_i)
                item.update(interval=[vlo, vhi], sigma=0.5 * abs(vhi - vlo),
                            one_sided=bool(lo_i <= lo_u + 1e-9 * rng or hi_i >= hi_u - 1e-9 * rng))
            else:
                item.update(interval=None, sigma=None)
        elif need_profile:
            item.update(method="jacobian (ill-conditioned)", identifiable=not unidentified, interval=None,
                        sigma=None if unidentified else _sigma_value(p, u, sd_u[j]))
        else:
            sv = _sigma_value(p, u, sd_u[j])
            item.update(method="jacobian", identifiable=True, sigma=sv,
                        interval=[fit.values[p.name] - sv, fit.values[p.name] + sv])
        _swept_interval(item, (fit.profile or {}).get(p.name), fit.score + scale)
        out[p.name] = item
    out["_conditioning"] = {"reciprocal_condition": rcond, "chi2_scale": scale}
    return out


def _swept_interval(item: dict, points: list[tuple[float, float]] | None, level: float) -> None:
    """A swept parameter's interval (``item``, from :func:`parameter_report`) widened over its sweep's profile points
    (:attr:`Fit.profile`: ``(value, -2 ln L)`` with the other parameters refitted) that lie at or below ``level``
    (the optimum's ``-2 ln L`` plus the 68 % rise, 1 or chi^2/dof). The Jacobian's and the local profile's
    intervals see the basin the fit sits in; on a rugged profile another basin as high or higher in likelihood
    (within the sweep's own rule, ``SWEEP_GAIN``, the fit stays where it was) is as consistent with the data, and
    an interval that leaves it out is too narrow (a viscous coefficient's staircase of basins, docs/diagnose.md
    9.60-9.61). The interval then spans the points and ``sigma`` is its half-width."""
    if not points or item.get("interval") is None:
        return
    near = [v for v, sc in points if sc <= level]
    lo, hi = item["interval"]
    if near and (min(near) < lo or max(near) > hi):
        lo, hi = min(lo, min(near)), max(hi, max(near))
        item.update(interval=[lo, hi], sigma=0.5 * (hi - lo), method=f"{item['method']} and the sweep's profile points",
                    sweep_points_within=len(near))


def _sigma_value(p: CauseParam, u: float, su: float) -> float:
    if p.scale == "log":
        return float(10.0**u * math.log(10.0) * su)
    return float(su * _span(p))


def _profile(F: Fitter, fit: Fit, j: int, h0: float, target: float = 1.0) -> tuple[float, float, bool]:
    """68 % profile-likelihood interval of parameter j in internal coordinates: the points where
    chi2 (others refitted) rises by ``target`` (1, or chi2/dof when the fit is poor)."""
    p = fit.plist[j]
    lo_u, hi_u = _u_bounds(p)
    u0 = fit.u[j]
    names = [q.name for q in fit.plist]

    def chi2_at(u):
        fixed = {p.name: _from_u(p, u)}
        g = F.fit(fit.causes, [fit.as_start()], fit.mask, fixed=fixed, max_nfev=40 * len(names))
        return g.chi2

    ends = []
    hit_bound = []
    for sgn in (-1.0, 1.0):
        h = max(h0, 1e-4 * (hi_u - lo_u))
        u_in, c_in = u0, fit.chi2
        found = False
        for _ in range(12):
            u1 = float(np.clip(u0 + sgn * h, lo_u, hi_u))
            c1 = chi2_at(u1)
            if c1 - fit.chi2 >= target:
                # bisect between u_in and u1
                a, b = u_in, u1
                for _ in range(8):
                    mid = 0.5 * (a + b)
                    if chi2_at(mid) - fit.chi2 >= target:
                        b = mid
                    else:
                        a = mid
                ends.append(0.5 * (a + b))
                hit_bound.append(False)
                found = True
                break
            u_in, c_in = u1, c1
            if u1 in (lo_u, hi_u):
                break
            h *= 2.5
        if not found:
            ends.append(lo_u if sgn < 0 else hi_u)
            hit_bound.append(True)
    identifiable = not all(hit_bound)
    return ends[0], ends[1], identifiable


# ------------------------------------------------------------------------------------------
# The diagnosis
# ------------------------------------------------------------------------------------------


def _check_baseline_identifiable(base: Fit) -> None:
    if base.k == 0 or base.J is None:
        return
    # a parameter the fit holds at a bound is fixed there, not informed (a sample stiffer than the rigid-sample
    # limit allows -- a contact branch steeper than the lever, e.g. a miscalibrated deflection sensitivity -- puts
    # E* towards its bound, where the curve depends on it ever less and only as a shift of the contact point): the
    # check is on the free ones (within 1e-3 of the range of a bound: the fit approaches such a limit asymptotically;
    # seed 2321 of the calibration study stopped 5e-4 of the log range below the rigid sample)
    free = np.array([_at_bound(p, base.u[j], 1e-3) is None for j, p in enumerate(base.plist)], bool)
    if not free.any():
        return
    J = base.J[:, free]
    plist = [p for p, f in zip(base.plist, free) if f]
    cn = np.linalg.norm(J, axis=0)
    dead = [p.name for p, c in zip(plist, cn) if c == 0]
    if dead:
        raise DataFormatError(f"the data cannot inform the baseline parameter(s) {', '.join(dead)} "
                              "(the model does not depend on them for the measured quantities); remove them from "
                              "[baseline] free or add data they affect")
    _, s, Vt = np.linalg.svd(J / cn, full_matrices=False)
    # finite-difference Jacobians are accurate to ~1e-5: a combination a thousand times weaker
    # than the typical column is not informed by the data
    if s.min() < 1e-3 * s.max():
        v = Vt[-1]
        combo = [p.name for p, x in zip(plist, v) if abs(x) > 0.2]
        raise DataFormatError(f"the data cannot inform the baseline parameters {', '.join(combo)} separately "
                              "(only a combination of them changes the measured quantities); calibrate fewer of them "
                              "([baseline] free) or add data that separates them")


def _whiten(F: "Fitter", noise: dict[str, Any], base: "Fit") -> "Fit":
    """Every fit from now on on AR(1) innovations (:mod:`.noise`); the baseline re-fitted so (the better of a
    fresh fit and one from the white optimum).

    Without a stated noise the problem's sigma was read from the record's point-to-point scatter, which
    understates an AR(1) noise's marginal sigma (by ``sqrt((1 - rho)(3 - rho) / 3)``, 0.38 at rho = 0.8). The
    problem's sigma becomes the estimated marginal one (``marginal_sd`` times it) before the re-fit, so that
    every residual is in units of the noise as estimated: for a residual linear in the data this only
    rescales (the whitened residuals are identical), but a force curve's sample next to a predicted jump is a
    two-branch mixture whose deviance is not scale-free (:meth:`ForceCurveProblem.residuals`), and with the
    scatter-read sigma it weighed the other branch as if the noise were 2.6x smaller (session 22: a JKR
    truth, seed 2001 at rho = 0.8, named DMT with the sigma unstated and JKR with it stated)."""
    isd = noise.get("innovation_sd")
    prob = F.problem
    mixture = noise["model"] == MIXTURE
    if (isd is not None or mixture) and noise.get("marginal_sd") and isinstance(getattr(prob, "sigma", None), float):
        prob.sigma = prob.sigma * float(noise["marginal_sd"])
        isd = None
    if mixture:  # a white floor plus a slow AR(1): exact dense whitening per sequence (:class:`.noise.MixtureWhitener`)
        F.white = MixtureWhitener(noise["share"], noise["rho"], F.problem.sequences, len(base.r))
    else:
        F.white = AR1Whitener(noise["rho"], F.problem.sequences, len(base.r), isd)
    if noise.get("sequence_scales"):  # each sequence in units of its own noise first (:func:`.noise.sequence_scales`)
        F.white = SequenceScale(noise["sequence_scales"], F.problem.sequences, len(base.r), F.white)
    # a problem judging its own residuals against the noise (a force curve's data starts: "the reference
    # already fits within the noise") judges them on the noise the fits use
    prob.whitener = F.white
    b1, b2 = F.baseline(), F.fit((), [dict(base.values)])
    return b1 if b1.score <= b2.score else b2


def lr_threshold(k: int, n_causes: int, alpha: float = ALPHA) -> float:
    """The likelihood-ratio test's threshold for a cause of ``k`` parameters, one of ``n_causes`` tested:
    ``chi2_k(1 - alpha / n_causes)`` (Bonferroni over the catalog: under the baseline the chance that any
    cause passes is at most ``alpha``; step 3 of the module docstring)."""
    return float(chi2_dist.ppf(1 - alpha / n_causes, k))


def boundary_lr_threshold(k: int, alpha: float = ALPHA) -> float:
    """The likelihood-ratio threshold of a model against one of its *limits*: a nested model reached where one
    of the container's ``k`` extra parameters runs to the edge of its range (JKR is Maugis-Dugdale at
    ``1/lambda = 0``). With the null on the boundary the statistic is not chi^2_k but the chi-bar-square
    mixture ``1/2 chi^2_(k-1) + 1/2 chi^2_k`` (Chernoff 1954; Self & Liang 1987, case 5: one parameter on the
    boundary, ``k - 1`` inside): half the time the unconstrained optimum lies beyond the edge and the fit sits
    on the limit with Delta chi^2 = 0. Returns ``x`` with ``P(statistic > x) = alpha`` (for ``k = 1``,
    ``chi2_1(1 - 2 alpha)``: 5.41 at alpha = 1 %, where ``chi2_1(1 - alpha)`` = 6.63 would test at 0.5 %)."""
    if k < 1:
        raise ValueError("a container has at least one parameter more than its limit")
    if k == 1:
        return float(chi2_dist.isf(2.0 * alpha, 1))

    def tail(x: float) -> float:
        return 0.5 * float(chi2_dist.sf(x, k - 1)) + 0.5 * float(chi2_dist.sf(x, k)) - alpha

    return float(brentq(tail, float(chi2_dist.isf(2.0 * alpha, k - 1)), float(chi2_dist.isf(alpha, k))))


def _candidates(F: "Fitter", causes, base: "Fit", alpha: float, n_causes: int) -> tuple["Fit", list["Fit"]]:
    """Step 3: every cause fitted nested in the baseline (and the baseline re-fitted where a candidate's own
    baseline parameters fit better); returns the (possibly re-fitted) baseline and the fits in cause order."""
    fits = F.map_nested([(base, (c,), None) for c in causes])
    # the baseline is nested in every candidate: where the baseline at a candidate's own baseline
    # parameters fits better than the baseline optimum by more than a one-parameter LR threshold
    # (the baseline fit stopped in a shallower basin or at its evaluation cap: a rugged chi^2), the
    # baseline is re-fitted from there and the candidates are fitted again from it (at most 3 rounds)
    thr1 = lr_threshold(1, n_causes, alpha)
    for _round in range(3):
        bf = min(fits, key=lambda f: f.score) if fits and base.k else None
        if bf is None or not bf.score < base.score - thr1:
            break
        bv = {p.name: bf.values[p.name] for p in base.plist}
        if not float(np.sum(F.residuals(bv, ()) ** 2)) + F.logdet() < base.score - thr1:
            break
        b2 = F.fit((), [bv])
        if not b2.score < base.score - thr1:
            break
        base = b2
        fits = F.map_nested([(base, (c,), None) for c in causes])
    # a contained limit law (a cause's ``limits``) re-fitted from its container's optimum where worse, and
    # the container from its limit's where it is the worse one
    fits = _limit_refits(F, causes, fits)
    return base, fits


def diagnose(problem, *, alpha: float = ALPHA, max_causes: int = 2, only: list[str] | None = None,
             margin: float = EVIDENCE_MARGIN, noise_model: str = "auto") -> dict[str, Any]:
    """Run the diagnosis on a problem object; return the JSON-able result (see module docstring).
    ``noise_model``: ``"auto"`` (white unless the residuals show an AR(1) correlation, :mod:`.noise`)
    or ``"white"`` (the samples taken as independent whatever the record shows)."""
    if noise_model not in ("auto", "white"):
        raise ValueError(f"noise_model must be 'auto' or 'white', got {noise_model!r}")
    # the noise model a diagnosis sets on its problem (an unstated AR(1) noise's sigma, the whitener) is
    # undone when it returns: the problem object stays as the measurement made it
    noise_keys = ("sigma", "sigma_from_scatter", "whitener")
    saved = {k: getattr(problem, k) for k in noise_keys if hasattr(problem, k)}
    # ... and so are the baseline's parameters and terms, which the declared conditions may extend (_declared_terms)
    terms = {k: getattr(problem, k) for k in ("base_params", "base_terms") if hasattr(problem, "declared_terms")}
    # ... and the baseline's law, which the diagnosis chooses among the problem's (_baseline_law, _law_with_cause)
    law = getattr(problem, "baseline_law", None) if getattr(problem, "baseline_laws", ()) else None

    def restore(start: bool = True) -> None:
        """The problem as the measurement made it; ``start``: for a run (no whitener)."""
        for k in noise_keys:
            if k in saved:
                if getattr(problem, k) is not saved[k]:
                    setattr(problem, k, saved[k])
            elif hasattr(problem, k):
                delattr(problem, k)
        if law is not None and problem.baseline_law != law:
            problem.set_baseline_law(law)
        for k, v in terms.items():
            setattr(problem, k, v)
        if start:
            problem.whitener = None

    restore()
    F = Fitter(problem)
    relaw, t0, nfev = None, time.perf_counter(), 0
    try:
        while True:
            try:
                res = _diagnose(problem, F, alpha=alpha, max_causes=max_causes, only=only, margin=margin,
                                noise_model=noise_model, relaw=relaw)
                # the run time and the evaluations of a first run under another law counted in
                res.update(runtime_s=time.perf_counter() - t0, model_evaluations=res["model_evaluations"] + nfev)
                return res
            except _LawAgain as again:  # the law chosen again with the lead cause: the diagnosis once more under it
                F.close_pool()
                restore()
                if hasattr(problem, "memo_clear"):  # the run again is the one a fresh problem under the law gives
                    problem.memo_clear()
                nfev += F.nfev
                F, relaw = Fitter(problem), again.law
    finally:
        F.close_pool()
        restore(start=False)


def _diagnose(problem, F: Fitter, *, alpha: float, max_causes: int, only: list[str] | None, margin: float,
              noise_model: str = "auto", relaw: dict[str, Any] | None = None) -> dict[str, Any]:
    """The diagnosis (:func:`diagnose`). ``relaw``: the baseline's law as :func:`_law_with_cause` chose it again on a
    first run (the run is then made under that law, and not chosen again)."""
    t0 = time.perf_counter()
    n = len(problem.groups)
    folds = folds_of(problem.groups)
    use_cv = len(folds) >= 3
    causes = [c for c in problem.causes if only is None or c.key in only]
    n_causes = max(len(causes), 1)
    base_names = {p.name for p in problem.base_params}
    for c in causes:  # the fits address parameters by name: a cause's must not shadow the baseline's
        clash = base_names & {p.name for p in c.params}
        if clash:
            raise RegistryError(f"cause {c.key}: parameter {', '.join(sorted(clash))} is also a baseline parameter")
    # 1-2. baseline and its chi-square test
    if relaw is None:
        base, load_law = _baseline_law(F, F.baseline())
    else:
        problem.set_baseline_law(relaw["law"])
        base, load_law = F.baseline(), relaw
    if load_law is not None:  # the causes are constrained again about the law taken
        causes = [c for c in problem.causes if only is None or c.key in only]
    _check_baseline_identifiable(base)
    # 1a. what the declared conditions imply (thermal activation at a declared temperature) joins the baseline
    base, declared = _declared_terms(F, base, alpha)
    # 1b. correlated noise (:mod:`.noise`): where the stated noise's high-frequency part and the
    # residuals' lag-one correlation both say AR(1), every fit from here on is whitened. Without a stated
    # noise the correlation comes from the residuals' own first and second differences, which a misfit
    # with structure at the sampling scale inflates as well (a sloped surface's friction): it is judged
    # on the residuals of the best nested candidate (the baseline plus one cause, fitted white), and only
    # if the correlation is there are the baseline and the candidates re-fitted whitened
    noise = noise_correlation(problem, base.r)
    if noise and noise_model == "white":
        noise = {k: v for k, v in noise.items() if k not in ("innovation_sd", "marginal_sd")}
        noise = dict(noise, model="white", rho=0.0, reason="white noise requested (noise_model)")
    deferred = bool(noise and noise_model == "auto" and not getattr(problem, "noise_stated", False))
    if noise and noise["model"] == "AR(1)" and not deferred:
        base = _whiten(F, noise, base)
    cands = []
    F.open_pool()
    while True:
        base, fits = _candidates(F, causes, base, alpha, n_causes)
        if not deferred:
            break
        deferred = False
        best = min(fits, key=lambda f: f.score) if fits else base
        again = noise_correlation(problem, best.r)
        noise = dict(again, baseline_estimate={k: noise[k] for k in ("rho", "rho_scatter", "rho_lag1")},
                     judged_on=("the best nested candidate's residuals ("
                                + ", ".join(c.key for c in best.causes) + ")") if best.causes else "the baseline")
        if again["model"] not in ("AR(1)", MIXTURE):
            q, scales = again.get("white_scale"), again.get("sequence_scales")
            if (q is None and scales is None) or not isinstance(getattr(problem, "sigma", None), float):
                break
            # an unstated white noise whose scale the whole record's residuals read differently from the
            # part the problem read it from, or differently in its sequences (:mod:`.noise`): every fit
            # again on the re-read sigma, each sequence in units of its own
            F.close_pool()  # the workers were forked with the old sigma
            if q is not None:
                noise["sigma_before_N"] = problem.sigma
                problem.sigma = problem.sigma * float(q)
                problem.sigma_from_scatter = False  # re-read from the residuals' differences (gof_p)
            if scales is not None:
                F.white = SequenceScale(scales, problem.sequences, len(base.r))
                problem.whitener = F.white
            b1, b2 = F.baseline(), F.fit((), [dict(base.values)])
            base = b1 if b1.score <= b2.score else b2
            F.open_pool()
            continue
        F.close_pool()  # the workers were forked with the white residuals
        base = _whiten(F, again, base)
        F.open_pool()
    if load_law is not None and relaw is None:  # the law chosen again with the lead cause (_law_with_cause)
        again = _law_with_cause(F, causes, base, fits, alpha, n_causes)
        if again is not None:
            load_law["with_cause"] = again
            if again["law"] != load_law["law"]:
                raise _LawAgain(dict(load_law, law=again["law"], chosen_with=again["cause"]))
    p_base = gof_p(base.chi2, base.dof, problem, F.white)
    omnibus = p_base < alpha
    cv = CrossValidation(F, folds, n) if use_cv else None
    for c, fit in zip(causes, fits):
        k = len(c.params)
        dchi2 = max(base.score - fit.score, 0.0)  # -2 ln L's gain (chi^2's, with a variance the model carries)
        thr = lr_threshold(k, n_causes, alpha)
        cands.append({"cause": c, "fit": fit, "k": k, "dchi2": dchi2, "lr_threshold": thr,
                      "lr_pass": bool(dchi2 > thr), "evidence": None, "evidence_cv": None,
                      "evidence_se": None, "method": None})
    # 2b. the targeted test: a catalog cause's likelihood-ratio test at alpha / N (step 2, second route; a problem
    # whose likelihood carries its model's own error only)
    targeted = ([d["cause"].key for d in cands if d["lr_pass"]]
                if getattr(problem, "model_error_in_likelihood", False) else [])
    significant = omnibus or bool(targeted)
    # 4. evidence out of sample where a claim is possible
    if significant and any(d["lr_pass"] for d in cands):
        if use_cv:
            cv.full_fits[()] = base
            cv.heldout(base)
        _score_in_order(cands, margin, lambda d: _evidence(d, base, cv, use_cv))
    for d in cands:
        if d["evidence"] is None and not use_cv and not d.get("pruned"):
            d["evidence"] = _akaike(d)
            d["method"] = "akaike (fewer than 3 groups)"
    claimed = [d for d in cands if significant and d["lr_pass"] and d["evidence"] is not None and d["evidence"] > 0]
    not_claimed: list[dict] = []
    vs_me = bool(getattr(problem, "extension_vs_model_error", False))
    # ranking: by the evidence (capped), or -- a problem with ``rank_by_heldout`` -- by the held-out
    # evidence itself: the cap bounds each cause's Bayes factor against the *baseline*, but when several
    # causes reach their caps it only ranks their in-sample fits (a cause with more parameters wins);
    # between two causes the held-out log likelihood difference is the out-of-sample comparison
    by_ho = bool(getattr(problem, "rank_by_heldout", False))

    def rank(d):
        return d["evidence_cv"] if by_ho and d.get("evidence_cv") is not None else d["evidence"]

    claimed.sort(key=lambda d: -rank(d))
    swept: set[int] = set()
    while claimed and id(claimed[0]) not in swept:  # the lead swept, and the ranking redone (_sweep_claim)
        swept.add(id(claimed[0]))
        _sweep_claim(F, claimed[0], base, cv, use_cv)
        claimed = sorted((d for d in claimed if d["evidence"] > 0), key=lambda d: -rank(d))
    parsimony = _parsimony(claimed, margin, alpha)
    findings: list[dict] = []
    declared_after: list[dict] = []  # declared terms taken on after a claim (_declared_after_claim)
    confounded: list[dict] = []
    chosen: list[Cause] = []
    current = base
    reasons: list[str] = []
    if claimed:
        best = claimed[0]

        def rival_of(d, lead):
            return (d is not lead and not d.get("contains_leader")
                    and (rank(d) >= rank(lead) - margin or d.get("sibling_limit")
                         or _tied_alternative(problem, d, lead, margin) or (by_ho and _unresolved(lead, d, cv, margin))))

        rivals = [d for d in claimed[1:] if rival_of(d, best)]
        best, rivals, occam = _fewest_parameters_lead(problem, claimed, best, rivals, rival_of)
        if id(best) not in swept:  # a lead taken by the fewest parameters (it may now stand first in ``claimed``)
            swept.add(id(best))
            _sweep_claim(F, best, base, cv, use_cv)
        # a cause within the margin of the winner that did not pass its own likelihood-ratio test (the same gain
        # with more parameters, or just short of the look-elsewhere threshold) is not claimed, but the data do not
        # separate it from the winner either: it is named in the confounded group, after the claimed rivals, and
        # never takes the lead (blind spectrum s11: an axial prestress 'explained' with a fluid load 0.7 nats and a
        # point mass 1.0 nat behind it, both unclaimed; docs/diagnose.md 9.54). A cause that contains the winner as
        # a limit is the winner plus an unsupported parameter: not a rival
        near = [d for d in cands if d is not best and not any(d is c for c in claimed) and not d.get("pruned")
                and d.get("fit") is not None and d.get("evidence") is not None and d["evidence"] > 0
                and best["cause"].key not in getattr(d["cause"], "limits", ()) and rank(d) >= rank(best) - margin]
        if rivals or near:
            confounded.append(_confounding(problem, best, rivals + near, margin))
            if near:
                confounded[-1]["not_claimed"] = [d["cause"].key for d in near]
        current = best["fit"]
        chain = [current]
        chosen.append(best["cause"])
        findings.append(_finding(problem, F, base, best, confounded[0] if confounded else None, alpha))
        if parsimony:
            findings[0]["parsimony"] = parsimony
        if occam:
            findings[0]["notes"] = list(findings[0].get("notes") or []) + [occam]
        current = _declared_after_claim(F, current, alpha, findings[-1], declared_after, cv)
        chain[-1] = current
        # 6. greedy extension while the chi-square test still fails
        while len(chosen) < max_causes and gof_p(current.chi2, current.dof, problem, F.white) < alpha:
            ext = []
            # every cause that passed the first likelihood-ratio test is a candidate extension, also one
            # not cross-validated in the ranking (pruned: its cap could not reach the winner's evidence)
            for d in claimed[1:] + [x for x in cands if x.get("pruned")]:
                c = d["cause"]
                if c in chosen or (confounded and c.key in confounded[0]["causes"]):
                    continue
                if c.alternative and any(x.alternative == c.alternative for x in chosen):
                    continue  # an alternative to a chosen cause (another contact law) replaces it, never extends it
                fit = F.nested(current, (c,))
                k = len(c.params)
                dchi2 = max(current.score - fit.score, 0.0)
                thr = lr_threshold(k, n_causes, alpha)
                if dchi2 <= thr:
                    continue
                e = {"cause": c, "fit": fit, "k": k, "dchi2": dchi2, "lr_threshold": thr, "lr_pass": True}
                _evidence(e, current, cv, use_cv)
                if e["evidence"] is not None and e["evidence"] > 0:
                    ext.append(e)
            if not ext:
                break
            # an extension whose parameter the data push onto a bound of its physical range (not its null value)
            # stands in for a misfit the catalog does not hold: one within its range is taken first (the real JPK
            # curve's sensitivity at its 2x bound had absorbed the contact's shape misfit in place of the
            # optical-interference wave the data's provenance reads; docs/diagnose.md section 9.15)
            ext.sort(key=lambda d: (_strained(d["fit"], d["cause"]), -d["evidence"]))
            nxt = ext[0]
            _sweep_claim(F, nxt, current, cv, use_cv)
            findings.append(_finding(problem, F, current, nxt, None, alpha))
            chosen.append(nxt["cause"])
            current = _declared_after_claim(F, nxt["fit"], alpha, findings[-1], declared_after, cv)
            chain.append(current)
        # a problem with ``extension_vs_model_error``: every claimed cause must take more than the excess
        # the chain leaves unexplained (_beyond_remainder)
        if vs_me:
            j = _beyond_remainder([f["delta_chi2"] for f in findings], chain)
            for i in range(j, len(findings)):
                f = findings[i]
                not_claimed.append({"cause": f["cause"], "after": [x["cause"] for x in findings[:i]],
                                    "delta_chi2": f["delta_chi2"], "evidence": f["evidence"],
                                    "remainder": max(chain[i].chi2 - chain[i].dof, 0.0),
                                    "reason": "a gain in the chain up to it does not exceed the excess chi^2 - dof that "
                                              "chain leaves unexplained: not separable from the model error that "
                                              "remainder shows"})
            if j < len(findings):
                findings, chosen = findings[:j], chosen[:j]
                current = chain[j - 1] if j else base
                if not j:
                    confounded = []
    # 7. the final model re-solved with the full model (where the fits used a reduced one)
    final = _final(problem, F, current, base, cv, folds, use_cv)
    verdict, reasons = _verdict(omnibus, findings, confounded, final, alpha, targeted)
    if not findings and not_claimed:
        reasons = reasons + [f"{x['cause']}: {x['reason']}" for x in not_claimed]
    result = {
        "measurement": str(getattr(problem, "path", "")),
        "kind": problem.kind,
        "data": problem.describe(),
        "method": {
            "evidence": ("leave-one-group-out cross-validation (held-out chi^2), capped at the in-sample "
                         "log likelihood ratio" if use_cv else "Akaike information criterion (fewer than 3 groups)"),
            "groups": len([x for x in dict.fromkeys(np.asarray(problem.groups).tolist())
                           if not (isinstance(x, (int, float)) and x < 0)]), "folds": len(folds),
            "alpha": alpha, "evidence_margin_nats": margin, "max_causes": max_causes,
            "claim_rule": ("likelihood-ratio test at alpha / N_causes AND evidence > 0 (the discrepancy: the baseline's "
                           "chi-square p < alpha, or that likelihood-ratio test)"
                           if getattr(problem, "model_error_in_likelihood", False) else
                           "baseline chi-square p < alpha AND likelihood-ratio test at alpha / N_causes AND evidence > 0"),
            "noise": noise or {"model": "white", "reason": "independent samples (no recording sequences)"},
            "model": problem.model_description(),
        },
        "baseline": {
            "parameters": parameter_report(F, base) if base.k else {},
            "chi2": base.chi2, "dof": base.dof, "p_value": p_base, "n": base.n, "targeted_test": targeted,
            "slip_law_check": slip_law_check(F, base),
            "residual_rms": _rms(base.r), "residual_rms_physical": problem.physical_rms(base.r),
            "residual_unit": problem.unit,
            "heldout_rms": _rms(base.cv_r) if base.cv_r is not None else None,
            "residuals": base.r, "structure": problem.structure(base.r),
            "declared_terms": declared,
            "declared_terms_after_claims": declared_after,
            "load_law": load_law,
        },
        "candidates": [_candidate_row(d) for d in sorted(cands, key=lambda d: -(d["evidence"] if d["evidence"] is not None else -1e300))],
        "findings": findings,
        "confounded": confounded,
        "not_claimed": not_claimed,
        "verdict": verdict,
        "verdict_reasons": reasons,
        "final": final["report"],
        "runtime_s": time.perf_counter() - t0,
        "model_evaluations": F.nfev,
    }
    extra = getattr(problem, "extra_report", None)
    if extra:
        result.update(extra())
    return result


def _test_term(F: Fitter, fit: Fit, t, alpha: float) -> tuple[Fit, dict[str, Any]]:
    """A declared term ``t`` tested on the model ``fit`` (the baseline, or a claim's model): fitted nested in it and
    taken on when it lowers ``-2 ln L`` (chi^2, plus the log-determinant of a variance the model carries,
    ``problem.variance_logdet``) by more than the likelihood-ratio threshold ``chi2_k(1 - alpha)`` of its k
    parameters and by more than the excess ``chi^2 - dof`` the model with it still leaves (:func:`_beyond_remainder`'s
    rule for a claimed cause: a gain below that remainder is not separable from the misfit it shows). Returns the
    nested fit and the row the report shows."""
    problem = F.problem
    logdet = getattr(problem, "variance_logdet", None)
    g = F.nested(fit, (t,))
    # the likelihood ratio: where the term's model carries a variance of its own (a scatter it fits), its
    # -2 ln L is chi^2 plus that variance's log-determinant (FrictionProblem.variance_logdet)
    pen = (logdet(g.values, g.causes) - logdet(fit.values, fit.causes)) if logdet is not None else 0.0
    gain = float(fit.chi2 - g.chi2 - pen)
    thr = lr_threshold(len(t.params), 1, alpha)
    # a hidden effect's misfit is partly taken by any flexible term (own misaligned seed 2005 at 0.01 K: the
    # activation gained 13 465 of a baseline chi^2 of 1.2e6 and, taken on, sent the misalignment's fit to another
    # basin); a declared temperature's own activation takes most of the athermal misfit (blind nulls at 0.3-2 K:
    # gains 164-6615 against remainders 0-156)
    # ... but a remainder the model with the term leaves within the noise (its chi-square test passes at alpha) is
    # the noise's, no misfit the gain could belong to (blind friction set 2's g12: the contact's stiffness at the
    # reversals gained 44.9, the loop left chi^2 851 on 797 dof, p = 0.09; session 68)
    remainder = max(float(g.chi2 - g.dof), 0.0)
    if gof_p(g.chi2, g.dof, problem, F.white) >= alpha:
        remainder = 0.0
    row: dict[str, Any] = {"term": t.key, "title": t.title, "implied_by": getattr(t, "implied_by", None),
                           "dchi2": float(fit.chi2 - g.chi2),
                           "variance_logdet": float(pen), "lr_gain": gain, "lr_threshold": thr,
                           "remainder": remainder, "taken": bool(gain > thr and gain > remainder), "note": t.note}
    if row["taken"]:
        row["values"] = {p.name: float(g.values[p.name]) for p in t.params}
        row["derived"] = t.derived(g.values, problem)
    return g, row


def _baseline_law(F: Fitter, base: Fit) -> tuple[Fit, dict[str, Any] | None]:
    """Step 1, where the problem has more than one law of its baseline (``problem.baseline_laws``, e.g. a friction
    record at two loads: the corrugation proportional to the load, the registry's law, or independent of it, the
    plain PT model; both are what ``simulate ffm`` runs, with and without a normal load, and the record does not say
    which its instrument follows): the baseline fitted under each, the law of the lowest chi^2 kept
    (``problem.set_baseline_law``). The laws have the same parameters, so the choice costs no degree of freedom
    beyond a look at two models; a law between them (an adhesion intercept) stays a cause, nested in the law kept.
    ``base``: the fit under the problem's current law. Returns the baseline and what was compared (None: one law)."""
    problem = F.problem
    laws = tuple(getattr(problem, "baseline_laws", ()) or ())
    if len(laws) < 2:
        return base, None
    first = problem.baseline_law
    chi2 = {first: float(base.chi2)}
    best, best_law = base, first
    for law in laws:
        if law == first:
            continue
        problem.set_baseline_law(law)
        g = F.baseline()
        chi2[law] = float(g.chi2)
        if g.score < best.score:
            best, best_law = g, law
    problem.set_baseline_law(best_law)
    return best, {"law": best_law, "chi2": chi2}


class _LawAgain(Exception):
    """Raised by :func:`_diagnose` where :func:`_law_with_cause` takes another baseline law: ``law`` is the
    ``load_law`` row of the report, with the law taken (``law``) and the cause it was chosen with."""

    def __init__(self, law: dict[str, Any]) -> None:
        super().__init__(law["law"])
        self.law = law


def _law_with_cause(F: Fitter, causes: list, base: Fit, fits: list[Fit], alpha: float,
                    n_causes: int) -> dict[str, Any] | None:
    """The baseline's law (:func:`_baseline_law`) chosen again with the lead candidate: the cause whose nested fit
    (step 3) is lowest, fitted nested in the baseline of every other law too (the baseline under that law, with the
    declared terms the baseline took, at their fitted values; the cause's own starts, data-derived ones and sweep, as
    in step 3). The law is a discrete part of the baseline, chosen by the lowest ``-2 ln L``: on the baseline alone
    the wrong law can fit better while the data's hidden effect is missing from both, and every cause is then nested
    in it (own viscous seed 2001 at two loads: the load-independent baseline 4.43e6 against 6.08e6, but viscous
    friction 1.8e6 on it against 1651 on the proportional law; docs/diagnose.md 9.61). Another law is taken where it
    lowers the lead's ``-2 ln L`` by more than a one-parameter likelihood-ratio threshold at ``alpha / n_causes`` (the
    rule by which step 3 re-fits the baseline); the diagnosis is then run again under it. Returns what was compared
    (``cause``, ``score`` per law, the ``law`` with the lowest, ``threshold``), None where no cause lowers the
    baseline's ``-2 ln L`` or the problem has one law."""
    problem = F.problem
    laws = tuple(getattr(problem, "baseline_laws", ()) or ())
    if len(laws) < 2 or not fits:
        return None
    i = min(range(len(fits)), key=lambda j: fits[j].score)
    lead, fit = causes[i], fits[i]
    if not fit.score < base.score:
        return None
    first = problem.baseline_law
    kept = {k: getattr(problem, k) for k in ("base_params", "base_terms", "causes", "declared_terms")}
    tparams = [p for t in kept["base_terms"] for p in t.params]
    held = {p.name: base.values[p.name] for p in tparams}
    score = {first: float(fit.score)}
    pool = F._pool is not None
    F.close_pool()  # the workers were forked under the law taken
    try:
        for law in laws:
            if law == first:
                continue
            problem.set_baseline_law(law)
            problem.base_params = list(problem.base_params) + tparams
            problem.base_terms = kept["base_terms"]
            starts = [dict(s, **held) for s in F.base_starts()]
            b = F.fit((), [s for i, s in enumerate(starts) if s not in starts[:i]])
            c = next((c for c in problem.causes if c.key == lead.key), None)
            if c is None:
                continue
            F.open_pool()
            score[law] = float(F.map_nested([(b, (c,), None)])[0].score)
            F.close_pool()
    finally:
        F.close_pool()
        problem.set_baseline_law(first)
        for k, v in kept.items():
            setattr(problem, k, v)
        if pool:
            F.open_pool()
    thr = lr_threshold(1, n_causes, alpha)
    best = min(score, key=score.get)
    return {"cause": lead.key, "score": score, "threshold": float(thr),
            "law": best if score[best] < score[first] - thr else first}


def _declared_terms(F: Fitter, base: Fit, alpha: float) -> tuple[Fit, list[dict[str, Any]]]:
    """Step 1a: the effects the measurement's declared conditions imply (``problem.declared_terms``: thermal
    activation at a declared temperature) join the baseline where the data show them.

    Each term is fitted nested in the baseline (from the baseline optimum with its parameters at their nulls, plus
    its own starts and sweep, as a cause is) and tested by :func:`_test_term` (its likelihood-ratio threshold is not
    divided among the catalog: the term is not one of many hypotheses but a consequence of what was declared). Taken on, its parameters become baseline parameters
    (``problem.base_params``) and its effect part of every model (``problem.base_terms``): the causes are then
    tested against, and nested in, the baseline with the term. Not taken on, the baseline stays as it was (a cold
    record's activation within the noise, an attempt frequency the data cannot inform). Returns the baseline and,
    per term, what was found (for the report)."""
    problem = F.problem
    out: list[dict[str, Any]] = []
    terms = list(getattr(problem, "declared_terms", ()) or ())
    if terms:
        F.open_pool()  # the term's screened starts and its sweep's two directions (Fitter.map_fits, swept)
    try:
        for t in terms:
            g, row = _test_term(F, base, t, alpha)
            if row["taken"]:
                problem.base_params = list(problem.base_params) + list(t.params)
                problem.base_terms = tuple(problem.base_terms) + (t,)
                base = Fit((), g.plist, g.u, dict(g.values), g.r, g.chi2, g.n, J=g.J, nfev=g.nfev, mask=g.mask, logdet=g.logdet,
                           start=f"{base.start}+{t.key}", nuisance=g.nuisance, var_rows=g.var_rows, profile=g.profile)
                F.close_pool()  # the workers were forked with the baseline without the term
                F.open_pool()
            out.append(row)
    finally:
        F.close_pool()  # the noise's reading may whiten the fits from here on: the next pool is forked after it
    return base, out


def _declared_after_claim(F: Fitter, fit: Fit, alpha: float, finding: dict, rows: list[dict], cv=None) -> Fit:
    """A declared term the baseline did not take (:func:`_declared_terms`: its gain lay within the misfit of a
    hidden effect) is tested again on the model of a claim, by the same rule (:func:`_test_term`). Taken on, the term is part of the model from there on (its parameters fitted in the
    chain, not a finding): a declared temperature's activation beside a hidden effect (blind friction records at
    0.5-2 K, whose athermal misfit the hidden effect dominates). ``rows`` receives what was tried; the finding is
    noted where a term was taken, and the chain's cross-validation folds start from the taken fit (``cv``). Returns
    the model to continue from."""
    problem = F.problem
    taken = {c.key for c in (getattr(problem, "base_terms", ()) or ())} | {c.key for c in fit.causes}
    for t in list(getattr(problem, "declared_terms", ()) or ()):
        if t.key in taken:
            continue
        g, row = _test_term(F, fit, t, alpha)
        row = {"term": row.pop("term"), "title": row.pop("title"), "after": finding["cause"], **row}
        if row["taken"]:
            finding["notes"] = list(finding.get("notes") or []) + [
                f"the declared conditions' {t.title.lower()} joined the model after this claim (-2 ln L lowered by "
                f"{row['lr_gain']:.1f}; the baseline's gain had been within the hidden effect's misfit)"]
            if cv is not None:  # the folds of the chain start from this optimum, as a claim's do (cv_warm)
                cv.full_fits[tuple(c.key for c in g.causes)] = g
            fit = g
        rows.append(row)
    return fit


def _strained(fit: "Fit", cause) -> bool:
    """Whether one of ``cause``'s parameters sits at a bound of its range that is not its null value (the cause
    pushed to the edge of what it may physically be; a parameter at its null, e.g. a drag's effective height at
    its far limit, is the cause's own limit, not a strain)."""
    names = [p.name for p in fit.plist]
    for p in cause.params:
        if p.name not in names:
            continue
        u = float(fit.u[names.index(p.name)])
        lo_u, hi_u = _u_bounds(p)
        if _at_bound(p, u) and abs(u - _to_u(p, p.null)) > 1e-6 * (hi_u - lo_u):
            return True
    return False


def _beyond_remainder(gains: list[float], fits: list["Fit"]) -> int:
    """The number of leading causes of a greedy chain that are claimed: the longest prefix c_1..c_j in
    which every cause's gain (``gains``: its Delta chi^2 over the model it extended) exceeds the excess
    chi^2 - dof that c_1..c_j leaves, R_j (``fits[j - 1]``).

    Physical reason: R_j is what the catalog's models demonstrably do not describe (their own error,
    or an effect outside the catalog). A cause whose gain is below that remainder is within the size
    of the model error present and may be absorbing part of it (a stick-slip model that misplaces
    slips leaves a slip-structured residual any flexible cause partly fits); a real cause takes its
    signal, and with every real effect in the chain R_j is the noise's ~sqrt(2 dof). For the last
    cause this reads "it takes more than half of the excess it found"; several comparable real
    effects are all claimed when the chain holds them (R small), whatever their order."""
    for j in range(len(fits), 0, -1):
        R = max(fits[j - 1].chi2 - fits[j - 1].dof, 0.0)
        if all(g > R for g in gains[:j]):
            return j
    return 0


def _score_in_order(cands: list[dict], margin: float, score: Callable[[dict], None]) -> None:
    """Evidence (``score`` sets ``d["evidence"]``) of the candidates that pass the LR test, in order of
    their in-sample improvement. The evidence is capped at Delta chi2 / 2, so a cause whose cap is below
    the best evidence so far minus the margin can neither win nor be confounded with the winner: it is
    not cross-validated (``pruned``; exact). A limit of a passing container (a cause's ``limits``) is
    never pruned: the parsimony rule (:func:`_parsimony`) can hand it the lead by its likelihood-ratio
    arm when the container's extra parameter is unsupported, whatever the limit's evidence (a DMT
    truth, force-curve seed 2067: Maugis-Dugdale 4.7 ahead of DMT in chi^2, below the LR line 6.6, but
    DMT's cap 0.07 nats below the pruning line, so the rule never saw it)."""
    limits_of_passing = {key for d in cands if d["lr_pass"] for key in getattr(d["cause"], "limits", ())}
    best_ev = -math.inf
    for d in sorted(cands, key=lambda d: -d["dchi2"]):
        if not d["lr_pass"]:
            continue
        if 0.5 * d["dchi2"] < best_ev - margin and d["cause"].key not in limits_of_passing:
            d["method"] = "not cross-validated: its cap Delta chi2 / 2 is below the winner's evidence minus the margin"
            d["evidence"] = None
            d["pruned"] = True
            continue
        score(d)
        best_ev = max(best_ev, d["evidence"])


def _limit_refits(F: Fitter, causes: list, fits: list) -> list:
    """A cause that is a limit of another (a cause's ``limits``: the keys of the causes it contains
    at a bound of its own parameters, e.g. Maugis-Dugdale -> JKR as lambda -> infinity, DMT as
    lambda -> 0) is fitted again from the container's optimum (its shared parameters) when its own
    fit ended worse than the container's: the limit is then never reported as fitting worse only
    because its multi-start missed the basin the container found (class 2 across causes)."""
    fits = list(fits)
    idx = {c.key: i for i, c in enumerate(causes)}
    for i, c in enumerate(causes):
        for key in getattr(c, "limits", ()):
            j = idx.get(key)
            if j is None or fits[j].score <= fits[i].score:
                continue
            start = {k_: v for k_, v in fits[i].values.items()
                     if any(p.name == k_ for p in fits[j].plist)}
            try:
                g = F.fit(fits[j].causes, [dict(fits[j].values, **start)])
            except DataFormatError:
                continue
            if g.score < fits[j].score:
                g.start = "limit of " + c.key
                fits[j] = g
    return _container_refits(F, causes, fits)


def _container_refits(F: Fitter, causes: list, fits: list) -> list:
    """The converse of :func:`_limit_refits`: a container that ended worse than a limit it contains
    (Maugis-Dugdale behind JKR: its multi-start stopped at an interior lambda on a rugged chi^2) is
    fitted again from the limit's optimum, its own extra parameters at either bound (the limit is
    reached at one of them). A container is then never reported as fitting worse than a cause it
    contains, as no cause is reported worse than the baseline it nests (class 2; found on an AR(1)
    force curve, session 22: Maugis-Dugdale 9.6 of chi^2 behind JKR)."""
    fits = list(fits)
    idx = {c.key: i for i, c in enumerate(causes)}
    for i, c in enumerate(causes):
        lims = [idx[k_] for k_ in getattr(c, "limits", ()) if k_ in idx]
        j = min(lims, key=lambda j_: fits[j_].score, default=None)
        if j is None or fits[j].score >= fits[i].score:
            continue
        shared = {k_: v for k_, v in fits[j].values.items() if any(p.name == k_ for p in fits[i].plist)}
        own = [p for p in c.params if p.name not in shared]
        starts = [{**fits[i].values, **shared, p.name: bound} for p in own for bound in (p.lo, p.hi)]
        try:
            g = F.fit(fits[i].causes, starts or [dict(fits[i].values, **shared)])
        except DataFormatError:
            continue
        if g.score < fits[i].score:
            g.start = "from its limit " + causes[j].key
            fits[i] = g
    return fits


def _akaike(d: dict) -> float:
    """A candidate's in-sample Akaike score against the baseline, in nats: ``dchi2 / 2 - k``."""
    return 0.5 * d["dchi2"] - d["k"]


def _tied_alternative(problem, d: dict, best: dict, margin: float) -> bool:
    """``d`` is an alternative to the leader ``best`` (another contact law: causes of one ``alternative``
    component) whose in-sample Akaike score is within ``margin`` of the leader's, on a problem whose held-out
    comparison of alternatives scatters (``insample_confounds_alternatives``: force curves, next to a jump):
    confounded with it whatever the held-out evidence says (docs/diagnose.md 9.31)."""
    alt = best["cause"].alternative
    return (bool(getattr(problem, "insample_confounds_alternatives", False)) and alt is not None
            and d["cause"].alternative == alt and _akaike(d) >= _akaike(best) - margin)


def _parsimony(claimed: list[dict], margin: float, alpha: float = ALPHA) -> dict[str, Any] | None:
    """Occam between nested causes: when the leader *contains* a claimed cause as a limit (its
    ``limits``) and either that cause's evidence is within ``margin`` of the leader's or the
    leader's extra parameters fail the likelihood-ratio test against it (in-sample chi-square lower
    by no more than :func:`boundary_lr_threshold` of the k extra parameters: the engine's claim rule
    between the two nested models, for a null on the edge of the container's range), the data do not support the leader's extra parameter:
    the contained (simpler) cause leads, and the container is not counted as a confounded rival
    (it is the same explanation plus an unsupported parameter). The LR arm makes the rule immune to
    the scatter of held-out evidence between models of equal in-sample fit. Only a limit with fewer
    parameters than the container is nested in it; a limit of equal size (DMT with its tail's range,
    session 26) is an alternative, which can still take the lead from the nested one by the Akaike
    score, the container then a rival like any other. A container within the margin *behind* one of its
    limits is ranked as if it led: which of them leads by a fraction of the margin must not change the
    verdict. Reorders ``claimed`` in place; returns the note for the report (None, and ``claimed`` in its
    first order, when the rule does not act)."""
    if not claimed:
        return None
    lead = claimed[0]
    # the same rule seen from the other side: the leader is one of a container's limits, and the container
    # is within the margin behind it: the container is ranked as if it led, so that the rule below decides
    # (a JKR truth under AR(1) noise, seed 2049: Maugis-Dugdale 2.7 of chi^2 *behind* JKR at its lambda
    # bound was reported as a confounded rival; had it led by as much, the rule below would have named JKR
    # alone; seed 2001: DMT 0.7 nats ahead of JKR held out, 1.9 behind it by Akaike -- the held-out scatter
    # next to a jump that the rule below exists for). Which of them leads by a fraction of the margin must
    # not change the verdict.
    best = next((d for d in claimed[1:] if lead["cause"].key in getattr(d["cause"], "limits", ())
                 and d["evidence"] >= lead["evidence"] - margin), lead)
    lims = set(getattr(best["cause"], "limits", ()))

    def unsupported(d):
        # the limit is the container at the edge of its extra parameter's range: the LR test's null is on the
        # boundary (:func:`boundary_lr_threshold`; chi2_k(1 - alpha) tested at alpha / 2, and an MD truth at
        # lambda 1.0, seed 2010, Delta chi^2 6.07 over JKR, was handed to JKR, docs/diagnose.md 9.38)
        lr = boundary_lr_threshold(best["k"] - d["k"], alpha)
        return d["evidence"] >= best["evidence"] - margin or best["dchi2"] - d["dchi2"] <= lr

    # only a limit with fewer parameters is nested: DMT with its tail's range fitted (W, zeta_0) has as many
    # as Maugis-Dugdale (W, lambda -- lambda is the Dugdale range in disguise), and MD's lambda -> 0 keeps a
    # Dugdale tail, not DMT's van der Waals one: of equal size, they are alternatives (session 26: an MD
    # truth, seed 2058, lambda 0.73, was handed to a DMT at its shortest tail and MD hidden as its container)
    inner = [d for d in claimed if d is not best and d["cause"].key in lims and best["k"] > d["k"] and unsupported(d)]
    if not inner:
        return None  # the container's extra parameters are supported (or no container): ``claimed`` as it was
    claimed.remove(best)
    claimed.insert(0, best)
    # between the container's limits (JKR and DMT under Maugis-Dugdale, nested or not) the in-sample
    # likelihood with Akaike's parameter count decides, not the held-out evidence: the limits are not nested
    # in each other, and where the data jump (snap-in, pull-off) the held-out evidence of a law is dominated
    # by the few held-out samples next to a jump, whose prediction falls on one side of it or the other --
    # a scatter of several nats that says nothing about the law (a DMT truth, seed 2043: DMT best in
    # sample by 3.7 over JKR, 2.7 nats behind it held out); for the same reason the other limit stays a
    # confounded rival when its evidence *or its in-sample Akaike score* is within the margin of the new
    # leader's (a JKR truth under AR(1) noise, seed 2001: DMT ahead by 1.2 nats in sample, 9 held out)
    siblings = [d for d in claimed[1:] if d["cause"].key in lims]
    new = max(siblings, key=_akaike)  # inner is among them
    for d in siblings:
        if d is not new and _akaike(d) >= _akaike(new) - margin:
            d["sibling_limit"] = True
    claimed.remove(new)
    claimed.insert(0, new)
    if new in inner:  # the container is the leader plus an unsupported parameter: not a rival
        best["contains_leader"] = True
    return {"rule": "a cause that contains a claimed limit with fewer parameters, within the evidence margin or "
                    "unsupported by the likelihood-ratio test against it, does not lead; the container's limits "
                    "are then ranked by their in-sample Akaike score",
            "container": best["cause"].key, "container_evidence": best["evidence"],
            "container_parameters": {p.name: best["fit"].values[p.name] for p in best["cause"].params},
            "contains_leader": bool(best.get("contains_leader"))}


def _fewest_parameters_lead(problem, claimed: list[dict], best: dict, rivals: list[dict], rival_of):
    """Occam within a confounded group (a problem with ``occam_within_group``: modal and spectra). The group's causes
    are within the evidence margin of the leader, or not resolved by the folds: the data do not separate them, so the
    ranking among them is the folds' scatter. Every parameter a cause has beyond another's costs it an Occam factor
    in a Bayes factor (the prior volume it spreads over), which held-out evidence within the margin cannot resolve;
    the cause with the fewest parameters therefore leads (the best by evidence among those), the others stay its
    confounded rivals. Only where the group is the same seen from it (the old leader is its rival). Blind spectrum
    s01 (a modulus error on a flapwise-only record in air): a three-parameter bonded overlap led a group of six by a
    fraction of the margin; a one-parameter cause is named (the thickness error, which the flapwise frequencies do
    not tell from the modulus error; docs/diagnose.md 9.38). Reorders ``claimed``; returns the leader, its
    rivals and the note for the report (None where the rule does not act)."""
    if not rivals or not getattr(problem, "occam_within_group", False):
        return best, rivals, None
    group = [best, *rivals]
    kmin = min(d["k"] for d in group)
    if best["k"] == kmin:
        return best, rivals, None
    new = next(d for d in group if d["k"] == kmin)
    new_rivals = [d for d in claimed if rival_of(d, new)]
    if not any(d is best for d in new_rivals):
        return best, rivals, None
    claimed.remove(new)
    claimed.insert(0, new)
    return new, new_rivals, (f"named first within its confounded group as the cause with the fewest parameters "
                             f"({new['k']}; {best['cause'].key}, with {best['k']}, led by held-out evidence within "
                             "what the data can separate)")


def _evidence(d: dict, ref: Fit, cv: CrossValidation | None, use_cv: bool) -> None:
    fit = d["fit"]
    if use_cv and cv is not None:
        causes = fit.causes
        won = fit.start.split("+")[0]  # a swept fit ("3+sweep") keeps the declared start it began from
        cv.winning_start[tuple(c.key for c in causes)] = int(won) if won.isdigit() else 0
        cv.full_fits[tuple(c.key for c in causes)] = fit
        cv.full_fits.setdefault(tuple(c.key for c in ref.causes), ref)
        if ref.cv is None:
            cv.heldout(ref)
        cv.heldout(fit)
        per_group = ref.cv_fold - fit.cv_fold
        e_cv = 0.5 * (ref.cv - fit.cv)
        d["evidence_cv"] = e_cv
        d["evidence_se"] = 0.5 * float(np.sqrt(len(per_group) * np.var(per_group))) if len(per_group) > 1 else None
        d["evidence"] = min(e_cv, 0.5 * d["dchi2"])
        d["method"] = "cross-validation" + (" (capped at the likelihood ratio)" if e_cv > 0.5 * d["dchi2"] else "")
        if ref.causes and bool(getattr(cv.F.problem, "heldout_predictive", False)):
            # an extension of a claimed chain is also held to the plain held-out error (module docstring, step 6)
            e_plain = 0.5 * (float(np.nansum(ref.cv_r**2)) - float(np.nansum(fit.cv_r**2)))
            d["evidence_plain"] = e_plain
            if e_plain < d["evidence"]:
                d["evidence"] = e_plain
                d["method"] = "cross-validation (plain held-out error: an extension of a claimed cause)"
    else:
        d["evidence"] = _akaike(d)
        d["method"] = "akaike (fewer than 3 groups)"


def _sweep_claim(F: Fitter, d: dict, ref: Fit, cv: CrossValidation | None, use_cv: bool) -> None:
    """A claimed cause's fit (the lead, or an extension taken) walked along the profiles of the parameters whose
    sweep waits for a claim (``CauseParam.sweep_claimed``, :meth:`Fitter.swept`), and where that lowers its chi^2
    beyond ``SWEEP_GAIN`` its gain, held-out evidence (the folds again, warm from the swept optimum) and row
    updated in ``d``. The caller ranks the claims again: a lower chi^2 need not predict the held-out groups
    better. A misaligned scan's angle and stiffness ratio: every held point is a 2D scan, so sweeping every
    candidate cost the three-scan example 22 -> 50 s for a candidate it does not claim, where own 2005's claimed
    angle goes from 6.3 % to 0.1 % off with it (docs/diagnose.md 9.42-9.43).

    The baseline's declared-condition terms (:func:`_declared_terms`) are walked too: their basin was found for the
    baseline, and a claim moves it (blind f05, a scanner's bow on an activated record: chi^2 1122 where the
    activation fitted after the bow reaches 1111)."""
    g = F.swept(d["fit"], (d["cause"],), claimed=True)
    terms = tuple(getattr(F.problem, "base_terms", ()) or ())
    if terms:
        g = F.swept(g, terms)
    if g is d["fit"]:
        return
    d["fit"] = g
    d["dchi2"] = max(ref.score - g.score, 0.0)
    if d.get("evidence") is None:
        return
    if use_cv and cv is not None:
        cv.forget(tuple(c.key for c in g.causes))
    _evidence(d, ref, cv, use_cv)


def _unresolved(best: dict, d: dict, cv: CrossValidation | None, margin: float) -> bool:
    """Neither the folds nor the in-sample fits separate ``d`` from the leader ``best``: its held-out
    deficit is within ``HELDOUT_SE_FACTOR`` standard errors of the paired per-fold differences and
    its in-sample Akaike deficit ``(chi2_d - chi2_best) / 2 + k_d - k_best`` within ``margin``. Both
    are needed: with a handful of folds one badly predicted group can make the standard error as
    large as the difference itself (a cause worse in-sample by 250 in chi^2 is not a rival)."""
    if best.get("evidence_cv") is None or d.get("evidence_cv") is None:
        return False
    ho = best["evidence_cv"] - d["evidence_cv"]
    ins = 0.5 * (_score(d["fit"]) - _score(best["fit"])) + d["k"] - best["k"]
    return ho <= HELDOUT_SE_FACTOR * _heldout_diff_se(best, d, cv) and ins < margin


def _heldout_diff_se(a: dict, b: dict, cv: CrossValidation | None) -> float:
    """Standard error (nats) of the held-out evidence difference of two claimed causes: half the
    ``sqrt(n var)`` of their per-fold held-out score differences (:meth:`CrossValidation.heldout`;
    0 without cross-validation)."""
    ra, rb = a["fit"].cv_fold, b["fit"].cv_fold
    if cv is None or ra is None or rb is None or len(cv.folds) < 2:
        return 0.0
    diff = ra - rb
    return 0.5 * float(np.sqrt(len(diff) * np.var(diff)))


def _candidate_row(d: dict) -> dict[str, Any]:
    f = d["fit"]
    return {"cause": d["cause"].key, "evidence": d["evidence"], "evidence_cv": d.get("evidence_cv"),
            "evidence_se": d.get("evidence_se"), "evidence_method": d.get("method") or "not evaluated (LR test failed "
            "or no significant discrepancy)", "delta_chi2": d["dchi2"], "k": d["k"], "lr_threshold": d["lr_threshold"],
            "lr_pass": d["lr_pass"], "chi2": f.chi2, "heldout_rms": _rms(f.cv_r) if f.cv_r is not None else None,
            "parameters": {p.name: f.values[p.name] for p in d["cause"].params}, "start": f.start}


def _finding(problem, F: Fitter, before: Fit, cand: dict, conf: dict | None, alpha: float = ALPHA) -> dict[str, Any]:
    fit = cand["fit"]
    c = cand["cause"]
    names = [p.name for p in c.params]
    params = parameter_report(F, fit, names, alpha=alpha)
    params.pop("_conditioning", None)
    flags, notes = [], []
    for nm, it in params.items():
        if it["at_bound"] and it["bound_binding"]:
            g = it["bound_gain_chi2"]
            flags.append(f"{nm} at its {it['bound']} bound" + (
                f" (lifting it would gain Delta chi2 {g:.3g} > {it['bound_threshold_chi2']:.3g})" if g is not None else ""))
        elif it["at_bound"]:
            notes.append(f"{nm} at its {it['bound']} bound, which does not bind: lifting it would gain Delta chi2 "
                         f"{it['bound_gain_chi2']:.2g} < {it['bound_threshold_chi2']:.3g} (chi2_1 at 1 - alpha), so the "
                         "estimate equals the bound within the noise")
        if not it.get("identifiable", True):
            flags.append(f"{nm} not identifiable")
    derived = c.derived(fit.values, problem)
    jk = _jackknife(problem, F, fit, names, c)
    if jk:
        for nm, sd in jk["sigma"].items():
            it = params[nm]
            it["sigma_jackknife"] = sd
            if it.get("sigma") is not None and sd > it["sigma"]:
                v = fit.values[nm]
                it.update(sigma_jacobian=it["sigma"], sigma=sd, interval=[v - sd, v + sd],
                          method=f"jackknife over {jk['units']} (larger than the Jacobian's)")
    corr = []
    if fit.J is not None and fit.k > 1:
        with np.errstate(invalid="ignore", divide="ignore"):
            C = np.linalg.pinv(fit.J.T @ fit.J)
            sd = np.sqrt(np.abs(np.diag(C)))
            R = C / np.outer(sd, sd)
        for i, j in itertools.combinations(range(fit.k), 2):
            if np.isfinite(R[i, j]) and abs(R[i, j]) > 0.95 and (fit.plist[i].name in names or fit.plist[j].name in names):
                corr.append({"a": fit.plist[i].name, "b": fit.plist[j].name, "correlation": float(R[i, j])})
    return {
        "cause": c.key, "title": c.title, "evidence": cand["evidence"], "evidence_cv": cand.get("evidence_cv"),
        "evidence_se": cand.get("evidence_se"), "delta_chi2": cand["dchi2"],
        "parameters": params, "derived": derived,
        "derived_sigma_jackknife": jk["derived_sigma"] if jk else None,
        "replicates": jk["replicates"] if jk else None,
        "status": "confounded" if conf else "identified", "confounded_with": conf["causes"][1:] if conf else [],
        "flags": flags, "notes": notes, "correlated_parameters": corr, "note": getattr(c, "note", ""),
        "gain": {
            "residual_rms_before": _rms(before.r), "residual_rms_after": _rms(fit.r),
            "heldout_rms_before": _rms(before.cv_r) if before.cv_r is not None else None,
            "heldout_rms_after": _rms(fit.cv_r) if fit.cv_r is not None else None,
            "chi2_before": before.chi2, "chi2_after": fit.chi2, "p_value_after": fit.p_value,
            "residual_rms_physical_before": problem.physical_rms(before.r),
            "residual_rms_physical_after": problem.physical_rms(fit.r),
            "evaluated_on": "reduced model" if getattr(problem, "reduced", False) else "full model",
        },
    }


def _jackknife(problem, F: Fitter, fit: Fit, names: list[str], cause) -> dict[str, Any] | None:
    """Delete-one-replicate jackknife of a finding's parameters and derived values, for a problem that
    declares ``replicate_units`` (residual rows of independent repeats of the measurement, e.g. the image
    lines of a friction-loop record, each its trace and retrace): the model refitted without each unit in
    turn (from the full fit), ``sigma = sqrt((m - 1)/m sum (theta_i - mean)^2)`` (Efron & Stein 1981). The
    Jacobian's sigma assumes residuals independent at the stated noise; where the repeats scatter more
    (a misfit the model does not carry, correlated along each line) the jackknife says so and is
    reported instead. None for fewer than three units."""
    units = getattr(problem, "replicate_units", None)
    if not units or len(units) < 3:
        return None
    vals, der = [], []
    for u in units:
        mask = np.ones(len(fit.r), bool)
        mask[u] = False
        f = F.fit(fit.causes, [dict(fit.values)], mask)
        vals.append({nm: f.values[nm] for nm in names})
        der.append(cause.derived(f.values, problem))
    m = len(units)

    def sd(xs) -> float:
        xs = np.asarray(xs, float)
        return float(math.sqrt((m - 1) / m * np.sum((xs - xs.mean()) ** 2)))

    keys = [k for k in der[0] if all(isinstance(d.get(k), (int, float)) for d in der)] if der else []
    return {"units": getattr(problem, "replicate_label", f"{m} replicates"),
            "sigma": {nm: sd([v[nm] for v in vals]) for nm in names},
            "derived_sigma": {k: sd([d[k] for d in der]) for k in keys},
            "replicates": [{**v, **{k: d[k] for k in keys}} for v, d in zip(vals, der)]}


def _confounding(problem, best: dict, rivals: list[dict], margin: float) -> dict[str, Any]:
    """The group of causes within ``margin`` nats of the winner and the measurements that separate them."""
    names = [best["cause"].key] + [d["cause"].key for d in rivals]
    fits = [best["fit"]] + [d["fit"] for d in rivals]
    preds: dict[str, dict[str, float]] = {}
    sig: dict[str, float] = {}
    unit: dict[str, str] = {}
    for name, fit in zip(names, fits):
        for m in problem.predict_observables(fit.values, fit.causes):
            preds.setdefault(m["measure"], {})[name] = m["value"]
            sig[m["measure"]] = m["sigma"]
            unit[m["measure"]] = m["unit"]
    pairs = {(i, j) for i in range(len(names)) for j in range(i + 1, len(names))}
    sep_pairs = {}
    for key, pr in preds.items():
        if len(pr) < len(names) or not all(np.isfinite(v) for v in pr.values()) or not sig.get(key):
            continue
        sep_pairs[key] = {(i, j) for i, j in pairs if abs(pr[names[i]] - pr[names[j]]) / sig[key] > 3.0}
    chosen, left = [], set(pairs)
    while left and sep_pairs:
        key = max(sep_pairs, key=lambda k: (len(sep_pairs[k] & left), max(abs(a - b) for a in preds[k].values() for b in preds[k].values()) / sig[k]))
        gain = sep_pairs[key] & left
        if not gain:
            break
        chosen.append({"measure": key, "unit": unit[key], "sigma": sig[key], "predictions": preds[key],
                       "separates_pairs": len(gain)})
        left -= gain
        if len(chosen) == 4:
            break
    return {"causes": names, "evidence": [best["evidence"]] + [d["evidence"] for d in rivals], "margin_nats": margin,
            "separating_measurements": chosen,
            "pairs_left_unseparated": [[names[i], names[j]] for i, j in sorted(left)]}


def _final(problem, F: Fitter, current: Fit, base: Fit, cv, folds, use_cv) -> dict[str, Any]:
    """Re-solve the final model with the full model; defect-corrected refit if the reduced model
    was off by more than 0.3 sigma somewhere; the statistics after."""
    rep: dict[str, Any] = {"causes": [c.key for c in current.causes]}
    fit = current
    full = getattr(problem, "full_residuals", None)
    r_full = None
    iterations = 0
    if full is not None and current.causes:
        r_full = full(fit.values, fit.causes)
        while iterations < 2 and np.nanmax(np.abs(r_full - fit.r)) > 0.3:
            defect = r_full - fit.r
            problem.defect = defect
            try:
                fit2 = F.fit(fit.causes, [fit.values])
            finally:
                problem.defect = None
            iterations += 1
            fit2.r = fit2.r - 0.0  # residuals with the defect are on the full model's scale
            r_full2 = full(fit2.values, fit2.causes)
            if np.sum(r_full2**2) < np.sum(r_full**2):
                fit = Fit(fit2.causes, fit2.plist, fit2.u, fit2.values, fit2.r - 0.0, fit2.chi2, fit2.n, fit2.J,
                          fit2.nfev, fit2.mask, fit.cv, fit.cv_r, fit.start, cv_fold=fit.cv_fold, logdet=fit2.logdet,
                          var_rows=fit2.var_rows)
                r_full = r_full2
            else:
                break
        rep["full_model"] = {"reduced_vs_full_max_sigma": float(np.nanmax(np.abs(r_full - current.r))),
                             "defect_corrected_refits": iterations}
    r_after = r_full if r_full is not None else fit.r
    chi2_after = float(np.sum(r_after**2))
    dof = max(len(r_after) - fit.k, 1)
    rep.update(chi2=chi2_after, dof=dof, p_value=gof_p(chi2_after, dof, problem, F.white), residual_rms=_rms(r_after),
               residual_rms_physical=problem.physical_rms(r_after), residuals=r_after,
               parameters={k: v for k, v in fit.values.items()})
    # a model that carries a fitted variance (``problem.variance_fitted``: friction's thermal slip scatter) can
    # lower its chi-square by widening that variance: there, a chi-square improbably *small* is a misfit too
    vf = getattr(problem, "variance_fitted", None)
    if current.causes and vf is not None and vf(fit.values, fit.causes):
        rep["variance_fitted"] = True
        rep["p_value_lower"] = gof_p_lower(chi2_after, dof, problem, F.white)
    ho = None
    if use_cv and cv is not None and current.causes:
        if fit.cv_r is None:
            cv.heldout(fit)
        cv_r = fit.cv_r + (r_after - fit.r)  # the reduced model's defect, carried to the held-out predictions
        T, p_ho, nho = heldout_statistic(fit, cv_r, folds, problem, F.white)
        ho = {"heldout_rms": _rms(cv_r), "heldout_statistic": T, "heldout_n": nho, "heldout_p_value": p_ho}
        rep.update(ho)
    if current.causes and base.cv_r is not None:
        rep["heldout_rms_before"] = _rms(base.cv_r)
    rep["residual_rms_before"] = _rms(base.r)
    return {"report": rep, "fit": fit, "heldout": ho}


def _verdict(omnibus: bool, findings: list[dict], confounded: list[dict], final: dict, alpha: float,
             targeted: list[str] = ()) -> tuple[str, list[str]]:
    if not findings and not omnibus:
        why = [f"baseline chi-square p >= {alpha}"]
        if targeted:
            why.append(f"{', '.join(targeted)}: likelihood-ratio test passed, held-out evidence not positive")
        return "no-significant-discrepancy", why
    if not findings:
        return "unexplained", ["no catalog cause passes the likelihood-ratio test with positive held-out evidence"]
    if confounded:
        return "confounded", [f"{', '.join(confounded[0]['causes'][1:])} within {confounded[0]['margin_nats']:.2f} nats "
                              f"of {confounded[0]['causes'][0]}"]
    reasons = []
    rep = final["report"]
    if rep["p_value"] < alpha:
        reasons.append(f"the extended model still fails the chi-square test (p = {rep['p_value']:.2g})")
    if rep.get("p_value_lower") is not None and rep["p_value_lower"] < alpha:
        reasons.append(f"residuals smaller than the noise (chi-square {rep['chi2']:.0f} on {rep['dof']} degrees of "
                       f"freedom, lower-tail p = {rep['p_value_lower']:.2g}): the model's fitted variance is overstated")
    ho = final.get("heldout")
    if ho is not None and ho["heldout_p_value"] < alpha:
        reasons.append(f"held-out residuals inconsistent with the noise (held-out RMS {ho['heldout_rms']:.2f} sigma, "
                       f"p = {ho['heldout_p_value']:.2g})")
    for f in findings:
        reasons += [f"{f['cause']}: {fl}" for fl in f["flags"]]
    return ("partly-explained", reasons) if reasons else ("explained", ["all verdict conditions met"])


def run(meas, **kw) -> dict[str, Any]:
    """Read a measurement (path) or take a problem, and diagnose it."""
    from probedyn.diagnose.problems import make_problem

    problem = meas if hasattr(meas, "residuals") else make_problem(meas)
    return diagnose(problem, **kw)
