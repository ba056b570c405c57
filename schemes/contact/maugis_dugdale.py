"""Maugis–Dugdale (MD) contact of a sphere on a flat: eqs 2.24–2.35 of the source, corrected.

Maugis, J. Colloid Interface Sci. 150 (1992) 243. A Dugdale (constant) adhesive stress
``sigma_0`` acts in an annulus ``a < r < c`` outside the contact radius ``a``; ``m = c / a``.
In the normalised variables of :mod:`.base` (``A``, ``P_bar``, ``D_bar``, transition parameter
``lam`` of 2.24) the model is, with ``s = sqrt(m^2 - 1)`` and ``t = atan(s)``:

* (2.25)  ``1 = lam A^2 / 2 [s + (m^2 - 2) t] + 4 lam^2 A / 3 [1 - m + s t]``
* (2.26)  ``D_bar = A^2 - 4/3 lam A s``               (departure 7: the factor A was missing)
* (2.27)  ``P_bar = A^3 - lam A^2 [s + m^2 t]``        (departure 7: atan(sqrt(m^2-1)), not atan(m^2-1))
* (2.28–2.30) dimensional units, with ``K`` (not ``k``) in (2.30)

Solution strategy (the robust one the source's "solve 2.25 and 2.26 simultaneously" is not):
the curve is parametrised by the contact radius ``A``. For fixed ``A > 0``, ``lam > 0`` the
right-hand side of (2.25) is a sum of ``g1(s) = s + (s^2 - 1) atan(s)`` and
``g2(s) = s atan(s) - (m - 1)`` with positive weights; both vanish at ``s = 0`` and are strictly
increasing (``g1' = 2 s atan(s) + 2 s^2 / m^2 > 0``, ``g2' = atan(s) - s (m - 1) / m^2 > 0``
because ``atan(s) >= s / m``) and unbounded. So (2.25) has exactly one root ``s > 0``. It is
found by a bracketed, vectorised Newton iteration on ``ln(rhs(s))`` against ``ln(s)`` (a nearly
linear function of slope 2–3, so Newton converges in a few steps from anywhere; a bisection
fallback keeps every iterate inside the bracket). ``g1`` is evaluated with the series of
``s - atan(s)`` for small ``s`` (it cancels to ``4/3 s^3``), ``g2`` as
``s atan(s) - s^2 / (1 + m)``, so the JKR end (``s -> 0``) keeps full relative precision.

Limits used by the tests: ``lam -> infinity`` gives JKR (``P_bar = A^3 - sqrt(6 A^3)``,
pull-off -1.5); ``lam -> 0`` gives DMT (``P_bar = A^3 - 2``, pull-off -2); ``A -> 0`` gives the
end point (2.31)–(2.32), derived independently in the docs.

The non-contact tail (2.33–2.34) is that of :meth:`.base.ContactModel.nd_tail`: the Hamaker
law ``-H R / (6 d^2)`` with the same ``H = 12 pi W zeta_0^2`` as the DMT model, its gap origin
placed so that it equals ``P0`` (2.31) at ``D0`` (2.32). The source's form
``-I0 (D0 - z0)^2 / (D - z0)^2`` is the same functional form; its sign conventions and its
``z0_bar`` are not defined in the print and are fixed here as explained in docs/contact.md.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from probedyn.core.errors import SolverError

from .base import CONTACT_MODELS, ContactModel

_SERIES_S = 0.1  # below this, s - atan(s) by its series (14 terms: error < 1e-17 relative)


def _s_minus_atan(s: np.ndarray) -> np.ndarray:
    """``s - atan(s)`` without cancellation for small ``s``."""
    out = s - np.arctan(s)
    small = s < _SERIES_S
    if np.any(small):
        x = s[small]
        x2 = x * x
        acc = np.zeros_like(x)
        term = x * x2  # s^3
        for k in range(1, 15):
            acc += (-1) ** (k + 1) * term / (2 * k + 1)
            term = term * x2
        out[small] = acc
    return out


def g_functions(s: np.ndarray):
    """``g1, g2, g1', g2'`` (derivatives with respect to s) of the Maugis equation (2.25)."""
    s = np.asarray(s, dtype=float)
    m = np.hypot(1.0, s)
    t = np.arctan(s)
    g1 = _s_minus_atan(s) + s * s * t
    g2 = s * t - s * s / (1.0 + m)
    dg1 = 2.0 * s * t + 2.0 * s * s / (m * m)
    dg2 = t - s * s * s / (m * m * (1.0 + m))  # s (m - 1) / m^2 with m - 1 = s^2 / (1 + m)
    return g1, g2, dg1, dg2


def _g4(s):  # compiled by numba on first use: the scalar :func:`g_functions`, and atan(s)
    m = math.hypot(1.0, s)
    t = math.atan(s)
    return (_sma(s) + s * s * t, s * t - s * s / (1.0 + m), 2.0 * s * t + 2.0 * s * s / (m * m),
            t - s * s * s / (m * m * (1.0 + m)), t)


def _root1(a, lam, tol, maxiter):  # compiled by numba on first use (:func:`_compiled`)
    """``(s, status)`` for one ``A = a``: bracketed Newton on ``ln(rhs(s)) = 0`` in ``x = ln s`` (bracket
    [-60, 60]); status 0 converged, 1 not converged, 2 no sign change over the bracket (checked when the
    iterate ends at a bracket end: a root inside it needs no check)."""
    c1 = 0.5 * lam * a * a
    c2 = 4.0 / 3.0 * lam * lam * a
    lo, hi = -60.0, 60.0
    x = math.log(min(math.sqrt(1.5 / (lam * lam * a)), 2.0 / (a * math.sqrt(math.pi * lam))))
    x = min(max(x, lo + 1e-3), hi - 1e-3)
    for _ in range(maxiter):
        s = math.exp(x)
        g1, g2, dg1, dg2, t = _g4(s)
        rhs = c1 * g1 + c2 * g2
        f = math.log(rhs)
        df = s * (c1 * dg1 + c2 * dg2) / rhs
        if f < 0:
            lo = x
        if f > 0:
            hi = x
        xn = x - f / df
        if not (lo <= xn <= hi) or not math.isfinite(xn):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= tol:
            if abs(xn) > 59.0:  # at a bracket end: is there a sign change at all?
                for j in range(2):
                    g1e, g2e, _, _, _ = _g4(math.exp(-60.0 if j == 0 else 60.0))
                    fe = math.log(c1 * g1e + c2 * g2e)
                    if (j == 0 and fe >= 0.0) or (j == 1 and fe <= 0.0):
                        return math.exp(xn), 2
            return math.exp(xn), 0
        x = xn
    return math.exp(x), 1


def _root_kernel(A, lam, tol, maxiter, out):
    """:func:`_root1` at every ``A[i]`` into ``out[i]``; returns -1 when done, else ``i`` (point ``i`` did not
    converge) or ``-2 - i`` (no sign change at point ``i``)."""
    for i in range(A.shape[0]):
        s, status = _root1(A[i], lam, tol, maxiter)
        if status == 1:
            return i
        if status == 2:
            return -2 - i
        out[i] = s
    return -1


def _curve_kernel(A, lam, tol, maxiter, D, P, dD, dP, S):
    """:func:`md_curve` point by point (its formulas, at the root :func:`_root1`); return code as
    :func:`_root_kernel`."""
    for i in range(A.shape[0]):
        a = A[i]
        s, status = _root1(a, lam, tol, maxiter)
        if status == 1:
            return i
        if status == 2:
            return -2 - i
        g1, g2, dg1, dg2, t = _g4(s)
        m2 = 1.0 + s * s
        F_A = lam * a * g1 + 4.0 / 3.0 * lam * lam * g2
        F_s = 0.5 * lam * a * a * dg1 + 4.0 / 3.0 * lam * lam * a * dg2
        ds = -F_A / F_s
        h = s + m2 * t
        dh = 2.0 + 2.0 * s * t
        D[i] = a * a - 4.0 / 3.0 * lam * a * s
        P[i] = a * a * a - lam * a * a * h
        dD[i] = 2 * a - 4.0 / 3.0 * lam * (s + a * ds)
        dP[i] = 3 * a * a - 2 * lam * a * h - lam * a * a * dh * ds
        S[i] = s
    return -1


def _sma(s):  # scalar s - atan(s), as :func:`_s_minus_atan`
    if s >= _SERIES_S:
        return s - math.atan(s)
    x2 = s * s
    acc = 0.0
    term = s * x2
    sign = 1.0
    for k in range(1, 15):
        acc += sign * term / (2 * k + 1)
        term = term * x2
        sign = -sign
    return acc


_JIT: dict = {}


def _compiled(kernel: str):
    """``kernel`` (:func:`_root_kernel`, :func:`_curve_kernel`) compiled with numba on first use (cached on
    disk): listing the contact registry (CLI help) imports this module and should not import numba."""
    if not _JIT:
        from numba import njit

        g = globals()
        for name in ("_sma", "_g4", "_root1", "_root_kernel", "_curve_kernel"):  # callees first: numba binds globals
            g[name] = njit(cache=True)(g[name])
            _JIT[name] = g[name]
    return _JIT[kernel]


def _raise_on(flag: int, A: np.ndarray, lam: float) -> None:
    if flag <= -2:
        raise SolverError(f"Maugis equation: no sign change in the bracket (lam={lam:g}, A={A[-2 - flag]:g})")
    if flag >= 0:
        raise SolverError(f"Maugis equation did not converge (lam={lam:g}, A={A[flag]:g})")


def solve_s(A, lam: float, tol: float = 1e-14, maxiter: int = 200) -> np.ndarray:
    """Root ``s = sqrt(m^2 - 1) > 0`` of the Maugis equation (2.25) for each ``A > 0``.

    Bracketed Newton on ``ln(rhs)`` vs ``ln(s)`` (bracket ``ln s`` in [-60, 60]) from the smaller of the
    two one-term solutions (JKR-like ``2/3 lam^2 A s^2 = 1``, DMT-like ``lam pi A^2 s^2 / 4 = 1``), point by
    point in a compiled loop (a force-curve fit solves it some 10^5 times: 1 ms per 600 points vectorised,
    a tenth of that compiled); raises :class:`SolverError` if any point fails to converge (never observed for
    1e-4 <= lam <= 1e4, 1e-10 <= A <= 1e4).
    """
    A = np.ascontiguousarray(np.atleast_1d(np.asarray(A, dtype=float)))
    if lam <= 0:
        raise SolverError("solve_s needs lam > 0 (lam = 0 is the DMT model)")
    out = np.empty(A.shape)
    _raise_on(_compiled("_root_kernel")(A.ravel(), float(lam), float(tol), int(maxiter), out.reshape(-1)), A.ravel(), lam)
    return out


def endpoint(lam: float) -> tuple[float, float]:
    """``(D0, P0)``: the ``A -> 0, m -> infinity`` end of the MD curve, eqs (2.32), (2.31)."""
    if lam == 0:
        return 0.0, -2.0
    q = 9 * math.pi * lam / (math.pi - 2) ** 2
    # sqrt(4 lam^4 + q) - 2 lam^2, rationalised (no cancellation at large lam)
    root = q / (math.sqrt(4 * lam**4 + q) + 2 * lam**2)
    P0 = -2.0 + 8 * lam * (math.pi - 2) ** 2 / (9 * math.pi) * root
    D0 = -8 * (math.pi - 2) / (9 * math.pi) * root
    return D0, P0


def md_curve(A, lam: float):
    """``(D_bar, P_bar, dD_bar/dA, dP_bar/dA, s)`` along the MD curve (2.25)–(2.27).

    Derivatives by implicit differentiation of (2.25): ``ds/dA = -F_A / F_s``.
    """
    A = np.atleast_1d(np.asarray(A, dtype=float))
    if lam == 0:  # DMT: m -> infinity, D = A^2, P = A^3 - 2
        return A * A, A**3 - 2.0, 2 * A, 3 * A * A, np.full_like(A, np.inf)
    if lam < 0:
        raise SolverError("md_curve needs lam >= 0")
    # point by point in the compiled loop (:func:`_curve_kernel`): the root (:func:`solve_s`), then with
    # g1, g2 of :func:`g_functions`, h = s + m^2 atan(s):
    #   D = A^2 - 4/3 lam A s,  P = A^3 - lam A^2 h,  ds/dA = -F_A / F_s
    Af = np.ascontiguousarray(A.ravel())
    D, P, dD, dP, s = (np.empty(Af.shape) for _ in range(5))
    _raise_on(_compiled("_curve_kernel")(Af, float(lam), 1e-14, 200, D, P, dD, dP, s), Af, lam)
    return tuple(v.reshape(A.shape) for v in (D, P, dD, dP, s))


@CONTACT_MODELS.register
class MaugisDugdale(ContactModel):
    """Maugis–Dugdale contact (2.24–2.35, corrected per departure 7) with the
    continuous van der Waals tail (2.33–2.34).

    Parameters: see :data:`.base.COMMON_PARAMS` (``lam`` sets the work of adhesion through
    2.24). ``lam = 0`` is the DMT limit (2.20), ``lam -> infinity`` the JKR limit.
    """

    key: ClassVar[str] = "md"
    title: ClassVar[str] = "Maugis-Dugdale"
    source: ClassVar[str] = "(2.24)-(2.35), corrected: departure 7"

    def nd_curve(self, A):
        D, P, dD, dP, _ = md_curve(A, self.lam)
        return D, P, dD, dP

    def nd_key(self) -> tuple:
        """The normalised curve depends on lambda alone (a cache key for its polylines; to 12 digits: lambda
        recomputed from z0 = f(lambda, W) differs in its last bits as W changes)."""
        return ("md", float(f"{self.lam:.12g}"))

    def nd_endpoint(self):
        return endpoint(self.lam)
