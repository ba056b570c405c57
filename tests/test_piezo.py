"""Coupled piezoelectric FEM (fem/piezo*.py) against exact and analytic references.

Tolerances:
* exact patch test (uniform field in a free block): round-off (1e-9);
* laminate theory in plane strain with a beam-theory (sliding) clamp: P2 represents the
  constant-curvature field and the quadratic induced potential exactly, so only the free-end
  zone remains: O((h/L)^2) = 0.25 % at L/h = 20 (tolerance 0.5 %);
* IEEE resonators: the 1D theory neglects lateral inertia, ``(pi nu r_g / L)^2 ~ 1e-3`` in
  frequency, and T2, T3 (thin bar) - a few 1e-3 in k_eff^2: tolerances 0.5 % (frequencies), 1.5 %
  (k_eff^2, the difference of two close frequencies amplifies the relative error ~8x);
* published e-form values are independent, rounded measurements: 1 % (c), 2.5 % (e), 5 % (eps^S).
"""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.core.errors import GeometryError, MaterialError, ParameterError
from probedyn.fem.materials import Material, rotate_voigt
from probedyn.fem.model import ElasticModel
from probedyn.fem.piezo import PiezoModel, coupling_factors
from probedyn.fem.piezo_benchmarks import (bar_31, bimorph_cantilever, bimorph_drive, box_bundle, free_block,
                                          rod_33)
from probedyn.fem.piezo_materials import EPS0, PUBLISHED_E_FORM, get_piezo_material, poling_rotation
from probedyn.lumped import actuation as act


# ---------------------------------------------------------------------------------------------
# materials
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["pzt-5h", "pzt-4"])
def test_d_to_e_conversion_round_trip_and_published(name):
    m = get_piezo_material(name)
    from probedyn.fem.piezo_materials import D_FORM, six_mm_tensors

    p = D_FORM[name]
    S, d, eT = six_mm_tensors(p["s11"], p["s12"], p["s13"], p["s33"], p["s44"], p["d31"], p["d33"], p["d15"],
                              p["eps11T"], p["eps33T"])
    # exact algebra: e-form back to d-form
    assert np.allclose(m.sE, S, rtol=1e-10, atol=1e-22)
    assert np.allclose(m.d, d, rtol=1e-10, atol=1e-22)
    assert np.allclose(m.epsT, eT, rtol=1e-10, atol=1e-20)
    # the same state from both forms: pick (S, E) and compare T, D
    rng = np.random.default_rng(1)
    Sv, E = rng.normal(size=6) * 1e-4, rng.normal(size=3) * 1e5
    T = m.cE @ Sv - m.e.T @ E
    D = m.e @ Sv + m.epsS @ E
    assert np.allclose(S @ T + d.T @ E, Sv, rtol=1e-9, atol=1e-16)
    assert np.allclose(d @ T + eT @ E, D, rtol=1e-9, atol=1e-14)
    # published e-form (independent, rounded measurements)
    P = PUBLISHED_E_FORM[name]
    c = m.cE / 1e10
    for key, val in (("c11", c[0, 0]), ("c12", c[0, 1]), ("c13", c[0, 2]), ("c33", c[2, 2]), ("c44", c[3, 3]),
                     ("c66", c[5, 5])):
        assert val == pytest.approx(P[key], rel=0.01), key
    for key, val in (("e31", m.e[2, 0]), ("e33", m.e[2, 2]), ("e15", m.e[0, 4])):
        assert val == pytest.approx(P[key], rel=0.025), key
    assert m.epsS[0, 0] / EPS0 == pytest.approx(P["eps11S"], rel=0.05)
    assert m.epsS[2, 2] / EPS0 == pytest.approx(P["eps33S"], rel=0.05)
    for key, val in (("k31", m.k31()), ("k33", m.k33()), ("k15", m.k15()), ("kp", m.kp())):
        assert val == pytest.approx(P[key], rel=0.03), key


def test_elastic_part_of_pzt5h_is_the_mechanical_material():
    from probedyn.fem.materials import get_material

    assert np.allclose(get_piezo_material("pzt-5h").cE, get_material("pzt-5h").C, rtol=1e-10)


def test_rotation_of_the_coupling_tensor():
    m = get_piezo_material("pzt-5h")
    R = poling_rotation([1.0, 2.0, -0.5])
    assert np.allclose(R @ R.T, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R[:, 2], np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5]))
    c, e, eps = m.rotated(R)
    # third-order tensor e_ijk from Voigt, rotated explicitly
    from probedyn.fem.materials import VOIGT_PAIRS

    et = np.zeros((3, 3, 3))
    for i in range(3):
        for J, (j, k) in enumerate(VOIGT_PAIRS):
            et[i, j, k] = et[i, k, j] = m.e[i, J]
    er = np.einsum("ia,jb,kc,abc->ijk", R, R, R, et)
    assert np.allclose([er[i, j, k] for i in range(3) for (j, k) in VOIGT_PAIRS],
                       e.ravel(), atol=1e-12 * np.abs(m.e).max())
    assert np.allclose(c, rotate_voigt(m.cE, R))
    assert np.allclose(eps, R @ m.epsS @ R.T)
    # opposite poling: c unchanged (6mm), e reversed
    c2, e2, eps2 = m.rotated(poling_rotation("-z"))
    assert np.allclose(c2, m.cE) and np.allclose(e2, -m.e) and np.allclose(eps2, m.epsS)


