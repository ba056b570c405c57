"""Oscillatory Stokes flow around a thin rectangular beam section: the flexural and torsional
hydrodynamic functions, by Taylor-Hood (P2/P1) finite elements.

Physics. A beam of width ``b`` and length ``L >> b`` vibrates with small amplitude at angular
frequency omega in an unbounded incompressible fluid (density rho, viscosity eta). Each cross-section
sees two-dimensional unsteady Stokes flow (the convective term is negligible for small amplitude).
With lengths scaled by the half-width ``a = b / 2``, velocities by the section's velocity scale and the
time factor ``exp(-i omega t)``::

    -i Re u = -grad p + lap u,   div u = 0,   Re = rho omega a^2 / eta = rho omega b^2 / (4 eta),

u prescribed on the section (no slip), u -> 0 far away (u = 0 on a circle of radius ``r_out``).

* ``motion="translate"`` (flexure): the section moves with velocity U e_y, normal to its faces.
  J. E. Sader, J. Appl. Phys. 84, 64 (1998) writes the force per unit length on the beam as
  ``F = (pi/4) rho omega^2 b^2 Gamma(omega) W`` (W the displacement, U = -i omega W), i.e.
  ``Gamma = -i F / (pi rho omega a^2 U)``: ``Gamma -> 1`` (added mass pi rho a^2 of a flat plate) as
  Re -> infinity, ``Im Gamma > 0`` is the dissipation.
* ``motion="rotate"`` (torsion): the section rotates about its centre line with angular velocity
  Omega (u = Omega (-y, x) on the section; C. P. Green and J. E. Sader, J. Appl. Phys. 92, 6262
  (2002)). The torque per unit length is normalised here by the inviscid added moment of inertia of
  a flat plate, (pi/8) rho a^4 = pi rho b^4 / 128: ``Gamma_tor = -i T / ((pi/8) rho omega a^4 Omega)``,
  so that ``Gamma_tor -> 1`` as Re -> infinity. (If a published torsional function is defined with the
  prefactor (pi/8) rho omega^2 b^4, b the full width, it is this one divided by 16: check the prefactor
  before comparing.)

Assumptions: 2D flow (L >> b), incompressible Newtonian fluid, small amplitude (linear, no
convection), unbounded fluid (no nearby surface), rigid section of thickness ``h`` (``thickness_ratio
= h / b``; Sader's and Green & Sader's functions are for h -> 0, reached by extrapolation in h, see
benchmarks/torsional_gamma_table.py).

Discretisation: P2 velocity / P1 pressure on straight triangles (:mod:`probedyn.meshes.section2d`),
viscous term in the symmetric-gradient form ``2 eps(u) : eps(v)`` (so that the weak residual is the
true traction ``(-p I + 2 eps(u)) n``; for a divergence-free u the PDE is the same as with the
Laplacian), real matrices A (viscous), M (mass), B (divergence) assembled once and combined into the
complex system ``A - i Re M``; Dirichlet data on both boundaries, one pressure value pinned on the
outer circle, the reduced system factorised by SuperLU (``scipy.sparse.linalg.splu``). The force and
torque are the **reaction**: minus the residual of the assembled momentum equations at the section's
velocity DOFs, weighted by the rigid motion (the consistent traction, much more accurate than
integrating the stress of the discrete solution: :func:`stress_integral`, 0.1-0.4 % off at Re = 10 and
converging slowly because of the corner singularities, while the reaction changes by < 1e-5).

Accuracy (benchmarks/torsional_gamma_table.py, Re = 0.1 .. 1e4): on the default mesh (``refine=1``, 20-100k
unknowns on the whole disc, a quarter of that on the quadrant) the reaction converges with order ~3-4 in the
mesh size and is within ~1e-4 (Re <= 1e3) to ~4e-4 (Re = 1e4) of |Gamma| from the converged value; the
zero-thickness extrapolation (:func:`thin_limit`) adds < 1e-4; the flexural function so obtained agrees with
Sader's fit within 1e-4 (real part, all Re) and 3e-4 (imaginary part, Re <= 100; it drifts to +0.7 % at Re =
1e4, the top of the fit's range, where our values follow the boundary-layer asymptote). Finite thickness
matters: at h/b = 0.01 and Re = 1e4 Gamma_i is 7-8 % low.

Symmetry (since session 41): both motions are symmetric under the section's two mirror lines, so one
quadrant is solved (:func:`probedyn.meshes.section2d.section_mesh` with ``quarter=True``, the default of
:func:`build_section_system`). A mirror maps the rigid motion to itself (even) or to minus itself (odd): the
translation ``(0, 1)`` is even about ``x = 0`` and odd about ``y = 0``, the rotation ``(-y, x)`` odd about both.
On a line about which the flow is even the normal velocity vanishes and the shear traction is zero (natural);
about which it is odd the tangential velocity vanishes and the pressure is odd, so the normal traction
``-p + 2 du_n/dn`` is zero (natural, and it fixes the pressure's constant: no pinned value). The loads are four
times the quadrant's. Measured against the whole disc on the same sizes (Re = 0.01, 10, 1e3, 1.3e4): within
2e-4 of each part for both motions (1.4e-3 of the translational Gamma_i at Re = 1.3e4, where the whole disc's mesh
is the less converged), 4-6x faster with the meshing (tests/test_stokes2d.py checks the agreement).

Performance note: complex SuperLU runs ~100x slower with multi-threaded OpenBLAS on few shared cores;
importing :mod:`probedyn` first sets ``OPENBLAS_NUM_THREADS=1`` (it must precede numpy's import).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu
from skfem import Basis, BilinearForm, ElementTriP1, ElementTriP2, ElementVector, FacetBasis, Functional
from skfem.helpers import ddot, div, dot, sym_grad

from probedyn.meshes.section2d import default_sizes, section_mesh

__all__ = ["MOTIONS", "StokesSection", "SectionFlow", "ThinLimit", "build_section_system", "default_r_out",
           "extrapolate_thin", "gamma_from_load", "section_hydrodynamic_function", "stress_integral", "thin_limit",
           "thin_thicknesses", "zero_thickness_gamma"]

MOTIONS = ("translate", "rotate")


def default_r_out(re: float) -> float:
    """Default radius of the outer circle (units of the half-width) at Reynolds number ``re``:
    ``max(200, 100 delta)``, delta = sqrt(2 / Re). The vortical part of the flow decays as exp(-r/delta),
    but the irrotational part of the translational flow is a dipole (u ~ r^-2), and u = 0 on the circle
    shifts Gamma by ~C / R^2 relative (measured: C ~ 1-2 delta^2 at Re = 0.1 and 1, ~0.6 at Re >= 100;
    concentric cylinders: 2): ~1e-4 at this radius. The rotational flow (a quadrupole,
    u ~ r^-3) is insensitive to R (< 1e-5 from R = 25 on)."""
    return max(200.0, 100.0 * math.sqrt(2.0 / re))


@BilinearForm
def _viscous(u, v, w):
    return 2.0 * ddot(sym_grad(u), sym_grad(v))


@BilinearForm
def _mass(u, v, w):
    return dot(u, v)


@BilinearForm
def _divergence(u, q, w):
    return -div(u) * q


class StokesSection:
    """The assembled Taylor-Hood system on one mesh (reusable for several Re and both motions).

    ``mesh`` needs boundaries ``section`` and ``outer`` (:func:`probedyn.meshes.section2d.section_mesh`).
    """

    def __init__(self, mesh):
        self.mesh = mesh
        self.ub = Basis(mesh, ElementVector(ElementTriP2()), intorder=4)
        self.pb = Basis(mesh, ElementTriP1(), intorder=4)
        nu, npr = self.ub.N, self.pb.N
        self.nu, self.npr = nu, npr
        self.A = _viscous.assemble(self.ub).tocsr()
        self.M = _mass.assemble(self.ub).tocsr()
        self.B = _divergence.assemble(self.ub, self.pb).tocsr()  # (npr, nu)
        self.quarter = "sym_x" in mesh.boundaries
        self.copies = 4 if self.quarter else 1

        def dofs(name):
            return np.unique(self.ub.get_dofs(mesh.boundaries[name]).all())

        self.sec = dofs("section")
        self._no_slip = np.unique(np.concatenate([self.sec, dofs("outer")]))
        comp = np.arange(nu) % 2  # interleaved DOFs: 2 s + c
        if self.quarter:
            # the velocity component each motion's symmetry fixes to zero on each line (module docstring)
            sx, sy = dofs("sym_x"), dofs("sym_y")
            on = {c: (sx[comp[sx] == c], sy[comp[sy] == c]) for c in (0, 1)}
            self._sym = {"translate": np.concatenate([on[0][0], on[0][1]]),  # u_x = 0 on both lines
                         "rotate": np.concatenate([on[1][0], on[0][1]])}  # tangential u = 0 on both
            self._pin = np.zeros(0, dtype=np.int64)  # the lines' natural normal traction fixes the pressure
        else:
            self._sym = {m: np.zeros(0, dtype=np.int64) for m in MOTIONS}
            self._pin = np.array([nu + int(self.pb.get_dofs(mesh.boundaries["outer"]).all()[0])])

    def _fixed(self, motion: str) -> np.ndarray:
        return np.unique(np.concatenate([self._no_slip, self._sym[motion], self._pin]))

    def rigid_velocity(self, motion: str) -> np.ndarray:
        """Velocity DOF vector of the rigid motion: (0, 1) for ``translate``, (-y, x) for ``rotate``
        (at every velocity DOF; the solver uses its section values)."""
        x, y = self.ub.doflocs
        comp = np.arange(self.nu) % 2  # interleaved DOFs: 2 s + c
        if motion == "translate":
            return (comp == 1).astype(float)
        if motion == "rotate":
            return np.where(comp == 0, -y, x)
        raise ValueError(f"motion must be one of {MOTIONS}, got {motion!r}")

    def solve(self, re: float, motions=MOTIONS) -> dict[str, "SectionFlow"]:
        """Solve at Reynolds number ``re`` for each motion (one factorisation per set of constrained DOFs:
        one for both motions on a whole mesh, one each on a quarter)."""
        re = float(re)
        Kuu = (self.A - 1j * re * self.M).tocsr()
        K = sp.bmat([[Kuu, self.B.T], [self.B, None]], format="csr")
        K_sec = K[self.sec]
        n = self.nu + self.npr
        out, factors = {}, {}
        for motion in motions:
            rigid = self.rigid_velocity(motion)
            fixed = self._fixed(motion)
            key = fixed.tobytes()
            if key not in factors:
                free = np.setdiff1d(np.arange(n), fixed)
                Kf = K[free]
                factors[key] = (free, splu(Kf[:, free].tocsc(), permc_spec="COLAMD", diag_pivot_thresh=0.1),
                                Kf[:, fixed])
            free, lu, K_free_fixed = factors[key]
            x = np.zeros(n, dtype=complex)
            x[self.sec] = rigid[self.sec]  # the symmetry lines' fixed components are zero there too
            x[free] = lu.solve(-(K_free_fixed @ x[fixed]))
            reaction = K_sec @ x  # the fluid's residual at the section's velocity DOFs
            # force (translate) or torque (rotate) on the body; a quarter carries a quarter of it
            load = -self.copies * np.dot(reaction, rigid[self.sec])
            out[motion] = SectionFlow(motion, re, x[: self.nu], x[self.nu:], complex(load), self)
        return out


@dataclass
class SectionFlow:
    """One solution: velocity and pressure DOFs, and the load on the body per unit length (force
    along y for ``translate``, torque for ``rotate``, in units of eta U resp. eta Omega a^2)."""

    motion: str
    re: float
    u: np.ndarray
    p: np.ndarray
    load: complex
    system: StokesSection

    @property
    def gamma(self) -> complex:
        """The hydrodynamic function ``Gamma_r + 1j Gamma_i`` (module docstring; Gamma_i > 0)."""
        return gamma_from_load(self.load, self.re, self.motion)


def gamma_from_load(load: complex, re: float, motion: str) -> complex:
    """Hydrodynamic function from the dimensionless force (translate) or torque (rotate) on the body."""
    norm = math.pi if motion == "translate" else math.pi / 8.0
    return complex(-1j * load / (norm * re))


def stress_integral(flow: SectionFlow) -> complex:
    """The same load as ``flow.load`` from the direct integral of the discrete stress
    ``(-p I + 2 eps(u)) n`` over the section's sides (less accurate: the stress is singular at the
    corners); for checks."""
    sysm = flow.system
    facets = sysm.mesh.boundaries["section"]
    fu = FacetBasis(sysm.mesh, sysm.ub.elem, facets=facets, intorder=6)
    fp = FacetBasis(sysm.mesh, sysm.pb.elem, facets=facets, intorder=6)

    @Functional
    def load(w):
        eps = sym_grad(w["u"])
        n = -w.n  # FacetBasis normals point out of the fluid: into the body; the body's outward normal
        tx = -w["p"] * n[0] + 2.0 * (eps[0, 0] * n[0] + eps[0, 1] * n[1])
        ty = -w["p"] * n[1] + 2.0 * (eps[1, 0] * n[0] + eps[1, 1] * n[1])
        if flow.motion == "translate":
            return ty
        x, y = w.x
        return x * ty - y * tx

    parts = [sysm.copies * load.assemble(fu, u=fu.interpolate(part(flow.u)), p=fp.interpolate(part(flow.p)))
             for part in (np.real, np.imag)]
    return complex(parts[0], parts[1])


def build_section_system(re: float, thickness_ratio: float = 0.01, refine: float = 1.0,
                         r_out: float | None = None, quarter: bool = True, **sizes) -> StokesSection:
    """Mesh the fluid around a section of thickness ratio ``h / b`` for Reynolds number ``re`` (the
    mesh is graded to the penetration depth sqrt(2/Re); ``refine`` divides all sizes) and assemble; by
    default one quadrant with the motions' symmetries (module docstring), ``quarter=False`` the whole disc."""
    t = 2.0 * thickness_ratio
    delta = math.sqrt(2.0 / re)
    opts = default_sizes(t, delta, refine)
    opts.update(sizes)
    mesh = section_mesh(t, r_out or default_r_out(re), quarter=quarter, **opts)
    return StokesSection(mesh)


