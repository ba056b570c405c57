"""Common interface of friction models (components usable by FFM and nano-pushing).

A friction model gives the friction force ``F`` (2-vector, acting on the tip *against* its
motion over the sample) from the tip position ``X`` (2,), sliding velocity ``V`` (2,), its
internal state ``Z`` (``n_state``,) and a normal-load factor ``load`` (friction levels are
multiplied by ``load``; ``load = F_n / F_n,ref``, Amontons scaling, see :mod:`probedyn.schemes.ffm`).
``rates`` gives dZ/dt and ``jacobian`` the analytic partial derivatives used by implicit
integrators.  1D models (``dim = 1``) only use the x components.
"""

from __future__ import annotations

from typing import Any, ClassVar, Mapping

import numpy as np

from probedyn.errors import ParameterError
from probedyn.params import ParamSet


class FrictionModel:
    """Base class: subclasses set ``name``, ``params``, ``n_state``, ``dim``, ``equations``."""

    name: ClassVar[str] = ""
    equations: ClassVar[str] = ""
    params: ClassVar[ParamSet] = ParamSet([])
    n_state: ClassVar[int] = 0
    dim: ClassVar[int] = 1

    def __init__(self, overrides: Mapping[str, Any] | None = None, **kw: Any) -> None:
        ov = dict(overrides or {})
        ov.update(kw)
        self.p = self.params.resolve(ov)
        self.validate()

    # -- to be provided by subclasses -------------------------------------------------------
    def validate(self) -> None:
        """Cross-parameter checks (single-parameter ranges are checked by the Params)."""

    def force(self, X, V, Z, load: float = 1.0) -> np.ndarray:
        raise NotImplementedError

    def rates(self, X, V, Z, load: float = 1.0) -> np.ndarray:
        return np.zeros(self.n_state)

    def jacobian(self, X, V, Z, load: float = 1.0):
        """Return (dF/dX, dF/dV, dF/dZ, dZd/dX, dZd/dV, dZd/dZ) with shapes
        (2,2), (2,2), (2,n), (n,2), (n,2), (n,n)."""
        raise NotImplementedError

    def initial_state(self) -> np.ndarray:
        return np.zeros(self.n_state)

    def steady_force(self, v: float, load: float = 1.0) -> float:
        """Friction force of steady sliding at constant velocity ``v`` along x."""
        raise NotImplementedError

    def length_scales(self) -> np.ndarray:
        """Characteristic magnitudes of the internal states (for error tolerances)."""
        return np.ones(self.n_state)

    def force_scale(self) -> float:
        """A characteristic friction force [N] (for tolerances and plots)."""
        return 1e-9

    def damping(self) -> float:
        """Viscous coefficient of the model against the substrate [N s/m] (thermal noise)."""
        return 0.0

    def describe(self) -> dict:
        return {"name": self.name, "equations": self.equations, "params": dict(self.p)}


def require(cond: bool, msg: str) -> None:
    if not cond:
        raise ParameterError(msg)
