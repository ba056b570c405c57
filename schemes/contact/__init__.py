"""Tip–sample contact models (section 2.2 of the source): one module per model, one registry.

Every model is a class registered in :data:`~.base.CONTACT_MODELS` (a
:class:`probedyn.core.registry.Registry`) that declares ``key``, ``title``, ``source``,
``params`` (default :data:`~.base.COMMON_PARAMS`) and its normalised load–penetration curve
(``nd_curve``, ``nd_endpoint``; see :class:`~.base.ContactModel`, which derives the branches,
pull-off, equilibrium at a load and the normalised curve of Fig 2.19 from it). The modules of
this package are imported on the first lookup, so **a new model is one new file**.

================  ===========================================  =========================
key               model                                         source
================  ===========================================  =========================
``dmt``           Derjaguin–Muller–Toporov + vdW tail           (2.20), (2.21)
``jkr``           Johnson–Kendall–Roberts                        text of 2.2.2.2 (not the printed 2.22)
``md``            Maugis–Dugdale + continuous vdW tail           (2.24)–(2.35), departure 7
``cone``          Sneddon cone blunted by the tip radius         Sneddon (1965), Briscoe et al. (1994)
``pyramid``       Bilodeau pyramid (equivalent cone), blunted    Bilodeau (1992)
================  ===========================================  =========================

``get_contact_model(name, **params)`` and ``list_models()`` are the registry's ``create`` and
``names``.
"""

from __future__ import annotations

from .base import COMMON_PARAMS, CONTACT_MODELS, ContactModel
from .dmt import DMT
from .jkr import JKR
from .maugis_dugdale import MaugisDugdale


def list_models() -> list[str]:
    """Keys of the registered contact models."""
    return CONTACT_MODELS.names()


def get_contact_model(name: str, **params) -> ContactModel:
    """An instance of contact model ``name`` (key or alias) with parameter overrides (SI units)."""
    return CONTACT_MODELS.create(name, **params)


__all__ = ["COMMON_PARAMS", "CONTACT_MODELS", "ContactModel", "DMT", "JKR", "MaugisDugdale", "get_contact_model",
           "list_models"]
