"""lumped.ritz: the Rayleigh-Ritz reduction (lowest modes + static correction shapes).

Every Ritz number here is compared with an independent full FEM solve of the same mesh: the
bare modes (``ElasticModel.modes``), and models re-assembled with ``PointMass`` / ``Spring``
(``ElasticModel.assemble`` adds them to the full K, M, a code path the Ritz reduction does not
use).  The coarse mesh (one P2 layer through the thickness, 6.2k DOFs) is enough: the
comparison is Ritz vs FEM on the same mesh, not FEM vs beam theory.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.fem.model import ElasticModel, PointMass, Spring
from probedyn.lumped.ritz import RitzBasis

N_FEM = 10


def variant(model: ElasticModel, point_masses=(), springs=()) -> ElasticModel:
    """The same mesh and materials with extra point masses / springs (a full FEM model)."""
    regions = {n: (m, R) for n, m, R in zip(model.region_names, model.materials, model.orientations)}
    return ElasticModel(model.bundle, regions, clamp=model.clamp,
                        point_masses=list(model.point_masses) + list(point_masses),
                        springs=list(model.springs) + list(springs), tip=model.tip, beam_axis=model.beam_axis)


@pytest.fixture(scope="module")
def cant():
    from probedyn.probes import get_probe

    p, _ = get_probe("cantilever")
    v = p.resolve({"elements_through_thickness": 1})
    model = p.build(v)
    fem = model.modes(N_FEM)
    return model, fem, p.beam(v)


@pytest.fixture(scope="module")
def bases(cant):
    model, _, _ = cant
    return {(n, att): RitzBasis.from_model(model, n, attachments=att)
            for n in (2, 4) for att in ((), ("tip",))}


def test_bare_ritz_frequencies_equal_fem(cant, bases):
    # (a) the exact eigenvectors are in the span: the first n Ritz values are the FEM's to
    # solver precision (ARPACK tol = 0: ~1e-12); the static pseudo-modes are Ritz values of the
    # M-orthogonal complement of the n modes, hence upper bounds of FEM modes n+1, n+2, ...
    model, fem, _ = cant
    f = fem.frequencies_hz
    for (n, att), rb in bases.items():
        assert rb.kinds[:n] == ["mode"] * n
        np.testing.assert_allclose(rb.frequencies_hz[:n], f[:n], rtol=1e-9)
        extra = rb.frequencies_hz[n:]
        assert len(extra) == (3 if att else 0)
        assert np.all(extra >= f[n:n + len(extra)] * (1 - 1e-9))
        np.testing.assert_allclose(rb.M, np.eye(rb.r), atol=1e-12)
    # the stored basis is M-orthonormal and K-orthogonal in the FEM's own matrices
    rb = bases[(4, ("tip",))]
    K, M = model.assemble()
    T = rb.T
    np.testing.assert_allclose(T.T @ (M @ T), np.eye(rb.r), atol=1e-10)
    np.testing.assert_allclose(T.T @ (K @ T), rb.K, atol=1e-9 * rb.K.max())


def test_static_correction_is_exact_in_the_static_limit(cant, bases):
    # With K^-1 A^T in the span, the reduced static response to a load at the attachment is the
    # FEM's exactly, also with a stiff spring there (the solution stays in span(K^-1 A^T)).
    model, _, _ = cant
    rb = bases[(2, ("tip",))]
    spring = Spring("tip", None, 1e3, None)
    stiff = variant(model, springs=[spring])
    for d in np.eye(3):
        u_fem = stiff.displacement_at(stiff.static_displacement({"tip": d}), "tip")
        u_red = rb.static_compliance("tip", springs=[spring]) @ d
        np.testing.assert_allclose(u_red, u_fem, rtol=1e-8, atol=1e-10 * np.abs(u_fem).max())
    # without the static shapes the same compliance misses the discarded modes' flexibility
    C2 = bases[(2, ())].static_compliance("tip")
    u0 = model.displacement_at(model.static_displacement({"tip": (0, 0, 1)}), "tip")
    assert C2[2, 2] < u0[2] * (1 - 1e-4)


@pytest.mark.parametrize("case", ["tip_mass", "tip_spring_z", "stiff_tip_spring"])
def test_tip_additions_vs_full_fem(cant, bases, case):
    # (b) Ritz vs a full FEM re-solve with the addition at the attachment.  Rayleigh-Ritz gives
    # upper bounds.  Mode-acceleration argument (module doc): with the static shapes the shape
    # error falls from the residual static flexibility e0 to about e0 omega^2/(omega_{n+1}^2 -
    # omega^2), and eigenvalue errors are quadratic in shape errors, so
    #     err_with <= (omega^2 / (omega_{n+1}^2 - omega^2))^2 err_without.
    model, fem, beam = cant
    add = {"tip_mass": dict(point_masses=[PointMass("tip", 0.25 * beam.mass)]),
           "tip_spring_z": dict(springs=[Spring("tip", None, 50.0, (0, 0, 1))]),
           "stiff_tip_spring": dict(springs=[Spring("tip", None, 1e5, None)])}[case]
    ref = variant(model, **add).modes(2).frequencies_hz
    for n in (2, 4):
        e = {}
        for att in ((), ("tip",)):
            f = bases[(n, att)].solve(n=2, **add).frequencies_hz
            rel = f / ref - 1
            assert np.all(rel > -1e-9), (n, att, rel)  # upper bounds
            e[att] = rel[0]
        if case == "stiff_tip_spring" and n == 2:
            continue  # omega_1 of the propped beam (709 kHz) is close to the bare omega_3 (958 kHz)
        w, wn = ref[0], fem.frequencies_hz[n]
        bound = (w**2 / (wn**2 - w**2)) ** 2
        assert e[("tip",)] <= bound * e[()], (n, e, bound)


def test_mass_away_from_attachments_converges_with_modes(cant):
    # (c) a point mass at an interior point (0.6 L on the mid-plane, not a static-correction
    # attachment; modes only) is reached only through the modes: the error falls with n (measured rate
    # ~n^-1.5..-1.9 for n = 4..16 on this mesh, docs/reduced-probes.md).  Bound used: at least
    # first order, err(16) < err(4) / 4.
    model, _, beam = cant
    pm = [PointMass((180e-6, 0.0, 0.0), 0.25 * beam.mass)]
    ref = variant(model, point_masses=pm).modes(1).frequencies_hz[0]
    full = RitzBasis.from_model(model, 16)
    errs = []
    for n in (4, 8, 16):
        f = full.leading(n).solve(pm, n=1).frequencies_hz[0]
        errs.append(f / ref - 1)
    assert all(e > -1e-9 for e in errs)
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < errs[0] / 4


def test_operator_expand_and_projection(cant, bases):
    model, fem, _ = cant
    rb = bases[(4, ("tip",))]
    # operator = FEM attachment operator applied to the basis, for a face and for coordinates
    for where in ("free_end", (150e-6, 0.0, 5e-6)):
        np.testing.assert_allclose(rb.operator(where), model.attachment(where) @ rb.T, rtol=1e-12, atol=1e-300)
    # expand(e_i) of a "mode" column is the FEM mode (up to sign)
    phi = fem.modes[0].shape
    u = rb.expand(np.eye(rb.r)[0])
    assert abs(abs(u @ phi) / (np.linalg.norm(u) * np.linalg.norm(phi)) - 1) < 1e-10
    # with_stiffness(T^T Kx T) == the same spring as a low-rank update
    A = model.attachment("free_end")
    d = np.array([0.0, 0.0, 1.0])
    a = sp.csr_matrix(d @ A)
    Kx = 20.0 * (a.T @ a)
    f1 = rb.with_stiffness(Kx).solve(n=3).frequencies_hz
    f2 = rb.solve(springs=[("free_end", None, 20.0, d)], n=3).frequencies_hz
    np.testing.assert_allclose(f1, f2, rtol=1e-10)
    f3 = rb.with_stiffness(Kx, scale=0.5).solve(n=1).frequencies_hz[0]
    assert f3 < f1[0]


def test_residual_check_and_roundtrip(cant, bases, tmp_path):
    model, _, beam = cant
    rb = bases[(4, ("tip",))]
    chk = rb.residual_check(point_masses=[("tip", 0.1 * beam.mass)], n=2)
    assert np.all(np.abs(chk["rel_diff"]) < 1e-6)
    arr = rb.to_arrays(include_basis=False, extra_attachments=["free_end"])
    np.savez(tmp_path / "r.npz", **arr)
    with np.load(tmp_path / "r.npz") as z:
        rb2 = RitzBasis.from_arrays({k: z[k] for k in z.files})
    s1 = rb.solve([("free_end", 1e-11)], n=3).frequencies_hz
    s2 = rb2.solve([("free_end", 1e-11)], n=3).frequencies_hz
    np.testing.assert_allclose(s1, s2, rtol=1e-12)
    with pytest.raises(GeometryError):
        rb2.operator((1e-4, 0.0, 0.0))  # coordinates need the FEM model
    with pytest.raises(ParameterError):
        rb.solve(point_masses=[("tip", -1.0)])
    with pytest.raises(ParameterError):
        RitzBasis.from_model(model, 2, attachments=[("tip", "w")])
