"""Beam references for the springs and masses at the apex of a tip under a rectangular cantilever.

Conventions of :mod:`probedyn.lumped.beam`: beam along x (clamp at 0), width w along y,
thickness t along z; the tip hangs under the beam (towards -z), its apex at distance ``x`` from
the clamp (the apex of a pyramid flush with the free end sits ``tip_height tan(half_angle)``
before it) and ``lever = tip_height + t/2`` below the beam's axis.

Scan direction (FFM across the beam, y): a force F_y at the apex bends the beam laterally and
twists it by the moment ``F_y lever`` (Saint-Venant torsion, **free warping**, also at the
clamp), so two springs act in series (the issue's form, with x = L):

    k_torsion = G J / (x lever^2),  J = beta w t^3 (torsion_constant_rect),
    k_lateral = 1 / (x^3 / (3 E I_z) [+ x / (kappa G A)]),   I_z = t w^3 / 12,
    1 / k_scan = 1 / k_torsion + 1 / k_lateral    (+ the tip's own compliance, not modelled).

What the beam model leaves out, and the direction it moves the FEM: the clamp's restraint of the
section's warping (stiffer torsion, a boundary layer ~w long), the rigid tip base (stiffer), the
tip's own bending and the apex singularity of a sharp tip (softer; the FEM's apex compliance
grows like 1/h_apex under refinement: docs/reduced-probes.md).

Normal (z): ``k = 1 / (x^3/(3 E I_y) [+ x/(kappa G A)])``, ``I_y = w t^3 / 12`` (section 2.3.1).
First-mode effective mass at the apex (eqs 3.1-3.3 referred to the apex, Euler–Bernoulli mode
phi of eq 2.39): ``m = (rho A int_0^L phi^2 dx + m_tip phi(x_tip)^2) / phi(x)^2``.
"""

from __future__ import annotations

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.lumped.beam import RectBeam, eb_mode_shape, eb_roots


def _x(beam: RectBeam, x: float | None) -> float:
    x = beam.L if x is None else float(x)
    if not (0 < x <= beam.L * (1 + 1e-12)):
        raise ParameterError(f"apex position x = {x:g} m must lie on the beam (0, {beam.L:g}]")
    return x


def torsion_stiffness(beam: RectBeam, lever: float, x: float | None = None) -> float:
    """``G J / (x lever^2)`` [N/m]: Saint-Venant torsion seen at a point ``lever`` below the axis."""
    if not lever > 0:
        raise ParameterError(f"lever (tip height + t/2) must be positive, got {lever:g} m")
    return beam.G * beam.J / (_x(beam, x) * lever**2)


def bending_stiffness(beam: RectBeam, direction: str = "flapwise", x: float | None = None,
                      shear: bool = False) -> float:
    """Static stiffness at distance x from the clamp: Euler–Bernoulli ``3 E I / x^3``, with
    ``shear`` the Timoshenko shear compliance ``x / (kappa G A)`` added."""
    x = _x(beam, x)
    c = x**3 / (3.0 * beam.E * beam.I(direction))
    if shear:
        c += x / (beam.k_shear * beam.G * beam.A)
    return 1.0 / c


def scan_stiffness(beam: RectBeam, tip_height: float, x: float | None = None, shear: bool = False) -> dict[str, float]:
    """Torsion through the tip height in series with lateral bending (module docstring).

    ``x=None, shear=False`` is the printed form ``k = G w t^3 beta / (L (h + t/2)^2)`` in series
    with ``3 E I_z / L^3``. Returns the parts and the series value [N/m]."""
    lever = tip_height + beam.t / 2.0
    kt = torsion_stiffness(beam, lever, x)
    kl = bending_stiffness(beam, "lateral", x, shear)
    return {"torsion": kt, "lateral_bending": kl, "series": 1.0 / (1.0 / kt + 1.0 / kl),
            "beta": beam.J / (beam.w * beam.t**3), "lever": lever}


def first_mode_effective_mass(beam: RectBeam, x: float | None = None, tip_mass: float = 0.0,
                              tip_x: float | None = None) -> float:
    """Effective mass [kg] of the first Euler–Bernoulli bending mode (either plane) referred to
    the point at distance x from the clamp, with an optional rigid tip mass at ``tip_x`` (its
    rotary inertia neglected). Without a tip mass and x = L: ``rho A L / 4``."""
    x = _x(beam, x)
    bL = float(eb_roots(1)[0])
    phi = lambda s: float(eb_mode_shape(np.array([s]), bL, beam.L)[0])  # noqa: E731
    # int_0^L phi^2 = L for the printed normalisation (|phi(L)| = 2)
    num = beam.rho * beam.A * beam.L
    if tip_mass:
        num += tip_mass * phi(_x(beam, tip_x)) ** 2
    return num / phi(x) ** 2


__all__ = ["torsion_stiffness", "bending_stiffness", "scan_stiffness", "first_mode_effective_mass"]
