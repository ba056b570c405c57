"""Two-dimensional fluid mesh around a thin rectangular beam section (oscillatory Stokes flow).

What: the annulus between an outer circle of radius ``r_out`` and a rectangular hole, the beam's
cross-section ``|x| <= 1``, ``|y| <= t/2``, meshed by gmsh with straight 3-node triangles and returned
as a scikit-fem :class:`~skfem.MeshTri` (quadratic fields are built on it by the solver, e.g.
``ElementTriP2``). Physical groups ``section`` (the four sides of the rectangle) and ``outer`` (the
circle) become ``mesh.boundaries`` (facet indices).

Units: dimensionless, lengths in units of the section's **half-width** ``a = b / 2`` (the section spans
x in [-1, 1]); ``t = h / a = 2 h / b`` is the thickness in the same unit, ``delta`` the viscous penetration
depth ``sqrt(2 eta / (rho omega)) / a = sqrt(2 / Re)`` (Re = rho omega a^2 / eta).

Mesh size (all divided by ``refine``): ``corner`` at the four corners (default ``min(t/4, face)``),
``face`` on the sides (default ``min(delta/4, 0.05)``), each growing linearly with the distance from the
corners resp. the sides at the rate ``growth`` (default 0.2), capped at ``r_out / 10`` (gmsh
Distance/Threshold fields, their minimum). Corners are sharp (no rounding). gmsh's Delaunay algorithm (5):
on the graded meshes of large Re (corner sizes 1e-5 of the outer radius) the Frontal-Delaunay one (6, used
until session 40) took 7.2 s for 17.5 k triangles against 1.25 s, and the torsional function at Re = 3e3 and
3e4 (refine 0.7) moved by 1e-4 and 2.6e-4 of itself, within the stated 2e-3 accuracy.

Assumptions: the section is a rectangle centred at the origin with its width along x; the fluid is
unbounded, represented by the disc of radius ``r_out`` (the solver puts u = 0 there).
"""

from __future__ import annotations

import math

import numpy as np
from skfem import MeshTri

from probedyn.core.errors import GeometryError
from probedyn.meshes._gmsh import gmsh_session
from probedyn.meshes.entities import tuple_keys

__all__ = ["section_mesh", "default_sizes"]


def default_sizes(thickness: float, delta: float, refine: float = 1.0, growth: float = 0.2) -> dict:
    """Default mesh sizes (units of the half-width) for section thickness ``thickness`` (= h/a) and
    penetration depth ``delta`` (= delta/a): see the module docstring."""
    face = min(delta / 4.0, 0.05)
    return {"face": face / refine, "corner": min(thickness / 4.0, face) / refine, "growth": growth / refine}


