"""Friction model registry (section 2.1 of the source); one module per model.

``get_friction_model(name, **params)`` returns an instance, ``list_models()`` the names,
``register(cls)`` adds a model class. Every model is a component with the interface of
:class:`.base.FrictionModel`: friction force given position, sliding velocity and internal
state, rates of the internal state, analytic partial derivatives (one compiled kernel).

===========  ====================================================  ===============================
name         model                                                 source
===========  ====================================================  ===============================
``lugre``    LuGre bristle model with Stribeck effect               (2.3)–(2.5)
``bristle``  generalised-bristle nano-friction model (1D, V_y = 0)  (2.7)–(2.9); 2D in ffm (2.10–2.12)
``pt``       Prandtl–Tomlinson sinusoidal potential (1D)            standard model; 2D in pt2d_scan
===========  ====================================================  ===============================
"""

from __future__ import annotations

from probedyn.core.errors import ParameterError

from .base import FrictionModel
from .bristle import GeneralisedBristle
from .lugre import LuGre
from .prandtl_tomlinson import PrandtlTomlinson

_REGISTRY: dict[str, type[FrictionModel]] = {}
_ALIASES = {"generalised-bristle": "bristle", "generalized-bristle": "bristle", "source": "bristle",
            "prandtl-tomlinson": "pt", "tomlinson": "pt"}


def register(cls: type[FrictionModel]) -> type[FrictionModel]:
    """Add a friction model class to the registry (usable as a decorator)."""
    if not (isinstance(cls, type) and issubclass(cls, FrictionModel) and cls.name):
        raise TypeError("register() expects a FrictionModel subclass with a name")
    _REGISTRY[cls.name] = cls
    return cls


for _cls in (GeneralisedBristle, LuGre, PrandtlTomlinson):
    register(_cls)


def list_models() -> list[str]:
    """Names of the registered friction models."""
    return list(_REGISTRY)


def get_friction_model(name: str, **params) -> FrictionModel:
    """An instance of friction model ``name`` with parameter overrides (SI units)."""
    key = _ALIASES.get(str(name).lower(), str(name).lower())
    if key not in _REGISTRY:
        raise ParameterError(f"unknown friction model {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[key](**params)


def model_class(name: str) -> type[FrictionModel]:
    key = _ALIASES.get(str(name).lower(), str(name).lower())
    if key not in _REGISTRY:
        raise ParameterError(f"unknown friction model {name!r} (known: {', '.join(_REGISTRY)})")
    return _REGISTRY[key]


__all__ = ["FrictionModel", "GeneralisedBristle", "LuGre", "PrandtlTomlinson", "get_friction_model",
           "list_models", "model_class", "register"]
