"""The synthetic examples a new user runs first: reproducible from their script, and diagnosed right.

``examples/make_examples.py`` regenerates ``afm_cantilever_modes`` (3D FEM truth mesh with a hidden
point mass), ``afm_cantilever_one_mode`` (f1 only of a lever 3 % too thick: confounded by design),
``ffm_stickslip_speeds`` (Langevin Prandtl-Tomlinson with a hidden viscous friction) and
``thermal_psd_air`` (thermal PSD in declared air, FEM truth with a hidden particle) from the independent
truth paths of ``tests/diagnose_truth.py`` / ``tests/diagnose_truth_spectra.py``. Slow: three FEM truths
and a Langevin truth (~30 s CPU; the spectrum truth is cached in ~/.cache/probedyn-truths/spectra), and
the four diagnoses through the CLI (~10, 6, 50 and 15 s CPU).
"""

from __future__ import annotations

import importlib.util
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from probedyn.cli import main

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples" / "measurements"


def _maker():
    spec = importlib.util.spec_from_file_location("make_examples", ROOT / "examples" / "make_examples.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _numbers(csv: Path) -> np.ndarray:
    rows = [r.split(",") for r in csv.read_text().splitlines()[1:]]
    return np.array([[float(c) if re.fullmatch(r"[-+0-9.eE]+", c) else math.nan for c in r] for r in rows])


@pytest.mark.slow
def test_shipped_examples_are_what_the_script_makes(tmp_path):
    """The shipped files are the script's output: sidecars identical; numbers to a relative 1e-8 (the FEM
    eigenvalues converge to 1e-11 and the Langevin run is seeded, but BLAS/PARDISO threading may change
    the last of the 10 printed digits), far below the stated 1e-3 frequency and 5 pN force noise; the
    spectrum is printed with 7 (frequency) and 4 (PSD) digits, so a last-digit flip there is one unit in
    that digit: relative 1e-3 on a PSD value (against its >= 12 % periodogram scatter) and 1e-6 on a
    frequency (against the stated 1e-4)."""
    mk = _maker()
    rtol = {"thermal_psd_air": [1e-6, 1e-3]}  # per column: frequency, PSD
    for name in mk.MAKERS:
        side = mk.MAKERS[name](tmp_path)
        assert side.read_text() == (EX / side.name).read_text()
        new, old = _numbers(side.with_suffix(".csv")), _numbers(EX / side.with_suffix(".csv").name)
        assert new.shape == old.shape
        for j, rt in enumerate(np.broadcast_to(rtol.get(name, 1e-8), new.shape[1:])):
            np.testing.assert_allclose(new[:, j], old[:, j], rtol=rt, atol=0, equal_nan=True, err_msg=f"{name} column {j}")


def _diagnose(name: str, capsys) -> dict:
    assert main(["diagnose", str(EX / f"{name}.toml"), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _within(p: dict, truth: float, n_sigma: float = 3.0) -> bool:
    """The fitted value within n_sigma of its own (noise-propagated) uncertainty of the truth."""
    return abs(p["value"] - truth) <= n_sigma * p["sigma"]


@pytest.mark.slow
def test_modal_example_names_the_hidden_particle(capsys):
    """afm_cantilever_modes: the hidden point mass (a 15 um silica sphere at the truth mesh's vertex
    nearest x/L = 0.85) is the first finding, with mass and position within 3 sigma of the truth."""
    mk = _maker()
    res = _diagnose("afm_cantilever_modes", capsys)
    f = res["findings"][0]
    assert f["cause"] == "point-mass"
    xi_node = float(re.search(r"vertex at x/L = ([0-9.]+)", (EX / "afm_cantilever_modes.toml").read_text()).group(1))
    assert _within(f["parameters"]["mass"], mk.particle_mass())
    assert _within(f["parameters"]["xi"], xi_node)


@pytest.mark.slow
def test_one_mode_example_is_a_confounding_report(capsys):
    """afm_cantilever_one_mode: one frequency (a lever 3 % thicker than nominal) cannot name one cause: the
    verdict is 'confounded' and the group holds thickness-error among the causes that can RAISE f1; a
    point mass or a compliant clamp (which can only lower it) is not in the group."""
    res = _diagnose("afm_cantilever_one_mode", capsys)
    assert res["verdict"] == "confounded"
    group = {res["findings"][0]["cause"], *[c for g in res["confounded"] for c in g["causes"]]}
    assert "thickness-error" in group and len(group) >= 2
    assert not group & {"point-mass", "clamp-compliance"}


@pytest.mark.slow
def test_spectrum_example_names_the_hidden_particle_in_declared_air(capsys):
    """thermal_psd_air: in declared air (the air loading is the baseline's, not a cause) the hidden 12 um
    silica particle is the first finding, mass and position within 3 sigma of the truth (the truth mesh's
    vertex stated in the sidecar), and fluid-loading is not claimed."""
    mk = _maker()
    res = _diagnose("thermal_psd_air", capsys)
    f = res["findings"][0]
    assert f["cause"] == "point-mass"
    assert "fluid-loading" not in [g["cause"] for g in res["findings"]]
    xi_node = float(re.search(r"vertex at x/L = ([0-9.]+)", (EX / "thermal_psd_air.toml").read_text()).group(1))
    assert _within(f["parameters"]["mass"], mk.particle_mass(mk.SPECTRUM_PARTICLE_D))
    assert _within(f["parameters"]["xi"], xi_node)


@pytest.mark.slow
def test_timeseries_example_of_a_plain_lever_claims_nothing(capsys):
    """tip_motion_timeseries: a thermally driven tip record of the nominal lever (two flapwise
    modes, no hidden effect) reduced to a PSD: both peaks labelled, nothing claimed. The labellings
    compared include ones that place no peak (the doublet and assignment proposals); such a
    labelling fits no rows and is scored by the price of the lines it leaves out (it once reached
    the modal problem with no mode and failed with a traceback)."""
    res = _diagnose("tip_motion_timeseries", capsys)
    assert res["verdict"] == "no-significant-discrepancy" and not res["findings"]


def test_a_modal_problem_without_modes_is_a_data_error(tmp_path):
    from probedyn.core.errors import DataFormatError
    from probedyn.diagnose.formats import read_measurement
    from probedyn.diagnose.modal import ModalProblem

    meas = read_measurement(EX / "afm_cantilever_modes.toml")
    keep = np.zeros(len(meas.freq), bool)
    empty = type(meas)(**{k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == keep.shape else v)
                          for k, v in vars(meas).items()})
    with pytest.raises(DataFormatError, match="no mode frequency"):
        ModalProblem(empty)


@pytest.mark.slow
def test_friction_example_names_the_hidden_viscous_friction(capsys):
    """ffm_stickslip_speeds: the hidden viscous friction is the first finding, gamma within 3 sigma."""
    mk = _maker()
    res = _diagnose("ffm_stickslip_speeds", capsys)
    f = res["findings"][0]
    assert f["cause"] == "viscous-friction"
    assert _within(f["parameters"]["gamma"], mk.GAMMA_VISC)


def test_friction_loop_example_names_the_blend_contrast_and_the_slope(capsys):
    """friction_loops_sbs_pmma (real Nanosurf lines of an SBS/PMMA blend): the half loop falls where the
    surface rises, so friction-contrast is claimed with a ratio below 1, and the slope coupling beside it.
    Independent check of the ratio: the half loop ``(trace - retrace) / 2`` at each position regressed on
    the relief coordinate by plain least squares, ``W = a (1 + beta zeta)``; the fit (whitened, with the
    slope law) agrees within twice the ratio's own jackknife uncertainty over the four lines (the slope enters
    the half loop at second order in t; the two weigh the samples differently: white against AR(1)), and
    the uncertainty is a real one, under 20 % of the ratio."""
    from probedyn.diagnose.problems import make_problem

    res = _diagnose("friction_loops_sbs_pmma", capsys)
    found = {f["cause"]: f for f in res["findings"]}
    assert set(found) == {"friction-contrast", "surface-slope"}
    p = make_problem(EX / "friction_loops_sbs_pmma.toml")
    pos = np.concatenate([s.position for s in p.data.scans])
    Z, W = [], []
    for sl in p.slices:
        tr = p.direction[sl] > 0
        o1, o2 = np.argsort(pos[sl][tr]), np.argsort(pos[sl][~tr])
        W.append(0.5 * (p.force[sl][tr][o1] - p.force[sl][~tr][o2]))
        Z.append(0.5 * (p.relief[sl][tr][o1] + p.relief[sl][~tr][o2]))
    a, b = np.linalg.lstsq(np.column_stack([np.ones(sum(map(len, Z))), np.concatenate(Z)]), np.concatenate(W), rcond=None)[0]
    ratio = found["friction-contrast"]["derived"]["friction_ratio_high_to_low"]
    sigma = found["friction-contrast"]["derived_sigma_jackknife"]["friction_ratio_high_to_low"]
    assert ratio < 1.0 and 0.0 < sigma < 0.2 * ratio
    assert abs(ratio - (1.0 + b / a)) < 2.0 * sigma, (ratio, sigma, 1.0 + b / a)


@pytest.mark.slow
def test_thin_lever_diagnosis_mesh_within_its_error_estimate():
    """Why the modal example is not the thin 200 x 30 x 2 um lever (session 7, before the fix of
    docs/diagnose.md section 2): the diagnosis' FEM of it at the default budget (meshed 6.3x thick,
    stretched back, not refined) must agree with the converged unstretched reference
    (tests/data/thin_lever_reference.json) within twice its own discretisation estimate plus 1e-4 (a
    tenth of the 1e-3 frequency noise a user states): the estimate enters the predictive sigma, so an
    error beyond it is a model error the diagnosis then blames on a cause. Before the fix: flapwise 4
    +1.28 % against an estimate of 0.07 %, torsion +0.57 % against 0.13 % (this test failed); the
    factor 2 allows the grid-convergence index's ~10 % shortfall on this pre-asymptotic mesh."""
    from probedyn.diagnose.modal_model import FEMBaseline
    from probedyn.probes import get_probe

    ref = json.loads((Path(__file__).parent / "data" / "thin_lever_reference.json").read_text())
    probe = get_probe("cantilever")[0]
    values = probe.resolve(dict(ref["geometry_m"]))
    b = FEMBaseline(probe, values, {"flapwise": 4, "lateral": 1, "torsion": 1})
    assert b.stretch > 5
    for fa, n in (("flapwise", 4), ("lateral", 1), ("torsion", 1)):
        fr = ref["frequencies_hz"][fa][:n]
        for o in range(1, n + 1):
            i = b.index(fa, o)
            assert abs(b.freqs[i] - fr[o - 1]) <= 2 * b.disc_err[i] + 1e-4 * fr[o - 1], (fa, o)
