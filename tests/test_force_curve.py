"""schemes.contact.force_curve: cantilever force curves over the contact models (jump-in/out)."""

from __future__ import annotations

import pytest

from probedyn.core.errors import ParameterError
from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.contact.force_curve import force_curve, tail_jump_gap


@pytest.mark.parametrize("k", [0.1, 1.0])
def test_jump_in_where_the_tail_gradient_equals_k(k):
    # sphere-flat vdW tail P = -HR/6d^2: |dP/dd| = HR/3d^3 = k at d* = (HR/3k)^(1/3); the path
    # is sampled with 0.3 % spacing in gap, the tolerance
    m = get_contact_model("dmt")
    r = force_curve(m, k)
    s = m.scales
    assert r["jump_in"] is not None and r["jump_in"]["in_tail"]
    assert r["jump_in"]["gap_before"] == pytest.approx(tail_jump_gap(s.H, s.R, k), rel=0.005)
    assert r["jump_in"]["P_before"] == pytest.approx(-s.H * s.R / (6 * r["jump_in"]["gap_before"] ** 2), rel=1e-3)
    assert r["jump_in"]["P_after"] < r["jump_in"]["P_before"]  # lands deeper in the attraction


def test_stiff_cantilever_does_not_jump():
    # d* below the tail's end gap (zeta_0 for DMT): the approach is continuous, and so is the
    # retraction of the DMT curve (it is monotone)
    m = get_contact_model("dmt")
    k = 20.0
    assert tail_jump_gap(m.scales.H, m.scales.R, k) < m.scales.z0
    r = force_curve(m, k)
    assert r["jump_in"] is None and r["jump_out"] is None


def test_soft_cantilever_jumps_out_at_the_pull_off():
    # k -> 0 is load control: the jump-out load tends to the pull-off force (DMT -2 pi W R,
    # JKR -1.5 pi W R); with k = 0.05 N/m the load at the fold differs from the minimum by
    # O(k * slope^-1), < 1 % here
    for name in ("dmt", "jkr"):
        m = get_contact_model(name)
        r = force_curve(m, 0.05)
        assert r["jump_out"]["P_before"] == pytest.approx(m.pull_off_force(), rel=0.01)
    with pytest.raises(ParameterError):
        force_curve(get_contact_model("dmt"), -1.0)
