"""schemes.ffm_modal: the FFM line scan on N modes of a reduced probe."""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes.ffm import FFM
from probedyn.schemes.ffm import line_scan as line_scan_1d
from probedyn.schemes.ffm_modal import ModalFFM, line_scan, modal_participation
from probedyn.schemes.stickslip_analysis import analyze


@pytest.fixture(scope="module")
def probe():
    from probedyn.probes.reduce import reduce_probe

    # the same reduction as tests/test_reduced_probe.py (a cache hit when run together)
    return reduce_probe("cantilever", {"tip_shape": "pyramid", "elements_through_thickness": 1}, n_modes=6, Q=100.0)


def test_one_mode_is_the_ffm_model():
    # N = 1 without residual: the same equations (2.13), (2.15) in the deflection w = x - V t
    # instead of x, integrated with the same method and tolerances.  A slip is a near-jump in
    # base position, so traces are compared by what the tolerance controls: the stick branch
    # before the first slip (pointwise, 1e-4 of the force scale with rtol = 1e-5) and the slip
    # positions, period and force extremes (1e-3).
    base = FFM.from_preset("vamwcnt")
    m, c, k = 5.5e-11, 7.2e-6, 380.0
    cant = dict(base.cantilever, m_x=m, c_x=c, k_x=k)
    ref = line_scan_1d(FFM(cantilever=cant, friction=base.friction, friction_y=base.friction_y), 1.5e-9)
    mod = line_scan(ModalFFM([m], [c], [k], base.friction, cant["V"]), 1.5e-9)
    a_ref, a_mod = analyze(ref.base, ref.lateral_force), analyze(mod.base, mod.lateral_force)
    assert a_mod["n_slips"] == a_ref["n_slips"] >= 2
    stick = mod.base < 0.95 * a_ref["first_slip_m"]
    F_ref = np.interp(mod.base[stick], ref.base, ref.lateral_force)
    assert np.abs(F_ref - mod.lateral_force[stick]).max() < 1e-4 * base.friction.values["F_s"]
    for key in ("first_slip_m", "period_m", "max_force_n", "kinetic_friction_n"):
        assert a_mod[key] == pytest.approx(a_ref[key], rel=1e-3, abs=1e-3 * abs(a_ref["max_force_n"]))


def test_chain_keeps_the_static_compliance(probe):
    # the N modes in series plus the residual pseudo-oscillator have the FEM's static stiffness
    # for every N; the one-mode scheme model (lumped) too, by construction
    k = probe.static_stiffness("scan")
    base = FFM.from_preset("vamwcnt")
    for n in (1, 2, 3):
        ch = ModalFFM.from_probe(probe, base.friction, 2e-6, n_modes=n)
        assert ch.k_static == pytest.approx(k, rel=1e-12)
        assert ch.labels[-1] == "static residual"
    assert ModalFFM.from_probe(probe, base.friction, 2e-6).k_static == pytest.approx(k, rel=1e-12)
    with pytest.raises(ParameterError):
        ModalFFM.from_probe(probe, base.friction, 2e-6, n_modes=50)


def test_slow_scan_first_slip_is_quasi_static(probe):
    # Quasi-static loading: whatever N, the first slip comes when the spring force reaches F_s,
    # after a base travel F_s / k_s plus the bristle's pre-sliding creep (same for all N), so the
    # first-slip positions agree to the slip's own width (< (F_s - F_c)/k_s).
    base = FFM.from_preset("vamwcnt")
    Fs, Fc = base.friction.values["F_s"], base.friction.values["F_c"]
    k = probe.static_stiffness("scan")
    first = []
    for n in (None, 1, 2):
        r = line_scan(ModalFFM.from_probe(probe, base.friction, 2e-6, n_modes=n), 1.5 * Fs / k + 2 * (Fs - Fc) / k)
        first.append(analyze(r.base, r.lateral_force)["first_slip_m"])
    assert np.ptp(first) < (Fs - Fc) / k
    assert abs(first[0] - Fs / k) < (Fs - Fc) / k


def test_modal_participation(probe):
    rows = modal_participation(probe)
    assert rows[0]["family"] == "lateral" and max(r["participation"] for r in rows) == rows[0]["participation"]
    assert rows[0]["step_velocity_ratio"] == pytest.approx(1.0)
    assert any(r["family"] == "torsion" for r in rows)
