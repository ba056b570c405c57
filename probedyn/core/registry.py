"""One registry pattern for every family of models: probes, friction laws, contact laws,
diagnose causes (and later placing/tracking variants).

A model is a class. It declares

* ``key``: its registry name (lower case, e.g. ``"bristle"``, ``"md"``, ``"cantilever"``);
* ``title``: one line saying what it is;
* ``source``: the equations / tables / references it implements (``"eqs 2.7-2.9, Table 2.1"``);
* ``params``: a :class:`~probedyn.core.params.ParamSet` of its parameters with units
  (or the family's own parameter declaration: a registry made with ``params_type=tuple``
  accepts e.g. the diagnose causes' tuples of ``CauseParam``);
* its behaviour: the members listed in the registry's ``required`` tuple (a friction law its
  compiled ``kernel``, a contact law its ``nd_curve``, a cause its ``effect`` ...).

:meth:`Registry.register` (a class decorator) validates all of that when the module is
imported: a missing key, a duplicate key, a missing behaviour or a behaviour left as the base
class's placeholder is a :class:`RegistryError` at import, never a silent fallback. Discovery
imports every module (not starting with ``_``) of the family's package, so **adding a model is
adding one file** that decorates its class with ``@REGISTRY.register``. A model defined
elsewhere (a user's module, a test) registers the same way.

Example (a friction law; the registry lives in ``probedyn.schemes.friction.base``)::

    from probedyn.schemes.friction.base import FRICTION_MODELS, FrictionModel

    @FRICTION_MODELS.register
    class Coulomb(FrictionModel):
        key = "coulomb"
        title = "Coulomb friction, regularised"
        source = "textbook"
        params = ParamSet([...])
        kernel = staticmethod(coulomb_kernel)   # a numba function, see FrictionModel
        ...

The registries of probedyn: ``probedyn.probes.PROBES``,
``probedyn.schemes.friction.base.FRICTION_MODELS``,
``probedyn.schemes.contact.base.CONTACT_MODELS`` (and the diagnose causes).
"""

from __future__ import annotations

import difflib
import importlib
import pkgutil
from typing import Any, Callable, ClassVar, Generic, Iterator, TypeVar

from probedyn.core.errors import ParameterError
from probedyn.core.params import ParamSet

T = TypeVar("T", bound=type)

__all__ = ["Model", "Registry", "RegistryError"]


class Model:
    """What every registered model declares; the base class of each family derives from it."""

    #: registry key (lower case)
    key: ClassVar[str] = ""
    #: one line saying what the model is
    title: ClassVar[str] = ""
    #: the equations / tables / references it implements
    source: ClassVar[str] = ""

    @property
    def name(self) -> str:
        """The registry key (read-only alias kept for callers written before the registry)."""
        return self.key

    @property
    def equations(self) -> str:
        """The source equations (alias of :attr:`source`)."""
        return self.source


class RegistryError(TypeError):
    """A model class that does not declare what its registry requires (a programming error,
    raised at import time)."""


