"""Mesh cache: meshes are built once per parameter set and stored by a hash of the parameters.

Cache folder: ``$PROBEDYN_CACHE`` (default ``~/.cache/probedyn/meshes``).  A cached mesh is one
``.npz`` file holding the vertex coordinates, the tetrahedra, the physical groups (subdomains
as element indices, boundaries as facet indices) and the named points; it is written
atomically, so concurrent runs never read half a file.  Exports to other formats go through
meshio (:meth:`MeshBundle.export`).
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from skfem import MeshHex, MeshHex2, MeshTet

from probedyn.core.errors import DataFormatError, ParameterError
from probedyn.core.io import atomic_path, to_jsonable
from probedyn.meshes._gmsh import element_volumes, export_meshio

#: Bump when the mesh format or a builder's meaning changes (invalidates old cache entries).
CACHE_VERSION = 2


@dataclass(frozen=True)
class MeshOptions:
    """Meshing controls shared by all geometries.

    ``element_size`` [m]: target edge length (None: derived from ``elements_through_thickness``);
    ``elements_through_thickness``: number of element layers across the thinnest dimension;
    the effective size is ``min(element_size, thinnest / elements_through_thickness)``.
    ``optimize``: gmsh tet-quality optimisation.
    """

    element_size: float | None = None
    elements_through_thickness: int = 2
    optimize: bool = True

    def size_for(self, thinnest: float) -> float:
        if self.elements_through_thickness < 1:
            raise ParameterError("elements_through_thickness must be at least 1")
        h = thinnest / self.elements_through_thickness
        if self.element_size is not None:
            if not (self.element_size > 0):
                raise ParameterError(f"element_size must be positive, got {self.element_size}")
            h = min(h, float(self.element_size))
        return h

    def as_dict(self) -> dict[str, Any]:
        return {
            "element_size": self.element_size,
            "elements_through_thickness": int(self.elements_through_thickness),
            "optimize": bool(self.optimize),
        }


@dataclass
class MeshBundle:
    """A meshed geometry ready for :class:`probedyn.fem.model.ElasticModel`.

    ``mesh``: :class:`skfem.MeshTet` (straight 4-node tets), :class:`skfem.MeshHex`
    (trilinear 8-node hexahedra) or :class:`skfem.MeshHex2` (curved 27-node hexahedra; both
    from ``meshes/structured.py``) with ``.subdomains``
    {group name: element indices} and ``.boundaries`` {group name: facet indices};
    ``points``: named points {name: (3,) coordinates [m]}, e.g. ``"tip"``;
    ``key``: hash of the builder name and parameters; ``path``: cache file (or None);
    ``meta``: free-form description (builder name, parameters).
    """

    mesh: Any
    points: dict[str, np.ndarray] = field(default_factory=dict)
    key: str = ""
    path: Path | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def element(self) -> str | None:
        """The element kind the mesh was built for (``meta["element"]``; None = the mesh
        type's default, see :mod:`probedyn.fem.assembly`)."""
        return self.meta.get("element")

    @property
    def n_vertices(self) -> int:
        return int(self.mesh.p.shape[1])

    @property
    def n_elements(self) -> int:
        return int(self.mesh.t.shape[1])

    def element_volumes(self) -> np.ndarray:
        """Volumes [m^3] of the elements."""
        return element_volumes(self.mesh)

    def export(self, path: str | Path) -> Path:
        """Write the mesh (with a ``region`` cell field) through meshio; format by suffix."""
        return export_meshio(self.mesh, path)

    # ---- persistence -------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        path = Path(path)
        cell = "hex2" if isinstance(self.mesh, MeshHex2) else ("hex" if isinstance(self.mesh, MeshHex) else "tet")
        arrays: dict[str, np.ndarray] = {"p": self.mesh.doflocs if cell == "hex2" else self.mesh.p, "t": self.mesh.t,
                                         "cell": np.array(cell)}
        for name, idx in (self.mesh.subdomains or {}).items():
            arrays[f"sub::{name}"] = np.asarray(idx)
        for name, idx in (self.mesh.boundaries or {}).items():
            arrays[f"bnd::{name}"] = np.asarray(idx)
        for name, x in self.points.items():
            arrays[f"pt::{name}"] = np.asarray(x, dtype=float)
        arrays["meta"] = np.array(json.dumps(to_jsonable({"key": self.key, "meta": self.meta, "version": CACHE_VERSION})))
        with atomic_path(path, defer=False) as tmp:  # a cache entry: kept even if the run fails
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)
        return path

    @classmethod
    def load(cls, path: str | Path) -> "MeshBundle":
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except (OSError, ValueError) as exc:
            raise DataFormatError(f"{path}: not a probedyn mesh file ({exc})") from None
        if "p" not in data or "t" not in data:
            raise DataFormatError(f"{path}: not a probedyn mesh file (no p/t arrays)")
        sub = {k[5:]: v for k, v in data.items() if k.startswith("sub::")}
        bnd = {k[5:]: v for k, v in data.items() if k.startswith("bnd::")}
        pts = {k[4:]: v for k, v in data.items() if k.startswith("pt::")}
        info = json.loads(str(data["meta"])) if "meta" in data else {}
        mesh_type = {"hex": MeshHex, "hex2": MeshHex2}.get(str(data["cell"]) if "cell" in data else "tet", MeshTet)
        mesh = mesh_type(data["p"], data["t"], _boundaries=bnd or None, _subdomains=sub or None)
        return cls(mesh, pts, info.get("key", ""), path, info.get("meta", {}))