# ---------------------------------------------------------------------------------------------
# exact and analytic references
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("solver", ["indefinite", "schur"])
def test_free_block_patch_test_is_exact(solver):
    """A free block in a uniform field is stress free: u = d^T E x and C = eps33^T A / t."""
    a, b, t = 1e-3, 0.8e-3, 0.5e-3
    m = get_piezo_material("pzt-5h")
    pm = free_block(a, b, t, n=1)
    r = pm.static({"electrode_top": 2.0}, solver=solver)
    S = m.d.T @ np.array([0.0, 0.0, -2.0 / t])
    for x in ([a, b, t], [a, 0.0, 0.0], [0.3 * a, 0.6 * b, 0.5 * t]):
        u = r.displacement_at(np.array(x))
        assert np.allclose(u, [S[0] * x[0], S[1] * x[1], S[2] * x[2]], rtol=1e-9, atol=1e-9 * abs(S[2]) * t)
    C = r.charges["electrode_top"] / 2.0
    assert C == pytest.approx(m.epsT[2, 2] * a * b / t, rel=1e-9)
    assert r.charges["electrode_bottom"] == pytest.approx(-2.0 * C, rel=1e-9)


@pytest.mark.parametrize("config", ["series", "parallel"])
def test_bimorph_plane_strain_matches_laminate_theory(config):
    """Wide bimorph (cylindrical bending, S2 = 0) with a beam-theory clamp: laminate theory
    with the induced potential, within the O((h/L)^2) free-end effect."""
    h, L = 0.1e-3, 2e-3
    pm = bimorph_cantilever(L, 0.05e-3, h, nx=20, ny=1, nz_layer=1, config=config, clamp="sliding",
                            plane_strain=True)
    st, others = bimorph_drive(config)
    uz = pm.static(st, others=others).displacement_at("x1")[2]
    ref = act.bimorph_tip_deflection(L, h, "pzt-5h", config, "plane_strain")
    assert uz == pytest.approx(ref, rel=5e-3)
    classic = act.bimorph_tip_deflection(L, h, "pzt-5h", config, "plane_strain", induced_potential=False)
    # the induced potential lowers the classic value by 1/(1 + k^2/(4(1-k^2))) = 0.893 for PZT-5H
    assert uz / classic == pytest.approx(1.0 / act.induced_potential_factor("pzt-5h", "plane_strain"), rel=5e-3)
    if config == "series":  # floating middle electrode settles at V/2 by symmetry
        assert pm.static(st, others=others).potentials["electrode_middle"] == pytest.approx(0.5, abs=1e-3)


def test_bimorph_short_circuit_stiffness_and_blocked_force():
    """Tip load with held electrodes (plane strain): EI stiffened by the same induced potential."""
    h, L, w = 0.1e-3, 2e-3, 0.05e-3
    pm = bimorph_cantilever(L, w, h, nx=20, ny=1, nz_layer=1, config="parallel", clamp="sliding",
                            plane_strain=True)
    F = 1e-4
    uz = pm.static({}, forces={"x1": (0, 0, F)}).displacement_at("x1")[2]
    # plane strain: bending stiffness per width with s -> (s11^2 - s12^2)/s11, tip shear neglected
    k = act.bimorph_tip_stiffness(L, w, h, "pzt-5h", "plane_strain")
    # Timoshenko shear adds ~ (E/kG)(h/L)^2 ~ 1 % at L/h = 20: tolerance 2 %
    assert F / uz == pytest.approx(k, rel=0.02)


@pytest.mark.parametrize("kind", ["bar31", "rod33"])
def test_resonance_antiresonance_and_keff_match_ieee(kind):
    L = 10e-3
    if kind == "bar31":
        pm, ref = bar_31(L, nx=10, ny=2, nz=1), act.bar31_frequencies(L)
    else:
        pm, ref = rod_33(L, nx=10, ny=2), act.rod33_frequencies(L)
    f = []
    for cond, f0 in (("short", ref["f_r"]), ("open", ref["f_a"])):
        r = pm.modes(4, cond, sigma=(2 * np.pi * f0) ** 2)
        k = int(np.argmax([s["axial"] for s in r.family_shares]))
        assert r.family_shares[k]["axial"] > 0.9
        f.append(r.frequencies_hz[k])
    assert f[0] == pytest.approx(ref["f_r"], rel=5e-3)
    assert f[1] == pytest.approx(ref["f_a"], rel=5e-3)
    assert coupling_factors(f[0], f[1]) == pytest.approx(ref["k_eff2"], rel=0.015)


