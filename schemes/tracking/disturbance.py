"""Tip-substrate disturbance of a periodic surface (source section 3.5.2, eq 3.45).

The adiabatic tip-surface potential of a square lattice, to first order in its Fourier series::

    P(x, y) = p1 [cos(k x) + cos(k y)] + p2 cos(k x) cos(k y),   k = 2 pi / a,

and the force on the tip is ``F = -grad P`` in the substrate plane. For KBr(100) the source takes
a = 0.66 nm and prints p1 = 5.28e-9 N m, p2 = 1.056e-9 N m (from its ref. [73]).

**Units (SOURCE-NOTES 13).** P is an energy, so p1, p2 are in J. The printed values would give a
force amplitude ``k p1 = 9.5e9 1/m x 5.28e-9 J = 50 N``, ten orders of magnitude above any
atomic force. probedyn reads the printed mantissas on the scale of the tip-surface corrugation
energy of alkali-halide surfaces (tenths of an eV): **p1 = 5.28e-20 J = 0.33 eV,
p2 = 1.056e-20 J = 0.066 eV** (the printed numbers times 1e-11). The lateral force amplitude is
then ``k p1 = 0.50 nN`` (up to ``k (p1 + p2) = 0.60 nN``) and the curvature of the potential
(the tip-surface lateral stiffness) ``k^2 p1 = 4.8 N/m``: a piconewton-to-nanonewton force, as
atomic friction measurements on KBr(100) show (lateral forces of a fraction of a nN). The choice
is stated in every result; :func:`kbr` takes a ``scale`` to show the sensitivity (studies run 0.1x to
10x; the Tomlinson parameter ``eta = k^2 p1 / k_t`` tells when the tip sticks and slips).

Assumptions: the substrate plane is spanned by probedyn x and y (z normal to the substrate, the
duo-bimorph's and the tube's "vertical" z); P does not depend on the tip height (the source's
assumption; a cylindrical path moves the tip normal to the surface too); the tip's rest position
``offset`` on the lattice is a parameter (default: a potential minimum when p1 > 0, i.e. half a
lattice period from the maximum at the origin).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from probedyn.core.errors import ParameterError

EV = 1.602176634e-19  # J

#: the printed values (section 3.5.4) and the unit reading probedyn uses (module docstring)
KBR_PRINTED = {"p1": 5.28e-9, "p2": 1.056e-9, "a": 0.66e-9, "printed_unit_p": "N m"}
KBR_UNIT_FACTOR = 1e-11


@dataclass(frozen=True)
class PeriodicSurface:
    """Eq 3.45 with p1, p2 [J], lattice a [m]; ``axes``: the two tip axes of the substrate
    plane; ``offset``: tip rest position on the lattice [m] (2,)."""

    p1: float
    p2: float
    a: float
    axes: tuple[str, str] = ("x", "y")
    offset: tuple[float, float] = (0.0, 0.0)
    name: str = "periodic surface"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.a) and 1e-11 < self.a < 1e-7):
            raise ParameterError(f"lattice constant a = {self.a:g} m is not an atomic lattice (0.01-100 nm)")
        for nm in ("p1", "p2"):
            v = getattr(self, nm)
            if not math.isfinite(v) or abs(v) > 1e-16:
                raise ParameterError(f"{nm} = {v:g} J is not a tip-surface corrugation energy (|p| <= 1e-16 J = 600 eV)")

    @property
    def k(self) -> float:
        return 2 * math.pi / self.a

    def potential(self, xy: np.ndarray) -> np.ndarray:
        X = (np.asarray(xy)[..., 0] + self.offset[0]) * self.k
        Y = (np.asarray(xy)[..., 1] + self.offset[1]) * self.k
        return self.p1 * (np.cos(X) + np.cos(Y)) + self.p2 * np.cos(X) * np.cos(Y)

    def force(self, xy: np.ndarray) -> np.ndarray:
        """``-grad P`` [N], shape of ``xy`` (..., 2)."""
        k = self.k
        X = (np.asarray(xy)[..., 0] + self.offset[0]) * k
        Y = (np.asarray(xy)[..., 1] + self.offset[1]) * k
        fx = k * np.sin(X) * (self.p1 + self.p2 * np.cos(Y))
        fy = k * np.sin(Y) * (self.p1 + self.p2 * np.cos(X))
        return np.stack([fx, fy], axis=-1)

    def jacobian(self, xy: Sequence[float]) -> np.ndarray:
        """d F / d (x, y) (2, 2) [N/m] at one point."""
        k = self.k
        X = (xy[0] + self.offset[0]) * k
        Y = (xy[1] + self.offset[1]) * k
        return k * k * np.array([[math.cos(X) * (self.p1 + self.p2 * math.cos(Y)), -self.p2 * math.sin(X) * math.sin(Y)],
                                 [-self.p2 * math.sin(X) * math.sin(Y), math.cos(Y) * (self.p1 + self.p2 * math.cos(X))]])

    @property
    def force_amplitude(self) -> float:
        return self.k * (abs(self.p1) + abs(self.p2))

    @property
    def stiffness(self) -> float:
        """Largest curvature of P, ``k^2 (|p1| + |p2|)`` [N/m] (compare with the holder spring)."""
        return self.k**2 * (abs(self.p1) + abs(self.p2))

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "p1_J": self.p1, "p2_J": self.p2, "p1_eV": self.p1 / EV, "p2_eV": self.p2 / EV,
                "a_m": self.a, "axes": list(self.axes), "offset_m": list(self.offset),
                "force_amplitude_N": self.force_amplitude, "max_curvature_N_per_m": self.stiffness}


def kbr(scale: float = 1.0, axes: tuple[str, str] = ("x", "y"), offset: tuple[float, float] | None = None) -> PeriodicSurface:
    """KBr(100) as printed in section 3.5.4 with p1, p2 read in units of 1e-11 J per printed
    'N m' (module docstring), times ``scale``. Default ``offset``: the tip rests at a minimum of P
    (``a/2`` along both axes: cos = -1, P = -2 p1 + p2)."""
    if not (math.isfinite(scale) and scale >= 0):
        raise ParameterError(f"disturbance scale must be >= 0, got {scale:g}")
    a = KBR_PRINTED["a"]
    off = (a / 2, a / 2) if offset is None else offset
    return PeriodicSurface(scale * KBR_PRINTED["p1"] * KBR_UNIT_FACTOR, scale * KBR_PRINTED["p2"] * KBR_UNIT_FACTOR, a,
                           tuple(axes), tuple(off), f"KBr(100) x{scale:g}")
