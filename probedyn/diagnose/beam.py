"""Reduced 1D finite-element beam for the modal diagnosis (re-solves in about a millisecond).

The diagnosis refits a modal model hundreds of times (every candidate cause, every
cross-validation fold), so it does not re-mesh a 3D solid: it uses a 1D beam whose element
matrices are assembled once in non-dimensional form and then only *scaled and updated by
low-rank terms* for each candidate.

Families (rectangular section, length L, width w, thickness t, isotropic E, rho, nu):

* ``flap``    bending about the width axis, EI = E w t^3 / 12 (the usual AFM "vertical" modes);
* ``lateral`` in-plane bending, EI = E t w^3 / 12;
* ``torsion`` St-Venant torsion, G J with J = w t^3 [1/3 - 0.21 (t/w)(1 - (t/w)^4/12)] (Roark,
  w >= t) and polar inertia rho I_p, I_p = w t (w^2 + t^2) / 12.

Bending uses Hermite cubic Euler-Bernoulli elements (the distributed-parameter model of the
source's section 2.3, eqs 2.36-2.46; the clamped-free frequency equation 2.40 is the limit
case verified in the tests). Torsion uses linear elements with the average of the consistent
and lumped mass matrices, which makes the eigenvalue error O(h^4) instead of O(h^2).

Model extensions, all as element or boundary terms on the same matrices:

* root rotational and translational springs (non-dimensional kappa_r = k_r L / EI,
  kappa_t = k_t L^3 / EI) -- clamp / base compliance; kappa -> infinity is the clamp;
* a point mass mu = m / (rho A L) at xi = x / L, optional rotary inertia j = J / (rho A L^3);
  with xi = 1 this is the tip-mass problem of eq 3.10 in its *corrected* form
  (SOURCE-NOTES item 1), which the tests check;
* axial force p = P L^2 / EI (geometric stiffness, tension > 0);
* fluid loading through Sader's hydrodynamic function Gamma(omega) for a thin rectangular
  beam (J. E. Sader, J. Appl. Phys. 84, 64 (1998), eqs 17, 20-21, 25): added mass per length
  (pi/4) rho_f w^2 Gamma_r and damping (pi/4) rho_f w^2 omega Gamma_i on the flapwise family.

The fluid loading is frequency dependent; for each mode it is applied by a fixed-point
iteration on the Rayleigh quotient with the vacuum mode shape (exact for a uniform beam;
with a point mass the error is second order in the mode-shape change because the Rayleigh
quotient is stationary). Mode-specific quality factors follow from the same quotient:
1/Q_fluid = T Gamma_i m_b / (1 + T Gamma_r m_b), T = pi rho_f w / (4 rho t), m_b the share of the
modal mass carried by the beam. For a uniform beam this is Sader's eq 25,
Q = (4 rho t / (pi rho_f w) + Gamma_r) / Gamma_i.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.special import kve

from probedyn.core.errors import ParameterError

__all__ = ["BeamFE", "BeamProps", "sader_gamma", "torsion_constant", "solve_family"]


def torsion_constant(w: float, t: float) -> float:
    """St-Venant torsion constant of a w x t rectangle (Roark, accurate to ~0.5 % for w >= t)."""
    a, b = max(w, t), min(w, t)
    r = b / a
    return a * b**3 * (1.0 / 3.0 - 0.21 * r * (1.0 - r**4 / 12.0))


def _omega_rect(re: np.ndarray) -> np.ndarray:
    """Sader (1998) eq 21: correction Omega(Re) from a circular to a rectangular section."""
    tau = np.log10(re)
    num_r = (0.91324 - 0.48274 * tau + 0.46842 * tau**2 - 0.12886 * tau**3
             + 0.044055 * tau**4 - 0.0035117 * tau**5 + 0.00069085 * tau**6)
    den_r = (1 - 0.56964 * tau + 0.48690 * tau**2 - 0.13444 * tau**3
             + 0.045155 * tau**4 - 0.0035862 * tau**5 + 0.00069085 * tau**6)
    num_i = (-0.024134 - 0.029256 * tau + 0.016294 * tau**2 - 0.00010961 * tau**3
             + 0.000064577 * tau**4 - 0.000044510 * tau**5)
    den_i = (1 - 0.59702 * tau + 0.55182 * tau**2 - 0.18357 * tau**3
             + 0.079156 * tau**4 - 0.014369 * tau**5 + 0.0028361 * tau**6)
    return num_r / den_r + 1j * num_i / den_i


def sader_gamma(omega, width: float, rho_f: float, eta_f: float, circular: bool = False) -> np.ndarray:
    """Hydrodynamic function Gamma = Gamma_r - i Gamma_i of a thin rectangular beam.

    Re = rho_f omega w^2 / (4 eta_f); Gamma_circ (Sader eq 20) times Omega(Re) (eq 21, valid
    for 1e-6 <= Re <= 1e4; values outside are clipped to that range). Returned with
    *positive* imaginary part convention ``Gamma_r + 1j * Gamma_i`` where Gamma_i > 0 is the
    dissipative part. Limits checked in the tests: Gamma_r -> 1 for Re -> infinity
    (inviscid added mass pi/4 rho_f w^2 of a plate) and the circular-cylinder asymptote
    Gamma_circ ~ 1 + 2 sqrt(2) (1 + i) / sqrt(Re).
    """
    omega = np.asarray(omega, dtype=float)
    re = rho_f * omega * width**2 / (4.0 * eta_f)
    re = np.clip(re, 1e-6, 1e4) if not circular else re
    s = np.sqrt(1j * re)
    z = -1j * s
    gc = 1.0 + 4.0j * kve(1, z) / (s * kve(0, z))  # scaled Bessel: ratio unchanged, no overflow
    g = gc if circular else _omega_rect(re) * gc
    return g.real + 1j * np.abs(g.imag)


@dataclass
class BeamProps:
    """Geometry and material of a rectangular beam (SI)."""

    length: float
    width: float
    thickness: float
    E: float
    rho: float
    nu: float = 0.3

    def validate(self) -> None:
        for name in ("length", "width", "thickness", "E", "rho"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"beam '{name}' must be positive and finite, got {v}")
        if not (-1.0 < self.nu < 0.5):
            raise ParameterError(f"beam Poisson ratio nu must be in (-1, 0.5), got {self.nu}")

    @property
    def area(self) -> float:
        return self.width * self.thickness

    def EI(self, family: str) -> float:
        w, t = self.width, self.thickness
        return self.E * (w * t**3 if family == "flap" else t * w**3) / 12.0

    @property
    def GJ(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu)) * torsion_constant(self.width, self.thickness)

    @property
    def rhoIp(self) -> float:
        w, t = self.width, self.thickness
        return self.rho * w * t * (w**2 + t**2) / 12.0


class BeamFE:
    """Non-dimensional 1D FE matrices on x in [0, 1], assembled once (``n_el`` elements).

    ``bending(...)`` and ``torsion(...)`` return eigenvalues lambda = omega^2 rho A L^4 / EI
    (bending) or omega^2 rho I_p L^2 / (G J) (torsion); the caller scales to Hz.
    """

    def __init__(self, n_el: int = 40):
        if n_el < 2:
            raise ParameterError("the reduced beam needs at least 2 elements")
        self.n_el = n_el
        h = 1.0 / n_el
        self.h = h
        ke = np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                       [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]) / h**3
        me = np.array([[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                       [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]]) * h / 420
        ge = np.array([[36, 3 * h, -36, 3 * h], [3 * h, 4 * h * h, -3 * h, -h * h],
                       [-36, -3 * h, 36, -3 * h], [3 * h, -h * h, -3 * h, 4 * h * h]]) / (30 * h)
        nd = 2 * (n_el + 1)
        K = np.zeros((nd, nd)); M = np.zeros((nd, nd)); G = np.zeros((nd, nd))
        for e in range(n_el):
            sl = slice(2 * e, 2 * e + 4)
            K[sl, sl] += ke; M[sl, sl] += me; G[sl, sl] += ge
        self.K, self.M, self.G = K, M, G
        nt = n_el + 1
        kt = np.array([[1.0, -1.0], [-1.0, 1.0]]) / h
        mt = np.array([[5.0, 1.0], [1.0, 5.0]]) * h / 12.0  # (consistent + lumped) / 2
        Kt = np.zeros((nt, nt)); Mt = np.zeros((nt, nt))
        for e in range(n_el):
            Kt[e:e + 2, e:e + 2] += kt; Mt[e:e + 2, e:e + 2] += mt
        self.Kt, self.Mt = Kt[1:, 1:], Mt[1:, 1:]  # clamped root

    def shape_at(self, xi: float) -> tuple[np.ndarray, np.ndarray]:
        """Global Hermite interpolation vectors of w and dw/dx at x = xi (non-dimensional)."""
        xi = min(max(float(xi), 0.0), 1.0)
        e = min(int(xi / self.h), self.n_el - 1)
        s = (xi - e * self.h) / self.h
        h = self.h
        N = np.array([1 - 3 * s**2 + 2 * s**3, h * (s - 2 * s**2 + s**3), 3 * s**2 - 2 * s**3, h * (-s**2 + s**3)])
        dN = np.array([(-6 * s + 6 * s**2) / h, 1 - 4 * s + 3 * s**2, (6 * s - 6 * s**2) / h, -2 * s + 3 * s**2])
        nd = 2 * (self.n_el + 1)
        n = np.zeros(nd); dn = np.zeros(nd)
        n[2 * e:2 * e + 4] = N; dn[2 * e:2 * e + 4] = dN
        return n, dn

    def bending(self, n_modes: int, *, kappa_r: float = math.inf, kappa_t: float = math.inf,
                mu: float = 0.0, xi: float = 1.0, j_rot: float = 0.0, p: float = 0.0,
                vectors: bool = False, masses: tuple = ()):
        """Lowest ``n_modes`` non-dimensional eigenvalues (and mode shapes) of one bending family.

        ``masses`` adds further point masses as (mu, xi, j_rot) tuples.
        Returns ``lam`` (and, with ``vectors``, ``phi`` mass-normalised with respect to the full
        mass matrix plus ``m_beam`` = phi^T M_beam phi, the beam's share of each modal mass).
        """
        K = self.K + p * self.G if p else self.K.copy()
        Mb = self.M
        M = Mb.copy()
        for m_, x_, j_ in ((mu, xi, j_rot), *masses):
            if m_ or j_:
                n, dn = self.shape_at(x_)
                M += m_ * np.outer(n, n)
                if j_:
                    M += j_ * np.outer(dn, dn)
        keep = slice(0, None)
        if math.isinf(kappa_r) and math.isinf(kappa_t):
            keep = slice(2, None)
        else:
            if math.isinf(kappa_t) or math.isinf(kappa_r):
                # one infinite spring: constrain that dof only
                idx = [i for i in range(K.shape[0]) if not ((i == 0 and math.isinf(kappa_t)) or (i == 1 and math.isinf(kappa_r)))]
                keep = np.array(idx)
            if math.isfinite(kappa_t):
                K[0, 0] += kappa_t
            if math.isfinite(kappa_r):
                K[1, 1] += kappa_r
        if isinstance(keep, slice):
            Kk, Mk, Mbk = K[keep, keep], M[keep, keep], Mb[keep, keep]
        else:
            Kk, Mk, Mbk = K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], Mb[np.ix_(keep, keep)]
        nm = min(n_modes, Kk.shape[0])
        if not vectors:
            # full spectrum with the divide-and-conquer driver: the subset driver (gvx) loses
            # accuracy when stiff root springs make K ill-conditioned (tested)
            return sla.eigh(Kk, Mk, eigvals_only=True, driver="gvd")[:nm]
        lam, phi = sla.eigh(Kk, Mk, driver="gvd")
        lam, phi = lam[:nm], phi[:, :nm]
        mb = np.einsum("in,ij,jn->n", phi, Mbk, phi)
        return lam, phi, mb

    def torsion(self, n_modes: int) -> np.ndarray:
        nm = min(n_modes, self.Kt.shape[0])
        return sla.eigh(self.Kt, self.Mt, eigvals_only=True, driver="gvd")[:nm]


def solve_family(fe: BeamFE, props: BeamProps, family: str, n_modes: int, *,
                 k_rot: float = math.inf, k_trans: float = math.inf, mass: float = 0.0,
                 xi: float = 1.0, rot_inertia: float = 0.0, axial_force: float = 0.0,
                 extra_masses: tuple = (),
                 rho_f: float = 0.0, eta_f: float = 1.8e-5, E_bend: float | None = None,
                 iterations: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies [Hz] and fluid quality factors (inf without fluid) of one family.

    Physical inputs: root springs k_rot [N m/rad], k_trans [N/m]; point ``mass`` [kg] at
    ``xi`` = x/L with rotary inertia [kg m^2] (``extra_masses``: more (kg, xi) pairs); ``axial_force`` [N] (tension > 0); fluid density
    ``rho_f`` [kg/m^3] and viscosity ``eta_f`` [Pa s] (flapwise family only); ``E_bend`` the
    Young's modulus along the beam axis for bending (anisotropy), default ``props.E``.
    """
    L = props.length
    if family == "torsion":
        lam = fe.torsion(n_modes)
        f = np.sqrt(lam * props.GJ / (props.rhoIp * L**2)) / (2 * math.pi)
        return f, np.full_like(f, np.inf)
    if family not in ("flap", "lateral"):
        raise ParameterError(f"unknown mode family '{family}' (flap, lateral, torsion)")
    E = props.E if E_bend is None else E_bend
    EI = props.EI(family) * E / props.E
    rA = props.rho * props.area
    kr = k_rot * L / EI if math.isfinite(k_rot) else math.inf
    kt = k_trans * L**3 / EI if math.isfinite(k_trans) else math.inf
    mu = mass / (rA * L)
    j = rot_inertia / (rA * L**3)
    p = axial_force * L**2 / EI
    scale = EI / (rA * L**4)
    use_fluid = family == "flap" and rho_f > 0
    more = tuple((m_ / (rA * L), x_, 0.0) for m_, x_ in extra_masses)
    out = fe.bending(n_modes, kappa_r=kr, kappa_t=kt, mu=mu, xi=xi, j_rot=j, p=p, vectors=use_fluid, masses=more)
    if not use_fluid:
        lam = np.maximum(out, 0.0)
        return np.sqrt(lam * scale) / (2 * math.pi), np.full(len(lam), np.inf)
    lam, _phi, mb = out
    lam = np.maximum(lam, 0.0)
    T = math.pi * rho_f * props.width / (4.0 * props.rho * props.thickness)
    om_vac = np.sqrt(lam * scale)
    om = om_vac.copy()
    for _ in range(iterations):
        g = sader_gamma(om, props.width, rho_f, eta_f)
        om = om_vac / np.sqrt(1.0 + T * g.real * mb)
    g = sader_gamma(om, props.width, rho_f, eta_f)
    inv_q = T * g.imag * mb / (1.0 + T * g.real * mb)
    return om / (2 * math.pi), 1.0 / inv_q
