"""Prandtl–Tomlinson (PT) model of atomic stick-slip: a tip dragged by a spring over a
periodic substrate potential (Prandtl 1928, Tomlinson 1929; Socoliuc et al., PRL 92, 134301, 2004).

Not in the source's equations; it is the standard physical model in which the lattice period
*emerges* (issue 4, item 1). Conventions:

* 1D:  ``U(x) = -U0 cos(2 pi x / a)``; the substrate force on the tip is
  ``-dU/dx = -(2 pi U0 / a) sin(2 pi x / a)``, so the friction force (against the tip, the
  FFM sign convention of (2.13)) is ``F = (2 pi U0 / a) sin(2 pi x / a) + gamma V``.
  With a lateral spring ``k``: stick-slip iff ``eta = 4 pi^2 U0 / (k a^2) > 1`` (the total
  energy ``U(x) + k (X - x)^2 / 2`` then has more than one minimum for some base position X);
  for eta < 1 the tip slides smoothly with a continuous force.
* 2D square lattice: ``U = -U0 [cos(q x) + cos(q y)]``, ``q = 2 pi / a`` (same eta along each axis).
* 2D hexagonal (triangular) lattice of constant ``a``: ``U = -(2 U0 / 3) sum_i cos(b_i . r)``
  with ``|b_i| = 4 pi / (sqrt 3 a)`` at 30, 150, 270 degrees; the minima are the lattice
  sites ``n a1 + m a2``, ``a1 = (a, 0)``, ``a2 = (a/2, sqrt(3) a/2)``.
* Dynamics (2D): ``m r'' + gamma r' = k (R(t) - r) - grad U + xi(t)``, base
  ``R(t) = R0 + V t (cos theta, sin theta)``; optional thermal Langevin force with
  ``<xi_i(t) xi_j(t')> = 2 gamma k_B T delta_ij delta(t - t')``, integrated with the BAOAB
  splitting (Leimkuhler & Matthews 2013: exact Ornstein–Uhlenbeck step for friction + noise),
  with a fixed seed.

The 1D model is also the registry component ``pt`` (no internal state), so the FFM model
(2.13)–(2.15) can run with it: ``FFM(model="pt")``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.constants import k as K_B  # Boltzmann constant [J/K]
from numba import njit

from probedyn.core.errors import ParameterError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset

from .base import FRICTION_MODELS, TABLE_2_1, FrictionModel, positive_param


#: mica lattice constant (Table 4.2 of the source)
MICA_LATTICE = preset("table-4.2-mica")["a"]


@njit(cache=True)
def pt_kernel(p, x, v, z):
    """F = (2 pi U0/a) sin(2 pi x/a) + gamma v; p = (U0, a, gamma). No internal state."""
    U0, a, gam = p[0], p[1], p[2]
    q = 2.0 * math.pi / a
    F0 = q * U0
    return (F0 * math.sin(q * x) + gam * v, 0.0, F0 * q * math.cos(q * x), gam, 0.0, 0.0, 0.0, 0.0)


@FRICTION_MODELS.register
class PrandtlTomlinson(FrictionModel):
    key = "pt"
    title = "Prandtl-Tomlinson sinusoidal substrate potential (1D)"
    source = "U = -U0 cos(2 pi x / a) (not in the source; standard atomic stick-slip model)"
    n_state = 0
    params = ParamSet([
        positive_param("U0", 4.1e-21, "J", "corrugation amplitude (U = -U0 cos(2 pi x/a))", "PT model",
                       hi=1e-15),
        positive_param("a", MICA_LATTICE, "m", "lattice constant (default: mica, Table 4.2)", "Table 4.2",
                       lo=1e-11, hi=1e-6),
        Param("gamma", 0.0, "N s/m", "tip-substrate damping coefficient", lo=0.0, hi=1.0, source="PT model"),
    ])
    packed = ("U0", "a", "gamma")
    load_params = ("U0",)
    kernel = staticmethod(pt_kernel)

    def scales(self) -> tuple[float, float]:
        """Peak substrate force ``2 pi U0 / a``; no internal state (scale 1)."""
        return 2 * math.pi * self.values["U0"] / self.values["a"], 1.0

    def eta(self, k: float) -> float:
        """Tomlinson parameter ``4 pi^2 U0 / (k a^2)`` for a lateral spring ``k``."""
        return 4 * math.pi**2 * self.values["U0"] / (k * self.values["a"] ** 2)

    @classmethod
    def from_eta(cls, eta: float, k: float, a: float = MICA_LATTICE, gamma: float = 0.0) -> "PrandtlTomlinson":
        if not (eta > 0 and k > 0 and a > 0):
            raise ParameterError(f"PT needs eta > 0, k > 0, a > 0; got eta={eta}, k={k}, a={a}")
        return cls(U0=eta * k * a * a / (4 * math.pi**2), a=a, gamma=gamma)


# ------------------------------------------------------------------------------------------
# 2D PT with square / hexagonal lattices and thermal noise
# ------------------------------------------------------------------------------------------

LATTICES = ("line", "square", "hex")


@njit(cache=True)
def _grad_u(lat, U0, a, x, y):
    """Gradient of the substrate potential: lat 0 = line (1D in x), 1 = square, 2 = hex."""
    if lat == 0:
        q = 2.0 * math.pi / a
        return U0 * q * math.sin(q * x), 0.0
    if lat == 1:
        q = 2.0 * math.pi / a
        return U0 * q * math.sin(q * x), U0 * q * math.sin(q * y)
    b = 4.0 * math.pi / (math.sqrt(3.0) * a)
    gx = 0.0
    gy = 0.0
    for ang in (math.pi / 6.0, 5.0 * math.pi / 6.0, 1.5 * math.pi):
        bx = b * math.cos(ang)
        by = b * math.sin(ang)
        s = math.sin(bx * x + by * y)
        gx += bx * s
        gy += by * s
    c = 2.0 * U0 / 3.0
    return c * gx, c * gy


@njit(cache=True)
def _baoab(lat, U0, a, k, m, gam, kT, X0, Y0, Vx, Vy, x0, y0, dt, n_steps, every, seed):
    np.random.seed(seed)
    n_out = n_steps // every + 1
    out = np.empty((n_out, 5))  # t, x, y, Fx_spring, Fy_spring
    x, y, vx, vy = x0, y0, 0.0, 0.0
    t = 0.0
    c1 = math.exp(-gam * dt / m)
    c2 = math.sqrt((1.0 - c1 * c1) * kT / m)
    gx, gy = _grad_u(lat, U0, a, x, y)
    fx = k * (X0 - x) - gx
    fy = k * (Y0 - y) - gy
    out[0, 0] = 0.0
    out[0, 1] = x
    out[0, 2] = y
    out[0, 3] = k * (X0 - x)
    out[0, 4] = k * (Y0 - y)
    j = 1
    for i in range(1, n_steps + 1):
        vx += 0.5 * dt * fx / m
        vy += 0.5 * dt * fy / m
        x += 0.5 * dt * vx
        y += 0.5 * dt * vy
        if kT > 0.0:
            vx = c1 * vx + c2 * np.random.randn()
            vy = c1 * vy + c2 * np.random.randn()
        else:
            vx = c1 * vx
            vy = c1 * vy
        x += 0.5 * dt * vx
        y += 0.5 * dt * vy
        t = i * dt
        Xb = X0 + Vx * t
        Yb = Y0 + Vy * t
        gx, gy = _grad_u(lat, U0, a, x, y)
        fx = k * (Xb - x) - gx
        fy = k * (Yb - y) - gy
        vx += 0.5 * dt * fx / m
        vy += 0.5 * dt * fy / m
        if i % every == 0 and j < n_out:
            out[j, 0] = t
            out[j, 1] = x
            out[j, 2] = y
            out[j, 3] = k * (Xb - x)
            out[j, 4] = k * (Yb - y)
            j += 1
    return out[:j]


@dataclass
class PT2DResult:
    t: np.ndarray
    base: np.ndarray      # (2, n) base position
    tip: np.ndarray       # (2, n) tip position
    force: np.ndarray     # (2, n) lateral spring force k (R - r) (what an FFM measures)
    scan_distance: np.ndarray  # base travel along the scan direction
    params: dict


def pt2d_scan(lattice: str = "hex", eta: float = 3.0, a: float = MICA_LATTICE, k: float = TABLE_2_1["k_x"],
              m: float = TABLE_2_1["m_x"], zeta: float = 0.5, angle_deg: float = 0.0, length: float | None = None,
              speed: float = 1e-4, temperature: float = 0.0, seed: int = 0, start=(0.0, 0.0),
              steps_per_period: int = 40, n_out: int = 20000) -> PT2DResult:
    """2D PT line scan along ``angle_deg`` (from lattice vector a1 = x axis).

    ``U0 = eta k a^2 / (4 pi^2)``; damping ``gamma = 2 zeta sqrt(m k (1 + eta))`` (zeta = 0.5:
    slips end in the next well, no multiple-site jumps for moderate eta). Time step:
    ``T_0 / steps_per_period`` with ``T_0 = 2 pi sqrt(m / (k (1 + eta)))`` (the stiffest
    curvature, 4 pi^2 U0/a^2 + k along an axis; for the hex lattice the curvature is the same).
    Defaults: the Table 2.1 cantilever (k_x, m_x, taken isotropic) at 100 um/s:
    ``V T_0 ~ 1e-12 m = 0.002 a``, quasi-static (V << a / T_0) while the run stays short
    (about 5e4 steps per lattice constant).
    """
    if lattice not in LATTICES:
        raise ParameterError(f"unknown lattice {lattice!r} (known: {', '.join(LATTICES)})")
    for nm, val in (("eta", eta), ("a", a), ("k", k), ("m", m), ("zeta", zeta), ("speed", speed)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise ParameterError(f"pt2d_scan: '{nm}' must be positive, got {val!r}")
    if temperature < 0:
        raise ParameterError(f"temperature must be >= 0 K, got {temperature}")
    length = 10 * a if length is None else length
    if length <= 0:
        raise ParameterError(f"scan length must be positive, got {length}")
    U0 = eta * k * a * a / (4 * math.pi**2)
    gam = 2 * zeta * math.sqrt(m * k * (1 + eta))
    T0 = 2 * math.pi * math.sqrt(m / (k * (1 + eta)))
    dt = T0 / steps_per_period
    T = length / speed
    n_steps = int(math.ceil(T / dt))
    if n_steps > 5e8:
        raise ParameterError(f"pt2d_scan would need {n_steps:.2g} steps; raise the speed or shorten the scan")
    every = max(1, n_steps // n_out)
    th = math.radians(angle_deg)
    lat = LATTICES.index(lattice)
    out = _baoab(lat, U0, a, k, m, gam, K_B * temperature, float(start[0]), float(start[1]),
                 speed * math.cos(th), speed * math.sin(th), float(start[0]), float(start[1]),
                 dt, n_steps, every, int(seed))
    t = out[:, 0]
    base = np.vstack([start[0] + speed * math.cos(th) * t, start[1] + speed * math.sin(th) * t])
    return PT2DResult(t=t, base=base, tip=out[:, 1:3].T, force=out[:, 3:5].T, scan_distance=speed * t,
                      params=dict(lattice=lattice, eta=eta, a=a, k=k, m=m, zeta=zeta, gamma=gam, U0=U0,
                                  angle_deg=angle_deg, speed=speed, temperature=temperature, seed=seed,
                                  dt=dt))


def lattice_sites(lattice: str, a: float, xlim, ylim) -> np.ndarray:
    """Potential minima (lattice sites) inside a box, as an (n, 2) array."""
    if lattice == "square":
        a1, a2 = np.array([a, 0.0]), np.array([0.0, a])
    elif lattice == "hex":
        a1, a2 = np.array([a, 0.0]), np.array([a / 2, math.sqrt(3) * a / 2])
    else:
        raise ParameterError("lattice_sites: 'square' or 'hex'")
    n = int(max(abs(xlim[0]), abs(xlim[1]), abs(ylim[0]), abs(ylim[1])) / a * 2.5) + 3
    i, j = np.meshgrid(np.arange(-n, n + 1), np.arange(-n, n + 1))
    pts = i.reshape(-1, 1) * a1 + j.reshape(-1, 1) * a2
    keep = (pts[:, 0] >= xlim[0]) & (pts[:, 0] <= xlim[1]) & (pts[:, 1] >= ylim[0]) & (pts[:, 1] <= ylim[1])
    return pts[keep]
