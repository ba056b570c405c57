"""Writing modal results: VTU (meshio, quadratic tetrahedra with one displacement field per
mode) and a JSON summary (no mode shapes).

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


def write_modes_vtu(result, path: str | Path) -> Path:
    """Write the mesh and every mode's displacement field to ``path`` (.vtu) atomically."""
    model = result.model
    if model is None:
        raise DataFormatError("modal result has no model attached; cannot write VTU")
    basis = model.basis
    conn = tetra10_connectivity(model.mesh, basis)
    n = basis.N
    point_data = {}
    for m in result.modes:
        point_data[f"mode_{m.index:02d}"] = m.shape.reshape(n, 3)
    order = sorted(range(len(model.region_names)), key=lambda i: model.region_names[i])
    rank = np.empty(len(order), dtype=np.int32)
    rank[order] = np.arange(len(order))
    cell_data = {"region": [rank[model.elem_region].astype(np.int32)]}
    mesh = meshio.Mesh(basis.doflocs.T, [("tetra10", conn)], point_data=point_data, cell_data=cell_data)
    path = Path(path)
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return path


def read_modes_vtu(path: str | Path):
    """Read a VTU written by :func:`write_modes_vtu`: returns (points (n,3), tetra10 (m,10),
    {field name: (n, 3)})."""
    try:
        m = meshio.read(path)
    except Exception as exc:
        raise DataFormatError(f"{path}: cannot read VTU ({exc})") from None
    cells = m.cells_dict.get("tetra10")
    if cells is None:
        raise DataFormatError(f"{path}: no tetra10 cells")
    return m.points, cells, dict(m.point_data)


def write_modes_json(result, path: str | Path) -> Path:
    """JSON summary (frequencies, families, effective masses, participation, energy shares,
    DOFs, timings) written atomically."""
    return write_json(path, result.to_dict())
