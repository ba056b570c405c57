"""The fluid's model form follows the model's own fluid, declared or fitted (``ModalProblem._hydro_setup``,
``ModalProblem._gap``).

The diagnosis loads the transverse motion of the 3D mode's top face (a Rayleigh quotient); Sader's uniform-beam
form, ``f_v / sqrt(1 + T Gamma_r)``, loads the whole modal mass, including the section's rotation. Their gap per
flapwise mode, ``g = -ln((1 + x / r) / (1 + x)) / 2`` (``x`` the added-mass ratio, ``r`` the top face's share of
the modal mass), is a model-form direction. Until session 34 it was computed once, for a declared medium only: a
fitted fluid (no medium declared) had none, and a second cause absorbed the gap (rate-study seed 1015, lever B in
ethanol: a point mass at x/L 0.21). Now every solve returns ``x`` and ``r`` of its own state.

Checked against independent references:

* ``r`` from the reduced solve equals the top share computed directly from the baseline FEM's mode shape and the
  face mass (a different path: the unreduced mesh) within the Ritz reduction's accuracy, and the full re-solve's
  equals it too;
* ``x`` equals the frequency ratio of the same state with and without the fluid, ``(f_v / f_fluid)^2 - 1``,
  exactly (the Rayleigh quotient's definition), and ``x`` scales with the fluid density at fixed viscosity to
  first order (the added mass ``(pi/4) rho_f w Gamma_r``);
* limits: ``r -> 1`` for a slender lever's first mode (Euler-Bernoulli: no rotary inertia), the gap vanishes in
  vacuum and shrinks as ``x (1 - r) / (2 r)`` for a light fluid;
* seed 1015 (slow): fluid loading alone, its density within 5 %.

Lateral modes are loaded by the Stokes layers of the lever's two faces (``hydrodynamics.stokes_layer_mass``;
until session 34 no family but flapwise was loaded, and an independent generator's lever in water, whose lateral
modes sat 6.7 % and 2.8 % below vacuum, was read as fluid loading plus a clamp). Checked: the reduced solve's
loaded lateral frequency against the uniform beam's ``f_v / sqrt(1 + rho_f delta / (rho t))`` (the truth
generator's ``lateral_fluid_loaded``: a different path, no FEM mode shape) within a few % of the shift, its Q
against ``(1 + x) / x`` with ``x = (f_v / f)^2 - 1`` exactly, and the full re-solve against the reduced one.

Torsion modes are loaded by Green & Sader's torsional function (session 35; ``hydrodynamics.torsion_gamma``,
probedyn's own 2D Stokes FEM values): checked against the uniform beam with the function solved directly.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_truth import RHO_SI, lateral_fluid_loaded, lever_geometry, make_modal_case, torsion_fluid_loaded  # noqa: E402

from probedyn.diagnose.engine import diagnose  # noqa: E402
from probedyn.diagnose.fem_terms import directional, face_mass_scalar  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402
from probedyn.diagnose.hydrodynamics import MEDIA, stokes_layer_mass  # noqa: E402
from probedyn.diagnose.modal import ModalProblem  # noqa: E402
from probedyn.diagnose.modal_model import FEMBaseline, ModalState, ReducedModal, full_solve  # noqa: E402
from probedyn.probes import get_probe  # noqa: E402

NEEDED = {"flapwise": 3, "lateral": 1, "torsion": 1}
FLAP = [("flapwise", 1), ("flapwise", 2), ("flapwise", 3)]


def _base(lever: str) -> tuple[FEMBaseline, ReducedModal]:
    probe = get_probe("cantilever")[0]
    b = FEMBaseline(probe, probe.resolve(lever_geometry(lever)), NEEDED)
    return b, ReducedModal(b)


@pytest.fixture(scope="module")
def lever_b():
    """The short, wide lever B (100 x 40 x 10 um): rotary inertia largest on its higher flapwise modes."""
    return _base("B")


def _state(b, medium) -> ModalState:
    return ModalState(medium=medium, axes={"length": b.length_axis, "width": b.width_axis,
                                           "thickness": b.thickness_axis}, length=b.L)


def _direct_top_share(b: FEMBaseline, fa: str, o: int) -> float:
    """``rho t int_top phi_z^2 dA / phi^T M phi`` of the baseline FEM's own mode shape (unreduced mesh)."""
    m = b.model
    _, M = m.assemble()
    e = np.zeros(3)
    e[b.thickness_axis] = 1.0
    S = directional(face_mass_scalar(m, "top"), np.outer(e, e))
    a = b.shapes[:, b.index(fa, o)]
    return float(m.materials[0].density) * b.t * float(a @ (S @ a)) / float(a @ (M @ a))