def thin_thicknesses(re: float) -> tuple[float, float, float]:
    """Thickness ratios ``h / b`` for the extrapolation to zero thickness at Reynolds number ``re``:
    ``h0, h0/2, h0/4`` with ``h0 = min(0.005, 0.04 delta / b)`` (delta / b = 1 / sqrt(2 Re)).

    Measured (h/b from 0.04 down to 8e-5, Re = 10, 1e3, 1e4): Gamma(h) is linear in h (successive
    differences halve, ratio 2.0-2.15) once h << a and h < ~0.04 delta; with h ~ delta it is not (the
    square corners then cut the edge singularity off at h instead of delta: at Re = 1e4, h/b = 0.01 the
    dissipative part is 8 % low)."""
    h0 = min(0.005, 0.04 / math.sqrt(2.0 * re))
    return (h0, h0 / 2.0, h0 / 4.0)


@dataclass
class ThinLimit:
    """Hydrodynamic function extrapolated to zero thickness from ``values`` at ``thickness_ratios``
    (each half the previous): ``gamma`` by quadratic Richardson extrapolation in h
    ``(8 f(h/4) - 6 f(h/2) + f(h)) / 3``, ``error`` its difference from the linear one ``2 f(h/4) - f(h/2)``."""

    gamma: complex
    error: float
    thickness_ratios: tuple
    values: tuple


