"""A record whose model is a mixture, read sample by sample: each sample's probability integral transform.

A friction record at a declared temperature is predicted as a mixture (docs/diagnose.md 9.56-9.58): each slip of
the path happens at one of the slip point's quantile nodes ``j`` (probability ``w_j``), and every sample that slip
reaches then reads the force ``mu_i + o_ij``; on top the detector's and the tip's thermal noise are Gaussian,
variance ``s_i^2``. The samples one slip reaches share its node.

The Gaussian chi-square of the mixture's mean and variance, ``sum (y - m)^2 / (s^2 + v)``, is far from ``chi2_n``
under such a law: a sample either slipped or not, and its fourth moment is a two-point law's. Under the model's own
mixture (blind g09's baseline, simulated) its variance is 56-118 times ``chi2_n``'s, and a test at 1 % rejects the
model that generated the record in 17-23 % of records; a sample between the branches, which the model cannot
produce, reads a modest residual (the last sample of a segment at 26-44 sigma from every realization, -2.8 in the
Gaussian residual, 9.58).

Each sample's probability integral transform through its own mixture,

    u_i = sum_j w_j Phi((y_i - mu_i - o_ij) / s_i),     z_i = Phi^-1(u_i),

is a standard normal under the model whatever the mixture (Diebold, Gunther & Tay 1998 for the PIT as the test of a
predictive law; at a Gaussian model, one node, ``z`` is the standardised residual). ``T = sum z_i^2`` has the mean
``n``. The samples of one slip share its node, so their ``z_i^2`` are correlated: given the node ``j`` each ``z_i``
depends on its own noise only, so ``Cov(z_i^2, z_k^2) = sum_j w_j g_ij g_kj - 1`` with ``g_ij = E[z_i^2 | j]``
(Gauss-Hermite quadrature over the noise). ``T`` is tested as a scaled chi-square of the same mean and variance
(Satterthwaite 1946). A Rosenblatt transform (conditioning each sample on the slip's samples before it) would make
the scores independent, but it also takes the joint law of a slip's samples from the model's translated path to the
letter; the marginal scores ask less of it.

What it is used for (docs/diagnose.md 9.58): the engine reports it beside the Gaussian chi-square test
(``engine.slip_law_check``) and the verdict does not read it. It checks the slip law's *support*: a sample the
mixture cannot produce is far out whatever its Gaussian residual, and it found three model errors at segment ends
(blind g09). But the model's slip quantiles are a deterministic path's, translated: a record's slip a fiftieth of a
sample beyond the latest quantile reads as a 12-sigma sample (blind g03, 4.2 K: T gives p = 1e-4 where the Gaussian
chi-square gives 0.69), so as a test it would declare unexplained nulls whose slip law is right to 0.01 a.

Assumptions: the nodes carry the slip's law (a midpoint rule in probability, 60 nodes, friction.slip_nodes); a
sample reached by two slips keeps the larger one's nodes and takes the other's variance as Gaussian (the two slips'
overlap is a few samples at the reach's ends); the noise is white (a whitened fit's residuals are tested as they
are)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

#: Gauss-Hermite (probabilists') nodes for ``E[z^2 | node]`` over the Gaussian noise
HERMITE_POINTS = 24


@dataclass
class SlipMixture:
    """The discrete part of a model's law: per (sample, slip) pair, the sample's offsets ``offsets[:, p]`` from its
    mean at the slip's nodes of probability ``weights`` (summing to 1); ``group[p]`` the slip. ``sample`` indexes the
    record's samples."""
    sample: np.ndarray
    group: np.ndarray
    offsets: np.ndarray
    weights: np.ndarray


@dataclass
class PitTest:
    """The probability integral transform's statistic ``T = sum z^2`` over ``n`` samples and the ratio of its variance
    under the model to ``chi2_n``'s (``var_ratio``, >= 1 where a slip's samples share its node)."""
    z: np.ndarray
    T: float
    n: int
    var_ratio: float

    def p_value(self, dof: int | None = None) -> float:
        """``P(T' > T)`` for ``T'`` the scaled chi-square of mean ``dof`` (default ``n``) and variance ``2 dof
        var_ratio``: ``T / c`` on ``dof / c`` degrees of freedom, ``c = var_ratio``."""
        from probedyn.diagnose.tails import chi2

        d = float(self.n if dof is None else dof)
        c = max(float(self.var_ratio), 1e-12)
        return float(chi2.sf(self.T / c, max(d / c, 1e-9)))


