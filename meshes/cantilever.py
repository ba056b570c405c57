"""Parametric rectangular AFM cantilever (source section 2.3) with an optional tip.

Geometry (SI units, metres):

* beam: the box ``0 <= x <= length``, ``|y| <= width/2``, ``|z| <= thickness/2``; x runs from the
  clamp (x = 0) to the free end, y across the width, z through the thickness (the contract's
  beam-axis convention: flapwise = z bending, lateral = y bending);
* optional tip on the underside at the free end, pointing to -z: a square ``pyramid`` or a
  ``cone`` of height ``tip_height`` and half-angle ``tip_half_angle`` (base half-size
  ``base = tip_height * tan(half_angle)``), its base centred at ``(length - base, 0, -thickness/2)``
  for a pyramid (flush with the free end) and at ``length - 1.25 base`` for a cone
  (:func:`tip_inset`).  The cone is meshed as a 24-sided pyramid whose base polygon has the
  circle's area, so its volume (mass) and centroid are the cone's.

Physical groups: volumes ``body`` and (with a tip) ``tip``; surfaces ``clamp`` (x = 0),
``free_end`` (x = length), ``top`` (z = +t/2), ``bottom`` (z = -t/2, outside the tip base).
Named points: ``tip`` (the apex, or without a tip the centre of the lower free-end edge
``(length, 0, -thickness/2)`` where a tip would sit), ``free_end_centre`` ``(length, 0, 0)``,
``clamp_centre`` ``(0, 0, 0)``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.meshes._gmsh import (RawMesh, entities_in_box, extract_tet_mesh, gmsh_session, mesher_3d, set_mesh_size,
                                   set_mesher_3d)
from probedyn.meshes.cache import MeshBundle, MeshOptions, cached_mesh

TIP_SHAPES = ("none", "pyramid", "cone")
UM = 1e6  # gmsh model units per metre
CONE_SIDES = 24


def tip_inset(shape: str) -> float:
    """Distance of the tip axis from the free end in units of the base half-size: a pyramid's
    base ends flush with the free end (1.0); a cone's circular base would touch the end face
    tangentially, a degenerate contact OpenCASCADE cannot mesh, so it is set back (1.25)."""
    return 1.25 if shape == "cone" else 1.0


def tip_apex(length: float, thickness: float, tip_shape: str, tip_height: float, tip_half_angle: float) -> np.ndarray:
    """Coordinates [m] of the named point ``tip``: the apex, or without a tip the centre of the
    lower free-end edge."""
    if tip_shape == "none":
        return np.array([length, 0.0, -thickness / 2])
    base = tip_height * math.tan(tip_half_angle)
    return np.array([length - tip_inset(tip_shape) * base, 0.0, -thickness / 2 - tip_height])


def validate_geometry(length: float, width: float, thickness: float, tip_shape: str = "none",
                      tip_height: float = 0.0, tip_half_angle: float = 0.0) -> float:
    """Check the sizes; return the tip base half-size [m] (0 without a tip).

    Sizes must be positive; the base of the tip must fit on the underside of the beam.
    (Plausibility ranges, e.g. 300 typed for 300e-6, are checked by the probe's Params.)
    """
    for name, v in (("length", length), ("width", width), ("thickness", thickness)):
        if not (np.isfinite(v) and v > 0):
            raise GeometryError(f"cantilever {name} must be positive, got {v:g} m")
    if tip_shape not in TIP_SHAPES:
        raise GeometryError(f"tip_shape must be one of {', '.join(TIP_SHAPES)}, got {tip_shape!r}")
    if tip_shape == "none":
        return 0.0
    if not (tip_height > 0):
        raise GeometryError(f"tip_height must be positive for a {tip_shape} tip, got {tip_height:g} m")
    if not (0 < tip_half_angle < math.pi / 2):
        raise GeometryError(f"tip_half_angle must lie in (0, pi/2) rad, got {tip_half_angle:g}")
    base = tip_height * math.tan(tip_half_angle)
    half = base * (math.sqrt(2 * math.pi / (CONE_SIDES * math.sin(2 * math.pi / CONE_SIDES))) if tip_shape == "cone" else 1.0)
    if 2 * half > width * (1 - 1e-9) or (tip_inset(tip_shape) * base + half) > length:
        raise GeometryError(
            f"tip base {2 * base:.3g} m (= 2 tip_height tan(half_angle)) does not fit on the "
            f"cantilever underside of width {width:.3g} m"
        )
    return base


def predicted_tets(length: float, width: float, thickness: float, h: float) -> float:
    """Tetrahedra of a box meshed at size ``h`` (six per cube of side h; gmsh's Delaunay gives
    ~0.8 of it)."""
    return (length / h) * (width / h) * (thickness / h) * 6


def _build(params: dict[str, Any]) -> MeshBundle:
    L0, w0, t0 = float(params["length"]), float(params["width"]), float(params["thickness"])
    shape = params.get("tip_shape", "none")
    th0, ta = float(params.get("tip_height", 0.0)), float(params.get("tip_half_angle", 0.0))
    base0 = validate_geometry(L0, w0, t0, shape, th0, ta)
    opts = MeshOptions(**params["mesh"])
    h0 = opts.size_for(min(w0, t0))
    # OpenCASCADE works with an absolute tolerance of 1e-7 model units: build in micrometres
    # and scale the nodes back to metres.
    L, w, t, th, base, h = (v * UM for v in (L0, w0, t0, th0, base0, h0))
    n_est = predicted_tets(L, w, t, h)
    if n_est > 5e7:
        raise GeometryError(f"element size {h:.3g} m would give ~{n_est:.2g} tetrahedra; choose a larger element_size")
    tol = 1e-4 * min(L, w, t)

    with gmsh_session("cantilever") as gmsh:
        occ = gmsh.model.occ
        box = occ.addBox(0, -w / 2, -t / 2, L, w, t)
        tip_vol = None
        if shape != "none":
            xc, zb = L - tip_inset(shape) * base, -t / 2
            if shape == "cone":
                # a right circular cone as a CONE_SIDES-sided pyramid with the circle's base area
                # (OpenCASCADE's true cone apex makes gmsh's surface mesher fail, "overlapping
                # facets", for many sizes); volume and centroid equal the cone's exactly.
                n = CONE_SIDES
                r = base * math.sqrt(2 * math.pi / (n * math.sin(2 * math.pi / n)))
                corners = [(r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n)) for k in range(n)]
            else:
                corners = [(sx * base, sy * base) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            pts = [occ.addPoint(xc + cx, cy, zb) for cx, cy in corners]
            apex = occ.addPoint(xc, 0, zb - th)
            m = len(pts)
            base_lines = [occ.addLine(pts[i], pts[(i + 1) % m]) for i in range(m)]
            side = [occ.addLine(p, apex) for p in pts]
            faces = [occ.addPlaneSurface([occ.addCurveLoop(base_lines)])]
            for i in range(m):
                loop = occ.addCurveLoop([base_lines[i], side[(i + 1) % m], -side[i]])
                faces.append(occ.addPlaneSurface([loop]))
            tip_vol = occ.addVolume([occ.addSurfaceLoop(faces)])
            occ.fragment([(3, box)], [(3, tip_vol)])
        occ.synchronize()

        vols = [tag for _, tag in gmsh.model.getEntities(3)]
        body, tips = [], []
        for v in vols:
            bb = gmsh.model.getBoundingBox(3, v)
            (tips if bb[2] < -t / 2 - tol else body).append(v)
        gmsh.model.addPhysicalGroup(3, body, name="body")
        if tips:
            gmsh.model.addPhysicalGroup(3, tips, name="tip")
        clamp = entities_in_box(2, (0, -w / 2, -t / 2), (0, w / 2, t / 2), tol)
        free = entities_in_box(2, (L, -w / 2, -t / 2), (L, w / 2, t / 2), tol)
        top = entities_in_box(2, (0, -w / 2, t / 2), (L, w / 2, t / 2), tol)
        bottom = entities_in_box(2, (0, -w / 2, -t / 2), (L, w / 2, -t / 2), tol)
        if tips:  # the tip base is an interior interface, not a free surface
            tip_faces = {tag for _, tag in gmsh.model.getBoundary([(3, v) for v in tips], oriented=False)}
            bottom = [f for f in bottom if f not in tip_faces]
        if not clamp or not free:
            raise GeometryError("cantilever: clamp or free-end face not found after meshing")
        gmsh.model.addPhysicalGroup(2, clamp, name="clamp")
        gmsh.model.addPhysicalGroup(2, free, name="free_end")
        gmsh.model.addPhysicalGroup(2, top, name="top")
        gmsh.model.addPhysicalGroup(2, bottom, name="bottom")
        set_mesh_size(h, h / 10 if tips else h)
        gmsh.option.setNumber("Mesh.Optimize", 1 if opts.optimize else 0)
        set_mesher_3d(params.get("mesher_3d", "delaunay"))
        gmsh.model.mesh.generate(3)
        raw: RawMesh = extract_tet_mesh()

    raw.points = raw.points / UM
    mesh = raw.to_skfem()
    points = {
        "tip": tip_apex(L0, t0, shape, th0, ta),
        "free_end_centre": np.array([L0, 0.0, 0.0]),
        "clamp_centre": np.array([0.0, 0.0, 0.0]),
    }
    return MeshBundle(mesh, points, meta={"element_size_used": h0})


def cantilever_mesh(
    length: float = 300e-6,
    width: float = 30e-6,
    thickness: float = 10e-6,
    tip_shape: str = "none",
    tip_height: float = 0.0,
    tip_half_angle: float = 0.0,
    options: MeshOptions | None = None,
    use_cache: bool = True,
) -> MeshBundle:
    """Mesh of the cantilever (cached by a hash of all arguments); see the module docstring
    for the geometry, groups and named points."""
    opts = options or MeshOptions()
    validate_geometry(length, width, thickness, tip_shape, tip_height, tip_half_angle)
    params = {
        "length": float(length), "width": float(width), "thickness": float(thickness),
        "tip_shape": tip_shape,
        "tip_height": float(tip_height) if tip_shape != "none" else 0.0,
        "tip_half_angle": float(tip_half_angle) if tip_shape != "none" else 0.0,
        "mesh": opts.as_dict(),
    }
    # the key exists only for the large meshes it changes: every other mesh's cache key is as before
    if mesher_3d(predicted_tets(length, width, thickness, opts.size_for(min(width, thickness)))) == "hxt":
        params["mesher_3d"] = "hxt"
    return cached_mesh("cantilever", params, _build, use_cache=use_cache)
