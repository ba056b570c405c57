"""The modal model the diagnosis explains: the probe's 3D FEM, a Ritz reduction of it for the
fits, and the full FEM re-solve of the extended model.

Baseline (:class:`FEMBaseline`): the registered probe (``probedyn.probes``: cantilever with or
without tip, duo-bimorph, piezotube, or a probe TOML) built with its parameters and mesh,
solved by :meth:`probedyn.fem.model.ElasticModel.modes`; every FEM mode carries its family
(``probedyn.fem.modes.classify_shapes``), and a measured ``(family, order)`` is the order-th FEM
mode of that family. The discretisation error of each FEM frequency is estimated by
Richardson's rule from the same probe on coarser meshes with *every* element size scaled by the
same factor (fewer elements through the thickness, and the axial size of a hexahedral mesh with
them: on a thin lever meshed thick and stretched back the error comes from the axial and width
sizes, s times the thickness, which the number of layers alone does not change), ``e = |f_h - f_H|
/ (r^q - 1)`` with ``r`` the ratio of the effective element sizes ``(V / N_elements)^(1/3)`` and
``q`` the order observed on two coarse meshes, kept within [0.8, 4] (the lowest order measured
with the clamp-edge singularity, docs/fem.md, and the h^4 of smooth eigenvalues of quadratic
elements), times Roache's safety factor of the grid convergence index (1.25 with the order
observed; 3 and the lowest order when the differences are not monotone). When the data state
their noise, the mesh is refined (on a stretched lever first along its axis, down to one layer of the
thick mesh; then the stretch halved, then all sizes halved) until every used
frequency's estimated error is at most a third of its noise or the next mesh would exceed the DOF
budget (:data:`REFINE_DOF_BUDGET`); the remaining estimate enters the error budget as a model
uncertainty added to the measurement noise in quadrature. When torsion is measured, a lever stretched more
than :data:`SIDE_GRADING_STRETCH` is graded across its width towards the side edges, where twist puts its
shear stress (:func:`build_within_budget`).

Extended model (:class:`ModalState`): what the causes change --

* ``scale``: an affine stretch of the geometry along x, y, z (thickness, width, length errors);
  exact through :func:`probedyn.diagnose.fem_terms.reduced_stiffness_split`;
* ``E_factor``, ``rho_factor``: all elastic constants / the density scaled;
* ``crystal``: the fraction ``a`` of the way from each region's declared isotropic material to the
  single crystal it approximates (:data:`CRYSTALS`: isotropic "silicon" -> cubic "silicon-110",
  lever axis along <110> on a (001) wafer), ``C = C_iso + a (C_crystal - C_iso)``; regions without
  a crystal are unchanged. Linear in C, so the reduced model uses the same stiffness split as the
  stretch, of ``C_crystal - C_iso`` alone (:func:`crystal_delta`), and the full re-solve the
  interpolated material;
* ``masses``: point masses ``(xi, m)`` on the *mass path*, the line parallel to the beam axis
  through the centroid of the clamp face, ``xi = 0`` at the clamp plane and 1 at the far end;
* ``clamp``: the clamp face as an **elastic foundation** instead of a rigid clamp: normal
  stiffness per unit area ``k_n`` and tangential stiffness per unit area ``k_t`` on the clamp
  face. For a rectangular root of thickness t and width w (beam theory) this is a rotational
  stiffness per unit clamp width ``k_n t^3 / 12`` and a translational stiffness per unit width
  ``k_t t`` for flapwise bending, and, with the *same* support, ``k_n t w^3 / 12`` and ``k_t w t``
  for lateral bending (and ``k_t I_p`` for twist). Parametrised by the dimensionless compliances
  ``c_rot = E / (L k_n)`` and ``c_trans = E t^2 / (12 L^3 k_t)`` (0 = rigid): the root rotation
  and root translation compliances relative to the beam's ``L / EI`` and ``L^3 / EI`` per unit width;
* ``overlap``: the lever **bonded over an overlap** instead (``(lam_n, lam_t, L_o / L)``): the bonded segment behind
  the clamp face, a beam on a bond of normal and shear stiffness per area (:mod:`probedyn.diagnose.overlap`; the
  bond lengths ``lam = 1 / (beta L)``), its chip-edge node tied to the clamp face's rigid motion; Guyan-condensed
  on it in the reduced model, every DOF of it in the full re-solve (:class:`_BondedSystem`);
* ``axial_stress``: a uniform axial prestress sigma (Pa) with geometric stiffness ``sigma G_axis``;
* ``medium``: fluid density and viscosity loading the flapwise modes through Sader's
  hydrodynamic function (:mod:`probedyn.diagnose.hydrodynamics`), applied per mode by the
  Rayleigh quotient with the (reduced or FEM) mode shape and iterated to the loaded frequency;
  ``fluid_factor`` scales that load (e.g. squeeze film near a surface); ``gas`` makes the medium a rarefied gas
  at its pressure and temperature (a residual gas in a vacuum: the continuum load scaled by the free-molecular
  damping, :mod:`probedyn.diagnose.hydrodynamics`);
* ``Q_int``: the intrinsic quality factor (one loss factor for every mode), ``1/Q = 1/Q_int + 1/Q_fluid``;
* ``terms``: any other FEM matrix a cause brings (:class:`Term`: a builder of a sparse K or M
  term, a factor and how it scales with the stretch).

Reduced model (:class:`ReducedModal`): the Ritz basis of the lowest FEM modes of the baseline,
plus static correction shapes for the clamp-face support (the clamped modes' root reactions
applied to the foundation-supported body) and for point masses on the mass path, M-orthonormalised;
a smart probe's lumped tip (a mass on the holder springs, ``fem/augmented.py``) keeps its three
coordinates beside the basis, and the static end stiffness (:func:`end_stiffness`) has its own shapes.
A state is evaluated by projecting every term once (cached) and solving a small dense
eigenproblem; measured modes are followed by their overlap with the baseline modes. The
final extended model is re-solved with the full FEM (:func:`full_solve`).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401  (sp.linalg)
from scipy.optimize import brentq

from probedyn.core.errors import DataFormatError, GeometryError, ProbedynError, SolverError
from probedyn.diagnose.fem_terms import (axial_gradient_matrix, directional, face_mass_scalar, face_normal,
                                         reduced_stiffness_split, stretch_sensitivity)
from probedyn.diagnose.hydrodynamics import (free_molecular_damping, rarefied_factor, sader_gamma,
                                             stokes_layer_mass, torsion_gamma)
from probedyn.diagnose.overlap import bond_stiffness, segment_matrices
from probedyn.fem.modes import FAMILY_COLUMNS, classify_shapes, section_slices
from probedyn.fem.eigen import factorize, shift_invert_eigsh
from probedyn.fem.elasticity import assemble_mass as el_mass, lumped_weights
from probedyn.fem.materials import Material, get_material
from probedyn.fem.augmented import AugmentedModel
from probedyn.fem.model import ElasticModel, PointMass
from probedyn.meshes.hexmeshes import DEFAULT_ACCURACY

__all__ = ["ModalState", "Term", "FEMBaseline", "ReducedModal", "full_solve", "FAMILIES"]

FAMILIES = ("flapwise", "lateral", "torsion", "axial")
C_MIN = 1e-7  # smallest clamp compliance solved with the foundation; below it the clamp is rigid
#: smallest bond length ``1 / (beta L)`` of a bonded overlap (:mod:`probedyn.diagnose.overlap`); both below it,
#: the bond is rigid (the baseline: the jump is a clamp ~1e-4 L further back, ~1.5e-4 in frequency)
LAMBDA_MIN = 1e-4


@dataclass
class Term:
    """An extra FEM matrix a cause brings: ``factor * build(model)`` added to K or M.

    ``key`` caches the built matrix and its projection; ``exponents`` (three numbers) say how the
    term scales with the geometric stretch ``s``: the term is multiplied by ``prod(s ** exponents)``.
    """

    key: str
    matrix: str  # "K" or "M"
    factor: float
    build: Callable[[ElasticModel], sp.spmatrix]
    exponents: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class ModalState:
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    E_factor: float = 1.0
    crystal: float = 0.0  # fraction from the isotropic model to the crystal (CRYSTALS)
    rho_factor: float = 1.0
    masses: list = field(default_factory=list)  # (xi, kg)
    clamp: tuple[float, float] = (0.0, 0.0)  # (c_rot, c_trans), 0 = rigid
    overlap: tuple[float, float, float] = (0.0, 0.0, 0.0)  # bonded overlap (lam_n, lam_t, L_o / L); 0, 0: none
    axial_stress: float = 0.0  # Pa
    medium: tuple[float, float] = (0.0, 1.8e-5)  # rho_f, eta_f
    fluid_factor: float = 1.0
    gas: tuple[float, float] | None = None  # a rarefied gas: (pressure Pa, temperature K); None: a continuum medium
    Q_int: float = math.inf
    terms: list = field(default_factory=list)
    axes: dict = field(default_factory=lambda: {"length": 0, "width": 1, "thickness": 2})
    length: float = 1.0  # nominal free length of this state's model [m] (for offsets such as dL)

    def free_molecular(self) -> tuple[float, float]:
        """The medium's free-molecular damping per unit area ``(b_n, b_t)``
        (:func:`~probedyn.diagnose.hydrodynamics.free_molecular_damping`); infinite for a continuum medium."""
        return (math.inf, math.inf) if self.gas is None else free_molecular_damping(*self.gas)

    def copy(self) -> "ModalState":
        return dataclasses.replace(self, scale=np.array(self.scale, float), masses=list(self.masses),
                                   terms=list(self.terms))


def _iso_E(model: ElasticModel) -> float:
    """Reference Young's modulus: the largest axial modulus of the regions (for scaling)."""
    return max(float(m.youngs_modulus((1.0, 0.0, 0.0))) if hasattr(m, "youngs_modulus") else float(m.C[0, 0])
               for m in model.materials)


DOF_BUDGET = 30_000  # DOFs of one diagnosis FEM (a thin lever is meshed thick and stretched back)
#: the estimated discretisation error of every used frequency is refined down to this fraction of
#: its stated noise: added in quadrature it widens sigma by at most sqrt(1 + 1/9) - 1 = 5 %, and an
#: error that is systematic (the same sign on every mode, so not averaged away like noise) adds at
#: most n / 9 to the chi^2 of n modes, below its own scatter sqrt(2 n) for any n < 160
DISC_NOISE_FRACTION = 1.0 / 3.0
#: the largest FEM the baseline refines to for the data's accuracy. Its cost grows faster than the DOFs (the
#: Ritz basis, static corrections and FEM re-solves): measured on lever A (300 x 30 x 10 um, load 9) 14 s CPU
#: at 7.3 k DOFs, 36 s at 13.8 k (docs/diagnose.md); ``dof_budget`` raises it per baseline. The default
#: cantilever's 6-mode diagnosis (issue 11's < 10 s) needs no refinement; 9 k until session 34 left the
#: estimate of thin levers' higher modes at 1-3 % (blind m01: a 0.7 % thickness error under flapwise 3's
#: 2.8 %, not found; m19: air undeclared under torsion's 1.1 %, 'unexplained'): both are named at 20 k
#: (25 s and 10 s wall)
REFINE_DOF_BUDGET = 20_000
#: range of the observed convergence order used in the Richardson estimate (module docstring): the
#: lowest order measured on the default hexahedral meshes (clamp-edge singularities, docs/fem.md) and
#: the h^4 of smooth eigenvalues of quadratic elements
ORDER_RANGE = (min(p for _, p in DEFAULT_ACCURACY.values()), 4.0)
#: Roache's safety factors of the grid convergence index: 1.25 on an order observed from three
#: meshes, 3 when it could not be observed (two meshes, or non-monotone differences)
GCI_SAFETY = (1.25, 3.0)


#: the single crystal an isotropic material of the catalog approximates, in the probe's axes
#: (x along the lever): isotropic "silicon" (E = 169 GPa along <110>, nu = 0.28) is cubic silicon with
#: the lever along <110> on a (001) wafer (fem/materials.py, Hopcroft et al. 2010)
CRYSTALS = {"silicon": "silicon-110"}


def crystal_delta(mat: Material, R=None) -> np.ndarray | None:
    """``C_crystal - C_iso`` (Voigt, Pa) of a region whose material has a crystal in :data:`CRYSTALS`
    and no orientation of its own (``R`` None: the crystal's constants are in the probe's axes), else None."""
    name = CRYSTALS.get(getattr(mat, "name", None))
    if name is None or R is not None:
        return None
    return np.asarray(get_material(name).C, float) - np.asarray(mat.C, float)