def extrapolate_thin(thickness_ratios, values) -> ThinLimit:
    """Zero-thickness extrapolation (see :class:`ThinLimit`) of three values at halving thicknesses."""
    h = np.asarray(thickness_ratios, dtype=float)
    if h.size != 3 or not np.allclose(h[1:] / h[:-1], 0.5):
        raise ValueError(f"need three thickness ratios, each half the previous; got {tuple(h)}")
    f1, f2, f3 = (complex(v) for v in values)
    quad = (8.0 * f3 - 6.0 * f2 + f1) / 3.0
    lin = 2.0 * f3 - f2
    return ThinLimit(quad, abs(quad - lin), tuple(h), (f1, f2, f3))


def thin_limit(re: float, motions=MOTIONS, refine: float = 1.0, r_out: float | None = None,
               thickness_ratios=None) -> dict[str, ThinLimit]:
    """Zero-thickness hydrodynamic functions at ``re`` for each motion: three solves at
    ``thickness_ratios`` (default :func:`thin_thicknesses`) and :func:`extrapolate_thin`."""
    hs = tuple(thickness_ratios or thin_thicknesses(re))
    sols = [build_section_system(re, hb, refine, r_out).solve(re, motions) for hb in hs]
    return {m: extrapolate_thin(hs, [s[m].gamma for s in sols]) for m in motions}


