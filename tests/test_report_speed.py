"""The report's speed-ups change no number (issue 15 part 1; docs/developing.md "The report
package"). References: the code paths they replace, run side by side.

* pushes: ``PushModel.rhs_1d`` does the operations of ``rhs`` on the 1D state, and the Radau
  subclass calls the LAPACK routines ``scipy.linalg.lu_factor/lu_solve`` call: both must agree
  to the last bit (``array_equal``), not to a tolerance, so that every push, and every printed
  step length and transition speed, is the same as before;
* the truncation check's direct frequency responses: one factorisation per frequency with the
  three directions as right-hand sides vs one factorisation per direction; the linear solves
  agree to their round-off (relative 1e-10 is 1e5 x machine epsilon times a condition number
  of order 10 for K - w^2 M below the first discarded mode: a wide margin).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import lu_factor, lu_solve

from probedyn.lumped.ritz import direct_compliance, direct_compliances
from probedyn.probes import get_probe
from probedyn.schemes import pushing as P
from probedyn.schemes import pushing_studies as PS


def test_rhs_1d_is_the_full_rhs_on_the_x_components_bit_for_bit():
    rng = np.random.default_rng(7)
    m = P.make_model("mica", {}, dim=1)
    scale = np.array([1e-9, 1e-6, 1e-9, 1e-6, 1e-11, 1e-6])  # positions, speeds, bristle, memory
    for _ in range(200):
        y1 = rng.standard_normal(6) * scale
        y1[2] += m.p["gap0"]  # around the start: in and out of contact
        full = np.zeros(P.NS)
        full[P.IX] = y1
        t = float(rng.uniform(0, 1e-3))
        assert np.array_equal(m.rhs_1d(t, y1), m.rhs(t, full)[P.IX])


@pytest.mark.parametrize("dtype", [float, complex])
def test_radau_direct_lapack_is_scipy_lu_bit_for_bit(dtype):
    rng = np.random.default_rng(3)
    solver = P._Radau(lambda t, y: -y, 0.0, np.ones(6), 1.0, jac=lambda t, y: -np.eye(6))
    for n in (6, 11):
        A = rng.standard_normal((n, n)).astype(dtype)
        b = rng.standard_normal(n).astype(dtype)
        if dtype is complex:
            A = A + 1j * rng.standard_normal((n, n))
            b = b + 1j * rng.standard_normal(n)
        lu_ref = lu_factor(A.copy(), overwrite_a=True)
        lu_new = solver.lu(A.copy())
        assert np.array_equal(lu_ref[0], lu_new[0]) and np.array_equal(lu_ref[1], lu_new[1])
        assert np.array_equal(lu_solve(lu_ref, b.copy(), overwrite_b=True), solver.solve_lu(lu_new, b.copy()))
    with pytest.raises(ValueError):
        solver.lu(np.full((6, 6), np.nan))


def test_push_memo_runs_each_distinct_push_once(monkeypatch):
    calls = []

    def fake_push(sub, ov, dim=None):
        calls.append((sub, dict(ov), dim))
        return object(), {}

    monkeypatch.setattr(P, "push", fake_push)
    monkeypatch.setattr(PS, "_RUNS", type(PS._RUNS)())
    a = PS.push("mica", {"V": P.PARAMS["V"].default})
    b = PS.push("mica", {"F_v": P.PARAMS["F_v"].default})  # both the defaults: the same push
    c = PS.push("mica", {"F_v": 2e-5})
    d = PS.push("mica", {"angle": 15.0})
    assert a is b and c is not a and d is not a
    assert [x[0] for x in calls] == ["mica"] * 3 and calls[-1][2] == 2


def test_direct_compliances_equal_one_solve_per_direction():
    p, _ = get_probe("cantilever")
    v = p.resolve({"elements_through_thickness": 1, "tip_shape": "none"})
    model = p.build(v)
    f1 = model.modes(1).modes[0].frequency_hz
    f = np.array([0.0, 0.5 * f1, 2.5 * f1])  # static, below and above the first mode
    dirs = [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0)]
    many = direct_compliances(model, "free_end", dirs, f)
    assert many.shape == (3, 3)
    for d, row in zip(dirs, many):
        np.testing.assert_allclose(row, direct_compliance(model, "free_end", d, f), rtol=1e-10)
