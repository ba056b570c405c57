"""Materials: positive definiteness, rotation of the Voigt stiffness, the table."""

from __future__ import annotations

import numpy as np
import pytest

from probedyn.core.errors import MaterialError
from probedyn.fem.materials import (
    PZT5H_SE, Material, get_material, mandel, material_names, radial_poling, rotate_voigt,
    rotation_about, tensor_to_voigt, voigt_to_tensor,
)

RNG = np.random.default_rng(7)


def random_rotation() -> np.ndarray:
    q, r = np.linalg.qr(RNG.standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_isotropic_positive_definite_and_moduli():
    m = Material.isotropic(169e9, 0.28, 2330.0)
    ev = np.linalg.eigvalsh(mandel(m.C))
    # Kelvin moduli of an isotropic solid: 3K (once) and 2G (five times)
    K, G = 169e9 / (3 * (1 - 2 * 0.28)), 169e9 / (2 * 1.28)
    assert np.allclose(np.sort(ev), np.sort([3 * K] + [2 * G] * 5), rtol=1e-12)
    assert m.youngs_modulus() == pytest.approx(169e9, rel=1e-12)
    assert m.isotropic_constants() == pytest.approx((169e9, 0.28), rel=1e-12)


def test_isotropic_is_rotation_invariant():
    C = get_material("silicon").C
    for _ in range(3):
        assert np.allclose(rotate_voigt(C, random_rotation()), C, rtol=0, atol=1e-6 * C.max())


@pytest.mark.parametrize("name", ["silicon-110", "pzt-5h"])
def test_rotation_invariants(name):
    C = get_material(name).C
    R = random_rotation()
    Cr = rotate_voigt(C, R)
    # rotating by R then by R^T returns C
    assert np.allclose(rotate_voigt(Cr, R.T), C, rtol=0, atol=1e-9 * C.max())
    # Kelvin (Mandel) eigenvalues are invariants of the 4th-order tensor
    assert np.allclose(np.linalg.eigvalsh(mandel(Cr)), np.linalg.eigvalsh(mandel(C)), rtol=1e-10)
    # Bond-matrix form agrees with the explicit tensor rotation C'_ijkl = R_ia R_jb R_kc R_ld C_abcd
    Tr = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, voigt_to_tensor(C))
    assert np.allclose(tensor_to_voigt(Tr), Cr, rtol=0, atol=1e-9 * C.max())
    # stacks of rotations broadcast
    Rs = np.stack([R, R.T])
    assert np.allclose(rotate_voigt(C, Rs)[0], Cr)


def test_silicon_110_young_modulus():
    # Cubic crystal: 1/E(n) = s11 - 2 (s11 - s12 - s44/2)(l^2 m^2 + m^2 n^2 + n^2 l^2).
    # Along [110]: the sum is 1/4. Independent of the rotation code.
    C11, C12, C44 = 165.7e9, 63.9e9, 79.6e9
    S = np.linalg.inv(Material.cubic(C11, C12, C44, 2330.0).C)
    s11, s12, s44 = S[0, 0], S[0, 1], S[3, 3]
    E110 = 1.0 / (s11 - 2 * (s11 - s12 - s44 / 2) * 0.25)
    m = get_material("silicon-110")
    assert m.youngs_modulus((1, 0, 0)) == pytest.approx(E110, rel=1e-10)  # beam axis x || [110]
    assert m.youngs_modulus((0, 0, 1)) == pytest.approx(1 / s11, rel=1e-10)  # z || [001]
    assert E110 == pytest.approx(169e9, rel=0.002)  # the textbook 169 GPa


def test_pzt_tables():
    m = get_material("pzt-5h")
    assert np.linalg.inv(m.C)[0, 0] == pytest.approx(PZT5H_SE["s11"], rel=1e-10)
    assert np.linalg.inv(m.C)[2, 2] == pytest.approx(PZT5H_SE["s33"], rel=1e-10)
    iso = get_material("pzt-5h-iso")
    assert iso.youngs_modulus() == pytest.approx(1 / PZT5H_SE["s11"], rel=1e-12)  # E = 1/s11 as in the source
    for name in material_names():
        assert np.linalg.eigvalsh(mandel(get_material(name).C)).min() > 0


def test_radial_poling_frame():
    R = radial_poling((0, 0, 0), (0, 0, 1))
    x = np.array([[1.0, 0.0, -2.0], [0.0, 3.0, 1.0], [5.0, 5.0, 5.0]])  # (3, 3 points)
    Rq = R(x)
    assert Rq.shape == (3, 3, 3)
    for k in range(3):
        assert np.allclose(Rq[k] @ Rq[k].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(Rq[k]) == pytest.approx(1.0)
        r = np.array([x[0, k], x[1, k], 0.0])
        assert np.allclose(Rq[k][:, 2], r / np.linalg.norm(r))  # local 3 = radial
    # a radially poled material at angle 90 deg equals the one at 0 deg rotated about z
    C = get_material("pzt-5h").C
    C0 = rotate_voigt(C, R(np.array([[1.0], [0.0], [0.0]]))[0])
    C90 = rotate_voigt(C, R(np.array([[0.0], [1.0], [0.0]]))[0])
    assert np.allclose(rotate_voigt(C0, rotation_about("z", np.pi / 2)), C90, atol=1e-6 * C.max())


def test_bad_materials():
    with pytest.raises(MaterialError, match="unknown material"):
        get_material("unobtainium")
    with pytest.raises(MaterialError, match="Poisson"):
        Material.isotropic(1e9, 0.5, 1000.0)
    with pytest.raises(MaterialError, match="positive"):
        Material.isotropic(-1e9, 0.2, 1000.0)
    with pytest.raises(MaterialError, match="positive definite"):
        Material("bad", -np.eye(6), 1000.0)
    with pytest.raises(MaterialError, match="anisotropic"):
        get_material("pzt-5h").with_overrides(E=1e9)
    assert get_material("silicon").with_overrides(nu=0.0).isotropic_constants()[1] == 0.0
