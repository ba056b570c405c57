"""Path tracking and probe control (schemes/tracking): fast checks with tolerances derived from
the physics or the numerics (finite-difference truncation, quadrature, first-order hold, exact
algebra). Long studies are in tests/test_tracking_slow.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probedyn.core.errors import DataFormatError, ParameterError, ProbedynError
from probedyn.probes.tracking import control_plant, plant_factory, smart_plant
from probedyn.schemes.tracking import actuation as act
from probedyn.schemes.tracking import controllers as ctl
from probedyn.schemes.tracking import disturbance as dist
from probedyn.schemes.tracking import inversion, paths, simulate, studies

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def tube():
    return control_plant()  # piezotube, k_t = 10 N/m, delta = 5 um, analytic body


# ------------------------------------------------------------------------------------- paths


@pytest.mark.parametrize("kind", paths.PATH_KINDS)
def test_path_derivatives_match_finite_differences(kind):
    """d/dt R[k-1] = R[k] for k = 1..4. Central difference error <= h^2/6 max|R[k+2]| (R[5] and
    R[6] estimated by differencing R[4]) plus round-off eps max|R[k-1]| / h."""
    p = paths.make_path(kind, size=0.5e-6, duration=1.0)
    T = p.duration
    t = np.linspace(0.013, 0.987, 301) * T
    h = 1e-4 * T
    R, Rp, Rm = p.derivatives(t), p.derivatives(t + h), p.derivatives(t - h)
    hi = [np.max(np.abs(R[j])) for j in range(5)]
    d5 = np.max(np.abs((Rp[4] - Rm[4]) / (2 * h)))
    d6 = np.max(np.abs((Rp[4] - 2 * R[4] + Rm[4]) / h**2))
    higher = hi + [d5, d6]
    for k in range(1, 5):
        fd = (Rp[k - 1] - Rm[k - 1]) / (2 * h)
        tol = 2 * (h**2 / 6 * higher[k + 2] + EPS * hi[k - 1] / h) + 1e-12 * hi[k]
        assert np.max(np.abs(fd - R[k])) <= tol, (kind, k)


@pytest.mark.parametrize("kind", paths.PATH_KINDS)
def test_paths_start_at_the_rest_position(kind):
    p = paths.make_path(kind, size=0.5e-6, duration=1.0)
    R0 = p.derivatives(np.array([0.0]))
    assert np.max(np.abs(R0[0])) <= 1e-12 * 0.5e-6
    assert np.max(np.abs(R0[1:])) == 0.0  # smooth ramps: velocity .. 4th derivative vanish at rest


def test_csv_path(tmp_path):
    f = tmp_path / "p.csv"
    t = np.linspace(0, 0.1, 11)
    xyz = np.stack([1e-7 * np.sin(20 * t), 2e-7 * t, np.zeros_like(t)], axis=1)
    f.write_text("t,x,y,z\n# comment\n" + "\n".join(",".join(f"{v:.17g}" for v in [ti, *r]) for ti, r in zip(t, xyz)))
    p = paths.read_csv_path(f)
    # an interpolating spline passes through the points (round-off of the collocation solve)
    assert np.max(np.abs(p.position(t) - xyz)) <= 1e3 * EPS * 2e-7
    # clamped ends: zero velocity and acceleration at both ends
    assert np.max(np.abs(p.derivatives(np.array([0.0, 0.1]), 2)[1:])) <= 1e-9 * np.max(np.abs(xyz)) / 0.1


@pytest.mark.parametrize("text, msg", [
    ("t,x,y\n0,0,0\n", "expected 4 columns"),
    ("0,0,0,0\n0.1,1e-7,0,abc\n", "cannot read 'abc'"),
    ("0,0,0,0\n0.2,1e-7,0,0\n0.1,0,0,0\n0.3,0,0,0\n", "times must increase strictly"),
    ("0.1,0,0,0\n0.2,1e-7,0,0\n0.3,0,0,0\n0.4,0,0,0\n", "first time must be 0"),
    ("0,0,0,0\n1,5,0,0\n2,0,0,0\n3,0,0,0\n", "micrometres typed as metres"),
    ("# nothing\n", "no data rows"),
])
def test_csv_path_bad_input(tmp_path, text, msg):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    with pytest.raises(DataFormatError) as e:
        paths.read_csv_path(f)
    assert msg in str(e.value) and "\n" not in str(e.value)


def test_bad_paths_and_range():
    with pytest.raises(ParameterError, match="unknown path"):
        studies.build_path("spiral", "piezotube")
    with pytest.raises(ParameterError, match="3D path"):
        studies.build_path("cone", "duo-bimorph")
    with pytest.raises(ParameterError, match="outside the actuator range"):
        studies.track(plant_factory(), "piezotube", "cone", "open", size=5e-6)  # needs 270 V axially
    with pytest.raises(ParameterError, match="cannot actuate"):
        inversion.path_on_outputs(smart_plant("duo-bimorph"),
                                  paths.make_path("circle", plane="xy").derivatives(np.linspace(0, 1, 5)))


# --------------------------------------------------------------------------------- actuation


def test_centred_tube_stroke_is_the_formulas():
    """delta = 0: the eccentric map (gamma_matrix, midpoint rule with n per quarter) gives
    diag(3.35, exact-annulus lateral) within the midpoint rule's error (pi/2/n)^2."""
    d31, L, Re, Ri = 185e-12, 5e-3, 0.5e-3, 0.45e-3
    G = act.eccentric_tube_stroke(Re, Ri, L, d31, n_theta=8192)
    s = act.tube_strokes(L, Re, Ri, d31)
    assert np.allclose(np.diag(G), [s["x"], s["lateral"], s["lateral"]], rtol=(math.pi / 2 / 2048) ** 2, atol=0)
    assert np.max(np.abs(G - np.diag(np.diag(G)))) <= 1e-12 * s["lateral"]  # symmetry: no coupling
    # holder end face: a rigid holder adds the end rotation, factor 1 + 2 L_h / L (exact)
    Gh = act.eccentric_tube_stroke(Re, Ri, L, d31, holder_length=0.5e-3)
    assert Gh[1, 1] / G[1, 1] == pytest.approx(1 + 2 * 0.5e-3 / L, rel=1e-12)
    assert Gh[0, 0] == pytest.approx(G[0, 0], rel=1e-12)


