"""Long nano-placing studies (``pytest -m slow``): the capture frequency equation against full FEM
re-solves over the whole beta range, the FEM-mode Rayleigh-Ritz model against full re-solves
with two masses, the 64 x 64 release map on Dask with two worker processes, and the slow
approach at a lower speed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from probedyn.schemes.placing import capture as cap
from probedyn.schemes.placing import multi as mu
from probedyn.schemes.placing import release as rel
from probedyn.schemes.placing.approach import Approach
from probedyn.schemes.placing.probe import TABLE, PlacingProbe

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module", params=[0.0, None], ids=["nu=0", "silicon"])
def fem(request):
    from probedyn.probes.placing import placing_model

    ov = {} if request.param is None else {"poisson_ratio": request.param}
    model, _ = placing_model(ov)
    return model, PlacingProbe.from_fem(model, n_modes=3)


def test_capture_equation_against_full_fem_resolves(fem):
    """Grounded spring K = k1 L^3/EI from 0 to 3000 (free end to nearly pinned) and tip masses
    mu = 0..1: bL from 1.25 to 10.0; the issue's bar is 0.5 %; the one-layer P2 FEM's own error
    on the third flapwise mode is ~0.1 %."""
    model, probe = fem
    rows = cap.capture_check(probe, [(K, m_) for K in (0.0, 3.0, 30.0, 300.0, 3000.0) for m_ in (0.0, 0.1, 1.0)], 3)
    err = max(abs(r["rel_diff"]) for r in rows)
    assert err < 5e-3
    assert min(r["bL"] for r in rows) < 1.3 and max(r["bL"] for r in rows) > 9.9


def test_capture_mode_shapes_fem_vs_analytic(fem):
    model, probe = fem
    for K in (0.0, 30.0, 3000.0):
        k1 = K * probe.EI / probe.L**3
        res = cap.fem_capture_frequencies(model, k1, 0.0, 3)
        c = cap.Capture.from_probe(probe, k1, 0.0)
        an = c.shapes(res["x"], 3)
        for j in range(3):
            a, f = an[j], res["shapes"][j]
            mac = (a @ f) ** 2 / ((a @ a) * (f @ f))
            assert mac > 0.999


def test_fem_mode_ritz_against_full_resolve_two_masses(fem):
    model, probe = fem
    L, mb = probe.L, probe.beam_mass
    for ratio in (0.1, 1.0):
        ms = [(0.5 * L, ratio * mb), (L, ratio * mb)]
        ref = mu.fem_frequencies(model, ms, 3)
        b = mu.ritz_basis(model, 8, [0.5 * L, L], static=True)
        om = mu.ritz_flapwise(b, ms, 3)
        # static shapes at the masses: exact statics; the dynamic residual ~ (w / w_9)^2 is < 1e-4
        assert np.all(np.abs(om / ref - 1) < 1e-4)
        assert np.all(om >= ref * (1 - 1e-9))  # upper bounds


def test_release_map_64x64_on_dask():
    probe = PlacingProbe.table()
    n = 64
    om = np.geomspace(1e6, 1e10, n)
    A = np.geomspace(1e-10, 2e-6, n)
    res = rel.outcome_map(probe, {"omega": om, "A": A}, fixed={"M": float(TABLE["M1"])}, workers=2,
                          processes=True, chunk_size=256)
    o = res.dataset["outcome"].transpose("omega", "A").values
    assert not np.any(o == -1)
    assert np.mean(o == 3) < 0.01
    tabs = rel._tables(float(TABLE["lambda"]))
    k1 = tabs.k1_bar * tabs.P / tabs.l
    wc = math.sqrt(k1 / float(TABLE["M1"]))
    Ath = rel.threshold_amplitude(float(TABLE["M1"]), om, tabs.pull_off_force, k1)
    for i in np.nonzero(om < 0.2 * wc)[0]:  # quasi-static contact: the pull-off threshold is the boundary
        assert np.all(o[i, A < 0.8 * Ath[i]] == 0)
        assert np.all(o[i, A > 1.5 * Ath[i]] == 2)


def test_slow_approach_converges_to_the_fold():
    ap = Approach.from_probe(PlacingProbe.table())
    d = [ap.simulate_approach(v)["delay_m"] for v in (1e-6, 1e-7)]
    expo = math.log(d[0] / d[1]) / math.log(10.0)
    assert 0.6 < expo < 0.8  # closer to the fold-passage 2/3 at the lower speed


def test_report_section_quick(tmp_path):
    from probedyn.report.placing import section

    md = section(tmp_path, quick=True)
    for key in ("Approach (4.13-4.21)", "Capture (4.22-4.41)", "Release (4.42)", "Flight and landing",
                "Several samples", "Table 4.4's mass"):
        assert key in md
    for name in ("approach", "capture", "release", "landing", "multi"):
        assert (tmp_path / f"placing_{name}.png").stat().st_size > 20_000
