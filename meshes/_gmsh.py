"""Shared gmsh helpers: a guarded in-process session, extraction of the mesh with its physical
groups into a scikit-fem :class:`~skfem.MeshTet`, and export through meshio.

Every geometry builder follows the same pattern::

    with gmsh_session("cantilever"):
        occ = gmsh.model.occ
        ...                                   # OpenCASCADE solids
        occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [vol], name="body")
        gmsh.model.addPhysicalGroup(2, [face], name="clamp")
        set_mesh_size(h)
        gmsh.model.mesh.generate(3)
        raw = extract_tet_mesh()              # -> RawMesh (numpy only)
    mesh = raw.to_skfem()

The physical-group names become ``mesh.subdomains`` (3D groups) and ``mesh.boundaries``
(2D groups).  Meshes are first order (straight-sided 4-node tetrahedra); quadratic fields are
built on them by scikit-fem (``ElementTetP2``).
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import meshio
import numpy as np
from skfem import MeshTet
from skfem.quadrature import get_quadrature

from probedyn.core.errors import GeometryError
from probedyn.core.io import atomic_path
from probedyn.meshes.entities import ensure_entities, tuple_keys

_LOCK = threading.RLock()


@contextlib.contextmanager
def gmsh_session(model_name: str = "probedyn", verbose: bool = False) -> Iterator[object]:
    """Initialise gmsh (no GUI, no signal handlers, quiet), yield the module, always finalise.

    A re-entrant lock serialises sessions within one process (gmsh has global state).
    If gmsh was already initialised by the caller, the session reuses it with a fresh model
    and does not finalise it.  The calling thread's OpenMP thread count is put back on exit:
    gmsh's HXT mesher sets it to its own (1) and leaves it, and PARDISO's factorisation in this
    thread then disagreed with its analysis in a background thread (:func:`set_mesher_3d`).
    """
    # gmsh is imported inside the builders only: it loads system GL libraries (libGLU, Xcursor,
    # ...) that a machine may lack, and a cached mesh (meshes.cache) is read without it.
    import gmsh

    from probedyn.core.signals import reassert_handlers

    omp_threads = _omp_max_threads(gmsh)
    with _LOCK:
        owner = not gmsh.isInitialized()
        if owner:
            gmsh.initialize(interruptible=False)
            reassert_handlers()  # gmsh resets SIGTERM/SIGHUP to the default action
        try:
            gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
            gmsh.option.setNumber("General.Verbosity", 2 if verbose else 0)
            # every session starts on gmsh's default 3D mesher: a reused gmsh keeps its options, and
            # only the builders that choose by size (set_mesher_3d) may use HXT
            gmsh.option.setNumber("Mesh.Algorithm3D", MESHERS_3D["delaunay"])
            gmsh.model.add(model_name)
            yield gmsh
        except Exception as exc:
            if type(exc) is not Exception:  # gmsh raises bare Exceptions; anything else is ours
                raise
            msg = str(exc).splitlines()[0] if str(exc) else repr(exc)
            raise GeometryError(f"gmsh failed for '{model_name}': {msg}") from exc
        finally:
            with contextlib.suppress(Exception):
                gmsh.model.remove()
            if owner:
                gmsh.finalize()
                reassert_handlers()
            if omp_threads is not None:
                gmsh.lib.omp_set_num_threads(omp_threads)


def _omp_max_threads(gmsh) -> int | None:
    """The calling thread's OpenMP ``max threads`` in gmsh's OpenMP runtime (None if gmsh has none)."""
    try:
        return int(gmsh.lib.omp_get_max_threads())
    except AttributeError:  # a gmsh built without OpenMP
        return None


def set_mesh_size(h_max: float, h_min: float | None = None) -> None:
    """Uniform characteristic length ``h_max`` [m] (``h_min`` defaults to h_max / 10)."""
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMax", float(h_max))
    gmsh.option.setNumber("Mesh.MeshSizeMin", float(h_min if h_min is not None else h_max / 10))
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.Optimize", 1)


# gmsh's 3D mesher by size (session 9, issue 15; docs/fem.md "Session 9"). HXT (Marot et al.
# 2019, gmsh's Mesh.Algorithm3D = 10), run on one thread (deterministic), meshes a large box ~4x
# faster than the default Delaunay (1) with a better worst tetrahedron (minSICN 0.35 vs 0.25 at
# 265k DOFs) but ~9 % fewer tetrahedra at the same size, so it would change every mesh's
# frequencies: it is used only where the predicted tetrahedron count exceeds HXT_MIN_TETS, far
# above every default probe, report and test mesh (the largest, 4 layers through the default
# cantilever, predicts 34,560), i.e. for benchmark-sized models whose mesh phase matters.
HXT_MIN_TETS = 50_000
MESHERS_3D = {"delaunay": 1, "hxt": 10}


def mesher_3d(predicted_tets: float) -> str:
    """The 3D mesher for a mesh of ``predicted_tets`` tetrahedra: ``'hxt'`` above HXT_MIN_TETS."""
    return "hxt" if predicted_tets > HXT_MIN_TETS else "delaunay"


def set_mesher_3d(name: str) -> None:
    """Select gmsh's 3D algorithm by name (see :data:`MESHERS_3D`).

    HXT runs on gmsh's default ``General.NumThreads`` = 1 (its meshes depend on the thread
    count) and sets the calling thread's OpenMP thread count to it; :func:`gmsh_session` puts
    the count back. Without that, PARDISO's factorisation in this thread ran with another thread
    count than its analysis in the background thread (``fem.eigen.Analysis``): the float32 factor
    of the 265k model came out so poor that the mixed eigen-solver stalled (3 of 3 runs;
    session 9, ``tests/test_mesh_cantilever.py``)."""
    import gmsh

    gmsh.option.setNumber("Mesh.Algorithm3D", MESHERS_3D[name])


def entities_in_box(dim: int, xmin, xmax, tol: float) -> list[int]:
    """Tags of entities of dimension ``dim`` inside the box [xmin - tol, xmax + tol]."""
    import gmsh

    ents = gmsh.model.getEntitiesInBoundingBox(
        xmin[0] - tol, xmin[1] - tol, xmin[2] - tol, xmax[0] + tol, xmax[1] + tol, xmax[2] + tol, dim
    )
    return [tag for _, tag in ents]


@dataclass
class RawMesh:
    """A first-order tetrahedral mesh as plain arrays.

    ``points`` (n, 3); ``tets`` (m, 4) 0-based; ``subdomains`` {name: element indices};
    ``boundary_tris`` {name: (k, 3) vertex indices of the boundary triangles}.
    """

    points: np.ndarray
    tets: np.ndarray
    subdomains: dict[str, np.ndarray] = field(default_factory=dict)
    boundary_tris: dict[str, np.ndarray] = field(default_factory=dict)

    def to_skfem(self):
        """A :class:`skfem.MeshTet` with ``subdomains`` and ``boundaries`` (facet indices)."""
        p = np.ascontiguousarray(self.points.T, dtype=float)
        t = np.ascontiguousarray(self.tets.T, dtype=np.int64)
        mesh = MeshTet(p, t)
        ensure_entities(mesh)
        # fix orientation-independent facet lookup: encode sorted vertex triples
        n = int(mesh.p.shape[1])
        keys = tuple_keys(np.sort(mesh.facets, axis=0), n)
        order = np.argsort(keys)
        sk = keys[order]
        boundaries: dict[str, np.ndarray] = {}
        for name, tris in self.boundary_tris.items():
            tr = np.sort(np.asarray(tris, dtype=np.int64), axis=1)
            q = tuple_keys(tr.T, n)
            pos = np.searchsorted(sk, q)
            pos = np.clip(pos, 0, len(sk) - 1)
            ok = sk[pos] == q
            if not ok.all():
                raise GeometryError(f"boundary group '{name}': {np.count_nonzero(~ok)} triangles are not mesh facets")
            boundaries[name] = np.sort(order[pos])
        subdomains = {k: np.sort(np.asarray(v, dtype=np.int64)) for k, v in self.subdomains.items()}
        out = MeshTet(p, t, _boundaries=boundaries or None, _subdomains=subdomains or None)
        for attr in ("_facets", "_t2f", "_edges", "_t2e"):  # same p and t: the entities carry over
            if hasattr(mesh, attr):
                setattr(out, attr, getattr(mesh, attr))
        return out


def extract_tet_mesh() -> RawMesh:
    """Read the current gmsh model's linear tetrahedra and its physical groups.

    Unused nodes (e.g. geometry-only points) are dropped and the numbering compacted.
    """
    import gmsh

    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3)
    tag_to_idx = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
    tag_to_idx[node_tags.astype(np.int64)] = np.arange(node_tags.size)

    # all tets, keeping their element tags for the physical groups
    etypes, etags, enodes = gmsh.model.mesh.getElements(3)
    tet_tags, tet_nodes = [], []
    for et, tg, nd in zip(etypes, etags, enodes):
        if et != 4:
            raise GeometryError(f"expected linear tetrahedra (gmsh type 4), got element type {et}")
        tet_tags.append(tg)
        tet_nodes.append(nd.reshape(-1, 4))
    if not tet_tags:
        raise GeometryError("gmsh produced no tetrahedra (is the geometry a closed solid?)")
    tet_tags = np.concatenate(tet_tags).astype(np.int64)
    tets = tag_to_idx[np.concatenate(tet_nodes).astype(np.int64)]

    # compact node numbering to the nodes used by tets
    used = np.unique(tets)
    remap = np.full(node_tags.size, -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    points = coords[used]
    tets = remap[tets]

    order = np.argsort(tet_tags)
    subdomains: dict[str, np.ndarray] = {}
    boundary_tris: dict[str, np.ndarray] = {}
    for dim, ptag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, ptag) or f"group{dim}_{ptag}"
        ents = gmsh.model.getEntitiesForPhysicalGroup(dim, ptag)
        if dim == 3:
            idx = []
            for e in ents:
                _, tg, _ = gmsh.model.mesh.getElements(3, int(e))
                if tg:
                    t = np.concatenate(tg).astype(np.int64)
                    idx.append(order[np.searchsorted(tet_tags[order], t)])
            subdomains[name] = np.concatenate(idx) if idx else np.zeros(0, dtype=np.int64)
        elif dim == 2:
            tris = []
            for e in ents:
                ets, _, nds = gmsh.model.mesh.getElements(2, int(e))
                for et, nd in zip(ets, nds):
                    if et != 2:
                        raise GeometryError(f"expected linear triangles on surface {e}, got type {et}")
                    tris.append(remap[tag_to_idx[nd.reshape(-1, 3).astype(np.int64)]])
            boundary_tris[name] = np.concatenate(tris) if tris else np.zeros((0, 3), dtype=np.int64)
    return RawMesh(points, tets, subdomains, boundary_tris)


def export_meshio(mesh, path: str | Path, file_format: str | None = None) -> Path:
    """Write a scikit-fem tet mesh with a ``region`` cell field (index into sorted subdomain
    names) through meshio, in any format meshio knows (by suffix: .vtu, .msh, .xdmf, ...)."""
    path = Path(path)
    region = np.full(mesh.t.shape[1], -1, dtype=np.int32)
    for i, name in enumerate(sorted(mesh.subdomains or {})):
        region[mesh.subdomains[name]] = i
    m = meshio.Mesh(mesh.p.T, [("tetra", mesh.t.T)], cell_data={"region": [region]})
    with atomic_path(path) as tmp:
        meshio.write(tmp, m, file_format=file_format or _meshio_format(path))
    return path


def _meshio_format(path: Path) -> str:
    ext = path.suffix.lower()
    fmts = meshio.extension_to_filetypes.get(ext)
    if not fmts:
        raise GeometryError(f"{path}: unknown mesh file suffix '{ext}'")
    return fmts[0]


def element_volumes(mesh) -> np.ndarray:
    """Volumes [m^3] of the elements: straight tetrahedra (a MeshTet), or hexahedra (MeshHex,
    trilinear; MeshHex2, curved: 3 x 3 x 3 Gauss points, exact for the trilinear Jacobian)."""
    if mesh.t.shape[0] == 8:
        X, W = get_quadrature(type(mesh).elem().refdom, 5)
        return np.abs(mesh._mapping().detDF(X)) @ W
    p = mesh.p[:, mesh.t]  # (3, 4, nel)
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    return np.abs(np.einsum("ie,ie->e", a, np.cross(b, c, axis=0))) / 6.0


def region_volumes(mesh, names) -> dict[str, float]:
    """Volume [m^3] of each named subdomain of a mesh (names the mesh lacks are left out)."""
    vol = element_volumes(mesh)
    return {n: float(vol[mesh.subdomains[n]].sum()) for n in names if n in (mesh.subdomains or {})}
