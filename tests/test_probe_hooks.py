"""schemes.probe_hooks: the one mapping from a reduced probe to each scheme's parameters."""

from __future__ import annotations

import math

import pytest

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset
from probedyn.lumped.reduced import ReducedProbe
from probedyn.schemes import probe_hooks as ph
from probedyn.schemes.stickslip import TwoMassModel


def test_table_probes_reproduce_the_tables():
    t21 = preset("table-2.1")
    c = ph.ffm_cantilever(ReducedProbe.from_preset("table-2.1"))
    for n in ("m_x", "c_x", "k_x", "m_y", "c_y", "k_y"):
        assert c[n] == pytest.approx(t21[n], rel=1e-12)
    t41 = preset("table-4.1")
    p = ph.pushing_tip(ReducedProbe.from_preset("table-4.1"))
    for n in ("k_tx", "m_tx", "c_t", "k_ty", "m_ty"):
        assert p[n] == pytest.approx(t41[n], rel=1e-12)
    with pytest.raises(ParameterError):
        ph.normal_stiffness(ReducedProbe.from_preset("table-2.1"))


def test_stickslip_scaling_of_table_4_3_is_the_models():
    # Table 4.3 as a probe: the scaling must give exactly the TwoMassModel's coefficients (eqs 4.5,
    # 4.7), zeta1 = 0.1 back, and u0 = 25 for U0 = 25 k a^2 / 4 pi^2
    tm = TwoMassModel()
    U0 = tm.U0_from_u0(25.0)
    s = ph.stickslip_scaling(ReducedProbe.from_preset("table-4.3"), U0, V=3e-6, x_s0=0.25 * tm.a)
    assert s["m"] == pytest.approx(tm.m, rel=1e-12) and s["k"] == pytest.approx(tm.k, rel=1e-12)
    assert s["zeta1"] == pytest.approx(0.1, rel=1e-12)
    assert s["u0"] == pytest.approx(25.0, rel=1e-12)
    assert s["v"] == pytest.approx(tm.v_from_speed(3e-6), rel=1e-12)
    assert s["psi"] == pytest.approx(math.pi / 2, rel=1e-12)
    assert any("u0 = 4 pi^2" in line for line in s["derivation"])
    with pytest.raises(ParameterError):
        ph.stickslip_scaling(ReducedProbe.from_preset("table-4.3"), -1.0)


def test_schemes_take_a_reduced_probe():
    # the table probe through the FFM and pushing schemes gives exactly the preset's scheme
    from probedyn.schemes import pushing as pu
    from probedyn.schemes.ffm import FFM

    a = FFM.from_preset("vamwcnt")
    b = FFM.from_preset("vamwcnt", probe=ReducedProbe.from_preset("table-2.2"))
    for n in ("m_x", "c_x", "k_x", "m_y", "c_y", "k_y"):
        assert b.cantilever[n] == pytest.approx(a.cantilever[n], rel=1e-12)
    assert b.probe.source == "Table 2.2"
    # explicit overrides still win over the probe
    c = FFM.from_preset("vamwcnt", overrides={"k_x": 0.3}, probe=ReducedProbe.from_preset("table-2.2"))
    assert c.cantilever["k_x"] == 0.3
    pa = pu.make_model("mica").p
    pb = pu.make_model("mica", probe=ReducedProbe.from_preset("table-4.1")).p
    for n in ("k_tx", "m_tx", "c_t", "k_ty", "m_ty"):
        assert pb[n] == pytest.approx(pa[n], rel=1e-12)


def test_two_mass_model_from_the_scaling():
    tm = TwoMassModel()
    s = ph.stickslip_scaling(ReducedProbe.from_preset("table-4.3"), tm.U0_from_u0(5.0))
    m = ph.two_mass_model(s)
    assert m.coefficients() == pytest.approx(tm.coefficients(), rel=1e-12)
