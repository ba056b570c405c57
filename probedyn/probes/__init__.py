"""Registry of probes: each ties a parametric geometry (meshes/) to materials, point masses and
springs (fem/) and to its analytic references and reductions (lumped/).

A probe is a subclass of :class:`Probe` registered in :data:`PROBES` (a
:class:`probedyn.core.registry.Registry`; ``@register_probe`` is its ``register``): it declares
``key``, ``title``, ``source`` and ``params`` (a :class:`~probedyn.core.params.ParamSet` of
geometry, material and mesh parameters in SI units) and implements :meth:`Probe.build` and
:meth:`Probe.tip_point`. Every public module of this package is imported on the first lookup,
so a new probe is one module here that decorates its class. A probe can also be given as a
TOML file::

    probe = "cantilever"
    length = 450e-6
    tip_mass = 1e-11

:func:`get_probe` returns the probe and the TOML keys (other than ``probe``) as overrides.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from probedyn.core.errors import DataFormatError
from probedyn.core.params import ParamSet, load_toml
from probedyn.core.registry import Model, Registry


class Probe(Model):
    """Base class.  Subclasses set ``key``, ``title``, ``source`` and ``params`` and implement
    :meth:`build` and :meth:`tip_point` (and usually :meth:`references`)."""

    #: geometry, material and mesh parameters (SI); every probe declares its own
    params: ClassVar[ParamSet]

    @property
    def description(self) -> str:
        """One line saying what the probe is (alias of :attr:`title`)."""
        return self.title

    def resolve(self, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
        """Defaults + validated overrides; subclasses add cross-parameter checks."""
        return self.params.resolve(overrides)

    def build(self, values: dict[str, Any]):
        """The :class:`~probedyn.fem.model.ElasticModel` for resolved ``values``."""
        raise NotImplementedError

    def references(self, values: dict[str, Any], result) -> list[dict[str, Any]]:
        """Analytic comparison rows for a :class:`~probedyn.fem.modes.ModalResult`:
        ``{"mode", "family", "formula", "fem_hz", "value_hz", "rel_diff"}``."""
        return []

    def tip_point(self, values: dict[str, Any]) -> np.ndarray:
        """Coordinates [m] of the probe tip (where effective masses are evaluated)."""
        raise NotImplementedError

    def static_stiffness(self, values: dict[str, Any], model) -> dict[str, Any]:
        """FEM static stiffness of the probe's loaded end beside its analytic references, as
        ``{name: N/m}``; a probe that declares no such reference returns ``{}``."""
        return {}

    def mass_per_length(self, values: dict[str, Any], model) -> float:
        """Mass per length [kg/m] of the body for the damping per length ``mu`` of eq 3.2: the
        FE model's mass without the rigid tip mass, over ``values["length"]``."""
        L = values.get("length")
        if not L:
            raise ParameterError(f"--mu needs a beam length; probe '{self.name}' has none, use --q")
        return (model.total_mass() - (values.get("tip_mass") or 0.0)) / L

    def modes(self, overrides: dict[str, Any] | None = None, n_modes: int = 8):
        """Convenience: resolve, build and solve."""
        values = self.resolve(overrides)
        return self.build(values).modes(n_modes)


#: The probes: one module per probe in this package (discovered on first lookup).
PROBES: Registry[type[Probe]] = Registry("probe", Probe, required=("build", "tip_point"), package="probedyn.probes")

#: class decorator adding a probe to :data:`PROBES`
register_probe = PROBES.register


def list_probes() -> list[str]:
    """Keys of the registered probes."""
    return PROBES.names()


def get_probe(name_or_path: str | Path) -> tuple[Probe, dict[str, Any]]:
    """A probe by registry key, or from a TOML file (``probe = "<key>"`` plus parameter
    keys).  Returns ``(probe, overrides)``; unknown names and malformed files raise."""
    s = str(name_or_path)
    overrides: dict[str, Any] = {}
    if s.endswith(".toml") or (Path(s).suffix and Path(s).exists()):
        data = load_toml(s)
        if "probe" not in data:
            raise DataFormatError(f"{s}: missing key 'probe' (e.g. probe = \"cantilever\")")
        name = str(data.pop("probe"))
        for k, v in data.items():
            if isinstance(v, dict):
                raise DataFormatError(f"{s}: tables are not supported, put '{k}' keys at top level")
            overrides[k] = v
    else:
        name = s
    probe = PROBES.create(name)
    if overrides:
        probe.params.resolve(overrides)  # validate now: names the bad key
    return probe, overrides