class Registry(Generic[T]):
    """A named family of model classes.

    ``base``: the class every model derives from; ``required``: names of members a model must
    define itself (not inherit unchanged from ``base``); ``package``: dotted name of the package
    whose modules are imported on first lookup (one module per model); ``aliases``: alternative
    names accepted by :meth:`get`; ``check``: an extra validation hook ``check(cls)`` that raises
    :class:`RegistryError` for family-specific rules (it may also prepare the class, e.g. give a
    compiled kernel a stable identity); ``params_type``: the type (or tuple of types) the
    ``params`` declaration must have, ``None`` for a family without one (``needs_params=False``
    is the same as ``params_type=None``).
    """

    def __init__(self, kind: str, base: type, required: tuple[str, ...] = (), package: str | None = None,
                 aliases: dict[str, str] | None = None, check: Callable[[type], None] | None = None,
                 needs_params: bool = True, params_type: type | tuple[type, ...] | None = ParamSet) -> None:
        self.kind = kind
        self.base = base
        self.required = tuple(required)
        self.package = package
        self.aliases = {k.lower(): v.lower() for k, v in (aliases or {}).items()}
        self._check = check
        self._params_type = params_type if needs_params else None
        self._classes: dict[str, type] = {}
        self._discovered = package is None

    # -- registration ---------------------------------------------------------------------------
    def register(self, cls: T) -> T:
        """Validate ``cls`` and add it under ``cls.key`` (usable as a class decorator)."""
        where = f"{self.kind} model {getattr(cls, '__qualname__', cls)!r}"
        if not (isinstance(cls, type) and issubclass(cls, self.base)):
            raise RegistryError(f"{where}: must derive from {self.base.__name__}")
        key = getattr(cls, "key", None)
        if not (isinstance(key, str) and key and key == key.strip().lower()):
            raise RegistryError(f"{where}: needs a lower-case string 'key'")
        for attr in ("title", "source"):
            if not (isinstance(getattr(cls, attr, None), str) and getattr(cls, attr)):
                raise RegistryError(f"{where}: needs a non-empty '{attr}' (what it is, which equations)")
        if self._params_type is not None and not isinstance(getattr(cls, "params", None), self._params_type):
            what = getattr(self._params_type, "__name__", "the declared type")
            raise RegistryError(f"{where}: needs 'params', a {what} of its parameters with units")
        for name in self.required:
            own = getattr(cls, name, None)
            if own is None or own is getattr(self.base, name, object()):
                raise RegistryError(f"{where}: must define '{name}' (required of every {self.kind} model)")
        if self._check is not None:
            self._check(cls)
        old = self._classes.get(key)
        if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
            raise RegistryError(f"{where}: key {key!r} is already taken by {old.__module__}.{old.__qualname__}")
        if key in self.aliases:
            raise RegistryError(f"{where}: key {key!r} is an alias of {self.aliases[key]!r}")
        self._classes[key] = cls
        return cls

    def unregister(self, key: str) -> None:
        """Remove a model (used by tests that register a temporary one)."""
        self._classes.pop(key, None)

    # -- lookup -----------------------------------------------------------------------------------
    def discover(self) -> None:
        """Import every public module of the family's package (each registers its models)."""
        if self._discovered:
            return
        self._discovered = True  # set first: a model module may look the registry up while imported
        try:
            pkg = importlib.import_module(self.package)
            for info in pkgutil.iter_modules(pkg.__path__):
                if not info.name.startswith("_"):
                    importlib.import_module(f"{self.package}.{info.name}")
        except BaseException:
            self._discovered = False  # a broken model module is an error at every lookup, not once
            raise

    def names(self) -> list[str]:
        self.discover()
        return sorted(self._classes)

    def __contains__(self, name: object) -> bool:
        self.discover()
        return isinstance(name, str) and self._resolve(name) in self._classes

    def __len__(self) -> int:
        self.discover()
        return len(self._classes)

    def __iter__(self) -> Iterator[type]:
        self.discover()
        return iter([self._classes[k] for k in sorted(self._classes)])

    def _resolve(self, name: str) -> str:
        s = str(name).strip().lower()
        return self.aliases.get(s, s)

    def get(self, name: str) -> T:
        """The class registered as ``name`` (or an alias); unknown names raise a
        :class:`ParameterError` that lists the known ones and the closest match."""
        self.discover()
        key = self._resolve(name)
        if key not in self._classes:
            known = sorted(self._classes)
            close = difflib.get_close_matches(key, known + list(self.aliases), n=1)
            hint = f"; did you mean '{self._resolve(close[0])}'?" if close else ""
            raise ParameterError(f"unknown {self.kind} model {name!r} (known: {', '.join(known)}){hint}")
        return self._classes[key]

    def create(self, name: str, *args: Any, **kwargs: Any) -> Any:
        """An instance of the model ``name``."""
        return self.get(name)(*args, **kwargs)

    def table(self) -> list[dict[str, Any]]:
        """One row per model: key, title, source (for ``--list`` commands and docs)."""
        return [{"key": c.key, "title": c.title, "source": c.source} for c in self]
