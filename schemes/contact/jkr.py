"""Johnson–Kendall–Roberts (JKR) contact (the model section 2.2.2.2 of the source describes).

JKR (Proc. R. Soc. A 324 (1971) 301): short-range adhesion acting only inside the contact,
no force out of contact. In Maugis' units (:mod:`.base`)::

    P_bar = A^3 - sqrt(6 A^3)          D_bar = A^2 - 2/3 sqrt(6 A)

i.e. ``P = K a^3 / R - sqrt(6 pi W K a^3)`` and ``delta = a^2 / R - 2/3 sqrt(6 pi W a / K)``.
Pull-off under load control ``-3/2 pi W R`` (at ``A^3 = 3/2``), under displacement control
``-5/6 pi W R`` (at ``A^3 = 1/6``, the minimum of ``D_bar``).

**Departure from the print.** Eq 2.22 as printed is not the JKR theory: its contact branch
``8/3 E* sqrt(2R) (z0 - d)^1.5`` carries no adhesive term at all (and the Hertz prefactor is
``4/3 E* sqrt(R)``), and its Lennard-Jones tail uses an undefined constant ``f``. The text around
it states the JKR assumptions (attraction only inside the contact, no force out of contact), and
those are implemented here; the approach jumps into contact at ``D_bar = 0`` onto the stable
branch (``P_bar = -4/3`` there). See docs/contact.md.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from .base import CONTACT_MODELS, ContactModel

_S6 = math.sqrt(6.0)


@CONTACT_MODELS.register
class JKR(ContactModel):
    """JKR contact: no force out of contact, adhesion inside it."""

    key: ClassVar[str] = "jkr"
    title: ClassVar[str] = "Johnson-Kendall-Roberts"
    source: ClassVar[str] = "JKR (1971); replaces the printed (2.22)"

    def nd_curve(self, A):
        A = np.atleast_1d(np.asarray(A, dtype=float))
        rA = np.sqrt(A)
        D = A * A - 2.0 / 3.0 * _S6 * rA
        P = A**3 - _S6 * A * rA
        dD = 2.0 * A - _S6 / (3.0 * rA)
        dP = 3.0 * A * A - 1.5 * _S6 * rA
        return D, P, dD, dP

    def nd_endpoint(self):
        return 0.0, 0.0
