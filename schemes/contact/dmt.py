"""Derjaguin–Muller–Toporov (DMT) contact: eq 2.20 of the source.

Hertzian contact (geometry constrained to stay Hertzian) offset by the van der Waals attraction
acting around the contact, plus the van der Waals sphere–flat force out of contact::

    F = -H R / (6 zeta_0^2) + 4/3 E* sqrt(R) delta^1.5     delta >= 0   (in contact)
    F = -H R / (6 (zeta_0 - delta)^2)                      delta <  0   (gap -delta)

with ``delta = zeta_0 - (x_s - (R_s + R_t))`` the penetration (the print writes the contact
branch with the separation ``x_s - (R_s + R_t)``; the two are the same thing). With
``W = H / (12 pi zeta_0^2)`` the offset is the DMT pull-off force ``-2 pi W R`` and, in Maugis'
units (see :mod:`.base`), ``P_bar = D_bar^1.5 - 2`` — the ``lam -> 0`` limit of Maugis–Dugdale.
``4/3 E* = K``. The force is continuous at ``delta = 0`` (both branches give -H R / (6 zeta_0^2)).
Assumptions: no hysteresis (the model has none); tip and sample elastic, radii from (2.21).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from .base import CONTACT_MODELS, ContactModel


@CONTACT_MODELS.register
class DMT(ContactModel):
    """DMT contact (2.20) with its van der Waals tail; ``P_bar = A^3 - 2``, ``D_bar = A^2``."""

    key: ClassVar[str] = "dmt"
    title: ClassVar[str] = "Derjaguin-Muller-Toporov"
    source: ClassVar[str] = "(2.20), (2.21)"

    def nd_curve(self, A):
        A = np.atleast_1d(np.asarray(A, dtype=float))
        return A * A, A**3 - 2.0, 2.0 * A, 3.0 * A * A

    def nd_endpoint(self):
        return 0.0, -2.0

    def point(self, delta: float) -> tuple[float, float, float, float]:
        """Closed form of (2.20) for time integrators (same values as the general curve solve of
        :meth:`ContactModel.point`; tests/test_pushing.py compares them): in contact
        (``delta > 0``) ``F = K sqrt(R) delta^1.5 - H R / (6 zeta_0^2)``, ``a = sqrt(R delta)``;
        out of contact the Hamaker tail ``-H R / (6 (zeta_0 - delta)^2)``."""
        s = self.scales
        if delta > 0.0:
            a = math.sqrt(s.R * delta)
            return (s.K * math.sqrt(s.R) * delta * math.sqrt(delta) - s.H * s.R / (6.0 * s.z0 * s.z0),
                    1.5 * s.K * a, a, 0.5 * a / delta)
        gap = s.z0 - delta
        return -s.H * s.R / (6.0 * gap * gap), -s.H * s.R / (3.0 * gap ** 3), 0.0, 0.0
