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

Out of contact (departure 47: the source's tail 2.33–2.34 is a van der Waals law grafted on at the
end point) the model is Maugis' own: the Dugdale stress ``sigma_0`` acts on a disc of radius ``c``
where the gap is below ``h0 = W / sigma_0`` while the surfaces do not touch. The disc pulls each
half-space in by ``2 sigma_0 c / E*`` at its centre and ``4 sigma_0 c / (pi E*)`` at its rim, so that
with the rim's gap equal to ``h0`` and ``C = c / a_unit`` (:func:`dugdale_noncontact`)::

    P_bar = -(pi lam / 2) C^2,     D_bar = C^2 / 2 - C_* C - 2 / (pi lam),     C_* = 8 lam / (3 pi)

from the free state (``C = 0``: the gap reaches ``h0`` at ``D_free = -2 / (pi lam)``) to the first
touch (the centre's gap closes: ``C^2 / 2 + 4 lam (pi - 2) / (3 pi) C = 2 / (pi lam)``), which is the
end point (2.31)–(2.32) exactly (tested: an independent check of both). The branch is stable
(``dD/dC > 0``) for ``C > C_*`` only; it has a stable part, ending at the end point, exactly when the
contact curve is monotone (``lam^3 < 9 pi / (16 (pi - 1))``, ``lam < 0.938``). Under displacement
control the approach stays free up to ``D_free`` and the retract follows the stable part down to
``D(C_*)`` (:meth:`MaugisDugdale.nd_tail`): the Dugdale law's hysteresis, which sets in below the
JKR-like regime. ``lam -> 0``: the rigid Dugdale ramp ``P_bar = -2 (1 - gap / h0)``, DMT's ``-2`` at
contact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
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


def dugdale_noncontact(C, lam: float):
    """``(D_bar, P_bar)`` on the Maugis-Dugdale non-contact branch at Dugdale-zone radius(es) ``C`` (module
    doc): ``D_bar = C^2 / 2 - 8 lam C / (3 pi) - 2 / (pi lam)``, ``P_bar = -(pi lam / 2) C^2``."""
    C = np.asarray(C, dtype=float)
    return C * C / 2.0 - 8.0 * lam / (3.0 * math.pi) * C - dugdale_range(lam), -0.5 * math.pi * lam * C * C


def touch_radius(lam: float) -> float:
    """The Dugdale-zone radius ``C_on`` at which the centre's gap closes (the first touch): the positive root of
    ``C^2 / 2 + 4 lam (pi - 2) / (3 pi) C - 2 / (pi lam) = 0``; the end point (2.31)-(2.32) is there."""
    b = 4.0 * lam * (math.pi - 2.0) / (3.0 * math.pi)
    q = 4.0 / (math.pi * lam)
    return q / (b + math.sqrt(b * b + q))  # -b + sqrt(b^2 + q), rationalised


def dugdale_range(lam: float) -> float:
    """The Dugdale range ``h0 = W / sigma_0`` in Maugis length units, ``2 / (pi lam)`` (0.97 zeta_0, 2.24)."""
    return 2.0 / (math.pi * lam)


@dataclass(frozen=True)
class DugdaleZone:
    """Landmarks of the non-contact branch (module doc), in Maugis units: ``C_*`` (the branch turns, dD/dC = 0),
    ``C_on`` (the first touch: the end point), ``D_free = -h0`` (the free state ends) and the fold
    ``D(C_*) = D_free - C_*^2 / 2`` (the retract's jump-out); a stable part exists where ``C_on > C_*``."""

    c_star: float
    c_on: float
    d_free: float

    @classmethod
    def of(cls, lam: float) -> "DugdaleZone":
        return cls(8.0 * lam / (3.0 * math.pi), touch_radius(lam), -dugdale_range(lam))

    @property
    def stable(self) -> bool:
        return self.c_on > self.c_star

    @property
    def d_fold(self) -> float:
        return self.d_free - 0.5 * self.c_star**2

    def entry(self, branch: str) -> float:
        """Where the stable part is reached: from the free state's end on loading, down to the fold on unloading."""
        return self.d_free if branch == "loading" else self.d_fold


@CONTACT_MODELS.register
class MaugisDugdale(ContactModel):
    """Maugis–Dugdale contact (2.24–2.32, corrected per departure 7) and, out of contact, Maugis' own
    Dugdale-zone branch (module doc, departure 47; :class:`MaugisDugdaleVdW` keeps the source's van der
    Waals tail 2.33–2.34).

    Parameters: see :data:`.base.COMMON_PARAMS` (``lam`` sets the work of adhesion through
    2.24). ``lam = 0`` is the DMT limit (2.20), ``lam -> infinity`` the JKR limit.
    """

    key: ClassVar[str] = "md"
    title: ClassVar[str] = "Maugis-Dugdale"
    #: out of contact: Maugis' own Dugdale zone (True) or the source's grafted van der Waals tail (``md-vdw``)
    own_noncontact: ClassVar[bool] = True
    source: ClassVar[str] = "(2.24)-(2.32), corrected: departure 7; out of contact Maugis' own Dugdale zone: departure 47"

    def nd_curve(self, A):
        D, P, dD, dP, _ = md_curve(A, self.lam)
        return D, P, dD, dP

    def nd_key(self) -> tuple:
        """The normalised curve depends on lambda alone (a cache key for its polylines; to 12 digits: lambda
        recomputed from z0 = f(lambda, W) differs in its last bits as W changes)."""
        return ("md", float(f"{self.lam:.12g}"))

    def nd_endpoint(self):
        return endpoint(self.lam)

    # ------------------------------------------------------------------ the non-contact branch
    @property
    def has_noncontact_branch(self) -> bool:
        return self._dugdale() is not None

    def _dugdale(self) -> DugdaleZone | None:
        """The non-contact branch's landmarks (:class:`DugdaleZone`); None at lam = 0 (DMT: no range) and for the
        source's grafted tail (``md-vdw``)."""
        if self.lam == 0 or not self.own_noncontact:
            return None
        return DugdaleZone.of(self.lam)

    def nd_edge(self, branch="loading") -> float:
        """Loading: the contact forms where the free state ends (``D_free``, the gap reaches ``h0``) if that is
        past the end point, else at the end point ``D0``; unloading: the contact curve's turning point."""
        dg = self._dugdale()
        if branch == "loading" and dg is not None:
            return max(self.nd_endpoint()[0], dg.d_free)
        return super().nd_edge(branch)

    def nd_tail(self, D, branch="loading"):
        """``(P_bar, dP_bar/dD_bar)`` out of contact: the stable part of the Dugdale non-contact branch
        (``C >= C_*``, inverted as ``C = C_* + sqrt(C_*^2 + 2 (D + 2 / (pi lam)))``) where the branch is reached
        -- on loading from ``D_free`` on (the free state ends there), on unloading down to its fold ``D(C_*)``
        -- and zero (free) elsewhere. ``lam = 0``: flat at ``P0 = -2`` (the DMT limit); ``md-vdw``: the source's
        van der Waals tail (:meth:`.base.ContactModel.nd_tail`)."""
        D = np.asarray(D, dtype=float)
        dg = self._dugdale()
        if dg is None:  # the van der Waals tail of the base class (flat at P0 = -2 for lam = 0)
            return super().nd_tail(D, branch)
        P, dP = np.zeros_like(D), np.zeros_like(D)
        if not dg.stable:  # no stable non-contact state (lam >= 0.938): free up to the contact
            return P, dP
        cs = dg.c_star
        on = (D >= dg.entry(branch)) & (D <= self.nd_endpoint()[0])
        if np.any(on):
            root = np.sqrt(np.maximum(cs * cs + 2.0 * (D[on] - dg.d_free), 0.0))
            C = cs + root
            P[on] = -0.5 * math.pi * self.lam * C * C
            with np.errstate(divide="ignore"):
                dP[on] = np.where(root > 0, -math.pi * self.lam * C / np.where(root > 0, root, 1.0), -np.inf)
        return P, dP

    def nd_pull_off(self) -> dict[str, float]:
        """As :meth:`.base.ContactModel.nd_pull_off`; under displacement control a law with a stable non-contact
        part (``lam < 0.938``) jumps out at that part's fold ``C_*`` (``D = D_free - C_*^2 / 2``,
        ``P = -(pi lam / 2) C_*^2``), not at the end point."""
        out = super().nd_pull_off()
        dg = self._dugdale()
        if dg is not None and dg.stable:
            out.update(D_jump_out=dg.d_fold, P_jump_out=-0.5 * math.pi * self.lam * dg.c_star**2, A_jump_out=0.0)
        return out

    def nd_tail_knots(self, branch="loading") -> np.ndarray:
        """The branch's ends (with the free side of its discontinuity) and 64 points uniform in ``C`` on its stable
        part: a polyline of the tail resolves the fold near ``D(C_*)`` and the jump at ``D_free``."""
        dg = self._dugdale()
        if dg is None or not dg.stable:
            return np.array([])
        c_lo = 2.0 * dg.c_star if branch == "loading" else dg.c_star  # D(2 C_*) = D_free
        if c_lo >= dg.c_on:
            return np.array([])
        D = dugdale_noncontact(np.linspace(c_lo, dg.c_on, 64), self.lam)[0]
        D[0] = dg.entry(branch)  # exactly (the formula's rounding aside)
        return np.concatenate([[np.nextafter(D[0], -np.inf)], D])

    def nd_noncontact_path(self, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
        """``(D_bar, P_bar)`` along the whole non-contact branch, its unstable part included, from the free state
        (``C = 0``) to the first touch (``C_on``: the end point); for the equilibrium path of a force curve."""
        dg = self._dugdale()
        if dg is None:
            return super().nd_noncontact_path(n)
        return dugdale_noncontact(np.linspace(0.0, dg.c_on, n), self.lam)


@CONTACT_MODELS.register
class MaugisDugdaleVdW(MaugisDugdale):
    """The source's Maugis-Dugdale (2.24)-(2.35): the contact curve of :class:`MaugisDugdale` with the van der
    Waals tail (2.33)-(2.34) grafted on at the end point instead of Maugis' own non-contact branch
    (:meth:`.base.ContactModel.nd_tail`: the Hamaker law ``-H R / (6 d^2)``, ``H = 12 pi W zeta_0^2``, its gap
    origin placed so that it equals ``P0`` (2.31) at ``D0`` (2.32); the print's
    ``-I0 (D0 - z0)^2 / (D - z0)^2`` has that form, its sign conventions and ``z0_bar`` fixed as in
    docs/contact.md). A long-range attraction beyond the Dugdale range: the model of the source's nano-placing
    (chapter 4), where the tail recaptures a released sample."""

    key: ClassVar[str] = "md-vdw"
    title: ClassVar[str] = "Maugis-Dugdale with the source's van der Waals tail"
    source: ClassVar[str] = "(2.24)-(2.35) as printed (tail 2.33-2.34), corrected: departure 7"
    own_noncontact: ClassVar[bool] = False
