"""Structured hexahedral meshes of prismatic probe parts (numpy, no gmsh).

A probe body that is a union of axis-aligned boxes (the cantilever beam, the bimorph layers
with their electrode strips and the holder block) is meshed as a tensor grid: breakpoints per
axis (every face of every box lies on a breakpoint), a number of elements per interval, and a
region name (or None = no material) per grid block.  A tube (the piezotube) is meshed in
cylindrical block coordinates by :func:`ring_grid`: angle sectors x radial layers x axial
intervals, the nodes of each radial layer interpolated between two circles (an eccentric bore
moves the inner circle only).

Elements are trilinear 8-node hexahedra (scikit-fem ``MeshHex``; vertex order of
``MeshHex.init_tensor``); on a box grid every element is a rectangular box, so the quadratic
fields (serendipity ``ElementHexS2`` or Lagrange ``ElementHex2``) are integrated exactly
(``probedyn.fem.assembly``).  Physical groups:

* subdomains = the region names of the blocks (elements), plus unions given by the caller;
* boundaries = facets whose vertices all lie in a closed box (and, unless ``interior`` is
  allowed for the group, on the boundary of the mesh): the same "entities in a box" rule the
  gmsh builders use, so the tagged faces (clamp, free_end, holder_end, top/bottom, electrodes,
  the interior electrode_middle) have the same meaning on tetrahedral and hexahedral meshes.
"""

from __future__ import annotations

import math
from typing import Callable, Mapping, Sequence

import numpy as np
from skfem import MeshHex, MeshHex2

from probedyn.core.errors import GeometryError

#: corner offsets (di, dj, dk) of the 8 vertices in scikit-fem's MeshHex order
_CORNERS = ((0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1), (1, 0, 1), (1, 1, 1))