@dataclass(frozen=True)
class _StiffnessPart:
    """A region's stiffness part for :func:`~probedyn.diagnose.fem_terms.reduced_stiffness_split`
    (not a material: a difference of two stiffnesses is not positive definite)."""

    C: np.ndarray


def crystal_parts(model: ElasticModel) -> list[_StiffnessPart] | None:
    """Per region of ``model``, its :func:`crystal_delta` (zero for a region without a crystal), as the
    ``materials`` of an assembly or a stiffness split; None when no region has a crystal."""
    deltas = [crystal_delta(mat, R) for mat, R in zip(model.materials, model.orientations)]
    if all(d is None for d in deltas):
        return None
    return [_StiffnessPart(np.zeros((6, 6)) if d is None else d) for d in deltas]


def tip_region(model: ElasticModel, thickness_axis: int) -> tuple[np.ndarray, np.ndarray, float] | None:
    """A meshed tip of ``model`` (its region named ``tip``): the tip's element mask, its mesh nodes
    and the coordinate along ``thickness_axis`` of the plane it is attached by (the nodes it shares
    with the lever); None without one (or on a mesh whose nodes are not its vertices)."""
    names = list(model.region_names)
    if "tip" not in names or model.mesh.doflocs.shape[1] != model.mesh.p.shape[1]:
        return None
    te = np.asarray(model.elem_region) == names.index("tip")
    if not te.any() or te.all():
        return None
    t = model.mesh.t
    nodes = np.unique(t[:, te])
    shared = np.intersect1d(nodes, np.unique(t[:, ~te]))
    if not shared.size:
        return None
    return te, nodes, float(np.mean(model.mesh.p[thickness_axis, shared]))


def stretch_points(X: np.ndarray, sc, tip=None, thickness_axis: int = 2) -> np.ndarray:
    """Node coordinates ``X`` (3, n) under the geometric stretch ``sc``: the lever's nodes by the
    affine map ``x_i -> s_i x_i``; the nodes of a meshed tip (``tip``: :func:`tip_region`) by the
    same in-plane stretch but *translated*, not stretched, through the thickness (a thicker lever
    carries the same tip: its height and mass do not follow the lever's thickness). The two maps
    agree on the attachment plane (a conforming mesh), and each is affine, so the stiffness split
    of :func:`~probedyn.diagnose.fem_terms.reduced_stiffness_split` stays exact region by region."""
    sc = np.asarray(sc, float)
    Y = X * sc[:, None]
    if tip is not None:
        _, nodes, plane = tip
        a = thickness_axis
        Y[a, nodes] = X[a, nodes] + (sc[a] - 1.0) * plane
    return Y


def _tip_sensitivity(m: ElasticModel, tip_elems: np.ndarray, V: np.ndarray, axis: int, lam: np.ndarray) -> np.ndarray:
    """The tip elements' part of ``(dK/ds_axis - lam dM/ds_axis) V`` under a stretch of the whole
    mesh (``K_tip V - S_tip V - lam M_tip V``, :func:`~probedyn.diagnose.fem_terms.stretch_sensitivity`)."""
    Mt = el_mass(m.mesh, np.where(tip_elems, m.elem_density, 0.0), element=m.element, basis=m.basis)
    St, KtV = stretch_sensitivity(m, V, elements=np.nonzero(tip_elems)[0], internal_force=True)
    return (KtV - St[axis]) - (Mt @ V) * lam[None, :]


def stretched(m0: ElasticModel, sc, cls=ElasticModel, tip_map=None, **kw) -> ElasticModel:
    """The model ``m0`` with its mesh stretched by ``sc`` along the three axes (an affine map of
    every node: a valid mesh of the stretched body with anisotropic elements; with ``tip_map`` =
    (:func:`tip_region`, thickness axis) a meshed tip is translated through the thickness instead,
    :func:`stretch_points`); materials, clamps, point masses and springs are kept (``kw``
    overrides constructor arguments)."""
    sc = np.asarray(sc, float)
    mesh = m0.mesh
    if np.any(sc != 1.0):
        if tip_map is not None and tip_map[0] is not None:
            mesh = dataclasses.replace(mesh, doflocs=stretch_points(mesh.doflocs, sc, *tip_map))
        else:
            mesh = dataclasses.replace(mesh, doflocs=mesh.doflocs * sc[:, None])
    bundle = dataclasses.replace(m0.bundle, mesh=mesh, path=None,
                                 points={k: np.asarray(v) * sc for k, v in m0.bundle.points.items()})
    args = dict(regions={name: (mat, R) for name, mat, R in zip(m0.region_names, m0.materials, m0.orientations)},
                clamp=m0.clamp, point_masses=m0.point_masses, springs=m0.springs, tip=m0.tip,
                beam_axis=m0.beam_axis, name=m0.name)
    lt = getattr(m0, "lumped_tip", None)
    if lt is not None:  # a smart probe's tip: a mass on the holder springs, off the mesh (fem/augmented.py)
        if not issubclass(cls, AugmentedModel):
            cls = AugmentedModel
        args["lumped_tip"] = lt
    args.update(kw)
    return cls(bundle, **args)


def thickness_stretch(values: dict[str, Any], budget: int = DOF_BUDGET) -> float:
    """The factor ``s`` by which a thin prismatic lever is meshed thicker (``t s``) and then
    stretched back to ``t``: isotropic tetrahedra of size ``t / n`` on a lever with
    ``L w / t^2`` large cost ``~ L w t / (t / n)^3`` DOFs, the stretched mesh ``s^2`` times fewer
    (its elements are ``s`` times longer than thick; the discretisation-error estimate is made
    on the same stretch). 1 when the plain mesh fits the budget, when the probe is not a plain
    lever (a meshed tip would be distorted) or has no thickness parameter."""
    from probedyn.fem.size import dofs_for_volume

    try:
        L, w, t = float(values["length"]), float(values["width"]), float(values["thickness"])
        ett = int(values.get("elements_through_thickness") or 2)
    except (KeyError, TypeError, ValueError):
        return 1.0
    if values.get("tip_shape", "none") not in (None, "none") or values.get("element_size"):
        return 1.0
    n = dofs_for_volume(L * w * t, min(w, t) / ett)
    if n <= budget or w <= t:
        return 1.0
    return float(min(math.sqrt(n / budget), w / t, L / (4 * t)))


#: the thickness stretch above which a mesh that must resolve twist is graded across its width towards the
#: side edges (:func:`build_within_budget`): the stretched mesh's width elements are ``1.2 s / 3`` thicknesses
#: wide (the default hexahedra, ``meshes/hexmeshes.py``), wider than the layer of torsion's shear stress at the
#: long edges (about one thickness) once s > 2.5. Measured on a 350 x 35 x 2.5 um lever (s = 4, 3 layers):
#: torsion 1 off by 0.2 % (1.1 kHz, converging at order ~1 in s) uniform, by 0.008 % graded
#: (docs/diagnose.md section 9.25)
SIDE_GRADING_STRETCH = 2.0
#: a stretched lever's mesh is refined along its axis first while its axial elements are longer than this
#: many layers of the thick mesh (:meth:`FEMBaseline._finer`)
AXIAL_LAYER_RATIO = 1.5
#: ... on a lever stretched at least this much (axial elements twice as long as the lever is thick); below, halving
#: the stretch reaches the plain mesh (axial size = thickness, docs/fem.md's cheapest to 0.06 %) in one step
AXIAL_FIRST_STRETCH = 2.0


def build_within_budget(probe, values: dict[str, Any], s: float = 1.0, twist: bool = False) -> ElasticModel:
    """``probe.build(values)``, or for ``s > 1`` the probe built ``s`` times thicker and its mesh
    stretched back to the declared thickness (see :func:`thickness_stretch`). ``twist``: the modes
    used include torsion; above :data:`SIDE_GRADING_STRETCH` the width is then graded towards the side
    edges from the declared thickness' element size (the probe's ``side_element``, ``1 / s`` of the
    thick mesh's), the same fraction on every mesh of one stretch (a Richardson estimate scales all
    sizes together)."""
    if s == 1.0:
        return probe.build(values)
    if twist and s > SIDE_GRADING_STRETCH and "side_element" in probe.params:
        values = dict(values, side_element=1.0 / s)
    m = probe.build(dict(values, thickness=values["thickness"] * s))
    ext = np.ptp(m.mesh.p, axis=1)
    ax = int(np.argmin(np.abs(ext - values["thickness"] * s)))
    sc = np.ones(3)
    sc[ax] = 1.0 / s
    return stretched(m, sc)


def observed_order(d: list[tuple[float, float]]) -> float | None:
    """Convergence order q from the differences ``d = [(r_a, f_a - f), (r_b, f_b - f)]`` of two
    coarse meshes (size ratios r_a < r_b) to the fine one: ``(r_b^q - 1) / (r_a^q - 1) = d_b / d_a``
    (each difference ``C h^q (r^q - 1)``); None when the differences do not converge monotonically
    (opposite signs, or the coarser mesh closer)."""
    (ra, da), (rb, db) = sorted(d)
    if not (rb > ra > 1.0) or da == 0.0 or db / da <= 0:
        return None
    ratio = db / da

    def g(q: float) -> float:  # increasing in q, -> ln rb / ln ra at q = 0
        return (rb**q - 1.0) / (ra**q - 1.0) - ratio

    lo, hi = 1e-3, 12.0
    if not g(lo) < 0.0 < g(hi):
        return None
    return float(brentq(g, lo, hi, xtol=1e-12))


