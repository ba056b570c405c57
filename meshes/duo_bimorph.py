"""Parametric duo-bimorph probe (source section 3.2.1, Fig 3.4, Table 3.1).

Geometry (SI metres, probedyn axes: x from the clamp to the free end, y across, z up):

* **body**: two PZT layers of thickness ``h/2`` each, ``0 <= x <= length``, ``|y| <= width/2``;
  ``lower_layer`` for ``-h/2 <= z <= 0``, ``upper_layer`` for ``0 <= z <= h/2``. Each layer is
  built from three strips in y (right ``y < -w0/2``, gap ``|y| < w0/2``, left ``y > w0/2``) so
  that the electrode gap ``w0`` splits the electrode faces;
* **electrodes** (tagged surfaces): ``electrode_upper_left`` / ``electrode_upper_right`` on
  ``z = +h/2``, ``electrode_lower_left`` / ``electrode_lower_right`` on ``z = -h/2`` (left =
  ``y > w0/2``), and ``electrode_middle`` (the interface ``z = 0``, interior facets);
* optional **holder** (``holder = "meshed"``): a block ``length <= x <= length + holder_length``,
  ``|y| <= holder_width/2``, ``-h/2 <= z <= -h/2 + holder_thickness`` (volume ``holder``) carrying
  its stiffness-tuning piezolayer of thickness ``piezolayer_thickness`` on top (volume
  ``holder_piezolayer``);
* optional **tip** (``tip = "meshed"``): a cone of base radius ``tip_radius`` and height
  ``tip_height`` pointing to ``-z`` under the holder end (or under the body end without a meshed
  holder), volume ``tip``.

Mesh: without a meshed tip the solid is a grid of boxes meshed as **structured** transfinite
hexahedra split into tetrahedra (``element_size`` = in-plane size, at least
``elements_through_thickness`` elements through every layer), so refinement studies see nested,
uniformly refined meshes; with the tip cone it is meshed unstructured (size ``element_size``).

Physical groups: volumes ``upper_layer``, ``lower_layer``, ``body`` (= both layers), ``holder``,
``holder_piezolayer``, ``tip``; surfaces ``clamp`` (x = 0), ``free_end`` (the part of x = length
not covered by the holder), ``holder_end`` (the holder end face x = length + holder_length, or
the whole body end face without a meshed holder), the five electrodes. Named points: ``tip`` (cone apex; without a
meshed tip the centre of the face where the lumped tip spring is attached, ``holder_end_centre``), ``holder``
(centroid of holder + piezolayer, or the body end centre without a meshed holder),
``holder_end_centre`` (centre of the holder end face, or the body end centre), ``free_end_centre``,
``clamp_centre``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.core.presets import preset
from probedyn.meshes._gmsh import RawMesh, entities_in_box, extract_tet_mesh, gmsh_session, set_mesh_size
from probedyn.meshes.cache import MeshBundle, MeshOptions, cached_mesh

UM = 1e6  # build in micrometres (OpenCASCADE tolerance is absolute, 1e-7 model units)
MAX_SIZE = 0.05  # m: no dimension of a micro-probe reaches 5 cm (micrometres typed as metres)

_T31 = preset("table-3.1")

#: default geometry: Table 3.1 (L, w, h, w0, L_h) and the holder block of docs/smart-probes.md
DEFAULTS: dict[str, Any] = {
    "length": _T31["L"], "width": _T31["w"], "thickness": _T31["h"], "electrode_gap": _T31["w0"],
    "holder": "meshed", "holder_length": _T31["L_h"], "holder_width": 30e-6,
    "holder_thickness": 8e-6, "piezolayer_thickness": 2e-6,
    "tip": "none", "tip_height": 5e-6, "tip_radius": 2e-6,
}


def _check_size(name: str, v: float) -> float:
    v = float(v)
    if not math.isfinite(v) or v <= 0:
        raise GeometryError(f"duo-bimorph {name} must be positive, got {v:g} m")
    if v > MAX_SIZE:
        raise GeometryError(f"duo-bimorph {name} = {v:g} m is not a micro-probe size (SI metres: did you mean {v:g}e-6 m?)")
    return v


def validate(p: dict[str, Any]) -> dict[str, Any]:
    """Complete ``p`` with defaults and check that the geometry can exist; raises a one-line
    :class:`GeometryError` otherwise. Returns the completed dict (floats)."""
    q = {**DEFAULTS, **p}
    for k in ("length", "width", "thickness", "holder_length", "holder_width", "holder_thickness",
              "piezolayer_thickness", "tip_height", "tip_radius"):
        if k == "holder_length" and float(q[k]) <= 0:
            raise GeometryError(f"duo-bimorph holder_length L_h must be positive, got {float(q[k]):g} m")
        q[k] = _check_size(k, q[k])
    q["electrode_gap"] = float(q["electrode_gap"])
    if not (0 < q["electrode_gap"] < q["width"]):
        raise GeometryError(
            f"duo-bimorph electrode_gap w0 = {q['electrode_gap']:g} m must lie in (0, width = {q['width']:g} m)")
    if q["holder"] not in ("meshed", "point"):
        raise GeometryError(f"duo-bimorph holder must be 'meshed' or 'point', got {q['holder']!r}")
    if q["tip"] not in ("meshed", "none"):
        raise GeometryError(f"duo-bimorph tip must be 'meshed' or 'none', got {q['tip']!r}")
    if q["holder"] == "meshed":
        if q["holder_width"] > q["width"] * (1 + 1e-9):
            raise GeometryError(
                f"duo-bimorph holder_width {q['holder_width']:g} m exceeds the body width {q['width']:g} m")
        if q["holder_thickness"] + q["piezolayer_thickness"] > q["thickness"] * (1 + 1e-9):
            raise GeometryError("duo-bimorph holder_thickness + piezolayer_thickness exceeds the body thickness h")
    if q["tip"] == "meshed":
        room_x = q["holder_length"] if q["holder"] == "meshed" else q["length"]
        room_y = q["holder_width"] if q["holder"] == "meshed" else q["width"]
        if 2 * q["tip_radius"] > min(room_x, room_y) * (1 + 1e-9):
            raise GeometryError(f"duo-bimorph tip base (diameter {2 * q['tip_radius']:g} m) does not fit under the holder")
    return q


def named_points(q: dict[str, Any]) -> dict[str, np.ndarray]:
    """The named points of the geometry (metres), see the module docstring."""
    L, h = q["length"], q["thickness"]
    end = np.array([L, 0.0, 0.0])
    if q["holder"] == "meshed":
        zc = -h / 2 + 0.5 * (q["holder_thickness"] + q["piezolayer_thickness"])
        holder = np.array([L + q["holder_length"] / 2, 0.0, zc])
        holder_end = np.array([L + q["holder_length"], 0.0, zc])
        x_tip = L + q["holder_length"] - q["tip_radius"]
    else:
        holder = end.copy()
        holder_end = end.copy()
        x_tip = L - q["tip_radius"]
    tip = np.array([x_tip, 0.0, -h / 2 - q["tip_height"]]) if q["tip"] == "meshed" else holder_end.copy()
    return {"tip": tip, "holder": holder, "holder_end_centre": holder_end, "free_end_centre": end,
            "clamp_centre": np.zeros(3)}


def _build(params: dict[str, Any]) -> MeshBundle:
    q = validate(params)
    opts = MeshOptions(**params["mesh"])
    thin = q["thickness"] / 2
    if q["holder"] == "meshed":
        thin = min(thin, q["holder_thickness"])
    structured = q["tip"] != "meshed"
    if structured:
        # grid of boxes meshed as transfinite hexahedra (split into tets): element_size is the
        # in-plane size and may exceed the layer thickness; through the thickness every
        # interval gets at least elements_through_thickness elements
        hs = float(opts.element_size) if opts.element_size else thin / max(1, int(opts.elements_through_thickness))
        if not hs > 0:
            raise GeometryError(f"element_size must be positive, got {hs:g} m")
    else:
        hs = opts.size_for(thin)
    L, w, h, g = (q[k] * UM for k in ("length", "width", "thickness", "electrode_gap"))
    Lh, wh, th, tp = (q[k] * UM for k in ("holder_length", "holder_width", "holder_thickness", "piezolayer_thickness"))
    tip_h, tip_r = q["tip_height"] * UM, q["tip_radius"] * UM
    s = hs * UM
    n_est = 6 * (L + Lh) * w * h / s**3
    if n_est > 3e6:
        raise GeometryError(f"element size {hs:.3g} m would give ~{n_est:.2g} tetrahedra; choose a larger element_size")
    tol = 1e-3 * min(g, h / 2, tp if q["holder"] == "meshed" else h)

    with gmsh_session("duo_bimorph") as gmsh:
        occ = gmsh.model.occ
        tools = []
        ystrips = [(-w / 2, -g / 2), (-g / 2, g / 2), (g / 2, w / 2)]
        if structured:
            mh = q["holder"] == "meshed"
            xb = [0.0, L] + ([L + Lh] if mh else [])
            yb = sorted({-w / 2, -g / 2, g / 2, w / 2} | ({-wh / 2, wh / 2} if mh else set()))
            zb = sorted({-h / 2, 0.0, h / 2} | ({-h / 2 + th, -h / 2 + th + tp} if mh else set()))
            for i in range(len(xb) - 1):
                for j in range(len(yb) - 1):
                    for k in range(len(zb) - 1):
                        yc, zc = 0.5 * (yb[j] + yb[j + 1]), 0.5 * (zb[k] + zb[k + 1])
                        if xb[i] >= L and not (abs(yc) < wh / 2 and zc < -h / 2 + th + tp):
                            continue
                        if yb[j + 1] - yb[j] < 1e-9 * w or zb[k + 1] - zb[k] < 1e-9 * h:
                            continue
                        tools.append((3, occ.addBox(xb[i], yb[j], zb[k], xb[i + 1] - xb[i], yb[j + 1] - yb[j],
                                                    zb[k + 1] - zb[k])))
        else:
            for z0 in (-h / 2, 0.0):
                for y0, y1 in ystrips:
                    tools.append((3, occ.addBox(0, y0, z0, L, y1 - y0, h / 2)))
            if q["holder"] == "meshed":
                tools.append((3, occ.addBox(L, -wh / 2, -h / 2, Lh, wh, th)))
                tools.append((3, occ.addBox(L, -wh / 2, -h / 2 + th, Lh, wh, tp)))
        if q["tip"] == "meshed":
            xt = (L + Lh if q["holder"] == "meshed" else L) - tip_r
            tools.append((3, occ.addCone(xt, 0, -h / 2, 0, 0, -tip_h, tip_r, 0)))
        occ.fragment(tools[:1], tools[1:])
        occ.synchronize()

        groups: dict[str, list[int]] = {k: [] for k in ("upper_layer", "lower_layer", "holder", "holder_piezolayer", "tip")}
        for _, v in gmsh.model.getEntities(3):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(3, v)
            xc, zc = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
            if z1 <= -h / 2 + tol:
                groups["tip"].append(v)
            elif xc > L:
                groups["holder" if zc < -h / 2 + th else "holder_piezolayer"].append(v)
            else:
                groups["upper_layer" if zc > 0 else "lower_layer"].append(v)
        for name, vols in groups.items():
            if vols:
                gmsh.model.addPhysicalGroup(3, vols, name=name)
        gmsh.model.addPhysicalGroup(3, groups["upper_layer"] + groups["lower_layer"], name="body")

        def faces(x0, x1, y0, y1, z0, z1):
            return entities_in_box(2, (x0, y0, z0), (x1, y1, z1), tol)

        clamp = faces(0, 0, -w / 2, w / 2, -h / 2, h / 2)
        end_faces = faces(L, L, -w / 2, w / 2, -h / 2, h / 2)
        if q["holder"] == "meshed":
            covered = set(faces(L, L, -wh / 2, wh / 2, -h / 2, -h / 2 + th + tp))
            end_faces = [f for f in end_faces if f not in covered]
        elec = {
            "electrode_upper_left": faces(0, L, g / 2, w / 2, h / 2, h / 2),
            "electrode_upper_right": faces(0, L, -w / 2, -g / 2, h / 2, h / 2),
            "electrode_lower_left": faces(0, L, g / 2, w / 2, -h / 2, -h / 2),
            "electrode_lower_right": faces(0, L, -w / 2, -g / 2, -h / 2, -h / 2),
            "electrode_middle": faces(0, L, -w / 2, w / 2, 0, 0),
        }
        if q["tip"] == "meshed" and q["holder"] == "point":  # the cone base is interior, not electrode
            base = {t for _, t in gmsh.model.getBoundary([(3, v) for v in groups["tip"]], oriented=False)}
            elec["electrode_lower_left"] = [f for f in elec["electrode_lower_left"] if f not in base]
            elec["electrode_lower_right"] = [f for f in elec["electrode_lower_right"] if f not in base]
        if not clamp or any(not v for k, v in elec.items()):
            raise GeometryError("duo-bimorph: clamp or electrode faces not found (degenerate geometry)")
        gmsh.model.addPhysicalGroup(2, clamp, name="clamp")
        if end_faces:
            gmsh.model.addPhysicalGroup(2, end_faces, name="free_end")
        if q["holder"] == "meshed":
            hend = faces(L + Lh, L + Lh, -wh / 2, wh / 2, -h / 2, -h / 2 + th + tp)
        else:
            hend = faces(L, L, -w / 2, w / 2, -h / 2, h / 2)
        gmsh.model.addPhysicalGroup(2, hend, name="holder_end")
        for name, fs in elec.items():
            gmsh.model.addPhysicalGroup(2, fs, name=name)
        if structured:
            ett = max(1, int(opts.elements_through_thickness))
            for _, c in gmsh.model.getEntities(1):
                x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, c)
                ext = (x1 - x0, y1 - y0, z1 - z0)
                ell = max(ext)
                n = max(1, math.ceil(ell / s - 1e-6))
                if ext[2] >= ell:
                    n = max(n, ett)
                gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
            for _, f in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(f)
            for _, vv in gmsh.model.getEntities(3):
                gmsh.model.mesh.setTransfiniteVolume(vv)
            gmsh.option.setNumber("Mesh.Optimize", 0)
        else:
            set_mesh_size(s, s / 10)
            gmsh.option.setNumber("Mesh.Optimize", 1 if opts.optimize else 0)
        gmsh.model.mesh.generate(3)
        raw: RawMesh = extract_tet_mesh()

    raw.points = raw.points / UM
    mesh = raw.to_skfem()
    return MeshBundle(mesh, named_points(q), meta={"element_size_used": hs})


def duo_bimorph_mesh(params: dict[str, Any] | None = None, options: MeshOptions | None = None,
                     use_cache: bool = True) -> MeshBundle:
    """Mesh of the duo-bimorph (cached by a hash of the geometry and mesh options).

    ``params``: any of the keys of :data:`DEFAULTS` (SI metres; ``holder`` 'meshed'/'point',
    ``tip`` 'meshed'/'none'). Impossible geometry raises :class:`GeometryError`.
    """
    q = validate(dict(params or {}))
    if q["holder"] == "point":  # holder sizes do not enter the mesh
        for k in ("holder_width", "holder_thickness", "piezolayer_thickness"):
            q[k] = DEFAULTS[k]
    if q["tip"] == "none":
        q["tip_height"], q["tip_radius"] = DEFAULTS["tip_height"], DEFAULTS["tip_radius"]
    q["mesh"] = (options or MeshOptions(elements_through_thickness=1)).as_dict()
    return cached_mesh("duo_bimorph", q, _build, use_cache=use_cache)
