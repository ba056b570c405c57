"""The tip-sample contact's lateral stiffness in series with the lever, at a friction loop's reversals.

Where the support turns, the tip sticks while the lateral force runs from the friction of one direction to that of
the other (:func:`probedyn.diagnose.friction_loop.reversal_deficit`). The force rises there at the stiffness of
everything between the support and the sliding interface: the lever's ``k_x`` in series with the lateral stiffness
of the contact (and the tip), ``k_stick = (1/k_x + 1/k_c)^-1`` (Carpick, Ogletree & Salmeron 1997; Lantz et al.
1997: a nanometre contact's k_c is of the order of a few N/m, comparable to a lever's torsion). Every contact has a
finite k_c, so the effect is no cause to discover but a term of the loop's baseline, taken where the reversals show
it (engine ``_declared_terms``, the likelihood-ratio rule of a declared condition's term); with a stiff contact the
baseline is the lever's ramp alone.

Parameter: the contact's compliance over the lever's, ``c = k_x / k_c`` (0: a rigid contact, the baseline), so
``k_stick = k_x / (1 + c)``. A record cannot tell a compliant contact from a lever softer than declared on the
reversals alone; the loop's level and slope do not depend on either. Measured on blind friction set 2's g12 (a
spring-block truth with k_c = 20 N/m behind a 1.2 N/m lever, ``c`` = 0.06): the first sample after each reversal
carried an excess chi^2 of 56 on 8 samples, the whole record p = 0.009 (docs/diagnose.md 9.53).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ContactStiffness(Cause):
    key = "contact-stiffness"
    kind = "friction"
    title = "Lateral contact stiffness in series with the lever (the stick at the reversals)"
    source = "Carpick, Ogletree & Salmeron (1997) APL 70, 1548: k_stick = (1/k_x + 1/k_contact)^-1"
    description = ("The stick after each reversal rises at the lever's stiffness in series with the contact's "
                   "lateral stiffness, not at k_x alone.")
    needs = "a friction loop whose reversals are resolved (the first samples of each segment above the noise)"
    changes = ("contact",)
    regimes = ("loop",)
    #: what implies the term (the report's wording; a declared condition's term says "the declared conditions")
    implied_by = "every contact's finite lateral stiffness"
    params = (CauseParam("compliance_ratio", "1", 0.0, 20.0, 0.0, "k_x / k_contact (0: a rigid contact)",
                         starts=(0.1, 0.5)),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        if not any(near is not None for _, near in getattr(problem, "rev_segments", ())):
            return None  # no reversal within the record
        c = ContactStiffness()
        c.declared = True
        return c

    def effect(self, v, s):
        s.stick_compliance += v["compliance_ratio"]

    def derived(self, v, problem):
        k = float(problem.data.k_x)
        c = float(v["compliance_ratio"])
        return {"k_stick_N_per_m": k / (1.0 + c), "k_contact_N_per_m": k / c if c > 0 else None}
