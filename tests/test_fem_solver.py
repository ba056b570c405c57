"""Assembly, solvers, springs/masses, output files and solver errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from probedyn.core.errors import GeometryError, SolverError
from probedyn.fem import elasticity as el
from probedyn.fem.eigen import have_pardiso
from probedyn.fem.materials import Material, get_material, radial_poling, rotation_about
from probedyn.fem.model import ElasticModel, PointMass, Spring
from probedyn.meshes._gmsh import element_volumes
from probedyn.meshes.cache import MeshOptions
from probedyn.meshes.cantilever import cantilever_mesh

L, W, T, E, RHO = 300e-6, 30e-6, 10e-6, 169e9, 2330.0
NU0 = Material.isotropic(E, 0.0, RHO)


@pytest.fixture(scope="module")
def coarse():
    return cantilever_mesh(L, W, T, options=MeshOptions(elements_through_thickness=1))


@pytest.fixture(scope="module")
def tipped():
    return cantilever_mesh(L, W, T, "pyramid", 10e-6, 0.35, options=MeshOptions(elements_through_thickness=1))


def test_fast_assembly_matches_skfem_form(tipped):
    # anisotropic body with a constant rotation, PZT tip with a position-dependent one
    m = tipped.mesh
    reg = el.element_regions(m, ["body", "tip"])
    mats = [get_material("silicon-110"), get_material("pzt-5h")]
    ors = [rotation_about("z", 0.3), radial_poling((0, 0, 0), (1, 0, 0))]
    K = el.assemble_stiffness(m, reg, mats, ors)
    K_ref = el.assemble_stiffness_skfem(m, reg, mats, ors)
    assert abs(K - K_ref).max() < 1e-12 * abs(K).max()


def test_rigid_motions_and_mass(tipped):
    # K annihilates the six rigid motions; the mass matrix integrates rho exactly
    model = ElasticModel(tipped, {"*": get_material("silicon-110")})
    K, M = model.assemble()
    x = model.basis.doflocs
    rig = []
    for c in range(3):
        r = np.zeros(model.ndofs_total)
        r[c::3] = 1
        rig.append(r)
    for axis in range(3):  # infinitesimal rotations omega x r
        w = np.eye(3)[axis]
        rig.append(np.cross(w, x.T).ravel())
    scale = abs(K).max() * np.abs(x).max()
    for r in rig:
        assert np.abs(K @ r).max() < 1e-9 * scale
    vol = element_volumes(tipped.mesh).sum()
    assert rig[0] @ (M @ rig[0]) == pytest.approx(2330.0 * vol, rel=1e-12)


def test_patch_uniform_strain_energy(coarse):
    # u = eps0 x is in the P2 space: strain energy = V eps0 : C : eps0 / 2 exactly (patch test)
    mat = get_material("pzt-5h")
    model = ElasticModel(coarse, {"body": (mat, rotation_about([1, 1, 0], 0.4))})
    K, _ = model.assemble()
    eps = np.array([[1.0, 0.3, -0.2], [0.3, -0.5, 0.1], [-0.2, 0.1, 0.7]]) * 1e-4
    u = (eps @ model.basis.doflocs).T.ravel()
    ev = np.array([eps[0, 0], eps[1, 1], eps[2, 2], 2 * eps[1, 2], 2 * eps[0, 2], 2 * eps[0, 1]])
    from probedyn.fem.materials import rotate_voigt

    C = rotate_voigt(mat.C, rotation_about([1, 1, 0], 0.4))
    assert 0.5 * u @ (K @ u) == pytest.approx(0.5 * L * W * T * ev @ C @ ev, rel=1e-10)


@pytest.mark.skipif(not have_pardiso(), reason="pypardiso not installed")
def test_pardiso_and_superlu_agree(coarse):
    model = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"])
    a = model.modes(4, solver="pardiso").frequencies_hz
    b = model.modes(4, solver="superlu").frequencies_hz
    assert np.allclose(a, b, rtol=1e-9)


def test_free_floating_has_six_rigid_modes(coarse):
    res = ElasticModel(coarse, {"body": NU0}).modes(7)
    f = res.frequencies_hz
    assert np.all(f[:6] < 1e-3 * f[6])  # six rigid-body modes at ~0 Hz, then the first elastic


def test_directional_and_stiff_springs(coarse):
    base = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"]).modes(2)
    flap0, lat0 = base.modes[0].frequency_hz, base.modes[1].frequency_hz
    k3 = 3 * E * W * T**3 / 12 / L**3
    # a z-spring on the free end leaves the lateral mode untouched and stiffens the flapwise one
    soft = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"],
                        springs=[Spring("free_end", None, k3, (0, 0, 1))]).modes(2)
    fl = {m.family: m.frequency_hz for m in soft.modes}
    assert fl["lateral"] == pytest.approx(lat0, rel=1e-9)
    assert fl["flapwise"] > flap0
    # a very stiff z-spring pins the end: clamped-pinned beam, bL = 3.9266 vs 1.8751
    # (Euler-Bernoulli; shear lowers the 3D value by ~0.3 %, 1.5 % allowed)
    stiff = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"],
                         springs=[Spring("free_end", None, 1e5 * k3, (0, 0, 1))]).modes(3)
    f_cp = (3.926602 / 1.8751041) ** 2 * flap0
    got = [m.frequency_hz for m in stiff.modes if m.family == "flapwise"][0]
    assert got == pytest.approx(f_cp, rel=0.015)
    # a spring between two points of the same rigid attachment does nothing
    same = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"],
                        springs=[Spring("free_end", "free_end", 1e3)]).modes(1)
    assert same.modes[0].frequency_hz == pytest.approx(flap0, rel=1e-9)


def test_point_mass_at_named_point_lowers_frequency(coarse):
    base = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"]).modes(1).modes[0].frequency_hz
    m = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"],
                     point_masses=[PointMass("tip", RHO * L * W * T)]).modes(1).modes[0]
    assert m.frequency_hz < 0.6 * base  # mu = 1: standard equation gives (1.248/1.875)^2 = 0.44
    assert m.kinetic_energy_share["point_masses"] > 0.5


def test_vtu_and_json(coarse, tmp_path):
    from probedyn.fem.io import read_modes_vtu

    res = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"]).modes(3)
    pts, cells, fields = read_modes_vtu(res.write_vtu(tmp_path / "m.vtu"))
    assert set(fields) >= {"mode_01", "mode_02", "mode_03"}
    assert np.allclose(fields["mode_02"], res.modes[1].shape.reshape(-1, 3))
    # VTK tetra10: node 4 is the midpoint of edge 0-1, node 9 of edge 2-3
    assert np.allclose(pts[cells[:, 4]], 0.5 * (pts[cells[:, 0]] + pts[cells[:, 1]]))
    assert np.allclose(pts[cells[:, 9]], 0.5 * (pts[cells[:, 2]] + pts[cells[:, 3]]))
    d = json.loads(res.write_json(tmp_path / "m.json").read_text())
    assert d["dofs"] == res.dofs and len(d["modes"]) == 3
    assert d["modes"][0]["family"] == "flapwise" and d["modes"][0]["frequency_hz"] > 0
    assert d["modes"][1]["effective_mass_tip"]["z"] is None  # lateral mode: tip does not move in z -> inf


def test_solver_errors(coarse):
    model = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"])
    with pytest.raises(SolverError, match="too coarse"):
        model.modes(model.dofs // 5)
    with pytest.raises(GeometryError, match="not a boundary"):
        ElasticModel(coarse, {"body": NU0}, clamp=["nowhere"])
    with pytest.raises(GeometryError, match="unknown point"):
        model.static_stiffness("nowhere")
    with pytest.raises(SolverError, match="floats freely"):
        ElasticModel(coarse, {"body": NU0}).static_displacement({"tip": (0, 0, 1)})
    from probedyn.core.errors import MaterialError

    with pytest.raises(MaterialError, match="not a mesh subdomain"):
        ElasticModel(coarse, {"beam": NU0})


def test_energy_shares_two_regions(tipped):
    # body + tip regions: shares are fractions of phi^T M phi and add up to 1. The tip sits at
    # the free end, where an Euler-Bernoulli mode has phi(L)^2 = 4 <phi^2>, so its share is
    # about 4x its mass fraction (slightly less: its base is 1-2 base sizes from the end);
    # 3..4.5 allows for that set-back and the tip's own rotation.
    model = ElasticModel(tipped, {"body": NU0, "tip": NU0}, clamp=["clamp"])
    res = model.modes(2)
    masses = model.region_masses()
    frac = masses["tip"] / (masses["tip"] + masses["body"])
    for m in res.modes:
        sh = m.kinetic_energy_share
        assert sh["body"] + sh["tip"] == pytest.approx(1.0, abs=1e-10)
        assert 3.0 * frac < sh["tip"] < 4.5 * frac


def test_probe_from_toml(tmp_path):
    from probedyn.core.errors import DataFormatError, ParameterError
    from probedyn.probes import get_probe

    f = tmp_path / "p.toml"
    f.write_text('probe = "cantilever"\nlength = 400e-6\npoisson_ratio = 0.0\n')
    probe, over = get_probe(str(f))
    assert probe.name == "cantilever" and over == {"length": 400e-6, "poisson_ratio": 0.0}
    assert probe.resolve(over)["length"] == 400e-6
    f.write_text('probe = "cantilever"\nlenght = 400e-6\n')
    with pytest.raises(ParameterError, match="unknown parameter 'lenght'"):
        get_probe(str(f))
    f.write_text("length = 400e-6\n")
    with pytest.raises(DataFormatError, match="missing key 'probe'"):
        get_probe(str(f))
    with pytest.raises(ParameterError, match="unknown probe"):
        get_probe("trampoline")


def test_vertex_displacement_is_the_field_at_vertices(coarse):
    # interpolating the mode at the vertex coordinates must give the vertex values
    model = ElasticModel(coarse, {"body": NU0}, clamp=["clamp"])
    res = model.modes(1)
    uv = model.vertex_displacement(res.modes[0].shape)
    idx = np.array([5, 17, coarse.mesh.p.shape[1] - 1])
    for i in idx:
        x = coarse.mesh.p[:, i]
        assert np.allclose(model.displacement_at(res.modes[0].shape, x), uv[i], rtol=1e-10, atol=1e-14 * np.abs(uv).max())


def test_shift_invert_wide_spectrum():
    # A long, finely meshed beam has lambda_1 ~ 1e-9 diag(K)/diag(M). Synthetic SPD pencil with
    # eigenvalues 1e-9 .. 1 in shuffled order (K diagonal, M = I, exact eigenvalues known): the
    # default shift and sigma = 0 both return the three lowest to 1e-8.
    import scipy.sparse as sps

    from probedyn.fem.eigen import shift_invert_eigsh

    n = 400
    lam = np.sort(np.concatenate([[1e-9, 2e-9, 5e-9], np.geomspace(1e-3, 1.0, n - 3)]))
    perm = np.random.default_rng(3).permutation(n)
    K = sps.csr_matrix((lam[perm], (np.arange(n), np.arange(n))), shape=(n, n))
    M = sps.identity(n, format="csr")
    for sigma in (None, 0.0):
        r = shift_invert_eigsh(K, M, 3, sigma=sigma)
        assert np.allclose(r.eigenvalues, lam[:3], rtol=1e-8)
