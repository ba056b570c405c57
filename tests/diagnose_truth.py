"""Truth generators for the diagnosis tests and the rate study (tests only; never imported by probedyn).

Every truth is produced by a path independent of the diagnosis:

* **modal**: probedyn's 3D FEM on a *finer mesh* than the diagnosis uses (4 layers of 20-node
  hexahedra through the thickness, not stretched, instead of the diagnosis' 3 layers meshed thick
  and stretched back), solved directly (shift-invert, no Ritz reduction), with the hidden effect built into the mesh or the matrices by code
  here -- a point mass on a mesh *vertex* (the diagnosis interpolates a point of its mass path),
  springs on the clamp face assembled here on the truth's own mesh and added to its full matrices
  (the diagnosis: its foundation on its coarser, stretched mesh, in a Ritz reduction), a lever *meshed on through a bonded overlap* (elements of t/4 along it) with springs on the overlap's
  bottom facets (the diagnosis: a beam segment on the bond tied to the clamp face), a *re-meshed* thicker / wider
  / longer lever (the diagnosis stretches its
  mesh), another Young's modulus, a geometric stiffness assembled here, and fluid loading by this
  module's own hydrodynamic function on the exact uniform-beam relation (torsion: Green & Sader's function solved
  directly by the 2D Stokes FEM, not the diagnosis' table); plus a Timoshenko beam
  (``probedyn.lumped.beam``) for the bending families;
* **friction** and **force curves**: see the later sections of this module.

The measurement written for the diagnosis holds only what an experimentalist has: the nominal
spec, the measured values, the stated noise. The truth stays with the test.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.special import kve

HERE = Path(__file__).resolve().parent
CACHE = HERE / "data" / "diagnose_modal_truth.json"

# levers of the study: (name, probe overrides) -- long, short-and-wide, narrow
LEVERS = {
    "A": dict(length=300e-6, width=30e-6, thickness=10e-6),
    "B": dict(length=100e-6, width=40e-6, thickness=10e-6),
    "C": dict(length=150e-6, width=20e-6, thickness=10e-6),
}
MODES = [("flapwise", 1), ("flapwise", 2), ("flapwise", 3), ("flapwise", 4), ("lateral", 1), ("torsion", 1)]
MODAL_EFFECTS = ["point-mass", "clamp-compliance", "thickness-error", "width-error", "length-error",
                 "modulus-error", "axial-prestress", "fluid-loading"]
TRUTH_ETT = 4  # hex-s2 layers through the thickness of the truth meshes (the diagnosis: 3, meshed thick and stretched)
E_SI, NU_SI, RHO_SI = 169e9, 0.28, 2330.0


def lever_geometry(lever) -> dict:
    """The geometry of ``lever``: a name of :data:`LEVERS` or a dict (length, width, thickness) of its own
    (the shipped examples, ``examples/make_examples.py``)."""
    return dict(LEVERS[lever]) if isinstance(lever, str) else dict(lever)


# ------------------------------------------------------------------------------------------
# Hydrodynamic function (own copy; Sader 1998 eqs 20-21)
# ------------------------------------------------------------------------------------------


def gamma_rect(omega, b, rho_f, eta_f):
    re = min(max(rho_f * omega * b * b / (4 * eta_f), 1e-6), 1e4)
    s = np.sqrt(1j * re)
    gc = 1 + 4j * kve(1, -1j * s) / (s * kve(0, -1j * s))
    t = math.log10(re)
    om_r = (0.91324 - 0.48274 * t + 0.46842 * t**2 - 0.12886 * t**3 + 0.044055 * t**4 - 0.0035117 * t**5
            + 0.00069085 * t**6) / (1 - 0.56964 * t + 0.48690 * t**2 - 0.13444 * t**3 + 0.045155 * t**4
                                    - 0.0035862 * t**5 + 0.00069085 * t**6)
    om_i = (-0.024134 - 0.029256 * t + 0.016294 * t**2 - 0.00010961 * t**3 + 0.000064577 * t**4
            - 0.000044510 * t**5) / (1 - 0.59702 * t + 0.55182 * t**2 - 0.18357 * t**3 + 0.079156 * t**4
                                     - 0.014369 * t**5 + 0.0028361 * t**6)
    g = (om_r + 1j * om_i) * gc
    return float(g.real), float(abs(g.imag))


def fluid_loaded(f_vac, w, t, rho, rho_f, eta_f):
    """Exact uniform-beam fluid loading of one flapwise mode: omega_f = omega_v / sqrt(1 + T Gamma_r(omega_f)),
    Q = (1/T + Gamma_r) / Gamma_i with T = pi rho_f w / (4 rho t) (Sader eq 25)."""
    T = math.pi * rho_f * w / (4 * rho * t)
    om_v = 2 * math.pi * f_vac
    om = om_v
    for _ in range(200):
        gr, _ = gamma_rect(om, w, rho_f, eta_f)
        new = om_v / math.sqrt(1 + T * gr)
        if abs(new - om) < 1e-14 * om:
            break
        om = new
    gr, gi = gamma_rect(om, w, rho_f, eta_f)
    return om / (2 * math.pi), (1 / T + gr) / gi


def lateral_fluid_loaded(f_vac, t, rho, rho_f, eta_f):
    """Uniform-beam loading of one lateral (in-plane) mode by the Stokes layers of its two faces: added mass
    ``w rho_f delta`` per length against the beam's ``rho w t``, ``x = rho_f delta / (rho t)``, ``delta =
    sqrt(2 eta_f / (rho_f omega))`` at the loaded frequency (iterated), ``Q = (1 + x) / x`` (Stokes's second
    problem: damping omega times the added mass)."""
    om_v = 2 * math.pi * f_vac
    om = om_v
    for _ in range(200):
        x = rho_f * math.sqrt(2 * eta_f / (rho_f * om)) / (rho * t)
        new = om_v / math.sqrt(1 + x)
        if abs(new - om) < 1e-14 * om:
            break
        om = new
    x = rho_f * math.sqrt(2 * eta_f / (rho_f * om)) / (rho * t)
    return om / (2 * math.pi), (1 + x) / x


_GAMMA_TOR_CACHE: dict = {}
GAMMA_TOR_REFINE = 0.7  # the 2D Stokes mesh of the truths: 2e-3 of Sader's function (tests/test_stokes2d.py)
GAMMA_TOR_PER_DECADE = 8  # the truths' grid in Re: log-log interpolation within 5e-4 (Gamma_r), 9e-4 (Gamma_i)


def _gamma_torsion_node(k: int) -> complex:
    """The 2D Stokes FEM's torsional function at the grid node ``Re = 10**(k / GAMMA_TOR_PER_DECADE)``, solved
    once per test run: memoised in the process and in the run's cache folder (``PROBEDYN_CACHE``, shared by the
    xdist workers; a file lock makes a second worker wait for the first's solve instead of repeating it)."""
    if k in _GAMMA_TOR_CACHE:
        return _GAMMA_TOR_CACHE[k]
    import probedyn.fem.stokes2d as solver
    import probedyn.meshes.section2d as mesher

    folder = Path(os.environ.get("PROBEDYN_CACHE") or tempfile.gettempdir()) / "truth-gamma-torsion"
    folder.mkdir(parents=True, exist_ok=True)
    code = hashlib.sha256(b"".join(Path(m.__file__).read_bytes() for m in (solver, mesher))).hexdigest()[:12]
    tag = f"n{GAMMA_TOR_PER_DECADE}-r{GAMMA_TOR_REFINE}-{code}-k{k}"  # a changed solver or mesh: new solves
    done = folder / f"{tag}.json"
    with open(folder / f"{tag}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if done.exists():
            re_, im = json.loads(done.read_text())
        else:
            re_k = 10.0 ** (k / GAMMA_TOR_PER_DECADE)
            g = complex(solver.zero_thickness_gamma(re_k, "rotate", refine=GAMMA_TOR_REFINE))
            re_, im = g.real, abs(g.imag)
            part = done.with_suffix(".part")
            part.write_text(json.dumps([re_, im]))
            part.replace(done)
    _GAMMA_TOR_CACHE[k] = complex(re_, im)
    return _GAMMA_TOR_CACHE[k]


def gamma_torsion_direct(re: float) -> complex:
    """Green & Sader's torsional function at ``re`` from probedyn's 2D oscillatory-Stokes FEM solved directly
    (:func:`probedyn.fem.stokes2d.zero_thickness_gamma`: three thicknesses extrapolated to zero) at the two
    nodes of a grid of ``GAMMA_TOR_PER_DECADE`` points per decade of Re that bracket it, each part interpolated
    linearly in ``ln Gamma`` against ``ln Re`` (exact for the boundary layer's power laws; measured on the
    smooth function, within 5e-4 of Gamma_r and 9e-4 of Gamma_i, below the mesh's 2e-3) -- not the diagnosis'
    table (its own solves on a coarser mesh; the table is cubic splines through solves at refine 1). The grid
    lets the truths of different tests share their solves (:func:`_gamma_torsion_node`)."""
    x = math.log10(re) * GAMMA_TOR_PER_DECADE
    k = math.floor(x)
    a = x - k
    g0, g1 = _gamma_torsion_node(k), _gamma_torsion_node(k + 1) if a > 1e-12 else _gamma_torsion_node(k)
    return complex(g0.real ** (1 - a) * g1.real ** a, g0.imag ** (1 - a) * g1.imag ** a)


def torsion_fluid_loaded(f_vac, w, t, rho, rho_f, eta_f):
    """Uniform-beam loading of one torsion mode (Green & Sader 2002): added moment of inertia ``(pi/128) rho_f w^4
    Gamma_tor,r`` per length against the section's polar one ``rho w t (w^2 + t^2) / 12``, ``T = (3 pi / 32)
    (rho_f / rho) w^3 / (t (w^2 + t^2))``; ``omega_f = omega_v / sqrt(1 + T Gamma_r(omega_f))``,
    ``Q = (1/T + Gamma_r) / Gamma_i``. Gamma is solved directly at the vacuum frequency's Re and at the first
    iterate's (:func:`gamma_torsion_direct`: the 2D solves at its grid nodes); the fixed point (a contraction:
    Gamma moves slowly with Re) is iterated on the line through the two in ln Re."""
    if not math.isfinite(f_vac):
        return f_vac, math.inf  # a mode the truth does not hold
    T = 3 * math.pi / 32 * rho_f / rho * w**3 / (t * (w * w + t * t))
    om_v = 2 * math.pi * f_vac
    re_of = rho_f * w * w / (4 * eta_f)
    x0, g0 = math.log(re_of * om_v), gamma_torsion_direct(re_of * om_v)
    om1 = om_v / math.sqrt(1 + T * g0.real)
    x1, g1 = math.log(re_of * om1), gamma_torsion_direct(re_of * om1)

    def gamma(om):
        if abs(x1 - x0) < 1e-12:
            return g1
        return g0 + (g1 - g0) * (math.log(re_of * om) - x0) / (x1 - x0)

    om = om1
    for _ in range(100):
        new = om_v / math.sqrt(1 + T * gamma(om).real)
        if abs(new - om) < 1e-13 * om:
            break
        om = new
    g = gamma(om)
    return om / (2 * math.pi), (1 / T + g.real) / g.imag


# ------------------------------------------------------------------------------------------
# FEM truths with the effect built in
# ------------------------------------------------------------------------------------------


def _probe():
    from probedyn.probes import get_probe

    return get_probe("cantilever")[0]


def _families_pick(freqs, fams, modes):
    out = []
    for fa, o in modes:
        idx = [i for i, x in enumerate(fams) if x == fa]
        out.append(freqs[idx[o - 1]] if len(idx) >= o else math.nan)
    return np.array(out)


def _solve_custom(model, K, M, n, clamped: bool, shapes: bool = False):
    """Eigen-solve a (possibly unclamped) model with extra matrices; FEM classification (and the
    mass-normalised shapes with ``shapes``)."""
    from probedyn.fem import elasticity as el
    from probedyn.fem.eigen import shift_invert_eigsh
    from probedyn.fem.modes import classify_shapes

    free = model.free_dofs if clamped else np.arange(model.ndofs_total)
    res = shift_invert_eigsh(K[free][:, free].tocsr(), M[free][:, free].tocsr(), n, sigma=0.0)
    Phi = np.zeros((model.ndofs_total, len(res.eigenvalues)))
    Phi[free] = res.vectors
    w = el.lumped_weights(model.mesh, model.elem_density)
    fams, _ = classify_shapes(model.basis.doflocs, w, Phi.reshape(model.n_nodes, 3, -1), axis=model.beam_axis)
    f = np.sqrt(np.maximum(res.eigenvalues, 0)) / (2 * math.pi)
    return (f, fams, Phi) if shapes else (f, fams)


def _geometric_stiffness(model, sigma):
    """sigma * int (d_x u).(d_x v) dV, assembled here with scikit-fem (the model's own scalar
    quadratic element, hexahedral or tetrahedral; scalar Laplacian along x, 3rd-order quadrature)."""
    from skfem import Basis, BilinearForm

    basis = Basis(model.mesh, model.basis.elem, intorder=4)

    @BilinearForm
    def gxx(u, v, w):
        return u.grad[0] * v.grad[0]

    return sigma * sp.kron(gxx.assemble(basis), sp.identity(3), format="csr")


def _face_mass(model, face):
    """The consistent face mass ``int_face N_i N_j dA`` of a face (a boundary's name, or facet indices) with the
    model's own scalar element: a Winkler foundation of stiffness ``k`` per unit area on the face is ``k`` times
    it, per direction."""
    from skfem import BilinearForm, FacetBasis

    facets = np.asarray(model.mesh.boundaries[face] if isinstance(face, str) else face)
    fb = FacetBasis(model.mesh, model.basis.elem, facets=facets, intorder=4)

    @BilinearForm
    def mass(u, v, w):
        return u * v

    return mass.assemble(fb)


def _face_nodal_areas(model, face):
    """Lumped nodal areas of a face: the diagonal of its consistent face mass (the model's own
    scalar element), scaled to the face area (HRZ lumping; every node gets a positive share).
    For loads (a force spread over the free end); not for springs (:func:`_truth_model`)."""
    S = _face_mass(model, face)
    d = S.diagonal()
    area = float(S.sum())
    return d * (area / d.sum())


def tip_overrides(tip: dict | None) -> dict:
    """The cantilever probe's tip parameters of a truth's ``tip`` (``shape``, ``height`` [m],
    ``half_angle`` [rad]); {} without a tip."""
    if not tip:
        return {}
    return {"tip_shape": tip["shape"], "tip_height": float(tip["height"]), "tip_half_angle": float(tip["half_angle"])}


def _truth_model(lever: str, effect: str | None, params: dict, ett: int = TRUTH_ETT, tip: dict | None = None):
    """The truth's FEM with ``effect`` built into the mesh or the matrices: (model, K, M, clamped, extra)."""
    from probedyn.fem.model import PointMass

    probe = _probe()
    geo = lever_geometry(lever)
    over = dict(geo, elements_through_thickness=ett, **tip_overrides(tip))
    if effect == "thickness-error":
        over["thickness"] = geo["thickness"] * params["t_ratio"]
    elif effect == "width-error":
        over["width"] = geo["width"] * params["w_ratio"]
    elif effect == "length-error":
        over["length"] = geo["length"] + params["dL"]
    elif effect == "modulus-error":
        over["youngs_modulus"] = E_SI * params["e_ratio"]
    elif effect == "crystal-anisotropy":  # the cubic crystal meshed as such (the cause interpolates C)
        over["material"] = params["material"]
    elif effect == "bonded-overlap":  # the lever meshed on through the overlap (x < L_o), its clamp face free
        over["length"] = geo["length"] * (1.0 + params["lo"])
        # elements of a quarter thickness along the lever: the bond's Winkler lengths are >= 0.8 t, and the default
        # grading (fine at x = 0, the overlap's free end) left 7-10 um elements at the chip edge -- flapwise 1 of
        # lever C on a bond of lam_n 0.047 moved -7.0 % there against -11.1 % resolved (t/2: -11.0 %, t/4: -11.1 %;
        # docs/diagnose.md 9.29)
        over["element_size"] = geo["thickness"] / 4.0
    values = probe.resolve(over)
    model = probe.build(values)
    extra = {}
    if effect == "point-mass":
        p = model.mesh.p
        target = np.array([params["xi"] * geo["length"], 0.0, 0.0])
        j = int(np.argmin(np.linalg.norm(p - target[:, None], axis=0)))
        node = p[:, j]
        model.point_masses.append(PointMass(tuple(node), params["mass"]))
        extra["xi_node"] = float(node[0] / geo["length"])
        model._K = model._M = None
    K, M = model.assemble()
    clamped = True
    if effect == "clamp-compliance":
        L, t = geo["length"], geo["thickness"]
        kn = E_SI / (L * params["c_rot"])
        kt = E_SI * t * t / (12 * L**3 * params["c_trans"]) if params["c_trans"] > 0 else kn * 1e6
        # the foundation on the face, consistent (k times the face mass, per direction; DOFs interleaved
        # x, y, z per node). Not lumped: HRZ nodal springs on 20-node hexahedra (a corner node gets a
        # ninth of a mid-side node's area) let the face deform between the nodes they hold, and that
        # compliance is mesh-dependent at the truth's sizes -- on lever C at c_rot = 0.0127 the static spring
        # constant dropped by 3.737 / 4.182 / 4.189 % with 2 / 4 / 6 layers, against 3.730 / 3.733 /
        # 3.733 % consistent and 3.670 % for the beam's 1 / (1 + 3 c_rot) (docs/diagnose.md 9.29)
        K = (K + sp.kron(_face_mass(model, "clamp"), sp.diags([kn, kt, kt]))).tocsr()
        clamped = False
    if effect == "bonded-overlap":
        K, extra["lo_mesh"] = _bond_springs(model, K, geo, params)
        clamped = False
    if effect == "axial-prestress":
        K = (K + _geometric_stiffness(model, params["sigma"])).tocsr()
    return model, K, M, clamped, extra


def _bond_springs(model, K, geo, params):
    """Springs on the bottom face of the overlap (the mesh's first ``lo L`` along x): normal ``k_n`` and
    tangential ``k_t`` per unit area (the bonded facets' consistent face mass, as the clamp's), from the bond
    lengths ``lam = 1 / (beta L)``, ``beta^4 = 3 k / (E t^3)``. Returns K and the bonded length over L as
    meshed (facets whose centroid lies in the overlap)."""
    L, t = geo["length"], geo["thickness"]
    k_n, k_t = (E_SI * t**3 / (3.0 * (params[k] * L) ** 4) for k in ("lam_n", "lam_t"))
    mesh = model.mesh
    bf = mesh.boundary_facets()
    fx = mesh.p[:, mesh.facets[:, bf]]  # (3, vertices, nf)
    zmin = mesh.p[2].min()
    bottom = np.all(np.abs(fx[2] - zmin) <= 1e-9 * t, axis=0) & (fx[0].mean(axis=0) < params["lo"] * L)
    facets = bf[bottom]
    S = _face_mass(model, facets)
    lo_mesh = float(mesh.p[0, np.unique(mesh.facets[:, facets])].max() / L)
    return (K + sp.kron(S, sp.diags([k_t, k_t, k_n]))).tocsr(), lo_mesh


def fem_truth(lever: str, effect: str | None, params: dict, ett: int = TRUTH_ETT, n_modes: int = 12,
              detector=None, tip: dict | None = None) -> dict:
    """Vacuum frequencies [Hz] of the MODES of lever ``lever`` carrying ``effect`` (FEM, ``ett``
    elements through the thickness). Fluid loading is applied afterwards (:func:`fluid_loaded`).
    ``detector(model) -> (node index, unit direction)``: also return each MODE's mass-normalised
    displacement there along that direction (``"detector_disp"``, for thermal spectra).
    ``tip``: a meshed tip (:func:`tip_overrides`; P2 tetrahedra, ``ett`` layers through the
    thickness -- the diagnosis meshes a tipped lever with 3); a thickness error leaves the tip as
    it is (a thicker lever carrying the same tip), as on a real lever."""
    model, K, M, clamped, extra = _truth_model(lever, effect, params, ett, tip)
    f, fams, Phi = _solve_custom(model, K, M, n_modes, clamped, shapes=True)
    if detector is not None:
        j, e = detector(model)
        d = np.asarray(e, float) @ Phi.reshape(model.n_nodes, 3, -1)[j]
        extra["detector_disp"] = _families_pick(d, fams, MODES).tolist()
    return {"freqs": _families_pick(f, fams, MODES).tolist(), "fem_families": fams, "dofs": int(model.dofs), **extra}


def static_truth(lever: str, effect: str | None, params: dict, ett: int = TRUTH_ETT) -> float:
    """The truth's static spring constant [N/m] for an end load: a force F spread over the
    ``free_end`` face as lumped nodal forces (:func:`_face_nodal_areas`, HRZ lumping) along z, over
    the area-weighted mean z deflection of the face -- the same work-conjugate pair as the
    diagnosis' consistent face average, built here independently, on the truth's own matrices
    (clamp springs, prestress, point mass)."""
    from probedyn.fem.eigen import factorize

    model, K, _, clamped, _ = _truth_model(lever, effect, params, ett)
    a = _face_nodal_areas(model, "free_end")
    f = np.zeros(model.ndofs_total)
    f[2::3] = a / a.sum()  # 1 N in total
    free = model.free_dofs if clamped else np.arange(model.ndofs_total)
    fac = factorize(K[free][:, free].tocsc(), spd=True)
    try:
        u = np.zeros(model.ndofs_total)
        u[free] = fac.solve(f[free])
    finally:
        fac.release()
    return float(1.0 / (f @ u))


STATIC_CACHE = HERE / "data" / "diagnose_modal_static_truth.json"


def cached_static_truth(lever: str, effect: str | None, params: dict, ett: int = TRUTH_ETT) -> float:
    """:func:`static_truth`, cached in ``tests/data/diagnose_modal_static_truth.json`` (the modal truths' keys)."""
    fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
    fem_effect = effect if effect != "fluid-loading" else None
    k = _key(lever, fem_effect, fem_params, ett)
    cache = json.loads(STATIC_CACHE.read_text()) if STATIC_CACHE.exists() else {}
    if k not in cache:
        cache[k] = {"k_static": static_truth(lever, fem_effect, fem_params, ett), "lever": lever, "effect": fem_effect,
                    "params": fem_params}
        tmp = STATIC_CACHE.with_suffix(".tmp")
        tmp.write_text(json.dumps(cache, indent=0, sort_keys=True))
        os.replace(tmp, STATIC_CACHE)
    return float(cache[k]["k_static"])


def timoshenko_truth(lever: str) -> dict:
    """Bending frequencies of the lever as a Timoshenko beam (shear + rotary inertia)."""
    from probedyn.lumped import beam as bm

    g = LEVERS[lever]
    b = bm.RectBeam(g["length"], g["width"], g["thickness"], E_SI, NU_SI, RHO_SI)
    fl = bm.timoshenko_frequencies(b, "flapwise", 4)
    la = bm.timoshenko_frequencies(b, "lateral", 2)
    return {"freqs": [*fl, la[0], math.nan]}


# ------------------------------------------------------------------------------------------
# Cache of FEM truths (keyed by lever, effect, parameters, mesh)
# ------------------------------------------------------------------------------------------


#: effects whose truth was rebuilt after its first version (the older cached entries are not reused)
TRUTH_REVISION = {"clamp-compliance": "consistent foundation", "bonded-overlap": "consistent bond, t/4 elements"}


def _key(lever, effect, params, ett, tip=None) -> str:
    items = [lever, effect, {k: v if isinstance(v, str) else round(float(v), 12) for k, v in sorted(params.items())}, ett]
    if effect in TRUTH_REVISION:
        items.append(TRUTH_REVISION[effect])
    if tip:  # untipped keys unchanged
        items.append(tip_overrides(tip))
    s = json.dumps(items)
    return hashlib.sha1(s.encode()).hexdigest()[:16]


#: tipped truths (P2 tetrahedra, 50-170 k DOFs, a minute each) are cached outside the repository
TIP_CACHE = Path(os.environ.get("PROBEDYN_TRUTH_CACHE", Path.home() / ".cache" / "probedyn-truths")) / "modal_tip.json"


def cached_fem_truth(lever, effect, params, ett=TRUTH_ETT, compute: bool = True, tip: dict | None = None) -> dict:
    path = TIP_CACHE if tip else CACHE
    cache = json.loads(path.read_text()) if path.exists() else {}
    k = _key(lever, effect, params, ett, tip)
    if k in cache:
        return cache[k]
    if not compute:
        raise KeyError(f"FEM truth {lever} {effect} {params} not cached (run tests/diagnose_truth.py)")
    out = fem_truth(lever, effect, params, ett, tip=tip)
    out.update(lever=lever, effect=effect, params=params, ett=ett, **({"tip": tip} if tip else {}))
    cache = json.loads(path.read_text()) if path.exists() else {}
    cache[k] = out
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(cache, indent=0, sort_keys=True))
    os.replace(tmp, path)
    return out


