"""The duo-bimorph smart probe (source section 3.2, Fig 3.4, Table 3.1).

Two PZT-5H layers poled through the thickness (local 3-axis = z, so the orientation is the
identity; the opposite polarities of the two layers do not change the elastic tensor of a
6mm material), clamped at x = 0, with the tip holder at the free end and the cantilever tip
(header) of mass ``m`` on the holder spring ``k_t`` (eq 3.4; Table 3.1: k_y2 = 0.1 N/m,
k_z2 = 10 N/m).

User choices (departure 5):

* ``holder = "meshed"`` (a silicon block L_h x holder_width x holder_thickness with its PZT
  stiffness-tuning piezolayer on top) or ``"point"`` (a rigid mass on the face-averaged
  displacement of the body end face, no rotary inertia, as in the beam equation 3.8);
* ``holder_mass_source = "table"``: the holder carries Table 3.1's ``m_h`` (the
  meshed holder's density is scaled so that holder + piezolayer weigh m_h), or ``"geometry"``:
  the holder weighs what its volume and materials give (1.2e-10 kg for the default block,
  ~1700 times less than the table value);
* ``tip = "lumped"`` (mass ``tip_mass`` on the springs k_tx, k_ty, k_tz attached to the holder
  end face), ``"meshed"`` (a silicon cone under the holder end; its stiffness is the holder's)
  or ``"none"``.

Density: Table 3.1's rho = 7800 kg/m^3 overrides the material's. Compliance: the FEM uses the
full PZT-5H s^E (s11 = 16.5e-12 1/Pa); Table 3.1 prints s11 = 20.7e-12 1/Pa, which is PZT-5H's
s33 (see docs/smart-probes.md); analytic references use the s11 of the FEM material so that
FEM and formula describe the same solid. ``material = "pzt-5h-iso"`` is the isotropic
E = 1/s11 option.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.fem.materials import get_material
from probedyn.lumped.smart import duo_bimorph_references
from probedyn.lumped.smart_analytic import DuoBimorphBeam
from probedyn.meshes._gmsh import region_volumes
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.duo_bimorph import DEFAULTS as GEOM
from probedyn.meshes.duo_bimorph import duo_bimorph_mesh, named_points, validate
from probedyn.meshes.hexmeshes import HexDivisions, duo_bimorph_hex_mesh, element_params, refinement_for
from probedyn.probes import register_probe
from probedyn.probes._smart import SmartProbe

PZT_CHOICES = ("pzt-5h", "pzt-5h-iso")

T31 = preset("table-3.1")

_PARAMS = ParamSet([
    Param("length", GEOM["length"], "m", "duo-bimorph length L (x)", lo=10e-6, hi=0.02, positive=True, source="Table 3.1"),
    Param("width", GEOM["width"], "m", "duo-bimorph width w (y)", lo=1e-6, hi=0.005, positive=True, source="Table 3.1"),
    Param("thickness", GEOM["thickness"], "m", "total thickness h of the two PZT layers (z)", lo=0.2e-6, hi=0.002,
          positive=True, source="Table 3.1"),
    Param("electrode_gap", GEOM["electrode_gap"], "m", "electrode separation w0 (splits each face into left/right)", lo=1e-8,
          hi=0.005, positive=True, source="Table 3.1, eq 3.5"),
    Param("holder", "meshed", "", "tip holder: meshed block + piezolayer, or a point mass m_h on the end face",
          kind=str, choices=("meshed", "point")),
    Param("holder_length", GEOM["holder_length"], "m", "holder length L_h", lo=1e-7, hi=0.005, positive=True,
          source="Table 3.1"),
    Param("holder_width", GEOM["holder_width"], "m", "holder width (meshed holder)", lo=1e-7, hi=0.005, positive=True),
    Param("holder_thickness", GEOM["holder_thickness"], "m", "holder block thickness (meshed holder)", lo=1e-8, hi=0.002, positive=True),
    Param("piezolayer_thickness", GEOM["piezolayer_thickness"], "m", "stiffness-tuning piezolayer on the holder", lo=1e-8, hi=0.002,
          positive=True, source="3.2.1"),
    Param("holder_material", "silicon", "", "material of the holder block", kind=str,
          choices=("silicon", "silicon-110", "silicon-nitride", "pzt-5h", "pzt-5h-iso")),
    Param("holder_mass_source", "table", "", "which mass drives the holder: Table 3.1 m_h or its geometry",
          kind=str, choices=("table", "geometry"), source="departure 5"),
    Param("holder_mass", T31["m_h"], "kg", "holder mass m_h (used when holder_mass_source = table)", lo=0.0,
          hi=1e-2, source="Table 3.1"),
    Param("tip", "lumped", "", "cantilever tip: mass m on the holder spring k_t, a meshed cone, or none",
          kind=str, choices=("lumped", "meshed", "none")),
    Param("tip_mass", T31["m"], "kg", "tip (header) mass m", lo=1e-18, hi=1e-2, positive=True, source="Table 3.1"),
    Param("k_tx", 100.0, "N/m", "holder spring along x (not in the source; an AFM cantilever is stiff axially)",
          lo=1e-4, hi=1e7, positive=True),
    Param("k_ty", T31["k_y2"], "N/m", "holder spring along y, k_y2", lo=1e-4, hi=1e7, positive=True,
          source="Table 3.1"),
    Param("k_tz", T31["k_z2"], "N/m", "holder spring along z, k_z2", lo=1e-4, hi=1e7, positive=True,
          source="Table 3.1"),
    Param("tip_height", GEOM["tip_height"], "m", "meshed tip cone height", lo=1e-8, hi=0.002, positive=True),
    Param("tip_radius", GEOM["tip_radius"], "m", "meshed tip cone base radius", lo=1e-8, hi=0.002, positive=True),
    Param("material", "pzt-5h", "", "PZT of the layers: transversely isotropic, or isotropic E = 1/s11",
          kind=str, choices=PZT_CHOICES),
    Param("density", T31["rho"], "kg/m^3", "density of the PZT (overrides the material's)", lo=1000.0,
          hi=20000.0, positive=True, source="Table 3.1"),
    Param("mu", 0.0, "N s/m^2", "environment damping factor mu of eq 3.2 (lumped models)", lo=0.0, hi=1e3,
          source="3.2"),
    Param("elements_through_thickness", 1, "", "elements through one PZT layer", lo=1, hi=20, kind=int),
    *element_params("maximum element size (hexahedra: along the probe away from the clamp); "
                    "None = layer thickness / elements_through_thickness (hexahedra: the total thickness, graded towards the clamp)",
                    1e-8, 0.001),
])

GEOM_KEYS = ("length", "width", "thickness", "electrode_gap", "holder", "holder_length", "holder_width",
             "holder_thickness", "piezolayer_thickness", "tip_height", "tip_radius")


@register_probe
class DuoBimorph(SmartProbe):
    """The duo-bimorph probe (module docstring)."""

    key = "duo-bimorph"
    title = "duo-bimorph smart probe (source 3.2): two PZT layers, tip holder + piezolayer, tip on holder spring"
    source = "section 3.2, Fig 3.4, eqs 3.1-3.18, Table 3.1"
    params = _PARAMS
    lumped_directions = ("y", "z")
    direction_groups = {"y": ("y",), "z": ("z",)}
    body_regions = ("upper_layer", "lower_layer")
    sweep_directions = ("y", "z")
    body_end = "holder_end"

    def resolve(self, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
        v = self.params.resolve(overrides)
        validate(self._geom(v))
        if v["length"] < 2 * v["width"] or v["length"] < 5 * v["thickness"]:
            raise GeometryError(
                f"duo-bimorph length {v['length']:g} m must exceed twice its width and five times its thickness (a beam)")
        return v

    @staticmethod
    def _geom(v: dict[str, Any]) -> dict[str, Any]:
        g = {k: v[k] for k in GEOM_KEYS}
        g["tip"] = "meshed" if v["tip"] == "meshed" else "none"
        return g

    def element(self, values: dict[str, Any]) -> str:
        """Hexahedra (``auto``: hex-s2) unless the tip cone is meshed (tetrahedra)."""
        el = values.get("element", "auto")
        if values["tip"] == "meshed":
            if el.startswith("hex"):
                raise GeometryError(f"element '{el}': the meshed tip cone needs element = tet-p2 or auto")
            return "tet-p2"
        return "hex-s2" if el == "auto" else el

    def mesh(self, values: dict[str, Any]):
        el = self.element(values)
        if el != "tet-p2":
            div = HexDivisions(int(values["elements_through_thickness"]), values.get("element_size"),
                               refine=refinement_for("duo-bimorph", values.get("accuracy")))
            return duo_bimorph_hex_mesh(validate(self._geom(values)), div, el)
        opts = MeshOptions(values.get("element_size"), int(values["elements_through_thickness"]))
        return duo_bimorph_mesh(self._geom(values), options=opts)

    def holder_geometric_mass(self, values: dict[str, Any]) -> float:
        """Mass [kg] of the nominal holder block + piezolayer with their own densities."""
        v = values
        vol_h = v["holder_length"] * v["holder_width"] * v["holder_thickness"]
        vol_p = v["holder_length"] * v["holder_width"] * v["piezolayer_thickness"]
        return vol_h * get_material(v["holder_material"]).density + vol_p * v["density"]

    def body_rho_A(self, values: dict[str, Any]) -> float:
        return values["density"] * values["width"] * values["thickness"]

    def build(self, values: dict[str, Any]):
        v = values
        bundle = self.mesh(v)
        pzt = self.pzt(v)
        extra, tip = {}, "holder_end"
        if v["tip"] == "meshed":
            si = get_material("silicon")
            vol = region_volumes(bundle.mesh, ["tip"])["tip"]
            extra["tip"] = si.with_overrides(rho=v["tip_mass"] / vol) if v["holder_mass_source"] == "table" else si
            tip = "tip"
        return self._smart_model(v, bundle, {"upper_layer": pzt, "lower_layer": pzt}, extra=extra, tip=tip)

    def tip_point(self, values: dict[str, Any]) -> np.ndarray:
        return named_points(validate(self._geom(values)))["tip"]

    def beam(self, values: dict[str, Any]) -> DuoBimorphBeam:
        return DuoBimorphBeam(values["length"], values["width"], values["thickness"], values["density"], self.s11(values))

    def references(self, values: dict[str, Any], result) -> list[dict[str, Any]]:
        """Analytic rows (see :func:`probedyn.lumped.smart.duo_bimorph_references`)."""
        return duo_bimorph_references(self, values, result)
