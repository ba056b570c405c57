"""Friction models (section 2.1 of the source): one module per model, one registry.

Every model is a class registered in :data:`~.base.FRICTION_MODELS` (a
:class:`probedyn.core.registry.Registry`): it declares ``key``, ``title``, ``source``,
``params`` (SI units) and brings its own numba ``kernel`` (friction force, rate of the internal
state and their analytic partial derivatives; see :mod:`.base`). The modules of this package are
imported on the first lookup, so **a new model is one new file** here (or a module that imports
:data:`~.base.FRICTION_MODELS` and registers its class anywhere else, e.g. in a test).

===========  ====================================================  ===============================
key          model                                                 source
===========  ====================================================  ===============================
``lugre``    LuGre bristle model with Stribeck effect               (2.3)–(2.5)
``bristle``  generalised-bristle nano-friction model (1D, V_y = 0)  (2.7)–(2.9); 2D in ffm (2.10–2.12)
``pt``       Prandtl–Tomlinson sinusoidal potential (1D)            standard model; 2D in pt2d_scan
===========  ====================================================  ===============================

``get_friction_model(name, **params)``, ``model_class(name)`` and ``list_models()`` are the
registry's ``create``, ``get`` and ``names``.
"""

from __future__ import annotations

from .base import FRICTION_MODELS, FrictionModel

#: register a model class (a decorator; the same as ``FRICTION_MODELS.register``)
register = FRICTION_MODELS.register


def list_models() -> list[str]:
    """Keys of the registered friction models."""
    return FRICTION_MODELS.names()


def model_class(name: str) -> type[FrictionModel]:
    """The class of friction model ``name`` (key or alias); unknown names raise ParameterError."""
    return FRICTION_MODELS.get(name)


def get_friction_model(name: str, **params) -> FrictionModel:
    """An instance of friction model ``name`` with parameter overrides (SI units)."""
    return FRICTION_MODELS.create(name, **params)


__all__ = ["FRICTION_MODELS", "FrictionModel", "get_friction_model", "list_models", "model_class", "register"]
