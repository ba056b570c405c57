"""``probedyn.meshes.entities.ensure_entities``: the facets and edges of a mesh by int64 keys
must be the very arrays scikit-fem builds with ``np.unique(axis=1)`` (same entities, order,
dtypes and element-to-entity maps), for every mesh type the project meshes with."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshHex, MeshTet

from probedyn.meshes.cantilever import cantilever_mesh
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.entities import ensure_entities
from probedyn.meshes.hexmeshes import HexDivisions, cantilever_hex

ATTRS = ("facets", "t2f", "edges", "t2e", "f2t", "boundary_facets")


def _meshes():
    yield "gmsh tets (cantilever with a pyramid tip)", cantilever_mesh(
        300e-6, 30e-6, 10e-6, "pyramid", 10e-6, 0.3, options=MeshOptions(elements_through_thickness=1)).mesh
    yield "tensor tets", MeshTet.init_tensor(*(np.linspace(0, 1, 5),) * 3)
    yield "hex-s2 cantilever", cantilever_hex(300e-6, 30e-6, 10e-6, HexDivisions(2), "hex-s2").mesh
    yield "tensor hexes", MeshHex.init_tensor(*(np.linspace(0, 1, 4),) * 3)


@pytest.mark.parametrize("name,mesh", list(_meshes()), ids=lambda x: x if isinstance(x, str) else "")
def test_entities_identical_to_scikit_fem(name, mesh):
    ref = type(mesh)(mesh.p, mesh.t)  # fresh copies: scikit-fem's lazy build vs ours
    new = type(mesh)(mesh.p, mesh.t)
    ensure_entities(new)
    for attr in ATTRS:
        a, b = getattr(ref, attr)() if attr == "boundary_facets" else getattr(ref, attr), \
            getattr(new, attr)() if attr == "boundary_facets" else getattr(new, attr)
        assert a.dtype == b.dtype and a.shape == b.shape, (name, attr)
        assert np.array_equal(a, b), (name, attr)


def test_mesh_that_has_entities_is_left_alone():
    m = MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3)
    f = m.facets
    ensure_entities(m)
    assert m.facets is f
