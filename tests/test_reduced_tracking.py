"""Path tracking on a reduced probe with the piezo FEM's actuation (issue 10 item 3).

Reference: the coupled piezoelectric FEM's static stroke per volt at the holder point
(``probedyn.probes.tracking.fem_stroke_matrix``: a separate coupled static solve per drive
pattern, ``probes/piezo.py``), on the same mesh.

Why the tolerances:
* with the static pseudo-modes (static correction) the reduced static response at the holder is
  the FEM's *exactly*: the static shapes of unit loads at the holder lie in the Ritz basis, so by
  reciprocity the Galerkin output there equals the exact one (docs/reduced-probes.md section 9);
  what is left is the linear solvers' precision, 1e-6 of the largest stroke is a wide margin;
* with the retained modes only the error is the discarded modes' part, bounded by
  Cauchy-Schwarz: ``|sum_{i>N} phi_i f_i/omega_i^2| <= sqrt(R_dd E_res)`` (R_dd the holder's
  residual compliance, E_res the actuation field's energy outside the retained modes);
* the two-body model (3.37) built from the reduced probe carries ``Gamma = K2 G``, so its static
  tip stroke is G: the piezo FEM's to the same precision.
"""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.core.errors import ParameterError
from probedyn.lumped.reduced import ReducedProbe
from probedyn.probes.reduced_tracking import (actuated_probe, reduced_modal_plant, reduced_two_body_plant,
                                              static_stroke, truncation_bound)
from probedyn.probes.tracking import _probe_values, fem_stroke_matrix, smart_plant

SHORT = {"length": 1e-4, "holder_length": 2e-5}  # a short duo-bimorph: 15k DOFs


def _check(name, ov, n_modes):
    rp = actuated_probe(name, ov, n_modes=n_modes, cache=False)
    probe, v = _probe_values(name, {**ov, "tip": "none"})
    G_fem, _ = fem_stroke_matrix(probe, v, holder_face=True)
    scale = np.abs(G_fem).max()
    G_c, G_n = static_stroke(rp, True), static_stroke(rp, False)
    assert np.all(np.abs(G_c - G_fem) <= 1e-6 * scale)
    err = np.abs(G_n - G_fem)
    assert np.all(err <= truncation_bound(rp) + 1e-9 * scale)
    assert np.all(np.diag(G_n) > 0) and err.max() > 0  # the modes alone miss something
    for plant in (reduced_modal_plant(rp), reduced_two_body_plant(rp)):
        assert np.all(np.abs(plant.static_gain() - G_fem) <= 1e-6 * scale)
    return rp, G_fem


def test_short_duo_bimorph_reduced_plant_static_stroke_is_the_piezo_fem(tmp_path):
    rp, G_fem = _check("duo-bimorph", SHORT, 4)
    # saved and loaded with its actuation (modes + static correction)
    back = ReducedProbe.load(rp.save(tmp_path / "duo.json"))
    assert back.actuation == rp.actuation and back.actuation_static == rp.actuation_static
    assert np.allclose(static_stroke(back, True), static_stroke(rp, True), rtol=1e-12, atol=0)
    # the modal plant's lowest frequency is the two-body model's (the tip on the first body mode)
    f_modal = reduced_modal_plant(back).frequencies_hz()
    f_two = reduced_two_body_plant(back).frequencies_hz()
    assert f_modal[0] == pytest.approx(f_two[0], rel=1e-3)
    # one FEM model on both paths of the tracking factory (smart_plant body="reduced" is this
    # two-body plant): not the default hex-s2 mesh for the FEM lumped body and the piezo FEM's
    # tet-p2 mesh for the reduced one (1e-3 apart); same mesh: the eigensolver's ~1e-11
    ref = smart_plant("duo-bimorph", SHORT, body="fem", gains="fem")
    assert ref.provenance["body_element"] == "tet-p2"
    assert np.allclose(f_two, ref.frequencies_hz(), rtol=1e-6)
    with pytest.raises(ParameterError, match="smart probe"):
        actuated_probe("cantilever")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["duo-bimorph", "piezotube"])
def test_default_smart_probe_reduced_plant_static_stroke_is_the_piezo_fem(name):
    rp, G_fem = _check(name, {}, 6)
    # the tracking factory's reduced body = the FEM lumped body (same first body modes): with the
    # piezo FEM's gains both are built on the piezo FEM's mechanical model (piezo.coupled_values:
    # one element and mesh), so they differ by the eigensolver's precision only (~1e-11)
    p = smart_plant(name, body="reduced", gains="fem")
    ref = smart_plant(name, body="fem", gains="fem")
    assert np.allclose(p.frequencies_hz(), ref.frequencies_hz(), rtol=1e-6)