# ------------------------------------------------------------------------------------------
# Cases: effect magnitudes, noise, files
# ------------------------------------------------------------------------------------------


def probe_mass(lever):
    g = lever_geometry(lever)
    return RHO_SI * g["length"] * g["width"] * g["thickness"]


def draw_modal_effect(effect: str, lever: str, rng) -> dict:
    """A random magnitude from about the detection limit up (1e-3 frequency noise)."""
    g = lever_geometry(lever)
    sgn = rng.choice([-1.0, 1.0])
    if effect == "point-mass":
        return {"mass": float(probe_mass(lever) * 10 ** rng.uniform(np.log10(0.005), np.log10(0.2))),
                "xi": float(rng.uniform(0.4, 1.0))}
    if effect == "clamp-compliance":
        return {"c_rot": float(10 ** rng.uniform(-2.5, -1.0)),
                "c_trans": float(10 ** rng.uniform(-4.0, -2.5)) if rng.uniform() < 0.5 else 0.0}
    if effect == "thickness-error":
        return {"t_ratio": float(1 + sgn * rng.uniform(0.02, 0.15))}
    if effect == "width-error":
        return {"w_ratio": float(1 + sgn * rng.uniform(0.03, 0.2))}
    if effect == "length-error":
        return {"dL": float(sgn * rng.uniform(0.01, 0.08) * g["length"])}
    if effect == "modulus-error":
        return {"e_ratio": float(1 + sgn * rng.uniform(0.03, 0.3))}
    if effect == "axial-prestress":
        s_cr = math.pi**2 * E_SI * g["thickness"] ** 2 / (48 * g["length"] ** 2)
        v = -rng.uniform(0.1, 0.6) if rng.uniform() < 0.3 else 10 ** rng.uniform(np.log10(0.2), np.log10(5))
        return {"sigma": float(v * s_cr)}
    if effect == "bonded-overlap":
        # a glue layer (epoxy, cyanoacrylate: E 0.5-5 GPa, nu 0.3-0.45, 1-20 um thick): normal stiffness per area
        # its constrained modulus over its thickness, shear stiffness its shear modulus over it
        e_g, nu_b, h = 10 ** rng.uniform(np.log10(5e8), np.log10(5e9)), rng.uniform(0.3, 0.45), 10 ** rng.uniform(-6, np.log10(2e-5))
        k_n = e_g * (1 - nu_b) / ((1 + nu_b) * (1 - 2 * nu_b) * h)
        k_t = e_g / (2 * (1 + nu_b) * h)
        lam = [float((E_SI * g["thickness"] ** 3 / (3 * k)) ** 0.25 / g["length"]) for k in (k_n, k_t)]
        return {"lam_n": lam[0], "lam_t": lam[1], "lo": float(rng.uniform(0.1, 0.4)),
                "glue_E": float(e_g), "glue_nu": float(nu_b), "glue_h": float(h)}
    if effect == "crystal-anisotropy":  # single-crystal silicon along <110> (cubic), diagnosed as isotropic silicon
        return {"material": "silicon-110", "a_crystal": 1.0}  # a_crystal: the cause's value for this truth
    if effect == "fluid-loading":
        name = str(rng.choice(["water", "ethanol", "air"]))
        rho_f, eta_f = {"water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3), "air": (1.18, 1.85e-5)}[name]
        return {"medium": name, "rho_f": rho_f, "eta_f": eta_f}
    raise ValueError(effect)


def make_modal_case(outdir: Path, seed: int, effect: str | None, lever: str = "A", *, noise: float = 1e-3,
                    q_noise: float = 0.05, with_Q: bool | None = None, declared_medium: str | None = "vacuum",
                    truth_kind: str = "fem", compute: bool = True, params: dict | None = None,
                    name: str | None = None, tip: dict | None = None, static_rel: float | None = None,
                    noise_free: bool = False) -> tuple[Path, dict]:
    """Write a modal measurement of lever ``lever`` (a name of LEVERS or a geometry dict, whose truth is
    solved uncached) with a hidden ``effect`` (None: noise only); ``params``: the effect's parameters
    (default: drawn from ``seed``); ``name``: the file stem (default ``modal_<seed>``); ``tip``: the lever
    carries a meshed tip (:func:`tip_overrides`, FEM truths only), declared in the sidecar's [probe];
    ``static_rel``: also a measured static spring constant (:func:`cached_static_truth`, FEM truths of a
    named lever only) with that relative noise, declared in [static] (its own random stream: the
    frequencies are those of the case without it); ``noise_free``: the record without its noise (the
    same draws are consumed and the same noise is stated: the detectability criterion's record)."""
    rng = np.random.default_rng(seed)
    if params is None:
        params = draw_modal_effect(effect, lever, rng) if effect else {}
    g = lever_geometry(lever)
    if truth_kind == "timoshenko":
        if tip:
            raise ValueError("a Timoshenko truth has no tip")
        tr = timoshenko_truth(lever)
        modes = MODES[:5]
        f = np.array(tr["freqs"][:5])
    else:
        fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
        fem_effect = effect if effect != "fluid-loading" else None
        tr = (cached_fem_truth(lever, fem_effect, fem_params, compute=compute, tip=tip) if isinstance(lever, str)
              else fem_truth(lever, fem_effect, fem_params, tip=tip))
        modes = MODES
        f = np.array(tr["freqs"])
    Q_int = float(10 ** rng.uniform(3, 4.5))
    Q = np.full(len(modes), Q_int)
    if effect == "fluid-loading":
        declared_medium = None  # the experimentalist did not declare it: the diagnosis must find it
    medium = params.get("medium") if effect == "fluid-loading" else declared_medium
    if medium in ("air", "water", "ethanol"):
        rho_f, eta_f = {"water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3), "air": (1.18, 1.85e-5)}[medium]
        for k, (fa, _) in enumerate(modes):
            if fa == "flapwise":
                f[k], qf = fluid_loaded(f[k], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
            elif fa == "lateral":
                f[k], qf = lateral_fluid_loaded(f[k], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
            elif fa == "torsion":
                f[k], qf = torsion_fluid_loaded(f[k], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
    if with_Q is None:
        with_Q = bool(rng.uniform() < 0.5) or effect == "fluid-loading"
    f_meas = f * (1 + noise * rng.standard_normal(len(f)) * (not noise_free))
    Q_meas = Q * np.exp(q_noise * rng.standard_normal(len(f)) * (not noise_free))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = name or f"modal_{seed}"
    rows = ["family,order,frequency_Hz" + (",Q" if with_Q else "")]
    for (fa, o), ff, qq in zip(modes, f_meas, Q_meas):
        if np.isfinite(ff):
            rows.append(f"{fa},{o},{ff:.10g}" + (f",{qq:.6g}" if with_Q else ""))
    (outdir / f"{name}.csv").write_text("\n".join(rows) + "\n")
    med = "" if declared_medium is None else f'[medium]\nname = "{declared_medium}"\n'
    static = ""
    k_true = None
    if static_rel is not None:
        if truth_kind != "fem" or tip or not isinstance(lever, str):
            raise ValueError("a static spring constant is generated for untipped FEM truths of a named lever only")
        k_true = cached_static_truth(lever, effect, params)
        k_meas = k_true * (1 + static_rel * np.random.default_rng(seed + 10**6).standard_normal() * (not noise_free))
        static = f"\n[static]\nspring_constant = {k_meas:.8g}\nsigma = {static_rel * k_meas:.6g}\n"
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "modal"\ndata = "{name}.csv"\n\n[probe]\nname = "cantilever"\n'
        f"length = {g['length']!r}\nwidth = {g['width']!r}\nthickness = {g['thickness']!r}\n"
        + "".join(f"{k} = {v!r}\n" for k, v in tip_overrides(tip).items()) + f"\n{med}\n"
        f"[noise]\nfrequency_rel = {noise!r}\nQ_rel = {q_noise!r}\n" + static)
    truth = {"effect": effect, "params": params, "lever": lever, "truth_kind": truth_kind, "Q_int": Q_int,
             **({"k_static": k_true} if k_true is not None else {}),
             **{k: v for k, v in tr.items() if k in ("xi_node",)}, **({"tip": tip} if tip else {})}
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# Thermal spectra
# ------------------------------------------------------------------------------------------


def make_spectrum_case(outdir: Path, seed: int, effect: str | None, lever: str = "A", *, medium: str = "air",
                       spur: bool = True, averages: int = 64, temperature: float = 295.0,
                       compute: bool = True) -> tuple[Path, dict]:
    """Thermal PSD of the lever's first three flapwise modes in ``medium`` (FEM truth + this module's
    Sader loading, equipartition areas k_B T / k_n with k_n = m_beam omega_n^2 / 4, the tip-referred
    modal stiffness of a uniform cantilever), a white + 1/f detector background, an optional
    electronic spur (a sinusoid: one bin wide) below f1, and the chi^2 scatter of ``averages``
    averaged periodograms."""
    rng = np.random.default_rng(seed)
    params = draw_modal_effect(effect, lever, rng) if effect else {}
    if effect == "fluid-loading":
        params = {"medium": medium, "rho_f": 0.0, "eta_f": 0.0}  # the declared medium is the truth
        effect = None
    g = LEVERS[lever]
    tr = cached_fem_truth(lever, effect, params, compute=compute)
    f_vac = np.array(tr["freqs"][:4])  # flapwise 1-4
    rho_f, eta_f = {"air": (1.18, 1.85e-5), "water": (997.0, 8.9e-4), "vacuum": (0.0, 1.8e-5)}[medium]
    Q_int = float(10 ** rng.uniform(3.5, 4.5))
    fs, Qs = [], []
    for fv in f_vac[:3]:
        if rho_f > 0:
            f1, qf = fluid_loaded(fv, g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
        else:
            f1, qf = fv, math.inf
        fs.append(f1)
        Qs.append(1 / (1 / Q_int + 1 / qf))
    T = temperature
    kB = 1.380649e-23
    m_b = probe_mass(lever)
    if effect == "point-mass":
        m_b += 0.0
    f_hi = 1.25 * fs[2]
    freq = np.linspace(fs[0] * 0.1, f_hi, 40000)
    df = freq[1] - freq[0]
    psd = np.zeros_like(freq)
    for f0, Q in zip(fs, Qs):
        k = m_b * (2 * math.pi * f0) ** 2 / 4
        A = 2 * kB * T / (math.pi * k * f0 * Q)
        psd += A / ((1 - (freq / f0) ** 2) ** 2 + (freq / (f0 * Q)) ** 2)
    white = 1e-4 * float(psd[np.argmin(abs(freq - fs[0]))]) / Qs[0] ** 0 * 1e-3
    psd += white * (1 + (fs[0] / freq))
    truth = {"effect": effect, "params": params, "lever": lever, "f": fs, "Q": Qs, "Q_int": Q_int}
    if spur:
        f_sp = fs[0] * rng.uniform(0.15, 0.8)
        j = int(np.argmin(abs(freq - f_sp)))
        psd[j] += 300 * psd[j] * rng.uniform(1, 10)
        truth["spur_Hz"] = float(freq[j])
    psd = psd * rng.gamma(averages, 1.0 / averages, size=len(psd))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"spectrum_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([freq, psd]), delimiter=",", header="frequency_Hz,value",
               comments="", fmt="%.10g")
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "spectrum"\ndata = "{name}.csv"\nquantity = "psd"\naverages = {averages}\n\n'
        f'[probe]\nname = "cantilever"\nlength = {g["length"]!r}\nwidth = {g["width"]!r}\nthickness = {g["thickness"]!r}\n\n'
        f'[medium]\nname = "{medium}"\ntemperature = {T!r}\n\n[noise]\nfrequency_rel = 1e-6\n')
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# Friction: Langevin Prandtl-Tomlinson with inertia and thermal noise, trace and retrace (GJF integrator)
# ------------------------------------------------------------------------------------------

FRICTION_EFFECTS = ["thermal-activation", "viscous-friction", "adhesion-load", "force-offset-drift",
                    "scanner-nonlinearity", "lattice-misalignment", "force-calibration"]
LEVER_FFM = dict(k_x=1.0, m_x=1e-12, Q_x=1.0)
#: temperature [K] of the friction truths without hidden thermal activation: the interval means resolve a
#: slip position to ~1 % of a sample, so that activation raises chi^2 at the truth by 4-10x at 1 K and 15-30 %
#: at 0.1 K (seeds 3, 4, 7); at 0.01 K it is within the noise (chi^2 / n = 0.99-1.01)
T_COLD = 0.01


def _langevin_kernel():
    from numba import njit

    @njit(cache=True)
    def run(U0, a, k, kt, m, gam, gvisc, kT, Vx, Vy, turns_t, turns_X, X0, Y0, x0, y0, dt, t_samp, mode, seed):
        """Langevin tip in -U0[cos(q x) + cos(q y)] (Vy = 0: the y axis is inert), pulled by a
        spring k along the scan and kt across it (the lever's two lateral stiffnesses) from a support moving piecewise linearly in time along the scan direction
        (turning times turns_t, positions turns_X along the scan); friction gam (the lever's
        damping, on the velocity relative to the support) + gvisc (the hidden viscous tip-substrate term), both with their thermal noise
        (fluctuation-dissipation, <xi xi> = 2 (gam + gvisc) k_B T). Integrator: Gronbech-Jensen &
        Farago (Mol. Phys. 111, 983 (2013)), which keeps the correct drift in the overdamped limit
        gamma dt / m >> 1 (BAOAB does not: its dynamics there runs with an effective mobility
        dt / 2m instead of 1 / gamma). Returns the scan-direction spring force at the sample times
        (mode 0: point values; 1: means over each sample interval)."""
        np.random.seed(seed)
        q = 2.0 * np.pi / a
        n = t_samp.size
        out = np.zeros(n)
        acc = np.zeros(n)
        cnt = np.zeros(n)
        g_tot = gam + gvisc
        bb = 1.0 / (1.0 + 0.5 * g_tot * dt / m)
        aa = (1.0 - 0.5 * g_tot * dt / m) * bb
        sig = np.sqrt(2.0 * g_tot * kT * dt)
        Vn = np.sqrt(Vx * Vx + Vy * Vy)
        ux = Vx / Vn
        uy = Vy / Vn
        x, y, vx, vy = x0, y0, 0.0, 0.0
        t = turns_t[0]
        seg = 0
        j = 0
        nsteps = int((turns_t[-1] - turns_t[0]) / dt) + 2
        # sample interval edges (midpoints)
        edges = np.empty(n + 1)
        edges[0] = t_samp[0] - 0.5 * (t_samp[1] - t_samp[0])
        for i in range(1, n):
            edges[i] = 0.5 * (t_samp[i] + t_samp[i - 1])
        edges[n] = t_samp[n - 1] + 0.5 * (t_samp[n - 1] - t_samp[n - 2])
        cur = 0
        dirn = 1.0 if turns_X[1] > turns_X[0] else -1.0
        s_pos = turns_X[0]
        Xb = X0 + s_pos * ux
        Yb = Y0 + s_pos * uy
        # the lever's damping gam acts on the tip's velocity relative to the support (-gam (v - V_support),
        # as in eq. 2.13): the support's part is the force gam V_support; gvisc acts on the velocity
        # relative to the substrate
        # the spring: k along the scan direction (ux, uy), kt across it (-uy, ux)
        ds = (Xb - x) * ux + (Yb - y) * uy
        dn = -(Xb - x) * uy + (Yb - y) * ux
        fx = k * ds * ux - kt * dn * uy - U0 * q * np.sin(q * x) + gam * dirn * Vn * ux
        fy = k * ds * uy + kt * dn * ux - (U0 * q * np.sin(q * y) if Vy != 0.0 else 0.0) + gam * dirn * Vn * uy
        for it in range(nsteps):
            # record the scan-direction spring force at time t
            Fs = k * ((Xb - x) * ux + (Yb - y) * uy)
            while cur < n and t >= edges[cur + 1]:
                cur += 1
            if cur < n and t >= edges[cur]:
                acc[cur] += Fs
                cnt[cur] += 1.0
            while j < n and t >= t_samp[j]:
                out[j] = Fs
                j += 1
            if j >= n and cur >= n:
                break
            bx = sig * np.random.randn() if kT > 0 else 0.0
            by = sig * np.random.randn() if kT > 0 else 0.0
            xn = x + bb * dt * vx + bb * dt * dt / (2.0 * m) * fx + bb * dt / (2.0 * m) * bx
            yn = y + bb * dt * vy + bb * dt * dt / (2.0 * m) * fy + bb * dt / (2.0 * m) * by
            t += dt
            while seg < turns_t.size - 2 and t >= turns_t[seg + 1]:
                seg += 1
            dirn = 1.0 if turns_X[seg + 1] > turns_X[seg] else -1.0
            s_pos = turns_X[seg] + dirn * (t - turns_t[seg]) * Vn
            Xb = X0 + s_pos * ux
            Yb = Y0 + s_pos * uy
            ds = (Xb - xn) * ux + (Yb - yn) * uy
            dn = -(Xb - xn) * uy + (Yb - yn) * ux
            fxn = k * ds * ux - kt * dn * uy - U0 * q * np.sin(q * xn) + gam * dirn * Vn * ux
            fyn = k * ds * uy + kt * dn * ux - (U0 * q * np.sin(q * yn) if Vy != 0.0 else 0.0) + gam * dirn * Vn * uy
            vx = aa * vx + dt / (2.0 * m) * (aa * fx + fxn) + bb / m * bx
            vy = aa * vy + dt / (2.0 * m) * (aa * fy + fyn) + bb / m * by
            x, y, fx, fy = xn, yn, fxn, fyn
        if mode == 1:
            for i in range(n):
                if cnt[i] > 0:
                    out[i] = acc[i] / cnt[i]
        return out

    return run


_LANGEVIN = None
#: time steps per period of the tip in its well (GJF is second order: 60 steps put the slip force within
#: ~0.1 noise level of a 4x finer run, see benchmarks/diagnose_rates_friction.py)
LANGEVIN_STEPS_PER_PERIOD = 60


def langevin_scan(*, U0, a, k, m, Q, speed, length, n_per_period=40, T=0.0, gvisc=0.0, theta=0.0, bow=0.0,
                  sampling="interval-mean", seed=0, phase=None, ky_ratio=1.0):
    """Trace and retrace of a Langevin PT tip (``ky_ratio``: the lever's stiffness across the scan over ``k``;
    the damping is isotropic, on the velocity relative to the support). Returns (nominal support positions, force, times,
    direction). The support runs 2 periods backwards first (like the end of a previous retrace),
    then traces ``length`` and retraces it. ``bow``: the true support position is the nominal one
    bowed by the scanner nonlinearity (the written positions are the nominal ones)."""
    global _LANGEVIN
    if _LANGEVIN is None:
        _LANGEVIN = _langevin_kernel()
    rng = np.random.default_rng(seed)
    gam = math.sqrt(m * k) / Q
    eta = 4 * math.pi**2 * U0 / (k * a * a)
    T0 = 2 * math.pi * math.sqrt(m / (k * (max(ky_ratio, 1.0) + eta)))
    dt = T0 / LANGEVIN_STEPS_PER_PERIOD
    n = int(round(length / a * n_per_period))
    Xn = np.linspace(0.0, length, n)  # nominal support positions of the samples (trace)
    pre = 2 * a
    # support path along the scan: -pre -> 0 (data trace starts) -> length -> 0
    Xtrue = Xn + bow * Xn * (length - Xn) / length
    s_turns = np.array([-pre, 0.0, length, 0.0])
    tt = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(s_turns))) / speed])
    # sample times (true support positions follow the nominal ones through the bow: X_true(X_nom))
    def t_of(xn, leg):
        xt = xn + bow * xn * (length - xn) / length
        return tt[leg] + (xt - s_turns[leg]) / speed if leg == 1 else tt[leg] + (s_turns[leg] - xt) / speed
    # the support itself moves uniformly in true position; nominal positions are where it is sampled
    t_tr = np.array([tt[1] + (xt - 0.0) / speed for xt in Xtrue])
    t_re = np.array([tt[2] + (length - xt) / speed for xt in Xtrue[::-1][1:]])  # the turning point once
    t_samp = np.concatenate([t_tr, t_re])
    ph = rng.uniform(0, a) if phase is None else phase
    X0 = -ph  # lattice registry: support coordinate 0 sits at -ph in the lattice frame
    vx, vy = speed * math.cos(theta), speed * math.sin(theta)
    # path for the kernel: turning times and positions along the scan line; start at rest in the
    # well nearest to the starting support position
    start = np.array([X0 + s_turns[0] * math.cos(theta), s_turns[0] * math.sin(theta)])
    x0 = round(start[0] / a) * a
    y0 = round(start[1] / a) * a if theta else 0.0
    kT = 1.380649e-23 * T
    F = _LANGEVIN(U0, a, k, ky_ratio * k, m, gam, gvisc, kT, vx, vy if theta else 0.0, tt, s_turns, X0, 0.0, x0, y0, dt, t_samp,
                  1 if sampling == "interval-mean" else 0, int(seed) % (2**31))
    pos = np.concatenate([Xn, Xn[::-1][1:]])
    direction = np.concatenate([np.ones(n), -np.ones(n - 1)])
    return pos, F, t_samp, direction


