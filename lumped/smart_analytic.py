"""Analytic references for the smart probes (source sections 3.2.2, 3.3.2, 3.5.1).

SI units; probedyn axes (x along the probe from the clamp, y across, z through the thickness).
For the piezotube the tube axis is x (the source calls it z); the source's lateral x (vertical)
is probedyn z and the source's y is probedyn y. Every formula was checked against a limit
case or an independent solution (tests/test_smart_analytic.py); departures from the print:

* **(3.10)** tip-mass frequency equation: the standard form (departure 1)
  ``1 + cos x cosh x + mu x (cos x sinh x - sin x cosh x) = 0``, ``x = lambda L``,
  ``mu = m / (rho A L)`` (from the end condition 3.8 / 3.16 / 3.24 without damping). The printed
  form is available as ``form="printed"`` only to show its error.
* **(3.13)/(3.18)** duo-bimorph vertical: bending stiffness ``w h^3 / (12 s11)`` and
  ``omega_n = sqrt(h^2 / (12 rho s11)) lambda_n^2`` (departure 3). Lateral (3.5):
  ``h w^3 / (12 s11)``, ``omega_n = sqrt(w^2 / (12 rho s11)) lambda_n^2``.
* **(3.21)** piezotube lateral: the thin-wall bending stiffness ``pi R^3 (Re - Ri) / s11``
  with ``R = (Re + Ri)/2``, and the exact annulus ``pi (Re^4 - Ri^4) / (4 s11)``; their ratio
  is ``1 + t^2 / (4 R^2)`` with ``t = Re - Ri`` (exact algebra).
* **(3.27)-(3.29)** piezotube longitudinal with the holder mass at the end:
  ``(omega L / a) tan(omega L / a) = rho A L / m_h``, ``a = 1 / sqrt(rho s11)``.

Assumptions: Euler-Bernoulli bending (no shear, no rotary inertia) unless a function says
``timoshenko``; the end mass is a point mass at x = L (no rotary inertia, no offset); the
modulus along the beam axis is ``1/s11`` (exact for uniaxial stress perpendicular to the
poling axis of a transversely isotropic PZT, which is the case for both probes: the bimorph
is poled through z, the tube radially, and the beam axis x is perpendicular to the poling).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import brentq

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.lumped.beam import tip_mass_roots

Form = Literal["standard", "printed"]


def _pos(name: str, v: float) -> float:
    v = float(v)
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{name} must be positive and finite, got {v:g}")
    return v


# ---------------------------------------------------------------------------------------------
# Generic Euler-Bernoulli cantilever with an end mass
# ---------------------------------------------------------------------------------------------


def tip_mass_beam_frequencies(EI: float, rho_A: float, L: float, m_end: float, n: int = 4,
                              form: Form = "standard") -> np.ndarray:
    """Bending frequencies [Hz] of a clamped beam with a point mass at x = L (3.10 corrected).

    ``omega_n = (lambda_n L)^2 sqrt(EI / (rho A L^4))``; ``lambda_n L`` from the standard form of
    (3.10) (or the printed one with ``form="printed"``, for comparison only).
    Limits: ``m_end -> 0`` gives 1.8751, 4.6941, ... (clamped-free); ``m_end -> inf`` gives the
    spring-mass ``omega^2 = 3 EI / (L^3 m_end)`` for the first mode.
    """
    EI, rho_A, L = _pos("EI", EI), _pos("rho A", rho_A), _pos("L", L)
    if m_end < 0:
        raise ParameterError(f"end mass must be >= 0, got {m_end:g} kg")
    x = tip_mass_roots(m_end / (rho_A * L), n, form)
    return x**2 * math.sqrt(EI / (rho_A * L**4)) / (2 * math.pi)


def rayleigh_end_mass_frequency(EI: float, rho_A: float, L: float, m_end: float,
                                shear_compliance: float = 0.0) -> float:
    """First bending frequency [Hz] by the textbook tip-mass (Rayleigh) estimate:
    ``k = 3 EI / L^3`` (plus an optional shear compliance in series), ``m = m_end + (33/140) rho A L``.

    Exact for ``m_end >> rho A L``; for ``m_end = 0`` it is 1.5 % high (1.8810^2 vs 1.8751^2).
    """
    c = L**3 / (3 * EI) + shear_compliance
    return math.sqrt(1.0 / (c * (m_end + 33.0 / 140.0 * rho_A * L))) / (2 * math.pi)


# ---------------------------------------------------------------------------------------------
# Duo-bimorph (section 3.2.2, eqs 3.5-3.19)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DuoBimorphBeam:
    """The duo-bimorph as a homogeneous rectangular beam: length ``L``, width ``w`` (y), total
    thickness ``h`` (z), density ``rho``, compliance along the beam ``s11`` [1/Pa]."""

    L: float
    w: float
    h: float
    rho: float
    s11: float

    def __post_init__(self) -> None:
        for k in ("L", "w", "h", "rho", "s11"):
            _pos(k, getattr(self, k))

    @property
    def A(self) -> float:
        return self.w * self.h

    @property
    def mass(self) -> float:
        return self.rho * self.A * self.L

    def EI(self, direction: str) -> float:
        """Bending stiffness [N m^2]: lateral (y) ``h w^3/(12 s11)`` (3.5); vertical (z)
        ``w h^3/(12 s11)`` (3.13 corrected, departure 3)."""
        if direction in ("lateral", "y"):
            return self.h * self.w**3 / (12 * self.s11)
        if direction in ("vertical", "flapwise", "z"):
            return self.w * self.h**3 / (12 * self.s11)
        raise ParameterError(f"direction must be lateral/y or vertical/z, got {direction!r}")

    def omega_scale(self, direction: str) -> float:
        """``sqrt(EI / (rho A))`` [m^2/s]: ``sqrt(w^2/(12 rho s11))`` lateral,
        ``sqrt(h^2/(12 rho s11))`` vertical (3.18 corrected)."""
        d = self.w if direction in ("lateral", "y") else self.h
        self.EI(direction)  # validates the direction
        return math.sqrt(d**2 / (12 * self.rho * self.s11))

    def frequencies(self, direction: str, m_end: float, n: int = 4, form: Form = "standard") -> np.ndarray:
        """Frequencies [Hz] with the end mass ``m_end`` (the holder, m_h): (3.10) + (3.18)."""
        x = tip_mass_roots(m_end / self.mass, n, form)
        return (x / self.L) ** 2 * self.omega_scale(direction) / (2 * math.pi)

    def static_stiffness(self, direction: str) -> float:
        """``3 EI / L^3`` [N/m] at the free end (Euler-Bernoulli)."""
        return 3 * self.EI(direction) / self.L**3

    def rayleigh_frequency(self, direction: str, m_end: float) -> float:
        """Textbook tip-mass estimate [Hz]: ``sqrt(3EI/L^3 / (m_end + 33/140 rho A L)) / 2pi``."""
        return rayleigh_end_mass_frequency(self.EI(direction), self.rho * self.A, self.L, m_end)


# ---------------------------------------------------------------------------------------------
# Piezotube (section 3.3.2, eqs 3.21-3.30) and its eccentric section (3.5.1)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Piezotube:
    """A uniform tube (axis x): outer radius ``Re``, inner ``Ri``, length ``L``, density ``rho``,
    axial compliance ``s11`` [1/Pa]. ``s66 = 2 (s11 - s12)`` (optional) enables the Timoshenko
    shear correction."""

    Re: float
    Ri: float
    L: float
    rho: float
    s11: float

    def __post_init__(self) -> None:
        for k in ("Re", "L", "rho", "s11"):
            _pos(k, getattr(self, k))
        if not (0 <= self.Ri < self.Re):
            raise GeometryError(f"piezotube: inner radius Ri = {self.Ri:g} m must be below Re = {self.Re:g} m")

    @property
    def A(self) -> float:
        return math.pi * (self.Re**2 - self.Ri**2)

    @property
    def mass(self) -> float:
        return self.rho * self.A * self.L

    @property
    def R_mean(self) -> float:
        return 0.5 * (self.Re + self.Ri)

    def I(self, exact: bool = True) -> float:
        """Second moment of area [m^4]: exact annulus ``pi (Re^4 - Ri^4)/4`` or the thin-wall
        value of (3.21) ``pi R^3 (Re - Ri)``."""
        if exact:
            return math.pi * (self.Re**4 - self.Ri**4) / 4
        return math.pi * self.R_mean**3 * (self.Re - self.Ri)

    def lateral_frequencies(self, m_end: float, n: int = 4, exact: bool = True, form: Form = "standard") -> np.ndarray:
        """Lateral bending frequencies [Hz] with the holder mass ``m_end`` at x = L (3.21-3.25)."""
        return tip_mass_beam_frequencies(self.I(exact) / self.s11, self.rho * self.A, self.L, m_end, n, form)

    def shear_compliance(self, s66: float, nu: float = 0.3) -> float:
        """End-load shear compliance ``L / (kappa G A)`` of the tube [m/N]: ``G = 1/s66`` (the
        axial-circumferential shear modulus of the wall), Cowper's thin-tube
        ``kappa = 2 (1 + nu) / (4 + 3 nu)``."""
        kappa = 2 * (1 + nu) / (4 + 3 * nu)
        return self.L * s66 / (kappa * self.A)

    @property
    def bar_speed(self) -> float:
        """``a = 1 / sqrt(rho s11)`` [m/s]."""
        return 1.0 / math.sqrt(self.rho * self.s11)

    def axial_frequencies(self, m_end: float, n: int = 3) -> np.ndarray:
        """Longitudinal frequencies [Hz]: roots of ``beta tan beta = rho A L / m_end`` with
        ``beta = omega L / a`` (3.27-3.29 without damping). ``m_end = 0`` gives
        ``beta = (2k - 1) pi / 2``; ``m_end -> inf`` gives ``omega^2 = (A/(s11 L)) / m_end``."""
        if m_end < 0:
            raise ParameterError(f"holder mass must be >= 0, got {m_end:g} kg")
        if m_end == 0:
            beta = (2 * np.arange(1, n + 1) - 1) * math.pi / 2
        else:
            ratio = self.mass / m_end
            f = lambda b: b * math.sin(b) - ratio * math.cos(b)  # noqa: E731  (beta tan beta = ratio)
            beta = []
            for k in range(n):  # one root in each (k pi, k pi + pi/2)
                lo, hi = k * math.pi + 1e-12, k * math.pi + math.pi / 2 - 1e-12
                beta.append(brentq(f, lo, hi, xtol=1e-14))
            beta = np.asarray(beta)
        return beta * self.bar_speed / self.L / (2 * math.pi)


@dataclass(frozen=True)
class EccentricSection:
    """Cross-section of a tube whose bore (radius ``Ri``) is offset by ``(dy, dz)`` from the
    outer circle (radius ``Re``) centred at the origin (Fig 3.19, probedyn axes).

    Exact for any offset: area ``A = pi (Re^2 - Ri^2)``, centroid ``c = -A_i d / A``; the
    centroidal second-moment tensor is ``I0 * 1 - (A_i A_o / A) d d^T`` with
    ``I0 = pi (Re^4 - Ri^4)/4``, ``A_o = pi Re^2``, ``A_i = pi Ri^2`` (parallel-axis theorem).
    Its principal directions are along the offset (the smaller moment) and perpendicular to it.
    """

    Re: float
    Ri: float
    dy: float = 0.0
    dz: float = 0.0

    @property
    def offset(self) -> float:
        return math.hypot(self.dy, self.dz)

    def second_moments(self) -> tuple[np.ndarray, np.ndarray]:
        """(principal moments ascending [m^4], unit directions (2, 2) as columns in (y, z))."""
        Ao, Ai = math.pi * self.Re**2, math.pi * self.Ri**2
        A = Ao - Ai
        I0 = math.pi * (self.Re**4 - self.Ri**4) / 4
        d = np.array([self.dy, self.dz])
        J = I0 * np.eye(2) - (Ai * Ao / A) * np.outer(d, d)
        w, v = np.linalg.eigh(J)
        return w, v

    def frequency_split(self) -> float:
        """Relative split ``f_perp / f_along - 1 = sqrt(I_max / I_min) - 1`` of the lateral pair:
        both directions carry the same mass, so the Euler-Bernoulli frequencies scale as
        ``sqrt(EI)`` whatever the end mass."""
        w, _ = self.second_moments()
        return math.sqrt(w[1] / w[0]) - 1.0

    def lower_mode_angle_deg(self) -> float:
        """Direction of the lower-frequency bending mode, degrees from +y towards +z in
        [0, 180): along the offset (the bore side is thinner). 0 for a centred bore."""
        if self.offset == 0:
            return 0.0
        return math.degrees(math.atan2(self.dz, self.dy)) % 180.0


# ---------------------------------------------------------------------------------------------
# Beam with a rigid end body of finite size (the meshed holder): "holder geometry"
# ---------------------------------------------------------------------------------------------


def end_body_frequencies(EI: float, rho_A: float, L: float, m: float, e: float = 0.0, J: float = 0.0,
                         shear_compliance: float = 0.0) -> np.ndarray:
    """The two lowest bending frequencies [Hz] of a clamped beam carrying a rigid body at its
    end: mass ``m`` with its centre of mass ``e`` beyond x = L and rotary inertia ``J``
    [kg m^2] about that centre.

    Ritz model in the end deflection w and rotation theta: the beam enters through its exact
    static end flexibility ``[[L^3/(3EI) + c_s, L^2/(2EI)], [L^2/(2EI), L/EI]]`` (``c_s`` =
    optional shear compliance ``L/(kappa G A)``) and the consistent mass of one Hermite cubic
    ``rho A L/420 [[156, -22 L], [-22 L, 4 L^2]]``; the body adds
    ``m [[1, e], [e, e^2]] + J [[0, 0], [0, 1]]`` (its centre moves by w + e theta). For
    ``e = J = 0`` and a heavy body the first frequency is the exact ``3EI/(L^3 m)`` limit; the
    Hermite mass makes it an upper bound otherwise (+1.5 % for m = 0).
    """
    F = np.array([[L**3 / (3 * EI) + shear_compliance, L**2 / (2 * EI)], [L**2 / (2 * EI), L / EI]])
    K = np.linalg.inv(F)
    Mb = rho_A * L / 420.0 * np.array([[156.0, -22 * L], [-22 * L, 4 * L**2]])
    Mr = m * np.array([[1.0, e], [e, e * e]]) + np.array([[0.0, 0.0], [0.0, J]])
    lam = eigh(K, Mb + Mr, eigvals_only=True)
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)


def end_body_first_mode_at(EI: float, rho_A: float, L: float, m: float, e: float, J: float, x_ref: float,
                           shear_compliance: float = 0.0) -> tuple[float, float]:
    """First mode of :func:`end_body_frequencies` as a 1-DOF oscillator referred to the
    displacement at ``x_ref`` beyond the beam end (e.g. the holder end face, where the tip
    spring acts): returns (M, k) with ``M = v^T M v / (w + x_ref theta)^2`` and
    ``k = omega^2 M`` (eqs 3.1, 3.3 referred to that point)."""
    F = np.array([[L**3 / (3 * EI) + shear_compliance, L**2 / (2 * EI)], [L**2 / (2 * EI), L / EI]])
    K = np.linalg.inv(F)
    Mt = rho_A * L / 420.0 * np.array([[156.0, -22 * L], [-22 * L, 4 * L**2]]) \
        + m * np.array([[1.0, e], [e, e * e]]) + np.array([[0.0, 0.0], [0.0, J]])
    lam, V = eigh(K, Mt)
    v = V[:, 0]
    u = v[0] + x_ref * v[1]
    M = float(v @ Mt @ v) / u**2
    return M, float(lam[0]) * M


def rigid_body_properties(p: np.ndarray, t: np.ndarray, density: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass (3,) and inertia tensor about it (3, 3) [kg m^2] of a set of
    straight tetrahedra (vertices ``p`` (3, n), connectivity ``t`` (4, k), ``density`` (k,)).

    Exact for linear tets: ``int x_i x_j dV = V/20 (sum_a x_ai x_aj + (sum_a x_ai)(sum_a x_aj))``.
    """
    X = p[:, t]  # (3, 4, k)
    a = X[:, 0]
    V = np.abs(np.einsum("ik,ik->k", X[:, 1] - a, np.cross(X[:, 2] - a, X[:, 3] - a, axis=0))) / 6.0
    w = density * V
    m = float(w.sum())
    s = X.sum(axis=1)  # (3, k)
    c = (s / 4.0 * w).sum(axis=1) / m
    second = (np.einsum("iak,jak->ijk", X, X) + np.einsum("ik,jk->ijk", s, s)) / 20.0  # per unit volume*V
    S = (second * (density * V)).sum(axis=2) - m * np.outer(c, c)  # int rho (x-c)(x-c)^T dV
    Jt = np.trace(S) * np.eye(3) - S
    return m, c, Jt
