"""What the two smart probes (duo-bimorph, piezotube) share: a PZT body, a tip holder that is
either meshed (a block or collar with its stiffness-tuning piezolayer) or a point mass, and the
cantilever tip as a lumped mass on the holder springs (eqs 3.4, 3.20), modelled by
:class:`probedyn.fem.augmented.AugmentedModel`.

A smart probe also declares what the lumped model of eq 3.37 (:mod:`probedyn.lumped.smart`)
needs from it, so the reduction never asks which probe it has: the modelled directions, how
FEM modes are grouped by direction (a degenerate pair is one group), the regions of the body
(the distributed drag of eq 3.2 acts there), the holder springs the localisation study sweeps,
and ``rho A`` of the body.
"""

from __future__ import annotations

from typing import Any, ClassVar

from probedyn.fem.augmented import AugmentedModel, LumpedTip
from probedyn.fem.materials import get_material
from probedyn.fem.model import PointMass
from probedyn.meshes._gmsh import region_volumes
from probedyn.probes import Probe

#: meshed holder regions (block or collar + piezolayer)
HOLDER_REGIONS = ("holder", "holder_piezolayer")


class SmartProbe(Probe):
    """Base of the smart probes (module docstring). Subclasses set the class attributes below
    and implement ``mesh``, ``body_regions_of`` (the PZT body's regions and materials),
    ``holder_geometric_mass`` and ``body_rho_A``."""

    #: directions of the lumped model (order of its matrices), eq 3.4 / 3.20
    lumped_directions: ClassVar[tuple[str, ...]] = ()
    #: FEM modes compared per group of directions (a degenerate pair forms one group)
    direction_groups: ClassVar[dict[str, tuple[str, ...]]] = {}
    #: regions of the PZT body (the drag of eq 3.2 acts on them)
    body_regions: ClassVar[tuple[str, ...]] = ()
    #: holder-spring directions set to k in the localisation study (section 3.4.1)
    sweep_directions: ClassVar[tuple[str, ...]] = ()
    #: attachment carrying the point-mass holder (end face of the body)
    body_end: ClassVar[str] = ""
    #: attachment of the tip's holder springs (holder end face)
    holder_end: ClassVar[str] = "holder_end"

    def pzt(self, values: dict[str, Any]):
        """The PZT of the body, with the table's density."""
        return get_material(values["material"]).with_overrides(rho=values["density"])

    def s11(self, values: dict[str, Any]) -> float:
        """Compliance along the probe axis x [1/Pa] of the PZT (a local 1-2 plane direction)."""
        return float(self.pzt(values).S[0, 0])

    def holder_mass(self, values: dict[str, Any]) -> float:
        """The holder mass that drives the model [kg] (table m_h or geometry)."""
        return values["holder_mass"] if values["holder_mass_source"] == "table" else self.holder_geometric_mass(values)

    def holder_geometric_mass(self, values: dict[str, Any]) -> float:
        raise NotImplementedError

    def body_rho_A(self, values: dict[str, Any]) -> float:
        """Mass per length of the PZT body [kg/m] (the damping c = mu int phi^2 of eq 3.2)."""
        raise NotImplementedError

    def _smart_model(self, values: dict[str, Any], bundle, body: dict[str, Any], orient=None,
                     extra: dict[str, Any] | None = None, tip: str = "holder_end") -> AugmentedModel:
        """The FE model: ``body`` regions, the holder (meshed: its density scaled so that block +
        piezolayer weigh m_h for the ``table`` source; point: m_h on :attr:`body_end`), ``extra``
        regions and, for ``tip = "lumped"``, the tip mass on the holder springs. ``orient``: the
        piezolayer's poling orientation (None = the material's axes)."""
        v = values
        pzt = self.pzt(v)

        def piezo(mat):
            return mat if orient is None else (mat, orient)

        regions: dict[str, Any] = dict(body)
        pms = []
        if v["holder"] == "meshed":
            hmat = get_material(v["holder_material"])
            if v["holder_mass_source"] == "table":
                vols = region_volumes(bundle.mesh, HOLDER_REGIONS)
                rho_h = v["holder_mass"] / sum(vols.values())
                regions["holder"] = hmat.with_overrides(rho=rho_h)
                regions["holder_piezolayer"] = piezo(pzt.with_overrides(rho=rho_h))
            else:
                regions["holder"] = hmat
                regions["holder_piezolayer"] = piezo(pzt)
        else:
            m_h = self.holder_mass(v)
            if m_h > 0:
                pms.append(PointMass(self.body_end, m_h))
        regions.update(extra or {})
        lumped = None
        if v["tip"] == "lumped":
            lumped = LumpedTip(v["tip_mass"], (v["k_tx"], v["k_ty"], v["k_tz"]), self.holder_end)
        return AugmentedModel(bundle, regions, clamp=["clamp"], point_masses=pms, tip=tip, beam_axis=0,
                              name=self.key, lumped_tip=lumped)
