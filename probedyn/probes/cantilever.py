"""The plain rectangular AFM cantilever of source section 2.3 (eqs 2.36–2.46, 3.10).

Parameters are SI.  ``youngs_modulus``, ``poisson_ratio`` and ``density`` default to None =
"take the material's value" and override it when given (only possible for an isotropic
material).  ``tip_mass`` is a rigid mass attached to the **area-averaged displacement of the
free-end face** (not to one node: a point load on one node of a 3D continuum is singular and
its effect would depend on the mesh).  It has no rotary inertia, like the point mass of the
beam equation (3.10).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.core.params import Param, ParamSet
from probedyn.fem.materials import get_material
from probedyn.fem.model import ElasticModel, PointMass
from probedyn.lumped import beam as bm
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.cantilever import cantilever_mesh, tip_apex, validate_geometry
from probedyn.meshes.hexmeshes import (HexDivisions, cantilever_hex_dofs, cantilever_hex_mesh, element_params,
                                      refinement_for)
from probedyn.probes import Probe, register_probe

_PARAMS = ParamSet([
    Param("length", 300e-6, "m", "beam length, clamp to free end (x)", lo=1e-6, hi=0.8, positive=True, source="2.3"),
    Param("width", 30e-6, "m", "beam width (y)", lo=1e-7, hi=0.1, positive=True, source="2.3"),
    Param("thickness", 10e-6, "m", "beam thickness (z)", lo=1e-8, hi=0.02, positive=True, source="2.3"),
    Param("material", "silicon", "", "material name from the table (probedyn.fem.materials)", kind=str,
          choices=("silicon", "silicon-110", "silicon-nitride", "pzt-5h", "pzt-5h-iso")),
    Param("youngs_modulus", None, "Pa", "Young's modulus; None = the material's (silicon: 169e9)",
          lo=1e8, hi=2e12, positive=True),
    Param("poisson_ratio", None, "", "Poisson ratio; None = the material's (silicon: 0.28)", lo=-0.99, hi=0.499),
    Param("density", None, "kg/m^3", "mass density; None = the material's (silicon: 2330)", lo=100.0, hi=30000.0,
          positive=True),
    Param("tip_mass", 0.0, "kg", "rigid mass on the free-end face (averaged attachment)", lo=0.0, hi=1e-3,
          source="3.10"),
    Param("tip_shape", "none", "", "tip on the underside at the free end", kind=str,
          choices=("none", "pyramid", "cone")),
    Param("tip_height", 10e-6, "m", "tip height (if tip_shape is not none)", lo=1e-7, hi=0.005, positive=True),
    Param("tip_half_angle", 0.35, "rad", "tip half-angle (0.35 rad = 20 deg)", lo=0.01, hi=1.5, positive=True),
    Param("elements_through_thickness", 3, "", "element layers through the thickness", lo=1, hi=40,
          kind=int),
    Param("side_element", None, "", "hexahedra: first element across the width at the side edges, over the "
          "through-thickness element, graded to the width elements (resolves torsion's shear-stress layer at the "
          "long edges of a lever meshed thick and stretched, as the modal diagnosis does); None = uniform width",
          lo=0.01, hi=1.0, positive=True),
    *element_params("maximum element size (hexahedra: along the beam away from the clamp); "
                    "None = thickness / elements_through_thickness (hexahedra: the thickness, graded towards the clamp)",
                    1e-8, 0.01),
])


@register_probe
class Cantilever(Probe):
    """Rectangular cantilever clamped at x = 0 (face ``clamp``), optional pyramid/cone tip."""

    key = "cantilever"
    title = "rectangular AFM cantilever (source 2.3), optional tip and tip mass"
    source = "section 2.3, eqs 2.36-2.46; tip mass eq 3.10"
    params = _PARAMS

    def resolve(self, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
        v = self.params.resolve(overrides)
        validate_geometry(v["length"], v["width"], v["thickness"], v["tip_shape"], v["tip_height"], v["tip_half_angle"])
        if v["length"] < v["width"] or v["length"] < 2 * v["thickness"]:
            raise GeometryError(
                f"cantilever length {v['length']:g} m must exceed its width {v['width']:g} m and twice its "
                f"thickness {v['thickness']:g} m (a beam)"
            )
        return v

    def material(self, values: dict[str, Any]):
        return get_material(values["material"]).with_overrides(
            values.get("youngs_modulus"), values.get("poisson_ratio"), values.get("density"))

    def element(self, values: dict[str, Any]) -> str:
        """The element kind of the mesh: hexahedra for the plain beam (``auto``: hex-s2, the
        fastest to 0.1 %, docs/fem.md), P2 tetrahedra when a tip is meshed."""
        el = values.get("element", "auto")
        if values["tip_shape"] != "none":
            if el.startswith("hex"):
                raise GeometryError(f"element '{el}': hexahedral meshes are for the plain beam (tip_shape = none); "
                                    f"a {values['tip_shape']} tip needs element = tet-p2 or auto")
            return "tet-p2"
        return "hex-s2" if el == "auto" else el

    def _divisions(self, values: dict[str, Any]) -> HexDivisions:
        return HexDivisions(int(values["elements_through_thickness"]), values.get("element_size"),
                            refine=refinement_for("cantilever", values.get("accuracy")), side=values.get("side_element"))

    def mesh(self, values: dict[str, Any]):
        el = self.element(values)
        if el != "tet-p2":
            return cantilever_hex_mesh(values["length"], values["width"], values["thickness"],
                                       self._divisions(values), el)
        opts = MeshOptions(values.get("element_size"), int(values["elements_through_thickness"]))
        return cantilever_mesh(values["length"], values["width"], values["thickness"], values["tip_shape"],
                               values["tip_height"], values["tip_half_angle"], options=opts)

    def build(self, values: dict[str, Any]):
        from probedyn.core import progress
        from probedyn.fem.size import check_model, dofs_for_volume
        from probedyn.meshes.cache import MeshOptions

        mat = self.material(values)
        # before meshing: the model this mesh gives must fit (tetrahedra: estimated from the
        # beam's volume and the mesh size; structured hexahedra: counted exactly)
        el = self.element(values)
        L, w, t = values["length"], values["width"], values["thickness"]
        if el == "tet-p2":
            h = MeshOptions(values.get("element_size"), int(values["elements_through_thickness"])).size_for(min(w, t))
            check_model(dofs_for_volume(L * w * t, h), "cantilever model")
        else:
            check_model(cantilever_hex_dofs(L, w, t, self._divisions(values), el), "cantilever model", element=el)
        with progress.stage("meshing the cantilever"):
            bundle = self.mesh(values)
        regions = {"body": mat}
        if "tip" in (bundle.mesh.subdomains or {}):
            regions["tip"] = mat
        pm = [PointMass("free_end", values["tip_mass"])] if values.get("tip_mass", 0) > 0 else []
        return ElasticModel(bundle, regions, clamp=["clamp"], point_masses=pm, tip="tip", beam_axis=0,
                            name="cantilever")

    def tip_point(self, values: dict[str, Any]) -> np.ndarray:
        return tip_apex(values["length"], values["thickness"], values["tip_shape"], values["tip_height"],
                        values["tip_half_angle"])

    def beam(self, values: dict[str, Any]):
        """The equivalent :class:`probedyn.lumped.beam.RectBeam` (isotropic materials only;
        an anisotropic one uses E along x and nu from the x-y compliance)."""
        mat = self.material(values)
        if mat.is_isotropic():
            E, nu = mat.isotropic_constants()
        else:
            S = mat.S
            E, nu = 1.0 / S[0, 0], float(np.clip(-S[0, 1] / S[0, 0], -0.99, 0.49))
        return bm.RectBeam(values["length"], values["width"], values["thickness"], E, nu, mat.density)

    def static_stiffness(self, values: dict[str, Any], model) -> dict[str, Any]:
        """FEM static stiffness of the free end (face-averaged, z) beside 3EI/L^3 with and
        without the Timoshenko shear correction."""
        from probedyn.lumped import beam as bm

        b = self.beam(values)
        return {"fem_n_per_m": float(model.static_stiffness("free_end", (0, 0, 1))),
                "euler_bernoulli_3EI_L3": bm.static_tip_stiffness(b, "flapwise", shear=False),
                "with_shear_correction": bm.static_tip_stiffness(b, "flapwise", shear=True)}

    def references(self, values: dict[str, Any], result) -> list[dict[str, Any]]:
        """Per FEM mode, the beam formula of its family and order: Euler–Bernoulli (2.40–2.41)
        and Timoshenko bending, Saint-Venant torsion, axial rod; with a tip mass the two forms
        of (3.10) (Euler–Bernoulli).  The tip (pyramid/cone) is not in the beam models."""
        b = self.beam(values)
        mu = values.get("tip_mass", 0.0) or 0.0
        count: dict[str, int] = {}
        n_max = len(result.modes)
        refs: dict[tuple[str, str], np.ndarray] = {}
        for fam in ("flapwise", "lateral"):
            if mu > 0:
                refs[(fam, "tip mass (3.10), standard form, Euler-Bernoulli")] = bm.tip_mass_frequencies(b, fam, mu, n_max, "standard")
                refs[(fam, "tip mass (3.10), printed form, Euler-Bernoulli")] = bm.tip_mass_frequencies(b, fam, mu, n_max, "printed")
            else:
                refs[(fam, "Euler-Bernoulli (2.40)")] = bm.eb_frequencies(b, fam, n_max)
                refs[(fam, "Timoshenko (shear + rotary inertia)")] = bm.timoshenko_frequencies(b, fam, n_max)
        if mu == 0:
            refs[("torsion", "Saint-Venant torsion")] = bm.torsion_frequencies(b, n_max)
            refs[("axial", "axial rod")] = bm.axial_frequencies(b, n_max)
        rows = []
        for m in result.modes:
            count[m.family] = count.get(m.family, 0) + 1
            k = count[m.family]
            for (fam, formula), vals in refs.items():
                if fam != m.family or k > len(vals):
                    continue
                ref = float(vals[k - 1])
                rows.append({"mode": m.index, "family": m.family, "order": k, "formula": formula,
                             "fem_hz": m.frequency_hz, "value_hz": ref,
                             "rel_diff": (m.frequency_hz - ref) / ref})
        return rows
