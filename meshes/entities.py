"""Faster construction of a scikit-fem mesh's facets and edges (identical arrays).

scikit-fem builds the facets (``mesh.facets``, ``mesh.t2f``) and edges (``mesh.edges``,
``mesh.t2e``) of a mesh on first use with ``np.unique(..., axis=1)`` over the sorted vertex
tuples of every element's facets and edges.  ``unique`` along an axis views each column as a
structured (void) record and sorts the records field by field: at 265k DOFs (P2 tetrahedra,
~44k vertices, ~180k tetrahedra) this took ~1 s of the model's set-up, more than the
compiled assembly of K.

:func:`ensure_entities` computes the same arrays by encoding every sorted tuple ``(a, b[, c])``
of vertex indices as one int64 key ``(a n + b) n + c`` (``n`` = number of vertices, so the
integer order of the keys is the lexicographic order of the tuples that ``unique(axis=1)``
uses) and taking ``np.unique`` of the 1-D keys with the same stable sort: the entities, their
order, the element-to-entity maps and the first-occurrence indices are identical (asserted
against scikit-fem's own ``build_entities`` in tests/test_mesh_entities.py).  Meshes whose keys
would overflow int64 (more than 2^21 vertices for facets of three vertices, never reached
here), meshes that already have the arrays and mesh types that build them differently
(``MeshHex`` keeps its facets' vertex order) are left to scikit-fem.
"""

from __future__ import annotations

import numpy as np


def tuple_keys(s: np.ndarray, n: int) -> np.ndarray:
    """One int64 key ``(a n + b) n + c`` per column of sorted vertex tuples ``s`` (k, m): the
    integer order of the keys is the lexicographic order of the tuples (``n`` > every index)."""
    s = np.asarray(s, dtype=np.int64)
    key = s[0].copy()
    for r in s[1:]:
        key *= n
        key += r
    return key


def _entities(t: np.ndarray, indices, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(sorted entity vertex tuples (k, m), element-to-entity map (len(indices), nel)) as
    scikit-fem's ``Mesh.build_entities(t, indices, sort=True)``."""
    idx = np.hstack(tuple(t[ix] for ix in indices))  # (k, len(indices) * nel)
    s = np.sort(idx, axis=0).astype(np.int64)
    key = tuple_keys(s, n)
    # the stable (merge) sort of np.unique with return_index: first occurrences, as unique(axis=1)
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    ents = np.ascontiguousarray(s[:, first].astype(t.dtype, copy=False))
    return ents, inverse.reshape(len(indices), t.shape[1])


def ensure_entities(mesh) -> None:
    """Build ``mesh``'s facets and edges (``_facets``, ``_t2f``, ``_edges``, ``_t2e``) by sorted
    int64 keys unless it has them already (module docstring); a mesh of another layout (not
    scikit-fem's attribute names, or keys that would overflow) is left untouched."""
    from skfem.mesh import Mesh

    if not isinstance(mesh, Mesh) or getattr(mesh.elem, "refdom", None) is None:
        return
    ref = mesh.elem.refdom
    t = mesh.t
    n = int(mesh.p.shape[1]) if t.size == 0 else max(int(mesh.p.shape[1]), int(t.max()) + 1)
    for attr, maps, init, indices in (("_facets", "_t2f", "_init_facets", getattr(ref, "facets", None)),
                                      ("_edges", "_t2e", "_init_edges", getattr(ref, "edges", None))):
        # only where the mesh type builds them with the base class's sorted entities (MeshHex keeps
        # its facets' vertex order: sort=False, left to scikit-fem)
        if indices is None or hasattr(mesh, attr) or getattr(type(mesh), init, None) is not getattr(Mesh, init, None):
            continue
        width = len(indices[0])
        if float(n) ** width >= 2.0**63:
            continue
        ents, m = _entities(t, indices, n)
        setattr(mesh, attr, ents)
        setattr(mesh, maps, m)


__all__ = ["ensure_entities", "tuple_keys"]