def test_tube_lateral_thin_wall_limit_and_printed_factor_two():
    """exact / thin-wall = 1 - t^2/(6 R^2) + O((t/R)^4) (series of the annulus integrals); the
    printed (3.34) is 2 R / Re times the thin-wall value (factor 2 for a thin tube)."""
    Re, d31, L = 1e-3, 185e-12, 5e-3
    for t in (0.2e-3, 0.05e-3, 0.01e-3):
        Ri = Re - t
        R = 0.5 * (Re + Ri)
        s = act.tube_strokes(L, Re, Ri, d31)
        ex, th = s["lateral"], s["lateral_thin"]
        assert abs(ex / th - (1 - t**2 / (6 * R**2))) <= (t / R) ** 4
        assert s["lateral_printed"] / th == pytest.approx(2 * R / Re, rel=1e-12)


def test_eccentric_stroke_against_brute_force_integration():
    """Independent check: the free-strain resultants on a fine polar midpoint grid about the
    outer centre (cells inside the bore dropped by their centre; error O(cell size / wall) on the
    bore boundary, ~1e-3 here) give the same stroke matrix."""
    Re, Ri, L, d31, dy, dz = 0.5e-3, 0.45e-3, 5e-3, 185e-12, 5e-6, 5e-6
    G = act.eccentric_tube_stroke(Re, Ri, L, d31, dy, dz)
    nth, nr = 2880, 400
    th = (np.arange(nth) + 0.5) * 2 * np.pi / nth
    r = Ri - 2 * math.hypot(dy, dz) + (np.arange(nr) + 0.5) * (Re - Ri + 2 * math.hypot(dy, dz)) / nr
    TH, Rr = np.meshgrid(th, r, indexing="ij")
    Y, Z = Rr * np.cos(TH), Rr * np.sin(TH)
    inside = (Y - dy) ** 2 + (Z - dz) ** 2 >= Ri**2
    dA = Rr * (2 * np.pi / nth) * ((Re - Ri + 2 * math.hypot(dy, dz)) / nr) * inside
    e = np.stack([np.cos(th), np.sin(th)], axis=1)
    de = e @ np.array([dy, dz])
    cr = dy * e[:, 1] - dz * e[:, 0]
    tloc = Re - (de + np.sqrt(Ri**2 - cr**2))
    q = np.floor(((np.degrees(th) + 45) % 360) / 90).astype(int)  # quadrant: 0 = +y, 1 = +z, 2 = -y, 3 = -z
    pats = {"V_x": [1, 1, 1, 1], "V_y": [-1, 0, 1, 0], "V_z": [0, -1, 0, 1]}
    A = dA.sum()
    c = np.array([(Y * dA).sum(), (Z * dA).sum()]) / A
    Iyy, Izz, Iyz = ((Y - c[0]) ** 2 * dA).sum(), ((Z - c[1]) ** 2 * dA).sum(), ((Y - c[0]) * (Z - c[1]) * dA).sum()
    Ic = np.array([[Iyy, Iyz], [Iyz, Izz]])
    Gb = np.zeros((3, 3))
    for j, k in enumerate(("V_x", "V_y", "V_z")):
        eps_p = (np.array(pats[k])[q] / tloc)[:, None] * d31
        N = (eps_p * dA).sum()
        m = np.array([(eps_p * (Y - c[0]) * dA).sum(), (eps_p * (Z - c[1]) * dA).sum()])
        kap = np.linalg.solve(Ic, m)
        Gb[0, j] = L * N / A
        Gb[1:, j] = -kap * L**2 / 2
    scale = np.abs(np.diag(G))[None, :]
    assert np.max(np.abs(G - Gb) / scale) <= 5e-3
    # physics: the bore offset towards +y, +z thins the wall there, the axial drive strains that side
    # more and bends the tube away from it; both lateral axes alike (45 degrees)
    assert G[1, 0] < 0 and G[2, 0] < 0 and G[1, 0] == pytest.approx(G[2, 0], rel=1e-12)


