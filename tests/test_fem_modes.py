"""Mode classification on synthetic displacement fields with known kinematics."""

from __future__ import annotations

import numpy as np

from probedyn.fem.modes import classify_shapes

L, W, T = 300e-6, 30e-6, 10e-6


def _cloud(n=6000, seed=0):
    rng = np.random.default_rng(seed)
    x = np.stack([rng.uniform(0, L, n), rng.uniform(-W / 2, W / 2, n), rng.uniform(-T / 2, T / 2, n)])
    return x, np.ones(n)


def test_families_of_synthetic_fields():
    x, w = _cloud()
    s = x[0] / L
    bend = s**2  # a bending deflection v(x) with slope v'(x) = 2 x / L^2
    dbend = 2 * s / L
    fields = {
        # flapwise: u_z = v, u_x = -z v' (plane sections stay plane)
        "flapwise": np.stack([-x[2] * dbend, 0 * s, bend]),
        "lateral": np.stack([-x[1] * dbend, bend, 0 * s]),
        # torsion: rotation theta(x) about the axis: u = theta (0, -z, y)
        "torsion": np.stack([0 * s, -x[2] * s / L, x[1] * s / L]),
        "axial": np.stack([s, 0 * s, 0 * s]),
        # cross-section breathing (plate-like): u_y ~ y, u_z ~ -z, not a rigid section motion
        "other": np.stack([0 * s, x[1] * s / W, -x[2] * s / T]),
    }
    U = np.stack([f.T for f in fields.values()], axis=-1)  # (n, 3, k)
    fams, shares = classify_shapes(x, w, U)
    assert fams == list(fields)
    for fam, sh in zip(fams[:4], shares[:4]):
        assert sh[fam] > 0.99  # exact rigid-section kinematics: nearly all energy in one group
    assert shares[4]["deformation"] > 0.99


def test_mixed_mode_is_other_and_axis_permutation():
    x, w = _cloud(seed=1)
    s = x[0] / L
    # equal flapwise and lateral translation amplitudes: no family above 0.5
    mixed = np.stack([0 * s, s**2, s**2]).T[:, :, None]
    fams, shares = classify_shapes(x, w, mixed)
    assert fams == ["other"]
    assert abs(shares[0]["flapwise"] - shares[0]["lateral"]) < 0.05
    # a beam along z (axis=2): the z-displacement is axial
    xz = x[[1, 2, 0]]  # beam axis now z
    U = np.stack([0 * s, 0 * s, s]).T[:, :, None]
    assert classify_shapes(xz, w, U, axis=2)[0] == ["axial"]
