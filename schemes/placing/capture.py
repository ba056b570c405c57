"""Capture phase: the cantilever with a sample at its end, eqs 4.22-4.41, Figs 4.18 and 4.21.

Beam (4.22)-(4.25): Euler-Bernoulli, clamped at ``x = 0``, free of moment at ``x = L``;
``rho A u'' + EI u'''' = 0``, ``u = U(x) e^{i omega t}``, ``U'''' = b^4 U`` with
``b^4 = rho A omega^2 / EI`` (the source's ``alpha_n = b^2``, 4.32). The sample of mass ``M`` is
held by the linearised contact spring ``k1`` (4.29) at the end. Two end conditions:

``end="grounded"`` (the source's model, 4.26-4.31: the contact spring is anchored at the
sample position ``z0``, which does not move, while the mass moves with the tip). The shear
force balance at ``x = L`` is (SOURCE-NOTES 4)::

    EI U'''(L) = (k1 - M omega^2) U(L),    i.e.  beta_n = k1/EI - M omega_n^2 / EI   (corrected 4.37)

An attached mass is an inertia ``-M omega^2``: it **lowers** the natural frequencies (this is
how cantilever mass sensing works). The printed (4.31)/(4.37) has ``k1 + M omega^2`` and so
concludes that heavier samples raise the frequency; the FEM with a point mass settles it
(:func:`fem_capture_frequencies`, tests).

``end="hanging"`` (transport: the sample hangs on the contact spring and is otherwise free):
the sample displacement ``Y = k1 U(L) / (k1 - M omega^2)`` and the end condition is
``EI U'''(L) = -M omega^2 k1 / (k1 - M omega^2) U(L)``. For ``omega << omega_c = sqrt(k1/M)``
this is a rigid tip mass (``-M omega^2``); the contact resonance ``omega_c`` is an extra mode.

Frequency equation (derived in docs/placing.md; the structure of the printed 4.38 with the
corrected beta): with ``x = bL``, ``K = k1 L^3 / EI``, ``mu = M / (rho A L)`` and
``beta L^3 = K - mu x^4`` (grounded)::

    x^3 (1 + cos x cosh x) = beta L^3 (cos x sinh x - sin x cosh x)            (4.38)

Limits (tests): ``K = mu = 0`` gives (2.40)/(4.39); ``K = 0`` the tip-mass equation (3.10,
standard form, SOURCE-NOTES 1); ``K -> infinity`` the clamped-pinned ``tan x = tanh x``
(3.9266, 7.0686, ...); a spring alone (``mu = 0``, ``K = 3``, i.e. ``k1 = k``) stiffens mode 1 to
``bL = 2.2135`` (``omega`` x 1.39, close to the ``sqrt(2)`` of a doubled static stiffness).
Mode shapes: (4.40) for every ``beta`` (the moment condition alone fixes the ratio of the two
constants), evaluated in a cancellation-free form.

Forced response (4.41): modal superposition with modes normalised to
``int rho A psi^2 dx + M psi(L)^2 = 1`` (grounded) and a force ``F0`` at the tip.

MD linearisation (4.28)-(4.29), Fig 4.18: the contact's operating point at a given load
(default: zero load, the hanging sample's weight ``M g`` being ~1e-17 N against nN adhesion),
``k1 = dP/ddelta`` there and ``k0 = P - k1 delta``; the piecewise-linear approximation of the
unloading (stable) branch and its error. With nodes uniform in ``delta`` the maximum error
decays only as ``N^-1/2``: the branch ends at the jump-out point with a vertical tangent,
``P - P_js ~ sqrt(delta - delta_min)``; nodes graded as ``(j/N)^4`` towards it restore ``N^-2``
(:func:`piecewise_linear_error`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, Sequence

import numpy as np
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError
from probedyn.fem.model import ElasticModel, PointMass, Spring

from .probe import PlacingProbe

End = Literal["grounded", "hanging"]
Form = Literal["corrected", "printed"]
ENDS = ("grounded", "hanging")

#: clamped-pinned roots tan x = tanh x (K -> infinity limit)
CLAMPED_PINNED = (3.926602312047919, 7.0685827456954875, 10.210176122813031, 13.351768777756622)


# ------------------------------------------------------------------------------------------
# Frequency equation (4.38) with the corrected beta (4.37)
# ------------------------------------------------------------------------------------------


def end_stiffness(x: float, K: float, mu: float, end: End = "grounded", form: Form = "corrected") -> float:
    """``beta L^3`` of the end condition ``EI U''' = beta EI U`` at ``x = bL``.

    grounded: ``K - mu x^4`` (corrected) or ``K + mu x^4`` (printed 4.37);
    hanging: ``-mu x^4 K / (K - mu x^4)`` (infinite at the contact resonance)."""
    if end == "grounded":
        return K - mu * x**4 if form == "corrected" else K + mu * x**4
    if end == "hanging":
        if form != "corrected":
            raise ParameterError("the printed form exists for the grounded end only")
        if K == math.inf:
            return -mu * x**4
        return -mu * x**4 * K / (K - mu * x**4)
    raise ParameterError(f"unknown end condition {end!r} (grounded, hanging)")


def frequency_function(x, K: float, mu: float, end: End = "grounded", form: Form = "corrected"):
    """(4.38) divided by ``cosh x`` (and, for the hanging end, multiplied by ``K - mu x^4`` so it
    has no pole): a smooth function whose positive roots are ``b_n L``. Vectorised in ``x``."""
    x = np.asarray(x, dtype=float)
    c, s = np.cos(x), np.sin(x)
    th = np.tanh(x)
    lhs = x**3 * (1.0 / np.cosh(np.minimum(x, 700.0)) + c)
    g = c * th - s
    if end == "hanging":
        if K == math.inf:
            return lhs + mu * x**4 * g
        return lhs * (K - mu * x**4) + mu * x**4 * K * g
    if K == math.inf:  # clamped-pinned: divide by K
        return -g
    if end != "grounded":
        raise ParameterError(f"unknown end condition {end!r} (grounded, hanging)")
    beta = K - mu * x**4 if form == "corrected" else K + mu * x**4
    if form not in ("corrected", "printed"):
        raise ParameterError(f"unknown form {form!r} (corrected, printed)")
    return lhs - beta * g


def capture_roots(K: float, mu: float, n: int = 3, end: End = "grounded", form: Form = "corrected") -> np.ndarray:
    """First ``n`` positive roots ``b_n L`` of (4.38): the function on a grid (logarithmic below
    1e-3, step 0.005 above; consecutive roots are at least ~0.3 apart in every case here),
    then Brent's method on the first ``n`` sign changes."""
    if not (K >= 0 and mu >= 0) or math.isnan(K) or math.isnan(mu):
        raise ParameterError(f"capture: K = k1 L^3/EI and mu = M/(rho A L) must be >= 0 (got {K}, {mu})")
    if end not in ENDS:
        raise ParameterError(f"unknown end condition {end!r} (grounded, hanging)")
    f = lambda x: float(frequency_function(x, K, mu, end, form))  # noqa: E731
    x_hi = (n + 2.5) * math.pi + (2.0 if end == "hanging" else 0.0) * math.pi
    grid = np.concatenate([np.geomspace(1e-6, 1e-3, 200), np.arange(1e-3 + 0.005, x_hi, 0.005)])
    v = frequency_function(grid, K, mu, end, form)
    idx = np.nonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)[0]
    roots = [float(grid[i]) for i in np.nonzero(v == 0.0)[0]]
    for i in idx:
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15))
    roots = sorted(roots)
    if len(roots) < n:
        raise SolverError(f"capture: only {len(roots)} of {n} roots found (K={K:g}, mu={mu:g})")
    return np.asarray(roots[:n])


def mode_shape(x: np.ndarray, bL: float, L: float) -> np.ndarray:
    """(4.40): ``cos bx - cosh bx - sigma (sin bx - sinh bx)``, ``sigma = (cos bL + cosh bL)/(sin bL + sinh bL)``,
    evaluated without ``cosh - sinh`` cancellation (as :func:`probedyn.lumped.beam.eb_mode_shape`)."""
    x = np.asarray(x, dtype=float)
    b = bL / L
    sig = (math.cos(bL) + math.cosh(bL)) / (math.sin(bL) + math.sinh(bL))
    bx = b * x
    hyp = 0.5 * ((1.0 - sig) * np.exp(bx) + (1.0 + sig) * np.exp(-bx))  # cosh - sig sinh
    return (np.cos(bx) - sig * np.sin(bx)) - hyp


# ------------------------------------------------------------------------------------------
# The capture model on a probe
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Capture:
    """Cantilever (``L``, ``EI``, ``rho A``) with a sample ``M`` on a contact spring ``k1`` at the
    end (``end``: grounded or hanging); ``zeta`` the modal damping ratio for (4.41)."""

    L: float
    EI: float
    rhoA: float
    k1: float
    M: float
    end: str = "grounded"
    zeta: float = 0.0

    def __post_init__(self) -> None:
        for name in ("L", "EI", "rhoA"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"capture: {name} must be positive, got {v}")
        if not (self.k1 >= 0 and self.M >= 0) or math.isnan(self.k1) or math.isnan(self.M):
            raise ParameterError(f"capture: k1 and M must be >= 0 (got {self.k1}, {self.M})")
        if self.end not in ENDS:
            raise ParameterError(f"unknown end condition {self.end!r} (grounded, hanging)")

    @classmethod
    def from_probe(cls, probe: PlacingProbe, k1: float, M: float, end: End = "grounded") -> "Capture":
        return cls(probe.L, probe.EI, probe.rhoA, float(k1), float(M), end, probe.zeta)

    @property
    def K(self) -> float:
        """``k1 L^3 / EI`` (= 3 k1 / k for a uniform beam)."""
        return self.k1 * self.L**3 / self.EI

    @property
    def mu(self) -> float:
        """``M / (rho A L)``."""
        return self.M / (self.rhoA * self.L)

    @property
    def omega_scale(self) -> float:
        return math.sqrt(self.EI / (self.rhoA * self.L**4))

    def roots(self, n: int = 3, form: Form = "corrected") -> np.ndarray:
        return capture_roots(self.K, self.mu, n, self.end, form)

    def frequencies(self, n: int = 3, form: Form = "corrected") -> np.ndarray:
        """Natural frequencies [rad/s] ``(b_n L)^2 sqrt(EI / (rho A L^4))``."""
        return self.roots(n, form) ** 2 * self.omega_scale

    def betas(self, n: int = 3) -> np.ndarray:
        """``beta_n L^3`` of each mode (corrected 4.37; grounded end)."""
        x = self.roots(n)
        return np.array([end_stiffness(float(v), self.K, self.mu, self.end) for v in x])

    def shapes(self, x: np.ndarray, n: int = 3) -> np.ndarray:
        """(n, len(x)) mode shapes (4.40) normalised to ``max |psi| = 1`` with ``psi > 0`` at the
        point of largest deflection."""
        out = []
        for bL in self.roots(n):
            psi = mode_shape(x, float(bL), self.L)
            i = int(np.argmax(np.abs(psi)))
            out.append(psi / psi[i])
        return np.asarray(out)

    def mass_normalised(self, n: int = 3, n_gauss: int = 400) -> list[dict[str, Any]]:
        """Modes normalised to ``int rho A psi^2 + M_end Y^2 = 1`` (grounded: the mass moves with
        the tip, ``Y = psi(L)``; hanging: ``Y = k1 psi(L) / (k1 - M omega^2)``)."""
        xg, wg = np.polynomial.legendre.leggauss(n_gauss)
        xs = 0.5 * self.L * (xg + 1.0)
        ws = 0.5 * self.L * wg
        res = []
        for bL in self.roots(n):
            om = bL**2 * self.omega_scale
            psi = mode_shape(xs, float(bL), self.L)
            tip = float(mode_shape(np.array([self.L]), float(bL), self.L)[0])
            if self.end == "grounded":
                Y = tip
            else:
                Y = self.k1 * tip / (self.k1 - self.M * om**2) if self.k1 > 0 else 0.0
            norm = math.sqrt(self.rhoA * float(np.sum(ws * psi**2)) + self.M * Y**2)
            res.append({"bL": float(bL), "omega": float(om), "tip": tip / norm, "sample": Y / norm,
                        "scale": 1.0 / norm})
        return res

    def forced_response(self, x: np.ndarray, omega, F0: float = 1.0, n: int = 6) -> np.ndarray:
        """(4.41): complex amplitude ``u(x)`` [m] for a force ``F0`` at the tip, ``n`` modes,
        modal damping ``zeta``. Shape (len(omega), len(x))."""
        x = np.asarray(x, dtype=float)
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        out = np.zeros((w.size, x.size), dtype=complex)
        for md in self.mass_normalised(n):
            psi_x = mode_shape(x, md["bL"], self.L) * md["scale"]
            den = md["omega"] ** 2 - w**2 + 2j * self.zeta * md["omega"] * w
            out += (F0 * md["tip"] / den)[:, None] * psi_x[None, :]
        return out


# ------------------------------------------------------------------------------------------
# FEM of the same beam with a point mass and a grounded spring at the tip
# ------------------------------------------------------------------------------------------


def _with_attachments(model, point_masses, springs):
    regions = {n: (m, R) for n, m, R in zip(model.region_names, model.materials, model.orientations)}
    return ElasticModel(model.bundle, regions, clamp=model.clamp, point_masses=point_masses, springs=springs,
                        tip=model.tip, beam_axis=model.beam_axis, name=f"{model.name}+sample")


def fem_capture_frequencies(model, k1: float, M: float, n: int = 3, face: str = "free_end",
                            mass_scale: float = 1.0) -> dict[str, Any]:
    """Flapwise frequencies [rad/s] and centre-line shapes of the FE model with a point mass ``M``
    and a grounded spring ``k1`` (along z) on the free-end face (face-averaged attachment, no
    rotary inertia: the beam's end condition). ``mass_scale`` multiplies ``M`` (to compare with
    a probe whose masses were rescaled: pass the probe's ``mass_scale``)."""
    pm = [PointMass(face, float(M) / mass_scale)] if M > 0 else []
    sp = [Spring(face, None, float(k1), (0.0, 0.0, 1.0))] if k1 > 0 else []
    fm = _with_attachments(model, pm, sp)
    res = fm.modes(2 * n + 3)
    flap = [md for md in res.modes if md.family == "flapwise"][:n]
    if len(flap) < n:
        raise SolverError(f"FEM capture: only {len(flap)} flapwise modes among {len(res.modes)}")
    x, shapes = centreline_shapes(fm, [md.shape for md in flap])
    return {"omega": np.array([md.omega / math.sqrt(mass_scale) for md in flap]), "x": x, "shapes": shapes,
            "dofs": fm.dofs}


def centreline_shapes(model, shapes: Sequence[np.ndarray], n_bins: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Cross-section-averaged z-displacement of FE mode shapes against x (nodes binned in x),
    each normalised to ``max |w| = 1`` with the largest deflection positive."""
    pos = model.basis.doflocs  # (3, N)
    xs = pos[0]
    L = float(xs.max() - xs.min())
    nb = n_bins or max(20, int(round(L / (np.ptp(pos[2]) or L) )))
    nb = min(nb, 200)
    edges = np.linspace(xs.min(), xs.max() + 1e-12 * L, nb + 1)
    idx = np.clip(np.digitize(xs, edges) - 1, 0, nb - 1)
    cnt = np.bincount(idx, minlength=nb)
    xc = np.bincount(idx, weights=xs, minlength=nb) / np.maximum(cnt, 1)
    out = []
    for phi in shapes:
        uz = np.asarray(phi).reshape(-1, 3)[:, 2]
        wz = np.bincount(idx, weights=uz, minlength=nb) / np.maximum(cnt, 1)
        i = int(np.argmax(np.abs(wz)))
        out.append(wz / wz[i])
    keep = cnt > 0
    return xc[keep], np.asarray(out)[:, keep]


def capture_check(probe: PlacingProbe, cases: Sequence[tuple[float, float]], n: int = 3,
                  end: End = "grounded") -> list[dict[str, Any]]:
    """Frequency equation vs FEM for ``(K, mu)`` cases (``K = k1 L^3/EI``, ``mu = M/(rho A L)``)
    on the probe's FE model: relative differences of the first ``n`` flapwise frequencies."""
    if probe.model is None:
        raise ParameterError("capture check needs a probe built from a FE model (PlacingProbe.from_fem)")
    if end != "grounded":
        raise ParameterError("the FEM check uses a grounded spring (end='grounded')")
    scale = float(probe.provenance.get("mass_scale", 1.0))
    rows = []
    for K, mu in cases:
        k1 = K * probe.EI / probe.L**3
        M = mu * probe.rhoA * probe.L
        cap = Capture.from_probe(probe, k1, M, end)
        an = cap.frequencies(n)
        fem = fem_capture_frequencies(probe.model, k1, M, n, mass_scale=scale)
        for i in range(n):
            rows.append({"K": K, "mu": mu, "mode": i + 1, "bL": float(cap.roots(n)[i]),
                         "beta_L3": float(end_stiffness(float(cap.roots(n)[i]), K, mu, end)),
                         "omega_eq": float(an[i]), "omega_fem": float(fem["omega"][i]),
                         "rel_diff": float(fem["omega"][i] / an[i] - 1.0)})
    return rows


# ------------------------------------------------------------------------------------------
# Maugis-Dugdale linearisation (4.28)-(4.29), Fig 4.18
# ------------------------------------------------------------------------------------------


def md_linearisation(contact, load: float = 0.0) -> dict[str, float]:
    """Operating point on the stable branch at ``load`` [N] (4.28: the contact load equals the
    probe's spring force ``k u_bar``) and the tangent ``I_c ~ k1 delta + k0`` (4.29)."""
    st = contact.at_load(float(load))
    k1 = float(st["stiffness"])
    d = float(st["penetration"])
    return {"load_n": float(load), "penetration_m": d, "contact_radius_m": float(st["radius"]),
            "k1_n_per_m": k1, "k0_n": float(load) - k1 * d, "pull_off_n": contact.pull_off_force()}


def _pl_reference(contact, delta_max: float | None, n_eval: int) -> tuple[float, float, np.ndarray, np.ndarray]:
    """The exact unloading branch on ``n_eval`` points from the jump-out point (dense near it)."""
    s = contact.scales
    d_min = float(contact._table()["D_min"]) * s.d_unit
    if delta_max is None:
        delta_max = float(contact.at_load(-3.0 * contact.pull_off_force())["penetration"])
    if not delta_max > d_min:
        raise ParameterError("delta_max must exceed the jump-out penetration")
    ue = np.linspace(0.0, 1.0, n_eval)
    de = d_min + (delta_max - d_min) * ue**4
    Pe = contact.force(de + np.r_[1e-12 * s.d_unit, np.zeros(n_eval - 1)], "unloading")
    return d_min, float(delta_max), de, np.asarray(Pe, float)


def piecewise_linear_error(contact, n_segments: int, spacing: str = "uniform", delta_max: float | None = None,
                           n_eval: int = 2001, reference=None) -> dict[str, Any]:
    """Piecewise-linear interpolation (4.29 on ``n_segments`` pieces) of the unloading (stable)
    branch from the jump-out point ``delta_min`` to ``delta_max`` (default: the penetration at a
    load of ``+3 |pull-off|``); errors against the exact MD force on ``n_eval`` points (or a
    precomputed ``reference`` from :func:`_pl_reference`).

    ``spacing="uniform"``: nodes uniform in delta; ``"graded"``: ``delta - delta_min ~ (j/N)^4``,
    the grading that restores the second order against the square-root end (a segment of
    length ``d`` next to ``x^(1/2)`` has the error ``~ d^(1/2)``, one at ``x`` has ``d^2 x^(-3/2)``;
    with ``x_j = (j/N)^q`` both are ``O(N^-2)`` for ``q >= 4``)."""
    if int(n_segments) < 1:
        raise ParameterError(f"n_segments must be >= 1, got {n_segments}")
    if spacing not in ("uniform", "graded"):
        raise ParameterError(f"spacing must be 'uniform' or 'graded', got {spacing!r}")
    d_min, delta_max, de, Pe = reference if reference is not None else _pl_reference(contact, delta_max, n_eval)
    s = contact.scales
    u = np.linspace(0.0, 1.0, int(n_segments) + 1)
    nodes = d_min + (delta_max - d_min) * (u if spacing == "uniform" else u**4)
    Pn = np.asarray(contact.force(nodes + np.r_[1e-12 * s.d_unit, np.zeros(len(nodes) - 1)], "unloading"), float)
    # exact values at the evaluation points, with the nodes merged in (the interpolant is exact there)
    Pl = np.interp(de, nodes, Pn)
    err = np.abs(Pl - Pe)
    w = np.gradient(de)
    return {"n_segments": int(n_segments), "spacing": spacing, "nodes_m": nodes, "node_forces_n": Pn,
            "delta_m": de, "force_n": Pe, "force_pl_n": Pl,
            "max_error_n": float(err.max()), "rms_error_n": float(math.sqrt(np.sum(err**2 * w) / np.sum(w))),
            "max_error_rel": float(err.max() / abs(contact.pull_off_force()))}


def convergence_order(ns: Sequence[int], errors: Sequence[float]) -> float:
    """Least-squares slope of ``log error`` against ``log n`` (observed order, negated)."""
    a = np.polyfit(np.log(np.asarray(ns, float)), np.log(np.asarray(errors, float)), 1)
    return float(-a[0])


__all__ = ["Capture", "capture_roots", "frequency_function", "end_stiffness", "mode_shape",
           "fem_capture_frequencies", "capture_check", "centreline_shapes", "md_linearisation",
           "piecewise_linear_error", "_pl_reference", "convergence_order", "CLAMPED_PINNED", "ENDS"]
