"""The viscoelastic (standard linear solid) sphere contact of probedyn.schemes.contact.viscoelastic and the
diagnose cause ``viscoelastic-sample`` built on it.

Independent checks: Lee-Radok's closed form for a constant-rate approach (Dawson's integral), the
elastic limits tau -> 0 (E_inf) and tau -> infinity (E_0), a brute-force O(N^2) quadrature of the
Lee-Radok / Ting integrals with the lever (tests/diagnose_truth_curves.visco_lever_truth, written
separately), and Ting's physics (the retract below the approach at equal indentation, contact lost
at positive indentation: before the approach's contact point).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_truth_curves import make_visco_case, visco_lever_truth  # noqa: E402

from probedyn.schemes.contact.viscoelastic import (  # noqa: E402
    lee_radok_constant_rate,
    power_law,
    sls_indentation_force,
    sls_lever_curve,
)

R = 20e-9
C, M = power_law("sphere", R)
E_INF, S, TAU, V = 1e6, 2.0, 0.05, 1e-6  # 1 MPa, E_0 = 3 E_inf, 50 ms, 1 um/s


def test_lee_radok_constant_rate_closed_form():
    dt = 5e-5
    t = np.arange(0, 0.1 + dt / 2, dt)
    P = sls_indentation_force(t, V * t, C, M, E_INF, S, TAU)
    Pc = lee_radok_constant_rate(t, V, C, E_INF, S, TAU)
    # the recursion is exact for g(delta(t)) linear in time within a step: its error is second order in dt / tau
    assert np.max(np.abs(P - Pc)) <= (dt / TAU) ** 2 * Pc.max()


def test_elastic_limits_of_the_relaxation_time():
    dt = 5e-5
    t = np.arange(0, 0.2 + dt / 2, dt)
    d = V * np.minimum(t, 0.2 - t)  # approach and retract (the retract through Ting's t1)
    Pe = E_INF * C * d**1.5
    fast = sls_indentation_force(t, d, C, M, E_INF, S, 1e-7)
    slow = sls_indentation_force(t, d, C, M, E_INF, S, 1e3)
    # tau << dt: the relaxing arm carries at most its weight on the last step, s tau / dt
    assert np.max(np.abs(fast - Pe)) <= S * 1e-7 / dt * Pe.max()
    # tau >> record T: the modulus E_0 = (1 + s) E_inf relaxed by at most a fraction T / tau
    assert np.max(np.abs(slow - (1 + S) * Pe)) <= S * 0.2 / 1e3 * Pe.max()
    # strength 0 is the elastic law (the nested null; to the round-off of Ting's t1 search -- the diagnosis
    # does not even enter the law at strength 0, so its null is bit-exact there)
    P0 = sls_indentation_force(t, d, C, M, E_INF, 0.0, TAU)
    assert np.allclose(P0, E_INF * C * np.maximum(d, 0) ** 1.5, rtol=1e-10, atol=1e-12 * Pe.max())


def test_ting_retract_below_approach_and_contact_lost_early():
    dt = 5e-5
    t = np.arange(0, 0.2 + dt / 2, dt)
    d = V * np.minimum(t, 0.2 - t)
    P = sls_indentation_force(t, d, C, M, E_INF, S, TAU)
    n = len(t) // 2
    app, ret = P[1:n], P[n + 1:][::-1][1:n]  # equal indentation: the mirrored sample
    assert np.all(ret[10:] < app[10:])
    lost = np.nonzero(P[n:] == 0)[0]
    assert lost.size and d[n + lost[0]] > 0.05 * d.max()  # the surface lags: the tip leaves it above delta = 0
    assert np.all(P >= 0)


@pytest.mark.parametrize("ratio", [1.0, 10.0])
def test_lever_curve_against_brute_force_quadrature(ratio):
    n, dt, k = 300, 2e-3, 1.0
    z_app = np.linspace(-60e-9, 200e-9, n)
    z = np.concatenate([z_app, z_app[::-1]])
    t = np.concatenate([np.arange(n) * dt, (n - 1) * dt + np.arange(1, n + 1) * dt / ratio])
    E, s, tau = 5e6, 0.8, 0.1
    F = sls_lever_curve(t, z, k, C, M, E, s, tau)
    Ft = visco_lever_truth(t, z, k, E, s, tau, R)
    # the two discretisations differ at the touch and in Ting's t1 by O(dt^2) terms; 1e-3 of the largest force
    # is below the noise of any force curve (0.05 nN of tens of nN)
    assert np.max(np.abs(F - Ft)) <= 1e-3 * Ft.max()
    # the lever's retract loses contact before the approach's contact point (z_rel = 0)
    ret = slice(n, 2 * n)
    assert z[ret][np.nonzero(F[ret] == 0)[0][0]] > 0
    # strength 0: Hertz on the lever (the baseline's law): delta + P / k = z_rel at every sample
    F0 = sls_lever_curve(t, z, k, C, M, E, 0.0, tau)
    dl = z - F0 / k
    assert np.allclose(F0, E * C * np.maximum(dl, 0) ** 1.5, rtol=1e-12, atol=1e-12 * F0.max())


def test_input_errors():
    with pytest.raises(ValueError):
        sls_lever_curve([0.0, 0.0], [0.0, 1e-9], 1.0, C, M, E_INF, S, TAU)
    with pytest.raises(ValueError):
        sls_lever_curve([0.0, 1.0], [0.0, 1e-9], 1.0, C, M, E_INF, -1.0, TAU)


def _problem(tmp_path, seed=2100, time=True):
    from probedyn.diagnose.problems import make_problem

    path, truth = make_visco_case(tmp_path, seed)
    if not time:  # the same record without its time column
        csv = path.with_suffix(".csv")
        rows = csv.read_text().splitlines()
        csv.write_text("\n".join(",".join(r.split(",")[:3]) for r in rows) + "\n")
    return make_problem(path), truth


def test_cause_nests_the_baseline_and_needs_times(tmp_path):
    from probedyn.diagnose.engine import Fitter

    prob, truth = _problem(tmp_path)
    keys = [c.key for c in prob.causes]
    assert "viscoelastic-sample" in keys
    c = prob.causes[keys.index("viscoelastic-sample")]
    F = Fitter(prob)
    v = {p.name: p.null for p in prob.base_params}  # the baseline's starting values
    r_base = F.residuals(v, ())
    r_null = F.residuals({**v, **{p.name: p.null for p in c.params}}, (c,))
    assert np.array_equal(r_base, r_null)  # the null is exactly the baseline
    r_true = F.residuals({**v, "strength": truth["params"]["strength"], "tau": truth["params"]["tau"]}, (c,))
    assert not np.allclose(r_true, r_base)
    prob2, _ = _problem(tmp_path / "nt", time=False)
    assert "viscoelastic-sample" not in [c.key for c in prob2.causes]
    assert "time_s" in prob2.describe()["causes_not_offered"]["viscoelastic-sample"]


@pytest.mark.slow
def test_viscoelastic_case_named_and_recovered(tmp_path):
    from probedyn.diagnose.engine import run

    path, truth = make_visco_case(tmp_path, 2100)
    res = run(path)
    f0 = res["findings"][0]
    assert f0["cause"] == "viscoelastic-sample"
    s = f0["parameters"]["strength"]
    # within 4 of its own standard errors of the truth (an uncertainty that cannot be right fails here)
    assert abs(s["value"] - truth["params"]["strength"]) <= 4 * s["sigma"]


def test_separating_measurements_ramp_rate_and_tip_radius(tmp_path):
    """The observables that separate a viscoelastic sample from elastic causes: an elastic contact
    predicts the same approach force at every ramp rate; the SLS sample relaxes on a slower ramp
    and stiffens on a faster one, bounded by the elastic curves of its relaxed and instantaneous
    moduli (E_inf <= E(t) <= E_0); a tip-radius error predicts another imaged radius."""
    prob, truth = _problem(tmp_path)
    keys = [c.key for c in prob.causes]
    visco = prob.causes[keys.index("viscoelastic-sample")]
    radius = prob.causes[keys.index("tip-radius-error")]
    v = {p.name: p.null for p in prob.base_params}

    def obs(values, causes):
        return {m["measure"]: m for m in prob.predict_observables(values, causes)}

    slow, fast = ("approach force at the deepest point, ramp 10x slower",
                  "approach force at the deepest point, ramp 10x faster")
    el = obs(v, ())
    assert el[slow]["value"] == el[fast]["value"]  # elastic: rate independent
    s, tau = truth["params"]["strength"], truth["params"]["tau"]
    vi = obs({**v, "strength": s, "tau": tau}, (visco,))
    E_inf = v.get("E_star", prob.E_star_declared)  # the baseline's modulus plays the relaxed one
    stiff = obs({**v, "E_star": E_inf * (1 + s)}, ())  # elastic at the instantaneous modulus E_0
    assert el[slow]["value"] <= vi[slow]["value"] < vi[fast]["value"]
    assert vi[fast]["value"] - vi[slow]["value"] > 3 * vi[slow]["sigma"]  # resolvable: tau within the ramp
    assert vi[fast]["value"] <= stiff[fast]["value"] * (1 + 1e-9)
    imaged = "tip radius imaged independently (SEM / tip characteriser)"
    tr = obs({**v, "r_ratio": 1.5}, (radius,))
    assert tr[imaged]["value"] == pytest.approx(1.5 * el[imaged]["value"], rel=1e-12)
    assert vi[imaged]["value"] == el[imaged]["value"]