def draw_friction_effect(effect: str | None, rng) -> dict:
    if effect == "thermal-activation":
        return {"T": 300.0}
    if effect == "viscous-friction":
        return {"gvisc": float(10 ** rng.uniform(np.log10(2e-4), np.log10(5e-3)))}  # N s/m at um/s speeds
    if effect == "adhesion-load":
        return {"n_adh": float(rng.uniform(0.3, 3.0) * 5e-9)}
    if effect == "force-offset-drift":
        return {"offset": float(rng.choice([-1, 1]) * rng.uniform(0.02, 0.2) * 1e-9),
                "drift": float(rng.choice([-1, 1]) * rng.uniform(0.0, 0.1) * 1e-9)}
    if effect == "scanner-nonlinearity":
        return {"bow": float(rng.choice([-1, 1]) * rng.uniform(0.03, 0.2))}
    if effect == "lattice-misalignment":
        # the lever's stiffness across the scan: ~0.65 k_x for a rectangular lever scanned across its axis,
        # higher where the tip and contact are stiffer across than the torsion along (session 48: the blind
        # friction set's 2D tips have 15 k_x)
        return {"theta_deg": float(rng.uniform(6.0, 35.0)), "ky_ratio": float(10 ** rng.uniform(np.log10(0.5), np.log10(20.0)))}
    if effect == "force-calibration":
        return {"g": float(10 ** (rng.choice([-1, 1]) * rng.uniform(0.05, 0.3)))}
    return {}


