"""Contact mechanics registry (section 2.2 of the source): one module per model.

``get_contact_model(name, **params)`` returns an instance; ``list_models()`` the names. All
models share the interface of :class:`.base.ContactModel`: force, contact radius and contact
stiffness against penetration on the loading / unloading / unstable branches, pull-off forces,
equilibrium at a given load, and the normalised (Maugis) curve of Fig 2.19.

================  ===========================================  =========================
name              model                                         source
================  ===========================================  =========================
``dmt``           Derjaguin–Muller–Toporov + vdW tail           (2.20), (2.21)
``jkr``           Johnson–Kendall–Roberts                        text of 2.2.2.2 (not the printed 2.22)
``md``            Maugis–Dugdale + continuous vdW tail           (2.24)–(2.35), SOURCE-NOTES 3
================  ===========================================  =========================
"""

from __future__ import annotations

from probedyn.core.errors import ParameterError

from .base import COMMON_PARAMS, ContactModel
from .dmt import DMT
from .jkr import JKR
from .maugis_dugdale import MaugisDugdale

_REGISTRY: dict[str, type[ContactModel]] = {
    DMT.name: DMT,
    JKR.name: JKR,
    MaugisDugdale.name: MaugisDugdale,
}
_ALIASES = {"maugis-dugdale": "md", "maugis_dugdale": "md", "maugis": "md"}


def list_models() -> list[str]:
    """Names of the registered contact models."""
    return list(_REGISTRY)


def get_contact_model(name: str, **params) -> ContactModel:
    """An instance of contact model ``name`` with parameter overrides (SI units)."""
    key = _ALIASES.get(str(name).lower(), str(name).lower())
    if key not in _REGISTRY:
        raise ParameterError(f"unknown contact model {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[key](**params)


__all__ = ["COMMON_PARAMS", "ContactModel", "DMT", "JKR", "MaugisDugdale", "get_contact_model", "list_models"]
