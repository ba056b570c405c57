"""Analytic references for a uniform, straight, rectangular cantilever (section 2.3 of the source).

Everything here is closed-form or a scalar root solve, SI units throughout. Conventions follow
the FEM (``probedyn.fem``): the beam axis is x (clamp at x = 0, free end at x = L), the width
``w`` is along y and the thickness ``t`` along z, so

* **flapwise** bending = deflection along z, second moment ``I = w t^3 / 12``;
* **lateral** bending = deflection along y, ``I = t w^3 / 12``.

Contents (source equations in brackets):

* :func:`eb_roots` – roots of ``1 + cos(bL) cosh(bL) = 0`` (2.40), Euler–Bernoulli frequencies
  ``omega = (bL)^2 sqrt(EI / (rho A L^4))`` (2.41 for the first one), mode shape (2.39)/(3.11).
* :func:`timoshenko_roots` – the full Timoshenko clamped-free frequency equation (shear
  deformation with Cowper's coefficient and rotary inertia; Huang 1961); the tests check it
  against an independent transfer-matrix evaluation (``tests/beam_reference.py``).
* :func:`torsion_frequencies` – Saint-Venant torsion with the rectangular torsion constant
  (series); **warping is neglected** (free warping everywhere, also at the clamp).
* :func:`axial_frequencies` – longitudinal rod modes.
* :func:`static_tip_stiffness` – ``3 EI / L^3`` (section 2.3.1, ``k_f``), optionally with the
  Timoshenko shear compliance ``L / (kappa G A)``.
* :func:`tip_mass_roots` – the tip-mass frequency equation (3.10) in the form **printed** in the
  source and in the **standard** form (departure 1), first N roots by bracketing.
* :func:`rayleigh_quotient` – (2.46) on a sampled mode shape.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Literal, Sequence

import numpy as np
from scipy.interpolate import make_interp_spline
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError

Direction = Literal["flapwise", "lateral"]
TipMassForm = Literal["standard", "printed"]


# --------------------------------------------------------------------------------------------
# Section properties
# --------------------------------------------------------------------------------------------


def cowper_kappa(nu: float) -> float:
    """Cowper's (1966) shear coefficient of a rectangular section: ``10(1+nu)/(12+11 nu)``.

    ``nu = 0`` gives 5/6; ``nu = 0.28`` gives 0.8503.
    """
    if not -1.0 < nu < 0.5:
        raise ParameterError(f"Poisson ratio {nu} outside (-1, 0.5)")
    return 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)


def torsion_constant_rect(a: float, b: float, n_terms: int = 50) -> float:
    """Saint-Venant torsion constant ``J`` of a solid ``a x b`` rectangle (series, not thin strip).

    With ``a >= b`` (long and short side):
    ``J = a b^3 / 3 * [1 - (192 / pi^5) (b / a) sum_{n odd} tanh(n pi a / (2 b)) / n^5]``
    (Timoshenko & Goodier, Theory of Elasticity, section 109). The series converges like
    ``n^-5``; 50 odd terms are exact to machine precision. Limits: square ``J = 0.1406 a^4``;
    thin strip ``J -> a b^3 / 3 (1 - 0.630 b / a)``.
    """
    if a <= 0 or b <= 0:
        raise ParameterError("torsion_constant_rect: sides must be positive")
    a, b = max(a, b), min(a, b)
    n = np.arange(1, 2 * n_terms, 2, dtype=float)
    s = np.sum(np.tanh(n * math.pi * a / (2.0 * b)) / n**5)
    return a * b**3 / 3.0 * (1.0 - 192.0 / math.pi**5 * (b / a) * s)


@dataclass(frozen=True)
class RectBeam:
    """A uniform rectangular cantilever: length ``L`` (x), width ``w`` (y), thickness ``t`` (z).

    ``E`` Young's modulus [Pa], ``nu`` Poisson ratio, ``rho`` density [kg/m^3]. Isotropic.
    ``G = E / (2 (1 + nu))`` and ``kappa`` (default: Cowper's rectangle value) feed Timoshenko.
    """

    L: float
    w: float
    t: float
    E: float
    nu: float
    rho: float
    kappa: float | None = None

    def __post_init__(self) -> None:
        for name in ("L", "w", "t", "E", "rho"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"beam {name} must be positive and finite, got {v!r}")
        if not -1.0 < self.nu < 0.5:
            raise ParameterError(f"Poisson ratio {self.nu} outside (-1, 0.5)")

    @property
    def A(self) -> float:
        return self.w * self.t

    @property
    def G(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def k_shear(self) -> float:
        return cowper_kappa(self.nu) if self.kappa is None else self.kappa

    @property
    def mass(self) -> float:
        return self.rho * self.A * self.L

    @property
    def mass_per_length(self) -> float:
        return self.rho * self.A

    def I(self, direction: Direction) -> float:
        """Second moment of area for bending in ``direction`` (flapwise: about y; lateral: about z)."""
        if direction == "flapwise":
            return self.w * self.t**3 / 12.0
        if direction == "lateral":
            return self.t * self.w**3 / 12.0
        raise ParameterError(f"unknown bending direction {direction!r}")

    @property
    def J(self) -> float:
        return torsion_constant_rect(self.w, self.t)

    @property
    def Ip(self) -> float:
        """Polar second moment of area about the beam axis, ``w t (w^2 + t^2) / 12``."""
        return self.w * self.t * (self.w**2 + self.t**2) / 12.0

    def omega_scale(self, direction: Direction) -> float:
        """``sqrt(EI / (rho A L^4))`` [rad/s]: omega = (bL)^2 times this."""
        return math.sqrt(self.E * self.I(direction) / (self.rho * self.A * self.L**4))


# --------------------------------------------------------------------------------------------
# Root bracketing helper
# --------------------------------------------------------------------------------------------


def _scan_roots(f: Callable[[float], float], x0: float, step: float, n: int, x_max: float) -> np.ndarray:
    """First ``n`` sign changes of ``f`` on ``[x0, x_max]`` scanned with ``step``, refined by brentq.

    The caller guarantees that ``step`` is smaller than the spacing of consecutive roots (all
    equations here have roots about pi apart in their natural variable), so none is skipped.
    """
    roots: list[float] = []
    xa, fa = x0, f(x0)
    while len(roots) < n:
        xb = xa + step
        if xb > x_max:
            break
        fb = f(xb)
        if fa == 0.0:
            roots.append(xa)
        elif fa * fb < 0.0:
            roots.append(brentq(f, xa, xb, xtol=1e-14, rtol=4 * np.finfo(float).eps, maxiter=200))
        xa, fa = xb, fb
    if len(roots) < n:
        raise SolverError(f"found only {len(roots)} of {n} roots below {x_max:g}")
    return np.asarray(roots)


# --------------------------------------------------------------------------------------------
# Euler–Bernoulli (2.38)–(2.41)
# --------------------------------------------------------------------------------------------


def eb_roots(n: int) -> np.ndarray:
    """First ``n`` roots ``b_r L`` of the clamped-free equation ``1 + cos(bL) cosh(bL) = 0`` (2.40).

    Solved as ``cos x + 1/cosh x = 0`` (no overflow); root r lies in ``((r-1) pi, r pi)``.
    1.87510, 4.69409, 7.85476, 10.99554, ...
    """
    f = lambda x: math.cos(x) + 1.0 / math.cosh(x)  # noqa: E731
    out = []
    for r in range(1, n + 1):
        lo = max((r - 1) * math.pi, 1e-9)
        out.append(brentq(f, lo, r * math.pi, xtol=1e-15))
    return np.asarray(out)


def eb_frequencies(beam: RectBeam, direction: Direction, n: int) -> np.ndarray:
    """Euler–Bernoulli bending frequencies [Hz]: ``omega_r = (b_r L)^2 sqrt(EI/(rho A L^4))`` (2.40–2.41)."""
    return eb_roots(n) ** 2 * beam.omega_scale(direction) / (2 * math.pi)


def eb_mode_shape(x: np.ndarray, bL: float, L: float) -> np.ndarray:
    """Clamped-free mode shape (2.39)/(3.11), normalised as printed: ``|phi(L)| = 2``, ``int phi^2 = L``.

    Written in the numerically stable form of Gonçalves et al. (2007) so that high modes do not
    lose digits to ``cosh - cos`` cancellation.
    """
    x = np.asarray(x, dtype=float)
    b = bL / L
    sig = (math.cosh(bL) + math.cos(bL)) / (math.sinh(bL) + math.sin(bL))
    bx = b * x
    # cosh - sig sinh = ((1 - sig) e^{bx} + (1 + sig) e^{-bx}) / 2, stable for large bx.
    hyp = 0.5 * ((1.0 - sig) * np.exp(bx) + (1.0 + sig) * np.exp(-bx))
    return (np.cos(bx) - sig * np.sin(bx)) - hyp


# --------------------------------------------------------------------------------------------
# Timoshenko
# --------------------------------------------------------------------------------------------


def _timo_params(beam: RectBeam, direction: Direction) -> tuple[float, float]:
    """Huang's non-dimensional ``r^2 = I/(A L^2)`` (rotary inertia), ``s^2 = EI/(kappa G A L^2)`` (shear)."""
    I = beam.I(direction)
    r2 = I / (beam.A * beam.L**2)
    s2 = beam.E * I / (beam.k_shear * beam.G * beam.A * beam.L**2)
    return r2, s2


def timoshenko_equation(b: float, r2: float, s2: float) -> float:
    """Huang's (1961) clamped-free Timoshenko frequency equation divided by ``cosh(b alpha)``.

    ``b^2 = rho A omega^2 L^4 / (EI)``; below the cut-off ``b r s < 1``:
    ``2 + [b^2 (r^2 - s^2)^2 + 2] cosh(b a) cos(b c) - b (r^2 + s^2) / sqrt(1 - b^2 r^2 s^2) sinh(b a) sin(b c) = 0``
    with ``a, c = sqrt(( -/+ (r^2 + s^2) + sqrt((r^2 - s^2)^2 + 4 / b^2)) / 2)``.
    For r, s -> 0: ``a = c = 1/sqrt(b)`` and it reduces to ``2 (1 + cos cosh) = 0`` (2.40).
    """
    root = math.sqrt((r2 - s2) ** 2 + 4.0 / b**2)
    a = math.sqrt(0.5 * (-(r2 + s2) + root))
    c = math.sqrt(0.5 * ((r2 + s2) + root))
    q = 1.0 - b * b * r2 * s2
    ba, bc = b * a, b * c
    return (
        2.0 / math.cosh(ba)
        + (b * b * (r2 - s2) ** 2 + 2.0) * math.cos(bc)
        - b * (r2 + s2) / math.sqrt(q) * math.tanh(ba) * math.sin(bc)
    )


def timoshenko_roots(beam: RectBeam, direction: Direction, n: int) -> np.ndarray:
    """First ``n`` roots ``b = sqrt(rho A omega^2 L^4 / EI)`` of the Timoshenko equation (shear + rotary inertia).

    Scanned in ``sqrt(b)`` (the Euler–Bernoulli ``bL`` variable, roots ~pi apart) with step 0.02.
    Raises :class:`SolverError` if the n-th root lies above the second-spectrum cut-off
    ``b r s = 1`` (the beam is then too short for beam theory to mean anything).
    """
    r2, s2 = _timo_params(beam, direction)
    x_max = (1.0 / math.sqrt(r2 * s2)) ** 0.5 * (1 - 1e-9)
    f = lambda x: timoshenko_equation(x * x, r2, s2)  # noqa: E731
    try:
        x = _scan_roots(f, 0.3, 0.02, n, x_max)
    except SolverError:
        raise SolverError(
            f"Timoshenko: fewer than {n} {direction} modes below the cut-off frequency; "
            "the beam is too stubby for beam theory"
        ) from None
    return x * x


def timoshenko_frequencies(beam: RectBeam, direction: Direction, n: int) -> np.ndarray:
    """Timoshenko clamped-free bending frequencies [Hz] (Cowper's kappa unless ``beam.kappa`` set)."""
    return timoshenko_roots(beam, direction, n) * beam.omega_scale(direction) / (2 * math.pi)


# --------------------------------------------------------------------------------------------
# Torsion, axial, static stiffness
# --------------------------------------------------------------------------------------------


def torsion_frequencies(beam: RectBeam, n: int) -> np.ndarray:
    """Saint-Venant torsion of a clamped-free bar [Hz]: ``omega_r = (2r-1) pi / (2L) sqrt(G J / (rho I_p))``.

    ``J`` is the rectangular torsion constant (series, :func:`torsion_constant_rect`), ``I_p`` the
    polar moment of area (rotary inertia of the section). **Warping is neglected**: the clamp
    in the FEM also prevents warping of the root section, which stiffens the first torsion mode
    slightly (the effect scales with the warping constant, small for a 3:1 section).
    """
    r = np.arange(1, n + 1)
    return (2 * r - 1) * math.pi / (2 * beam.L) * math.sqrt(beam.G * beam.J / (beam.rho * beam.Ip)) / (2 * math.pi)


def axial_frequencies(beam: RectBeam, n: int) -> np.ndarray:
    """Longitudinal rod modes of a clamped-free bar [Hz]: ``omega_r = (2r-1) pi / (2L) sqrt(E/rho)``.

    Lateral inertia (Rayleigh–Love) neglected; the 3D FEM with ``nu > 0`` sits slightly below.
    """
    r = np.arange(1, n + 1)
    return (2 * r - 1) * math.pi / (2 * beam.L) * math.sqrt(beam.E / beam.rho) / (2 * math.pi)


def static_tip_stiffness(beam: RectBeam, direction: Direction = "flapwise", shear: bool = True) -> float:
    """Static stiffness at the free end under an end force [N/m].

    Euler–Bernoulli: ``k_f = 3 EI / L^3`` (section 2.3.1). With ``shear=True`` the Timoshenko
    shear compliance is added in series: ``1/k = L^3/(3 EI) + L/(kappa G A)``. For the default
    silicon cantilever (L/t = 30) the correction is -0.07 % flapwise (3 s^2 = 3 EI/(kappa G A L^2)).
    """
    I = beam.I(direction)
    c = beam.L**3 / (3.0 * beam.E * I)
    if shear:
        c += beam.L / (beam.k_shear * beam.G * beam.A)
    return 1.0 / c


# --------------------------------------------------------------------------------------------
# Tip-mass frequency equation (3.10)
# --------------------------------------------------------------------------------------------


def tip_mass_equation(x: float, mass_ratio: float, form: TipMassForm = "standard") -> float:
    """Left side of the tip-mass frequency equation, divided by ``cosh(x)``; ``x = lambda L``.

    ``mass_ratio`` = m / (rho A L).

    * ``standard`` (departure 1; clamped beam with a point mass m at the free end):
      ``1 + cos x cosh x + (m/(rho A L)) x (cos x sinh x - sin x cosh x) = 0``.
      From the end condition ``EI v''' = m (d2v/dt2)`` (3.8 without damping): the mass term
      carries the factor ``lambda L`` that makes it an inertia ``m omega^2``.
    * ``printed`` (3.10 as typeset in the source):
      ``x (1 + cos x cosh x) + (m/(rho A L)) (cos x sinh x - cosh x sin x) = 0``.
      It has the factor on the wrong term: its mass -> infinity limit is ``tan x = tanh x``
      (3.9266, a pinned tip) instead of ``x -> 0`` (a spring-mass system).
    """
    if form == "standard":
        return 1.0 / math.cosh(x) + math.cos(x) + mass_ratio * x * (math.cos(x) * math.tanh(x) - math.sin(x))
    if form == "printed":
        return x * (1.0 / math.cosh(x) + math.cos(x)) + mass_ratio * (math.cos(x) * math.tanh(x) - math.sin(x))
    raise ParameterError(f"unknown form {form!r} of eq 3.10 (standard or printed)")


def tip_mass_roots(mass_ratio: float, n: int, form: TipMassForm = "standard") -> np.ndarray:
    """First ``n`` positive roots ``lambda_n L`` of (3.10), printed or standard form.

    Robust bracketing: the roots of both forms are separated by at least ~pi/2 (they interlace
    with the clamped-free and clamped-pinned roots), so a scan with step 0.01 from x = 1e-4
    followed by Brent's method finds every root in order. For the standard form with a very
    heavy mass the first root ``(3/mass_ratio)^(1/4)`` can fall below the scan start; it is then
    bracketed on a logarithmic grid first.
    """
    if mass_ratio < 0 or not math.isfinite(mass_ratio):
        raise ParameterError(f"tip mass ratio must be >= 0 and finite, got {mass_ratio}")
    f = lambda x: tip_mass_equation(x, mass_ratio, form)  # noqa: E731
    x0 = 1e-2
    roots: list[float] = []
    if form == "standard" and mass_ratio > 0:
        # first root ~ (3/mass_ratio)^(1/4) may be below x0: bracket it on a log grid.
        grid = np.geomspace(1e-6, x0, 200)
        vals = [f(x) for x in grid]
        for i in range(len(grid) - 1):
            if vals[i] * vals[i + 1] < 0:
                roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))
                break
    rest = _scan_roots(f, x0, 0.01, n - len(roots), 10.0 + (n + 1) * math.pi) if n > len(roots) else []
    return np.concatenate([np.asarray(roots), np.asarray(rest)])[:n]


