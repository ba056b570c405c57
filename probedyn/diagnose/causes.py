"""The catalog of candidate causes: physically named model extensions.

A cause is one small class: an ``id``, the data ``kind`` it applies to (``modal`` or
``friction``), a description, its parameters (:class:`CauseParam`, with unit, bounds and
starting values) and ``apply(values, state)``, which edits the model state the baseline model
is evaluated from. Adding a cause = writing one class and decorating it with ``@register``.

The modal causes live in :mod:`probedyn.diagnose.causes_modal`, the friction causes in
:mod:`probedyn.diagnose.causes_friction`; importing this module imports both.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

from probedyn.core.errors import ParameterError

__all__ = ["CauseParam", "Cause", "register", "CATALOG", "catalog", "get_cause", "catalog_table"]


@dataclass(frozen=True)
class CauseParam:
    """A fitted parameter of a cause.

    ``scale`` = ``"lin"`` or ``"log"``: log parameters are fitted as log10 of the value (for
    quantities spanning decades); ``lo``/``hi`` bound the *value* (not its log). ``starts``
    are the starting values tried (multi-start for multimodal parameters such as a position).
    ``neutral`` is the value at which the cause has no effect (the baseline); ``secondary``
    parameters are held at ``hold`` when the data have fewer points than parameters.
    """

    name: str
    unit: str
    lo: float
    hi: float
    starts: tuple[float, ...]
    doc: str = ""
    scale: str = "lin"
    neutral: float | None = None
    secondary: bool = False
    hold: float | None = None
    display_factor: float = 1.0  # multiply for a display value (e.g. ratio -> percent) -- unused if 1


class Cause:
    """Base class of a model extension. Subclasses set the class attributes and ``apply``."""

    id: ClassVar[str] = ""
    kind: ClassVar[str] = ""
    title: ClassVar[str] = ""
    description: ClassVar[str] = ""
    params: ClassVar[tuple[CauseParam, ...]] = ()
    needs: ClassVar[str] = ""  # what data the cause needs to be identifiable
    source: ClassVar[str] = ""

    def apply(self, values: dict[str, float], state: dict[str, Any]) -> None:
        """Put the cause's parameters into the model state. Default: each parameter under its
        own name (the model reads ``state[name]``); causes that combine or accumulate override it."""
        for p in self.params:
            state[p.name] = values[p.name]

    def derived(self, values: dict[str, float], problem: Any) -> dict[str, float]:
        """Physical quantities derived from the fitted parameters (for the report)."""
        return {}

    @classmethod
    def describe(cls) -> dict[str, Any]:
        return {
            "id": cls.id,
            "kind": cls.kind,
            "title": cls.title,
            "description": cls.description,
            "needs": cls.needs,
            "source": cls.source,
            "parameters": [
                {"name": p.name, "unit": p.unit, "bounds": [p.lo, p.hi], "neutral": p.neutral,
                 "scale": p.scale, "description": p.doc}
                for p in cls.params
            ],
        }


CATALOG: dict[str, type[Cause]] = {}


def register(cls: type[Cause]) -> type[Cause]:
    """Class decorator adding a cause to the catalog (ids must be unique)."""
    if not cls.id or cls.kind not in ("modal", "friction"):
        raise ParameterError(f"cause class {cls.__name__} needs an id and kind modal|friction")
    if cls.id in CATALOG:
        raise ParameterError(f"duplicate cause id '{cls.id}'")
    CATALOG[cls.id] = cls
    return cls


def catalog(kind: str | None = None) -> list[type[Cause]]:
    _load()
    return [c for c in CATALOG.values() if kind is None or c.kind == kind]


def get_cause(cause_id: str) -> type[Cause]:
    _load()
    if cause_id not in CATALOG:
        raise ParameterError(f"unknown cause '{cause_id}' (known: {', '.join(CATALOG)})")
    return CATALOG[cause_id]


def catalog_table(kind: str | None = None) -> list[dict[str, Any]]:
    return [c.describe() for c in catalog(kind)]


def _load() -> None:
    from probedyn.diagnose import causes_friction, causes_modal  # noqa: F401  (registration)