def test_schur_and_indefinite_solvers_agree_and_modes_match_dense():
    import scipy.linalg as sla

    pm = bimorph_cantilever(1e-3, 0.1e-3, 0.1e-3, nx=6, ny=1, nz_layer=1, config="parallel")
    st, others = bimorph_drive("parallel")
    a = pm.static(st, others=others, solver="indefinite")
    b = pm.static(st, others=others, solver="schur")
    assert np.allclose(a.u, b.u, rtol=0, atol=1e-8 * np.abs(a.u).max())
    # modes of the condensed stiffness K + Kur Krr^-1 Kur^T (dense, independent of ARPACK)
    T, P, _, _ = pm._operators(pm.electrical_condition("short"))
    K, M, free, _ = pm.mechanical_system()
    Kup, Kpp = pm.blocks()
    Kur = (Kup[free] @ T).toarray()
    Krr = (T.T @ Kpp @ T).toarray()
    Keff = K.toarray() + Kur @ np.linalg.solve(Krr, Kur.T)
    lam = sla.eigh(Keff, M.toarray(), eigvals_only=True, subset_by_index=[0, 3])
    for solver in ("indefinite", "schur"):
        f = pm.modes(4, "short", solver=solver).frequencies_hz
        assert np.allclose(f, np.sqrt(lam) / (2 * np.pi), rtol=1e-7)
    # open circuit is stiffer, mode by mode
    assert np.all(pm.modes(4, "open").frequencies_hz >= f * (1 - 1e-9))


def test_actuation_loads_reproduce_the_static_solution():
    """K_eff^-1 F (F from actuation_loads) equals the coupled static solution."""
    pm = bimorph_cantilever(1e-3, 0.1e-3, 0.1e-3, nx=6, ny=1, nz_layer=1, config="parallel")
    F, free = pm.actuation_loads(["electrode_middle"])
    T, P, _, _ = pm._operators(pm.electrical_condition("short"))
    K, M, _, _ = pm.mechanical_system()
    Kup, Kpp = pm.blocks()
    Kur = (Kup[free] @ T).toarray()
    Keff = K.toarray() + Kur @ np.linalg.solve((T.T @ Kpp @ T).toarray(), Kur.T)
    u = np.linalg.solve(Keff, F[:, 0])
    ref = pm.static({"electrode_middle": 1.0}).u[free]
    assert np.allclose(u, ref, atol=1e-9 * np.abs(ref).max())


# ---------------------------------------------------------------------------------------------
# bad input: one-line errors
# ---------------------------------------------------------------------------------------------

def _two_layer_bundle():
    h = 0.1e-3
    return box_bundle(np.linspace(0, 1e-3, 5), np.linspace(0, 0.1e-3, 2), np.linspace(-h / 2, h / 2, 3),
                      layers={"upper_layer": (0, h), "lower_layer": (-h, 0)},
                      planes={"electrode_top": (2, h / 2), "electrode_bottom": (2, -h / 2),
                              "electrode_middle": (2, 0.0)})


def _one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 300
    return msg


def test_bad_input_unknown_electrode_unpoled_region_and_non_piezo_material():
    m = get_piezo_material("pzt-5h")
    bundle = _two_layer_bundle()
    mech = ElasticModel(bundle, {"body": m.elastic()}, clamp=["x0"], tip="x1")
    pm = PiezoModel(mech, {"upper_layer": (m, "+z"), "lower_layer": (m, "+z")})
    with pytest.raises(GeometryError) as e:
        pm.static({"electrode_nowhere": 1.0})
    assert "unknown electrode 'electrode_nowhere'" in _one_line(e)
    with pytest.raises(MaterialError) as e:
        PiezoModel(mech, {"upper_layer": (m, None)})
    assert "no poling direction" in _one_line(e)
    with pytest.raises(MaterialError) as e:
        PiezoModel(mech, {"upper_layer": ("silicon", "+z")})
    assert "no piezoelectric constants" in _one_line(e)
    # an electrode on a layer that is not piezoelectric (only the upper layer is)
    with pytest.raises(MaterialError) as e:
        PiezoModel(mech, {"upper_layer": (m, "+z")}, electrodes=["electrode_top", "electrode_bottom"])
    assert "electrode 'electrode_bottom' lies on a material without piezoelectric constants" in _one_line(e)
    # elastic tensor of the mechanical model does not match the piezo material's c^E
    si = Material.isotropic(169e9, 0.28, 2330.0, "silicon")
    mech2 = ElasticModel(bundle, {"upper_layer": si, "lower_layer": m.elastic()}, clamp=["x0"], tip="x1")
    with pytest.raises(MaterialError) as e:
        PiezoModel(mech2, {"upper_layer": (m, "+z"), "lower_layer": (m, "+z")})
    assert "is not the c^E" in _one_line(e)
    with pytest.raises(ParameterError):
        pm.static({"electrode_top": float("nan")})
    with pytest.raises(ParameterError):
        pm.static({"electrode_top": "sideways"})
    with pytest.raises(ParameterError):
        pm.modes(2, "open")  # no reference electrode
