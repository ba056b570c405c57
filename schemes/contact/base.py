"""Common machinery of the tip–sample contact models (section 2.2 of the source).

Conventions (all models)
------------------------
* ``delta`` is the **penetration** (approach of the two bodies beyond first touch), in m:
  ``delta > 0`` overlap, ``delta < 0`` a gap of ``-delta`` measured from the point where the
  contact disappears (see the tail below).
* The interaction force ``P`` is the **load** the sample exerts on the tip along the common
  normal, in N, **positive = repulsive** (compressive), negative = adhesive (tensile).
* Normalisation of Maugis (1992) and of eqs 2.28–2.30 of the source (with departure 7:
  eq 2.30 uses the same ``K`` as 2.28)::

      A     = a     / (pi W R^2 / K)^(1/3)          contact radius
      P_bar = P     / (pi W R)                       load
      D_bar = delta / (pi^2 W^2 R / K^2)^(1/3)       penetration

  with ``K = 4/3 E*`` (Maugis' elastic constant), ``E*`` from (2.21) and the effective radius
  ``R`` from (2.21).

Every model is a curve parametrised by the contact radius ``A >= 0``:
``(D_bar(A), P_bar(A))`` plus a **non-contact tail** ``P_bar(D_bar)`` for penetrations beyond
the ``A -> 0`` end point ``(D0, P0)``. Parametrising by ``A`` is what makes the Maugis–Dugdale
solve robust: for a given ``A`` the Maugis equation has exactly one root ``m`` (proved in
``maugis_dugdale.py``), whereas for a given penetration there can be zero, one or two contact
states (the JKR-like S-shaped curve has an unstable branch).

Branches of ``force(delta)``:

* the curve ``D_bar(A)`` either increases monotonically (DMT-like) or first decreases to a
  minimum ``D_min`` at ``A_*`` (the jump-out point under displacement control) and then
  increases (JKR-like). ``A >= A_*`` is the **stable** branch, ``0 < A < A_*`` the
  **unstable** one.
* ``branch="loading"`` (approach): tail for ``D_bar < D0``, stable branch for ``D_bar >= D0``.
  For a JKR-like curve the force jumps at ``D0`` from the tail value to the stable branch
  (the jump-into-contact instability of a displacement-controlled approach).
* ``branch="unloading"`` (retraction): stable branch down to ``D_min``, tail below it (the
  jump-out). For a DMT-like curve both branches are the same continuous function.
* ``branch="unstable"``: the unstable contact branch for ``D_min <= D_bar <= D0`` (NaN outside).

Force at a given penetration: a table of the curve (dense in ``A``) gives, by linear
interpolation of ``A`` against ``D_bar`` on the monotone branch, a bracket and a first guess;
a safeguarded Newton iteration on ``D_bar(A) - D_target`` with the analytic ``dD_bar/dA``
then lands on the curve to machine precision. All of it is vectorised.

Parameters (SI, shared by all models): Table 4.1 of the source (tip and sample moduli, Poisson
ratios and radii, Hamaker constant) and zeta_0 from Table 4.4, read from
:mod:`probedyn.core.presets`. The work of adhesion defaults to the Hamaker value ``W = H / (12 pi zeta_0^2)``
(the value for which the DMT contact force -2 pi W R equals the van der Waals force
-H R / (6 zeta_0^2) of (2.20) at contact); ``W`` or the transition parameter ``lam`` (2.24)
may be given instead (``lam`` sets ``W``; then ``H = 12 pi W zeta_0^2`` so that one Hamaker
constant is used throughout).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, Mapping

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.core.registry import Model, Registry

Branch = Literal["loading", "unloading", "stable", "unstable"]

#: smallest normalised contact radius evaluated on the curve (A = 0 is the analytic end point)
A_FLOOR = 1e-10

#: Maugis' numerical factor in (2.24): 2 / 0.97 (Dugdale range h0 = 0.97 zeta_0).
MAUGIS_206 = 2.06

_T41 = preset("table-4.1")

COMMON_PARAMS = ParamSet([
    Param("E_t", _T41["E_t"], "Pa", "Young's modulus of the tip", lo=1e5, hi=2e12, positive=True,
          source="Table 4.1, (2.21)"),
    Param("nu_t", _T41["nu_t"], "", "Poisson ratio of the tip", lo=-0.999, hi=0.5, source="Table 4.1, (2.21)"),
    Param("E_s", _T41["E_s"], "Pa", "Young's modulus of the sample", lo=1e5, hi=2e12, positive=True,
          source="Table 4.1, (2.21)"),
    Param("nu_s", _T41["nu_s"], "", "Poisson ratio of the sample", lo=-0.999, hi=0.5, source="Table 4.1, (2.21)"),
    Param("R_t", _T41["R_t"], "m", "tip radius", lo=1e-10, hi=1e-3, positive=True, source="Table 4.1, (2.21)"),
    Param("R_s", _T41["R_s"], "m", "sample radius (0 = flat sample)", lo=0.0, hi=1e-2,
          source="Table 4.1, (2.21)"),
    Param("H", _T41["H"], "J", "Hamaker constant (sets W when W and lam are not given)",
          lo=0.0, hi=1e-17, source="Table 4.1, (2.20), (2.23)"),
    Param("z0", preset("table-4.4")["zeta0"], "m", "inter-atomic distance zeta_0", lo=1e-11, hi=1e-8,
          positive=True, source="Table 4.4, (2.20), (2.24)"),
    Param("W", None, "J/m^2", "work of adhesion (default H / (12 pi z0^2))", lo=0.0, hi=100.0,
          source="(2.24)"),
    Param("lam", None, "", "Maugis transition parameter (if given, sets W through (2.24))",
          lo=0.0, hi=1e4, source="(2.24)"),
])


@dataclass(frozen=True)
class ContactScales:
    """Derived quantities and the Maugis units of a parameter set."""

    E_star: float  # Pa, (2.21)
    K: float  # Pa, 4/3 E*
    R: float  # m, (2.21)
    W: float  # J/m^2
    H: float  # J, Hamaker constant consistent with W: 12 pi W z0^2
    z0: float  # m
    lam: float  # (2.24)
    a_unit: float  # m, (pi W R^2 / K)^(1/3)       (2.28)
    P_unit: float  # N, pi W R                      (2.29)
    d_unit: float  # m, (pi^2 W^2 R / K^2)^(1/3)   (2.30, with K)

    @property
    def z0_bar(self) -> float:
        """zeta_0 in units of ``d_unit``; equals 2.06 / (pi lam)."""
        return self.z0 / self.d_unit if self.d_unit > 0 else math.inf


def lam_from(W: float, R: float, K: float, z0: float) -> float:
    """Transition parameter (2.24): ``lam = 2.06 / z0 * (W^2 R / (pi K^2))^(1/3)``."""
    return MAUGIS_206 / z0 * (W * W * R / (math.pi * K * K)) ** (1.0 / 3.0)


def W_from_lam(lam: float, R: float, K: float, z0: float) -> float:
    """Inverse of :func:`lam_from`: the work of adhesion that gives ``lam``."""
    return (lam * z0 / MAUGIS_206) ** 1.5 * math.sqrt(math.pi * K * K / R)


def resolve_scales(values: Mapping[str, Any]) -> ContactScales:
    """Validate a resolved parameter dict and compute :class:`ContactScales`."""
    E_t, E_s = float(values["E_t"]), float(values["E_s"])
    nu_t, nu_s = float(values["nu_t"]), float(values["nu_s"])
    for name, v in (("E_t", E_t), ("E_s", E_s), ("R_t", values["R_t"]), ("z0", values["z0"])):
        if not (v is not None and math.isfinite(float(v)) and float(v) > 0):
            raise ParameterError(f"parameter '{name}' must be positive, got {v}")
    for name, v in (("nu_t", nu_t), ("nu_s", nu_s)):
        if not -1.0 < v <= 0.5:
            raise ParameterError(f"parameter '{name}' = {v} is not a Poisson ratio in (-1, 0.5]")
    R_t, R_s, z0 = float(values["R_t"]), float(values["R_s"]), float(values["z0"])
    if R_s < 0:
        raise ParameterError(f"parameter 'R_s' must be >= 0 (0 = flat), got {R_s}")
    E_star = 1.0 / ((1 - nu_t**2) / E_t + (1 - nu_s**2) / E_s)
    K = 4.0 / 3.0 * E_star
    R = R_t if R_s == 0 else 1.0 / (1.0 / R_t + 1.0 / R_s)
    lam_in, W_in, H_in = values.get("lam"), values.get("W"), values.get("H")
    if lam_in is not None and W_in is not None:
        raise ParameterError("give the work of adhesion W or the transition parameter lam, not both")
    if lam_in is not None:
        lam_in = float(lam_in)
        if not (math.isfinite(lam_in) and lam_in >= 0):
            raise ParameterError(f"transition parameter lambda must be >= 0, got {lam_in}")
        W = W_from_lam(lam_in, R, K, z0)
    elif W_in is not None:
        W = float(W_in)
        if not (math.isfinite(W) and W >= 0):
            raise ParameterError(f"work of adhesion W must be >= 0, got {W} J/m^2")
    else:
        H = float(H_in if H_in is not None else 0.0)
        if not (math.isfinite(H) and H >= 0):
            raise ParameterError(f"Hamaker constant H must be >= 0, got {H} J")
        W = H / (12.0 * math.pi * z0 * z0)
    H = 12.0 * math.pi * W * z0 * z0
    lam = lam_from(W, R, K, z0) if lam_in is None else lam_in
    if W > 0:
        a_unit = (math.pi * W * R * R / K) ** (1 / 3)
        P_unit = math.pi * W * R
        d_unit = (math.pi**2 * W * W * R / (K * K)) ** (1 / 3)
    else:
        a_unit = P_unit = d_unit = 0.0
    return ContactScales(E_star, K, R, W, H, z0, lam, a_unit, P_unit, d_unit)


def _as_array(x) -> tuple[np.ndarray, bool]:
    arr = np.asarray(x, dtype=float)
    return np.atleast_1d(arr), arr.ndim == 0


class ContactModel(Model, ABC):
    """A tip–sample contact model: force, contact radius and stiffness vs. penetration.

    Subclasses provide the normalised curve (:meth:`nd_curve`), its ``A -> 0`` end point
    (:meth:`nd_endpoint`) and, if it differs from the Hamaker tail, the normalised non-contact
    tail (:meth:`nd_tail`). Everything else (branches, interpolation, pull-off, dimensional
    wrappers) lives here. A model registers with ``@CONTACT_MODELS.register`` and declares
    ``key``, ``title``, ``source`` (and ``params``, by default :data:`COMMON_PARAMS`); a module in
    this package is found by discovery, so **a new contact model is one file**.
    """

    params: ClassVar[ParamSet] = COMMON_PARAMS

    #: the law has an attraction (a work of adhesion W, Maugis' units, a pull-off, jumps on a spring);
    #: False for a non-adhesive law (a bare elastic indenter): its reports give only what it defines
    adhesive: ClassVar[bool] = True

    #: table resolution of the parametric curve (points in A)
    n_table: ClassVar[int] = 600

    def __init__(self, **overrides: Any) -> None:
        self.values = self.params.resolve(overrides)
        self.scales = resolve_scales(self.values)
        self._table_cache: dict[float, dict[str, np.ndarray]] = {}

    # ------------------------------------------------------------------ normalised model
    @property
    def lam(self) -> float:
        return self.scales.lam

    @abstractmethod
    def nd_curve(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(D_bar, P_bar, dD_bar/dA, dP_bar/dA)`` on the contact curve for ``A > 0``."""

    @abstractmethod
    def nd_endpoint(self) -> tuple[float, float]:
        """``(D0, P0)``: the ``A -> 0`` end of the contact curve."""

    def nd_edge(self, branch: Branch = "loading") -> float:
        """The normalised penetration where ``branch`` leaves the tail for the contact curve: ``D0`` on
        loading (the end point: a JKR-like law jumps into contact there), the turning point ``D_min`` on
        unloading (the jump-out). A law whose non-contact branch has its own folds overrides it."""
        return self.nd_endpoint()[0] if branch == "loading" else float(self._table()["D_min"])

    def nd_tail_knots(self, branch: Branch = "loading") -> np.ndarray:
        """Penetrations a polyline of the tail must hold (its discontinuities and the part where it bends
        sharply); none for the Hamaker tail, which is smooth."""
        return np.array([])

    @property
    def has_noncontact_branch(self) -> bool:
        """The law has a non-contact equilibrium branch of its own (:meth:`nd_noncontact_path`), not a tail that is
        a function of the penetration."""
        return False

    def nd_noncontact_path(self, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
        """``(D_bar, P_bar)`` along a non-contact equilibrium branch of the law's own, unstable parts included
        (Maugis-Dugdale's Dugdale zone); empty for a law whose tail is a function of the penetration."""
        return np.array([]), np.array([])

    def nd_tail(self, D: np.ndarray, branch: Branch = "loading") -> tuple[np.ndarray, np.ndarray]:
        """Non-contact tail ``(P_bar, dP_bar/dD_bar)`` below the branch's edge (:meth:`nd_edge`); the same
        on both branches here (a law with a non-contact branch of its own overrides it).

        The Hamaker sphere–flat law ``P = -H R / (6 d^2)`` (2.23) written in Maugis units
        (``-H R / 6 = -2 pi W R zeta_0^2``), with the gap ``d = d0 + (D0 - D)`` whose origin
        ``d0`` makes it equal to ``P0`` at ``D0`` (the continuity condition behind 2.33):
        ``P_bar = -2 z0_bar^2 / (d0 + D0 - D)^2`` with ``d0 = z0_bar sqrt(2 / -P0)``.
        For the DMT model (``P0 = -2``, ``D0 = 0``) this is exactly (2.20).
        """
        D0, P0 = self.nd_endpoint()
        D = np.asarray(D, dtype=float)
        if P0 >= 0:  # no force at the end point (JKR): no tail
            return np.zeros_like(D), np.zeros_like(D)
        zb = self._nd_z0_bar()
        if not math.isfinite(zb):  # lambda -> 0 in Maugis units: the tail is flat at P0
            return np.full_like(D, P0), np.zeros_like(D)
        d0 = zb * math.sqrt(2.0 / -P0)
        gap = d0 + (D0 - D)
        P = -2.0 * zb * zb / gap**2
        dP = -4.0 * zb * zb / gap**3
        return P, dP

    def _nd_z0_bar(self) -> float:
        """zeta_0 in Maugis units from lambda alone (2.24): ``2.06 / (pi lam)``."""
        lam = self.lam
        return math.inf if lam == 0 else MAUGIS_206 / (math.pi * lam)

    # ------------------------------------------------------------------ the table and branches
    def _table(self, A_max: float = 4.0) -> dict[str, np.ndarray]:
        """Dense table of the curve for ``0 <= A <= A_max`` with the stable/unstable split."""
        key = float(A_max)
        for k, tab in self._table_cache.items():
            if k >= key:
                return tab
        n = self.n_table
        # dense near A = 0 (where the curve turns), uniform-in-sqrt elsewhere
        A = np.unique(np.concatenate([
            np.geomspace(1e-7, 1e-2, 60) * A_max,
            A_max * np.linspace(0.0, 1.0, n)[1:] ** 2,
        ]))
        D, P, dD, dP = self.nd_curve(A)
        if not (np.all(np.isfinite(D)) and np.all(np.isfinite(P))):
            raise SolverError(f"{self.key}: non-finite point on the contact curve (lambda={self.lam:g})")
        D0, P0 = self.nd_endpoint()
        A = np.concatenate([[0.0], A])
        D = np.concatenate([[D0], D])
        P = np.concatenate([[P0], P])
        dD = np.concatenate([[dD[0]], dD])
        dP = np.concatenate([[dP[0]], dP])
        # the turning point (jump-out under displacement control): dD/dA = 0
        A_star, D_min = self._refine_minimum(A, D, int(np.argmin(D)), value=0, slope=2, n_iter=80)
        tab = dict(A=A, D=D, P=P, dD=dD, dP=dP, A_star=A_star, D_min=D_min, A_max=A_max)
        self._table_cache[key] = tab
        return tab

    def _refine_minimum(self, A: np.ndarray, f: np.ndarray, i: int, value: int, slope: int,
                        n_iter: int) -> tuple[float, float]:
        """Minimum of a curve quantity ``f`` (entry ``value`` of :meth:`nd_curve`) found at table
        index ``i``, refined inside the table bracket by bisection on the sign of its derivative
        (entry ``slope``); at the table's ends the table value is kept."""
        if not 0 < i < len(A) - 1:
            return A[i], f[i]
        lo, hi = A[i - 1], A[i + 1]
        for _ in range(n_iter):
            mid = 0.5 * (lo + hi)
            if self.nd_curve(np.array([mid]))[slope][0] < 0:
                lo = mid
            else:
                hi = mid
        a = 0.5 * (lo + hi)
        return a, float(self.nd_curve(np.array([a]))[value][0])

    def _table_covering(self, D_target: float) -> dict[str, np.ndarray]:
        A_max = 4.0
        for _ in range(60):
            tab = self._table(A_max)
            if tab["D"][-1] >= D_target:
                return tab
            A_max *= 2.0
        raise SolverError(f"{self.key}: penetration {D_target:g} (normalised) out of reach")

    def _solve_branch(self, D_t: np.ndarray, stable: bool) -> np.ndarray:
        """Contact radius ``A`` with ``D_bar(A) = D_t`` on the stable (or unstable) branch."""
        out = np.full(D_t.shape, np.nan)
        if D_t.size == 0:
            return out
        tab = self._table_covering(float(np.max(D_t)) if stable else 0.0)
        A, D = tab["A"], tab["D"]
        A_star = tab["A_star"]
        if stable:
            sel = A >= A_star
            As = np.concatenate([[A_star], A[sel & (A > A_star)]])
            Ds = np.concatenate([[tab["D_min"]], D[sel & (A > A_star)]])
        else:
            sel = A <= A_star
            As = np.concatenate([A[sel & (A < A_star)], [A_star]])[::-1]
            Ds = np.concatenate([D[sel & (A < A_star)], [tab["D_min"]]])[::-1]
        # As, Ds increasing in Ds on both branches now
        ok = (D_t >= Ds[0]) & (D_t <= Ds[-1])
        if not np.any(ok):
            return out
        Dt = D_t[ok]
        j = np.clip(np.searchsorted(Ds, Dt) - 1, 0, len(Ds) - 2)
        lo, hi = As[j].copy(), As[j + 1].copy()
        if not stable:
            lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        x = np.interp(Dt, Ds, As)
        sign = 1.0 if stable else -1.0  # D increases with A on the stable branch, decreases on the other
        for _ in range(60):
            xe = np.maximum(x, A_FLOOR)
            Dx, _, dDx, _ = self.nd_curve(xe)
            f = sign * (Dx - Dt)
            lo = np.where(f < 0, x, lo)
            hi = np.where(f > 0, x, hi)
            step = (Dx - Dt) / np.where(dDx != 0, dDx, np.inf)
            xn = x - step
            bad = ~((xn >= lo) & (xn <= hi)) | ~np.isfinite(xn)
            xn = np.where(bad, 0.5 * (lo + hi), xn)
            done = np.abs(xn - x) <= 1e-14 * np.maximum(1.0, np.abs(x))
            x = xn
            if np.all(done):
                break
        out[ok] = x
        return out

    def nd_state(self, D, branch: Branch = "loading") -> dict[str, np.ndarray]:
        """Normalised load, contact radius and stiffness at normalised penetration(s) ``D``."""
        D, scalar = _as_array(D)
        if branch not in ("loading", "unloading", "stable", "unstable"):
            raise ParameterError(f"unknown branch {branch!r} (loading, unloading, stable, unstable)")
        D0, _ = self.nd_endpoint()
        tab = self._table()
        D_min = tab["D_min"]
        A = np.full(D.shape, np.nan)
        if branch == "unstable":
            in_c = (D >= D_min) & (D <= D0)
            A[in_c] = self._solve_branch(D[in_c], stable=False)
            contact = in_c
        else:
            edge = self.nd_edge(branch) if branch != "stable" else D_min
            contact = D >= edge
            A[contact] = self._solve_branch(D[contact], stable=True)
        P = np.full(D.shape, np.nan)
        k = np.full(D.shape, np.nan)
        c = contact & np.isfinite(A)
        if np.any(c):
            Ac = np.maximum(A[c], A_FLOOR)
            _, Pc, dDc, dPc = self.nd_curve(Ac)
            P[c] = Pc
            k[c] = dPc / dDc
            zero = A[c] == 0
            if np.any(zero):  # exactly at the A -> 0 end point
                Pz = P[c]
                Pz[zero] = self.nd_endpoint()[1]
                P[c] = Pz
        if branch in ("loading", "unloading"):
            nc = ~contact
            if np.any(nc):
                Pt, kt = self.nd_tail(D[nc], branch)
                P[nc], k[nc] = Pt, kt
                A[nc] = 0.0
        res = dict(D=D, P=P, A=A, k=k, contact=contact)
        if scalar:
            res = {key: v[0] for key, v in res.items()}
        return res

    # ------------------------------------------------------------------ pull-off
    def nd_pull_off(self) -> dict[str, float]:
        """Pull-off under load control (minimum load) and under displacement control (jump-out).

        ``P_bar`` is minimised along the whole curve ``A >= 0`` (the tail lies between P0 and 0,
        so it never undercuts it): grid search on the table, then bisection on the analytic
        ``dP_bar/dA = 0``.
        """
        tab = self._table()
        A, P = tab["A"], tab["P"]
        A_pc, P_pc = self._refine_minimum(A, P, int(np.argmin(P)), value=1, slope=3, n_iter=100)
        P_pc = min(P_pc, self.nd_endpoint()[1])
        A_star = tab["A_star"]
        if A_star > 0:
            D_js, P_js = (float(v[0]) for v in self.nd_curve(np.array([A_star]))[:2])
        else:
            D_js, P_js = self.nd_endpoint()
        return dict(P_pull_off=float(P_pc), A_pull_off=float(A_pc),
                    D_jump_out=float(D_js), P_jump_out=float(P_js), A_jump_out=float(A_star))

    def pull_off_normalized(self) -> float:
        """Pull-off force (load control) divided by ``pi W R`` (negative = tensile)."""
        return self.nd_pull_off()["P_pull_off"]

    # ------------------------------------------------------------------ dimensional interface
    def force(self, delta, branch: Branch = "loading"):
        """Interaction force [N] (positive repulsive) at penetration ``delta`` [m]."""
        return self.state(delta, branch)["force"]

    def contact_radius(self, delta, branch: Branch = "loading"):
        """Contact radius [m] (0 out of contact)."""
        return self.state(delta, branch)["radius"]

    def stiffness(self, delta, branch: Branch = "loading"):
        """``dF/ddelta`` [N/m] along the chosen branch."""
        return self.state(delta, branch)["stiffness"]

    def state(self, delta, branch: Branch = "loading") -> dict[str, Any]:
        """Force [N], contact radius [m], stiffness [N/m] and contact flag at ``delta`` [m].

        Without adhesion (``W = 0``) every model reduces to Hertz: ``P = K sqrt(R) delta^1.5``.
        """
        d, scalar = _as_array(delta)
        s = self.scales
        if s.W == 0:
            pos = np.maximum(d, 0.0)
            F = s.K * math.sqrt(s.R) * pos**1.5
            k = 1.5 * s.K * math.sqrt(s.R) * np.sqrt(pos)
            a = np.sqrt(s.R * pos)
            res = dict(force=F, radius=a, stiffness=k, contact=d > 0)
        else:
            st = self.nd_state(d / s.d_unit, branch)
            res = dict(force=np.asarray(st["P"]) * s.P_unit, radius=np.asarray(st["A"]) * s.a_unit,
                       stiffness=np.asarray(st["k"]) * s.P_unit / s.d_unit,
                       contact=np.asarray(st["contact"]))
            res = {k_: np.atleast_1d(v) for k_, v in res.items()}
        if scalar:
            res = {k_: (v[0].item() if hasattr(v[0], "item") else v[0]) for k_, v in res.items()}
        return res

    def point(self, delta: float) -> tuple[float, float, float, float]:
        """One penetration ``delta`` [m] on the loading branch, as plain floats for the
        right-hand sides of time integrators: ``(force [N], dF/ddelta [N/m], contact radius a
        [m], da/ddelta)`` (radius and its derivative 0 out of contact). This general version
        solves the curve (:meth:`state`); a model with a closed form overrides it."""
        st = self.state(float(delta), "loading")
        F, k = float(st["force"]), float(st["stiffness"])
        a = float(st["radius"]) if st["contact"] else 0.0
        if not st["contact"] or a <= 0.0:
            return F, k, 0.0, 0.0
        s = self.scales
        dD = float(self.nd_curve(np.array([max(a / s.a_unit, A_FLOOR)]))[2][0])
        return F, k, a, s.a_unit / (s.d_unit * dD)

    def pull_off_force(self) -> float:
        """Pull-off force [N] under load control (negative = tensile); 0 without adhesion."""
        s = self.scales
        return 0.0 if s.W == 0 else self.pull_off_normalized() * s.P_unit

    def at_load(self, load) -> dict[str, np.ndarray]:
        """Equilibrium contact on the stable branch under an applied load [N] (load control).

        Returns contact radius [m], penetration [m] and contact stiffness [N/m]; loads below the
        pull-off force raise :class:`ParameterError` (the contact cannot exist). This is what
        the adhesion–friction coupling uses: the true contact area at a given cantilever load.
        """
        L, scalar = _as_array(load)
        s = self.scales
        if s.W == 0:
            if np.any(L < 0):
                raise ParameterError("a tensile load cannot be carried without adhesion (W = 0)")
            a = np.cbrt(L * s.R / s.K)
            delta = a * a / s.R
            k = 1.5 * s.K * math.sqrt(s.R) * np.sqrt(delta)
            res = dict(radius=a, penetration=delta, stiffness=k)
        else:
            Pb = L / s.P_unit
            po = self.nd_pull_off()
            if np.any(Pb < po["P_pull_off"] - 1e-12):
                raise ParameterError(
                    f"load {float(np.min(L)):.3g} N is below the pull-off force "
                    f"{po['P_pull_off'] * s.P_unit:.3g} N: no contact exists")
            A = self._solve_load(Pb, po["A_pull_off"])
            D, _, dD, dP = self.nd_curve(np.maximum(A, A_FLOOR))
            res = dict(radius=A * s.a_unit, penetration=D * s.d_unit,
                       stiffness=dP / dD * s.P_unit / s.d_unit)
        if scalar:
            res = {k_: float(v[0]) for k_, v in res.items()}
        return res

    def _solve_load(self, Pb: np.ndarray, A_pc: float) -> np.ndarray:
        """``A >= A_pc`` with ``P_bar(A) = Pb`` (P_bar increases there): bisection + Newton."""
        A_hi = max(4.0, 2.0 * float(np.max(np.cbrt(np.maximum(Pb, 0.0) + 2.0))) + 2.0)
        while self.nd_curve(np.array([A_hi]))[1][0] < np.max(Pb):
            A_hi *= 2.0
        lo = np.full(Pb.shape, A_pc)
        hi = np.full(Pb.shape, A_hi)
        x = 0.5 * (lo + hi)
        for _ in range(200):
            _, P, _, dP = self.nd_curve(np.maximum(x, A_FLOOR))
            f = P - Pb
            lo = np.where(f < 0, x, lo)
            hi = np.where(f > 0, x, hi)
            xn = x - f / np.where(dP > 0, dP, np.inf)
            bad = ~((xn >= lo) & (xn <= hi)) | ~np.isfinite(xn)
            xn = np.where(bad, 0.5 * (lo + hi), xn)
            if np.all(np.abs(xn - x) <= 1e-14 * np.maximum(1.0, x)):
                x = xn
                break
            x = xn
        return x

    # ------------------------------------------------------------------ fast evaluation for ODEs
    def interpolant(self, branch: Branch = "loading", delta_max: float | None = None, n: int = 400):
        """A fast callable ``f(delta) -> (force [N], stiffness [N/m])`` for time integration.

        The contact part is a cubic spline of the load against ``u = sqrt(D_bar - D_edge)``
        (``D_edge = D0`` for loading, ``D_min`` for unloading), in which the curve is smooth even
        at a vertical tangent (the turning point, where ``dP/dD ~ 1/sqrt(D - D_min)``); the tail
        is evaluated analytically. Spline error O(h^4): below 1e-8 of ``pi W R`` with the
        defaults (tested). ``delta_max`` (m) bounds the spline (default 20 Maugis units);
        beyond it the exact solver is used.
        """
        if branch not in ("loading", "unloading"):
            raise ParameterError(f"interpolant branch must be 'loading' or 'unloading', got {branch!r}")
        s = self.scales
        if s.W == 0:
            return lambda delta: (self.state(delta)["force"], self.state(delta)["stiffness"])
        edge = self.nd_edge(branch)
        Dmax = 20.0 if delta_max is None else float(delta_max) / s.d_unit
        if Dmax <= edge:
            raise ParameterError(f"delta_max must exceed the contact edge {edge * s.d_unit:.3g} m")
        u = np.linspace(0.0, math.sqrt(Dmax - edge), n)
        st = self.nd_state(edge + u * u + np.r_[1e-15, np.zeros(n - 1)], "stable")
        from scipy.interpolate import CubicSpline  # here, not at import: the registry's keys are listed by the CLI

        spline = CubicSpline(u, st["P"])
        dspline = spline.derivative()

        def f(delta):
            d, scalar = _as_array(delta)
            Db = d / s.d_unit
            P = np.empty_like(Db)
            k = np.empty_like(Db)
            tail = Db < edge
            far = Db > Dmax
            mid = ~tail & ~far
            if np.any(tail):
                P[tail], k[tail] = self.nd_tail(Db[tail], branch)
            if np.any(mid):
                uu = np.sqrt(Db[mid] - edge)
                P[mid] = spline(uu)
                with np.errstate(divide="ignore", invalid="ignore"):
                    k[mid] = np.where(uu > 0, dspline(uu) / (2 * uu), np.inf)
            if np.any(far):
                ex = self.nd_state(Db[far], "stable")
                P[far], k[far] = ex["P"], ex["k"]
            F, K = P * s.P_unit, k * s.P_unit / s.d_unit
            return (float(F[0]), float(K[0])) if scalar else (F, K)

        return f

    # ------------------------------------------------------------------ curves for plots
    def nd_curves(self, D_range: tuple[float, float] = (-2.5, 3.0), n: int = 400) -> dict[str, np.ndarray]:
        """The full normalised picture: parametric contact curve, its stable/unstable split and
        the tail, for plotting Fig 2.19."""
        tab = self._table_covering(D_range[1])
        A, D, P = tab["A"], tab["D"], tab["P"]
        keep = D <= D_range[1]
        D0, P0 = self.nd_endpoint()
        Dt = np.linspace(D_range[0], D0, n)
        Pt, _ = self.nd_tail(Dt) if D0 > D_range[0] else (np.array([]), None)
        return dict(A=A[keep], D=D[keep], P=P[keep], stable=(A >= tab["A_star"])[keep],
                    D_tail=Dt if D0 > D_range[0] else np.array([]), P_tail=Pt,
                    D0=D0, P0=P0, D_min=tab["D_min"], A_star=tab["A_star"])

    def describe(self) -> dict[str, Any]:
        s = self.scales
        return dict(model=self.key, title=self.title, equations=self.source,
                    E_star_pa=s.E_star, K_pa=s.K, R_m=s.R, W_j_m2=s.W, H_j=s.H, z0_m=s.z0,
                    lam=s.lam, a_unit_m=s.a_unit, P_unit_n=s.P_unit, d_unit_m=s.d_unit)


#: The contact models: one module per model in this package (discovered on first lookup).
CONTACT_MODELS: Registry[type[ContactModel]] = Registry(
    "contact", ContactModel, required=("nd_curve", "nd_endpoint"), package="probedyn.schemes.contact",
    aliases={"maugis-dugdale": "md", "maugis_dugdale": "md", "maugis": "md"})