def _dominant(parts: list[SlipMixture]) -> dict[int, tuple[float, int, np.ndarray, np.ndarray]]:
    """Per sample the slip of the largest variance: ``(variance, slip, offsets about their mean, weights)``. The
    other slips reaching the sample keep their variance in the Gaussian part."""
    pairs: dict[tuple[int, int], list] = {}
    for P in parts:
        for p, (i, g) in enumerate(zip(P.sample.tolist(), P.group.tolist())):
            key = (i, g)
            if key in pairs:  # one slip's own segment and its carry across a reversal: the same node
                pairs[key][0] = pairs[key][0] + P.offsets[:, p]
            else:
                pairs[key] = [P.offsets[:, p].copy(), P.weights]
    best: dict[int, tuple[float, int, np.ndarray, np.ndarray]] = {}
    for (i, g), (o, w) in pairs.items():
        o = o - float(np.sum(w * o))
        v = float(np.sum(w * o**2))
        if i not in best or v > best[i][0]:
            best[i] = (v, g, o, w)
    return best


def _score(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The normal score of a tail pair (logarithms): accurate in either tail."""
    return np.where(lo < hi, special.ndtri_exp(np.minimum(lo, 0.0)), -special.ndtri_exp(np.minimum(hi, 0.0)))


def pit_test(e: np.ndarray, total: np.ndarray, parts: list[SlipMixture], use: np.ndarray | None = None,
             variance: bool = True) -> PitTest:
    """The probability integral transform of residuals ``e = y - mean`` (the mixture's mean) under the model whose
    variance per sample is ``total`` (the noise's and the mixture's): Gaussian noise convolved with the discrete slip
    parts ``parts``. ``use``: the samples tested (a boolean mask). Returns the scores over the tested samples, in
    order, their ``T = sum z^2`` and its variance under the model relative to ``chi2_n`` (the module's text; a
    property of the model, not of the data: ``variance=False`` leaves it at 1, for records drawn from one model)."""
    e = np.asarray(e, float)
    n = len(e)
    use = np.ones(n, bool) if use is None else np.asarray(use, bool)
    best = _dominant(parts)
    s2 = np.array(total, float)  # the total holds every slip's variance; the dominant one's is the nodes'
    for i, (v, _, _, _) in best.items():
        s2[i] -= v
    if np.any(s2[use] <= 0):
        raise ValueError("pit_test: the variance left to the noise must be positive")
    s = np.sqrt(s2)
    z = np.where(use, e / s, np.nan)
    rows = [(i, g, o, w) for i, (v, g, o, w) in best.items() if use[i] and v > 0]
    if rows:
        K = max(len(r[2]) for r in rows)
        idx = np.array([r[0] for r in rows])
        O = np.zeros((len(rows), K))
        W = np.zeros((len(rows), K))
        for a, (_, _, o, w) in enumerate(rows):
            O[a, :len(o)], W[a, :len(w)] = o, w
        S = s[idx]
        # the data's scores, in logarithms (a sample far outside its mixture keeps its size)
        t = (e[idx][:, None] - O) / S[:, None]
        lw = np.log(np.maximum(W, 1e-300))
        lo = special.logsumexp(lw + special.log_ndtr(t), axis=1)
        hi = special.logsumexp(lw + special.log_ndtr(-t), axis=1)
        z[idx] = _score(lo, hi)
    extra = 0.0
    if rows and variance:
        # E[z^2 | node j] per sample: the sample at node j's offset plus the Gaussian noise (Gauss-Hermite)
        t_gh, w_gh = np.polynomial.hermite_e.hermegauss(HERMITE_POINTS)
        w_gh = w_gh / w_gh.sum()
        G = np.empty((len(rows), K))
        for c0 in range(0, len(rows), 32):
            c = slice(c0, c0 + 32)
            x = (O[c][:, :, None] - O[c][:, None, :])[:, :, :, None] / S[c][:, None, None, None] + t_gh  # (s, j, l, q)
            u = np.einsum("sl,sjlq->sjq", W[c], special.ndtr(x))
            G[c] = (special.ndtri(np.clip(u, 1e-300, 1.0 - 1e-16)) ** 2) @ w_gh
        groups: dict[int, list[int]] = {}
        for a, r in enumerate(rows):
            groups.setdefault(r[1], []).append(a)
        for members in groups.values():
            if len(members) < 2:
                continue
            Gm, w = G[members], W[members[0]]
            C = (Gm * w[None, :]) @ Gm.T - 1.0  # Cov(z_i^2, z_k^2) over the node
            extra += float(np.sum(C) - np.trace(C))
    zu = z[use]
    nu = int(use.sum())
    return PitTest(zu, float(zu @ zu), nu, 1.0 + extra / (2.0 * max(nu, 1)))
