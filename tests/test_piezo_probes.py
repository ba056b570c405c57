"""The smart probes as electromechanical models (probedyn/probes/piezo.py), on coarse meshes.

Tolerances come from the physics and the measured discretisation order (docs/piezo.md):
* linearity, symmetry and reciprocity of the coupled model: round-off;
* piezotube, 12 straight-sided elements around the circumference: the O((2 pi / N)^2) error
  is +3 to +5 % (lateral) and +2 % (axial) at N = 12 (measured order 2 from N = 24, 36, 48), so 6 %;
* duo-bimorph vertical range with a narrow gap: between the induced-potential factors of a
  plate (kp) and of a narrow beam (k31), the two limits of the layer's stress state.
"""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.core.errors import GeometryError, MaterialError, ParameterError
from probedyn.fem.piezo_materials import get_piezo_material
from probedyn.lumped import actuation as act
from probedyn.probes import piezo as P

TUBE = {"element_size": 400e-6, "holder": "point", "tip": "none"}
DUO = {"element_size": 15e-6, "holder": "point", "tip": "none"}
D31 = float(get_piezo_material("pzt-5h").d[2, 0])


@pytest.fixture(scope="module")
def tube():
    return P.piezo_model("piezotube", TUBE)


def test_piezotube_factor_two_of_eq_334_and_axial_335(tube):
    probe, values, pm, setup = tube
    res = pm.static_many([setup.pattern(None, p) for p in ("V_x", "V_y", "V_z")])
    lat_x = res[0].displacement_at("tube_end")[2]
    lat_y = res[1].displacement_at("tube_end")[1]
    ax = res[2].displacement_at("tube_end")[0]
    L, Re, Ri = values["length"], values["Re"], values["Ri"]
    # symmetry of the structured mesh under a 90-degree rotation: V_x and V_y are the same drive
    assert lat_x == pytest.approx(lat_y, rel=1e-9)
    printed = act.tube_lateral_per_volt(L, Re, Ri, D31, "printed")
    corrected = act.tube_lateral_per_volt(L, Re, Ri, D31, "thin")
    assert lat_x == pytest.approx(corrected, rel=0.06)
    # the print is twice the FEM, up to the thin-wall difference of outer and mean radius:
    # printed / corrected = 2 R / Re exactly (1.90 here)
    assert printed / corrected == pytest.approx(2 * 0.5 * (Re + Ri) / Re, rel=1e-12)
    assert printed / lat_x == pytest.approx(2 * 0.5 * (Re + Ri) / Re, rel=0.06)
    assert ax == pytest.approx(act.tube_axial_per_volt(L, Re, Ri, D31), rel=0.06)
    # 3.36: equal lateral and axial ranges need V_z/V_x = lat/ax; printed 0.9 L/Re is twice that
    assert act.tube_voltage_ratio(L, Re, Ri, "printed") / (lat_x / ax) == pytest.approx(2 * 0.5 * (Re + Ri) / Re,
                                                                                       rel=0.1)


def test_linearity_and_reciprocity(tube):
    """Pattern = sum of single-electrode responses (the mean-potential rule on shared edges is
    linear); capacitances symmetric; tip displacement per volt = charge per newton (reciprocity
    of the symmetric coupled system)."""
    probe, values, pm, setup = tube
    pat = setup.pattern(None, "V_x")
    one = pm.static_many([{e: 1.0} for e in pat])
    tot = pm.static(pat)
    u_sum = sum(v * r.u for (e, v), r in zip(pat.items(), one))
    assert np.allclose(tot.u, u_sum, atol=1e-10 * np.abs(tot.u).max())
    a, b = one[0], one[1]
    ea, eb = list(pat)
    assert a.charges[eb] == pytest.approx(b.charges[ea], rel=1e-8)
    F = 1e-3
    f = pm.static({}, forces={"tube_end": (0.0, 0.0, F)})
    u_per_volt = a.displacement_at("tube_end")[2]
    q_per_newton = f.charges[ea] / F
    assert abs(q_per_newton) == pytest.approx(abs(u_per_volt), rel=1e-7)


def test_gamma_from_fem_matches_corrected_formula():
    rows = P.gamma_study([5e-6], TUBE)
    G, F = rows[0]["fem"].normalised, rows[0]["formula"].normalised
    # mesh (N = 12) and thin-wall-field errors: a few 1e-3 on the normalised entries
    assert np.allclose(G, F, atol=6e-3)
    assert G[0, 2] == pytest.approx(F[0, 2], rel=0.05)  # u_z -> lateral, the largest coupling
    assert rows[0]["fem"].symmetric_part_min() > 0.9


