"""Fluid loading of a vibrating beam: Sader's hydrodynamic function (added mass and damping).

J. E. Sader, J. Appl. Phys. 84, 64 (1998): a thin rectangular beam of width ``w`` oscillating
flapwise at angular frequency omega in a fluid of density ``rho_f`` and viscosity ``eta_f`` feels a
force per unit length ``F = (pi/4) rho_f w^2 omega^2 Gamma(omega) W`` with
``Gamma = Gamma_r - i Gamma_i``: an added mass ``(pi/4) rho_f w^2 Gamma_r`` per length and a damping
``(pi/4) rho_f w^2 omega Gamma_i``. ``Gamma`` is the circular-cylinder function (eq 20) times a
rational correction ``Omega(Re)`` (eq 21), ``Re = rho_f omega w^2 / (4 eta_f)``.

Assumptions (Sader's): ``L >> w`` (two-dimensional flow across the width), the fluid is
incompressible, the amplitude is small, the beam is far from any surface.

**Torsion** (Green & Sader, J. Appl. Phys. 92, 6262 (2002)): a section rotating about its centre line with
angle theta feels a torque per unit length ``T = (pi/128) rho_f w^4 omega^2 Gamma_tor(omega) theta``: the
inviscid added moment of inertia of a flat plate, ``(pi/8) rho_f (w/2)^4``, times the torsional function,
``Gamma_tor -> 1`` for Re -> infinity (same Re). Green & Sader computed it by a boundary-integral method; the
values here (:func:`torsion_gamma`) are probedyn's own, from the two-dimensional oscillatory Stokes flow about a
thin section solved by finite elements (:mod:`probedyn.fem.stokes2d`, ``benchmarks/torsional_gamma_table.py``),
whose flexural solution reproduces Sader's ``Gamma_rect`` (``tests/test_stokes2d.py``). Written with the
prefactor ``(pi/8) rho_f omega^2 w^4`` the same function is this one divided by 16.

**Lateral (in-plane) motion** drags the fluid by its two large faces: Stokes's second problem (a plane
oscillating in its own plane; Landau & Lifshitz, Fluid Mechanics, section 24) gives a shear stress
``-(1 + i) (eta_f / delta) U`` per face, ``delta = sqrt(2 eta_f / (rho_f omega))`` the viscous penetration
depth, i.e. an added mass ``rho_f delta / 2`` per unit face area and a damping ``omega`` times it
(:func:`stokes_layer_mass`). Assumed: ``delta << w`` (the layer thin against the width: 0.75 um in water at
0.5 MHz) and the edges' pressure left out (their share of the load is about ``t^2 / (w delta)``: a few % in
air, ~10 % for a 2 um lever in water).

**A rarefied gas** (a residual gas in a vacuum chamber): where the gas's mean free path is not small against the
width (Knudsen number ``lambda / w``; air: lambda ~ 68 nm at 1 bar, 0.1 mm at 60 Pa) the continuum functions
above do not hold: their damping does not vanish with the pressure (it depends on the viscosity, not the density,
at low Re), while a rarefied gas's does, in proportion. In the free-molecular limit each molecule exchanges
momentum with the plate alone (:func:`free_molecular_damping`): a force per unit area ``b_n v`` on a plate moving
normal to itself, ``b_t v`` per face moving in its own plane, both proportional to the pressure and independent of
the frequency, with no added mass. Between the limits the continuum load (added mass and damping alike) is scaled
by ``c_fm / (c_fm + c_cont)``, ``c`` the two dampings (:func:`rarefied_factor`): the damping is their harmonic
sum, which is Cunningham's slip correction in its first-order form, ``F_cont / (1 + A Kn)``, with its constant
fixed by the free-molecular limit; the added mass vanishes with it. Exact in both limits; between them an
interpolation (Bidkar et al., Appl. Phys. Lett. 94, 163117 (2009), solve the Boltzmann equation there).

Used by the modal diagnosis (:mod:`probedyn.diagnose.modal_model`): the declared medium loads
the baseline's flapwise, torsion and lateral modes, and the fluid cause fits an unknown medium (in a declared
vacuum, a residual gas at its pressure, rarefied).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.constants import R as R_GAS
from scipy.special import kve

__all__ = ["sader_gamma", "torsion_gamma", "stokes_layer_mass", "free_molecular_damping", "rarefied_factor",
           "MEDIA", "M_AIR", "ROOM_TEMPERATURE"]

#: media a sidecar may name: (density kg/m^3, dynamic viscosity Pa s) at about 20-25 C
MEDIA = {"vacuum": (0.0, 1.8e-5), "air": (1.18, 1.85e-5), "nitrogen": (1.14, 1.76e-5),
         "water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3)}
#: the temperature of MEDIA and of a record that declares none [K]
ROOM_TEMPERATURE = 295.0
#: molar mass of dry air [kg/mol]
M_AIR = 0.028965

_RE_RANGE = (1e-6, 1e4)  # validity range of eq 21


def _omega_rect(re: np.ndarray) -> np.ndarray:
    """Sader (1998) eq 21: correction Omega(Re) from a circular to a rectangular section."""
    tau = np.log10(re)
    num_r = (0.91324 - 0.48274 * tau + 0.46842 * tau**2 - 0.12886 * tau**3
             + 0.044055 * tau**4 - 0.0035117 * tau**5 + 0.00069085 * tau**6)
    den_r = (1 - 0.56964 * tau + 0.48690 * tau**2 - 0.13444 * tau**3
             + 0.045155 * tau**4 - 0.0035862 * tau**5 + 0.00069085 * tau**6)
    num_i = (-0.024134 - 0.029256 * tau + 0.016294 * tau**2 - 0.00010961 * tau**3
             + 0.000064577 * tau**4 - 0.000044510 * tau**5)
    den_i = (1 - 0.59702 * tau + 0.55182 * tau**2 - 0.18357 * tau**3
             + 0.079156 * tau**4 - 0.014369 * tau**5 + 0.0028361 * tau**6)
    return num_r / den_r + 1j * num_i / den_i


def sader_gamma(omega, width: float, rho_f: float, eta_f: float, circular: bool = False) -> np.ndarray:
    """``Gamma_r + 1j * Gamma_i`` (``Gamma_i > 0`` is the dissipative part) at angular frequency omega.

    Re outside eq 21's range [1e-6, 1e4] is clipped to it. Limits (tests): ``Gamma_r -> 1`` for
    Re -> infinity (inviscid added mass (pi/4) rho_f w^2 of a plate) and the circular-cylinder
    asymptote ``1 + 2 sqrt(2) (1 + i) / sqrt(Re)``.
    """
    omega = np.asarray(omega, dtype=float)
    re = rho_f * omega * width**2 / (4.0 * eta_f)
    if not circular:
        re = np.clip(re, *_RE_RANGE)
    s = np.sqrt(1j * re)
    z = -1j * s
    gc = 1.0 + 4.0j * kve(1, z) / (s * kve(0, z))  # scaled Bessel functions: same ratio, no overflow
    g = gc if circular else _omega_rect(re) * gc
    return g.real + 1j * np.abs(g.imag)


#: Green & Sader's torsional function of a thin plate, computed by probedyn's 2D oscillatory-Stokes FEM
#: (``benchmarks/torsional_gamma_table.py`` -> ``benchmarks/results/torsional_gamma_table.json``; zero-thickness
#: limit, estimated error <= 1.2e-4 relative): (Gamma_tor,r, Gamma_tor,i) at log10 Re = -1, -0.75, ..., 4
_TORSION_LOG10_RE = np.arange(-1.0, 4.0 + 1e-9, 0.25)
_TORSION_TABLE = np.array([
    (10.3867, 163.906),
    (8.96185, 93.6144),
    (7.64864, 53.9256),
    (6.46677, 31.4349),
    (5.43049, 18.6155),
    (4.54498, 11.2436),
    (3.80613, 6.95115),
    (3.20203, 4.41055),
    (2.71625, 2.87569),
    (2.33102, 1.9256),
    (2.02918, 1.32164),
    (1.79484, 0.927349),
    (1.6138, 0.663365),
    (1.47415, 0.482406),
    (1.36649, 0.355689),
    (1.28343, 0.265247),
    (1.21927, 0.199613),
    (1.16967, 0.151307),
    (1.13127, 0.115347),
    (1.10154, 0.0882988),
    (1.07852, 0.0678124),
])
#: above Re = 1e4 (``benchmarks/torsional_gamma_table.py``'s ``fit_asymptote``): the boundary layer of a plate whose
#: slip velocity is singular at the edges, ``Gamma - 1 = (sqrt 2 / pi) (1 + i) ln(Re) / sqrt(Re) + c1 / sqrt(Re) +
#: c2 / Re + c3 ln(Re) / Re`` (the log coefficient from the slip ``Omega (x^2 - a^2/2) / sqrt(a^2 - x^2)``; c
#: fitted to the table on [10^2.5, 10^4], residual <= 3e-5): (c1, c2, c3) of the real and the imaginary part
#: the log term's coefficient (per unit 1 + i) for rotation; translation's is half (its slip U x / sqrt(a^2 - x^2))
TORSION_LOG_COEF = math.sqrt(2.0) / math.pi
_TORSION_ASYMPTOTE = ((3.62289, 0.446726, 0.858414), (2.27907, 9.19856, 2.8956))


def torsion_gamma(omega, width: float, rho_f: float, eta_f: float) -> np.ndarray:
    """Green & Sader's torsional function ``Gamma_tor,r + 1j * Gamma_tor,i`` (``Gamma_i > 0`` dissipative) at
    angular frequency omega, ``Re = rho_f omega w^2 / (4 eta_f)`` (module docstring).

    Interpolated in log Re (cubic, on ``ln Gamma_r`` and ``ln Gamma_i``) in the table's range [0.1, 1e4];
    above it the fitted boundary-layer asymptote (:data:`_TORSION_ASYMPTOTE`); below it clipped to Re = 0.1 (a
    lever far below that is not an AFM lever in a fluid). Limits (``tests/test_stokes2d.py``): ``Gamma_r -> 1``
    as Re -> infinity (the inviscid plate), ``Re Gamma_i -> 16`` as Re -> 0 (the steady Stokes torque
    ``2 pi eta a^2 Omega`` of a rotating flat plate of half-width a)."""
    omega = np.asarray(omega, dtype=float)
    re = rho_f * omega * width**2 / (4.0 * eta_f)
    lo, hi = 10.0 ** _TORSION_LOG10_RE[0], 10.0 ** _TORSION_LOG10_RE[-1]
    x = np.log10(np.clip(re, lo, hi))
    g = np.exp(_TORSION_SPLINES[0](x)) + 1j * np.exp(_TORSION_SPLINES[1](x))
    big = re > hi
    if np.any(big):
        r = np.asarray(re, float)[big] if np.ndim(re) else float(re)
        terms = np.array([1.0 / np.sqrt(r), 1.0 / r, np.log(r) / r])
        (cr, ci) = (np.asarray(c) for c in _TORSION_ASYMPTOTE)
        ga = (1.0 + (1.0 + 1j) * TORSION_LOG_COEF * np.log(r) / np.sqrt(r)
              + np.tensordot(cr, terms, 1) + 1j * np.tensordot(ci, terms, 1))
        if np.ndim(re):
            g = np.array(g, complex)
            g[big] = ga
        else:
            g = ga
    return g


#: how a section's thickness changes the hydrodynamic functions, computed by probedyn's 2D oscillatory-Stokes FEM
#: (``benchmarks/section_thickness_table.py`` -> ``benchmarks/results/section_thickness_table.json``): the relative
#: change of Gamma_r (added mass) and Gamma_i (damping) of a rectangle of thickness ratio t/w against the zero-thickness
#: limit (Sader's Gamma_rect; Green & Sader's torsional function), at log10 Re = -1, 0, ..., 4 (rows) and
#: t/w = 0.02, 0.05, 0.1, 0.2, 0.33, 0.5 (columns); 0 at t/w = 0. At Re = 1e4 the flexural added mass tends to the
#: inviscid rectangle's (DNV-RP-C205 Table A-1: +14 %, +21 %, +36 % at t/w = 0.1, 0.2, 0.5; here +12.4 %, +19.7 %,
#: +34.0 %, from below as the boundary layer thins)
THICKNESS_LOG10_RE = np.arange(-1.0, 4.0 + 1e-9, 1.0)
THICKNESS_RATIOS = np.array([0.02, 0.05, 0.1, 0.2, 0.33, 0.5])
_THICKNESS_CHANGE = {
    ("flexure", "r"): ((0.007799, 0.01957, 0.03918, 0.07811, 0.1276, 0.1906),
                       (0.007805, 0.02026, 0.04156, 0.08442, 0.1391, 0.2082),
                       (0.008581, 0.02358, 0.04941, 0.09934, 0.1586, 0.2277),
                       (0.01506, 0.03906, 0.07575, 0.1366, 0.2006, 0.2694),
                       (0.02574, 0.05956, 0.1047, 0.1736, 0.242, 0.3126),
                       (0.03519, 0.07422, 0.1237, 0.1971, 0.2682, 0.3403)),
    ("flexure", "i"): ((0.004749, 0.01174, 0.02321, 0.04555, 0.07349, 0.1086),
                       (0.006269, 0.01537, 0.03029, 0.05984, 0.09793, 0.1474),
                       (0.003601, 0.00926, 0.02096, 0.05039, 0.09493, 0.1571),
                       (-0.0141, -0.02389, -0.02316, 0.001538, 0.04626, 0.1097),
                       (-0.05625, -0.08324, -0.09145, -0.07577, -0.03851, 0.01785),
                       (-0.1164, -0.1552, -0.1715, -0.164, -0.1336, -0.08556)),
    ("torsion", "r"): ((0.02952, 0.07273, 0.1461, 0.3076, 0.5636, 1.016),
                       (0.02439, 0.06045, 0.1217, 0.2558, 0.4667, 0.8358),
                       (0.01895, 0.04811, 0.09709, 0.1988, 0.3482, 0.602),
                       (0.019, 0.04836, 0.0921, 0.1634, 0.246, 0.3795),
                       (0.02911, 0.06507, 0.1069, 0.1572, 0.1934, 0.2429),
                       (0.04259, 0.08313, 0.1251, 0.1664, 0.181, 0.1902)),
    ("torsion", "i"): ((0.0221, 0.05661, 0.1182, 0.257, 0.4679, 0.797),
                       (0.02335, 0.0594, 0.1232, 0.2664, 0.4865, 0.8376),
                       (0.02384, 0.05988, 0.1239, 0.2707, 0.5036, 0.8904),
                       (0.01312, 0.03951, 0.09714, 0.2417, 0.4764, 0.8756),
                       (-0.02416, -0.01223, 0.03776, 0.1706, 0.3911, 0.7742),
                       (-0.08486, -0.08562, -0.04717, 0.0689, 0.2683, 0.6182)),
}


def section_thickness_change(re, t_over_w: float, motion: str = "flexure") -> tuple[np.ndarray, np.ndarray]:
    """Relative change ``(dGamma_r / Gamma_r, dGamma_i / Gamma_i)`` of the flexural (Sader's) or torsional (Green &
    Sader's) hydrodynamic function when the section has thickness ratio ``t_over_w`` instead of zero, at ``re``
    (:data:`_THICKNESS_CHANGE`). Bilinear in (log10 Re, t/w) with 0 at t/w = 0; clipped to the table (0.1 <= Re <=
    1e4, t/w <= 0.5). A thicker section carries more fluid (up to the inviscid rectangle's added mass at large Re)
    and, at large Re, less damping: its square edges cut the thin plate's singular edge flow."""
    if motion not in ("flexure", "torsion"):
        raise ValueError(f"motion must be 'flexure' or 'torsion', got {motion!r}")
    x = np.clip(np.log10(np.maximum(np.asarray(re, float), 1e-300)), THICKNESS_LOG10_RE[0], THICKNESS_LOG10_RE[-1])
    h = float(np.clip(t_over_w, 0.0, THICKNESS_RATIOS[-1]))
    return tuple(np.interp(x, THICKNESS_LOG10_RE, _thickness_column(motion, part, h)) for part in ("r", "i"))


@functools.lru_cache(maxsize=64)
def _thickness_column(motion: str, part: str, h: float) -> np.ndarray:
    """:data:`_THICKNESS_CHANGE` interpolated to thickness ratio ``h`` at every tabulated Re (linear in t/w,
    0 at t/w = 0); a fit evaluates one probe's ratio thousands of times."""
    tab = np.column_stack([np.zeros(len(THICKNESS_LOG10_RE)), np.array(_THICKNESS_CHANGE[(motion, part)])])
    at_h = np.array([np.interp(h, np.r_[0.0, THICKNESS_RATIOS], row) for row in tab])
    at_h.flags.writeable = False
    return at_h


def stokes_layer_mass(omega, rho_f: float, eta_f: float):
    """Added mass per unit area of one face of a plate oscillating in its own plane at angular frequency
    omega: ``rho_f delta / 2`` with ``delta = sqrt(2 eta_f / (rho_f omega))`` (module docstring); the
    dissipative force per area is ``omega`` times this mass times the velocity, so a mode loaded by it alone has
    ``Q = (m + m_a) / m_a``."""
    omega = np.asarray(omega, dtype=float)
    return 0.5 * rho_f * np.sqrt(2.0 * eta_f / (rho_f * omega))


_TORSION_SPLINES = tuple(CubicSpline(_TORSION_LOG10_RE, np.log(np.maximum(_TORSION_TABLE[:, j], 1e-300)))
                         for j in (0, 1))


def free_molecular_damping(p: float, T: float = ROOM_TEMPERATURE, M: float = M_AIR) -> tuple[float, float]:
    """Damping per unit area [N s / m^3] of a thin plate in a gas at pressure ``p`` [Pa] and temperature ``T`` [K]
    (molar mass ``M``) in the free-molecular limit: ``(b_n, b_t)``, ``b_n`` for the plate moving normal to itself
    (both faces together), ``b_t`` for one face moving in its own plane.

    Derivation (linear in ``v / c``, ``c = sqrt(2 R T / M)``; molecules re-emitted diffusely at the plate's
    temperature, full accommodation): the molecules that strike a face moving into the gas at ``v`` carry the
    momentum flux ``p / 2 + 2 p v sqrt(M / (2 pi R T))`` and number flux ``n (sqrt(R T / (2 pi M)) + v / 2)``;
    re-emitted, they leave with the momentum flux ``p / 2 + (p v / 2) sqrt(pi M / (2 R T))``; the face behind loses
    the same. Net: ``b_n = (4 + pi) p sqrt(M / (2 pi R T))``. In its own plane a face returns the struck molecules
    with its own velocity: ``b_t = p sqrt(M / (2 pi R T))`` (the number flux times the molecular mass).
    Specular reflection would give ``b_n = 8 p sqrt(M / (2 pi R T))`` (12 % more, Christian's Q =
    (pi/2)^(3/2) rho t f sqrt(RT/M) / p for a plate) and no ``b_t``. Edges (``t << w``) are left out."""
    g = math.sqrt(M / (2.0 * math.pi * R_GAS * T))
    return (4.0 + math.pi) * p * g, p * g


def rarefied_factor(c_fm: float, c_cont: float) -> float:
    """The factor on a continuum load (added mass and damping) of a gas whose free-molecular damping is ``c_fm``
    and continuum damping ``c_cont`` (same mode, same units): ``c_fm / (c_fm + c_cont)``, 1 in a continuum
    (``c_fm`` infinite), -> ``c_fm / c_cont`` rarefied (module docstring)."""
    if not math.isfinite(c_fm):
        return 1.0
    tot = c_fm + c_cont
    return c_fm / tot if tot > 0 else 0.0
