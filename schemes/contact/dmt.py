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

from typing import ClassVar

import numpy as np

from .base import ContactModel


class DMT(ContactModel):
    """DMT contact (2.20) with its van der Waals tail; ``P_bar = A^3 - 2``, ``D_bar = A^2``."""

    name: ClassVar[str] = "dmt"
    title: ClassVar[str] = "Derjaguin-Muller-Toporov"
    equations: ClassVar[str] = "(2.20), (2.21)"

    def nd_curve(self, A):
        A = np.atleast_1d(np.asarray(A, dtype=float))
        return A * A, A**3 - 2.0, 2.0 * A, 3.0 * A * A

    def nd_endpoint(self):
        return 0.0, -2.0
