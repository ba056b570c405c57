"""The piezotube smart probe (source section 3.3, Figs 3.9-3.11, 3.19; Table 3.2).

A radially poled PZT-5H tube (orientation varying in space: local 3-axis = the radial unit
vector about the tube axis, evaluated at every quadrature point by
:func:`probedyn.fem.materials.radial_poling`), clamped at x = 0 (the tube axis is probedyn x;
the source's z), with the tip holder at the free end and the cantilever tip of mass ``m`` on
the holder spring ``k_t`` (eq 3.20).

User choices (departure 5):

* ``holder = "meshed"`` (a silicon collar of length L_h with the tube's cross-section and its
  PZT stiffness-tuning piezolayer ring, radially poled) or ``"point"`` (a rigid mass m_h on the
  face-averaged displacement of the tube end face, no rotary inertia, as in eqs 3.24, 3.29);
* ``holder_mass_source = "table"`` (Table 3.2's m_h = 2e-5 kg; the meshed collar's density is
  scaled to it) or ``"geometry"``;
* ``tip = "lumped"`` (mass ``tip_mass`` on k_tx, k_ty, k_tz at the holder end face) or
  ``"none"``. Table 3.2 gives neither m nor k_t: the defaults take Table 3.1's m
  and k_t = 10 N/m (the "manipulation" stiffness of section 3.4.1).

Defaults: Re = 0.5 mm, L = 5 mm (Table 3.2), **Ri = 0.45 mm** (section 3.5; Table 3.2 prints
0.3 mm), rho = 7800 kg/m^3 (Table 3.2, overrides the material's). Eccentricity: the bore centre
is offset by (delta_y, delta_z) (the source's (delta_y, delta_x), Fig 3.19); the radial poling is
taken about the outer circle's axis.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.fem.materials import get_material, radial_poling
from probedyn.lumped.smart import piezotube_references
from probedyn.lumped.smart_analytic import Piezotube as Tube
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.piezotube import DEFAULTS as GEOM
from probedyn.meshes.hexmeshes import HexDivisions, element_params, piezotube_hex_mesh, refinement_for
from probedyn.meshes.piezotube import piezotube_mesh, validate
from probedyn.probes import register_probe
from probedyn.probes._smart import SmartProbe

T32 = preset("table-3.2")

_PARAMS = ParamSet([
    Param("Re", GEOM["Re"], "m", "outer radius R_e", lo=10e-6, hi=0.05, positive=True, source="Table 3.2"),
    Param("Ri", GEOM["Ri"], "m", "inner (bore) radius R_i (section 3.5; Table 3.2 prints 0.3e-3)", lo=1e-6,
          hi=0.05, positive=True, source="3.5"),
    Param("length", GEOM["length"], "m", "tube length L (probedyn x)", lo=50e-6, hi=0.1, positive=True, source="Table 3.2"),
    Param("delta_y", 0.0, "m", "bore offset along y (source delta_y)", lo=-0.01, hi=0.01, source="Fig 3.19"),
    Param("delta_z", 0.0, "m", "bore offset along z (source delta_x)", lo=-0.01, hi=0.01, source="Fig 3.19"),
    Param("holder", "meshed", "", "tip holder: meshed collar + piezolayer ring, or a point mass m_h", kind=str,
          choices=("meshed", "point")),
    Param("holder_length", GEOM["holder_length"], "m", "holder (collar) length L_h", lo=1e-6, hi=0.05, positive=True),
    Param("holder_wall", GEOM["holder_wall"], "m", "radial thickness of the holder collar outside Re", lo=1e-6, hi=0.05,
          positive=True),
    Param("piezolayer_thickness", GEOM["piezolayer_thickness"], "m", "stiffness-tuning piezolayer ring on the holder", lo=1e-7, hi=0.005,
          positive=True, source="3.3.1"),
    Param("holder_material", "silicon", "", "material of the holder collar", kind=str,
          choices=("silicon", "silicon-110", "silicon-nitride", "pzt-5h", "pzt-5h-iso")),
    Param("holder_mass_source", "table", "", "which mass drives the holder: Table 3.2 m_h or its geometry",
          kind=str, choices=("table", "geometry"), source="departure 5"),
    Param("holder_mass", T32["m_h"], "kg", "holder mass m_h", lo=0.0, hi=1.0, source="Table 3.2"),
    Param("tip", "lumped", "", "cantilever tip: mass m on the holder springs k_t, or none", kind=str,
          choices=("lumped", "none")),
    Param("tip_mass", preset("table-3.1")["m"], "kg", "tip mass m (Table 3.2 gives none; Table 3.1's value)",
          lo=1e-18, hi=1.0, positive=True, source="Table 3.1"),
    Param("k_tx", 10.0, "N/m", "holder spring along the tube axis", lo=1e-4, hi=1e8, positive=True, source="3.4.1"),
    Param("k_ty", 10.0, "N/m", "holder spring along y", lo=1e-4, hi=1e8, positive=True, source="3.4.1"),
    Param("k_tz", 10.0, "N/m", "holder spring along z", lo=1e-4, hi=1e8, positive=True, source="3.4.1"),
    Param("material", "pzt-5h", "", "PZT of the tube: transversely isotropic radially poled, or isotropic E = 1/s11",
          kind=str, choices=("pzt-5h", "pzt-5h-iso")),
    Param("density", T32["rho"], "kg/m^3", "density of the PZT (overrides the material's)", lo=1000.0,
          hi=20000.0, positive=True, source="Table 3.2"),
    Param("mu", T32["mu"], "N s/m^2", "environment damping factor mu of eq 3.2 (lumped models)", lo=0.0, hi=1e3,
          source="Table 3.2"),
    Param("elements_through_thickness", 1, "", "elements through the tube wall", lo=1, hi=12,
          kind=int),
    *element_params("circumferential/axial element size; None = 4 x wall / elements_through_thickness "
                    "(hexahedra: 8 x wall)",
                    1e-7, 0.01),
])

GEOM_KEYS = ("Re", "Ri", "length", "delta_y", "delta_z", "holder", "holder_length", "holder_wall",
             "piezolayer_thickness")


@register_probe
class Piezotube(SmartProbe):
    """The piezotube probe (module docstring)."""

    key = "piezotube"
    title = "piezotube smart probe (source 3.3): radially poled PZT tube, holder + piezolayer, tip on holder spring"
    source = "sections 3.3, 3.5, Figs 3.9-3.11, 3.19, eqs 3.19-3.29, Table 3.2"
    params = _PARAMS
    lumped_directions = ("x", "y", "z")
    direction_groups = {"lateral": ("y", "z"), "axial": ("x",)}
    body_regions = ("tube",)
    sweep_directions = ("x", "y", "z")
    body_end = "tube_end"

    def resolve(self, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
        v = self.params.resolve(overrides)
        validate({k: v[k] for k in GEOM_KEYS})
        return v

    def element(self, values: dict[str, Any]) -> str:
        """Hexahedra with curved (quadratic) geometry for ``auto`` (hex-s2), else as given."""
        el = values.get("element", "auto")
        return "hex-s2" if el == "auto" else el

    def mesh(self, values: dict[str, Any]):
        el = self.element(values)
        if el != "tet-p2":
            div = HexDivisions(int(values["elements_through_thickness"]), values.get("element_size"),
                               refine=refinement_for("piezotube", values.get("accuracy")))
            return piezotube_hex_mesh(validate({k: values[k] for k in GEOM_KEYS}), div, el)
        opts = MeshOptions(values.get("element_size"), int(values["elements_through_thickness"]))
        return piezotube_mesh({k: values[k] for k in GEOM_KEYS}, options=opts)

    def s11(self, values: dict[str, Any]) -> float:
        """Axial compliance [1/Pa]: the tube axis is perpendicular to the radial poling, so it is
        a local 1-2 plane direction of the 6mm material (s22 = s11)."""
        return float(self.pzt(values).S[0, 0])

    def s66(self, values: dict[str, Any]) -> float:
        """Axial-circumferential shear compliance of the wall [1/Pa] (= 2 (s11 - s12))."""
        return float(self.pzt(values).S[5, 5])

    def holder_geometric_mass(self, values: dict[str, Any]) -> float:
        v = values
        R2 = v["Re"] + v["holder_wall"]
        a = np.pi * (R2**2 - v["Ri"] ** 2) * v["holder_length"]
        b = np.pi * ((R2 + v["piezolayer_thickness"]) ** 2 - R2**2) * v["holder_length"]
        return float(a * get_material(v["holder_material"]).density + b * v["density"])

    def body_rho_A(self, values: dict[str, Any]) -> float:
        return values["density"] * math.pi * (values["Re"] ** 2 - values["Ri"] ** 2)

    def build(self, values: dict[str, Any]):
        v = values
        Rr = radial_poling(axis_point=(0.0, 0.0, 0.0), axis_dir=(1.0, 0.0, 0.0))
        # tip = "holder_end": the mesh part's reference attachment (the lumped tip has its own DOFs)
        return self._smart_model(v, self.mesh(v), {"tube": (self.pzt(v), Rr)}, orient=Rr)

    def tip_point(self, values: dict[str, Any]) -> np.ndarray:
        return np.array([values["length"] + (values["holder_length"] if values["holder"] == "meshed" else 0.0), 0.0, 0.0])

    def tube(self, values: dict[str, Any]) -> Tube:
        return Tube(values["Re"], values["Ri"], values["length"], values["density"], self.s11(values))

    def references(self, values: dict[str, Any], result) -> list[dict[str, Any]]:
        return piezotube_references(self, values, result)