def make_friction_case(outdir: Path, seed: int, effect: str | None, *, noise: float = 5e-12,
                       sampling: str = "interval-mean", length_periods: int = 8, params: dict | None = None,
                       name: str | None = None, corrugation_follows_load: bool = True) -> tuple[Path, dict]:
    """Three scans (two speeds a decade apart at one load, and the lower speed at twice the load) of a
    Langevin PT truth with a hidden effect, trace and retrace, written as a friction measurement.
    ``params``: the effect's parameters (default: drawn from ``seed``); ``name``: the file stem
    (default ``friction_<seed>``). ``corrugation_follows_load``: False holds the corrugation at the first
    scan's on every scan (the plain PT model's, whose corrugation knows no load; blind friction set 2's nulls)."""
    rng = np.random.default_rng(seed)
    drawn = draw_friction_effect(effect, rng)
    params = drawn if params is None else dict(params)
    a = 0.5e-9 * rng.uniform(0.97, 1.03)
    k, m, Q = LEVER_FFM["k_x"], LEVER_FFM["m_x"], LEVER_FFM["Q_x"]
    eta = rng.uniform(3.0, 6.0)
    N1 = 5e-9
    # U0 per unit (total) load: eta is that of the first scan's corrugation, with or without adhesion
    u0 = eta * k * a * a / (4 * math.pi**2) / (N1 + params.get("n_adh", 0.0))
    # thermal noise always; at T_COLD thermal activation stays within the noise, so it is the hidden effect only
    # where T = 300 K
    T = params.get("T", T_COLD)
    v_lo = 10 ** rng.uniform(np.log10(20e-9), np.log10(100e-9))
    scans = [(0, v_lo, N1), (1, 10 * v_lo, N1), (2, v_lo, 2 * N1)]
    rows = ["scan,position_m,lateral_force_N,time_s"]
    tom = []
    runs = []
    for sid, v, N in scans:
        U0 = u0 * ((N if corrugation_follows_load else N1) + params.get("n_adh", 0.0))
        runs.append(langevin_scan(U0=U0, a=a, k=k, m=m, Q=Q, speed=v, length=length_periods * a, T=T,
                                  gvisc=params.get("gvisc", 0.0), theta=math.radians(params.get("theta_deg", 0.0)),
                                  bow=params.get("bow", 0.0), sampling=sampling, seed=seed * 10 + sid,
                                  ky_ratio=params.get("ky_ratio", 1.0)))
    # the detector drifts at one rate, drift / (the longest scan's duration); each scan's clock restarts (its
    # times written from 0), so the drift is about each scan's middle (session 30: before, the same amount over
    # every scan, a scan ten times faster drifting ten times faster -- the diagnosis' own old model)
    t_ref = max(r[2][-1] - r[2][0] for r in runs)
    for (sid, v, N), (pos, F, t, d) in zip(scans, runs):
        F = params.get("g", 1.0) * F
        if "offset" in params:
            tm = 0.5 * (t[0] + t[-1])
            F = F + params["offset"] + params.get("drift", 0.0) * (t - tm) / t_ref
        F = F + noise * rng.standard_normal(len(F))
        for x, f, tt in zip(pos, F, t):
            rows.append(f"{sid},{x:.9e},{f:.9e},{tt - t[0]:.9e}")
        tom.append(f"[[scans]]\nid = {sid}\nspeed = {v!r}\nload = {N!r}\n")
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = name or f"friction_{seed}"
    (outdir / f"{name}.csv").write_text("\n".join(rows) + "\n")
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "friction"\ndata = "{name}.csv"\nsampling = "{sampling}"\n\n'
        f"[lever]\nk_x = {k!r}\nm_x = {m!r}\nQ_x = {Q!r}\n\n[sample]\nlattice = 5e-10\n\n"
        # a declared temperature implies the activation (the baseline carries it, engine _declared_terms): the hidden
        # thermal activation is a record whose temperature is not declared
        + (f"[medium]\ntemperature = {T!r}\n\n" if T > 0 and effect != "thermal-activation" else "")
        # the stated noise is the detector's: the tip's thermal motion comes on top of it (the Langevin integration)
        + f'[noise]\nforce = {noise!r}\nforce_part = "detector"\n\n' + "\n".join(tom))
    truth = {"effect": effect, "params": params, "a": a, "eta": eta, "u0": u0, "T": T, "v_lo": v_lo}
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# Force-distance curves: the contact registry with a lever, solved by continuation
# ------------------------------------------------------------------------------------------

