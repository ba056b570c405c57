"""Common interface of the friction models of the registry (section 2.1 of the source).

A friction model is a *component*: given the tip position relative to the sample ``x`` [m], the
sliding velocity ``v`` [m/s] (tip relative to sample) and its internal state variables ``z``
(bristle deflection, ...), it returns

* the friction force ``F`` [N] acting *against* the tip (the FFM equation (2.13) reads
  ``m x'' + c x' + k x = D - F``),
* the rates ``dz/dt`` of its internal state variables,
* the analytic partial derivatives of both with respect to ``x``, ``v`` and ``z`` (for implicit
  integrators).

One-dimensional models carry at most one internal state (``n_state`` is 0 or 1), so the
whole component is described by one scalar kernel

    ``kernel(p, x, v, z) -> (F, zdot, dF_dx, dF_dv, dF_dz, dzd_dx, dzd_dv, dzd_dz)``

compiled with numba (``p`` is the float64 parameter vector of :meth:`FrictionModel.pack`). The
same compiled kernel is used by the numpy-facing methods below, by the fast FFM integrator of
:mod:`probedyn.schemes.ffm` and by any other scheme (pushing, coupling), so there is a single
source of truth for each formula.

**Normal-load input.** Single-asperity friction levels scale with the normal load (or the
contact area); :meth:`FrictionModel.scaled` returns a copy whose force levels (every parameter
with ``scales=True`` in :attr:`FrictionModel.load_params`) are multiplied by a factor, and
:meth:`FrictionModel.at_load` does it with ``factor = L / L_ref``.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.core.params import Param, ParamSet


class FrictionModel:
    """Base class: a parameter set, validation, a numba kernel and numpy wrappers."""

    #: registry name
    name: ClassVar[str] = ""
    #: one-line description and the source equations implemented
    title: ClassVar[str] = ""
    equations: ClassVar[str] = ""
    #: declared parameters (SI units)
    params: ClassVar[ParamSet]
    #: names of the parameters packed (in order) into the kernel's parameter vector
    packed: ClassVar[tuple[str, ...]] = ()
    #: parameters that scale with the normal load (force levels)
    load_params: ClassVar[tuple[str, ...]] = ()
    #: number of internal state variables (0 or 1)
    n_state: ClassVar[int] = 1
    #: integer tag used by the fast FFM integrator to dispatch to the kernel
    kind: ClassVar[int] = -1
    #: reference normal load of the default force levels [N] (mica FFM experiment, 2.1.5.1)
    reference_load: ClassVar[float] = 141.75e-9

    def __init__(self, **overrides: Any) -> None:
        self.values: dict[str, Any] = self.params.resolve(overrides)
        self.validate()

    # -- parameters -------------------------------------------------------------------------
    def validate(self) -> None:
        """Raise :class:`ParameterError` for non-physical combinations (subclasses extend)."""

    def __getitem__(self, name: str) -> Any:
        return self.values[name]

    def pack(self) -> np.ndarray:
        """The kernel's float64 parameter vector."""
        return np.array([float(self.values[n]) for n in self.packed], dtype=np.float64)

    def scaled(self, factor: float) -> "FrictionModel":
        """A copy with the force levels (``load_params``) multiplied by ``factor`` > 0."""
        if not (isinstance(factor, (int, float)) and math.isfinite(factor) and factor > 0):
            raise ParameterError(f"friction scale factor must be positive and finite, got {factor!r}")
        new = dict(self.values)
        for n in self.load_params:
            new[n] = self.values[n] * factor
        return type(self)(**new)

    def at_load(self, normal_load: float, reference_load: float | None = None) -> "FrictionModel":
        """Force levels proportional to the normal load (Amontons at the single-asperity level):
        ``factor = normal_load / reference_load`` (default reference: 141.75 nN, section 2.1.5.1)."""
        ref = self.reference_load if reference_load is None else reference_load
        if not (normal_load > 0 and ref > 0):
            raise ParameterError(f"normal load must be positive (compressive), got {normal_load!r} N")
        return self.scaled(normal_load / ref)

    def describe(self) -> dict[str, Any]:
        return dict(name=self.name, title=self.title, equations=self.equations,
                    n_state=self.n_state, values=dict(self.values), params=self.params.table())

    # -- evaluation ---------------------------------------------------------------------------
    @staticmethod
    def kernel(p, x, v, z):  # pragma: no cover - replaced by a numba function in subclasses
        raise NotImplementedError

    def evaluate(self, x, v, z) -> dict[str, np.ndarray]:
        """Vectorised evaluation of the kernel: force, rate and the six partial derivatives."""
        x, v, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(v, float), np.asarray(z, float))
        p = self.pack()
        flat = np.empty((8, x.size))
        for i, (xi, vi, zi) in enumerate(zip(x.reshape(-1), v.reshape(-1), z.reshape(-1))):
            flat[:, i] = self.kernel(p, float(xi), float(vi), float(zi))
        out = flat.reshape((8,) + x.shape)
        keys = ("F", "zdot", "dF_dx", "dF_dv", "dF_dz", "dzd_dx", "dzd_dv", "dzd_dz")
        return dict(zip(keys, out))

    def force(self, x, v, z):
        """Friction force [N] (against the tip's motion)."""
        return self.evaluate(x, v, z)["F"]

    def rate(self, x, v, z):
        """Rate of the internal state variable ``dz/dt``."""
        return self.evaluate(x, v, z)["zdot"]

    def steady_force(self, v) -> np.ndarray:
        """Steady-state friction force at constant sliding velocity ``v`` (``dz/dt = 0``);
        subclasses with a closed form override this."""
        raise NotImplementedError


def positive_param(name: str, default: float, unit: str, doc: str, source: str,
                   lo: float | None = None, hi: float | None = None) -> Param:
    """A strictly positive parameter (negative stiffness, mass, friction are rejected)."""
    return Param(name, default, unit, doc, lo=lo, hi=hi, positive=True, source=source)
