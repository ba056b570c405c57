"""Structured hexahedral meshes of the probes (cantilever beam, duo-bimorph, piezotube).

Same geometry, physical groups and named points as the tetrahedral gmsh builders
(``meshes/cantilever.py``, ``meshes/duo_bimorph.py``, ``meshes/piezotube.py``), meshed by
:mod:`probedyn.meshes.structured` in numpy (milliseconds, no gmsh).  Used for the quadratic
hexahedra ``hex-s2`` (serendipity, 20 nodes) and ``hex-q2`` (27 nodes) of
:mod:`probedyn.fem.assembly`; meshes with a meshed tip (pyramid, cone) stay tetrahedral.

Divisions (:class:`HexDivisions`): ``n_thick`` elements through the thinnest layer, an
in-plane size ``h`` along the probe axis far from the clamp, and a geometric grading towards
the clamp: the first element is ``h0 = thickness / n_thick`` long (the clamp edges are
singular: the stress field there is not smooth, and uniformly large elements converge slowly),
growing by ``ratio`` per element up to ``h``.  A refinement study scales ``h0`` and ``h``
together (nested meshes for factor 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from probedyn.core.errors import GeometryError
from probedyn.core.params import Param
from probedyn.meshes.cache import MeshBundle, cached_mesh
from probedyn.meshes.duo_bimorph import named_points
from probedyn.meshes.piezotube import N_SECT, QUARTERS
from probedyn.meshes.structured import box_grid, ring_grid, subdivide, with_facets, with_groups

#: values of the probes' ``element`` parameter
ELEMENT_CHOICES = ("auto", "tet-p2", "hex-s2", "hex-q2")


def element_params(size_doc: str, size_lo: float, size_hi: float) -> list:
    """The mesh parameters every meshed probe declares: ``accuracy``, ``element`` and
    ``element_size`` (its description and bounds per probe)."""
    return [
        Param("accuracy", None, "", "requested relative accuracy of the frequencies (hexahedra): the default mesh "
              "refined by the measured error and convergence order of docs/fem.md; None = the default mesh",
              lo=1e-5, hi=0.05, positive=True),
        Param("element", "auto", "", "finite element: auto = the fastest to 0.1 % (docs/fem.md), tet-p2 = P2 "
              "tetrahedra (gmsh), hex-s2 = 20-node serendipity or hex-q2 = 27-node hexahedra (structured)",
              kind=str, choices=ELEMENT_CHOICES),
        Param("element_size", None, "m", size_doc, lo=size_lo, hi=size_hi, positive=True),
    ]

#: default divisions (docs/fem.md, "Accuracy per second": the cheapest meshes found with every
#: reported frequency within the target of the converged value)
CANTILEVER_DEFAULT = {"n_thick": 3, "h_over_t": 1.0, "aspect": 1.2}  # 10 modes within 0.06 % (0.1 % target)
DUO_DEFAULT = {"n_thick": 1, "h_over_t": 1.0, "aspect": 1.0}  # 8 modes within 0.24 % (0.3 % target)
TUBE_DEFAULT = {"n_thick": 1, "h_over_wall": 8.0}

#: measured accuracy of the default meshes (max relative frequency error of the reported modes
#: against the Richardson-extrapolated value) and the lowest observed convergence order in h
#: (singular stresses at the clamp edges and re-entrant corners limit it): docs/fem.md
DEFAULT_ACCURACY = {"cantilever": (6.0e-4, 0.8), "duo-bimorph": (2.4e-3, 1.1), "piezotube": (1.1e-3, 1.1)}


def refinement_for(probe: str, accuracy: float | None) -> float:
    """Refinement factor of the default hexahedral mesh that reaches ``accuracy`` (relative
    frequency error) by the measured error of the default mesh and its convergence order:
    ``r = (e0 / accuracy)^(1 / p)`` (1 when the default is already as accurate)."""
    if accuracy is None:
        return 1.0
    e0, p = DEFAULT_ACCURACY[probe]
    return max(1.0, (e0 / float(accuracy)) ** (1.0 / p))


#: limit on the number of hexahedra of one mesh (a typo in a size must not exhaust memory)
MAX_HEX = 400_000


def graded(a: float, b: float, h0: float, h: float, ratio: float = 1.5) -> np.ndarray:
    """Nodes from ``a`` to ``b``: first element ``h0`` (at ``a``), each next one ``ratio`` times
    longer up to ``h``, then uniform; the sizes are scaled to end exactly at ``b``."""
    if not (b > a and h0 > 0 and h > 0 and ratio >= 1):
        raise GeometryError(f"graded spacing needs b > a, positive sizes and ratio >= 1 (got {a}, {b}, {h0}, {h}, {ratio})")
    length = b - a
    h0 = min(h0, h)
    sizes = []
    s, tot = h0, 0.0
    while tot + s < length and s < h:
        sizes.append(s)
        tot += s
        s = min(s * ratio, h)
    rest = length - tot
    if rest > 0:
        n = max(1, math.ceil(rest / h - 1e-9))
        sizes += [rest / n] * n
    sizes = np.asarray(sizes) * (length / np.sum(sizes))
    x = a + np.concatenate([[0.0], np.cumsum(sizes)])
    x[-1] = b  # exactly (a point on the end face must lie in the mesh, not 1e-19 outside)
    return x


def graded_both(a: float, b: float, h0a: float, h0b: float, h: float, ratio: float = 1.5) -> np.ndarray:
    """Nodes from ``a`` to ``b`` graded towards both ends (first elements ``h0a`` at ``a`` and
    ``h0b`` at ``b``), meeting at the middle."""
    m = 0.5 * (a + b)
    left = graded(a, m, h0a, h, ratio)
    right = b - graded(0.0, b - m, h0b, h, ratio)[::-1]
    return np.concatenate([left, right[1:]])


def _merge(breaks, tol: float) -> list[float]:
    """Sorted breakpoints with near-duplicates (closer than ``tol``) merged."""
    out: list[float] = []
    for v in sorted(breaks):
        if not out or v - out[-1] > tol:
            out.append(float(v))
    return out


def _split(breaks, size: float, minimum=1):
    return subdivide(breaks, size, minimum)


@dataclass(frozen=True)
class HexDivisions:
    """Element counts and sizes of a structured hexahedral mesh (module docstring); None = the
    builder's default (the fastest mesh found to reach the accuracy target, docs/fem.md)."""

    n_thick: int | None = None  # elements through the thinnest layer (beam, bimorph layer, tube wall)
    h: float | None = None  # axial size far from the clamp [m]
    ratio: float = 1.5  # growth of the axial size away from the clamp
    refine: float = 1.0  # divides all sizes (a refinement study keeps the rest fixed)
    clamp: float = 0.25  # first element at the clamp: clamp x the through-thickness size
    aspect: float | None = None  # size across the width (bimorph, beam) / around (tube) over the through size
    side: float | None = None  # beam: first element across the width at the side edges over the through size (None: uniform)

    def as_dict(self) -> dict[str, Any]:
        return {"n_thick": self.n_thick, "h": self.h, "ratio": float(self.ratio), "refine": float(self.refine),
                "clamp": float(self.clamp), "aspect": self.aspect, "side": self.side}