FORCE_EFFECTS = ["adhesion-dmt", "adhesion-jkr", "adhesion-md", "tip-radius-error"]


def _continuation_curve(z, P, k, start_delta):
    """Quasi-static tip-sample force along piezo positions z (one direction), by continuation:
    Newton on delta + P(delta)/k = z from the previous solution; where the solution branch ends
    (the fold: P' < -k, Newton leaves the branch) the tip jumps: a bracketing search in the
    direction of motion for the next root with P' > -k."""
    out = np.empty(len(z))
    d = start_delta
    h = 1e-13
    for i, zz in enumerate(z):
        g = lambda x: x + float(np.asarray(P(x)).ravel()[0]) / k - zz  # noqa: E731
        ok = False
        x = d
        for _ in range(60):
            gp = (g(x + h) - g(x - h)) / (2 * h)
            if not np.isfinite(gp) or gp <= 0:
                break
            step = g(x) / gp
            x -= step
            if abs(step) < 1e-16:
                ok = True
                break
        if not ok or abs(x - d) > 2e-9:
            # jump: scan in the direction of motion for the nearest stable root
            sgn = 1.0 if (i == 0 or zz >= z[i - 1]) else -1.0
            # the jump's length is not bounded by a fixed window: a pull-off lands where the lever
            # has relaxed its deflection, |P(d)| / k further (85 nm for 6 nN on a 0.07 N/m lever), plus
            # the piezo step: a 1 pm grid over the first 60 nm, then a 10 pm grid out to twice that
            reach = 2.0 * (abs(zz - d) + abs(float(np.asarray(P(d)).ravel()[0])) / k) + 60e-9
            x = None
            for grid in (d + sgn * np.linspace(0, 60e-9, 60001),
                         d + sgn * np.linspace(60e-9, max(reach, 61e-9), int(max(reach - 60e-9, 1e-9) / 1e-11) + 2)):
                gv = grid + np.asarray(P(grid), float) / k - zz
                cross = np.nonzero(np.sign(gv[1:]) != np.sign(gv[:-1]))[0]
                for c in cross:
                    lo, hi = grid[c], grid[c + 1]
                    for _ in range(80):
                        mid = 0.5 * (lo + hi)
                        if np.sign(g(mid)) == np.sign(g(lo)):
                            lo = mid
                        else:
                            hi = mid
                    xr = 0.5 * (lo + hi)
                    if (g(xr + 1e-12) - g(xr - 1e-12)) > 0:
                        x = xr
                        break
                if x is not None:
                    break
            if x is None:
                x = d
        d = x
        out[i] = float(np.asarray(P(d)).ravel()[0])
    return out


