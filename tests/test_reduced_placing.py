"""Nano-placing on a reduced probe (issue 10 item 3): ``PlacingProbe.from_reduced``.

Reference: the placing probe nano-placing builds itself from the same FE model
(``PlacingProbe.from_ritz(placing_ritz(model))``: its own eigen-solve and static solve of the
free-end face) and the FEM's direct frequency response ``(K - omega^2 M) u = A^T d``.

Why the tolerances: a reduced probe keeps the FEM modes themselves (the Ritz frequencies of
the retained modes are the FEM's) and the static shapes of its point, so its static stiffness
at the point is the FEM static solve: the reduction adds no truncation error to k, the
frequencies or the tip-normalised modal masses; what is left is the solvers' precision (linear
solves ~1e-12, shift-invert eigen-solution ~1e-10; 1e-7 is a wide margin). The dynamic tip
compliance of a static-corrected modal sum obeys the truncation bound of docs/reduced-probes.md
section 2: ``0 <= H_FEM - H_corr <= R x^2 / (1 - x^2)``, x = f / validity limit, R the residual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.lumped.reduced import reduce_model
from probedyn.lumped.ritz import direct_compliance
from probedyn.probes.placing import placing_model, placing_probe, placing_probe_from_reduced, placing_ritz
from probedyn.schemes.placing.probe import PlacingProbe


@pytest.fixture(scope="module")
def pair():
    model, values = placing_model()  # Table 4.4 cantilever, one element layer (13.8k DOFs)
    ref = PlacingProbe.from_ritz(placing_ritz(model), n_modes=4, zeta=0.0)
    rp = reduce_model(model, "free_end", n_modes=8, provenance=dict(probe="cantilever", parameters=values))
    rp.ritz.model = model
    return model, ref, rp


def test_placing_probe_from_reduced_is_the_fem_placing_probe(pair):
    model, ref, rp = pair
    pp = placing_probe_from_reduced(rp, n_modes=4, zeta=0.0)
    assert pp.k == pytest.approx(ref.k, rel=1e-7)
    assert np.allclose(pp.omegas, ref.omegas, rtol=1e-7, atol=0)
    assert np.allclose(pp.modal_masses, ref.modal_masses, rtol=1e-7, atol=0)
    assert pp.rhoA == pytest.approx(ref.rhoA, rel=1e-12) and pp.L == pytest.approx(ref.L, rel=1e-12)
    # Euler-Bernoulli sanity (independent): 3EI/L^3 of the Table 4.4 beam is 1 N/m by construction,
    # the 3D plate is stiffer by ~1/(1 - nu^2) at most (w/t = 1.6: closer to the beam), f1 within 1 %
    assert 1.0 <= pp.k <= 1.0 / (1 - 0.28**2)
    assert pp.model is model and pp.ritz is rp.ritz  # kept for capture / several samples


def test_reduced_placing_compliance_within_truncation_bound(pair):
    model, ref, rp = pair
    pp = placing_probe_from_reduced(rp, n_modes=8, zeta=0.0)  # every normal mode retained
    x = np.array([0.0, 0.5, 0.9])
    f = x * rp.validity_hz
    H = direct_compliance(model, "free_end", (0.0, 0.0, 1.0), f)
    Hc = pp.tip_compliance(2 * math.pi * f).real
    R = 1.0 / pp.k - float(np.sum(1.0 / pp.modal_stiffnesses()))
    tol = 1e-7 * abs(H[0])
    assert R > 0
    assert abs(Hc[0] - H[0]) <= tol
    assert np.all(H - Hc >= -tol)
    assert np.all(H - Hc <= R * x**2 / (1 - x**2) + tol)


def test_place_accepts_saved_reduced_probe(pair, tmp_path):
    model, ref, rp = pair
    path = rp.save(tmp_path / "placing.json")
    pp = placing_probe(str(path), n_modes=4)
    assert pp.k == pytest.approx(ref.k, rel=1e-7)
    assert pp.f1 == pytest.approx(ref.f1, rel=1e-7)
    with pytest.raises(ParameterError, match="overrides"):
        placing_probe(str(path), {"length": 1e-3})
    with pytest.raises(ParameterError, match="no normal direction"):
        placing_probe("table-2.1")