def zero_thickness_gamma(re: float, motion: str = "translate", refine: float = 1.0,
                         r_out: float | None = None) -> complex:
    """The zero-thickness hydrodynamic function of ``motion`` at ``re`` (:func:`thin_limit`: three solves,
    ~7 s on the default mesh), i.e. Sader's Gamma_rect (``translate``) or the torsional function
    (``rotate``, normalised to 1 at large Re)."""
    if motion not in MOTIONS:
        raise ValueError(f"motion must be one of {MOTIONS}, got {motion!r}")
    return thin_limit(re, (motion,), refine, r_out)[motion].gamma


def section_hydrodynamic_function(re: float, motion: str = "translate", thickness_ratio: float = 0.01,
                                  refine: float = 1.0, r_out: float | None = None) -> complex:
    """Hydrodynamic function ``Gamma_r + 1j Gamma_i`` (``Gamma_i > 0``) of a rectangular section of
    thickness ratio ``h / b`` at ``Re = rho omega b^2 / (4 eta)`` for ``motion`` ``translate`` (Sader
    1998's flexural Gamma, -> 1 at large Re) or ``rotate`` (torsion, normalised by the plate's inviscid
    added moment of inertia, -> 1 at large Re; a function defined with the prefactor (pi/8) rho omega^2 b^4
    is this / 16).

    ``thickness_ratio=0`` gives the zero-thickness limit of Sader and Green & Sader (three solves and
    extrapolation, :func:`thin_limit`). ``refine`` divides the mesh sizes; ``r_out`` is the outer radius
    in half-widths (default :func:`default_r_out`). Assumptions: module docstring.
    """
    if motion not in MOTIONS:
        raise ValueError(f"motion must be one of {MOTIONS}, got {motion!r}")
    if thickness_ratio == 0:
        return zero_thickness_gamma(re, motion, refine, r_out)
    system = build_section_system(re, thickness_ratio, refine, r_out)
    return system.solve(re, (motion,))[motion].gamma