def make_force_case(outdir: Path, seed: int, effect: str | None, *, noise: float = 0.1e-9, n: int = 400,
                    declare_E: bool = False) -> tuple[Path, dict]:
    """An approach-retract curve of a lever (k) with a tip of radius R on a sample, from the contact
    registry with a hidden adhesion law (or a tip-radius error), a tilted force baseline and noise."""
    from probedyn.schemes.contact import get_contact_model

    rng = np.random.default_rng(seed)
    k = float(10 ** rng.uniform(-0.5, 1.0))  # 0.3 - 10 N/m
    R_nom = 20e-9
    E_s = float(10 ** rng.uniform(8.5, 10.5))  # 0.3 - 30 GPa
    E_t, nu = 169e9, 0.28
    params: dict = {}
    R = R_nom
    if effect == "tip-radius-error":
        params["r_ratio"] = float(10 ** (rng.choice([-1, 1]) * rng.uniform(0.15, 0.6)))
        R = R_nom * params["r_ratio"]
        declare_E = True
    Es_star = 1 / ((1 - nu**2) / E_t + (1 - 0.3**2) / E_s)
    if effect in ("adhesion-dmt", "adhesion-jkr", "adhesion-md"):
        params["W"] = float(10 ** rng.uniform(-2.0, -0.7))
        kw = dict(E_t=E_t, nu_t=nu, E_s=E_s, nu_s=0.3, R_t=R, R_s=0.0)
        if effect == "adhesion-md":
            params["lam"] = float(10 ** rng.uniform(-0.5, 0.5))
            from probedyn.schemes.contact.base import MAUGIS_206

            K = 4 / 3 * Es_star
            z0 = MAUGIS_206 / params["lam"] * (params["W"] ** 2 * R / (math.pi * K * K)) ** (1 / 3)
            model = get_contact_model("md", **kw, W=params["W"], z0=z0)
        else:
            model = get_contact_model(effect.split("-")[1], **kw, W=params["W"])
        Pl = lambda d: model.force(d, "loading")  # noqa: E731
        Pu = lambda d: model.force(d, "unloading")  # noqa: E731
    else:
        Pl = Pu = lambda d: 4 / 3 * Es_star * math.sqrt(R) * np.maximum(d, 0.0) ** 1.5  # noqa: E731
    # ramp: from 40 nm away to a maximum load of ~ 20 - 60 nN
    Fmax = float(rng.uniform(20e-9, 60e-9))
    dmax = (Fmax / (4 / 3 * Es_star * math.sqrt(R))) ** (2 / 3)
    z_c = float(rng.uniform(-5e-9, 5e-9))
    z_top = z_c + dmax + Fmax / k
    z_app = np.linspace(z_c - 40e-9, z_top, n)
    z_ret = z_app[::-1]
    F_app = _continuation_curve(z_app - z_c, Pl, k, -40e-9)
    F_ret = _continuation_curve(z_ret - z_c, Pu, k, z_top - z_c - F_app[-1] / k)
    z = np.concatenate([z_app, z_ret])
    F = np.concatenate([F_app, F_ret])
    b0, b1 = float(rng.normal(0, 5e-9)), float(rng.normal(0, 0.02) * k)
    Fm = F + b0 + b1 * z + noise * rng.standard_normal(len(F))
    seg = np.concatenate([np.zeros(n, int), np.ones(n, int)])
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"force_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([z, Fm, seg]), delimiter=",", header="z_m,force_N,segment",
               comments="", fmt=["%.10e", "%.10e", "%d"])
    sample = f"\n[sample]\nE = {E_s!r}\nnu = 0.3\n" if declare_E else ""
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "force"\ndata = "{name}.csv"\n\n[lever]\nk = {k!r}\n\n[tip]\nradius = {R_nom!r}\n'
        f"E = {E_t!r}\nnu = {nu!r}\n{sample}\n[noise]\nforce = {noise!r}\n")
    truth = {"effect": effect, "params": params, "k": k, "E_s": E_s, "z_c": z_c, "b0": b0, "b1": b1}
    return outdir / f"{name}.toml", truth


if __name__ == "__main__":  # precompute the FEM truths of the rate study (slow: about one FEM solve each)
    import sys

    from diagnose_cases import modal_cases  # noqa: E402  (tests/diagnose_cases.py)

    n_eff = int(sys.argv[1]) if len(sys.argv) > 1 else 56
    n_null = int(sys.argv[2]) if len(sys.argv) > 2 else 56
    for case in modal_cases(n_eff, n_null):
        if case["truth_kind"] == "fem":
            rng = np.random.default_rng(case["seed"])
            eff = case["effect"]
            params = draw_modal_effect(eff, case["lever"], rng) if eff else {}
            fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
            out = cached_fem_truth(case["lever"], eff if eff != "fluid-loading" else None, fem_params)
            print(case["seed"], eff, case["lever"], out["freqs"][:2], flush=True)
