"""Several samples on one probe: Rayleigh-Ritz, eqs 4.45-4.55, Figs 4.24-4.26, SOURCE-NOTES 7, 11.

Rayleigh-Ritz (4.45)-(4.51). With ``z(x) = sum_i a_i psi_i(x)`` the stiffness and mass matrices
of the cantilever (``EI``, ``rho S``, ``L``) carrying samples ``M_k`` at ``l_k`` are::

    K_ij = EI int_0^L psi_i'' psi_j'' dx,
    M_ij = rho S int_0^L psi_i psi_j dx + sum_k M_k psi_i(l_k) psi_j(l_k)        (4.51 with S: SOURCE-NOTES 7)

and ``det(K - omega^2 M) = 0`` (4.49). Two bases:

* :class:`PolynomialRitz`: ``psi_i = xi^2 P_{i-1}(2 xi - 1)``, ``xi = x/L``, ``i = 1..n`` (``P`` the
  Legendre polynomials): the span of ``x^2 .. x^{n+1}``, admissible for the clamp
  (``psi(0) = psi'(0) = 0``), well conditioned for large ``n``. For ``n = 2`` it spans the
  source's ``x^2, x^3`` and gives the same frequencies as the printed matrices (4.54)-(4.55)
  (:func:`printed_matrices`, tests).
* the FEM mode basis: :class:`probedyn.lumped.ritz.RitzBasis` (the probe's FEM modes, plus
  static correction shapes at the sample positions if requested); masses enter as low-rank
  updates of the reduced matrices.

Reference: :func:`exact_frequencies`, the exact Euler-Bernoulli solution with point masses by
transfer matrices (``EI w'''' = rho S omega^2 w`` on each segment; a mass's inertia load
``M omega^2 w delta(x - l)`` makes the shear jump by ``[EI w'''] = M omega^2 w``, so that at the tip
``EI w'''(L) = -M omega^2 w(L)``, the sign of SOURCE-NOTES 4), and the 3D FEM with point masses (full re-solve).

Inverse problem (4.52, SOURCE-NOTES 11). The measured data are the relative frequency shifts
``f_n / f_n0 - 1`` of the first modes. :func:`identifiability` gives, for each set of unknowns
among ``l_1, l_2, M_1, M_2`` and each number of measured modes, the rank and conditioning of the
Jacobian (analytic, from eigenvalue perturbation: ``d lambda_n / d M_k = -lambda_n (psi_k^T v_n)^2``,
``d lambda_n / d l_k = -2 lambda_n M_k (psi_k^T v_n)(psi_k'^T v_n)``) and the standard deviations
of the unknowns per unit relative frequency noise. One frequency can never fix two unknowns;
two equal masses are interchangeable (their positions are determined up to a swap).
:func:`solve_inverse` solves one case by least squares from several starts, with the
Gauss-Newton covariance.

Selective release (Figs 4.25-4.26). Each sample is released when its contact carries more than
the pull-off force (:func:`.release.threshold_amplitude`, confirmed by the release simulation);
its local motion is the forced response of the loaded probe at its position (modal
superposition, base excitation ``Y0`` of the clamp or a force ``F0`` at the tip).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np
import scipy.linalg as sla
from scipy.linalg import expm
from scipy.optimize import brentq, least_squares

from probedyn.core.errors import ParameterError, SolverError

from probedyn.fem.model import PointMass
from probedyn.lumped.ritz import RitzBasis

from .capture import _with_attachments
from .probe import TABLE, PlacingProbe, flapwise_indices, sample_point
from .release import placing_contact, threshold_amplitude


def _check_masses(masses: Sequence[tuple[float, float]], L: float) -> list[tuple[float, float]]:
    out = []
    for item in masses:
        try:
            l, M = (float(v) for v in item)
        except (TypeError, ValueError):
            raise ParameterError(f"a sample is (position, mass), got {item!r}") from None
        if not (0 < l <= L * (1 + 1e-12)):
            raise ParameterError(f"sample position {l:.4g} m must lie in (0, L = {L:.4g} m]")
        if not (math.isfinite(M) and M >= 0):
            raise ParameterError(f"sample mass must be >= 0, got {M}")
        out.append((min(l, L), M))
    return out


# ------------------------------------------------------------------------------------------
# Polynomial Rayleigh-Ritz
# ------------------------------------------------------------------------------------------


_BASE_CACHE: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


@dataclass(frozen=True)
class PolynomialRitz:
    """Rayleigh-Ritz with ``n`` polynomial shape functions on a uniform cantilever."""

    L: float
    EI: float
    rhoS: float
    n: int

    def __post_init__(self) -> None:
        if int(self.n) != self.n or self.n < 1:
            raise ParameterError(f"number of shape functions must be a positive integer, got {self.n}")
        for name in ("L", "EI", "rhoS"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"Rayleigh-Ritz: {name} must be positive, got {v}")

    @classmethod
    def from_probe(cls, probe: PlacingProbe, n: int) -> "PolynomialRitz":
        return cls(probe.L, probe.EI, probe.rhoA, int(n))

    def psi(self, xi, d: int = 0) -> np.ndarray:
        """(n, len(xi)) ``d``-th derivative (0..3) with respect to ``xi`` of the shape functions
        ``xi^2 P_{i-1}(t)``, ``t = 2 xi - 1``; Legendre values and derivatives by the three-term
        recurrences ``(k+1) P_{k+1} = (2k+1) t P_k - k P_{k-1}``,
        ``P^(j)_{k+1} = P^(j)_{k-1} + (2k+1) P^(j-1)_k``."""
        if d not in (0, 1, 2, 3):
            raise ParameterError("derivative order must be 0..3")
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        t = 2.0 * xi - 1.0
        n = self.n
        P = np.zeros((4, n + 1, xi.size))  # P[j, k] = d^j P_k / dt^j
        P[0, 0] = 1.0
        if n >= 1:
            P[0, 1] = t
            P[1, 1] = 1.0
        for k in range(1, n):
            P[0, k + 1] = ((2 * k + 1) * t * P[0, k] - k * P[0, k - 1]) / (k + 1)
            for j in (1, 2, 3):
                P[j, k + 1] = P[j, k - 1] + (2 * k + 1) * P[j - 1, k]
        # derivatives with respect to xi: d/dxi = 2 d/dt
        L0, L1, L2, L3 = P[0, :n], 2.0 * P[1, :n], 4.0 * P[2, :n], 8.0 * P[3, :n]
        if d == 0:
            return xi**2 * L0
        if d == 1:
            return 2 * xi * L0 + xi**2 * L1
        if d == 2:
            return 2 * L0 + 4 * xi * L1 + xi**2 * L2
        return 6 * L1 + 6 * xi * L2 + xi**2 * L3

    def base_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``K``, ``M`` of the bare beam (Gauss-Legendre, exact for these polynomials; cached)."""
        key = (self.L, self.EI, self.rhoS, self.n)
        if key not in _BASE_CACHE:
            xg, wg = np.polynomial.legendre.leggauss(self.n + 4)
            xi = 0.5 * (xg + 1.0)
            w = 0.5 * wg
            P0 = self.psi(xi, 0)
            P2 = self.psi(xi, 2)
            K = self.EI / self.L**3 * (P2 * w) @ P2.T
            M = self.rhoS * self.L * (P0 * w) @ P0.T
            if len(_BASE_CACHE) > 64:
                _BASE_CACHE.clear()
            _BASE_CACHE[key] = (K, M)
        K, M = _BASE_CACHE[key]
        return K.copy(), M.copy()

    def matrices(self, masses: Sequence[tuple[float, float]] = ()) -> tuple[np.ndarray, np.ndarray]:
        """(4.50)-(4.51) with the samples ``[(l_k, M_k)]``."""
        K, M = self.base_matrices()
        for l, m in _check_masses(masses, self.L):
            p = self.psi([l / self.L], 0)[:, 0]
            M = M + m * np.outer(p, p)
        return K, M

    def solve(self, masses: Sequence[tuple[float, float]] = (), n_modes: int | None = None) -> dict[str, np.ndarray]:
        """Frequencies [rad/s] and mass-normalised coefficient vectors (columns)."""
        K, M = self.matrices(masses)
        try:
            w2, V = sla.eigh(K, M)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"Rayleigh-Ritz eigenproblem failed: {exc}") from None
        k = self.n if n_modes is None else min(int(n_modes), self.n)
        return {"omega": np.sqrt(np.maximum(w2[:k], 0.0)), "V": V[:, :k], "K": K, "M": M}

    def shape(self, V: np.ndarray, x) -> np.ndarray:
        """Deflection ``(len(x), k)`` of coefficient vectors ``V`` at positions ``x`` [m]."""
        return self.psi(np.asarray(x, float) / self.L, 0).T @ V