def subdivide(breaks: Sequence[float], size: float, minimum: Sequence[int] | int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates along one axis: every interval of ``breaks`` split into
    ``max(minimum, ceil(length / size))`` equal elements.  Returns (coordinates, interval index
    of every element)."""
    b = np.asarray(breaks, dtype=float)
    if b.ndim != 1 or b.size < 2 or np.any(np.diff(b) <= 0):
        raise GeometryError(f"breakpoints must increase strictly, got {list(b)}")
    if not size > 0:
        raise GeometryError(f"element size must be positive, got {size:g}")
    mins = np.broadcast_to(np.asarray(minimum, dtype=int), (b.size - 1,))
    xs, owner = [b[:1]], []
    for i in range(b.size - 1):
        n = max(int(mins[i]), math.ceil((b[i + 1] - b[i]) / size - 1e-9))
        xs.append(np.linspace(b[i], b[i + 1], n + 1)[1:])
        owner.append(np.full(n, i))
    return np.concatenate(xs), np.concatenate(owner)


def box_grid(x: np.ndarray, y: np.ndarray, z: np.ndarray, block: tuple[np.ndarray, np.ndarray, np.ndarray],
             region: Callable[[int, int, int], str | None]) -> MeshHex:
    """Hexahedra of the tensor grid ``x`` x ``y`` x ``z`` whose block (``block[axis][element
    index]``) has a region (``region(i, j, k)`` not None); unused vertices are dropped.
    Subdomains = region names."""
    return _grid(lambda I, J, K: np.stack([x[I], y[J], z[K]]), (x.size, y.size, z.size), block, region)


def ring_grid(theta: np.ndarray, s: np.ndarray, x: np.ndarray, block: tuple[np.ndarray, np.ndarray, np.ndarray],
              region: Callable[[int, int, int], str | None],
              position: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray], curved: bool = True) -> MeshHex:
    """Hexahedra of a closed ring: angles ``theta`` in [0, 2 pi) (periodic: element ``i`` spans
    ``theta[i] .. theta[i + 1]``, the last one back to ``theta[0] + 2 pi``), a radial parameter
    ``s`` and the axial coordinate ``x``; ``position(theta, s, x)`` maps parameters to
    coordinates (3, ...).  Blocks and regions as in :func:`box_grid`.

    ``curved``: a :class:`skfem.MeshHex2` whose 27 geometry nodes per element are placed by
    ``position`` at their parametric locations (circles are then represented to O(h^3)
    instead of by chords, whose sag would cost ~ (d theta)^2 / 8 in radius); else trilinear."""
    nth = theta.size
    th = np.append(theta, theta[0] + 2 * np.pi)
    mesh, par = _grid(lambda I, J, K: np.stack([th[I], s[J], x[K]]), (nth + 1, s.size, x.size), block, region,
                      periodic=nth, params=True)
    if not curved:
        return MeshHex(np.asarray(position(*par), dtype=float), mesh.t, _subdomains=mesh.subdomains)
    lin = MeshHex(np.asarray(position(*par), dtype=float), mesh.t)
    m2 = MeshHex2.from_mesh(lin)
    ed = m2.dofs.element_dofs  # (27, nel): geometry nodes of every element
    ref = MeshHex2.elem().doflocs  # (27, 3) reference locations
    e1 = MeshHex.elem()
    N = np.stack([e1.lbasis(ref.T, v)[0] for v in range(8)])  # (8, 27) trilinear weights
    pv = par[:, mesh.t]  # (3, 8, nel) parameters of the element vertices
    t0 = pv[0].min(axis=0)
    pv[0] = np.where(pv[0] - t0 > np.pi, pv[0] - 2 * np.pi, pv[0])  # unwrap across the seam
    pg = np.einsum("vg,cve->cge", N, pv)  # (3, 27, nel) parameters of the geometry nodes
    dof = m2.doflocs.copy()
    dof[:, ed] = np.asarray(position(*pg), dtype=float)
    return MeshHex2(dof, m2.t, _subdomains=mesh.subdomains)


def _grid(coords, shape, block, region, periodic: int = 0, params: bool = False):
    n0, n1, n2 = shape
    bi, bj, bk = block
    e0, e1, e2 = n0 - 1, n1 - 1, n2 - 1
    names: dict[tuple[int, int, int], str | None] = {}
    for key in {(int(a), int(b), int(c)) for a in np.unique(bi) for b in np.unique(bj) for c in np.unique(bk)}:
        names[key] = region(*key)
    I, J, K = np.meshgrid(np.arange(e0), np.arange(e1), np.arange(e2), indexing="ij")
    I, J, K = I.ravel(), J.ravel(), K.ravel()
    reg = np.array([names[(int(a), int(b), int(c))] or "" for a, b, c in zip(bi[I], bj[J], bk[K])], dtype=object)
    keep = reg != ""
    I, J, K, reg = I[keep], J[keep], K[keep], reg[keep]
    if I.size == 0:
        raise GeometryError("structured mesh: no block has a region")
    n0v = periodic if periodic else n0

    def vid(a, b, c):
        a = a % n0v if periodic else a
        return (a * n1 + b) * n2 + c

    t = np.stack([vid(I + di, J + dj, K + dk) for di, dj, dk in _CORNERS])
    used = np.unique(t)
    remap = np.full(n0v * n1 * n2, -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    a, rest = np.divmod(used, n1 * n2)
    b, c = np.divmod(rest, n2)
    p = np.asarray(coords(a, b, c), dtype=float)
    sub = {str(name): np.nonzero(reg == name)[0] for name in sorted(set(reg))}
    mesh = MeshHex(np.ascontiguousarray(p), np.ascontiguousarray(remap[t]), _subdomains=sub)
    return (mesh, p) if params else mesh


def with_groups(mesh: MeshHex, boxes: Mapping[str, tuple], tol: float, unions: Mapping[str, Sequence[str]] = (),
                require: Sequence[str] = ()) -> MeshHex:
    """``mesh`` with boundaries ``{name: facets}`` for ``boxes[name] = (lo, hi)`` or ``(lo, hi,
    True)`` (interior facets allowed) and subdomain unions ``{name: [regions]}``.  A group named
    in ``require`` that comes out empty raises :class:`GeometryError`."""
    fp = mesh.p[:, mesh.facets]  # (3, 4, nf): the facet's corner vertices
    bnd = np.zeros(mesh.facets.shape[1], dtype=bool)
    bnd[mesh.boundary_facets()] = True
    out = {}
    for name, spec in boxes.items():
        lo, hi = np.asarray(spec[0], float), np.asarray(spec[1], float)
        interior = len(spec) > 2 and bool(spec[2])
        inside = np.all((fp >= lo[:, None, None] - tol) & (fp <= hi[:, None, None] + tol), axis=(0, 1))
        f = np.nonzero(inside & (bnd | interior))[0]
        if f.size == 0 and name in require:
            raise GeometryError(f"structured mesh: face group '{name}' is empty (degenerate geometry)")
        if f.size:
            out[name] = f
    sub = dict(mesh.subdomains or {})
    for name, parts in dict(unions).items():
        idx = [sub[q] for q in parts if q in sub]
        if idx:
            sub[name] = np.sort(np.concatenate(idx))
    return _same_type(mesh, out, sub)


def _same_type(mesh, boundaries, subdomains):
    if isinstance(mesh, MeshHex2):
        return MeshHex2(mesh.doflocs, mesh.t, _boundaries=boundaries or None, _subdomains=subdomains or None)
    return MeshHex(mesh.p, mesh.t, _boundaries=boundaries or None, _subdomains=subdomains or None)


def with_facets(mesh: MeshHex, groups: Mapping[str, np.ndarray], unions: Mapping[str, Sequence[str]] = ()) -> MeshHex:
    """``mesh`` with boundaries ``groups`` (facet indices) added and subdomain unions."""
    bnd = dict(mesh.boundaries or {})
    bnd.update({k: np.asarray(v, dtype=np.int64) for k, v in groups.items() if len(v)})
    sub = dict(mesh.subdomains or {})
    for name, parts in dict(unions).items():
        idx = [sub[q] for q in parts if q in sub]
        if idx:
            sub[name] = np.sort(np.concatenate(idx))
    return _same_type(mesh, bnd, sub)


__all__ = ["subdivide", "box_grid", "ring_grid", "with_groups", "with_facets"]
