"""Parametric cantilever mesh: geometry, physical groups, cache, export, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.meshes._gmsh import element_volumes
from probedyn.meshes.cache import MeshBundle, MeshOptions
from probedyn.meshes.cantilever import cantilever_mesh

L, W, T = 300e-6, 30e-6, 10e-6


def _facet_area(mesh, facets):
    p = mesh.p[:, mesh.facets[:, facets]]  # (3, 3, k)
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], axis=0), axis=0).sum()


def test_box_geometry_and_groups():
    b = cantilever_mesh(L, W, T, options=MeshOptions(elements_through_thickness=1))
    m = b.mesh
    assert np.allclose(m.p.min(axis=1), [0, -W / 2, -T / 2]) and np.allclose(m.p.max(axis=1), [L, W / 2, T / 2])
    assert element_volumes(m).sum() == pytest.approx(L * W * T, rel=1e-12)  # straight tets fill a box exactly
    assert set(m.subdomains) == {"body"} and len(m.subdomains["body"]) == m.t.shape[1]
    assert {"clamp", "free_end", "top", "bottom"} <= set(m.boundaries)
    xc = m.p[0, m.facets[:, m.boundaries["clamp"]]]
    assert np.all(xc == 0.0)
    assert np.allclose(m.p[0, m.facets[:, m.boundaries["free_end"]]], L)
    assert _facet_area(m, m.boundaries["clamp"]) == pytest.approx(W * T, rel=1e-12)
    assert _facet_area(m, m.boundaries["top"]) == pytest.approx(L * W, rel=1e-12)
    assert np.allclose(b.points["tip"], [L, 0, -T / 2])


@pytest.mark.parametrize("shape", ["pyramid", "cone"])
def test_tip_volume(shape):
    h, a = 12e-6, math.radians(20)
    base = h * math.tan(a)
    b = cantilever_mesh(L, W, T, shape, h, a, options=MeshOptions(elements_through_thickness=1))
    m = b.mesh
    v_tip = element_volumes(m)[m.subdomains["tip"]].sum()
    v_body = element_volumes(m)[m.subdomains["body"]].sum()
    assert v_body == pytest.approx(L * W * T, rel=1e-9)
    exact = (2 * base) ** 2 * h / 3 if shape == "pyramid" else math.pi * base**2 * h / 3
    # planar faces: exact for the pyramid and for the cone's equal-area 24-gon pyramid
    assert v_tip == pytest.approx(exact, rel=1e-9)
    inset = 1.0 if shape == "pyramid" else 1.25
    assert np.allclose(b.points["tip"], [L - inset * base, 0, -T / 2 - h])
    assert m.p[2].min() == pytest.approx(-T / 2 - h, rel=1e-9)


def test_cache_and_export(tmp_path):
    opts = MeshOptions(elements_through_thickness=1)
    a = cantilever_mesh(L, W, T, options=opts)
    b = cantilever_mesh(L, W, T, options=opts)
    assert a.key == b.key and a.path == b.path and a.path.exists()
    assert np.array_equal(a.mesh.t, b.mesh.t)
    c = cantilever_mesh(L * 1.1, W, T, options=opts)
    assert c.key != a.key
    loaded = MeshBundle.load(a.path)
    assert set(loaded.mesh.boundaries) == set(a.mesh.boundaries)
    import meshio

    out = a.export(tmp_path / "cant.vtu")
    mm = meshio.read(out)
    assert mm.cells_dict["tetra"].shape[0] == a.mesh.t.shape[1]
    assert np.allclose(mm.points, a.mesh.p.T)


@pytest.mark.parametrize("kw,msg", [
    (dict(length=0.0), "length must be positive"),
    (dict(width=-1e-6), "width must be positive"),
    (dict(tip_shape="pyramid", tip_height=40e-6, tip_half_angle=0.6), "does not fit"),
    (dict(tip_shape="star"), "tip_shape"),
])
def test_bad_geometry(kw, msg):
    args = dict(length=L, width=W, thickness=T)
    args.update(kw)
    with pytest.raises(GeometryError, match=msg):
        cantilever_mesh(**args)


def test_probe_rejects_micrometres_as_metres():
    from probedyn.probes import get_probe

    probe = get_probe("cantilever")[0]
    with pytest.raises(ParameterError, match="300e-6"):
        probe.resolve({"length": 300})
    with pytest.raises(ParameterError, match="unknown parameter"):
        probe.resolve({"lenght": 300e-6})
    with pytest.raises(ParameterError, match="must be positive"):
        probe.resolve({"thickness": -1e-6})
    with pytest.raises(ParameterError, match="not one of"):
        probe.resolve({"material": "cheese"})


def test_only_large_meshes_use_hxt_and_the_openmp_thread_count_survives_it():
    """gmsh's HXT mesher (session 9) is used above HXT_MIN_TETS predicted tetrahedra only: every
    default probe / report / test mesh (up to 4 layers through the default cantilever) keeps the
    Delaunay mesh and its cache key. HXT sets the calling thread's OpenMP thread count to 1 and
    leaves it; gmsh_session must put it back (PARDISO's factorisation in this thread must run
    with the thread count of its analysis in the background thread: with 1 vs 2 the float32
    factor of the 265k model was useless and the mixed eigen-solver stalled)."""
    import gmsh

    from probedyn.meshes._gmsh import HXT_MIN_TETS, mesher_3d
    from probedyn.meshes.cantilever import predicted_tets

    for ett in (1, 2, 3, 4):
        assert mesher_3d(predicted_tets(L, W, T, T / ett)) == "delaunay"
    assert mesher_3d(predicted_tets(L, W, T, T / 5)) == "hxt"  # the 265k benchmark model
    small = cantilever_mesh(L, W, T, options=MeshOptions(elements_through_thickness=1), use_cache=False)
    assert "mesher_3d" not in small.meta["params"]  # the cache key of every small mesh is unchanged
    before = gmsh.lib.omp_get_max_threads()
    h = T / 5.2
    assert predicted_tets(L, W, T, h) > HXT_MIN_TETS
    b = cantilever_mesh(L, W, T, options=MeshOptions(element_size=h, elements_through_thickness=1), use_cache=False)
    assert gmsh.lib.omp_get_max_threads() == before
    assert b.meta["params"]["mesher_3d"] == "hxt"
    m = b.mesh
    assert element_volumes(m).sum() == pytest.approx(L * W * T, rel=1e-12)
    assert _facet_area(m, m.boundaries["clamp"]) == pytest.approx(W * T, rel=1e-12)
    assert np.all(element_volumes(m) > 0)
