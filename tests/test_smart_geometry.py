"""Geometries of the smart probes: physical groups, electrode areas, symmetry of the tube
mesh, and one-line errors for impossible geometry."""

import math

import numpy as np
import pytest

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.duo_bimorph import duo_bimorph_mesh
from probedyn.meshes.piezotube import piezotube_mesh
from probedyn.probes import get_probe


def facet_area(mesh, facets):
    p = mesh.p[:, mesh.facets[:, facets]]  # (3, 3, k)
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], axis=0), axis=0).sum()


def tet_volume(mesh, elems):
    X = mesh.p[:, mesh.t[:, elems]]
    a = X[:, 0]
    return np.abs(np.einsum("ik,ik->k", X[:, 1] - a, np.cross(X[:, 2] - a, X[:, 3] - a, axis=0))).sum() / 6


@pytest.fixture(scope="module")
def duo():
    return duo_bimorph_mesh({"tip": "meshed"}, MeshOptions(element_size=10e-6, elements_through_thickness=1))


def test_duo_bimorph_groups_and_areas(duo):
    m = duo.mesh
    L, w, h, g = 300e-6, 30e-6, 10e-6, 5e-6
    for name in ("upper_layer", "lower_layer", "holder", "holder_piezolayer", "tip", "body"):
        assert name in m.subdomains and m.subdomains[name].size > 0
    # boxes are meshed exactly: volumes and electrode areas to round-off
    assert tet_volume(m, m.subdomains["upper_layer"]) == pytest.approx(L * w * h / 2, rel=1e-9)
    assert tet_volume(m, m.subdomains["holder"]) == pytest.approx(50e-6 * 30e-6 * 8e-6, rel=1e-9)
    for name in ("electrode_upper_left", "electrode_upper_right", "electrode_lower_left", "electrode_lower_right"):
        assert facet_area(m, m.boundaries[name]) == pytest.approx(L * (w - g) / 2, rel=1e-9)
    assert facet_area(m, m.boundaries["electrode_middle"]) == pytest.approx(L * w, rel=1e-9)
    assert facet_area(m, m.boundaries["clamp"]) == pytest.approx(w * h, rel=1e-9)
    # left electrodes are on y > w0/2, upper on z = +h/2
    c = m.p[:, m.facets[:, m.boundaries["electrode_upper_left"]]].mean(axis=1)
    assert np.all(c[1] > g / 2) and np.allclose(c[2], h / 2)
    assert duo.points["tip"][2] == pytest.approx(-h / 2 - 5e-6)


def test_duo_bimorph_structured_mesh_is_nested_grid():
    """Without a tip cone the mesh is a structured grid of boxes: halving element_size halves
    the element edges along x (60 -> 120 intervals on the body electrode edges)."""
    a = duo_bimorph_mesh({}, MeshOptions(element_size=10e-6, elements_through_thickness=1))
    b = duo_bimorph_mesh({}, MeshOptions(element_size=5e-6, elements_through_thickness=1))
    for bun in (a, b):
        m = bun.mesh
        assert tet_volume(m, m.subdomains["body"]) == pytest.approx(300e-6 * 30e-6 * 10e-6, rel=1e-9)
        assert facet_area(m, m.boundaries["electrode_upper_left"]) == pytest.approx(300e-6 * 12.5e-6, rel=1e-9)
    xa = np.unique(np.round(a.mesh.p[0] / 1e-9))
    xb = np.unique(np.round(b.mesh.p[0] / 1e-9))
    assert len(xb) - 1 == 2 * (len(xa) - 1)
    assert set(xa.tolist()) <= set(xb.tolist())


@pytest.fixture(scope="module")
def tube():
    return piezotube_mesh({}, MeshOptions(element_size=400e-6, elements_through_thickness=1))


def test_piezotube_electrodes(tube):
    m = tube.mesh
    Re, Ri, L = 0.5e-3, 0.45e-3, 5e-3
    n = 12 * tube.meta["divisions"]["n_sector"]
    facet = math.sin(math.pi / n) / (math.pi / n)  # faceted cylinder / true cylinder
    outer = sum(facet_area(m, m.boundaries[f"electrode_sector_{k:02d}"]) for k in range(12))
    assert outer == pytest.approx(2 * math.pi * Re * L * facet, rel=1e-9)
    assert facet_area(m, m.boundaries["electrode_inner"]) == pytest.approx(2 * math.pi * Ri * L * facet, rel=1e-9)
    # a quartered electrode is the union of three sectors
    q = set(m.boundaries["electrode_zp"].tolist())
    assert q == set(np.concatenate([m.boundaries[f"electrode_sector_{k:02d}"] for k in (2, 3, 4)]).tolist())
    c = m.p[:, m.facets[:, m.boundaries["electrode_zp"]]].mean(axis=1)
    assert np.all(np.degrees(np.arctan2(c[2], c[1])) > 45 - 1e-9) and np.all(np.degrees(np.arctan2(c[2], c[1])) < 135 + 1e-9)


def test_piezotube_mesh_is_invariant_under_quarter_turn(tube):
    # rotation by 90 deg about x maps the vertex set onto itself (degenerate y/z pair by construction)
    p = tube.mesh.p
    r = np.vstack([p[0], -p[2], p[1]])
    key = lambda q: np.round(q.T / 1e-9).astype(np.int64)  # noqa: E731
    a = {tuple(v) for v in key(p)}
    b = {tuple(v) for v in key(r)}
    assert a == b


def test_eccentric_bore_moves_the_inner_surface():
    b = piezotube_mesh({"delta_y": 20e-6, "holder": "point"}, MeshOptions(element_size=400e-6, elements_through_thickness=1))
    m = b.mesh
    X = m.p[:, np.unique(m.facets[:, m.boundaries["electrode_inner"]])]
    r = np.hypot(X[1] - 20e-6, X[2])
    assert r == pytest.approx(np.full(r.size, 0.45e-3), rel=1e-9)


@pytest.mark.parametrize("probe, ov, words", [
    ("piezotube", {"Ri": 0.5e-3}, "inner radius"),
    ("piezotube", {"Ri": 0.6e-3}, "inner radius"),
    ("piezotube", {"delta_y": 48e-6}, "breaks the wall"),
    ("piezotube", {"delta_y": 30e-6, "delta_z": 40e-6}, "breaks the wall"),
    ("piezotube", {"holder_length": 0.0}, "holder_length"),
    ("piezotube", {"holder_length": -1e-3}, "holder_length"),
    ("duo-bimorph", {"holder_length": 0.0}, "holder_length"),
    ("duo-bimorph", {"width": -30e-6}, "width"),
    ("duo-bimorph", {"length": 300.0}, "micrometres"),
    ("piezotube", {"Re": 0.5}, "micrometres"),
    ("duo-bimorph", {"electrode_gap": 40e-6}, "electrode_gap"),
])
def test_impossible_geometry_is_one_line_error(probe, ov, words):
    p, _ = get_probe(probe)
    with pytest.raises(ParameterError) as exc:
        p.resolve(ov)
    msg = str(exc.value)
    assert "\n" not in msg and words in msg


def test_mesh_validation_without_params():
    with pytest.raises(GeometryError, match="breaks the wall"):
        piezotube_mesh({"delta_z": 45e-6})
    with pytest.raises(GeometryError, match="holder_length"):
        duo_bimorph_mesh({"holder_length": -5e-6})
