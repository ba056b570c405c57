"""Tail probabilities and quantiles of the chi-square and normal laws, from :mod:`scipy.special`.

The same special functions ``scipy.stats.chi2`` and ``scipy.stats.norm`` evaluate (``chdtrc``,
``chdtri``, ``gammaincinv``, ``ndtr``, ``ndtri``), so the numbers are identical, without importing
:mod:`scipy.stats` (0.28 s of every diagnosis's start-up, measured on the 2-core CI machine; the
engine needs four functions of it; friction and spectra use the same ones). ``k`` is the number of degrees of freedom (k > 0).
"""
from __future__ import annotations

from scipy import special


class chi2:  # noqa: N801  (named as scipy.stats.chi2, whose four methods it stands for)
    """The chi-square law of ``k`` degrees of freedom."""

    @staticmethod
    def sf(x, k):
        """P(X > x)."""
        return special.chdtrc(k, x)

    @staticmethod
    def cdf(x, k):
        """P(X <= x)."""
        return special.chdtr(k, x)

    @staticmethod
    def isf(p, k):
        """The x with P(X > x) = p."""
        return special.chdtri(k, p)

    @staticmethod
    def ppf(q, k):
        """The x with P(X <= x) = q."""
        return 2.0 * special.gammaincinv(0.5 * k, q)


class norm:  # noqa: N801
    """The standard normal law."""

    @staticmethod
    def sf(x):
        """P(X > x)."""
        return special.ndtr(-x)

    @staticmethod
    def isf(p):
        """The x with P(X > x) = p."""
        return -special.ndtri(p)