def _count_check(n: int) -> None:
    if n > MAX_HEX:
        raise GeometryError(f"the structured mesh would have {n} hexahedra (limit {MAX_HEX}); choose a larger element_size")


# ---------------------------------------------------------------------------------------------
# cantilever
# ---------------------------------------------------------------------------------------------

def cantilever_hex_grid(L: float, w: float, t: float, div: HexDivisions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node coordinates (x, y, z) of the tensor grid of :func:`cantilever_hex`.

    Across the width the elements are ``aspect`` times the through-thickness size, uniform, or with
    ``div.side`` graded towards both side edges from ``side`` times that size (growth ``div.ratio``):
    the diagnosis meshes a thin lever thick and stretches it back (``probedyn.diagnose.modal_model``),
    which leaves the width elements several thicknesses wide, while twist concentrates its shear
    stress within about one thickness of the long edges (Saint-Venant's stress function of a thin
    strip, Timoshenko & Goodier 1970 section 109); the graded width resolves that layer."""
    r = float(div.refine)
    nz = max(1, math.ceil((div.n_thick or CANTILEVER_DEFAULT["n_thick"]) * r - 1e-9))
    hz = t / nz
    aspect = div.aspect or CANTILEVER_DEFAULT["aspect"]
    h = (div.h if div.h else CANTILEVER_DEFAULT["h_over_t"] * t) / r
    x = graded(0.0, L, div.clamp * hz, max(h, hz), div.ratio)
    if div.side is not None and div.side < aspect:
        # symmetric halves: the centre line y = 0 is a node line
        y = graded_both(-w / 2, w / 2, div.side * hz, div.side * hz, aspect * hz, div.ratio)
    else:
        ny = 2 * max(1, math.ceil(w / (2 * aspect * hz) - 1e-9))  # even: the centre line y = 0 is a node line
        y = np.linspace(-w / 2, w / 2, ny + 1)
    return x, y, np.linspace(-t / 2, t / 2, nz + 1)


def grid_nodes(nx: int, ny: int, nz: int, element: str) -> int:
    """Nodes of a full nx x ny x nz grid of quadratic hexahedra: vertices + edge midpoints
    (``hex-s2``), + face and cell centres (``hex-q2``)."""
    v = (nx + 1) * (ny + 1) * (nz + 1)
    e = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz
    if element == "hex-s2":
        return v + e
    f = nx * ny * (nz + 1) + nx * (ny + 1) * nz + (nx + 1) * ny * nz
    return v + e + f + nx * ny * nz


def cantilever_hex_dofs(L: float, w: float, t: float, div: HexDivisions, element: str) -> int:
    """Free displacement DOFs of :func:`cantilever_hex` clamped at x = 0 (exact, before any
    mesh is built): the grid's nodes less those of the clamp face, times 3."""
    x, y, z = cantilever_hex_grid(L, w, t, div)
    ny, nz = y.size - 1, z.size - 1
    face = (ny + 1) * (nz + 1) + ny * (nz + 1) + (ny + 1) * nz + (ny * nz if element == "hex-q2" else 0)
    return 3 * (grid_nodes(x.size - 1, ny, nz, element) - face)


def cantilever_hex(L: float, w: float, t: float, div: HexDivisions, element: str) -> MeshBundle:
    """Rectangular beam [0, L] x [-w/2, w/2] x [-t/2, t/2] (no tip), graded towards the clamp.

    Through the thickness ``n_thick`` elements; across the width an even number (the centre line
    y = 0 carries the named point ``tip``) of elements of about the thickness size; along x
    from ``h0 = t / n_thick`` at the clamp to ``h`` (default ``3 t``)."""
    x, y, z = cantilever_hex_grid(L, w, t, div)
    ny, nz = y.size - 1, z.size - 1
    _count_check((x.size - 1) * ny * nz)
    zero = (np.zeros(x.size - 1, int), np.zeros(ny, int), np.zeros(nz, int))
    mesh = box_grid(x, y, z, zero, lambda i, j, k: "body")
    tol = 1e-6 * min(L, w, t)
    mesh = with_groups(mesh, {
        "clamp": ((0, -w / 2, -t / 2), (0, w / 2, t / 2)),
        "free_end": ((L, -w / 2, -t / 2), (L, w / 2, t / 2)),
        "top": ((0, -w / 2, t / 2), (L, w / 2, t / 2)),
        "bottom": ((0, -w / 2, -t / 2), (L, w / 2, -t / 2)),
    }, tol, require=("clamp", "free_end"))
    points = {"tip": np.array([L, 0.0, -t / 2]), "free_end_centre": np.array([L, 0.0, 0.0]),
              "clamp_centre": np.zeros(3)}
    return MeshBundle(mesh, points, meta={"element": element, "divisions": {"x": x.size - 1, "y": ny, "z": nz}})


# ---------------------------------------------------------------------------------------------
# duo-bimorph
# ---------------------------------------------------------------------------------------------

def duo_bimorph_hex(q: dict[str, Any], div: HexDivisions, element: str) -> MeshBundle:
    """The duo-bimorph without a meshed tip (``meshes/duo_bimorph.py`` for the geometry): the
    grid of boxes of the structured tetrahedral builder, as hexahedra.  Through every layer
    interval at least ``n_thick`` elements (thinnest layer: the holder's piezolayer gets fewer
    when it is thinner than the element size through the body); across y about twice the
    through-thickness size; along x graded from the clamp."""
    r = float(div.refine)
    L, w, h, g = q["length"], q["width"], q["thickness"], q["electrode_gap"]
    mh = q["holder"] == "meshed"
    Lh, wh, th, tp = q["holder_length"], q["holder_width"], q["holder_thickness"], q["piezolayer_thickness"]
    nl = max(1, math.ceil((div.n_thick or DUO_DEFAULT["n_thick"]) * r - 1e-9))
    hz = (h / 2) / nl
    aspect = div.aspect or DUO_DEFAULT["aspect"]
    xb = [0.0, L] + ([L + Lh] if mh else [])
    yb = _merge({-w / 2, -g / 2, g / 2, w / 2} | ({-wh / 2, wh / 2} if mh else set()), 1e-9 * w)
    zb = _merge({-h / 2, 0.0, h / 2} | ({-h / 2 + th, -h / 2 + th + tp} if mh else set()), 1e-9 * h)
    hmax = (div.h if div.h else DUO_DEFAULT["h_over_t"] * h) / r
    xa = graded(0.0, L, div.clamp * hz, max(hmax, hz), div.ratio)
    if mh:
        xh, _ = _split([L, L + Lh], min(hmax, max(hz, Lh / 2)))
        x = np.concatenate([xa, xh[1:]])
        xown = np.concatenate([np.zeros(xa.size - 1, int), np.ones(xh.size - 1, int)])
    else:
        x, xown = xa, np.zeros(xa.size - 1, int)
    y, yown = _split(yb, aspect * hz)
    z, zown = _split(zb, hz)
    _count_check((x.size - 1) * (y.size - 1) * (z.size - 1))

    def region(i, j, k):
        yc, zc = 0.5 * (yb[j] + yb[j + 1]), 0.5 * (zb[k] + zb[k + 1])
        if i == 0:
            return "upper_layer" if zc > 0 else "lower_layer"
        if abs(yc) < wh / 2 and zc < -h / 2 + th + tp:
            return "holder" if zc < -h / 2 + th else "holder_piezolayer"
        return None

    mesh = box_grid(x, y, z, (xown, yown, zown), region)
    tol = 1e-6 * min(g, h / 2, tp if mh else h)
    xe = L + Lh if mh else L
    boxes = {
        "clamp": ((0, -w / 2, -h / 2), (0, w / 2, h / 2)),
        "free_end": ((L, -w / 2, -h / 2), (L, w / 2, h / 2)),
        "holder_end": ((xe, -wh / 2, -h / 2), (xe, wh / 2, -h / 2 + th + tp)) if mh else
                      ((L, -w / 2, -h / 2), (L, w / 2, h / 2)),
        "electrode_upper_left": ((0, g / 2, h / 2), (L, w / 2, h / 2)),
        "electrode_upper_right": ((0, -w / 2, h / 2), (L, -g / 2, h / 2)),
        "electrode_lower_left": ((0, g / 2, -h / 2), (L, w / 2, -h / 2)),
        "electrode_lower_right": ((0, -w / 2, -h / 2), (L, -g / 2, -h / 2)),
        "electrode_middle": ((0, -w / 2, 0), (L, w / 2, 0), True),
    }
    mesh = with_groups(mesh, boxes, tol, unions={"body": ["upper_layer", "lower_layer"]},
                       require=("clamp", "holder_end", "electrode_upper_left", "electrode_upper_right",
                                "electrode_lower_left", "electrode_lower_right", "electrode_middle"))
    return MeshBundle(mesh, named_points(q), meta={"element": element, "element_size_used": hz,
                                                   "divisions": {"x": x.size - 1, "y": y.size - 1, "z": z.size - 1}})


# ---------------------------------------------------------------------------------------------
# piezotube
# ---------------------------------------------------------------------------------------------

def piezotube_hex(q: dict[str, Any], div: HexDivisions, element: str, curved: bool = True) -> MeshBundle:
    """The piezotube (``meshes/piezotube.py`` for the geometry and groups) as a ring of hexahedra:
    12 sectors of ``n_sector`` elements (the electrode pattern), ``n_thick`` through the wall,
    the collar's wall and piezolayer with proportional counts, graded along x from the clamp.
    ``curved``: quadratic geometry (MeshHex2), circles exact to O(h^3)."""
    r = float(div.refine)
    Re, Ri, L = q["Re"], q["Ri"], q["length"]
    dy, dz = q["delta_y"], q["delta_z"]
    mh = q["holder"] == "meshed"
    Lh, hw, tp = q["holder_length"], q["holder_wall"], q["piezolayer_thickness"]
    wall = Re - Ri
    nw = max(1, math.ceil((div.n_thick or TUBE_DEFAULT["n_thick"]) * r - 1e-9))
    hr = wall / nw
    h = (div.h if div.h else TUBE_DEFAULT["h_over_wall"] * wall) / r
    arc = 2 * math.pi * 0.5 * (Re + Ri) / N_SECT
    n_sector = max(1, math.ceil(arc / h - 1e-9))
    theta = np.radians(-15.0) + np.arange(N_SECT * n_sector) * (2 * math.pi / (N_SECT * n_sector))
    th_own = np.arange(N_SECT * n_sector) // n_sector
    if mh:  # graded towards the clamp and towards the re-entrant junction with the collar
        xa = graded_both(0.0, L, div.clamp * hr, div.clamp * hr, max(h, hr), div.ratio)
        xh = L + graded(0.0, Lh, div.clamp * hr, max(h, hr), div.ratio)
        x = np.concatenate([xa, xh[1:]])
        xown = np.concatenate([np.zeros(xa.size - 1, int), np.ones(xh.size - 1, int)])
        n_hw = max(1, math.ceil(hw / (2 * hr) - 1e-9))
        n_tp = max(1, math.ceil(tp / hr - 1e-9))
        s = np.concatenate([np.linspace(0, 1, nw + 1), 1 + np.linspace(0, 1, n_hw + 1)[1:],
                            2 + np.linspace(0, 1, n_tp + 1)[1:]])
        sown = np.concatenate([np.zeros(nw, int), np.ones(n_hw, int), np.full(n_tp, 2)])
    else:
        xa = graded(0.0, L, div.clamp * hr, max(h, hr), div.ratio)
        x, xown = xa, np.zeros(xa.size - 1, int)
        s, sown = np.linspace(0, 1, nw + 1), np.zeros(nw, int)
    _count_check((x.size - 1) * theta.size * (s.size - 1))

    def position(tht, ss, xx):
        c, sn = np.cos(tht), np.sin(tht)
        w0 = np.clip(ss, 0.0, 1.0)
        # wall: from the bore circle (centre (dy, dz)) to the outer circle along the same angle
        yin, zin = dy + Ri * c, dz + Ri * sn
        rr = np.where(ss <= 1.0, Re, np.where(ss <= 2.0, Re + (ss - 1.0) * hw, Re + hw + (ss - 2.0) * tp))
        yy = np.where(ss <= 1.0, (1 - w0) * yin + w0 * Re * c, rr * c)
        zz = np.where(ss <= 1.0, (1 - w0) * zin + w0 * Re * sn, rr * sn)
        return np.stack([np.broadcast_to(xx, np.shape(yy)), yy, zz])

    def region(i, j, k):
        if k == 0:
            return "tube" if j == 0 else None
        return "holder_piezolayer" if j == 2 else "holder"

    mesh = ring_grid(theta, s, x, (th_own, sown, xown), region, position, curved=curved)
    # ---- groups: planes by coordinates, cylinders by radius and angle ----------------------
    fp = mesh.p[:, mesh.facets]  # (3, 4, nf) corner vertices (on the true circles)
    bnd = np.zeros(mesh.facets.shape[1], dtype=bool)
    bnd[mesh.boundary_facets()] = True
    tol = 1e-6 * min(wall, tp)
    fx = fp[0]
    rad = np.hypot(fp[1], fp[2])
    rin = np.hypot(fp[1] - dy, fp[2] - dz)
    in_tube = np.all(fx <= L + tol, axis=0)
    groups: dict[str, np.ndarray] = {}
    groups["clamp"] = np.nonzero(bnd & np.all(np.abs(fx) < tol, axis=0))[0]
    groups["tube_end"] = np.nonzero(np.all(np.abs(fx - L) < tol, axis=0) & np.all(rad <= Re + tol, axis=0)
                                    & (bnd if not mh else np.ones_like(bnd)))[0]
    if not mh:
        groups["tube_end"] = np.nonzero(bnd & np.all(np.abs(fx - L) < tol, axis=0))[0]
    xe = L + Lh if mh else L
    groups["holder_end"] = np.nonzero(bnd & np.all(np.abs(fx - xe) < tol, axis=0))[0]
    outer = bnd & in_tube & np.all(np.abs(rad - Re) < tol, axis=0) & ~np.all(np.abs(fx - fx[:1]) < tol, axis=0)
    inner = bnd & in_tube & np.all(np.abs(rin - Ri) < tol, axis=0) & ~np.all(np.abs(fx - fx[:1]) < tol, axis=0)
    groups["electrode_inner"] = np.nonzero(inner)[0]
    ang = np.degrees(np.arctan2(fp[2].mean(axis=0), fp[1].mean(axis=0)))
    sector = np.round(ang / 30.0).astype(int) % N_SECT
    for k in range(N_SECT):
        groups[f"electrode_sector_{k:02d}"] = np.nonzero(outer & (sector == k))[0]
    for name, ks in QUARTERS.items():
        groups[name] = np.nonzero(outer & np.isin(sector, ks))[0]
    empty = [k for k, v in groups.items() if v.size == 0]
    if empty:
        raise GeometryError(f"piezotube hex mesh: empty face groups {', '.join(empty)} (degenerate geometry)")
    mesh = with_facets(mesh, groups, unions={"body": ["tube"]})
    points = {"tip": np.array([xe, 0.0, 0.0]), "holder_end_centre": np.array([xe, 0.0, 0.0]),
              "tube_end_centre": np.array([L, 0.0, 0.0]), "clamp_centre": np.zeros(3)}
    return MeshBundle(mesh, points, meta={"element": element, "divisions": {
        "n_wall": nw, "n_sector": n_sector, "x": x.size - 1, "s": s.size - 1, "curved": bool(curved)}})




# ---------------------------------------------------------------------------------------------
# cached entry points (same cache as the gmsh meshes: $PROBEDYN_CACHE, hashed parameters)
# ---------------------------------------------------------------------------------------------

def _cached(name: str, params: dict[str, Any], build) -> MeshBundle:
    return cached_mesh(name, params, build)


def cantilever_hex_mesh(length: float, width: float, thickness: float, div: HexDivisions | None = None,
                        element: str = "hex-s2") -> MeshBundle:
    """Cached :func:`cantilever_hex`."""
    div = div or HexDivisions()
    params = {"length": float(length), "width": float(width), "thickness": float(thickness),
              "div": div.as_dict(), "element": element}
    return _cached("cantilever_hex", params, lambda p: cantilever_hex(p["length"], p["width"], p["thickness"],
                                                                       HexDivisions(**p["div"]), p["element"]))


def duo_bimorph_hex_mesh(q: dict[str, Any], div: HexDivisions | None = None, element: str = "hex-s2") -> MeshBundle:
    """Cached :func:`duo_bimorph_hex` (``q``: the validated geometry of ``meshes/duo_bimorph.py``)."""
    div = div or HexDivisions(1)
    params = {**{k: v for k, v in q.items() if k != "mesh"}, "div": div.as_dict(), "element": element}
    return _cached("duo_bimorph_hex", params, lambda p: duo_bimorph_hex(p, HexDivisions(**p["div"]), p["element"]))


def piezotube_hex_mesh(q: dict[str, Any], div: HexDivisions | None = None, element: str = "hex-s2",
                       curved: bool = True) -> MeshBundle:
    """Cached :func:`piezotube_hex` (``q``: the validated geometry of ``meshes/piezotube.py``)."""
    div = div or HexDivisions(1)
    params = {**{k: v for k, v in q.items() if k != "mesh"}, "div": div.as_dict(), "element": element,
              "curved": bool(curved)}
    return _cached("piezotube_hex", params,
                   lambda p: piezotube_hex(p, HexDivisions(**p["div"]), p["element"], p["curved"]))


__all__ = ["cantilever_hex_grid", "grid_nodes", "cantilever_hex_dofs", "ELEMENT_CHOICES", "DEFAULT_ACCURACY", "refinement_for", "HexDivisions", "graded", "cantilever_hex", "duo_bimorph_hex", "piezotube_hex", "MAX_HEX",
           "cantilever_hex_mesh", "duo_bimorph_hex_mesh", "piezotube_hex_mesh"]
