"""Long convergence studies of the coupled piezoelectric FEM (``-m slow``; numbers in docs/piezo.md)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from probedyn.fem.piezo_benchmarks import bimorph_cantilever, bimorph_drive, tube_cantilever
from probedyn.fem.piezo_materials import get_piezo_material
from probedyn.lumped import actuation as act
from probedyn.probes import piezo as P

pytestmark = pytest.mark.slow
D31 = float(get_piezo_material("pzt-5h").d[2, 0])


def observed_order(e1: float, e2: float, e3: float, r: float = 2.0) -> float:
    """Order p from three values on meshes refined by the ratio r: (e1 - e2)/(e2 - e3) = r^p."""
    return float(np.log(abs((e1 - e2) / (e2 - e3))) / np.log(r))


@pytest.mark.parametrize("config", ["series", "parallel"])
def test_bimorph_full_clamp_converges_to_laminate_theory(config):
    """Fully clamped (rigid wall) plane-strain bimorph, L/h = 20: uniform refinement x2.
    The clamp corner is singular (the wall blocks the layers' opposite free strains), so the
    order is below the P2 value 2 for smooth solutions; the converged value lies within the
    O(h/L) clamp zone effect (5 %) of laminate theory and within 2 %."""
    h, L = 0.1e-3, 2e-3
    ref = act.bimorph_tip_deflection(L, h, "pzt-5h", config, "plane_strain")
    vals = []
    for n in (1, 2, 4):
        pm = bimorph_cantilever(L, 0.05e-3, h, nx=20 * n, ny=1, nz_layer=n, config=config, clamp="full",
                                plane_strain=True)
        st, others = bimorph_drive(config)
        vals.append(pm.static(st, others=others).displacement_at("x1")[2] / ref)
    p = observed_order(*vals)
    assert 1.0 < p < 2.5
    extrapolated = vals[2] + (vals[2] - vals[1]) / (2**p - 1)
    assert extrapolated == pytest.approx(1.0, abs=0.02)
    assert vals[2] == pytest.approx(1.0, abs=0.02)


def test_narrow_bimorph_tends_to_one_dimensional_theory():
    """Width << thickness: the layers are in uniaxial stress (k31); the residual is the
    interface boundary layer of width ~w where T2 != 0, so the gap halves with w/h."""
    h, L = 0.1e-3, 3e-3
    ref = act.bimorph_tip_deflection(L, h, "pzt-5h", "series", "narrow")
    gaps = []
    for wh in (1 / 8, 1 / 16):
        pm = bimorph_cantilever(L, wh * h, h, nx=30, ny=1, nz_layer=16, config="series", clamp="sliding")
        st, others = bimorph_drive("series")
        gaps.append(1 - pm.static(st, others=others).displacement_at("x1")[2] / ref)
    assert 0 < gaps[1] < gaps[0] < 0.025
    assert gaps[1] / gaps[0] == pytest.approx(0.5, abs=0.15)


def test_tube_converges_to_thick_wall_formulas():
    """Sliding clamp, N = 24, 36 elements around: O(N^-2) (straight-sided tets), extrapolated
    lateral and axial per volt within 1 % of the thick-wall beam formulas."""
    L, Re, Ri = 5e-3, 0.5e-3, 0.45e-3
    lat_ref = act.tube_lateral_per_volt(L, Re, Ri, D31, "thick")
    ax_ref = act.tube_axial_per_volt(L, Re, Ri, D31, "thick")
    res = {}
    for N, es in ((24, 200e-6), (36, 100e-6)):
        pm = tube_cantilever(Re, Ri, L, n_wall=1, element_size=es, clamp="sliding")
        a, b = pm.static_many([{"electrode_zp": -1.0, "electrode_zm": 1.0},
                               {e: 1.0 for e in ("electrode_yp", "electrode_zp", "electrode_ym", "electrode_zm")}])
        res[N] = (a.displacement_at("tube_end")[2] / lat_ref, b.displacement_at("tube_end")[0] / ax_ref)
    for k in range(2):
        e24, e36 = res[24][k], res[36][k]
        ext = e36 + (e36 - e24) / ((36 / 24) ** 2 - 1)
        assert ext == pytest.approx(1.0, abs=0.01)
    # printed 3.34 is 2 R/Re times the converged lateral value
    printed = act.tube_lateral_per_volt(L, Re, Ri, D31, "printed")
    assert printed / (res[36][0] * lat_ref) == pytest.approx(2 * 0.475 / 0.5, rel=0.02)


def test_gamma_default_mesh_matches_corrected_formula_for_1_to_5_um():
    rows = P.gamma_study([1e-6, 3e-6, 5e-6], {})
    for r in rows:
        G, F = r["fem"], r["formula"]
        assert np.allclose(G.normalised, F.normalised, atol=2e-3)
        assert G.lambda_min() == pytest.approx(F.lambda_min(), abs=2e-3)
        assert G.symmetric_part_min() > 0  # positive definite
    lam = [r["fem"].lambda_min() for r in rows]
    assert lam[0] > lam[1] > lam[2]


@pytest.mark.parametrize("name", ["duo-bimorph", "piezotube"])
def test_open_circuit_stiffens_every_mode(name):
    probe, values, pm, setup = P.piezo_model(name, {"holder": "point", "tip": "none"})
    t = P.coupling_table(pm, 4)
    for r in t["rows"]:
        assert r["f_oc_hz"] >= r["f_sc_hz"] * (1 - 1e-9)
        assert 0 <= r["k_eff2"] < 0.5  # below k33^2 = 0.56, the largest coupling of PZT-5H


def test_report_section_runs_quick(tmp_path):
    path = Path(__file__).resolve().parents[1] / "probedyn" / "report" / "piezo.py"
    spec = importlib.util.spec_from_file_location("piezo_report_section", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    md = mod.section(tmp_path, True)
    for f in ("piezo-duo-range.png", "piezo-tube-range.png", "piezo-gamma.png"):
        assert (tmp_path / f).stat().st_size > 10_000
        assert f in md
