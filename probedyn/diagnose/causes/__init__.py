"""The catalog of causes: physically named extensions of probedyn's own models.

A cause is one class in one module of this package, registered with
``@CAUSES.register`` (the one registry pattern, :class:`probedyn.core.registry.Registry`). It
declares

* ``key`` (registry name), ``title``, ``source`` (equations / references), ``kind`` -- the data
  kind whose model it extends: ``"modal"`` (modal data and spectra: the probe's FEM),
  ``"friction"`` (the FFM line-scan model of :mod:`probedyn.schemes.ffm`) or ``"force"``
  (force-distance curves: lever + contact registry);
* ``params``: a tuple of :class:`CauseParam` -- unit, bounds, the **null value** at which the
  cause has no effect (the extended model is then exactly the baseline: causes are *nested*),
  the fitting scale and extra starting values for the multi-start fit;
* ``changes``: the model quantities it acts on (``"thickness"``, ``"medium"``, ``"temperature"``,
  ...); a quantity the measurement declares as known (``[conditions]``, ``[probe] known``)
  excludes or constrains the cause (:meth:`Cause.constrain`);
* ``effect(values, state)``: **its own effect on the model** -- it edits the model state the
  problem's simulator is evaluated from (a modal cause adds FEM matrix terms, point masses or
  geometric scalings; a friction cause changes the FFM setup or the measurement chain). The
  engine never branches on a cause's key.

Adding a cause = one new module here (or any module that registers a class the same way,
e.g. a test); ``probedyn diagnose --list-causes`` shows it and the diagnosis uses it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from probedyn.core.registry import Registry, RegistryError

__all__ = ["CauseParam", "Cause", "CAUSES", "KINDS", "catalog", "catalog_table"]

KINDS = ("modal", "friction", "force")


@dataclass(frozen=True)
class CauseParam:
    """A fitted parameter of a cause (or of a baseline calibration).

    ``lo``/``hi`` bound the value; ``null`` is the value at which the cause has no effect (it
    must lie in ``[lo, hi]``); ``scale`` ``"lin"`` or ``"log"`` (fitted as log10 of the value;
    then ``lo > 0``); ``starts``: values tried besides the null value in the multi-start fit
    (a position along the beam, a compliance spanning decades, ...); ``sweep``: the step (in the value, or
    its log10 for ``"log"``) of a profile sweep after every full-data fit of the cause
    (engine ``Fitter.swept``; 0: none). A parameter whose misfit is rugged along it (one that moves
    stick-slip events across samples) declares one: a local optimiser stops in the first basin.
    ``sweep_claimed``: the sweep runs only once the cause is claimed (the lead, or an extension taken),
    not on every candidate's fit: for a parameter whose held fits are costly (a misaligned scan's angle, each
    point a 2D scan) and whose first basin is already good enough for the ranking.
    ``sweep_relative``: the step is a fraction of the value (a geometric walk, ``v (1 + sweep)^k`` and
    ``v / (1 + sweep)^k``) for a linear parameter whose null is 0 and whose values span decades (a viscous
    coefficient); a fit ending at the null is not swept.
    """

    name: str
    unit: str
    lo: float
    hi: float
    null: float
    doc: str = ""
    scale: str = "lin"
    starts: tuple[float, ...] = ()
    sweep: float = 0.0
    sweep_claimed: bool = False
    sweep_relative: bool = False

    def __post_init__(self) -> None:
        if not (self.lo <= self.null <= self.hi):
            raise RegistryError(f"parameter {self.name}: null value {self.null} outside [{self.lo}, {self.hi}]")
        if self.scale not in ("lin", "log"):
            raise RegistryError(f"parameter {self.name}: scale must be 'lin' or 'log'")
        if self.scale == "log" and not self.lo > 0:
            raise RegistryError(f"parameter {self.name}: a log-scale parameter needs lo > 0")
        if not self.sweep >= 0:
            raise RegistryError(f"parameter {self.name}: sweep must be >= 0")
        if self.sweep_relative and (self.scale != "lin" or self.lo < 0):
            raise RegistryError(f"parameter {self.name}: a relative sweep needs a linear scale and lo >= 0")
        for s in self.starts:
            if not (self.lo <= s <= self.hi):
                raise RegistryError(f"parameter {self.name}: start {s} outside [{self.lo}, {self.hi}]")

    def to_u(self, v: float) -> float:
        return math.log10(v) if self.scale == "log" else float(v)

    def from_u(self, u: float) -> float:
        return 10.0 ** u if self.scale == "log" else float(u)

    @property
    def u_bounds(self) -> tuple[float, float]:
        return self.to_u(self.lo), self.to_u(self.hi)

    def with_bounds(self, lo: float, hi: float, null: float | None = None) -> "CauseParam":
        n = self.null if null is None else null
        return CauseParam(self.name, self.unit, lo, hi, min(max(n, lo), hi), self.doc, self.scale,
                          tuple(s for s in self.starts if lo <= s <= hi), self.sweep, self.sweep_claimed,
                          self.sweep_relative)

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "unit": self.unit, "bounds": [self.lo, self.hi], "null": self.null,
                "scale": self.scale, "description": self.doc}


class Cause:
    """Base class of a cause. Subclasses set the class attributes and define :meth:`effect`."""

    key: ClassVar[str] = ""
    title: ClassVar[str] = ""
    source: ClassVar[str] = ""
    kind: ClassVar[str] = ""
    description: ClassVar[str] = ""
    needs: ClassVar[str] = ""  # which data make it identifiable
    params: ClassVar[tuple[CauseParam, ...]] = ()
    changes: ClassVar[tuple[str, ...]] = ()
    #: friction: the regimes of the record the cause applies to (``"stick-slip"``: samples resolve the lattice;
    #: ``"loop"``: each sample averages many periods, :mod:`probedyn.diagnose.friction_loop`); empty: stick-slip
    regimes: ClassVar[tuple[str, ...]] = ()
    #: the model component the cause *selects* rather than edits (the contact law: DMT, JKR or Maugis-Dugdale
    #: replaces the Hertz sphere): two causes of one component are alternatives, so neither extends a model
    #: the other is in (the engine's greedy extension skips it; their combination is the later law alone)
    alternative: ClassVar[str | None] = None

    def __init__(self, params: tuple[CauseParam, ...] | None = None, note: str = "") -> None:
        # a problem may narrow the parameters (declared conditions); the class stays untouched
        self.params = tuple(type(self).params if params is None else params)
        self.note = note
        #: set by :meth:`constrain` where the measurement's declared conditions *imply* the effect (thermal
        #: activation at a declared temperature): it is then no cause to discover but a term of the baseline, which
        #: carries it where the data show it (engine ``_declared_terms``), and the other causes extend that baseline
        self.declared = False

    def effect(self, values: dict[str, float], state: Any) -> None:  # pragma: no cover - placeholder
        """Apply the cause with parameter ``values`` to the model ``state`` (in place)."""
        raise NotImplementedError

    def derived(self, values: dict[str, float], problem: Any) -> dict[str, float]:
        """Physical quantities derived from the fitted parameters (SI; for the report)."""
        return {}

    def constrain(self, problem: Any) -> "Cause | None":
        """This cause as the measurement's declared conditions allow it: ``None`` when a declared
        quantity rules it out (default: any quantity in ``changes`` declared known), else a
        (possibly narrowed) instance."""
        known = getattr(problem, "known", set())
        hit = [c for c in self.changes if c in known]
        return None if hit else self

    @property
    def id(self) -> str:  # the key, as reported
        return self.key

    def __repr__(self) -> str:
        return f"<cause {self.key}>"

    @classmethod
    def describe(cls) -> dict[str, Any]:
        return {"id": cls.key, "key": cls.key, "kind": cls.kind, "title": cls.title, "description": cls.description,
                "needs": cls.needs, "source": cls.source, "changes": list(cls.changes),
                "parameters": [p.describe() for p in cls.params]}


def _check(cls: type) -> None:
    if cls.kind not in KINDS:
        raise RegistryError(f"cause {cls.__qualname__}: kind must be one of {', '.join(KINDS)}")
    if not isinstance(cls.params, tuple) or not all(isinstance(p, CauseParam) for p in cls.params):
        raise RegistryError(f"cause {cls.__qualname__}: params must be a tuple of CauseParam")
    if not cls.params:
        raise RegistryError(f"cause {cls.__qualname__}: needs at least one parameter")
    names = [p.name for p in cls.params]
    if len(set(names)) != len(names):
        raise RegistryError(f"cause {cls.__qualname__}: duplicate parameter names")


CAUSES: Registry = Registry("cause", Cause, required=("effect",), package="probedyn.diagnose.causes",
                            check=_check, needs_params=False)


def catalog(kind: str | None = None) -> list[type[Cause]]:
    """Registered cause classes (of one data kind), sorted by key."""
    return [c for c in CAUSES if kind is None or c.kind == kind]


def catalog_table(kind: str | None = None) -> list[dict[str, Any]]:
    return [c.describe() for c in catalog(kind)]
