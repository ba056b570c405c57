"""A contact model written the way a user adds one: this file and nothing else.

Hertz contact without adhesion (section 2.2, eq 2.20 with no van der Waals term): in Maugis'
units ``D_bar = A^2``, ``P_bar = A^3`` (so ``P = 4/3 E* sqrt(R) delta^1.5``), no force out of
contact, pull-off 0. Registered in the contact registry on import; tests/test_new_models.py runs
it through ``probedyn contact``.
"""

from typing import ClassVar

import numpy as np

from probedyn.schemes.contact.base import CONTACT_MODELS, ContactModel


@CONTACT_MODELS.register
class Hertz(ContactModel):
    key: ClassVar[str] = "hertz"
    title: ClassVar[str] = "Hertz, no adhesion (an example model, tests only)"
    source: ClassVar[str] = "Hertz (1882); eq 2.20 without the van der Waals term"

    def nd_curve(self, A):
        A = np.atleast_1d(np.asarray(A, dtype=float))
        return A * A, A**3, 2.0 * A, 3.0 * A * A

    def nd_endpoint(self):
        return 0.0, 0.0