def test_duo_bimorph_patterns_and_narrow_gap_range():
    probe, values, pm, setup = P.piezo_model("duo-bimorph", {**DUO, "electrode_gap": 1e-6})
    rz, ry = pm.static_many([setup.pattern(None, "V_z"), setup.pattern(None, "V_y")])
    uz, uy = rz.displacement_at("holder_end"), ry.displacement_at("holder_end")
    assert uz[2] > 0 and uy[1] > 0  # positive commands move the tip along +z, +y
    assert abs(uz[1]) < 1e-2 * uz[2] and abs(uy[2]) < 1e-2 * uy[1]
    f = act.duo_bimorph_range(values["length"], values["width"], values["thickness"], values["electrode_gap"],
                              abs(D31))
    lo = 1 / act.induced_potential_factor("pzt-5h", "plate")
    hi = 1 / act.induced_potential_factor("pzt-5h", "narrow")
    assert lo < uz[2] / f["dz"] < hi
    assert uy[1] == pytest.approx(f["dy"], rel=0.03)
    # the series poling with its own patterns gives the same deflections (same fields)
    _, _, pms, ss = P.piezo_model("duo-bimorph", {**DUO, "electrode_gap": 1e-6}, poling="series")
    assert pms.static(ss.pattern(None, "V_z")).displacement_at("holder_end")[2] == pytest.approx(uz[2], rel=1e-8)


def test_modal_actuation_reproduces_the_static_tip_response(tube):
    probe, values, pm, setup = tube
    ma = P.modal_actuation(pm, 6, electrodes=["electrode_zp"])
    # the first bending pair carries almost all of a cantilever's static tip response
    assert ma.truncation[0] < 0.05
    assert ma.modal_force.shape == (6, 1)


def test_bad_input_is_one_line():
    with pytest.raises(ParameterError) as e:
        P.piezo_setup("cantilever")
    assert "no piezoelectric actuation" in str(e.value)
    with pytest.raises(MaterialError) as e:
        P.piezo_model("piezotube", {**TUBE, "material": "pzt-5h-iso"})
    assert "no piezoelectric constants" in str(e.value)
    setup = P.piezo_setup("piezotube")
    with pytest.raises(GeometryError) as e:
        P.resolve_drive(setup, None, None, ["electrode_sector_03"], 1.0)
    assert "unknown electrode 'electrode_sector_03'" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(ParameterError):
        P.resolve_drive(setup, None, "V_w")
    with pytest.raises(ParameterError):
        P.resolve_drive(setup, None, None, ["electrode_zp", "electrode_zm"], [1.0, 2.0, 3.0])
    with pytest.raises(ParameterError):
        P.piezo_setup("duo-bimorph", "diagonal")


def test_projected_actuation_expands_the_static_response():
    """f_i = omega_i^2 phi_i^T M u_e on ANY complete M-orthonormal basis reproduces u_e; with the
    elastic (c^E) modes of a small model the full expansion is exact (dense check)."""
    import scipy.linalg as sla

    from probedyn.fem.piezo_benchmarks import bimorph_cantilever

    pm = bimorph_cantilever(1e-3, 0.1e-3, 0.1e-3, nx=4, ny=1, nz_layer=1, config="parallel")
    K, M, free, _ = pm.mechanical_system()
    lam, Phi = sla.eigh(K.toarray(), M.toarray())
    f = P.project_actuation(pm, Phi, np.sqrt(lam), ["electrode_middle"])
    u = P.static_per_volt(pm, ["electrode_middle"])[:, 0]
    assert np.allclose(Phi @ (f[:, 0] / lam), u, atol=1e-9 * np.abs(u).max())


def test_fill_reduced_actuation_from_a_ritz_basis(tube):
    """The modal forces per volt on the Ritz basis (modes + static shapes) of the elastic model:
    the static tip response per volt is recovered by the reduced model within the basis'
    truncation (the static shapes sit at the tip face, the load is distributed)."""
    from types import SimpleNamespace

    from probedyn.lumped.ritz import RitzBasis

    probe, values, pm, setup = tube
    rb = RitzBasis.from_model(pm.mech, 6, attachments=[("tube_end", "xyz")])
    rp = SimpleNamespace(ritz=rb, modes=list(range(rb.r)), actuation={})
    act_ = P.fill_reduced_actuation(rp, pm, ["electrode_zp"])
    f = np.asarray(act_["electrode_zp"])
    assert f.shape == (rb.r,)
    u_red = rb.operator("tube_end") @ (f / rb.omega**2)
    u_fem = pm.static({"electrode_zp": 1.0}).displacement_at("tube_end")
    # truncation bound: the discarded modes' share of a static response is at most of the order
    # (omega_1 / omega_n)^2 of the first retained to the last retained mode (measured: 1e-4)
    bound = (rb.omega[0] / rb.omega[rb.n_modes - 1]) ** 2
    assert np.abs(u_red - u_fem).max() < bound * np.abs(u_fem).max()
