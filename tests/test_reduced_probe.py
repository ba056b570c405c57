"""lumped.reduced.ReducedProbe and its builder probes.reduce.reduce_probe.

References: ElasticModel.static_displacement (a separate static solve), the FEM's direct
frequency response ``(K - omega^2 M) u = A^T d`` (lumped.ritz.direct_compliance, a sparse
indefinite solve per frequency), and the source tables (core.presets).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from probedyn.core.errors import DataFormatError, ParameterError
from probedyn.core.presets import preset
from probedyn.lumped.reduced import DIRECTIONS, ReducedProbe
from probedyn.lumped.ritz import direct_compliance
from probedyn.probes.reduce import attach_model, reduce_probe, resolve_probe

COARSE_TIP = {"tip_shape": "pyramid", "elements_through_thickness": 1}


@pytest.fixture(scope="module")
def rp():
    return reduce_probe("cantilever", COARSE_TIP, n_modes=6, Q=100.0)


def test_static_stiffness_is_the_fem_static_solve(rp):
    # an independent static solve (ElasticModel.static_displacement, own factorisation)
    model = rp.ritz.model
    for i, d in enumerate(DIRECTIONS):
        ax = rp.frame[i]
        u = model.static_displacement({"tip": ax})
        k = 1.0 / float(ax @ model.displacement_at(u, "tip"))
        assert rp.static_stiffness(d) == pytest.approx(k, rel=1e-9)
    # the Ritz basis inside the probe has the same static compliance (static shapes at the point)
    C = rp.frame @ rp.ritz.static_compliance(rp.point) @ rp.frame.T
    np.testing.assert_allclose(C, rp.static_compliance, rtol=1e-8, atol=1e-9 * np.abs(C).max())
    # and its first n Ritz frequencies are the retained modes, validity = mode n+1 above them
    np.testing.assert_allclose(rp.ritz.frequencies_hz[:rp.n_modes], [m.frequency_hz for m in rp.modes], rtol=1e-12)
    assert rp.validity_hz > rp.modes[-1].frequency_hz


@pytest.mark.parametrize("direction", DIRECTIONS)
def test_modal_truncation_bounds_vs_fem_frequency_response(rp, direction):
    # Undamped, the discarded modes contribute sum_{i>n} phi_i^2/(w_i^2 - w^2) with every term
    # >= 0 below w_{n+1} = 2 pi validity_hz.  With x = w/w_{n+1} and R the residual (static)
    # compliance of the discarded modes this gives rigorous bounds:
    #   without the static correction   R <= H_fem - H_modes <= R / (1 - x^2)
    #   with it                         0 <= H_fem - H_corr  <= R x^2 / (1 - x^2)
    i = DIRECTIONS.index(direction)
    f = np.array([0.0, 0.5, 0.9]) * rp.validity_hz
    x = f / rp.validity_hz
    H = direct_compliance(rp.ritz.model, rp.point, rp.frame[i], f)
    Hc = rp.compliance(direction, f, damped=False).real
    Hn = rp.compliance(direction, f, static_correction=False, damped=False).real
    R = rp.residual_compliance(direction)
    tol = 1e-7 * abs(H[0])  # solver precision relative to the static compliance
    assert R > 0
    assert np.all(H - Hn >= R - tol)
    assert np.all(H - Hn <= R / (1 - x**2) + tol)
    assert np.all(H - Hc >= -tol)
    assert np.all(H - Hc <= R * x**2 / (1 - x**2) + tol)
    assert abs(Hc[0] - H[0]) <= tol  # static limit exact


def test_direction_views(rp):
    # participations + residual share = 1 (static compliance split exactly); Q = 100 damping
    for d in DIRECTIONS:
        osc, r = rp.oscillators(d)
        C = 1.0 / rp.static_stiffness(d)
        assert sum(o.participation for o in osc) + r / C == pytest.approx(1.0, rel=1e-9)
        for o in osc:
            assert o.damping_ratio == pytest.approx(1 / 200.0, rel=1e-9)
            assert o.stiffness == pytest.approx((2 * math.pi * o.frequency_hz) ** 2 * o.mass, rel=1e-12)
    # normal: the first flapwise mode dominates (beam theory: 97 % of the tip compliance,
    # 1 - 3/bL1^4 sum... ; here >= 0.9); scan (y): the first lateral mode
    assert rp.lumped("normal").family == "flapwise" and rp.lumped("normal").participation > 0.9
    assert rp.lumped("scan").family == "lateral"
    with pytest.raises(ParameterError):
        rp.static_stiffness("vertical")


def test_cache_save_load(rp, tmp_path):
    again = reduce_probe("cantilever", COARSE_TIP, n_modes=6, Q=100.0)
    assert again.provenance["cache"] == "hit" and again.ritz.model is not None
    np.testing.assert_allclose(again.static_compliance, rp.static_compliance, rtol=1e-14)
    assert [m.frequency_hz for m in again.modes] == [m.frequency_hz for m in rp.modes]
    assert [m.family for m in again.modes] == [m.family for m in rp.modes]
    p = rp.save(tmp_path / "probe.json")
    back = ReducedProbe.load(p)
    assert back.provenance["source"] == "FEM" and back.provenance["mesh_key"] == rp.provenance["mesh_key"]
    assert back.provenance["dofs"] == rp.ritz.meta["dofs"]
    f = 0.5 * rp.validity_hz
    assert back.compliance("scan", f) == pytest.approx(rp.compliance("scan", f), rel=1e-12)
    s1 = rp.ritz.solve([("tip", 1e-12)], n=2).frequencies_hz
    s2 = back.ritz.solve([("tip", 1e-12)], n=2).frequencies_hz
    np.testing.assert_allclose(s1, s2, rtol=1e-12)
    assert resolve_probe(str(p)).validity_hz == rp.validity_hz
    # a loaded probe gets its FE model back (same mesh hash) for attachments at coordinates
    attach_model(back)
    pm = [((150e-6, 0.0, 0.0), 1e-12)]
    np.testing.assert_allclose(back.ritz.solve(pm, n=2).frequencies_hz, rp.ritz.solve(pm, n=2).frequencies_hz,
                               rtol=1e-10)
    # a Ritz file that does not match the recorded hash is refused
    npz = tmp_path / "probe.ritz.npz"
    npz.write_bytes(npz.read_bytes()[:-7] + b"garbage")
    with pytest.raises(DataFormatError):
        ReducedProbe.load(p)
    (tmp_path / "bad.json").write_text(json.dumps({"format": "other"}))
    with pytest.raises(DataFormatError):
        ReducedProbe.load(tmp_path / "bad.json")


def test_table_presets_are_reduced_probes_with_their_source():
    t = ReducedProbe.from_preset("table-2.1")
    pr = preset("table-2.1")
    assert t.source == "Table 2.1" and t.validity_hz is None and t.ritz is None
    assert t.static_stiffness("scan") == pr["k_x"] and t.static_stiffness("lateral") == pr["k_y"]
    lump = t.lumped("scan")
    assert lump.mass == pytest.approx(pr["m_x"], rel=1e-12) and lump.damping == pytest.approx(pr["c_x"], rel=1e-12)
    with pytest.raises(ParameterError):
        t.static_stiffness("normal")  # Table 2.1 has no normal spring
    t43 = ReducedProbe.from_preset("table-4.3")
    p43 = preset("table-4.3")
    m = p43["m1"] * p43["m2"] / (p43["m1"] + p43["m2"])
    k = p43["k1"] * p43["k2"] / (p43["k1"] + p43["k2"])
    assert t43.lumped("scan").damping == pytest.approx(2 * p43["zeta1"] * math.sqrt(k * m), rel=1e-12)
    assert resolve_probe("table-4.1").static_stiffness("scan") == preset("table-4.1")["k_tx"]
    with pytest.raises(ParameterError):
        ReducedProbe.from_preset("table-3.2")


def test_bad_input():
    with pytest.raises(ParameterError):
        reduce_probe("cantilever", COARSE_TIP, n_modes=2, Q=-1.0)
    with pytest.raises(ParameterError):
        reduce_probe("cantilever", COARSE_TIP, n_modes=2, frame={"scan": (1, 0, 0), "lateral": (1, 0, 0),
                                                                  "normal": (0, 0, 1)})
    with pytest.raises(ParameterError):
        resolve_probe("table-2.1", {"k_x": 1.0})


@pytest.mark.slow
@pytest.mark.parametrize("name, over", [("duo-bimorph", {"holder": "point", "tip": "lumped"}), ("piezotube", {})])
def test_smart_probes_reduce_at_their_lumped_tip(name, over):
    # the augmented model (mesh + lumped tip DOFs) is reduced in its own coordinates: the retained
    # modes are the augmented eigen-solution's, the point is the lumped tip, whose static stiffness
    # along each axis is the holder's in series with the tip spring k_t (Table 3.1: k_y2 = 0.1 N/m
    # along scan = y for the duo-bimorph, far softer than the body there)
    rp = reduce_probe(name, over, n_modes=4, cache=False)
    assert rp.point == "lumped_tip"
    fem = rp.ritz.model.modes(5).frequencies_hz
    np.testing.assert_allclose([m.frequency_hz for m in rp.modes], fem[:4], rtol=1e-8)
    assert rp.validity_hz == pytest.approx(fem[4], rel=1e-8)
    kt = rp.ritz.model.lumped_tip.stiffness
    for i, d in enumerate(DIRECTIONS):
        axis = int(np.argmax(np.abs(rp.frame[i])))
        assert rp.static_stiffness(d) < kt[axis] * (1 + 1e-9)
