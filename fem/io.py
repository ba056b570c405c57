"""Writing modal results: VTU (meshio, quadratic tetrahedra or hexahedra with one displacement
field per mode) and a JSON summary (no mode shapes).

The VTU holds the P2 nodes (vertices + edge midpoints) as points and ``tetra10`` cells in
VTK's node order (4 vertices, then the edges 01, 12, 02, 03, 13, 23), so ParaView and
pyvista show the quadratic field.  Point fields: ``mode_01`` ... (3 components, mass-
normalised, in m/sqrt(kg)); cell field ``region`` (index into the alphabetically sorted
region names, which the JSON summary lists under ``model.regions``).
"""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np

from probedyn.core.errors import DataFormatError
from probedyn.core.io import atomic_path, write_json

# VTK tetra10 edge order as vertex pairs
_VTK_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


def tetra10_connectivity(mesh, basis) -> np.ndarray:
    """(nel, 10) P2 node indices in VTK tetra10 order (checked by coordinates)."""
    ed = basis.element_dofs.T  # (nel, 10): 4 vertex dofs then 6 edge dofs (skfem edge order)
    x = basis.doflocs
    conn = np.empty_like(ed)
    conn[:, :4] = ed[:, :4]
    mids = x[:, ed[:, 4:]]  # (3, nel, 6)
    for k, (a, b) in enumerate(_VTK_EDGES):
        target = 0.5 * (x[:, ed[:, a]] + x[:, ed[:, b]])  # (3, nel)
        d = np.linalg.norm(mids - target[:, :, None], axis=0)  # (nel, 6)
        j = np.argmin(d, axis=1)
        conn[:, 4 + k] = ed[np.arange(ed.shape[0]), 4 + j]
    return conn


# VTK hexahedron vertex order = scikit-fem MeshHex order permuted (skfem.io.meshio.HEX_MAPPING)
_VTK_HEX_VERTS = (0, 3, 6, 2, 1, 5, 7, 4)
# VTK hexahedron20 / hexahedron27 edges (vertex pairs in VTK order) and hexahedron27 faces
_VTK_HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))
_VTK_HEX_FACES = ((0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2), (0, 3, 2, 1), (4, 5, 6, 7))


def _nearest(ed: np.ndarray, x: np.ndarray, cand: slice, target: np.ndarray) -> np.ndarray:
    """Per element, the DOF among ``ed[:, cand]`` nearest to ``target`` (3, nel)."""
    pos = x[:, ed[:, cand]]  # (3, nel, k)
    j = np.argmin(np.linalg.norm(pos - target[:, :, None], axis=0), axis=1)
    return ed[:, cand][np.arange(ed.shape[0]), j]


def hexahedron_connectivity(mesh, basis) -> tuple[str, np.ndarray]:
    """(meshio cell type, (nel, 20 | 27) node indices in VTK order) of a quadratic hexahedral basis:
    vertices in VTK order, then edge nodes (and face and centre nodes for 27) matched by their
    positions (the parametric mid-points: mid-edge of the straight edge for trilinear geometry;
    for curved geometry the node nearest to it)."""
    ed = basis.element_dofs.T  # (nel, nb): 8 vertex dofs first
    x = basis.doflocs
    nb = ed.shape[1]
    v = ed[:, list(_VTK_HEX_VERTS)]
    cols = [v]
    for a, b in _VTK_HEX_EDGES:
        cols.append(_nearest(ed, x, slice(8, 20), 0.5 * (x[:, v[:, a]] + x[:, v[:, b]]))[:, None])
    if nb == 27:
        for f in _VTK_HEX_FACES:
            cols.append(_nearest(ed, x, slice(20, 26), 0.25 * sum(x[:, v[:, k]] for k in f))[:, None])
        cols.append(ed[:, 26:27])
    return ("hexahedron20" if nb == 20 else "hexahedron27"), np.hstack(cols)


def cell_connectivity(model) -> tuple[str, np.ndarray]:
    """(meshio cell type, connectivity) of a model's quadratic elements in VTK node order."""
    basis = model.basis
    nb = basis.element_dofs.shape[0]
    if nb == 10:
        return "tetra10", tetra10_connectivity(model.mesh, basis)
    return hexahedron_connectivity(model.mesh, basis)


def write_modes_vtu(result, path: str | Path) -> Path:
    """Write the mesh and every mode's displacement field to ``path`` (.vtu) atomically
    (``tetra10`` cells for P2 tetrahedra, ``hexahedron20`` / ``hexahedron27`` for hexahedra)."""
    model = result.model
    if model is None:
        raise DataFormatError("modal result has no model attached; cannot write VTU")
    basis = model.basis
    ctype, conn = cell_connectivity(model)
    n = basis.N
    point_data = {}
    for m in result.modes:
        point_data[f"mode_{m.index:02d}"] = m.shape.reshape(n, 3)
    order = sorted(range(len(model.region_names)), key=lambda i: model.region_names[i])
    rank = np.empty(len(order), dtype=np.int32)
    rank[order] = np.arange(len(order))
    cell_data = {"region": [rank[model.elem_region].astype(np.int32)]}
    mesh = meshio.Mesh(basis.doflocs.T, [(ctype, conn)], point_data=point_data, cell_data=cell_data)
    path = Path(path)
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return path


def read_modes_vtu(path: str | Path):
    """Read a VTU written by :func:`write_modes_vtu`: returns (points (n,3), cells (m, 10 | 20 | 27)
    (tetra10, hexahedron20 or hexahedron27), {field name: (n, 3)})."""
    try:
        m = meshio.read(path)
    except Exception as exc:
        raise DataFormatError(f"{path}: cannot read VTU ({exc})") from None
    cells = next((m.cells_dict[k] for k in ("tetra10", "hexahedron20", "hexahedron27") if k in m.cells_dict), None)
    if cells is None:
        raise DataFormatError(f"{path}: no tetra10 or quadratic hexahedron cells")
    return m.points, cells, dict(m.point_data)


def write_modes_json(result, path: str | Path) -> Path:
    """JSON summary (frequencies, families, effective masses, participation, energy shares,
    DOFs, timings) written atomically."""
    return write_json(path, result.to_dict())