def test_the_solves_share_and_added_mass_match_independent_paths(lever_b):
    b, red = lever_b
    water = _state(b, MEDIA["water"])
    h: dict = {}
    f_w, _ = red.solve(water, FLAP, hydro=h)
    f_v, _ = red.solve(_state(b, (0.0, 1.8e-5)), FLAP)
    direct = np.array([_direct_top_share(b, fa, o) for fa, o in FLAP])
    # rotary inertia: the top face carries less than the whole modal mass, more so for higher modes
    assert np.all(direct < 1.0) and direct[2] < direct[0]
    assert np.allclose(h["r"], direct, rtol=2e-3), (h["r"], direct)
    # the added-mass ratio is the loaded frequency's own: f_w = f_v / sqrt(1 + x)
    assert np.allclose(h["x"], (f_v / f_w) ** 2 - 1.0, rtol=1e-9)
    # the full FEM re-solve reports the same pair
    _, _, info = full_solve(b, water, FLAP)
    assert np.allclose(info["hydro"]["r"], h["r"], rtol=2e-3)
    assert np.allclose(info["hydro"]["x"], h["x"], rtol=5e-3)
    # first order in the density at fixed viscosity: half the density, about half the added mass
    h2: dict = {}
    red.solve(_state(b, (0.5 * MEDIA["water"][0], MEDIA["water"][1])), FLAP, hydro=h2)
    assert np.allclose(h2["x"] / h["x"], 0.5, rtol=0.05)


def test_stokes_layer_mass_is_half_the_penetration_depths_fluid():
    rho, eta = MEDIA["water"]
    om = 2 * math.pi * 5e5
    delta = math.sqrt(2 * eta / (rho * om))  # 0.75 um
    assert float(stokes_layer_mass(om, rho, eta)) == pytest.approx(0.5 * rho * delta, rel=1e-12)
    assert 0.7e-6 < delta < 0.8e-6
    # a quarter of the frequency, twice the layer
    assert float(stokes_layer_mass(om / 4, rho, eta)) == pytest.approx(2 * float(stokes_layer_mass(om, rho, eta)))


@pytest.mark.parametrize("medium", ["water", "air"])
def test_lateral_modes_carry_the_faces_stokes_layers(lever_b, medium):
    b, red = lever_b
    need = [("lateral", 1)]
    rho_f, eta_f = MEDIA[medium]
    f_v, _ = red.solve(_state(b, (0.0, 1.8e-5)), need)
    f_l, Q_l = red.solve(_state(b, (rho_f, eta_f)), need)
    x = (f_v[0] / f_l[0]) ** 2 - 1.0
    assert x > 0 and Q_l[0] == pytest.approx((1 + x) / x, rel=1e-9)  # Stokes: damping = omega x added mass
    # the uniform beam (the truth generator's formula): the same shift within a few % of it
    g = lever_geometry("B")
    f_u, Q_u = lateral_fluid_loaded(f_v[0], g["thickness"], RHO_SI, rho_f, eta_f)
    assert (f_l[0] / f_v[0] - 1) == pytest.approx(f_u / f_v[0] - 1, rel=0.05)
    assert Q_l[0] == pytest.approx(Q_u, rel=0.05)
    # the full FEM re-solve agrees with the reduced one
    f_full, Q_full, _ = full_solve(b, _state(b, (rho_f, eta_f)), need)
    assert f_full[0] == pytest.approx(f_l[0], rel=1e-5) and Q_full[0] == pytest.approx(Q_l[0], rel=1e-3)


