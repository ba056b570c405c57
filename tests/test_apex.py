"""FFM's spring at the tip apex and the masses at the apex: FEM vs beam references
(probedyn.studies.reduced.apex_check, probedyn.lumped.apex).

Default cantilever (300 x 30 x 10 um silicon, nu = 0.28) with its default pyramid tip (10 um,
half-angle 0.35 rad), coarse mesh (one P2 layer, 6.5k DOFs; the default two-layer mesh moves
every number used here by < 0.5 % except the sharp apex itself, see the slow test).
"""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.lumped import apex as ax
from probedyn.lumped.beam import RectBeam
from probedyn.studies.reduced import apex_check


@pytest.fixture(scope="module")
def chk():
    return apex_check({"elements_through_thickness": 1}, above_apex=(2e-6,))


def test_printed_form_is_torsion_in_series_with_lateral_bending():
    # hand values: beta(w/t = 3) = 0.2633 (Timoshenko & Goodier series), G = E / 2(1+nu)
    b = RectBeam(300e-6, 30e-6, 10e-6, 169e9, 0.28, 2330.0)
    k = ax.scan_stiffness(b, 10e-6)
    G = 169e9 / 2.56
    assert k["beta"] == pytest.approx(0.2633, abs=1e-4)
    assert k["torsion"] == pytest.approx(G * 30e-6 * 1e-15 * k["beta"] / (300e-6 * 15e-6**2), rel=1e-12)
    assert k["lateral_bending"] == pytest.approx(3 * 169e9 * (10e-6 * 30e-6**3 / 12) / 300e-6**3, rel=1e-12)
    assert 1 / k["series"] == pytest.approx(1 / k["torsion"] + 1 / k["lateral_bending"], rel=1e-12)
    # limits: a tall tip -> torsion dominates (k ~ 1/h^2); no tip lever -> lateral bending dominates
    assert ax.scan_stiffness(b, 1e-3)["series"] == pytest.approx(ax.scan_stiffness(b, 1e-3)["torsion"], rel=0.01)
    with pytest.raises(Exception):
        ax.bending_stiffness(b, x=2 * b.L)


def test_scan_stiffness_fem_vs_beam(chk):
    fem, ref = chk["fem"], chk["formula_refined"]
    # The beam alone (load at the centre of the tip base): Timoshenko lateral bending at the
    # apex's x.  Remaining effects: P2 discretisation (converged to 0.2 % by refinement) and the
    # clamp's Poisson boundary layer (~nu^2 w/L): 1 %.
    assert fem["tip_base"]["scan"] == pytest.approx(ref["lateral_bending"], rel=0.01)
    # 2 um above the apex: + torsion through the lever h + t/2 in series.  The clamp's warping
    # restraint stiffens the torsion (5 % of the compliance here) and the tip's own bending over
    # its lower part softens: 2 %.
    assert fem["apex+2um"]["scan"] == pytest.approx(ref["series"], rel=0.02)
    # at the sharp apex the tip's own compliance adds (mesh-dependent, ~1/h_apex): softer than
    # 2 um up, which is softer than the beam alone
    assert fem["apex"]["scan"] < fem["apex+2um"]["scan"] < fem["tip_base"]["scan"]
    # the printed form (x = L, no shear) vs the refined one: (L/x_a)^3 in bending, L/x_a in torsion
    La = chk["parameters"]["length"] / chk["x_apex"]
    pr = chk["formula_printed"]
    assert ref["torsion"] == pytest.approx(pr["torsion"] * La, rel=1e-12)
    assert ref["lateral_bending"] < pr["lateral_bending"] * La**3


def test_normal_stiffness_and_effective_masses_vs_beam(chk):
    fem = chk["fem"]
    # normal: Timoshenko bending at the apex's x within 1 % (the lever does not enter: a normal
    # force at the apex bends the beam only; shear adds 0.5 %, discretisation 0.1 %, the tip
    # base's local stiffening and the 3D plate effect of w = 3t the rest)
    assert fem["apex"]["normal"] == pytest.approx(chk["normal_reference"]["refined"], rel=0.01)
    em = chk["effective_mass"]
    # first flapwise mode referred to the apex: rho A L / phi(x_a)^2 (+ the tip's mass) within 1 %
    # (shear and rotary inertia ~ (t/L)^2 (bL)^2 = 4e-3; the tip's rotary inertia is neglected)
    assert em["normal_fem"] == pytest.approx(em["beam_at_apex_with_tip"], rel=0.01)
    # ... which is 4 % above the quarter beam mass of the free end (the apex sits 3.6 um inside)
    assert em["normal_fem"] > em["beam_quarter_mass"] * 1.02
    # first lateral mode (the scan direction's mass in FFM): shear and rotary inertia
    # ~ (w/L)^2 (bL)^2 = 3.5e-2 -> 3 %
    assert em["scan_fem"] == pytest.approx(em["beam_at_apex_with_tip"], rel=0.03)


@pytest.mark.slow
def test_sharp_apex_compliance_grows_like_one_over_element_size():
    # The compliance of a sharp tip loaded at its apex diverges (a point force at a cone's
    # apex: stress ~ F/r^2, displacement ~ F/(E r)), so on a mesh refined to h_apex at the apex
    # the excess compliance over the point 1 um up grows like 1/h_apex: C_x * h_apex = const.
    # The mesh puts h/10 at the tip (h = t / elements_through_thickness).
    prods = []
    for ett in (1, 2, 3):
        c = apex_check({"elements_through_thickness": ett}, above_apex=(1e-6,))
        dC = 1 / c["fem"]["apex"]["scan"] - 1 / c["fem"]["apex+1um"]["scan"]
        h_apex = c["parameters"]["thickness"] / ett / 10
        prods.append(dC * h_apex)
    prods = np.array(prods)
    assert np.ptp(prods) / prods.mean() < 0.2
