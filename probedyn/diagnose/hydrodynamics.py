"""Fluid loading of a vibrating beam: Sader's hydrodynamic function (added mass and damping).

J. E. Sader, J. Appl. Phys. 84, 64 (1998): a thin rectangular beam of width ``w`` oscillating
flapwise at angular frequency omega in a fluid of density ``rho_f`` and viscosity ``eta_f`` feels a
force per unit length ``F = (pi/4) rho_f w^2 omega^2 Gamma(omega) W`` with
``Gamma = Gamma_r - i Gamma_i``: an added mass ``(pi/4) rho_f w^2 Gamma_r`` per length and a damping
``(pi/4) rho_f w^2 omega Gamma_i``. ``Gamma`` is the circular-cylinder function (eq 20) times a
rational correction ``Omega(Re)`` (eq 21), ``Re = rho_f omega w^2 / (4 eta_f)``.

Assumptions (Sader's): ``L >> w`` (two-dimensional flow across the width), the fluid is
incompressible, the amplitude is small, the beam is far from any surface. Torsion is not loaded (it
needs the torsional function of Green & Sader); the diagnosis states this where it applies the function.

**Lateral (in-plane) motion** drags the fluid by its two large faces: Stokes's second problem (a plane
oscillating in its own plane; Landau & Lifshitz, Fluid Mechanics, section 24) gives a shear stress
``-(1 + i) (eta_f / delta) U`` per face, ``delta = sqrt(2 eta_f / (rho_f omega))`` the viscous penetration
depth, i.e. an added mass ``rho_f delta / 2`` per unit face area and a damping ``omega`` times it
(:func:`stokes_layer_mass`). Assumed: ``delta << w`` (the layer thin against the width: 0.75 um in water at
0.5 MHz) and the edges' pressure left out (their share of the load is about ``t^2 / (w delta)``: a few % in
air, ~10 % for a 2 um lever in water).

Used by the modal diagnosis (:mod:`probedyn.diagnose.modal_model`): the declared medium loads
the baseline's flapwise modes, and the fluid cause fits an unknown medium.
"""

from __future__ import annotations

import numpy as np
from scipy.special import kve

__all__ = ["sader_gamma", "stokes_layer_mass", "MEDIA"]

#: media a sidecar may name: (density kg/m^3, dynamic viscosity Pa s) at about 20-25 C
MEDIA = {"vacuum": (0.0, 1.8e-5), "air": (1.18, 1.85e-5), "nitrogen": (1.14, 1.76e-5),
         "water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3)}

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


def stokes_layer_mass(omega, rho_f: float, eta_f: float):
    """Added mass per unit area of one face of a plate oscillating in its own plane at angular frequency
    omega: ``rho_f delta / 2`` with ``delta = sqrt(2 eta_f / (rho_f omega))`` (module docstring); the
    dissipative force per area is ``omega`` times this mass times the velocity, so a mode loaded by it alone has
    ``Q = (m + m_a) / m_a``."""
    omega = np.asarray(omega, dtype=float)
    return 0.5 * rho_f * np.sqrt(2.0 * eta_f / (rho_f * omega))