def test_duo_bimorph_equal_stroke_voltage_ratio():
    """(3.33): equal strokes need V_z / V_y = h (w + w0) / w^2 (exact algebra of 3.31, 3.32)."""
    L, w, w0, h = 300e-6, 30e-6, 5e-6, 10e-6
    s = act.duo_bimorph_strokes(L, w, w0, h, -185e-12)
    assert s["y"] / s["z"] == pytest.approx(h * (w + w0) / w**2, rel=1e-13)


# ------------------------------------------------------------------------------ plant, model


def test_plant_static_gain_is_the_stroke(tube):
    """Static tip = holder (the spring carries no static load) and K2^-1 Gamma = G: Cq K^-1 B = G."""
    G = tube.blocks["G"]
    assert np.max(np.abs(tube.static_gain() - G)) <= 1e-9 * np.max(np.abs(G))


def test_slow_model_is_the_low_frequency_limit(tube):
    """The corrected slow model (3.49 with q1'' in 3.47-3.48, plus C2) matches the full plant's
    transfer function at low frequency to third order (it neglects C2 K1^-1 z' and J K1^-1 z'');
    with the printed J q1' the mass K* J is missing (it turns into a small damping, in quadrature) and
    the match drops to second order."""
    b = tube.blocks
    s = ctl.slow_model(b)

    def G_full(w):
        return tube.frequency_response(np.array([w]))[0]

    def G_slow(w, M, Cc):
        return np.linalg.solve(-w * w * M + 1j * w * Cc + s["K"], s["B"])

    def rel(w, M, Cc):
        g = G_full(w)
        return np.linalg.norm(g - G_slow(w, M, Cc)) / np.linalg.norm(g)

    w1 = 2 * np.pi * 20.0
    order = math.log2(rel(2 * w1, s["M"], s["C"]) / rel(w1, s["M"], s["C"]))
    assert order >= 2.9
    printed_M, printed_C = b["D"], s["C"] + s["Kstar"] @ b["J"]  # J q1' -> K* J q1' (a damping)
    order_p = math.log2(rel(2 * w1, printed_M, printed_C) / rel(w1, printed_M, printed_C))
    assert abs(order_p - 2) <= 0.1
    # K* = K1 (K1 + K2)^-1 equals the printed (K1 + K2)^-1 K1 when the matrices commute (diagonal here)
    K1, K2 = b["K1"], b["K2"]
    assert np.allclose(s["Kstar"], np.linalg.solve(K1 + K2, K1), rtol=1e-12, atol=0)


def test_stability_of_the_laws(tube):
    """No time-scale separation on the real probe: slow-only feedback (3.54) destabilises the tube
    mode (non-collocated), the plain PID at the same bandwidth too; composite control is stable."""
    laws = studies.default_laws()
    st = {k: ctl.stability(tube, c.design(tube)) for k, c in laws.items()}
    assert st["composite (3.50-3.54)"]["stable"]
    assert not st["slow (3.54)"]["stable"]
    assert not st["PID, same bandwidth"]["stable"]
    assert st["open (dynamic inverse)"]["stable"]


# ------------------------------------------------------------------------------- inversion