def printed_matrices(EI: float, rhoS: float, L: float, masses: Sequence[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """(4.54)-(4.55) as printed: shape functions ``x^2``, ``x^3`` (dimensional)."""
    ms = _check_masses(masses, L)
    M = np.array([[rhoS * L**5 / 5, rhoS * L**6 / 6], [rhoS * L**6 / 6, rhoS * L**7 / 7]], float)
    for l, m in ms:
        M += m * np.array([[l**4, l**5], [l**5, l**6]])
    K = np.array([[4 * EI * L, 6 * EI * L**2], [6 * EI * L**2, 12 * EI * L**3]], float)
    return K, M


def matrices_frequencies(K: np.ndarray, M: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum(sla.eigh(K, M, eigvals_only=True), 0.0))


# ------------------------------------------------------------------------------------------
# Exact Euler-Bernoulli reference (transfer matrices)
# ------------------------------------------------------------------------------------------


def _field(b4L4: float, s: float) -> np.ndarray:
    """Transfer matrix of a uniform segment of non-dimensional length ``s`` for the state
    ``[w, w', w'', w''']`` (lengths in L, ``w'''' = (bL)^4 w``)."""
    A = np.zeros((4, 4))
    A[0, 1] = A[1, 2] = A[2, 3] = 1.0
    A[3, 0] = b4L4
    return expm(A * s)


def exact_determinant(bL: float, masses_nd: Sequence[tuple[float, float]]) -> float:
    """Boundary determinant of the clamped-free beam with point masses (``xi_k``, ``mu_k = M_k/(rho S L)``):
    at ``xi_k`` the shear jumps, ``[w'''] = mu_k (bL)^4 w`` (the mass's inertia load)."""
    b4 = bL**4
    T = np.eye(4)
    xi0 = 0.0
    for xi, mu in sorted(masses_nd):
        T = _field(b4, xi - xi0) @ T
        J = np.eye(4)
        J[3, 0] = mu * b4
        T = J @ T
        xi0 = xi
    T = _field(b4, 1.0 - xi0) @ T
    # clamped: w = w' = 0; unknowns w''(0), w'''(0); free: w''(1) = w'''(1) = 0
    m = T[2:4, 2:4]
    m = m / np.abs(m).max(axis=1, keepdims=True)
    return float(np.linalg.det(m))


def exact_frequencies(L: float, EI: float, rhoS: float, masses: Sequence[tuple[float, float]], n: int = 4) -> np.ndarray:
    """First ``n`` natural frequencies [rad/s] of the Euler-Bernoulli cantilever with point
    masses, by transfer matrices (independent of the Rayleigh-Ritz algebra)."""
    ms = _check_masses(masses, L)
    nd = [(l / L, m / (rhoS * L)) for l, m in ms]
    f = lambda x: exact_determinant(x, nd)  # noqa: E731
    roots = []
    grid = np.arange(0.05, 4.0 * (n + 2), 0.01)
    fa = f(grid[0])
    for xa, xb in zip(grid[:-1], grid[1:]):
        fb = f(xb)
        if fa * fb < 0:
            roots.append(brentq(f, xa, xb, xtol=1e-14, rtol=1e-14))
            if len(roots) == n:
                break
        fa = fb
    if len(roots) < n:
        raise SolverError(f"exact beam: found {len(roots)} of {n} roots")
    return np.asarray(roots) ** 2 * math.sqrt(EI / (rhoS * L**4))


# ------------------------------------------------------------------------------------------
# FEM references: full re-solve and the FEM-mode Ritz basis
# ------------------------------------------------------------------------------------------


def fem_frequencies(model, masses: Sequence[tuple[float, float]], n: int = 4, mass_scale: float = 1.0) -> np.ndarray:
    """Flapwise frequencies [rad/s] of the FE model with point masses at the centroid line
    (full re-solve). ``mass_scale``: the probe's mass factor (``mass_source="table"``)."""
    pms = [PointMass(sample_point(model, l), m / mass_scale) for l, m in masses if m > 0]
    fm = _with_attachments(model, pms, [])
    res = fm.modes(2 * n + 3)
    flap = [md.omega for md in res.modes if md.family == "flapwise"][:n]
    if len(flap) < n:
        raise SolverError(f"FEM: only {len(flap)} flapwise modes found")
    return np.asarray(flap) / math.sqrt(mass_scale)


def ritz_basis(model, n_modes: int, positions: Sequence[float] = (), static: bool = False):
    """The FEM-mode Ritz basis of ``model`` (issue 10's :class:`probedyn.lumped.ritz.RitzBasis`):
    ``n_modes`` FEM modes, plus static correction shapes (z) at the sample ``positions`` if
    ``static``."""
    att = [(sample_point(model, l), "z") for l in positions] if static else []
    return RitzBasis.from_model(model, int(n_modes), attachments=att)


def ritz_flapwise(basis, masses: Sequence[tuple[float, float]], n: int = 4, model=None) -> np.ndarray:
    """Flapwise frequencies [rad/s] of the FEM-mode Ritz model with point masses."""
    mdl = model if model is not None else basis.model
    pms = [(sample_point(mdl, l), m) for l, m in masses if m > 0]
    sol = basis.solve(point_masses=pms)
    flap = flapwise_indices(sol, mdl)
    if len(flap) < n:
        raise SolverError(f"Ritz: only {len(flap)} flapwise modes in a basis of {basis.r}")
    return sol.omega[flap[:n]]


# ------------------------------------------------------------------------------------------
# Inverse problem and identifiability (SOURCE-NOTES 11)
# ------------------------------------------------------------------------------------------

UNKNOWN_SETS = (("M1",), ("l1",), ("M1", "M2"), ("l1", "l2"), ("l1", "M1"), ("l1", "l2", "M1"),
                ("l1", "l2", "M1", "M2"))


def _shifts_and_jacobian(rr: PolynomialRitz, l: np.ndarray, M: np.ndarray, n_f: int):
    """Relative frequency shifts ``f_n/f_n0 - 1`` (n = 1..n_f) and their derivatives with respect
    to ``[l_1, l_2, M_1, M_2]`` (per metre and per kg)."""
    base = rr.solve(())["omega"][:n_f]
    sol = rr.solve(list(zip(l, M)))
    om = sol["omega"][:n_f]
    V = sol["V"][:, :n_f]
    lam = om**2
    y = om / base - 1.0
    J = np.zeros((n_f, 2 * len(l)))
    for k in range(len(l)):
        p = rr.psi([l[k] / rr.L], 0)[:, 0]
        dp = rr.psi([l[k] / rr.L], 1)[:, 0] / rr.L
        a = p @ V
        b = dp @ V
        dlam_dM = -lam * a**2
        dlam_dl = -2.0 * lam * M[k] * a * b
        # d(omega/omega0) = d lambda / (2 omega omega0)
        J[:, k] = dlam_dl / (2 * om * base)
        J[:, len(l) + k] = dlam_dM / (2 * om * base)
    return y, J


def identifiability(probe: PlacingProbe, l=(0.5, 1.0), M=None, n_modes_list=(1, 2, 3, 4), n_shape: int = 12,
                    unknown_sets=UNKNOWN_SETS, rank_tol: float = 1e-8) -> list[dict[str, Any]]:
    """Identifiability of ``unknown_sets`` from the first ``n`` measured frequencies (relative
    shifts) for two samples at ``l`` (fractions of L) with masses ``M`` [kg] (default Table 4.4's
    M1, M2). Per row: rank of the scaled Jacobian, its condition number, and the standard
    deviation of each unknown (relative: l/L and M/M_true) per unit relative frequency noise;
    ``identifiable`` = full column rank."""
    M = np.asarray([TABLE["M1"], TABLE["M2"]] if M is None else M, float)
    lpos = np.asarray(l, float) * probe.L
    rr = PolynomialRitz.from_probe(probe, n_shape)
    names = ["l1", "l2", "M1", "M2"]
    scale = np.concatenate([np.full(2, probe.L), M])  # parameters in units of L and of their true masses
    rows = []
    for nf in n_modes_list:
        y, J = _shifts_and_jacobian(rr, lpos, M, int(nf))
        Js = J * scale[None, :]
        for us in unknown_sets:
            cols = [names.index(u) for u in us]
            A = Js[:, cols]
            s = np.linalg.svd(A, compute_uv=False)
            smax = s[0] if s.size else 0.0
            rank = int(np.sum(s > rank_tol * max(smax, 1e-300))) if smax > 0 else 0
            ok = rank == len(cols) and A.shape[0] >= len(cols)
            sd = {}
            if ok:
                C = np.linalg.inv(A.T @ A)
                sd = {u: float(math.sqrt(C[i, i])) for i, u in enumerate(us)}
            rows.append({"unknowns": "+".join(us), "n_frequencies": int(nf), "rank": rank,
                         "identifiable": bool(ok), "condition": float(smax / s[-1]) if ok else math.inf,
                         "sd_per_unit_noise": sd,
                         "max_shift": float(np.max(np.abs(y)))})
    return rows


def solve_inverse(probe: PlacingProbe, measured: np.ndarray, unknowns: Sequence[str], known: dict[str, float],
                  sigma: float, n_shape: int = 12, starts: int = 12, seed: int = 0) -> dict[str, Any]:
    """Least-squares estimate of ``unknowns`` (subset of l1, l2 [m], M1, M2 [kg]) from measured
    relative frequency shifts ``measured`` (first modes, noise ``sigma`` each), from ``starts``
    starting points; returns every distinct minimum with its Gauss-Newton standard deviations."""
    names = ["l1", "l2", "M1", "M2"]
    for u in unknowns:
        if u not in names:
            raise ParameterError(f"unknown {u!r} is not one of {', '.join(names)}")
    missing = [n for n in names if n not in unknowns and n not in known]
    if missing:
        raise ParameterError(f"give the known values of {', '.join(missing)}")
    if len(measured) < len(unknowns):
        raise ParameterError(f"{len(measured)} frequencies cannot determine {len(unknowns)} unknowns")
    rr = PolynomialRitz.from_probe(probe, n_shape)
    nf = len(measured)
    Mref = max([known.get("M1", 0), known.get("M2", 0), float(TABLE["M1"])])
    scale = {"l1": probe.L, "l2": probe.L, "M1": Mref, "M2": Mref}
    rng = np.random.default_rng(seed)

    def full(p):
        v = dict(known)
        v.update({u: p[i] * scale[u] for i, u in enumerate(unknowns)})
        return np.array([v["l1"], v["l2"]]), np.array([v["M1"], v["M2"]])

    def resid(p):
        l, M = full(p)
        y, _ = _shifts_and_jacobian(rr, l, M, nf)
        return (y - measured) / sigma

    def jac(p):
        l, M = full(p)
        _, J = _shifts_and_jacobian(rr, l, M, nf)
        cols = [names.index(u) for u in unknowns]
        return J[:, cols] * np.array([scale[u] for u in unknowns])[None, :] / sigma

    lo = np.array([0.02 if u.startswith("l") else 0.0 for u in unknowns])
    hi = np.array([1.0 if u.startswith("l") else 100.0 for u in unknowns])
    sols = []
    for _ in range(int(starts)):
        p0 = lo + (hi - lo) * rng.uniform(0.05, 0.95, len(unknowns))
        if any(u.startswith("M") for u in unknowns):
            p0 = np.where([u.startswith("M") for u in unknowns], rng.uniform(0.2, 5.0, len(unknowns)), p0)
        r = least_squares(resid, p0, jac=jac, bounds=(lo, hi), xtol=1e-14, ftol=1e-14, gtol=1e-14)
        chi2 = float(np.sum(r.fun**2))
        try:
            C = np.linalg.inv(r.jac.T @ r.jac)
            sd = np.sqrt(np.diag(C))
        except np.linalg.LinAlgError:
            sd = np.full(len(unknowns), np.inf)
        est = {u: float(r.x[i] * scale[u]) for i, u in enumerate(unknowns)}
        err = {u: float(sd[i] * scale[u]) for i, u in enumerate(unknowns)}
        if not any(all(abs(est[u] - s["estimate"][u]) <= 1e-6 * scale[u] for u in unknowns) for s in sols):
            sols.append({"estimate": est, "sd": err, "chi2": chi2})
    sols.sort(key=lambda s: s["chi2"])
    acceptable = [s for s in sols if s["chi2"] <= sols[0]["chi2"] + max(len(measured), 1) * 4.0]
    # two samples of equal (known) mass are interchangeable: a solution and its swap are one
    swap_equal = ("l1" in unknowns and "l2" in unknowns and "M1" not in unknowns and "M2" not in unknowns
                  and abs(known.get("M1", 0) - known.get("M2", 0)) <= 1e-12 * max(known.get("M1", 0), 1e-300))
    distinct = []
    for s_ in acceptable:
        e = s_["estimate"]
        if swap_equal and any(abs(e["l1"] - d["estimate"]["l2"]) <= 1e-6 * probe.L
                              and abs(e["l2"] - d["estimate"]["l1"]) <= 1e-6 * probe.L for d in distinct):
            continue
        distinct.append(s_)
    return {"solutions": sols, "acceptable": acceptable, "distinct": distinct, "unique": len(distinct) == 1,
            "swap_symmetric": swap_equal}


# ------------------------------------------------------------------------------------------
# Selective release
# ------------------------------------------------------------------------------------------


def local_response(probe: PlacingProbe, masses: Sequence[tuple[float, float]], omega, drive: str = "base",
                   n_shape: int = 12, n_modes: int = 8) -> np.ndarray:
    """Complex amplitude of the absolute vertical motion at each sample (``(len(omega), n_samples)``)
    per unit drive: base excitation (per metre of clamp motion) or a tip force (per newton), by
    modal superposition of the loaded probe's Rayleigh-Ritz modes with damping ratio ``zeta``."""
    ms = _check_masses(masses, probe.L)
    if drive not in ("base", "tip"):
        raise ParameterError(f"drive must be 'base' or 'tip', got {drive!r}")
    rr = PolynomialRitz.from_probe(probe, n_shape)
    sol = rr.solve(ms)
    om, V = sol["omega"][:n_modes], sol["V"][:, :n_modes]
    w = np.atleast_1d(np.asarray(omega, float))
    xs = np.array([l for l, _ in ms])
    phi = rr.shape(V, xs)  # (n_samples, k)
    z = probe.zeta
    den = om[None, :] ** 2 - w[:, None] ** 2 + 2j * z * om[None, :] * w[:, None]  # (nw, k)
    if drive == "base":
        xg, wg = np.polynomial.legendre.leggauss(n_shape + 4)
        xi = 0.5 * (xg + 1)
        b = probe.rhoA * probe.L * (rr.psi(xi, 0) * (0.5 * wg)).sum(axis=1)
        for l, m in ms:
            b = b + m * rr.psi([l / probe.L], 0)[:, 0]
        gam = b @ V  # (k,)
        return 1.0 + (w[:, None] ** 2 * gam[None, :] / den) @ phi.T
    phiL = rr.shape(V, [probe.L])[0]
    return (phiL[None, :] / den) @ phi.T


def probe_at(probe: PlacingProbe, l: float, masses: Sequence[tuple[float, float]] = (), n_shape: int = 12,
             n_modes: int = 4) -> PlacingProbe:
    """The probe seen at the position ``l``: its Rayleigh-Ritz modes normalised at ``l``
    (modal mass ``1 / phi_n(l)^2``), for a release run of a sample sitting there."""
    rr = PolynomialRitz.from_probe(probe, n_shape)
    sol = rr.solve(masses)
    om, V = sol["omega"][:n_modes], sol["V"][:, :n_modes]
    ph = rr.shape(V, [l])[0]
    keep = np.abs(ph) > 1e-6 * np.max(np.abs(ph))
    mm = tuple(float(1.0 / ph[i] ** 2) for i in range(len(ph)) if keep[i])
    ws = tuple(float(om[i]) for i in range(len(ph)) if keep[i])
    K, _ = rr.matrices(masses)
    # static stiffness at l: 1 / (psi(l)^T K^-1 psi(l))
    p = rr.psi([l / probe.L], 0)[:, 0]
    k = float(1.0 / (p @ np.linalg.solve(K, p)))
    prov = dict(probe.provenance)
    prov["position_m"] = float(l)
    return replace(probe, k=k, omegas=ws, modal_masses=mm, provenance=prov)


def release_thresholds(probe: PlacingProbe, masses: Sequence[tuple[float, float]], omega, drive: str = "base",
                       F_po: float | None = None, k1: float | None = None, zeta_c: float = 0.1) -> np.ndarray:
    """Drive amplitude [m of base motion, or N of tip force] at which each sample's contact
    reaches the pull-off force (``(len(omega), n_samples)``): the local threshold
    (:func:`.release.threshold_amplitude`) over the local response per unit drive."""
    ms = _check_masses(masses, probe.L)
    if F_po is None or k1 is None:
        c = placing_contact()
        F_po = c.pull_off_force() if F_po is None else F_po
        k1 = float(c.at_load(0.0)["stiffness"]) if k1 is None else k1
    T = np.abs(local_response(probe, ms, omega, drive))
    w = np.atleast_1d(np.asarray(omega, float))
    A_th = np.stack([threshold_amplitude(m, w, F_po, k1, zeta_c) for _, m in ms], axis=1)
    with np.errstate(divide="ignore"):
        return A_th / T


__all__ = ["PolynomialRitz", "printed_matrices", "matrices_frequencies", "exact_frequencies", "fem_frequencies",
           "ritz_basis", "ritz_flapwise", "flapwise_indices", "identifiability", "solve_inverse", "local_response", "probe_at",
           "release_thresholds", "sample_point", "UNKNOWN_SETS"]