def tip_mass_frequencies(beam: RectBeam, direction: Direction, tip_mass: float, n: int,
                         form: TipMassForm = "standard") -> np.ndarray:
    """Bending frequencies [Hz] of the cantilever with a point mass at the tip (3.10), Euler–Bernoulli.

    ``omega_n = (lambda_n L)^2 sqrt(EI/(rho A L^4))`` (the source's text after 3.10).
    """
    x = tip_mass_roots(tip_mass / beam.mass, n, form)
    return x**2 * beam.omega_scale(direction) / (2 * math.pi)


# --------------------------------------------------------------------------------------------
# Rayleigh quotient (2.46)
# --------------------------------------------------------------------------------------------


def rayleigh_quotient(x: Sequence[float], Y: Sequence[float], EI: float | Callable, m_x: float | Callable,
                      L: float | None = None) -> float:
    """``omega^2 = int EI (Y'')^2 dx / int m_x Y^2 dx`` (2.46) for a sampled shape ``Y(x)`` [rad^2/s^2].

    ``x`` need not be sorted; duplicates (several FEM nodes at one x) are averaged. ``Y`` is
    interpolated by a quintic spline (C4, so Y'' is smooth and converges as h^4) and both
    integrals are evaluated by 8-point Gauss–Legendre on every sample interval. ``EI`` and
    ``m_x`` are constants or callables of x. The result is an upper bound of the first
    eigenvalue for any admissible shape (Rayleigh's principle) and equals omega_r^2 on an
    exact mode shape.
    """
    x = np.asarray(x, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if x.shape != Y.shape or x.ndim != 1:
        raise ParameterError("rayleigh_quotient: x and Y must be 1-D arrays of equal length")
    xu, inv = np.unique(np.round(x, 12 - int(math.floor(math.log10(max(np.ptp(x), 1e-300))))), return_inverse=True)
    Yu = np.bincount(inv, weights=Y) / np.bincount(inv)
    if xu.size < 8:
        raise ParameterError("rayleigh_quotient needs at least 8 distinct sample positions")
    spl = make_interp_spline(xu, Yu, k=5)
    d2 = spl.derivative(2)
    g, wg = np.polynomial.legendre.leggauss(8)
    a, b = xu[:-1, None], xu[1:, None]
    xq = (0.5 * (b - a) * g + 0.5 * (a + b)).ravel()
    wq = (0.5 * (b - a) * wg).ravel()
    ei = EI(xq) if callable(EI) else EI
    mx = m_x(xq) if callable(m_x) else m_x
    V = np.sum(wq * ei * d2(xq) ** 2)
    T = np.sum(wq * mx * spl(xq) ** 2)
    if T <= 0:
        raise ParameterError("rayleigh_quotient: the shape is identically zero")
    return float(V / T)