def test_dynamic_inverse_converges_at_the_integrators_order(tube):
    """Driving the plant with the exact two-body inverse, the only error left is the first-order
    hold of the forcing: second order in h (observed order 2 +- 0.3)."""
    p = paths.make_path("cone", size=0.5e-6, duration=0.02)
    law = ctl.OpenLoop("dynamic").design(tube)
    e = [simulate.simulate(tube, law, p, h=h).metrics()["max_error_m"] for h in (2e-6, 1e-6)]
    assert abs(math.log2(e[0] / e[1]) - 2) <= 0.3
    qs = simulate.simulate(tube, ctl.OpenLoop("quasi-static").design(tube), p, h=1e-6).metrics()["max_error_m"]
    assert e[1] < 1e-3 * qs


def test_frequency_domain_inverse_agrees_with_the_exact_one(tube):
    """The general (FFT, stable-inversion) inverse reproduces the two-body inverse's dynamic
    correction; the discrepancy falls with the grid step (observed order > 1.5)."""
    p = paths.make_path("cone", size=0.5e-6, duration=0.02)
    errs = []
    for n in (2000, 8000):
        t = np.linspace(0, p.duration, n + 1)
        R = inversion.path_on_outputs(tube, p.derivatives(t))
        u1, _ = inversion.two_body_inverse(tube, R)
        u2 = inversion.fft_inverse(tube, t, R[0], R[1])
        u0 = inversion.quasi_static(tube, R[0])
        errs.append(np.max(np.abs(u1 - u2)) / np.max(np.abs(u1 - u0)))
    assert errs[1] <= 1e-6 and math.log(errs[0] / errs[1], 4) > 0.75


# ------------------------------------------------------------------------------- simulator


def test_simulator_against_the_closed_loop_transfer_function(tube):
    """Item 7: the steady-state error of a circle from the closed-loop frequency response agrees
    with the time simulation within the first-order-hold bound of the integrator."""
    r = studies.frequency_response_check(tube, h=1e-5)
    assert r["agrees"], r
    assert r["tolerance_m"] < 0.3 * r["forced_error_amplitude_m"]  # the check discriminates


def test_disturbance_force_is_minus_the_gradient():
    s = dist.kbr(1.0)
    rng = np.random.default_rng(3)
    xy = rng.uniform(0, 2e-9, size=(20, 2))
    h = 1e-13
    for i, d in enumerate(np.eye(2)):
        fd = -(s.potential(xy + h * d) - s.potential(xy - h * d)) / (2 * h)
        # truncation h^2/6 k^3 (p1 + p2) plus round-off eps |P| / h
        tol = h**2 / 6 * s.k**3 * (s.p1 + s.p2) + 4 * EPS * 2 * (s.p1 + s.p2) / h
        assert np.max(np.abs(fd - s.force(xy)[:, i])) <= tol
        Jfd = (s.force(xy[0] + h * d) - s.force(xy[0] - h * d)) / (2 * h)
        assert np.max(np.abs(Jfd - s.jacobian(xy[0])[:, i])) <= h**2 / 6 * s.k**4 * (s.p1 + s.p2) \
            + 4 * EPS * s.force_amplitude / h
    # the unit reading of SOURCE-NOTES 13: p1 = 0.33 eV, a force amplitude of 0.5-0.6 nN
    assert s.p1 / dist.EV == pytest.approx(0.3296, rel=1e-3)
    assert 1e-12 < s.force_amplitude < 1e-9


def test_nonlinear_integrator_is_second_order(tube):
    """With the KBr disturbance (nonlinear in the tip position) ETD2 is second order: successive
    differences at h, h/2, h/4 fall by 4 (observed order 2 +- 0.35). The comparison with an
    independent solve_ivp solution is in tests/test_tracking_slow.py."""
    # a 2.5 nm helix in 1 ms: lattice crossings at v / a ~ 60 kHz, resolved by >= 40 steps
    p = paths.make_path("cylinder", size=2.5e-9, height=1e-8, duration=1e-3)
    law = ctl.CompositeControl(0.2, 0.7, 0.7).design(tube)
    surf = dist.kbr(1.0)
    t_eval = np.linspace(0, 1e-3, 11)
    ys = []
    for h in (4e-7, 2e-7, 1e-7):
        r = simulate.simulate(tube, law, p, surface=surf, h=h, max_points=10**7)
        ys.append(np.array([np.interp(t_eval, r.t, r.y[:, j]) for j in range(3)]).T)
    d1, d2 = np.max(np.abs(ys[0] - ys[1])), np.max(np.abs(ys[1] - ys[2]))
    assert abs(math.log2(d1 / d2) - 2) <= 0.35