def _usable(d: Path) -> None:
    """Raise OSError unless ``d`` is (or can be made) a folder this process can write in."""
    d.mkdir(parents=True, exist_ok=True)
    if not d.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "not a folder", str(d))
    if not os.access(d, os.W_OK | os.X_OK):
        raise PermissionError(errno.EACCES, "not writable", str(d))


def cache_dir() -> Path:
    """``$PROBEDYN_CACHE`` or ``~/.cache/probedyn/meshes`` (created on demand).

    An unusable ``$PROBEDYN_CACHE`` (a file, a read-only or forbidden folder) is a one-line
    :class:`~probedyn.core.errors.OutputError`: the user asked for it. An unusable default
    location (a read-only home) falls back to a folder in the system's temporary directory.
    """
    from probedyn.core.errors import OutputError

    env = os.environ.get("PROBEDYN_CACHE")
    if env:
        d = Path(env)
        try:
            _usable(d)
        except OSError as exc:
            reason = "it is a file" if isinstance(exc, (FileExistsError, NotADirectoryError)) else (
                exc.strerror or type(exc).__name__).lower()
            raise OutputError(f"PROBEDYN_CACHE={env} is not a usable folder ({reason}); point it at a "
                              "writable folder or unset it") from None
        return d
    d = Path.home() / ".cache" / "probedyn" / "meshes"
    try:
        _usable(d)
    except OSError:
        d = Path(tempfile.gettempdir()) / f"probedyn-cache-{os.getuid()}" / "meshes"
        _usable(d)
    return d


def params_key(builder_name: str, params: dict[str, Any]) -> str:
    """Stable hash of a builder name and its (JSON-able) parameters."""
    blob = json.dumps(
        {"builder": builder_name, "params": to_jsonable(params), "v": CACHE_VERSION},
        sort_keys=True, separators=(",", ":"),
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def cached_mesh(
    builder_name: str,
    params: dict[str, Any],
    build_fn: Callable[[dict[str, Any]], MeshBundle],
    use_cache: bool = True,
) -> MeshBundle:
    """Return the mesh for ``params``, building it with ``build_fn(params)`` on a cache miss.

    ``params`` must contain everything the geometry and mesh depend on (including the mesh
    options); it is hashed with ``builder_name``.  A corrupt cache file is rebuilt.
    """
    key = params_key(builder_name, params)
    if use_cache:
        path = cache_dir() / f"{builder_name}-{key}.npz"
        if path.exists():
            try:
                b = MeshBundle.load(path)
                if b.key == key:
                    return b
            except Exception:  # corrupt or stale: rebuild below
                pass
    bundle = build_fn(params)
    bundle.key = key
    bundle.meta = {"builder": builder_name, "params": params, **bundle.meta}
    if use_cache:
        from probedyn.core.errors import OutputError

        try:
            bundle.path = bundle.save(cache_dir() / f"{builder_name}-{key}.npz")
        except OutputError:  # a full disk under the cache: the mesh is still good, just not kept
            bundle.path = None
    return bundle