def section_mesh(thickness: float, r_out: float, face: float, corner: float, growth: float = 0.2,
                 sampling: int | None = None, quarter: bool = False) -> MeshTri:
    """Triangular mesh of the fluid around the rectangle ``|x| <= 1, |y| <= thickness/2`` inside the
    circle of radius ``r_out`` (module docstring; units of the half-width).

    ``face`` and ``corner``: element sizes at the sides and at the corners; ``growth``: their
    increase per unit distance; the size is capped at ``r_out / 10``. ``sampling``: points per side
    of gmsh's distance field (default: enough for the finest size). Returns a MeshTri with
    ``mesh.boundaries == {"section": facets, "outer": facets}``.

    ``quarter=True``: only the quadrant ``x >= 0, y >= 0`` (the section's top face and right end, one corner, a
    quarter of the circle), with the symmetry lines as two more groups, ``sym_x`` (on ``x = 0``) and ``sym_y``
    (on ``y = 0``); the solver imposes each motion's symmetry there (:mod:`probedyn.fem.stokes2d`).
    """
    t = float(thickness)
    if not (0 < t < 2.0):
        raise GeometryError(f"section thickness must lie in (0, 2) half-widths, got {t:g}")
    if not (r_out > 2.0):
        raise GeometryError(f"outer radius must exceed 2 half-widths, got {r_out:g}")
    if not (0 < corner <= face and growth > 0):
        raise GeometryError(f"mesh sizes must satisfy 0 < corner <= face and growth > 0 "
                            f"(got {corner:g}, {face:g}, {growth:g})")
    s_max = r_out / 10.0
    n_samp = int(sampling or min(20000, max(100, math.ceil(4.0 / face))))
    with gmsh_session("section2d") as gmsh:
        geo = gmsh.model.geo
        hw, ht = 1.0, t / 2.0
        centre = geo.addPoint(0.0, 0.0, 0.0)
        if quarter:
            end_mid, corner_pt, top_mid = (geo.addPoint(x, y, 0.0) for x, y in ((hw, 0.0), (hw, ht), (0.0, ht)))
            corners = [corner_pt]
            rim = [geo.addPoint(r_out, 0.0, 0.0), geo.addPoint(0.0, r_out, 0.0)]
            sym_y = geo.addLine(end_mid, rim[0])
            arcs = [geo.addCircleArc(rim[0], centre, rim[1])]
            sym_x = geo.addLine(rim[1], top_mid)
            sides = [geo.addLine(top_mid, corner_pt), geo.addLine(corner_pt, end_mid)]
            surface = geo.addPlaneSurface([geo.addCurveLoop([sym_y, arcs[0], sym_x] + sides)])
        else:
            corners = [geo.addPoint(x, y, 0.0) for x, y in ((-hw, -ht), (hw, -ht), (hw, ht), (-hw, ht))]
            sides = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
            rim = [geo.addPoint(r_out * math.cos(k * math.pi / 2), r_out * math.sin(k * math.pi / 2), 0.0)
                   for k in range(4)]
            arcs = [geo.addCircleArc(rim[k], centre, rim[(k + 1) % 4]) for k in range(4)]
            surface = geo.addPlaneSurface([geo.addCurveLoop(arcs), geo.addCurveLoop(sides)])
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surface], name="fluid")
        gmsh.model.addPhysicalGroup(1, sides, name="section")
        gmsh.model.addPhysicalGroup(1, arcs, name="outer")
        if quarter:
            gmsh.model.addPhysicalGroup(1, [sym_x], name="sym_x")
            gmsh.model.addPhysicalGroup(1, [sym_y], name="sym_y")

        fld = gmsh.model.mesh.field
        fields = []
        for tags, key, size in ((corners, "PointsList", corner), (sides, "CurvesList", face)):
            dist = fld.add("Distance")
            fld.setNumbers(dist, key, tags)
            if key == "CurvesList":
                fld.setNumber(dist, "Sampling", n_samp)
            thr = fld.add("Threshold")
            fld.setNumber(thr, "InField", dist)
            fld.setNumber(thr, "SizeMin", size)
            fld.setNumber(thr, "SizeMax", s_max)
            fld.setNumber(thr, "DistMin", 0.0)
            fld.setNumber(thr, "DistMax", (s_max - size) / growth)
            fields.append(thr)
        fmin = fld.add("Min")
        fld.setNumbers(fmin, "FieldsList", fields)
        fld.setAsBackgroundMesh(fmin)
        for name, value in (("MeshSizeExtendFromBoundary", 0), ("MeshSizeFromPoints", 0),
                            ("MeshSizeFromCurvature", 0), ("ElementOrder", 1), ("Algorithm", 5),
                            ("MeshSizeMin", 0.0), ("MeshSizeMax", s_max)):
            gmsh.option.setNumber(f"Mesh.{name}", value)
        gmsh.model.mesh.generate(2)
        p, tri, lines = _extract(gmsh)
    return _to_skfem(p, tri, lines)


def _extract(gmsh):
    """Node coordinates (n, 2), triangles (m, 3) and {group: (k, 2) line vertex pairs}, compacted."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    etypes, _, enodes = gmsh.model.mesh.getElements(2)
    if list(etypes) != [2]:
        raise GeometryError(f"expected linear triangles (gmsh type 2), got types {list(etypes)}")
    tri = index[enodes[0].astype(np.int64)].reshape(-1, 3)
    lines = {}
    for dim, ptag in gmsh.model.getPhysicalGroups(1):
        pairs = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            _, _, nodes = gmsh.model.mesh.getElements(1, int(ent))
            pairs.append(index[nodes[0].astype(np.int64)].reshape(-1, 2))
        lines[gmsh.model.getPhysicalName(dim, ptag)] = np.concatenate(pairs)
    used = np.unique(tri)
    remap = np.full(tags.size, -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return coords.reshape(-1, 3)[used, :2], remap[tri], {k: remap[v] for k, v in lines.items()}


def _to_skfem(p: np.ndarray, tri: np.ndarray, lines: dict) -> MeshTri:
    """MeshTri (scikit-fem sorts each triangle's vertices) with the line groups as facet index sets."""
    p = np.ascontiguousarray(p.T)
    tri = np.ascontiguousarray(tri.T)
    mesh = MeshTri(p, tri)
    n = p.shape[1]
    keys = tuple_keys(mesh.facets, n)  # skfem's facets are sorted vertex pairs in key order
    bnd = {}
    for name, pairs in lines.items():
        q = tuple_keys(np.sort(pairs, axis=1).T, n)
        pos = np.clip(np.searchsorted(keys, q), 0, keys.size - 1)
        if not np.all(keys[pos] == q):
            raise GeometryError(f"boundary group '{name}': line elements that are not mesh facets")
        bnd[name] = np.sort(pos)
    return MeshTri(p, tri, _boundaries=bnd)
