"""lumped.compare: the Rayleigh quotient (2.46) on FEM mode shapes."""

import pytest

from probedyn.lumped.compare import comparison_rows
from probedyn.lumped import beam as bm
from probedyn.probes import get_probe


@pytest.fixture(scope="module")
def solved():
    p, _ = get_probe("cantilever")
    values = p.resolve({"poisson_ratio": 0.0, "elements_through_thickness": 2})
    return p, values, p.build(values).modes(3)


def test_rayleigh_quotient_of_fem_mode_is_euler_bernoulli_frequency(solved):
    # The RQ uses the Euler-Bernoulli energy functional; on the FEM's first flapwise shape
    # (which differs from the EB shape by shear terms of order (t/L)^2 ~ 1e-3) it must return
    # the EB frequency to that order. (Rayleigh's upper bound does not apply: with shear the
    # centreline slope at the clamp is not zero, so the FEM shape is not EB-admissible.)
    p, values, result = solved
    rows = [r for r in comparison_rows(p, values, result) if "Rayleigh" in r["formula"]]
    r1 = next(r for r in rows if r["family"] == "flapwise" and r["order"] == 1)
    f_eb = bm.eb_frequencies(p.beam(values), "flapwise", 1)[0]
    assert r1["value_hz"] == pytest.approx(f_eb, rel=2e-3)


def test_rows_cover_every_bending_mode_and_are_sorted(solved):
    p, values, result = solved
    rows = comparison_rows(p, values, result)
    assert [r["mode"] for r in rows] == sorted(r["mode"] for r in rows)
    bending = {m.index for m in result.modes if m.family in ("flapwise", "lateral")}
    assert bending <= {r["mode"] for r in rows if "Rayleigh" in r["formula"]}
