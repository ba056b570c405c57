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
:mod:`probedyn.schemes.ffm` (which receives the kernel as an argument: no dispatch on the model)
and by any other scheme, so there is a single source of truth for each formula.

**Adding a model** is one module in this package (or anywhere, e.g. a test)::

    @njit(cache=True)
    def my_kernel(p, x, v, z): ...               # the 8-tuple above

    @FRICTION_MODELS.register
    class MyModel(FrictionModel):
        key = "mine"; title = "..."; source = "eq ..."
        params = ParamSet([...]); packed = ("F_0", ...); n_state = 0
        kernel = staticmethod(my_kernel)
        def scales(self): return (self["F_0"], 1.0)

Registration checks the declaration (:data:`FRICTION_MODELS`, a
:class:`probedyn.core.registry.Registry`): ``key``, ``title``, ``source``, ``params``, a numba
``kernel`` of the model's own, ``scales`` and the packed names being parameters. ``probedyn
simulate ffm --model mine`` then runs it.

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
from probedyn.core.presets import preset
from probedyn.core.registry import Model, Registry, RegistryError
from probedyn.schemes.rosenbrock import stable_identity

#: Table 2.1 (mica FFM experiment): default friction levels of the bristle-type models
TABLE_2_1 = preset("table-2.1")


class FrictionModel(Model):
    """Base class: a parameter set, validation, a numba kernel and numpy wrappers."""

    #: declared parameters (SI units)
    params: ClassVar[ParamSet]
    #: names of the parameters packed (in order) into the kernel's parameter vector
    packed: ClassVar[tuple[str, ...]] = ()
    #: parameters that scale with the normal load (force levels)
    load_params: ClassVar[tuple[str, ...]] = ()
    #: number of internal state variables (0 or 1)
    n_state: ClassVar[int] = 1
    #: reference normal load of the default force levels [N] (mica FFM experiment, 2.1.5.1)
    reference_load: ClassVar[float] = TABLE_2_1["normal_load"]

    def __init__(self, **overrides: Any) -> None:
        self.values: dict[str, Any] = self.params.resolve(overrides)
        self.validate()

    # -- parameters -------------------------------------------------------------------------
    def validate(self) -> None:
        """Raise :class:`ParameterError` for non-physical combinations (subclasses extend)."""

    def __getitem__(self, name: str) -> Any:
        return self.values[name]

    def scales(self) -> tuple[float, float]:
        """``(force scale [N], internal-state scale)``: the natural size of the friction force
        and of ``z`` (absolute tolerances of the integrators are fractions of them)."""
        raise NotImplementedError

    def levels(self) -> tuple[float, float] | None:
        """``(F_s, F_c)``, static and kinetic friction levels [N] of models that have them (the
        quasi-static estimates ``F_s / k`` of the first slip and ``(F_s - F_c) / k`` of the
        sawtooth period use them); ``None`` for a model without such levels."""
        return None

    def presliding_stiffness(self) -> float | None:
        """Contact (bristle) stiffness of the stick phase [N/m], if the model has one."""
        return None

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
        return dict(name=self.key, title=self.title, equations=self.source,
                    n_state=self.n_state, values=dict(self.values), params=self.params.table())

    # -- evaluation ---------------------------------------------------------------------------
    @staticmethod
    def kernel(p, x, v, z):  # pragma: no cover - every registered model brings its own (numba)
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


class BristleModel(FrictionModel):
    """A bristle-type model (LuGre 2.3-2.5, the generalised bristle 2.7-2.9): static and kinetic
    levels ``F_s``, ``F_c`` and the bristle stiffness ``sigma0`` among its parameters."""

    def scales(self) -> tuple[float, float]:
        """Static friction and the bristle deflection at it, ``F_s / sigma0``."""
        return self.values["F_s"], self.values["F_s"] / self.values["sigma0"]

    def levels(self) -> tuple[float, float]:
        return self.values["F_s"], self.values["F_c"]

    def presliding_stiffness(self) -> float:
        return self.values["sigma0"]


def positive_param(name: str, default: float, unit: str, doc: str, source: str,
                   lo: float | None = None, hi: float | None = None) -> Param:
    """A strictly positive parameter (negative stiffness, mass, friction are rejected)."""
    return Param(name, default, unit, doc, lo=lo, hi=hi, positive=True, source=source)


def _stable_identity(kernel: Any, owner: str) -> None:
    """Give a numba kernel a process-independent identity (:func:`probedyn.schemes.rosenbrock.stable_identity`).

    The FFM integrator receives the kernel as an argument, so numba compiles one specialisation
    per kernel; the on-disk cache finds it again in a new process only if the kernel's
    serialised identity is the same there."""
    stable_identity(kernel, f"friction:{owner}")


def _check_friction(cls: type) -> None:
    """Family rules of :data:`FRICTION_MODELS` (see :class:`probedyn.core.registry.Registry`)."""
    where = f"friction model {cls.__qualname__!r}"
    kern = getattr(cls, "kernel", None)
    if not hasattr(kern, "py_func"):
        raise RegistryError(f"{where}: 'kernel' must be a numba-compiled function (@njit)")
    missing = [n for n in cls.packed if n not in cls.params]
    if missing or not cls.packed:
        raise RegistryError(f"{where}: 'packed' must name its kernel's parameters "
                            f"(not parameters: {', '.join(missing) or 'none given'})")
    bad = [n for n in cls.load_params if n not in cls.params]
    if bad:
        raise RegistryError(f"{where}: load_params {bad} are not parameters")
    if cls.n_state not in (0, 1):
        raise RegistryError(f"{where}: n_state must be 0 or 1, got {cls.n_state!r}")
    _stable_identity(kern, f"{cls.__module__}.{cls.__qualname__}")


#: The friction models: one module per model in this package (discovered on first lookup).
FRICTION_MODELS: Registry[type[FrictionModel]] = Registry(
    "friction", FrictionModel, required=("kernel", "scales"), package="probedyn.schemes.friction",
    aliases={"generalised-bristle": "bristle", "generalized-bristle": "bristle", "source": "bristle",
             "prandtl-tomlinson": "pt", "tomlinson": "pt"},
    check=_check_friction)
