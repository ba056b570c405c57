"""Parametric piezotube probe (source section 3.3.1, Figs 3.9-3.11, 3.19; Table 3.2).

Geometry (SI metres, probedyn axes: the tube axis is **x**, from the clamp at x = 0; the source
calls the tube axis z, its lateral x is probedyn z and its y is probedyn y):

* **tube** (volume ``tube``, also ``body``): outer circle of radius ``Re`` centred on the x axis,
  bore of radius ``Ri`` centred at ``(delta_y, delta_z)`` (eccentricity, Fig 3.19),
  ``0 <= x <= length``;
* optional **holder** (``holder = "meshed"``): a thick collar ``length <= x <= length +
  holder_length`` made of the tube's cross-section and a ring ``Re <= r <= Re + holder_wall``
  (volume ``holder``; the thick wall keeps the collar from ovalising under a heavy holder
  mass) and its stiffness-tuning piezolayer, a ring of thickness ``piezolayer_thickness``
  around it (``holder_piezolayer``).
  (The cantilever tip on the holder is lumped: Table 3.2 gives no tip geometry.)

Electrodes (tagged surfaces on ``0 <= x <= length``): 12 equal 30-degree sectors
``electrode_sector_00`` ... ``_11`` (sector k centred at theta = 30 k degrees, theta measured
from +y towards +z; Moheimani & Yong's pattern, Fig 3.11b), the quartered electrodes
``electrode_yp``, ``electrode_zp``, ``electrode_ym``, ``electrode_zm`` (90 degrees centred on
+y, +z, -y, -z, each the union of three sectors, Fig 3.11a / eq 3.39) and
``electrode_inner`` (the bore). Other surfaces: ``clamp`` (x = 0), ``tube_end`` (x = length),
``holder_end`` (x = length + holder_length, or the tube end without a holder).

Mesh: **structured** (gmsh transfinite volumes, hexahedra split into six tetrahedra):
``n_wall`` elements through the wall, ``n_sector`` per 30-degree sector, axial size about the
circumferential size. The pattern repeats every 30 degrees, so for a centred bore the mesh is
invariant under a 90-degree rotation and the lateral y/z pair is exactly degenerate; an
eccentric bore only moves nodes, so the split of the pair measures the eccentricity and not
mesh noise.

Named points: ``tip`` and ``holder_end_centre`` = centre of the last end face,
``tube_end_centre`` and ``clamp_centre`` (axis points; they lie in the bore, so attach masses and springs to the
boundary groups, which are face-averaged).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.core.presets import preset
from probedyn.meshes._gmsh import RawMesh, entities_in_box, extract_tet_mesh, gmsh_session
from probedyn.meshes.cache import MeshBundle, MeshOptions, cached_mesh

MM = 1e3  # build in millimetres
MAX_SIZE = 0.1  # m
MIN_WALL = 5e-6  # m: thinnest wall that can be built and meshed (also the eccentricity margin)
N_SECT = 12
QUARTERS = {"electrode_yp": (11, 0, 1), "electrode_zp": (2, 3, 4), "electrode_ym": (5, 6, 7), "electrode_zm": (8, 9, 10)}

_T32 = preset("table-3.2")

#: default geometry: Table 3.2 (R_e, R_i as corrected, L) and the holder collar of docs/smart-probes.md
DEFAULTS: dict[str, Any] = {
    "Re": _T32["R_e"], "Ri": _T32["R_i"], "length": _T32["L"], "delta_y": 0.0, "delta_z": 0.0,
    "holder": "meshed", "holder_length": 0.5e-3, "holder_wall": 0.25e-3, "piezolayer_thickness": 25e-6,
}


def validate(p: dict[str, Any]) -> dict[str, Any]:
    """Complete with defaults and check that the tube can exist (one-line GeometryError)."""
    q = {**DEFAULTS, **p}
    for k in ("Re", "Ri", "length", "holder_length", "holder_wall", "piezolayer_thickness"):
        v = float(q[k])
        if k == "holder_length" and v <= 0:
            raise GeometryError(f"piezotube holder_length L_h must be positive, got {v:g} m")
        if not math.isfinite(v) or v <= 0:
            raise GeometryError(f"piezotube {k} must be positive, got {v:g} m")
        if v > MAX_SIZE:
            raise GeometryError(f"piezotube {k} = {v:g} m is not a probe size (SI metres: did you mean {v:g}e-6 m?)")
        q[k] = v
    q["delta_y"], q["delta_z"] = float(q["delta_y"]), float(q["delta_z"])
    if q["Ri"] >= q["Re"]:
        raise GeometryError(f"piezotube inner radius Ri = {q['Ri']:g} m must be smaller than the outer radius Re = {q['Re']:g} m")
    d = math.hypot(q["delta_y"], q["delta_z"])
    wall = q["Re"] - q["Ri"]
    if not math.isfinite(d) or d >= wall - MIN_WALL - 1e-12 * q["Re"]:
        raise GeometryError(
            f"piezotube eccentricity |delta| = {d:g} m breaks the wall: it must stay below "
            f"Re - Ri - {MIN_WALL:g} m = {wall - MIN_WALL:g} m")
    if q["holder"] not in ("meshed", "point"):
        raise GeometryError(f"piezotube holder must be 'meshed' or 'point', got {q['holder']!r}")
    return q


def mesh_counts(q: dict[str, Any], opts: MeshOptions) -> dict[str, int]:
    """Structured divisions: through the wall, per sector, along the tube and the holder."""
    wall = q["Re"] - q["Ri"]
    n_wall = max(1, int(opts.elements_through_thickness))
    size = float(opts.element_size) if opts.element_size else 4.0 * wall / n_wall
    if not size > 0:
        raise GeometryError(f"element_size must be positive, got {size:g} m")
    arc = 2 * math.pi * 0.5 * (q["Re"] + q["Ri"]) / N_SECT
    n_sector = max(1, math.ceil(arc / size - 1e-9))
    n_len = max(2, math.ceil(q["length"] / size - 1e-9))
    n_hold = max(1, math.ceil(q["holder_length"] / size - 1e-9))
    n_layer = max(1, math.ceil(q["piezolayer_thickness"] / (wall / n_wall) - 1e-9))
    n_hw = max(1, math.ceil(q["holder_wall"] / (2 * wall / n_wall) - 1e-9))
    n_hex = N_SECT * n_sector * (n_wall * (n_len + n_hold) + (n_layer + n_hw) * n_hold)
    if 6 * n_hex > 3e6:
        raise GeometryError(f"element size {size:.3g} m would give ~{6 * n_hex:.2g} tetrahedra; choose a larger element_size")
    return {"n_wall": n_wall, "n_sector": n_sector, "n_length": n_len, "n_holder": n_hold, "n_layer": n_layer,
            "n_holder_wall": n_hw}


def sector_edges_deg() -> np.ndarray:
    """Angles of the sector boundaries [deg]: sector k spans 30 k - 15 ... 30 k + 15."""
    return 30.0 * np.arange(N_SECT) - 15.0


def _build(params: dict[str, Any]) -> MeshBundle:
    q = validate(params)
    opts = MeshOptions(**params["mesh"])
    nc = mesh_counts(q, opts)
    Re, Ri, L = q["Re"] * MM, q["Ri"] * MM, q["length"] * MM
    dy, dz = q["delta_y"] * MM, q["delta_z"] * MM
    Lh, tp, hw = q["holder_length"] * MM, q["piezolayer_thickness"] * MM, q["holder_wall"] * MM
    meshed_holder = q["holder"] == "meshed"
    tol = 1e-4 * min(Re - Ri, tp)
    phis = np.radians(sector_edges_deg())

    def section(x0: float, r_in: float, c_in: tuple[float, float], r_out: float) -> list[int]:
        """12 four-sided sector surfaces at x = x0 between a circle of radius r_in centred at
        c_in and a circle of radius r_out centred on the axis."""
        occ = gmsh.model.occ
        co, ci = occ.addPoint(x0, 0, 0), occ.addPoint(x0, c_in[0], c_in[1])
        po = [occ.addPoint(x0, r_out * math.cos(f), r_out * math.sin(f)) for f in phis]
        pi = [occ.addPoint(x0, c_in[0] + r_in * math.cos(f), c_in[1] + r_in * math.sin(f)) for f in phis]
        ao = [occ.addCircleArc(po[k], co, po[(k + 1) % N_SECT]) for k in range(N_SECT)]
        ai = [occ.addCircleArc(pi[k], ci, pi[(k + 1) % N_SECT]) for k in range(N_SECT)]
        rl = [occ.addLine(pi[k], po[k]) for k in range(N_SECT)]
        out = []
        for k in range(N_SECT):
            loop = occ.addCurveLoop([rl[k], ao[k], -rl[(k + 1) % N_SECT], -ai[k]])
            out.append(occ.addPlaneSurface([loop]))
        return out

    with gmsh_session("piezotube") as gmsh:
        occ = gmsh.model.occ
        vols: list[tuple[int, int]] = []

        def extrude(surfs: list[int], length: float) -> None:
            for d, t in occ.extrude([(2, s) for s in surfs], length, 0, 0):
                if d == 3:
                    vols.append((3, t))

        extrude(section(0.0, Ri, (dy, dz), Re), L)
        if meshed_holder:
            extrude(section(L, Ri, (dy, dz), Re), Lh)
            extrude(section(L, Re, (0.0, 0.0), Re + hw), Lh)
            extrude(section(L, Re + hw, (0.0, 0.0), Re + hw + tp), Lh)
        occ.fragment(vols[:1], vols[1:])
        occ.removeAllDuplicates()
        occ.synchronize()

        # ---- structured mesh constraints by entity kind -----------------------------------
        mesh = gmsh.model.mesh
        for _, c in gmsh.model.getEntities(1):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, c)
            kind = gmsh.model.getType(1, c)
            if kind == "Line" and x1 - x0 > tol:
                n = nc["n_length"] if x1 - x0 > Lh + 10 * tol or not meshed_holder else nc["n_holder"]
                if meshed_holder and abs((x1 - x0) - L) < 10 * tol:
                    n = nc["n_length"]
                elif meshed_holder and abs((x1 - x0) - Lh) < 10 * tol:
                    n = nc["n_holder"]
            elif kind == "Line":
                r0 = math.hypot(y0, z0)
                r1 = math.hypot(y1, z1)
                rmin = min(r0, r1)
                n = nc["n_layer"] if rmin > Re + hw - tol else (nc["n_holder_wall"] if rmin > Re - tol else nc["n_wall"])
            else:
                n = nc["n_sector"]
            mesh.setTransfiniteCurve(c, n + 1)
        for _, s in gmsh.model.getEntities(2):
            mesh.setTransfiniteSurface(s)
        for _, v in gmsh.model.getEntities(3):
            mesh.setTransfiniteVolume(v)

        # ---- physical groups -----------------------------------------------------------
        tube, holder, layer = [], [], []
        for _, v in gmsh.model.getEntities(3):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(3, v)
            if x1 <= L + tol:
                tube.append(v)
            else:
                com = gmsh.model.occ.getCenterOfMass(3, v)
                (layer if math.hypot(com[1], com[2]) > Re + hw else holder).append(v)
        gmsh.model.addPhysicalGroup(3, tube, name="tube")
        gmsh.model.addPhysicalGroup(3, tube, name="body")
        if holder:
            gmsh.model.addPhysicalGroup(3, holder, name="holder")
            gmsh.model.addPhysicalGroup(3, layer, name="holder_piezolayer")

        B = Re + hw + tp + 1
        clamp = entities_in_box(2, (0, -B, -B), (0, B, B), tol)
        tube_end = entities_in_box(2, (L, -Re - tol, -Re - tol), (L, Re + tol, Re + tol), tol)
        x_end = L + Lh if meshed_holder else L
        holder_end = entities_in_box(2, (x_end, -B, -B), (x_end, B, B), tol) if meshed_holder else list(tube_end)
        outer, inner = {}, []
        for _, s in gmsh.model.getEntities(2):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, s)
            if x1 > L + tol or x1 - x0 < tol:
                continue  # holder or end faces
            if gmsh.model.getType(2, s) == "Plane":
                continue  # radial planes between sectors (interior)
            com = gmsh.model.occ.getCenterOfMass(2, s)
            on = gmsh.model.getClosestPoint(2, s, com)[0]  # a point on the (cylindrical) face
            r = math.hypot(on[1], on[2])
            ang = math.degrees(math.atan2(on[2], on[1]))
            ri = math.hypot(on[1] - dy, on[2] - dz)
            if abs(ri - Ri) < abs(r - Re):
                inner.append(s)
            else:
                k = int(round(ang / 30.0)) % N_SECT
                outer.setdefault(k, []).append(s)
        if len(outer) != N_SECT or not inner or not clamp:
            raise GeometryError("piezotube: electrode or clamp surfaces not found (degenerate geometry)")
        gmsh.model.addPhysicalGroup(2, clamp, name="clamp")
        gmsh.model.addPhysicalGroup(2, tube_end, name="tube_end")
        gmsh.model.addPhysicalGroup(2, holder_end, name="holder_end")
        gmsh.model.addPhysicalGroup(2, inner, name="electrode_inner")
        for k in range(N_SECT):
            gmsh.model.addPhysicalGroup(2, outer[k], name=f"electrode_sector_{k:02d}")
        for name, ks in QUARTERS.items():
            gmsh.model.addPhysicalGroup(2, [s for k in ks for s in outer[k]], name=name)

        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.option.setNumber("Mesh.Optimize", 0)  # keep the structured pattern
        gmsh.model.mesh.generate(3)
        raw: RawMesh = extract_tet_mesh()

    raw.points = raw.points / MM
    mesh = raw.to_skfem()
    xe = q["length"] + (q["holder_length"] if meshed_holder else 0.0)
    points = {"tip": np.array([xe, 0.0, 0.0]), "holder_end_centre": np.array([xe, 0.0, 0.0]),
              "tube_end_centre": np.array([q["length"], 0.0, 0.0]), "clamp_centre": np.zeros(3)}
    return MeshBundle(mesh, points, meta={"divisions": nc})


def piezotube_mesh(params: dict[str, Any] | None = None, options: MeshOptions | None = None,
                   use_cache: bool = True) -> MeshBundle:
    """Structured mesh of the piezotube (cached). ``params``: keys of :data:`DEFAULTS` (SI);
    ``options.elements_through_thickness`` = elements through the wall, ``options.element_size``
    = circumferential/axial size (default 4 x wall / n_wall)."""
    q = validate(dict(params or {}))
    if q["holder"] == "point":
        for k in ("holder_length", "holder_wall", "piezolayer_thickness"):
            q[k] = DEFAULTS[k]
    q["mesh"] = (options or MeshOptions(elements_through_thickness=1)).as_dict()
    return cached_mesh("piezotube", q, _build, use_cache=use_cache)