@pytest.mark.parametrize("medium", ["water", "air"])
def test_torsion_modes_carry_green_and_sader_load(lever_b, medium):
    """The 3D torsion mode loaded through its top face's transverse motion (``(3 pi/32) rho_f w Gamma_tor`` per
    area, the interpolated table) against the uniform beam with Green & Sader's function solved directly by the 2D
    Stokes FEM (the truth generator's ``torsion_fluid_loaded``: no 3D mode shape, no table): the same shift and Q
    within the warping of a 40 x 10 um section's mode (a few %); x is the Rayleigh quotient's ratio exactly; the
    full re-solve equals the reduced one."""
    b, red = lever_b
    need = [("torsion", 1)]
    rho_f, eta_f = MEDIA[medium]
    f_v, _ = red.solve(_state(b, (0.0, 1.8e-5)), need)
    h: dict = {}
    f_l, Q_l = red.solve(_state(b, (rho_f, eta_f)), need, hydro=h)
    x = (f_v[0] / f_l[0]) ** 2 - 1.0
    assert x > 0 and h["x"][0] == pytest.approx(x, rel=1e-6) and np.isnan(h["r"][0])
    g = lever_geometry("B")
    f_u, Q_u = torsion_fluid_loaded(f_v[0], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
    assert (f_l[0] / f_v[0] - 1) == pytest.approx(f_u / f_v[0] - 1, rel=0.05)
    assert Q_l[0] == pytest.approx(Q_u, rel=0.05)
    f_full, Q_full, info = full_solve(b, _state(b, (rho_f, eta_f)), need)
    assert f_full[0] == pytest.approx(f_l[0], rel=1e-5) and Q_full[0] == pytest.approx(Q_l[0], rel=1e-3)
    assert info["hydro"]["x"][0] == pytest.approx(x, rel=1e-3)


def test_gap_limits(lever_b):
    b, red = lever_b
    # vacuum: no fluid, no gap
    assert not np.any(ModalProblem._gap(b, np.full(3, np.nan), np.ones(3)))
    # a light fluid: g ~ -x (1 - r) / (2 r)
    x, r = np.array([1e-4, 1e-4]), np.array([0.97, 0.9])
    assert np.allclose(ModalProblem._gap(b, x, r), -x * (1 - r) / (2 * r), rtol=1e-3)
    # r = 1 (uniform Euler-Bernoulli beam): the two forms agree
    assert ModalProblem._gap(b, np.array([0.3]), np.array([1.0]))[0] == pytest.approx(0.0, abs=1e-15)
    # a slender lever's first mode is nearly a Euler-Bernoulli beam's: r -> 1
    c, red_c = _base("C")
    h: dict = {}
    red_c.solve(_state(c, MEDIA["water"]), FLAP[:1], hydro=h)
    assert 0.99 < h["r"][0] <= 1.0


def test_the_gap_direction_follows_a_fitted_fluid(tmp_path):
    """No medium declared: the direction exists (a liquid can be fitted), is zero for a vacuum model and equals
    the declared-medium problem's gap for the same fluid."""
    path, _ = make_modal_case(tmp_path, 1015, "fluid-loading", "B", truth_kind="fem", declared_medium=None)
    prob = ModalProblem(read_measurement(path))
    assert prob.mf_names[-1] == "fluid on the 3D mode or the uniform beam"
    gap = np.zeros(prob.n)
    prob.predict({}, (), gap=gap)
    assert not gap.any()  # the vacuum baseline: no fluid, no gap
    fluid = next(c for c in prob.causes if c.key == "fluid-loading")
    rho, eta = MEDIA["water"]
    prob.predict({"rho_f": rho, "eta_f": eta}, (fluid,), gap=gap)
    flap = np.asarray(prob.data.family) == "flapwise"
    assert np.all(gap[flap] < 0) and not gap[~flap].any()
    # rotary inertia grows with the mode number: so does the gap's share of the shift
    assert abs(gap[flap][-1]) > abs(gap[flap][0])
    declared = path.with_name("declared.toml")
    declared.write_text(path.read_text().replace("[noise]", '[medium]\nname = "water"\n\n[noise]'))
    pw = ModalProblem(read_measurement(declared))
    gw = np.zeros(pw.n)
    pw.predict({}, (), gap=gw)
    assert np.allclose(gw, gap, rtol=1e-9, atol=1e-15)


@pytest.mark.slow
def test_a_fluid_loaded_lever_is_fluid_loading_alone():
    """Seed 1015 of the modal rate study (lever B, 100 x 40 x 10 um, in ethanol, medium not declared; truth:
    probedyn's FEM on a finer mesh loaded by the uniform-beam Sader relation). Without the gap direction for the
    fitted fluid a point mass at x/L 0.21 (or a thickness error) took the 3D-vs-uniform load difference of the
    higher flapwise modes (rho_f 812 kg/m^3, chi^2 36); with it fluid loading alone (rho_f 789.8 for 789, chi^2 11)."""
    with tempfile.TemporaryDirectory() as tmp:
        path, truth = make_modal_case(Path(tmp), 1015, "fluid-loading", "B", truth_kind="fem", declared_medium=None)
        res = diagnose(ModalProblem(read_measurement(path)))
    assert [f["cause"] for f in res["findings"]] == ["fluid-loading"]
    rho = res["findings"][0]["parameters"]["rho_f"]
    assert math.isclose(rho["value"], truth["params"]["rho_f"], rel_tol=0.05)  # ethanol, 789 kg/m^3
