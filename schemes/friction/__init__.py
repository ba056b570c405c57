"""Friction model registry (one module per model).

>>> from probedyn.schemes.friction import get_friction_model, list_models
>>> m = get_friction_model("lugre")(F_s=1e-9, F_c=0.5e-9)

Each model is a :class:`~probedyn.schemes.friction.base.FrictionModel`: friction force,
internal-state rates and their analytic Jacobians, usable as a component by FFM
(:mod:`probedyn.schemes.ffm`) and nano-pushing.
"""

from __future__ import annotations

from probedyn.errors import ParameterError

from .base import FrictionModel
from .bristle import Bristle
from .lugre import LuGre
from .prandtl_tomlinson import PrandtlTomlinson

_REGISTRY: dict[str, type[FrictionModel]] = {}


def register(cls: type[FrictionModel]) -> type[FrictionModel]:
    """Register a model class under ``cls.name`` (usable as a decorator)."""
    _REGISTRY[cls.name] = cls
    return cls


def get_friction_model(name: str) -> type[FrictionModel]:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ParameterError(f"unknown friction model '{name}' (known: {', '.join(sorted(_REGISTRY))})") from None


def list_models() -> list[str]:
    return sorted(_REGISTRY)


for _c in (LuGre, Bristle, PrandtlTomlinson):
    register(_c)

__all__ = ["FrictionModel", "LuGre", "Bristle", "PrandtlTomlinson", "register", "get_friction_model", "list_models"]
