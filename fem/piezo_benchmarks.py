"""Reference problems for the coupled piezoelectric FEM (structured box meshes, no gmsh).

Each builder returns a :class:`~probedyn.fem.piezo.PiezoModel` on a structured mesh of
``MeshTet.init_tensor`` boxes (hexahedra split into tetrahedra), so refinement studies see
nested, uniformly refined meshes.  Used by the tests, docs/piezo.md and the report:

* :func:`free_block` - a free PZT block with a 3-2-1 support and full electrodes on two faces:
  the uniform field ``E = V/t`` leaves it stress free (``S = d^T E`` is compatible), so the
  FEM must reproduce ``u = d^T E x`` and the free capacitance ``eps33^T A / t`` exactly (a
  patch test of the whole coupled formulation and of the d -> e conversion);
* :func:`bimorph_cantilever` - a symmetric two-layer PZT cantilever, series (opposite poling,
  voltage across the outer electrodes, middle electrode floating) or parallel (same poling,
  middle electrode driven, outer electrodes grounded); reference: laminate theory
  (:mod:`probedyn.lumped.actuation`);
* :func:`bar_31` - a length-extensional bar (poled and electroded through its thickness, free
  ends) for the k31 resonance/antiresonance check; :func:`rod_33` - a rod poled along its
  length with end electrodes (k33 check).

Axes: x along the length (clamp at x = 0 for the cantilever), y across, z through the thickness.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.fem.model import ElasticModel
from probedyn.fem.piezo import PiezoModel
from probedyn.fem.piezo_materials import PiezoMaterial, get_piezo_material
from probedyn.meshes.cache import MeshBundle


def box_bundle(xs: Sequence[float], ys: Sequence[float], zs: Sequence[float],
               layers: dict[str, tuple[float, float]] | None = None,
               planes: dict[str, tuple[int, float]] | None = None) -> MeshBundle:
    """Structured tet mesh of the box spanned by the grid lines ``xs, ys, zs`` [m].

    ``layers``: {subdomain: (z_lo, z_hi)} (by element centroid); ``planes``: {boundary name:
    (axis, coordinate)} - the facets lying in that plane (interior planes allowed, e.g. the
    middle electrode).  Also defines ``x0``/``x1``, ``y0``/``y1``, ``z0``/``z1`` (the six faces)
    and the named points ``end_centre`` (centre of the x = max face) and ``origin``.
    """
    from skfem import MeshTet

    xs, ys, zs = (np.asarray(a, dtype=float) for a in (xs, ys, zs))
    m0 = MeshTet.init_tensor(xs, ys, zs)
    p, t = m0.p, m0.t
    mesh = MeshTet(p, t)
    fmid = mesh.p[:, mesh.facets].mean(axis=1)
    ext = max(np.ptp(xs), np.ptp(ys), np.ptp(zs))
    tol = 1e-9 * ext
    allp = {"x0": (0, xs.min()), "x1": (0, xs.max()), "y0": (1, ys.min()), "y1": (1, ys.max()),
            "z0": (2, zs.min()), "z1": (2, zs.max())}
    allp.update(planes or {})
    bnd = {}
    for name, (ax, c) in allp.items():
        on = np.all(np.abs(mesh.p[ax, mesh.facets] - c) < tol, axis=0)
        f = np.nonzero(on)[0]
        if f.size == 0:
            raise GeometryError(f"box mesh: plane '{name}' (axis {ax} = {c:g}) has no facets on the grid")
        bnd[name] = f
    cz = mesh.p[2, mesh.t].mean(axis=0)
    subs = {"body": np.arange(mesh.t.shape[1])}
    for name, (lo, hi) in (layers or {}).items():
        subs[name] = np.nonzero((cz > lo) & (cz < hi))[0]
    mesh = MeshTet(p, t, _boundaries=bnd, _subdomains=subs)
    pts = {"end_centre": np.array([xs.max(), 0.5 * (ys.min() + ys.max()), 0.5 * (zs.min() + zs.max())]),
           "origin": np.array([xs.min(), ys.min(), zs.min()])}
    return MeshBundle(mesh, pts, meta={"builder": "box", "shape": [len(xs) - 1, len(ys) - 1, len(zs) - 1]})


def _vertex(mesh, x) -> int:
    d = np.linalg.norm(mesh.p - np.asarray(x, dtype=float)[:, None], axis=0)
    i = int(np.argmin(d))
    if d[i] > 1e-9 * np.ptp(mesh.p):
        raise GeometryError(f"no vertex at {x}")
    return i


def support_321(model: ElasticModel, a, b, c) -> np.ndarray:
    """Full-vector DOF indices of a statically determinate support: vertex ``a`` fixed in x, y, z;
    ``b`` (on the x axis from a) in y, z; ``c`` (in the x-y plane) in z."""
    mesh = model.mesh
    nd = model.basis.nodal_dofs[0]  # vertex -> scalar node
    ia, ib, ic = (int(nd[_vertex(mesh, q)]) for q in (a, b, c))
    return np.array([3 * ia, 3 * ia + 1, 3 * ia + 2, 3 * ib + 1, 3 * ib + 2, 3 * ic + 2])


def free_block(a: float = 1e-3, b: float = 0.8e-3, t: float = 0.5e-3, n: int = 2,
               material: str | PiezoMaterial = "pzt-5h") -> PiezoModel:
    """A free block a x b x t poled +z, electrodes ``electrode_top`` (z = t) and
    ``electrode_bottom`` (z = 0, the reference), 3-2-1 supported (module docstring)."""
    mat = get_piezo_material(material)
    xs, ys, zs = np.linspace(0, a, n + 1), np.linspace(0, b, n + 1), np.linspace(0, t, n + 1)
    bundle = box_bundle(xs, ys, zs, planes={"electrode_top": (2, t), "electrode_bottom": (2, 0.0)})
    mech = ElasticModel(bundle, {"body": mat.elastic()}, clamp=(), tip="end_centre", name="free-block")
    fixed = support_321(mech, (0, 0, 0), (a, 0, 0), (0, b, 0))
    return PiezoModel(mech, {"body": (mat, "+z")}, electrodes=["electrode_top", "electrode_bottom"],
                      reference="electrode_bottom", fixed_dofs=fixed)


BIMORPH_CONFIGS = ("series", "parallel")


def bimorph_cantilever(length: float = 2e-3, width: float = 0.2e-3, thickness: float = 0.2e-3,
                       nx: int = 20, ny: int = 2, nz_layer: int = 1, config: str = "series",
                       material: str | PiezoMaterial = "pzt-5h", clamp: str = "full",
                       plane_strain: bool = False) -> PiezoModel:
    """Symmetric PZT bimorph cantilever (layers of ``thickness/2``), clamped at x = 0.

    Electrodes: ``electrode_top`` (z = h/2), ``electrode_middle`` (z = 0, interior),
    ``electrode_bottom`` (z = -h/2).  ``series``: upper layer poled +z, lower -z; drive with
    ``{"electrode_top": V}``, bottom grounded, middle floating.  ``parallel``: both poled +z;
    drive with ``{"electrode_middle": V}``, top and bottom grounded.  Tip = the area-averaged
    displacement of the end face ``x1``.

    ``clamp``: ``"full"`` (every DOF of the x = 0 face fixed: a rigid wall that also blocks the
    piezoelectric strains in y and z at the root) or ``"sliding"`` (beam-theory clamp: u_x = 0
    on the face, so the section stays plane and normal to the axis, u_y = 0 on its line y = 0 and
    u_z = 0 at its centre, so the section may deform freely in its own plane).
    ``plane_strain``: u_y = 0 everywhere (a slice of a wide plate in cylindrical bending: the
    exact setting of classical laminate theory with S_2 = 0).
    """
    if clamp not in ("full", "sliding"):
        raise ParameterError(f"bimorph clamp must be 'full' or 'sliding', got {clamp!r}")
    if config not in BIMORPH_CONFIGS:
        raise ParameterError(f"bimorph config must be 'series' or 'parallel', got {config!r}")
    mat = get_piezo_material(material)
    h = thickness
    xs = np.linspace(0, length, nx + 1)
    ys = np.linspace(-width / 2, width / 2, ny + 1)
    zs = np.linspace(-h / 2, h / 2, 2 * nz_layer + 1)
    bundle = box_bundle(xs, ys, zs, layers={"upper_layer": (0.0, h), "lower_layer": (-h, 0.0)},
                        planes={"electrode_top": (2, h / 2), "electrode_middle": (2, 0.0),
                                "electrode_bottom": (2, -h / 2)})
    el_mat = mat.elastic()
    mech = ElasticModel(bundle, {"body": el_mat}, clamp=["x0"] if clamp == "full" else [], tip="x1",
                        name=f"bimorph-{config}")
    fixed = np.zeros(0, dtype=np.int64) if clamp == "full" else sliding_clamp_dofs(mech, "x0", 0)
    if plane_strain:
        fixed = np.union1d(fixed, 3 * np.arange(mech.n_nodes) + 1)
    lower = "-z" if config == "series" else "+z"
    return PiezoModel(mech, {"upper_layer": (mat, "+z"), "lower_layer": (mat, lower)},
                      electrodes=["electrode_top", "electrode_middle", "electrode_bottom"],
                      reference="electrode_bottom", tip="x1", fixed_dofs=fixed)


def sliding_clamp_dofs(model: ElasticModel, face: str, axis: int = 0) -> np.ndarray:
    """DOFs of a beam-theory clamp on ``face`` (normal ``axis``): the normal displacement on the
    whole face (the section stays plane and normal to the axis: no rotation, no axial motion);
    the first transverse component on the face's centre line along the second transverse axis
    (blocks the in-plane translation and the rotation about ``axis``); the second transverse
    component at the face centre.  The section may deform freely in its own plane."""
    basis = model.basis
    nodes = np.unique(basis.get_dofs(facets=model.mesh.boundaries[face]).all())
    x = basis.doflocs[:, nodes]
    ext = np.ptp(basis.doflocs, axis=1).max()
    a1, a2 = [c for c in range(3) if c != axis]
    mid1 = 0.5 * (x[a1].min() + x[a1].max())
    mid2 = 0.5 * (x[a2].min() + x[a2].max())
    line = np.abs(x[a1] - mid1) < 1e-9 * ext  # the centre line along a2
    centre = line & (np.abs(x[a2] - mid2) < 1e-9 * ext)
    if not np.any(centre):
        raise GeometryError(f"sliding clamp on '{face}': no node at the face centre (use even divisions)")
    return np.unique(np.concatenate([3 * nodes + axis, 3 * nodes[line] + a1, 3 * nodes[centre] + a2]))


def bimorph_drive(config: str, volts: float = 1.0) -> tuple[dict[str, float | str], str]:
    """(electrode states, others) for the standard drive of :func:`bimorph_cantilever`."""
    if config == "series":
        return {"electrode_top": volts, "electrode_bottom": 0.0, "electrode_middle": "float"}, "ground"
    if config == "parallel":
        return {"electrode_middle": volts, "electrode_top": 0.0, "electrode_bottom": 0.0}, "ground"
    raise ParameterError(f"bimorph config must be 'series' or 'parallel', got {config!r}")


def bar_31(length: float = 10e-3, width: float = 1e-3, thickness: float = 0.5e-3, nx: int = 20, ny: int = 2,
           nz: int = 1, material: str | PiezoMaterial = "pzt-5h") -> PiezoModel:
    """Free length-extensional bar poled +z with electrodes on z = 0 (reference) and z = t."""
    mat = get_piezo_material(material)
    xs, ys, zs = np.linspace(0, length, nx + 1), np.linspace(0, width, ny + 1), np.linspace(0, thickness, nz + 1)
    bundle = box_bundle(xs, ys, zs, planes={"electrode_top": (2, thickness), "electrode_bottom": (2, 0.0)})
    mech = ElasticModel(bundle, {"body": mat.elastic()}, clamp=(), tip="x1", name="bar-31")
    return PiezoModel(mech, {"body": (mat, "+z")}, electrodes=["electrode_top", "electrode_bottom"],
                      reference="electrode_bottom", tip="x1")


def rod_33(length: float = 10e-3, side: float = 1e-3, nx: int = 20, ny: int = 2,
           material: str | PiezoMaterial = "pzt-5h") -> PiezoModel:
    """Free rod poled along its length (+x) with end electrodes x0 (reference) and x1."""
    mat = get_piezo_material(material)
    xs, ys, zs = np.linspace(0, length, nx + 1), np.linspace(0, side, ny + 1), np.linspace(0, side, ny + 1)
    bundle = box_bundle(xs, ys, zs, planes={"electrode_x1": (0, length), "electrode_x0": (0, 0.0)})
    mech = ElasticModel(bundle, {"body": (mat.elastic(), _rot_to_x())}, clamp=(), tip="x1", name="rod-33")
    return PiezoModel(mech, {"body": (mat, "+x")}, electrodes=["electrode_x1", "electrode_x0"],
                      reference="electrode_x0", tip="x1")


def _rot_to_x() -> np.ndarray:
    from probedyn.fem.piezo_materials import poling_rotation

    return poling_rotation("+x")




TUBE_LAYOUT = ("electrode_yp", "electrode_zp", "electrode_ym", "electrode_zm", "electrode_inner")


def tube_cantilever(Re: float | None = None, Ri: float | None = None, length: float | None = None, n_wall: int = 1,
                    element_size: float | None = None, delta_y: float = 0.0, delta_z: float = 0.0,
                    clamp: str = "full", material: str | PiezoMaterial = "pzt-5h") -> PiezoModel:
    """The bare piezotube (no holder) of :mod:`probedyn.meshes.piezotube`, radially poled, with the
    quartered layout (inner electrode = reference), clamped at x = 0 (``clamp = "full"``: all
    DOFs of the end face; ``"sliding"``: u_x on the face, the face free to deform in its plane
    (u_z on the y = 0 line, u_y at two points of the z = 0 line blocking the rigid in-plane
    motion: see :func:`sliding_clamp_dofs`)).  Tip = the area-averaged tube end ``tube_end``.
    ``Re``, ``Ri``, ``length`` default to the piezotube preset (Table 3.2 as corrected)."""
    from probedyn.core.presets import preset

    t32 = preset("table-3.2")
    Re = t32["R_e"] if Re is None else Re
    Ri = t32["R_i"] if Ri is None else Ri
    length = t32["L"] if length is None else length
    from probedyn.fem.materials import radial_poling
    from probedyn.meshes.cache import MeshOptions
    from probedyn.meshes.piezotube import piezotube_mesh

    if clamp not in ("full", "sliding"):
        raise ParameterError(f"tube clamp must be 'full' or 'sliding', got {clamp!r}")
    mat = get_piezo_material(material)
    bundle = piezotube_mesh({"Re": Re, "Ri": Ri, "length": length, "delta_y": delta_y, "delta_z": delta_z,
                             "holder": "point"}, MeshOptions(element_size, int(n_wall)))
    Rr = radial_poling(axis_point=(0.0, 0.0, 0.0), axis_dir=(1.0, 0.0, 0.0))
    mech = ElasticModel(bundle, {"tube": (mat.elastic(), Rr)}, clamp=["clamp"] if clamp == "full" else [],
                        tip="tube_end", name="tube")
    fixed = np.zeros(0, dtype=np.int64) if clamp == "full" else _tube_sliding(mech)
    return PiezoModel(mech, {"tube": (mat, Rr)}, electrodes=list(TUBE_LAYOUT), reference="electrode_inner",
                      tip="tube_end", fixed_dofs=fixed)


def _tube_sliding(mech: ElasticModel) -> np.ndarray:
    """u_x on the clamp face; u_z at the nodes of the face on the y axis (y != 0, z = 0 ... the
    two wall crossings of the z = 0 line carry u_y = 0 only at one of them)."""
    basis = mech.basis
    nodes = np.unique(basis.get_dofs(facets=mech.mesh.boundaries["clamp"]).all())
    x = basis.doflocs[:, nodes]
    ext = np.ptp(basis.doflocs, axis=1).max()
    on_y = np.abs(x[2]) < 1e-9 * ext  # the two wall crossings of the y axis (z = 0)
    on_z = np.abs(x[1]) < 1e-9 * ext  # ... of the z axis (y = 0)
    if not (np.any(on_y) and np.any(on_z)):
        raise GeometryError("sliding tube clamp: no nodes on the y or z axis of the clamp face")
    # block in-plane rigid motion: u_z = 0 on the y-axis nodes (symmetric about z = 0) and
    # u_y = 0 on the z-axis nodes; this also blocks the rotation about x
    return np.unique(np.concatenate([3 * nodes, 3 * nodes[on_y] + 2, 3 * nodes[on_z] + 1]))


__all__ = ["box_bundle", "support_321", "free_block", "bimorph_cantilever", "bimorph_drive", "bar_31", "rod_33",
           "tube_cantilever", "sliding_clamp_dofs", "TUBE_LAYOUT",
           "BIMORPH_CONFIGS"]