def test_saturation_and_noise(tube):
    p = paths.make_path("cone", size=0.5e-6, duration=0.05)
    law = ctl.CompositeControl(0.2, 0.7, 0.7).design(tube)
    r = simulate.simulate(tube, law, p, v_max=15.0)
    assert np.max(np.abs(r.u)) <= 15.0 * (1 + 1e-12)
    noise = simulate.SensorNoise(2e-9, 10e3, seed=4)
    nu = noise.realise(0.05, 3, 1e-6)
    tg = np.arange(int(round(0.05 / 1e-6)) + 1) * 1e-6
    v = nu(tg)
    # equal-amplitude random-phase sinusoids on the record's Fourier grid: RMS exactly rms (the
    # record holds one more sample than the FFT period: error O(1/N))
    assert np.sqrt(np.mean(v[:-1, :3] ** 2, axis=0)) == pytest.approx([2e-9] * 3, rel=1e-9)
    fd = np.gradient(v[:, 0], 1e-6)
    # the derivative channel is the spectral derivative: central differences agree to (w h)^2 / 6
    w = 2 * np.pi * 10e3
    assert np.max(np.abs(fd[1:-1] - v[1:-1, 3])) <= (w * 1e-6) ** 2 / 6 * np.max(np.abs(v[:, 3])) * 3


def test_track_summary_and_provenance():
    res, s = studies.track(plant_factory(), "duo-bimorph", "circle", "open", duration=0.2)
    assert set(s["metrics"]["axes"]) == {"y", "z"}
    assert "analytic gains" in s["provenance"]["gains"]
    assert s["metrics"]["relative_max_error_after_transient"] < 1e-3
    with pytest.raises(ProbedynError, match="unstable"):
        studies.track(plant_factory(), "piezotube", "cone", "slow")


# ------------------------------------------------------------------------------------- CLI


def test_track_cli_json_and_bad_input(capsys, tmp_path):
    import json

    from probedyn.cli import main

    assert main(["track", "duo-bimorph", "--path", "circle", "--control", "open", "--duration", "0.2", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["metrics"]["axes"]) == {"y", "z"} and set(d["metrics"]["voltage_peak_V"]) == {"V_y", "V_z"}
    assert "gains" in d["provenance"] and "body" in d["provenance"]
    bad = tmp_path / "bad.csv"
    bad.write_text("0,0,0,0\n0.2,1e-8,0,0\n0.1,0,0,0\n0.3,0,0,0\n")
    for argv in (["track", "piezotube", "--path", "spiral"], ["track", "piezotube", "--path", str(bad)],
                 ["track", "piezotube", "--path", "cone", "--size", "5e-6"],
                 ["track", "piezotube", "--path", "cone", "--control", "bang-bang"]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("probedyn: error:") and "\n" not in err


def test_track_cli_out(tmp_path, capsys):
    import importlib.util

    if importlib.util.find_spec("probedyn.report") is None or \
            importlib.util.find_spec("probedyn.report").submodule_search_locations is None:
        pytest.skip("probedyn.report is not a package yet (lands with i9-cli)")
    from probedyn.cli import main

    assert main(["track", "piezotube", "--path", "cone", "--duration", "0.1", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "track.png").stat().st_size > 10000 and (tmp_path / "track.json").exists()


def test_modal_body_plant_is_the_two_body_model_in_other_coordinates(tube):
    """r = d retained modes with Phi = U reproduce the two-body plant (3.37) exactly: same
    frequencies (1e-9 relative, eigen-solver round-off) and static stroke."""
    import scipy.linalg as sla

    from probedyn.schemes.tracking.plants import modal_body_plant, with_blocks

    b = tube.blocks
    lam, V = sla.eigh(b["K2"], b["J"])  # J-orthonormal body modes in holder coordinates: q2 = V eta
    omega = np.sqrt(lam)
    Act = V.T @ b["Gamma"]
    p = modal_body_plant(omega, 0.0, V, Act, b["D"][0, 0], np.diag(b["K1"]), tube.outputs, tube.inputs)
    tube0 = with_blocks(tube, C2=np.zeros_like(b["C2"]))  # the modal plant was built without body damping
    assert np.allclose(np.sort(p.frequencies_hz()), np.sort(tube0.frequencies_hz()), rtol=1e-9, atol=0)
    assert np.allclose(p.static_gain(), tube.static_gain(), rtol=1e-9, atol=1e-9 * np.max(np.abs(tube.static_gain())))