class FEMBaseline:
    """The probe's FEM, its modes and what the reduced model needs to know about its geometry."""

    def __init__(self, probe, values: dict[str, Any], needed: dict[str, int], *, estimate_error: bool = True,
                 max_modes: int = 40, noise: dict[tuple[str, int], float] | None = None,
                 dof_budget: int = REFINE_DOF_BUDGET) -> None:
        """``noise``: the stated frequency noise (Hz) of every used ``(family, order)``; with it the
        mesh is refined until the estimated discretisation error of each is at most
        :data:`DISC_NOISE_FRACTION` of it (within ``dof_budget`` DOFs)."""
        self.dof_budget = int(dof_budget)
        self.needed, self.max_modes = dict(needed), int(max_modes)
        t0 = time.perf_counter()
        self.probe = probe
        self.values = dict(values)
        self.stretch = thickness_stretch(self.values)
        self.mesh_values = dict(self.values)  # the mesh parameters of the model actually used
        self.refinements: list[str] = []
        self.twist = "torsion" in needed  # the width graded for twist on a stretched mesh (build_within_budget)
        self._build(build_within_budget(probe, self.values, self.stretch, self.twist), needed, max_modes)
        self.disc_err = np.zeros(len(self.families))
        self.disc_note = "not estimated"
        if estimate_error:
            self._estimate_discretisation(needed, len(self.families))
            if noise:
                self._refine_for(noise, needed, max_modes)
        self.solve_s = time.perf_counter() - t0  # FEM, error estimate and refinement
        self.beam_gap, self.plate_gap, self.beam_note = self._beam_gap()

    def _build(self, model: ElasticModel, needed: dict[str, int], max_modes: int) -> None:
        """Geometry and modes of ``model`` (the baseline's FEM)."""
        self.model = m = model
        probe = self.probe
        self.axis = int(m.beam_axis)
        self.length_axis, self.width_axis, self.thickness_axis = self.axis, (self.axis + 1) % 3, (self.axis + 2) % 3
        p = m.mesh.p
        self.extent = np.ptp(p, axis=1)
        self.L = float(self.extent[self.axis])
        if not m.clamp:
            raise DataFormatError(f"probe '{probe.name}' has no clamp: the modal diagnosis needs a clamped probe")
        self.clamp_face = m.clamp[0]
        self.E_ref = _iso_E(m)
        # clamp-face geometry
        f = np.asarray(m.mesh.boundaries[self.clamp_face])
        fv = m.mesh.p[:, np.unique(m.mesh.facets[:, f])]
        self.clamp_centroid = fv.mean(axis=1)
        self.t = float(np.ptp(fv[self.thickness_axis])) or float(self.extent[self.thickness_axis])
        # a meshed tip: geometric causes stretch the lever, the tip keeps its height (stretch_points)
        self.tip = tip_region(m, self.thickness_axis)
        self.w = float(np.ptp(fv[self.width_axis])) or float(self.extent[self.width_axis])
        self.clamp_normal = face_normal(m, self.clamp_face)
        self.has_top = "top" in (m.mesh.boundaries or {})
        # modes: enough to contain every needed (family, order)
        n = max(8, int(1.5 * sum(needed.values())) + 2)
        while True:
            res = m.modes(min(n, max_modes))
            fams = [md.family for md in res.modes]
            ok = all(fams.count(fa) >= o for fa, o in needed.items())
            if ok or n >= max_modes:
                break
            n = min(2 * n, max_modes)
        missing = [f"{fa} {o}" for fa, o in needed.items() if fams.count(fa) < o]
        if missing:
            raise DataFormatError(f"the probe's lowest {len(fams)} FEM modes contain no {', '.join(missing)} mode "
                                  f"(families found: {', '.join(sorted(set(fams)))}); check the family labels")
        self.result = res
        self.freqs = res.frequencies_hz
        self.families = fams
        self.shapes = np.column_stack([md.shape for md in res.modes])

    def _beam_gap(self) -> tuple[np.ndarray | None, np.ndarray | None, str]:
        """The 1D-3D model-form gap of every FEM mode: ``ln(f_FEM / f_beam)`` with probedyn's own
        beam theory (:mod:`probedyn.lumped.beam`) of the same prism -- Timoshenko bending (Cowper's
        kappa) with ``E`` for the flapwise and lateral modes, Saint-Venant torsion (no warping) and
        the rod for the axial modes -- and, for the bending modes, the same with the plate modulus
        ``E / (1 - nu^2)`` (``plate_gap``). The two beam moduli bound a lever's effective bending
        stiffness (anticlastic curvature free / fully restrained); the 3D FEM with its rigid clamp lies
        between them, and how far it lies from the beam measures how much the 3D details (plate
        effect, the clamp's boundary layer, warping restraint of the root in torsion) move each mode.
        ``None`` when the probe is not a plain isotropic prism (a tip, several materials, an anisotropic
        crystal, attached masses): no beam of it exists."""
        from probedyn.lumped import beam as bm

        self.prism = None  # (L, w, t, E, nu, rho) of the beam, when the probe is a plain isotropic prism
        m = self.model
        mats = list(m.materials)
        if (m.point_masses or m.springs or getattr(m, "lumped_tip", None) is not None
                or not all(mt.is_isotropic(rtol=1e-6) for mt in mats)):
            return None, None, "no beam model (not a plain isotropic prism)"
        consts = {(round(mt.isotropic_constants()[0], 3), round(mt.isotropic_constants()[1], 9), mt.density)
                  for mt in mats}
        if len(consts) != 1:
            return None, None, "no beam model (several materials)"
        E, nu = mats[0].isotropic_constants()
        rho = float(mats[0].density)
        L, w, t = self.L, self.w, self.t
        if not abs(m.total_mass() / (rho * L * w * t) - 1.0) < 1e-3:
            return None, None, "no beam model (the body is not the prism of its clamp face and length)"
        self.prism = (L, w, t, E, nu, rho)
        counts = {fa: self.families.count(fa) for fa in FAMILIES}
        gap = np.full(len(self.families), np.nan)
        plate = np.full(len(self.families), np.nan)
        for modulus, out in ((E, gap), (E / (1.0 - nu * nu), plate)):
            rb = bm.RectBeam(L, w, t, modulus, nu, rho)
            ref: dict[str, np.ndarray] = {}
            for fa, n in counts.items():
                if not n:
                    continue
                if fa in ("flapwise", "lateral"):
                    for k in range(n, 0, -1):  # the orders below the beam's cut-off (a stubby section)
                        try:
                            ref[fa] = bm.timoshenko_frequencies(rb, fa, k)
                            break
                        except ProbedynError:
                            continue
                elif fa == "torsion" and modulus == E:
                    ref[fa] = bm.torsion_frequencies(rb, n)
                elif fa == "axial" and modulus == E:
                    ref[fa] = bm.axial_frequencies(rb, n)
            cnt: dict[str, int] = {}
            for i, fa in enumerate(self.families):
                cnt[fa] = cnt.get(fa, 0) + 1
                if fa in ref and cnt[fa] <= len(ref[fa]):
                    out[i] = math.log(self.freqs[i] / ref[fa][cnt[fa] - 1])
        return gap, plate, ("Timoshenko bending (Cowper kappa), Saint-Venant torsion and rod modes of the "
                            f"{L:.4g} x {w:.4g} x {t:.4g} m prism, E = {E:.4g} Pa, nu = {nu:.3g}")

    def index(self, family: str, order: int) -> int:
        k = 0
        for i, fa in enumerate(self.families):
            if fa == family:
                k += 1
                if k == order:
                    return i
        raise DataFormatError(f"no FEM mode {family} {order}")

    def _coarse_values(self, mv: dict[str, Any], ett_c: int) -> dict[str, Any]:
        """Mesh parameters of a mesh with every element size ``ett / ett_c`` times those of the mesh
        of ``mv`` (same stretch): fewer layers through the thickness (which set the width size
        too), and the axial size scaled with them (``element_size``; a hexahedral mesh's default
        axial size is proportional to the thickness, not to the layers)."""
        ett = int(mv["elements_through_thickness"])
        k = ett / ett_c
        c = dict(mv, elements_through_thickness=ett_c)
        es = mv.get("element_size")
        if es:
            c["element_size"] = float(es) * k
        elif str(self.model.bundle.element or "").startswith("hex"):
            c["element_size"] = self._axial_size() * k
        return c

    def _modes_by_family(self, model: ElasticModel, n: int) -> dict[str, list[float]]:
        r = model.modes(n)
        return {fa: [md.frequency_hz for md in r.modes if md.family == fa] for fa in FAMILIES}

    def _estimate_discretisation(self, needed: dict[str, int], n: int) -> None:
        """Richardson estimate of every FEM frequency's discretisation error (module docstring)
        from one or two coarser meshes with all element sizes scaled by the same factor."""
        v = self.mesh_values
        ett = int(v.get("elements_through_thickness", 0) or 0)
        if ett < 2:
            self.disc_note = "not estimated (fewer than two elements through the thickness)"
            return
        coarse = sorted({max(1, round(ett / 1.5)), max(1, ett // 3)} - {ett}, reverse=True)
        n_el = self.model.mesh.t.shape[1]
        runs = []
        try:
            for ett_c in coarse:
                mc = build_within_budget(self.probe, self.probe.resolve(self._coarse_values(v, ett_c)), self.stretch,
                                         self.twist)
                runs.append(((n_el / mc.mesh.t.shape[1]) ** (1.0 / 3.0), self._modes_by_family(mc, n), ett_c))
        except ProbedynError as exc:
            if not runs:
                self.disc_note = f"not estimated (coarse mesh failed: {exc})"
                return
        err = np.zeros(n)
        orders = []
        cnt: dict[str, int] = {}
        for i, fa in enumerate(self.families):
            cnt[fa] = cnt.get(fa, 0) + 1
            d = []
            for r, fc, _ in runs:
                lst = fc.get(fa, [])
                if cnt[fa] <= len(lst):
                    d.append((r, lst[cnt[fa] - 1] - self.freqs[i]))
            if not d:
                continue
            q = observed_order(d) if len(d) == 2 else None
            orders.append(q)
            if q is None:  # not observed: the lowest order and the two-mesh safety factor
                qq, fs = ORDER_RANGE[0], GCI_SAFETY[1]
            else:
                qq, fs = min(max(q, ORDER_RANGE[0]), ORDER_RANGE[1]), GCI_SAFETY[0]
            err[i] = fs * max(abs(di) / (r**qq - 1.0) for r, di in d)
        self.disc_err = err
        obs = [q for q in orders if q is not None]
        self.disc_orders = orders
        self.disc_note = ("Richardson estimate from " + " and ".join(f"{e} (size ratio {r:.2f})" for r, _, e in runs)
                          + f" instead of {ett} elements through the thickness, all sizes scaled; observed order "
                          + (f"{min(obs):.2f}-{max(obs):.2f}" if obs else "not determined")
                          + f" (used within {ORDER_RANGE[0]}-{ORDER_RANGE[1]}, GCI safety {GCI_SAFETY[0]}/"
                          f"{GCI_SAFETY[1]}); {self.model.dofs} DOFs, stretch "
                          f"{self.stretch:.3g}" + (f"; refined: {'; '.join(self.refinements)}" if self.refinements else ""))

    def _axial_size(self) -> float:
        """The longest element along the beam axis of this baseline's mesh (hexahedra: the size away from
        the clamp grading); 0 for other meshes."""
        if not str(self.model.bundle.element or "").startswith("hex"):
            return 0.0
        x = np.unique(np.round(self.model.mesh.p[self.axis][self.model.mesh.t[:8]], 12))
        return float(np.max(np.diff(x)))

    def _finer(self) -> tuple[dict[str, Any], float] | None:
        """The next finer mesh. On a lever stretched at least :data:`AXIAL_FIRST_STRETCH`, first along the
        axis: its hexahedra are as long as the *thick* lever (``s t``), ``ett`` times its layers, and the
        error of the higher bending modes is that axial size's (a 275 x 45 x 3.5 um lever at s = 3.9 against
        the converged FEM: flapwise 3 and 5 off by 3.2e-3 and 9.4e-3 with elements ``s t`` long, 2.0e-4
        and 4.2e-4 with elements one layer long; docs/diagnose.md section 9.54), so the axial size is halved,
        down to one layer of the thick mesh (:data:`AXIAL_LAYER_RATIO`). Then the thickness stretch is
        halved (the width sizes are s times the thickness), and from s = 1 on every size halved (a stretch
        below 1.5 is first set to 1 together with that halving: alone it would refine by less than 1.5)."""
        if self.stretch >= 1.5:
            hx, layer = self._axial_size(), self._layer()
            if self.stretch >= AXIAL_FIRST_STRETCH and layer > 0 and hx > AXIAL_LAYER_RATIO * layer:
                return dict(self.mesh_values, element_size=max(layer, hx / 2.0)), self.stretch
            return self.mesh_values, max(1.0, self.stretch / 2.0)
        ett = int(self.mesh_values.get("elements_through_thickness", 0) or 0)
        if ett < 1 or ett * 2 > 40:
            return None
        fine = self._coarse_values(dict(self.mesh_values), ett)  # the current axial size, explicit
        fine["elements_through_thickness"] = 2 * ett
        if fine.get("element_size"):
            fine["element_size"] = fine["element_size"] / 2.0
        return fine, 1.0

    def _layer(self) -> float:
        """The through-thickness element size of the thick mesh a stretched lever is built on (``s t / ett``);
        0 without layers."""
        ett = int(self.mesh_values.get("elements_through_thickness", 0) or 0)
        return self.stretch * self.t / ett if ett > 0 else 0.0

    def excess(self, noise: dict[tuple[str, int], float]) -> float:
        """The largest ratio of a used frequency's estimated discretisation error to
        :data:`DISC_NOISE_FRACTION` of its noise (``noise``: Hz per ``(family, order)``)."""
        worst = 0.0
        for (fa, o), sig in noise.items():
            if sig > 0 and np.isfinite(sig):
                worst = max(worst, self.disc_err[self.index(fa, o)] / (DISC_NOISE_FRACTION * sig))
        return worst

    def _refine_for(self, noise: dict[tuple[str, int], float], needed: dict[str, int], max_modes: int) -> None:
        """Refine the mesh until every used frequency's estimated error is at most
        :data:`DISC_NOISE_FRACTION` of its noise, within ``dof_budget``."""
        while self.excess(noise) > 1.0:
            if not self._refine_step(needed, max_modes, self.excess(noise)):
                return

    def _refine_step(self, needed: dict[str, int], max_modes: int, ratio: float) -> bool:
        """Replace the mesh by the next finer one within ``dof_budget`` (and re-estimate its
        discretisation error); False (with a note) when there is none."""
        nxt = self._finer()
        if nxt is None:
            return False
        vals, s = nxt
        axial = s == self.stretch and vals.get("element_size") != self.mesh_values.get("element_size")
        try:
            m = build_within_budget(self.probe, self.probe.resolve(vals), s, self.twist)
        except ProbedynError:
            return False
        if axial:
            # finer along the axis; over the budget, the stretch that fills it with the axial size kept at one
            # thick layer (the width and thickness sizes grow with s, the DOFs ~ 1 / s^2), taken only when it is
            # still finer along the axis than this mesh by AXIAL_LAYER_RATIO
            for _ in range(4):  # the DOFs fall more slowly than 1 / s^2 on a width graded for twist: iterate
                if vals is None or m.dofs <= self.dof_budget:
                    break
                k = math.sqrt(m.dofs / self.dof_budget) * 1.05
                s, vals = s * k, dict(vals, element_size=float(vals["element_size"]) * k)
                if vals["element_size"] * AXIAL_LAYER_RATIO > self._axial_size():
                    vals = None
                    break
                try:
                    m = build_within_budget(self.probe, self.probe.resolve(vals), s, self.twist)
                except ProbedynError:
                    vals = None
            if vals is None or m.dofs > self.dof_budget:
                self.disc_note += (f"; not refined further: the mesh finer along the axis exceeds the budget "
                                   f"({self.dof_budget} DOFs), the estimate enters sigma")
                return False
        else:
            if m.dofs > self.dof_budget and s < self.stretch:
                # the stretch that fills the budget (DOFs ~ 1 / s^2)
                s = self.stretch * math.sqrt(self.model.dofs / self.dof_budget)
                if s > 0.85 * self.stretch:
                    self.disc_note += (f"; not refined further: the next mesh has {m.dofs} DOFs (budget "
                                       f"{self.dof_budget}), the estimate enters sigma")
                    return False
                m = build_within_budget(self.probe, self.probe.resolve(vals), max(1.0, s), self.twist)
            if m.dofs > self.dof_budget or m.dofs < 1.2 * self.model.dofs:  # too large / not finer
                self.disc_note += (f"; not refined further: the next mesh has {m.dofs} DOFs (budget "
                                   f"{self.dof_budget}), the estimate enters sigma")
                return False
        self.refinements.append(f"{self.model.dofs} -> {m.dofs} DOFs (stretch {self.stretch:.3g} -> {max(1.0, s):.3g}"
                                + (f", axial size {self._axial_size():.3g} -> {float(vals['element_size']):.3g} m" if axial
                                   else "") + f", error/noise {ratio:.2g})")
        self.mesh_values, self.stretch = dict(self.probe.resolve(vals)), max(1.0, s)
        self._build(m, needed, max_modes)
        self.disc_err = np.zeros(len(self.families))
        self._estimate_discretisation(needed, len(self.families))
        return True

    def refined(self, noise: dict[tuple[str, int], float]) -> FEMBaseline:
        """This baseline, or the finer one (same probe, same budget) whose estimated discretisation
        error of every ``(family, order)`` in ``noise`` is at most :data:`DISC_NOISE_FRACTION` of
        its noise (Hz) -- the refinement ``FEMBaseline(..., noise=noise)`` makes, for a baseline
        built before the noise was known (a spectrum's peaks are labelled on it). The chain of finer
        meshes does not depend on the noise (only where it stops), so each finer baseline is built
        once and kept: measurements of one probe with different noise share them."""
        b = self
        if any(fa == "torsion" for fa, _ in noise):
            b = b.graded_for_twist()  # a torsion line labelled on a baseline built for bending
        while b.excess(noise) > 1.0:
            if "_finer_baseline" not in b.__dict__:
                c = b._copy_for_new_mesh()
                t0 = time.perf_counter()
                ok = c._refine_step(b.needed, b.max_modes, b.excess(noise))
                if ok:
                    c.beam_gap, c.plate_gap, c.beam_note = c._beam_gap()
                    c.solve_s = b.solve_s + time.perf_counter() - t0
                    b._finer_baseline = c
                else:  # no finer mesh within the budget: the estimate enters sigma (the note says why)
                    b._finer_baseline = None
                    b.disc_note = c.disc_note
            if b._finer_baseline is None:
                return b
            b = b._finer_baseline
        return b

    def _copy_for_new_mesh(self) -> FEMBaseline:
        """A shallow copy to be rebuilt on another mesh: without what belongs to this mesh (its Ritz reduction,
        the finer and the twist-graded baselines derived from it), with its own list of refinements."""
        c = copy.copy(self)
        for attr in ("reduced", "_finer_baseline", "_twist_baseline"):
            c.__dict__.pop(attr, None)
        c.refinements = list(self.refinements)
        return c

    def graded_for_twist(self) -> FEMBaseline:
        """This baseline with its width graded for twist (:func:`build_within_budget` with ``twist``): the same
        probe, stretch and layers, rebuilt and its discretisation re-estimated; itself when already graded or
        not stretched past :data:`SIDE_GRADING_STRETCH`. Built once (a spectrum's baseline is built for bending
        before its peaks are labelled; a torsion line among them needs the graded width, :meth:`refined`)."""
        if self.twist or self.stretch <= SIDE_GRADING_STRETCH:
            return self
        if "_twist_baseline" not in self.__dict__:
            c = self._copy_for_new_mesh()
            t0 = time.perf_counter()
            c.twist = True
            c.refinements.append(f"width graded for twist (stretch {self.stretch:.3g})")
            c._build(build_within_budget(c.probe, c.mesh_values, c.stretch, True), c.needed, c.max_modes)
            c.disc_err = np.zeros(len(c.families))
            c._estimate_discretisation(c.needed, len(c.families))
            c.beam_gap, c.plate_gap, c.beam_note = c._beam_gap()
            c.solve_s = self.solve_s + time.perf_counter() - t0
            self._twist_baseline = c
        return self._twist_baseline

    # -- geometry helpers ---------------------------------------------------------------------
    def mass_path(self, xi: np.ndarray) -> np.ndarray:
        """Points (3, n) of the mass path at fractions ``xi`` of the length."""
        xi = np.clip(np.asarray(xi, float), 1e-6, 1 - 1e-6)
        lo = float(self.model.mesh.p[self.axis].min())
        pts = np.repeat(self.clamp_centroid[:, None], xi.size, axis=1)
        pts[self.axis] = lo + xi * self.L
        return pts

    def clamp_stiffness(self, c_rot: float, c_trans: float, scale=np.ones(3)) -> tuple[float, float]:
        """Foundation stiffnesses per unit area (k_n, k_t) [N/m^3] of the dimensionless compliances,
        for the stretched geometry (length L s_L, thickness t s_t)."""
        L = self.L * scale[self.length_axis]
        t = self.t * scale[self.thickness_axis]
        E = self.E_ref
        k_n = E / (L * max(c_rot, C_MIN))
        k_t = E * t * t / (12.0 * L**3 * max(c_trans, C_MIN))
        return k_n, k_t

    def overlap_stiffness(self, lam_n: float, lam_t: float, scale=np.ones(3)) -> tuple[float, float]:
        """Bond stiffnesses per unit area (k_n, k_t) [N/m^3] of the bonded overlap's dimensionless bond
        lengths ``lam = 1 / (beta L)`` (:func:`probedyn.diagnose.overlap.bond_stiffness`), stretched
        geometry; below :data:`LAMBDA_MIN` a bond is taken as rigid as that."""
        L = self.L * scale[self.length_axis]
        t = self.t * scale[self.thickness_axis]
        return tuple(bond_stiffness(max(lam, LAMBDA_MIN), self.E_ref, t, L) for lam in (lam_n, lam_t))

    def overlap_segment(self, s: "ModalState", condensed: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The bonded segment's stiffness and mass (:func:`probedyn.diagnose.overlap.segment_matrices`) of
        state ``s``, its DOFs rotated to the model's axes: node 0 is the clamp face's rigid motion about its
        centroid, in the order of the rigid-motion shapes (``u_x, u_y, u_z, theta_x, theta_y, theta_z``).
        ``condensed``: the 6 x 6 matrices of node 0 alone (Guyan condensation: the segment's static shapes
        under the node's motions, which carry its inertia too)."""
        sc = np.asarray(s.scale, float)
        lam_n, lam_t, lo = s.overlap
        k_n, k_t = self.overlap_stiffness(lam_n, lam_t, sc)
        mat = self.model.materials[0]
        if mat.is_isotropic(rtol=1e-6):
            E, nu = mat.isotropic_constants()
        else:  # a crystal: the axial modulus and the shear modulus C44 (the segment is a beam of it)
            E = self.E_ref
            nu = min(max(E / (2.0 * float(np.asarray(mat.C, float)[3, 3])) - 1.0, 0.0), 0.49)
        E *= s.E_factor
        L = self.L * sc[self.length_axis]
        Kl, Ml = segment_matrices(E, nu, mat.density * s.rho_factor, self.w * sc[self.width_axis],
                                  self.t * sc[self.thickness_axis], lo * L, k_n, k_t)
        Rl = self._segment_frame  # local -> model axes
        if not condensed:
            T = np.kron(np.eye(Kl.shape[0] // 3), Rl.T)  # model-axis DOFs -> local DOFs, per 3-vector
            return T.T @ Kl @ T, T.T @ Ml @ T
        # Guyan: the segment's static shapes under its chip-edge node's six motions
        Tg = np.vstack([np.eye(6), -np.linalg.solve(Kl[6:, 6:], Kl[6:, :6])])
        T = np.kron(np.eye(2), Rl.T)
        return T.T @ _sym(Tg.T @ Kl @ Tg) @ T, T.T @ _sym(Tg.T @ Ml @ Tg) @ T

    @functools.cached_property
    def _segment_frame(self) -> np.ndarray:
        """The bonded segment's local axes in the model's (columns: along the lever into the chip, across the
        width, through the thickness), from the clamp face's normal (:meth:`overlap_segment`)."""
        ex = -np.asarray(self.clamp_normal, float)
        ez = np.zeros(3)
        ez[self.thickness_axis] = 1.0
        ez -= ex * float(ex @ ez)
        ez /= np.linalg.norm(ez)
        return np.column_stack([ex, np.cross(ez, ex), ez])

    def clamp_face_factor(self, scale) -> float:
        """Area stretch of the clamp face (product of the two in-plane stretches)."""
        n = np.abs(self.clamp_normal)
        k = int(np.argmax(n))
        return float(np.prod([scale[i] for i in range(3) if i != k]))


class ReducedModal:
    """Ritz reduction of a :class:`FEMBaseline` for fast evaluation of extended states.

    The basis is a union of blocks, each a set of shapes an effect needs (the FEM modes of
    the baseline are always in it):

    * ``modes``: the baseline's FEM modes, each also split into its x, y and z displacement
      components (an affine stretch rescales the components of a mode differently);
    * ``stretch``: first-order shape sensitivities ``K^-1 (dK/ds_a - lambda_i dM/ds_a) phi_i`` of
      the modes to a stretch along each axis (Fox & Kapoor);
    * ``rigid``: the six rigid-body motions (the root of a soft clamp translates and rotates) and
      the clamped body's static responses ``K^-1 M r`` to their inertia (a moving root is a base
      excitation); every other shape is zero on the clamp face, so with these blocks alone the face
      moves rigidly (the bonded overlap, ``ModalState.overlap``: the face tied to the segment's end);
    * ``clamp``: for every mode, the static extension into the body of the clamp-face displacement a
      Winkler foundation takes under the mode's root reaction (its normal and tangential parts:
      ``u_face = S^-1 R / k``);
    * ``mass``: static responses to unit forces on the mass path (at four positions);
    * ``prestress``: ``K^-1 G phi_i``;
    * ``crystal``: ``K^-1 dK phi_i`` with ``dK`` the stiffness of ``C_crystal - C_iso``
      (:func:`crystal_delta`; only when a region has a crystal);
    * ``lumped``: for a smart probe whose tip is a mass on the holder springs (``fem/augmented.py``, three
      coordinates off the mesh), the static responses to unit forces at the springs' attachment; every state
      of such a probe uses them, and its reduced matrices carry the tip's three coordinates
      (:meth:`_Sub.augment`), as ``AugmentedModel.augmented`` does for the FEM;
    * ``static``: the static response to a uniform traction on the ``free_end`` face along the
      thickness axis (only for :meth:`static_stiffness`, never in an eigenproblem's basis): with it
      the reduced static compliance of the baseline is the FEM's to round-off; ``static_clamp``: the
      foundation shapes (as the clamp block's) of its root reaction and of theirs, for a compliant
      clamp.

    One factorisation of the clamped stiffness serves every block. A state uses the blocks its
    effects need (``blocks_for``): a smaller eigenproblem, and no cross-talk from shapes the
    state does not need. Everything is projected once on the union (M-orthonormal); a block
    set's basis is a change of coordinates of it. Measured modes are followed by family and
    order, the family of a reduced mode by the same kinematic energy shares as the FEM's
    classification (:func:`probedyn.fem.modes.classify_shapes`, 24 slices, share > 0.5),
    written as quadratic forms on the basis.
    """

    BLOCKS = ("modes", "stretch", "rigid", "clamp", "mass", "prestress", "crystal", "lumped", "static", "static_clamp")

    def __init__(self, base: FEMBaseline, n_modes: int | None = None, n_mass_corr: int = 4) -> None:
        t0 = time.perf_counter()
        self.base = base
        m = base.model
        K, M = m.assemble()
        self.K, self.M = K, M
        N = m.ndofs_total
        nm = len(base.families) if n_modes is None else min(n_modes, len(base.families))
        Phi0 = base.shapes[:, :nm]
        lam0 = (2 * np.pi * base.freqs[:nm]) ** 2
        free = m.free_dofs
        fac = factorize(K[free][:, free], spd=True)

        def ksolve(F):
            out = np.zeros((N, F.shape[1]))
            out[free] = fac.solve(np.ascontiguousarray(F[free]))
            return out

        blocks: dict[str, list[np.ndarray]] = {b: [] for b in self.BLOCKS}
        A_end = None
        A_lt = None
        try:
            sh = Phi0.reshape(m.n_nodes, 3, nm)
            blocks["modes"].append(Phi0)
            for c in range(3):
                part = np.zeros_like(sh)
                part[:, c] = sh[:, c]
                blocks["modes"].append(part.reshape(N, nm))
            # stretch sensitivities: dK/ds_a phi = K phi - S_a phi, dM/ds_a = M
            Sa = stretch_sensitivity(m, Phi0)
            KP, MP = K @ Phi0, M @ Phi0
            for a in range(3):
                F = (KP - Sa[a]) - MP * lam0[None, :]
                if base.tip is not None and a == base.thickness_axis:
                    # the tip is translated, not stretched, through the thickness: its elements
                    # contribute nothing to dK/ds and dM/ds along that axis (stretch_points)
                    F -= _tip_sensitivity(m, base.tip[0], Phi0, a, lam0)
                blocks["stretch"].append(ksolve(F))
            # rigid: the face's rigid motions (each rotation's components apart) and the inertia they drive
            rig = _rigid_motions(m, base.clamp_centroid, split=True)
            blocks["rigid"].append(rig)
            # the clamped body's static response to the rigid motions' inertia (a root that moves
            # drives the lever as a base excitation does)
            blocks["rigid"].append(ksolve(np.asarray(M @ rig)))
            # clamp: the foundation's face displacement under the root reactions
            cd = m.clamped_dofs
            Sface = face_mass_scalar(m, base.clamp_face)
            nn = np.outer(base.clamp_normal, base.clamp_normal)
            # the face mass factorised once, its normal and tangential projections built once (every
            # foundation shape below solves with them)
            Sd_lu = sp.linalg.splu(directional(Sface, np.eye(3))[cd][:, cd].tocsc())
            Dparts = [sp.kron(sp.identity(m.n_nodes), sp.csr_matrix(D), format="csr")[cd][:, cd]
                      for D in (nn, np.eye(3) - nn)]

            def foundation_shapes(R: np.ndarray) -> list[np.ndarray]:
                """The body's static extension of the face displacement a Winkler foundation takes
                under the root reactions ``R`` (columns), normal and tangential parts."""
                out = []
                for Dfull in Dparts:
                    uf = np.asarray(Sd_lu.solve(np.asarray(Dfull @ R[cd]))).reshape(len(cd), -1)
                    u = np.zeros((N, R.shape[1]))
                    u[cd] = uf
                    # static extension into the body with the face held at uf: K_ff u_f = -K_fc u_c
                    rhs = -(K[:, cd] @ uf)
                    u[free] = fac.solve(np.ascontiguousarray(rhs[free]))
                    out.append(u)
                return out

            blocks["clamp"] += foundation_shapes(KP - MP * lam0[None, :])
            # point masses on the mass path
            xi_c = np.linspace(1.0, 0.0, n_mass_corr, endpoint=False)[::-1]
            try:
                Ac = m.points_operator(base.mass_path(xi_c))
                blocks["mass"].append(ksolve(np.asarray(Ac.T.todense())))
                self.mass_ok = True
            except GeometryError:
                self.mass_ok = False
            # prestress
            self.Gfull = axial_gradient_matrix(m, base.axis)
            blocks["prestress"].append(ksolve(self.Gfull @ Phi0))
            # the crystal's elastic constants: first-order shape changes K^-1 dK phi (dM = 0)
            parts = crystal_parts(m)
            if parts is not None:
                from probedyn.fem import elasticity as el

                dK = el.assemble_stiffness(m.mesh, m.elem_region, parts, m.orientations, element=m.element, basis=m.basis)
                blocks["crystal"].append(ksolve(dK @ Phi0))
            # a lumped tip's attachment: unit forces there (the springs pull the mesh at it)
            lt = getattr(m, "lumped_tip", None)
            if lt is not None:
                A_lt = m.attachment(lt.attach).tocsr()
                blocks["lumped"].append(ksolve(np.asarray(A_lt.T.todense())))
            # the static end load (uniform traction on the free-end face, thickness direction)
            # and, for a compliant clamp, the foundation's face displacement under its root reaction
            A_end = _end_operator(m, base.thickness_axis)
            if A_end is not None:
                u_end = ksolve(np.asarray(A_end.T.todense()))
                blocks["static"].append(u_end)
                u1 = foundation_shapes(np.asarray(K @ u_end))
                blocks["static_clamp"] += u1 + foundation_shapes(np.asarray(K @ np.column_stack(u1)))
        finally:
            fac.release()
        # union basis, block by block in the order of BLOCKS: each block is made orthogonal (in the
        # energy norm K + lambda_1 M) to the blocks before it (twice, for round-off) and only its
        # new directions are kept, so the FEM modes stay exactly in the basis and a shape with
        # little kinetic but much strain energy (a cross-section correction) is not dropped.
        E = (K + lam0[0] * M).tocsr()
        Q = np.zeros((N, 0))
        EQ = np.zeros((N, 0))
        # one array at a time (a block's arrays in order): the FEM modes go in before their x, y, z
        # splits, which on a slender lever have ~(L/t)^2 times their energy, so that the modes are
        # never a small-eigenvalue combination of the splits (dropped as round-off)
        for Xb in [arr for bname in self.BLOCKS for arr in blocks[bname]]:
            EX = E @ Xb
            nrm = np.sqrt(np.maximum(np.einsum("ij,ij->j", Xb, EX), 1e-300))
            Xb, EX = Xb / nrm, EX / nrm
            for _ in range(2):
                if Q.shape[1]:
                    c = Q.T @ EX
                    Xb = Xb - Q @ c
                    EX = EX - EQ @ c
            w, V = np.linalg.eigh(_sym(Xb.T @ EX))
            keep = w > 1e-14 * max(1.0, w.max())
            Tb = V[:, keep] / np.sqrt(w[keep])[None, :]
            Q = np.column_stack([Q, Xb @ Tb])
            EQ = np.column_stack([EQ, EX @ Tb])
        # Gram-Schmidt in the energy norm loses orthogonality when E is very ill-conditioned (a
        # thin lever meshed thick and stretched 10x, rigid-body shapes beside bending shapes):
        # re-orthonormalise the union once (symmetric, E_r^-1/2), dropping numerically dependent
        # directions, so that E_r = I to round-off and coordinates in the basis are exact
        for _ in range(2):
            EQ = E @ Q  # recomputed, not the updated product (which drifts by cancellation)
            w, V = np.linalg.eigh(_sym(Q.T @ EQ))
            keep = w > 1e-10 * w.max()
            Tf = V[:, keep] / np.sqrt(w[keep])[None, :]
            Q = Q @ Tf
        P = Q
        # the products with the basis, each sparse matrix once (E P = K P + lambda_1 M P)
        KP, MP = K @ P, M @ P
        EQ = KP + lam0[0] * MP
        self.Phi = Q  # orthonormal in the energy norm E = K + lambda_1 M
        self.shift = float(lam0[0])  # the same shift for the reduced eigenproblems (_lowest_pairs)
        self.r = P.shape[1]
        self.E_r = _sym(P.T @ EQ)
        cols, owner, chunk = [], [], []
        for b in self.BLOCKS:
            for arr in blocks[b]:
                chunk += [len(cols)] * arr.shape[1]
                cols.append(arr)
                owner += [b] * arr.shape[1]
        owner = np.array(owner)
        self._chunk = np.array(chunk)
        # coordinates of each raw shape in the basis: raw = Phi C  with  C = Phi^T E raw
        self._raw_coords = np.linalg.solve(self.E_r, EQ.T @ np.column_stack(cols))
        self._owner = owner
        self.M_r = _sym(P.T @ MP)
        Mel = m._Mel if m._Mel is not None else M
        self.M_el = self.M_r.copy() if Mel is M else _sym(P.T @ (Mel @ P))
        self.M_fixed = self.M_r - self.M_el
        self.M_tip = None  # the meshed tip's share of M_el (translated, not stretched, through the thickness)
        if base.tip is not None:
            Mt = el_mass(m.mesh, np.where(base.tip[0], m.elem_density, 0.0), element=m.element, basis=m.basis)
            self.M_tip = _sym(P.T @ (Mt @ P))
        self.K_r = _sym(P.T @ KP)
        # the clamp face's area moments and every basis shape's face moments (reference coordinates about
        # the face centroid): the rigid motion a shape gives the face, in any stretched geometry (_Sub.face_rigid)
        Xc = (m.basis.doflocs - base.clamp_centroid[:, None]).T  # (n_nodes, 3)
        s1 = np.asarray(Sface @ np.ones(m.n_nodes)).ravel()
        SX = np.asarray(Sface @ Xc)
        U = P.reshape(m.n_nodes, 3, self.r)
        self.face_A = float(s1.sum())
        self.face_X1 = Xc.T @ s1
        self.face_J = Xc.T @ SX
        self.face_m0 = np.einsum("n,ncr->cr", s1, U)
        self.face_m1 = np.einsum("nd,ncr->cdr", SX, U)
        self.Sn_r = P.T @ (directional(Sface, nn) @ P)
        self.St_r = P.T @ (directional(Sface, np.eye(3) - nn) @ P)
        self.G_r = P.T @ (self.Gfull @ P)
        self.top_r = self.top_w_r = None
        if base.has_top:
            St, Sw = top_face_forms(m, base.thickness_axis, base.width_axis)
            self.top_r = P.T @ (St @ P)
            self.top_w_r = P.T @ (Sw @ P)  # in-plane, across the width
        self._fam_forms = _family_forms(m, P)
        self._Ks = None  # stretch split (lazy: only geometric causes need it)
        self._Ks_tip = None  # the meshed tip's part of it
        self._Kc: dict[bool, np.ndarray | None] = {}  # the same splits of crystal_delta (lazy: crystal)
        self._sub: dict = {}
        self._term_cache: dict[str, np.ndarray] = {}
        self._overlap_cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._path_xi = np.linspace(0.0, 1.0, 101)
        self._path_ops: np.ndarray | None = None
        self.end_op = None if A_end is None else np.asarray(A_end @ P).ravel()  # (r,) face-mean deflection
        self.lumped_tip = getattr(m, "lumped_tip", None)
        self.A_lt_r = None if A_lt is None else np.asarray(A_lt @ P)  # (3, r) the lumped tip's attachment
        self.build_s = time.perf_counter() - t0

    # -- block sub-bases ----------------------------------------------------------------------
    @staticmethod
    def blocks_for(s: ModalState) -> tuple[str, ...]:
        need = ["modes"]
        if np.any(np.asarray(s.scale) != 1.0):
            need.append("stretch")
        face = s.clamp[0] >= C_MIN or s.clamp[1] >= C_MIN
        bonded = overlap_active(s)
        if face and bonded:
            raise ProbedynError("a compliant clamp face and a bonded overlap are two models of one support: "
                                "a state takes one of them")
        if face:
            need += ["rigid", "clamp"]
        if bonded:
            need.append("rigid")
        if any(mass for _, mass in s.masses):
            need.append("mass")
        if s.axial_stress:
            need.append("prestress")
        if s.crystal:
            need.append("crystal")
        if s.terms:  # a cause's own matrix: all shapes (but the static load's, which is for static_stiffness)
            need = [b for b in ReducedModal.BLOCKS if not b.startswith("static")
                    and not (bonded and b == "clamp")]  # a bonded face moves rigidly
        return tuple(need)

    def _blocks(self, s: ModalState) -> tuple[str, ...]:
        """:meth:`blocks_for` plus, for a probe with a lumped tip, its attachment's shapes (every state)."""
        b = self.blocks_for(s)
        if self.lumped_tip is not None and "lumped" not in b:
            b = tuple(x for x in self.BLOCKS if x in b or x == "lumped")
        return b

    def _subspace(self, blocks: tuple[str, ...]) -> "_Sub":
        hit = self._sub.get(blocks)
        if hit is None:
            # the same block-ordered orthogonalisation as the union, in reduced coordinates
            Er = self.E_r
            T = np.zeros((self.r, 0))
            for ci in range(int(self._chunk.max()) + 1):
                sel = self._chunk == ci
                if self._owner[sel][0] not in blocks:
                    continue
                X = self._raw_coords[:, sel]
                EX = Er @ X
                nrm = np.sqrt(np.maximum(np.einsum("ij,ij->j", X, EX), 1e-300))
                X, EX = X / nrm, EX / nrm
                for _ in range(2):
                    if T.shape[1]:
                        c = T.T @ EX
                        X = X - T @ c
                        EX = Er @ X
                w, V = np.linalg.eigh(_sym(X.T @ EX))
                keep = w > 1e-14 * max(1.0, w.max())
                T = np.column_stack([T, X @ (V[:, keep] / np.sqrt(w[keep])[None, :])])
            hit = _Sub(self, T)
            self._sub[blocks] = hit
        return hit

    @property
    def Ks(self) -> np.ndarray:
        """Stiffness split by derivative directions on the union basis (computed on first use)."""
        if self._Ks is None:
            Ks, _ = reduced_stiffness_split(self.base.model, self.Phi)
            self._Ks = Ks
        return self._Ks

    @property
    def Ks_tip(self) -> np.ndarray | None:
        """The meshed tip's elements' part of :attr:`Ks` (None without a tip)."""
        if self._Ks_tip is None and self.base.tip is not None:
            self._Ks_tip = reduced_stiffness_split(self.base.model, self.Phi,
                                                   elements=np.nonzero(self.base.tip[0])[0])[0]
        return self._Ks_tip

    def Kc(self, tip: bool = False) -> np.ndarray | None:
        """:attr:`Ks` (``tip``: :attr:`Ks_tip`) of ``C_crystal - C_iso`` alone (:func:`crystal_delta`)."""
        if tip not in self._Kc:
            m = self.base.model
            parts = crystal_parts(m)
            if (tip and self.base.tip is None) or parts is None:
                self._Kc[tip] = None
            else:
                els = np.nonzero(self.base.tip[0])[0] if tip else None
                self._Kc[tip] = reduced_stiffness_split(m, self.Phi, elements=els, materials=parts)[0]
        return self._Kc[tip]

    def path_ops(self) -> np.ndarray:
        """(101, 3, r) reduced displacement operators on the mass path (xi = 0, 0.01, ..., 1)."""
        if self._path_ops is None:
            m = self.base.model
            A = m.points_operator(self.base.mass_path(self._path_xi))  # one vectorised mesh search
            self._path_ops = np.asarray(A @ self.Phi).reshape(len(self._path_xi), 3, self.r)
        return self._path_ops

    def term(self, t: Term) -> np.ndarray:
        hit = self._term_cache.get(t.key)
        if hit is None:
            A = t.build(self.base.model)
            hit = self.Phi.T @ (A @ self.Phi)
            self._term_cache[t.key] = hit
        return hit

    def static_stiffness(self, s: ModalState) -> float:
        """The static spring constant [N/m] of state ``s`` at the free end (:func:`end_stiffness`'s
        definition) on the Ritz basis of the state's blocks plus the baseline's static end-load
        response; ``nan`` for a probe without a ``free_end`` face. Exact for the baseline and for
        states that change the mass only (their stiffness is the baseline's); otherwise a Ritz
        (upper-bound) stiffness, checked against :func:`full_static_stiffness` in the tests."""
        if self.end_op is None:
            return math.nan
        need = set(self._blocks(s)) | {"static"}
        if "clamp" in need:
            need.add("static_clamp")
        blocks = tuple(b for b in self.BLOCKS if b in need)
        sub = self._subspace(blocks)
        K, _ = sub.matrices(s, penalty="clamp" in blocks)
        a = sub.T.T @ self.end_op
        if overlap_active(s):
            K, _ = sub.overlap_terms(K, K, s)
        try:
            c = float(a @ np.linalg.solve(K, a))
        except (np.linalg.LinAlgError, ValueError):
            return math.nan  # beyond buckling: no static equilibrium
        return 1.0 / c if c > 0 else math.nan

    def solve(self, s: ModalState, needed: list[tuple[str, int]], hydro: dict | None = None
              ) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies [Hz] and quality factors of the ``(family, order)`` modes in state ``s``; ``hydro`` (a
        dict, filled when given): per mode the fluid's added-mass ratio ``x`` and the top face's share ``r``
        of the vacuum mode's modal mass (used by :meth:`ModalProblem._gap`; NaN where there is no fluid load)."""
        blocks = self._blocks(s)
        sub = self._subspace(blocks)
        K, M = sub.matrices(s, penalty="clamp" in blocks)
        q = K.shape[0]
        if self.lumped_tip is not None:
            K, M = sub.augment(K, M)
        if overlap_active(s):
            K, M = sub.overlap_terms(K, M, s)
        nlow = min(K.shape[0], max(2 * len(self.base.families), 12))
        lam, V = _lowest_pairs(K, M, nlow, self.shift)
        fams = sub.families_of(V[:q, :nlow])
        vt = np.zeros((V.shape[0], len(needed)))
        lt = np.zeros(len(needed))
        for k, (fa, o) in enumerate(needed):
            idx = [i for i, x in enumerate(fams) if x == fa]
            if len(idx) >= o:
                i = idx[o - 1]
                lt[k] = max(lam[i], 0.0)
                vt[:, k] = V[:, i]
        f = np.sqrt(lt) / (2 * np.pi)
        Q = np.full(len(needed), s.Q_int)
        rho_f, eta_f = s.medium
        if rho_f > 0 and s.fluid_factor > 0 and sub.top is not None:
            sc = np.asarray(s.scale, float)
            w = self.base.w * sc[self.base.width_axis]
            area = float(np.prod([sc[i] for i in range(3) if i != self.base.thickness_axis]))
            rho_t = self.base.model.materials[0].density * s.rho_factor * self.base.t * sc[self.base.thickness_axis]
            b_n, b_t = s.free_molecular()
            for k, (fa, _) in enumerate(needed):
                if fa == "lateral" and lt[k] > 0:
                    a = vt[:, k]
                    sw = area * float(a[:q] @ sub.top_w @ a[:q])
                    f[k], Q[k] = _stokes_mode(float(a @ K @ a), float(a @ M @ a), sw, math.sqrt(lt[k]), rho_f, eta_f,
                                              s.fluid_factor, s.Q_int, b_fm=b_t)
                if fa not in ("flapwise", "torsion") or lt[k] <= 0:
                    continue
                a = vt[:, k]
                mq, sq = float(a @ M @ a), area * float(a[:q] @ sub.top @ a[:q])
                f[k], Q[k], x = _fluid_mode(float(a @ K @ a), mq, sq, math.sqrt(lt[k]), w, rho_f, eta_f,
                                            s.fluid_factor, s.Q_int, torsion=fa == "torsion", b_fm=b_n)
                if hydro is not None:
                    hydro.setdefault("x", np.full(len(needed), np.nan))[k] = x
                    # the top face's share: flapwise only (torsion's load is the uniform beam's exactly)
                    hydro.setdefault("r", np.full(len(needed), np.nan))[k] = (
                        min(rho_t * sq / mq, 1.0) if fa == "flapwise" else np.nan)
        f[lt == 0] = np.nan
        return f, Q


class _Sub:
    """The reduced pieces projected on one block set's basis ``T`` (coordinates in the union)."""

    def __init__(self, red: ReducedModal, T: np.ndarray) -> None:
        self.red = red
        self.T = T
        P = lambda A: _sym(T.T @ A @ T)  # noqa: E731
        self.K = P(red.K_r)
        self.M_el = P(red.M_el)
        self.M_fixed = P(red.M_fixed)
        self.M_tip = None if red.M_tip is None else P(red.M_tip)
        self.Sn = P(red.Sn_r)
        self.St = P(red.St_r)
        self.G = P(red.G_r)
        self.top = None if red.top_r is None else P(red.top_r)
        self.top_w = None if red.top_w_r is None else P(red.top_w_r)
        self.forms = np.array([P(red._fam_forms[f]) for f in FAMILIES + ("total",)])
        self.A_lt = None if red.A_lt_r is None else red.A_lt_r @ T
        self.face_m0 = red.face_m0 @ T
        self.face_m1 = red.face_m1 @ T
        self._face: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}  # overlap_terms, per stretch
        self._Ks = None
        self._Ks_tip = None
        self._Kc: dict[bool, np.ndarray | None] = {}
        self._path = None
        self._terms: dict[str, np.ndarray] = {}

    @property
    def Ks(self) -> np.ndarray:
        if self._Ks is None:
            self._Ks = np.einsum("ri,jlrs,sk->jlik", self.T, self.red.Ks, self.T, optimize=True)
        return self._Ks

    @property
    def Ks_tip(self) -> np.ndarray | None:
        if self._Ks_tip is None and self.red.Ks_tip is not None:
            self._Ks_tip = np.einsum("ri,jlrs,sk->jlik", self.T, self.red.Ks_tip, self.T, optimize=True)
        return self._Ks_tip

    def Kc(self, tip: bool = False) -> np.ndarray | None:
        if tip not in self._Kc:
            A = self.red.Kc(tip)
            self._Kc[tip] = None if A is None else np.einsum("ri,jlrs,sk->jlik", self.T, A, self.T, optimize=True)
        return self._Kc[tip]

    def path_operator(self, xi: float) -> np.ndarray:
        if self._path is None:
            self._path = self.red.path_ops() @ self.T  # (101, 3, q)
        n = self._path.shape[0]
        x = float(np.clip(xi, 0.0, 1.0)) * (n - 1)
        i = min(int(x), n - 2)
        f = x - i
        return (1 - f) * self._path[i] + f * self._path[i + 1]

    def term(self, t: Term) -> np.ndarray:
        hit = self._terms.get(t.key)
        if hit is None:
            hit = _sym(self.T.T @ self.red.term(t) @ self.T)
            self._terms[t.key] = hit
        return hit

    def matrices(self, s: ModalState, penalty: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Reduced K and M of state ``s``. Only the ``clamp`` shapes move the clamp face; with them
        in the basis a rigid clamp is the foundation at compliance ``C_MIN`` (frequency error ~1e-7),
        without them (``penalty=False``) the clamp term is left out."""
        base = self.red.base
        sc = np.asarray(s.scale, float)
        vol = float(np.prod(sc))
        # a meshed tip is stretched in-plane only (stretch_points): its own factors
        tip = self.M_tip is not None and np.any(sc != 1.0)
        sct = sc.copy()
        sct[base.thickness_axis] = 1.0
        vol_t = float(np.prod(sct))
        def stretched_sum(Ks: np.ndarray, Kt: np.ndarray | None) -> np.ndarray:
            out = np.zeros_like(self.K)
            for j in range(3):
                for l in range(3):
                    if Kt is None:
                        out += (vol / (sc[j] * sc[l])) * Ks[j, l]
                    else:
                        out += (vol / (sc[j] * sc[l])) * (Ks[j, l] - Kt[j, l]) + (vol_t / (sct[j] * sct[l])) * Kt[j, l]
            return out

        if np.any(sc != 1.0):
            Ks = self.Ks
            K = stretched_sum(Ks, self.Ks_tip if tip else None)
            if s.crystal and self.Kc() is not None:  # None: no region has a crystal
                K += s.crystal * stretched_sum(self.Kc(), self.Kc(True) if tip else None)
            # the split's quadrature remainder (fem_terms.reduced_stiffness_split) is stiffness too: it
            # scales with the modulus as in the unstretched branch below (continuous at s = 1)
            K = s.E_factor * (K + (self.K - Ks.sum(axis=(0, 1))))
        else:
            K = s.E_factor * self.K if s.E_factor != 1.0 else self.K.copy()
            if s.crystal and self.Kc() is not None:
                K += (s.E_factor * s.crystal) * self.Kc().sum(axis=(0, 1))
        if penalty:
            kn, kt = base.clamp_stiffness(*s.clamp, scale=sc)
            fa = base.clamp_face_factor(sc)
            K += fa * (kn * self.Sn + kt * self.St)
        if s.axial_stress:
            K += s.axial_stress * (vol / sc[base.axis] ** 2) * self.G
        if tip:
            M = s.rho_factor * (vol * (self.M_el - self.M_tip) + vol_t * self.M_tip) + self.M_fixed
        else:
            M = (vol * s.rho_factor) * self.M_el + self.M_fixed
        for xi, mass in s.masses:
            if mass:
                A = self.path_operator(xi)
                M = M + mass * (A.T @ A)
        for t in s.terms:
            f = t.factor * float(np.prod(sc ** np.asarray(t.exponents, float)))
            if t.matrix == "K":
                K = K + f * self.term(t)
            else:
                M = M + f * self.term(t)
        return _sym(K), _sym(M)

    def augment(self, K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``K``, ``M`` with the lumped tip's three coordinates (``AugmentedModel.augmented``): the tip mass m on
        the diagonal springs K_t to the attachment A, ``[[K + A^T K_t A, -A^T K_t], [-K_t A, K_t]]`` and
        ``diag(M, m I)``. The springs' attachment is a face average, which an affine stretch leaves unchanged."""
        lt = self.red.lumped_tip
        Kt = np.diag(np.asarray(lt.stiffness, float))
        A = self.A_lt
        q = K.shape[0]
        Ka = np.zeros((q + 3, q + 3))
        Ka[:q, :q] = K + A.T @ Kt @ A
        Ka[:q, q:] = -A.T @ Kt
        Ka[q:, :q] = -Kt @ A
        Ka[q:, q:] = Kt
        Ma = np.zeros((q + 3, q + 3))
        Ma[:q, :q] = M
        Ma[q:, q:] = lt.mass * np.eye(3)
        return Ka, Ma

    def face_rigid(self, scale, gram: bool = False):
        """(6, q) the clamp face's rigid motion (translations, rotations about its centroid, model axes) of
        each basis shape in the geometry stretched by ``scale``: the face-mass least-squares fit of the
        face displacement by the stretched face's rigid motions (exact when the face moves rigidly).
        ``gram``: also their Gram matrix ``int R^T R dA`` (over the reference face's area)."""
        red = self.red
        sc = np.asarray(scale, float)
        J = red.face_J * np.outer(sc, sc)
        X1 = red.face_X1 * sc
        G = np.zeros((6, 6))
        G[:3, :3] = red.face_A * np.eye(3)
        rot = np.einsum("cad,d->ca", _EPS, X1)  # int (e_a x X)_c dA
        G[:3, 3:] = rot
        G[3:, :3] = rot.T
        G[3:, 3:] = np.einsum("cad,cbe,de->ab", _EPS, _EPS, J)
        rhs = np.zeros((6, self.face_m0.shape[1]))
        rhs[:3] = self.face_m0
        rhs[3:] = np.einsum("cad,d,cdk->ak", _EPS, sc, self.face_m1)
        P = np.linalg.solve(G, rhs)
        return (P, G) if gram else P

    def overlap_terms(self, K: np.ndarray, M: np.ndarray, s: "ModalState") -> tuple[np.ndarray, np.ndarray]:
        """``K``, ``M`` with the bonded segment (:meth:`FEMBaseline.overlap_segment`) condensed on its chip-edge
        node (Guyan: its static shapes under the node's six motions, which carry its inertia too -- exact in
        statics, and in dynamics while the segment's own modes on the bond lie above the measured ones: the
        full re-solve keeps every DOF of it, :func:`full_solve`). The node is the clamp face's rigid motion
        ``P a`` (:meth:`face_rigid`; coordinates appended before, e.g. a lumped tip's, do not move the face);
        the face's deformation beyond it is held as by a rigid clamp."""
        base = self.red.base
        key = (tuple(s.overlap), tuple(np.asarray(s.scale, float)), s.E_factor, s.rho_factor)
        cache = self.red._overlap_cache
        if key not in cache:  # a fit's finite differences in other parameters reuse the segment
            if len(cache) > 64:
                cache.clear()
            cache[key] = base.overlap_segment(s, condensed=True)
        Kr, Mr = cache[key]
        q = self.face_m0.shape[1]
        sk = tuple(np.asarray(s.scale, float))
        if sk not in self._face:  # the face's projection and the hold on its deformation: per geometry
            P, G = self.face_rigid(s.scale, gram=True)
            # a stretched mesh's rotation shapes are not rigid, their face parts are: int |u - R q|^2 dA = u^T S u - q^T G q
            hold = base.clamp_stiffness(C_MIN, C_MIN)[0] * base.clamp_face_factor(s.scale) * (self.Sn + self.St - P.T @ G @ P)
            if len(self._face) > 64:
                self._face.clear()
            self._face[sk] = (P, _sym(hold))
        P, hold = self._face[sk]
        K, M = K.copy(), M.copy()
        K[:q, :q] += _sym(P.T @ Kr @ P) + hold
        M[:q, :q] += _sym(P.T @ Mr @ P)
        return K, M

    def families_of(self, V: np.ndarray) -> list[str]:
        q = (V[None, :, :] * (self.forms @ V)).sum(axis=1)  # (5, k)
        shares = q[:-1] / q[-1]
        j = np.argmax(shares, axis=0)
        ok = shares[j, np.arange(V.shape[1])] >= 0.5
        return [FAMILIES[jj] if o else "other" for jj, o in zip(j, ok)]


def _sym(A: np.ndarray) -> np.ndarray:
    return 0.5 * (A + A.T)


_EPS = np.zeros((3, 3, 3))  # the Levi-Civita symbol: (e_a x X)_c = eps[c, a, d] X_d
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _EPS[_i, _j, _k], _EPS[_i, _k, _j] = 1.0, -1.0


def overlap_active(s: ModalState) -> bool:
    """Whether state ``s`` carries a bonded overlap (a compliant bond over a positive length)."""
    lam_n, lam_t, lo = s.overlap
    return lo > 0 and max(lam_n, lam_t) > LAMBDA_MIN


def _lowest_pairs(K: np.ndarray, M: np.ndarray, n: int, shift: float) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` lowest eigenpairs of ``K v = lam M v`` (reduced, dense), solved as the shifted
    inverse pencil ``M v = mu (K + shift M) v``, ``lam = 1 / mu - shift``: the Ritz basis is
    orthonormal in the energy norm ``K + lambda_1 M``, so ``K + shift M`` is well conditioned while
    ``M`` alone is not (shapes with much strain and little kinetic energy: condition numbers up
    to 1e10 on very thin levers, where a Cholesky factor of ``M`` loses every digit of the low
    modes). Vectors are returned M-normalised. Falls back to the direct pencil if ``K + shift M``
    is not positive definite (a state beyond buckling)."""
    r = K.shape[0]
    try:
        mu, V = sla.eigh(M, K + shift * M, subset_by_index=[r - n, r - 1], driver="gvx")
        lam = 1.0 / mu[::-1] - shift
        V = V[:, ::-1]
    except (np.linalg.LinAlgError, ValueError):
        try:
            lam, V = sla.eigh(K, M, subset_by_index=[0, n - 1], driver="gvx")
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise SolverError(f"reduced eigenproblem failed: {exc}") from None
    mn = np.sqrt(np.maximum(np.einsum("ij,ij->j", V, M @ V), 1e-300))
    return lam, V / mn[None, :]


def _fluid_mode(kq, mq, sq, om, w, rho_f, eta_f, factor, Q_int, torsion: bool = False, b_fm: float = math.inf):
    """Loaded frequency [Hz], Q and added-mass ratio ``x`` (the fluid's added modal mass over the mode's own) of
    one flapwise mode (Rayleigh quotient with its shape): added mass ``(pi/4) rho_f w Gamma_r`` per unit area
    of the top face's transverse motion, damping from Gamma_i, iterated to the loaded frequency.

    ``torsion``: a torsion mode, ``(3 pi / 32) rho_f w Gamma_tor,r`` per unit area of the top face's transverse
    motion: for a section rotating by theta (``u_t = theta y``, ``int u_t^2 dy = theta^2 w^3 / 12``) this is the
    added moment of inertia ``(pi/128) rho_f w^4 Gamma_tor,r`` per length of Green & Sader (2002), i.e. their
    uniform-beam loading exactly for a rigid section rotation (:func:`~probedyn.diagnose.hydrodynamics.torsion_gamma`).

    ``b_fm``: a rarefied gas's free-molecular damping per unit area of the face's transverse motion (both faces,
    :func:`~probedyn.diagnose.hydrodynamics.free_molecular_damping`); the continuum load is scaled by
    :func:`~probedyn.diagnose.hydrodynamics.rarefied_factor` at each frequency (infinite: a continuum)."""
    gamma = torsion_gamma if torsion else sader_gamma
    ma0 = factor * (3.0 * math.pi / 32.0 if torsion else 0.25 * math.pi) * rho_f * w * sq
    c_fm = b_fm * sq

    def load(o):  # Gamma at o, scaled for a rarefied gas
        gg = complex(gamma(o, w, rho_f, eta_f))
        return gg if not math.isfinite(c_fm) else gg * rarefied_factor(c_fm, o * ma0 * gg.imag)

    def loaded(o):  # one pass of the fixed point o = sqrt(kq / (mq + ma Gamma_r(o))), and Gamma at o
        gg = load(o)
        return math.sqrt(kq / (mq + ma0 * gg.real)), gg

    # the fixed point by secant steps on h(o) = loaded(o) - o (the plain iteration contracts by ~x / (2 (1 + x))
    # |d ln Gamma_r / d ln omega| per pass, ~0.05 in water: 11 passes to 1e-14 against 4-5); a secant step that
    # is not finite and positive falls back to the plain pass
    done = False
    prev = None
    for _ in range(60):
        om_new, g = loaded(om)
        h = om_new - om
        done = abs(h) <= 1e-14 * om
        if done:
            break
        nxt = om_new
        if prev is not None and h != prev[1]:
            cand = om - h * (om - prev[0]) / (h - prev[1])
            if math.isfinite(cand) and cand > 0:
                nxt = cand
        prev = (om, h)
        om = nxt
    if not done:
        g = load(om)
    qf = (mq + ma0 * g.real) / (ma0 * g.imag) if g.imag > 0 else math.inf
    return om / (2 * math.pi), 1.0 / (1.0 / Q_int + 1.0 / qf), ma0 * g.real / mq


def top_face_forms(model: ElasticModel, thickness_axis: int, width_axis: int) -> tuple[sp.spmatrix, sp.spmatrix]:
    """The top face's mass forms ``int u_t^2 dA`` (transverse: Sader's load on flapwise modes) and
    ``int u_w^2 dA`` (in-plane across the width: the Stokes layers on lateral modes) of ``model``."""
    St = face_mass_scalar(model, "top")
    forms = []
    for ax in (thickness_axis, width_axis):
        e = np.zeros(3)
        e[ax] = 1.0
        forms.append(directional(St, np.outer(e, e)))
    return forms[0], forms[1]


def _stokes_mode(kq, mq, sq_w, om, rho_f, eta_f, factor, Q_int, b_fm: float = math.inf):
    """Loaded frequency [Hz] and Q of one lateral mode: the Stokes layers of the top and bottom faces
    (:func:`~probedyn.diagnose.hydrodynamics.stokes_layer_mass` per face; the bottom face moves across the
    width as the top one in lateral bending), ``sq_w`` the top face's in-plane mass form ``int u_w^2 dA`` of
    the mode, iterated to the loaded frequency. ``b_fm``: a rarefied gas's free-molecular damping per unit area
    of one face moving in its plane (as in :func:`_fluid_mode`; infinite: a continuum)."""

    def added(o):  # the two layers' added mass at o (their damping is o times it), scaled for a rarefied gas
        ma = factor * 2.0 * float(stokes_layer_mass(o, rho_f, eta_f)) * sq_w
        return ma if not math.isfinite(b_fm) else ma * rarefied_factor(2.0 * b_fm * sq_w, o * ma)

    for _ in range(60):
        ma = added(om)
        om_new = math.sqrt(kq / (mq + ma))
        done = abs(om_new - om) <= 1e-14 * om
        om = om_new
        if done:
            break
    ma = added(om)
    qf = (mq + ma) / ma if ma > 0 else math.inf
    return om / (2 * math.pi), 1.0 / (1.0 / Q_int + 1.0 / qf)


def _family_forms(model: ElasticModel, P: np.ndarray, n_slices: int = 24) -> dict[str, np.ndarray]:
    """Quadratic forms on the basis ``P`` of the family energy shares of
    :func:`probedyn.fem.modes.classify_shapes` (same slices, weights and rigid-section fit)."""
    from probedyn.fem import elasticity as el

    coords = model.basis.doflocs
    weights = el.lumped_weights(model.mesh, model.elem_density)
    axis = model.beam_axis
    perm = [axis, (axis + 1) % 3, (axis + 2) % 3]
    Xp = coords[perm]
    r = P.shape[1]
    U = P.reshape(model.n_nodes, 3, r)[:, perm, :]
    groups = FAMILY_COLUMNS
    forms = {f: np.zeros((r, r)) for f in groups}
    wU = U * weights[:, None, None]
    forms["total"] = np.einsum("nir,nis->rs", U, wU)
    for idx, sw, A in section_slices(Xp, weights, n_slices):
        b = (U[idx] * sw[:, None, None]).reshape(3 * idx.size, r)
        coef = np.linalg.lstsq(A, b, rcond=None)[0]  # (6, r)
        for f, cols in groups.items():
            Ac = A[:, cols] @ coef[cols]
            forms[f] += Ac.T @ Ac
    return forms


# ------------------------------------------------------------------------------------------
# Full FEM re-solve of an extended state
# ------------------------------------------------------------------------------------------


class _ExtendedModel(AugmentedModel):
    """An :class:`ElasticModel` with extra global matrices (clamp foundation, prestress, cause terms)."""

    def __init__(self, *args, extra_K=None, extra_M=None, **kw) -> None:
        super().__init__(*args, **kw)
        self._extra_K = extra_K
        self._extra_M = extra_M

    def assemble(self):
        if self._K is None:
            K, M = super().assemble()
            if self._extra_K is not None:
                K = (K + self._extra_K).tocsr()
            if self._extra_M is not None:
                M = (M + self._extra_M).tocsr()
            self._K, self._M = K, M
        return self._K, self._M


def _scaled_material(mat: Material, e: float, r: float, a: float = 0.0, R=None) -> Material:
    """``mat`` with its stiffness ``e (C + a (C_crystal - C))`` and density ``r rho``."""
    d = crystal_delta(mat, R) if a else None
    if e == 1.0 and r == 1.0 and d is None:
        return mat
    C = np.asarray(mat.C, float)
    if d is not None:
        C = C + a * d
    return Material(mat.name, e * C, mat.density * r,
                    mat.note + f"; diagnose: C x {e:.6g}" + (f", {a:.6g} of the way to {CRYSTALS[mat.name]}" if d is not None
                                                            else "") + f", rho x {r:.6g}")


def extended_model(base: FEMBaseline, s: ModalState) -> ElasticModel:
    """The full FEM of state ``s``: the mesh stretched by ``s.scale`` (the geometry the stretch
    represents), materials scaled, point masses attached at their coordinates, the clamp replaced
    by the elastic foundation when it is compliant, prestress and cause terms added as global
    matrices (the fluid is not in it: :func:`full_solve` applies it per mode)."""
    m0 = base.model
    sc = np.asarray(s.scale, float)
    regions = {name: (_scaled_material(mat, s.E_factor, s.rho_factor, s.crystal, R), R)
               for name, mat, R in zip(m0.region_names, m0.materials, m0.orientations)}
    pms = list(m0.point_masses)
    for xi, mass in s.masses:
        if mass > 0:
            pms.append(PointMass(tuple(base.mass_path(np.array([xi]))[:, 0] * sc), mass))
    compliant = s.clamp[0] >= C_MIN or s.clamp[1] >= C_MIN
    clamp = [c for c in m0.clamp if not (compliant and c == base.clamp_face)]
    model = stretched(m0, sc, _ExtendedModel, tip_map=(base.tip, base.thickness_axis), regions=regions, clamp=clamp,
                      point_masses=pms,
                      name=m0.name + " (extended)")
    extra_K = None
    extra_M = None
    if compliant:
        S = face_mass_scalar(model, base.clamp_face)
        nn = np.outer(base.clamp_normal, base.clamp_normal)
        kn, kt = base.clamp_stiffness(*s.clamp, scale=sc)
        extra_K = kn * directional(S, nn) + kt * directional(S, np.eye(3) - nn)
    if s.axial_stress:
        G = s.axial_stress * axial_gradient_matrix(model, base.axis)
        extra_K = G if extra_K is None else extra_K + G
    for t in s.terms:
        A = t.factor * t.build(model)  # built on the stretched model: no extra scaling
        if t.matrix == "K":
            extra_K = A if extra_K is None else extra_K + A
        else:
            extra_M = A if extra_M is None else extra_M + A
    model._extra_K, model._extra_M = extra_K, extra_M
    return model


def _end_operator(model: ElasticModel, axis: int) -> sp.csr_matrix | None:
    """(1, N) operator: the mean displacement of the ``free_end`` face along ``axis`` (the
    work-conjugate of a uniform traction on it); None when the probe has no such face."""
    if "free_end" not in (model.mesh.boundaries or {}):
        return None
    return model.attachment("free_end")[axis]


def end_stiffness(model: ElasticModel, axis: int) -> float:
    """The static spring constant [N/m] at the free end: a force F spread as a uniform traction over
    the ``free_end`` face along ``axis`` (the lever's thickness) over the face-mean deflection it
    causes -- the end load of beam theory (``3 E I / L^3`` for a slender Euler-Bernoulli lever),
    which converges under mesh refinement where a point load's deflection does not. The model's
    own clamp, or (with no clamp) its global matrices' support (an elastic foundation), holds it;
    ``nan`` without a ``free_end`` face."""
    A = _end_operator(model, axis)
    if A is None:
        return math.nan
    K, _ = model.assemble()
    free = model.free_dofs
    fac = factorize(K[free][:, free].tocsc(), spd=True)
    try:
        u = fac.solve(np.ascontiguousarray(np.asarray(A.T.todense())[free]))
    finally:
        fac.release()
    c = float((A[:, free] @ u).ravel()[0])
    if not (math.isfinite(c) and c > 0):
        raise SolverError(f"static end stiffness: non-positive compliance {c:g} m/N (a state beyond buckling?)")
    return 1.0 / c


def full_static_stiffness(base: FEMBaseline, s: ModalState) -> float:
    """:func:`end_stiffness` of the full FEM of state ``s`` (:func:`extended_model`; a bonded overlap:
    :class:`_BondedSystem`)."""
    model = extended_model(base, s)
    if not overlap_active(s):
        return end_stiffness(model, base.thickness_axis)
    A = _end_operator(model, base.thickness_axis)
    if A is None:
        return math.nan
    sysb = _BondedSystem(base, s, model)
    g = sysb.load(A)
    fac = factorize(sysb.K.tocsc(), spd=True)
    try:
        c = float(g @ fac.solve(np.ascontiguousarray(g)))
    finally:
        fac.release()
    if not (math.isfinite(c) and c > 0):
        raise SolverError(f"static end stiffness: non-positive compliance {c:g} m/N (a state beyond buckling?)")
    return 1.0 / c


def _rigid_motions(model: ElasticModel, centroid: np.ndarray, split: bool = False) -> np.ndarray:
    """(N, 6) the rigid motions of ``model``: translations, then rotations about ``centroid`` (model axes).
    ``split``: (N, 9), each rotation's two displacement components as separate shapes (``(z, 0, 0)`` and
    ``(0, 0, -x)`` for a rotation about y): an affine stretch of the geometry turns a rigid rotation of the
    mesh into a strained one, and the rotation of the stretched body is another combination of the two."""
    X = model.basis.doflocs - np.asarray(centroid, float)[:, None]
    rig = np.zeros((model.n_nodes, 3, 9 if split else 6))
    for c in range(3):
        rig[:, c, c] = 1.0
        e = np.zeros(3)
        e[c] = 1.0
        r = np.cross(e[None, :], X.T)  # (n, 3)
        if not split:
            rig[:, :, 3 + c] = r
            continue
        comps = [d for d in range(3) if d != c]
        for j, d in enumerate(comps):
            rig[:, d, 3 + 2 * c + j] = r[:, d]
    return rig.reshape(model.ndofs_total, rig.shape[2])


class _BondedSystem:
    """The full FEM of a bonded-overlap state: the body with its clamp face moving rigidly, ``u = v + R q``
    (``v`` zero on the face, ``R`` the face's rigid motions about its centroid), and the bonded segment's
    DOFs with its chip-edge node equal to ``q``. Unknowns ``[v_free, q, segment]``; exact, sparse (``R``
    adds six dense columns)."""

    def __init__(self, base: "FEMBaseline", s: ModalState, model: ElasticModel) -> None:
        K, M = model.assemble()
        self.model, self.free = model, model.free_dofs
        # the clamp face's centroid in the stretched geometry (the face is the lever's, never a tip's)
        self.R = R = _rigid_motions(model, base.clamp_centroid * np.asarray(s.scale, float))
        Ks, Ms = base.overlap_segment(s)
        fr = self.free
        blocks = []
        for A, S in ((K, Ks), (M, Ms)):
            A = A.tocsr()
            AR = np.asarray(A @ R)
            top = sp.hstack([A[fr][:, fr], sp.csr_matrix(AR[fr]), sp.csr_matrix((fr.size, S.shape[0] - 6))])
            seg = S.copy()
            seg[:6, :6] += R.T @ AR
            low = sp.hstack([sp.csr_matrix(np.vstack([AR[fr].T, np.zeros((S.shape[0] - 6, fr.size))])),
                             sp.csr_matrix(_sym(seg))])
            blocks.append(sp.vstack([top, low]).tocsr())
        self.K, self.M = blocks

    def body(self, V: np.ndarray) -> np.ndarray:
        """The body's displacement (N, k) of augmented vectors ``V``."""
        nf = self.free.size
        U = self.R @ V[nf:nf + 6]
        U[self.free] += V[:nf]
        return U

    def load(self, A: sp.spmatrix) -> np.ndarray:
        """The generalised force of a body load ``A`` (1, N) on the augmented unknowns."""
        a = np.asarray(A.todense()).ravel()
        return np.concatenate([a[self.free], self.R.T @ a, np.zeros(self.K.shape[0] - self.free.size - 6)])


def full_solve(base: FEMBaseline, s: ModalState, needed: list[tuple[str, int]], n_modes: int | None = None
               ) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Frequencies and Q of the measured ``(family, order)`` modes from the full FEM of state ``s``
    (:func:`extended_model`; a bonded overlap: :class:`_BondedSystem`); the fluid loading is applied per
    flapwise mode with the FEM mode shape (Rayleigh quotient, iterated to the loaded frequency).
    """
    t0 = time.perf_counter()
    sc = np.asarray(s.scale, float)
    model = extended_model(base, s)
    n = n_modes or len(base.families) + 4
    if overlap_active(s):
        sysb = _BondedSystem(base, s, model)
        r = shift_invert_eigsh(sysb.K, sysb.M, n, sigma=0.0)
        V = r.vectors / np.sqrt(np.einsum("ij,ij->j", r.vectors, sysb.M @ r.vectors))[None, :]
        U = sysb.body(V)
        wts = lumped_weights(model.mesh, model.elem_density, model.element, model.basis)
        fams, _ = classify_shapes(model.basis.doflocs, wts, U.reshape(model.n_nodes, 3, -1), axis=model.beam_axis)
        omegas = np.sqrt(np.maximum(r.eigenvalues, 0.0))
        # per mode: (family, omega, body shape, modal stiffness, modal mass) -- the segment's share included
        modes = [(fams[i], float(omegas[i]), U[:, i], float(V[:, i] @ (sysb.K @ V[:, i])), 1.0)
                 for i in range(V.shape[1])]
    else:
        res = model.modes(n, sigma=None if not model.clamp else 0.0)  # assembles (its PARDISO analysis overlaps)
        K, M = model.assemble()
        modes = [(md.family, md.omega, md.shape, float(md.shape @ (K @ md.shape)), float(md.shape @ (M @ md.shape)))
                 for md in res.modes]
    fams = [md[0] for md in modes]
    f = np.empty(len(needed))
    Q = np.full(len(needed), s.Q_int)
    Stop = Stop_w = None
    x_added = np.full(len(needed), np.nan)
    r_top = np.full(len(needed), np.nan)
    rho_t = model.materials[0].density * base.t * sc[base.thickness_axis]
    rho_f, eta_f = s.medium
    if rho_f > 0 and s.fluid_factor > 0 and "top" in (model.mesh.boundaries or {}):
        Stop, Stop_w = top_face_forms(model, base.thickness_axis, base.width_axis)
    w = base.w * sc[base.width_axis]
    b_n, b_t = s.free_molecular()
    for k, (fa, o) in enumerate(needed):
        idx = [i for i, x in enumerate(fams) if x == fa]
        if len(idx) < o:
            f[k] = np.nan
            continue
        _, omega, a, kq, mq = modes[idx[o - 1]]
        f[k] = omega / (2 * np.pi)
        if Stop_w is not None and fa == "lateral":
            f[k], Q[k] = _stokes_mode(kq, mq, float(a @ (Stop_w @ a)), omega, rho_f, eta_f, s.fluid_factor, s.Q_int,
                                      b_fm=b_t)
        if Stop is not None and fa in ("flapwise", "torsion"):
            sq = float(a @ (Stop @ a))
            f[k], Q[k], x_added[k] = _fluid_mode(kq, mq, sq, omega, w, rho_f, eta_f,
                                                 s.fluid_factor, s.Q_int, torsion=fa == "torsion", b_fm=b_n)
            if fa == "flapwise":
                r_top[k] = min(rho_t * sq / mq, 1.0)
    info = {"dofs": model.dofs, "seconds": time.perf_counter() - t0, "families": fams,
            "frequencies_hz": [md[1] / (2 * np.pi) for md in modes], "hydro": {"x": x_added, "r": r_top}}
    return f, Q, info
