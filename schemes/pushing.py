"""Nano-pushing of a spherical sample on an atomically flat lattice (source section 4.1.1–4.1.2).

The model (Tables 4.1–4.2, Fig 4.1)
-----------------------------------
A lumped probe tip (masses ``m_tx``, ``m_ty``, stiffnesses ``k_tx``, ``k_ty``, damping ``c_t``,
Table 4.1) is driven by its base at constant speed ``V`` along the push axis x of the probe frame.
Its spherical apex (radius ``R_t``) touches a spherical sample (radius ``R_s``, mass ``m_s``) that
rests on a mica or HOPG substrate. All coordinates are displacements in the substrate plane; the
tip and sample centres sit at the same height (the tip pushes at the sample's equator), so the
contact force lies in the plane and does not change the normal load on the substrate (the
friction levels of Table 4.2 are taken at a fixed load, as in the source).

* **Tip–sample contact** (section 2.2, eq 2.20): the DMT model of the contact registry
  (:class:`probedyn.schemes.contact.dmt.DMT`, its closed form :meth:`~.DMT.point`) along the
  push axis, at the penetration ``delta = zeta0 - s`` of the gap ``s = x_s - x_t`` (van der Waals
  tail ``-HR/6s^2`` for ``s >= zeta0``, DMT = Hertz + constant adhesion for ``s < zeta0``). The contact normal is kept along x: the lateral offsets are
  below a nanometre while the centre distance is ``R_s + R_t = 210 nm``, so the rotation of the
  normal changes the forces by less than ``(1 nm / 210 nm) = 0.5 %``. Transverse (y) coupling is a
  stuck (no-slip) Mindlin tangential spring ``k_t = (4 G*/E*) k_n(s)`` (Hertz ``k_n = 2E* a_c``,
  Mindlin ``k_t = 8 G* a_c``), present only while in contact. Sample rotation (rolling) is not
  modelled, as in the source.
* **Sample–substrate friction** (section 2.1.4, eqs 2.4–2.9, with the lattice entering as a
  modelling choice, departure 14)::

      F_sub = sigma0 z + sigma1 dz/dt + F_v v + S(w) grad U(r),      S(w) = exp(-(w/V_s)^2)
      dz/dt = v - |v| z sigma0 / F_c                                  (isotropic LuGre bristle)
      dw/dt = (|v| - w) / tau_p,  tau_p = a / V_s                     (memory speed of the pinning)
      U(r)  = -U0 sum_j cos(G_j . r),  |G_j| = 4 pi / (sqrt(3) a),  U0 = (F_s - F_c) a / (4 pi)

  The bristle carries the kinetic (Coulomb) part ``F_c`` exactly as the LuGre model of eq 2.5 with
  ``g = F_c / sigma0``. The excess ``F_s - F_c`` of static over kinetic friction is not a constant:
  it is the pinning of the sample in the hexagonal (triangular-minima) lattice potential ``U`` of
  the substrate, a Prandtl–Tomlinson-type corrugation whose peak force along a lattice axis is
  exactly ``F_s - F_c`` (along the axis ``U = -U0 (1 + 2 cos(2 pi x / a))``). Its amplitude fades
  with speed through the source's own Stribeck factor of eq 2.4/2.9, evaluated on the memory
  speed ``w`` (the sliding rate averaged over the time to cross a lattice constant at ``V_s``; on
  the instantaneous speed it would make every creep violently unstable): at rest the
  resistance ranges from ``F_c`` (at a lattice site) to ``F_s`` (a quarter period uphill), which is
  how this model realises the "jumping mechanism" ``F_s = F_s(a, gamma)``, ``F_c = F_c(a, gamma)``
  of eq 2.6; when sliding much faster than ``V_s`` the friction is ``F_c + F_v V``. The step
  length is *not* put in: it emerges as the distance between equivalent yield points of the
  lattice. The printed generalised bristle (2.7–2.12) alone has no length scale tied to ``a``; its
  slip period is about ``2 (F_s - F_c) / k`` (departure 11).
* **Dissipation**: ``F_v`` is the viscous term of eq 2.7 (units N s/m, departure 10); the
  default 1e-7 N s/m is the value fitted on mica in Table 2.1. It over-damps the slip of the
  sample on the contact spring (damping ratio ``F_v / 2 sqrt(k m_s) ~ 4``); air / capillary
  damping (Fig 4.6) is modelled by raising it to 2e-5 – 5e-5 N s/m.

Numerics: the system is stiff (tip period ~1.6 ns, bristle relaxation ~10 ps while sliding,
stick phases ~100 us); it is integrated with scipy's Radau (implicit, order 5) with the analytic
Jacobian of :meth:`PushModel.jac`. In 1D only the x components are integrated (by symmetry the
2D model at ``angle = 0`` keeps ``y = 0`` exactly; a test checks the reduction).

The 2D push direction makes the angle ``angle`` (gamma of Fig 2.7) with the main lattice axis; in
the probe frame the lattice is rotated by ``-angle``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from scipy.integrate import Radau, solve_ivp
from scipy.linalg import lapack as _lapack

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.lumped.reduced import ReducedProbe
from probedyn.schemes.contact import ContactModel, get_contact_model
from probedyn.schemes.probe_hooks import pushing_tip

# --------------------------------------------------------------------------------------------
# Substrates (Table 4.2)
# --------------------------------------------------------------------------------------------

SUBSTRATES: dict[str, dict[str, float]] = {
    # lattice parameter a [m], static F_s and kinetic F_c friction [N] (Table 4.2)
    "mica": dict(preset("table-4.2-mica")),
    "hopg": dict(preset("table-4.2-hopg")),
}


def substrate(name: str) -> dict[str, float]:
    """Table 4.2 values of a substrate (``mica`` or ``hopg``, case-insensitive)."""
    key = str(name).strip().lower()
    if key not in SUBSTRATES:
        raise ParameterError(f"unknown substrate {name!r} (known: {', '.join(SUBSTRATES)})")
    return dict(SUBSTRATES[key])


# --------------------------------------------------------------------------------------------
# Parameters
# --------------------------------------------------------------------------------------------

_T41 = preset("table-4.1")

PARAMS = ParamSet([
    # probe (Table 4.1)
    Param("k_tx", _T41["k_tx"], "N/m", "tip stiffness along the push axis", lo=1e-3, hi=1e7, positive=True,
          source="Table 4.1"),
    Param("k_ty", _T41["k_ty"], "N/m", "tip stiffness across the push axis", lo=1e-3, hi=1e7, positive=True,
          source="Table 4.1"),
    Param("m_tx", _T41["m_tx"], "kg", "tip effective mass (x)", lo=1e-22, hi=1e-6, positive=True, source="Table 4.1"),
    Param("m_ty", _T41["m_ty"], "kg", "tip effective mass (y)", lo=1e-22, hi=1e-6, positive=True, source="Table 4.1"),
    Param("c_t", _T41["c_t"], "N s/m", "tip damping", lo=0.0, hi=1e-2, source="Table 4.1"),
    # sample and tip material (Table 4.1)
    Param("m_s", _T41["m_s"], "kg", "sample mass", lo=1e-22, hi=1e-6, positive=True, source="Table 4.1"),
    Param("R_s", _T41["R_s"], "m", "sample radius", lo=1e-10, hi=1e-4, positive=True, source="Table 4.1"),
    Param("R_t", _T41["R_t"], "m", "tip radius", lo=1e-10, hi=1e-4, positive=True, source="Table 4.1"),
    Param("E_s", _T41["E_s"], "Pa", "sample Young modulus", lo=1e5, hi=2e12, positive=True, source="Table 4.1"),
    Param("E_t", _T41["E_t"], "Pa", "tip Young modulus", lo=1e5, hi=2e12, positive=True, source="Table 4.1"),
    Param("nu_s", _T41["nu_s"], "", "sample Poisson ratio", lo=-0.99, hi=0.5, source="Table 4.1"),
    Param("nu_t", _T41["nu_t"], "", "tip Poisson ratio", lo=-0.99, hi=0.5, source="Table 4.1"),
    Param("H", _T41["H"], "J", "tip-sample Hamaker constant", lo=0.0, hi=1e-17, source="Table 4.1"),
    Param("zeta0", preset("table-4.4")["zeta0"], "m",
          "inter-atomic distance of the DMT law, eq 2.20 (Table 4.4, as schemes.contact)",
          lo=5e-11, hi=2e-9, positive=True, source="eq 2.20, Table 4.4"),
    # sample-substrate friction
    Param("sigma0", _T41["sigma0"], "N/m", "bristle stiffness", lo=1e-2, hi=1e9, positive=True, source="Table 4.1"),
    Param("sigma1", -1.0, "N s/m", "bristle damping; negative = critical 2 sqrt(sigma0 m_s)", lo=-1.0, hi=1.0,
          source="eq 2.5"),
    Param("V_s", _T41["V_s"], "m/s", "Stribeck velocity", lo=1e-9, hi=1.0, positive=True, source="Table 4.1"),
    Param("F_v", preset("table-2.1")["F_v_x"], "N s/m",
          "viscous friction coefficient (Table 2.1 value; units per departure 10)",
          lo=0.0, hi=1e-2, source="eq 2.7, Table 2.1"),
    Param("a", 0.0, "m", "lattice parameter; 0 = from the substrate (Table 4.2)", lo=0.0, hi=1e-8, source="Table 4.2"),
    Param("F_s", 0.0, "N", "static friction; 0 = from the substrate", lo=0.0, hi=1e-5, source="Table 4.2"),
    Param("F_c", 0.0, "N", "kinetic friction; 0 = from the substrate", lo=0.0, hi=1e-5, source="Table 4.2"),
    # scenario (section 4.1.1)
    Param("V", _T41["V"], "m/s", "base pushing speed", lo=1e-9, hi=1.0, positive=True, source="4.1.1"),
    Param("angle", 0.0, "deg", "angle between push direction and main lattice axis", lo=-180.0, hi=180.0,
          source="Fig 2.7"),
    Param("gap0", 4e-10, "m", "initial tip-sample gap", lo=0.0, hi=1e-7, source="4.1.1"),
    Param("travel", 0.0, "m", "base travel; 0 = pre-sliding estimate + 14 lattice constants", lo=0.0, hi=1e-6),
    Param("tau_p", -1.0, "s", "memory time of the lattice pinning (Stribeck) state; negative = a / V_s",
          lo=-1.0, hi=1.0),
    Param("v_eps", 1e-8, "m/s", "speed regularising |v| in the bristle law (creep bound)", lo=1e-14, hi=1e-3,
          positive=True),
    Param("rtol", 1e-6, "", "integrator relative tolerance", lo=1e-12, hi=1e-2, positive=True),
])


def _probe_fields(probe: Any) -> dict[str, float]:
    """k and m (and optional damping) of a LumpedModel-like object, a mapping or a number pair;
    a :class:`~probedyn.lumped.reduced.ReducedProbe` gives its scan / lateral one-mode models
    (:func:`probedyn.schemes.probe_hooks.pushing_tip`)."""
    if probe is None:
        return {}
    if isinstance(probe, ReducedProbe):
        return pushing_tip(probe)
    if isinstance(probe, Mapping):
        get = probe.get
    else:
        def get(name, default=None):
            return getattr(probe, name, default)
    k = get("k", None)
    if k is None:
        k = get("stiffness", None)
    m = get("m", None)
    if m is None:
        m = get("mass", None)
    if k is None or m is None:
        raise ParameterError("probe must provide a stiffness (k or stiffness) and a mass (m or mass)")
    out: dict[str, float] = {}
    try:
        k = float(k)
        m = float(m)
    except (TypeError, ValueError):
        raise ParameterError(f"probe stiffness/mass must be numbers, got {k!r}, {m!r}") from None
    if not (k > 0 and math.isfinite(k)):
        raise ParameterError(f"probe stiffness must be positive, got {k:g} N/m")
    if not (m > 0 and math.isfinite(m)):
        raise ParameterError(f"probe mass must be positive, got {m:g} kg")
    out["k_tx"], out["m_tx"] = k, m
    ky = get("k_y", None)
    my = get("m_y", None)
    # Without a transverse mode, keep Table 4.1's anisotropy k_ty/k_tx = 1/3 and equal masses.
    out["k_ty"] = float(ky) if ky is not None else k / 3.0
    out["m_ty"] = float(my) if my is not None else m
    c = get("damping", None)
    if c is None:
        c = get("c", None)
    if c is not None:
        out["c_t"] = float(c)
    return out


# --------------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------------

# state layout (2D): tip x, y, vx, vy; sample x, y, vx, vy; bristle zx, zy; memory speed w
NS = 11
IX = [0, 2, 4, 6, 8, 10]  # the x components (and w): the 1D state


@dataclass
class PushModel:
    """The nano-pushing model; build with :func:`make_model`. See the module docstring."""

    p: dict[str, float]
    dim: int = 1
    contact: ContactModel = field(init=False)

    def __post_init__(self) -> None:
        p = self.p
        if self.dim not in (1, 2):
            raise ParameterError(f"dim must be 1 or 2, got {self.dim}")
        if not p["F_s"] > p["F_c"] > 0:
            raise ParameterError(
                f"friction levels must satisfy F_s > F_c > 0, got F_s = {p['F_s']:g} N, F_c = {p['F_c']:g} N")
        if not p["a"] > 0:
            raise ParameterError(f"lattice parameter must be positive, got {p['a']:g} m")
        self.contact = get_contact_model("dmt", **{k: p[k] for k in ("E_t", "nu_t", "E_s", "nu_s", "R_t", "R_s", "H")},
                                         z0=p["zeta0"])
        self.E_star = self.contact.scales.E_star  # eq 2.21
        self.R = self.contact.scales.R
        G_s = p["E_s"] / (2 * (1 + p["nu_s"]))
        G_t = p["E_t"] / (2 * (1 + p["nu_t"]))
        self.G_star = 1.0 / ((2 - p["nu_s"]) / G_s + (2 - p["nu_t"]) / G_t)
        self.kappa = 4.0 * self.G_star / self.E_star  # Mindlin k_t / Hertz k_n
        self.zeta0 = p["zeta0"]
        self.sigma1 = p["sigma1"] if p["sigma1"] >= 0 else 2.0 * math.sqrt(p["sigma0"] * p["m_s"])
        self.tau_p = p["tau_p"] if p["tau_p"] > 0 else p["a"] / p["V_s"]
        a = p["a"]
        self.U0 = (p["F_s"] - p["F_c"]) * a / (4.0 * math.pi)
        g = 4.0 * math.pi / (math.sqrt(3.0) * a)
        gam = math.radians(p["angle"])
        th = np.radians([30.0, 150.0, 270.0]) - gam
        self.G = g * np.column_stack([np.cos(th), np.sin(th)])  # (3, 2) in the probe frame
        # where the sample starts: at a lattice site (a potential minimum)
        self.x0 = p["gap0"]

    # -- substrate ----------------------------------------------------------------------------
    def lattice_force(self, rx: float, ry: float) -> tuple[np.ndarray, np.ndarray]:
        """grad U and its Hessian at sample position (rx, ry) (relative to the start site)."""
        ph = self.G[:, 0] * (rx - self.x0) + self.G[:, 1] * ry
        s = np.sin(ph)
        c = np.cos(ph)
        grad = self.U0 * (self.G.T @ s)
        hess = self.U0 * (self.G.T * c) @ self.G
        return grad, hess

    def lattice_grad(self, rx: float, ry: float) -> np.ndarray:
        """grad U alone (the right-hand side needs no Hessian): the same operations as
        :meth:`lattice_force`, so the same numbers to the last bit."""
        ph = self.G[:, 0] * (rx - self.x0) + self.G[:, 1] * ry
        return self.U0 * (self.G.T @ np.sin(ph))

    def potential(self, rx, ry):
        ph = self.G[:, 0, None] * (np.asarray(rx) - self.x0) + self.G[:, 1, None] * np.asarray(ry)
        return -self.U0 * np.cos(ph).sum(axis=0)

    # -- tip-sample contact ---------------------------------------------------------------------
    def normal_contact(self, s: float, jacobian: bool = False) -> tuple[float, float, float, float]:
        """DMT contact at the gap ``s`` (penetration ``zeta0 - s``): normal force ``Fn`` [N]
        (positive = repulsive), ``kn = -dFn/ds``, the Hertz stiffness of the contact patch
        ``kc = 2 E* a`` (0 out of contact; Mindlin's tangential spring is ``kappa kc``) and, with
        ``jacobian``, ``dkc/ds`` with the penetration floored at 1e-3 zeta0 (it is infinite at
        first touch; the floor only softens the Jacobian, not the right-hand side)."""
        delta = self.zeta0 - s
        Fn, kn, a, da = self.contact.point(delta)
        kc = 2.0 * self.E_star * a
        dkc = 0.0
        if jacobian and delta > 0.0:
            floor = 1e-3 * self.zeta0
            if delta < floor:
                da = self.contact.point(floor)[3]
            dkc = -2.0 * self.E_star * da
        return Fn, kn, kc, dkc

    # -- dynamics (2D state) --------------------------------------------------------------------
    def forces(self, t: float, y: np.ndarray) -> dict[str, Any]:
        p = self.p
        xt, yt, ut, wt, xs, ys, us, ws, zx, zy, wm = y
        s = xs - xt
        Fn, _, kc, _ = self.normal_contact(s)
        Ft = -self.kappa * kc * (ys - yt)
        sp2 = us * us + ws * ws
        vabs = math.sqrt(sp2 + p["v_eps"] ** 2)
        S = math.exp(-(wm / p["V_s"]) ** 2)
        r = p["sigma0"] / p["F_c"]
        zdx = us - vabs * r * zx
        zdy = ws - vabs * r * zy
        grad, _ = self.lattice_force(xs, ys)
        Fsx = p["sigma0"] * zx + self.sigma1 * zdx + p["F_v"] * us + S * grad[0]
        Fsy = p["sigma0"] * zy + self.sigma1 * zdy + p["F_v"] * ws + S * grad[1]
        wdot = (vabs - wm) / self.tau_p
        return {"Fn": Fn, "Ft": Ft, "Fsub": (Fsx, Fsy), "zdot": (zdx, zdy), "wdot": wdot, "S": S, "grad": grad}

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        # :meth:`forces` inlined (the integrators call this ~1e4 times per push): the same
        # floating-point operations in the same order, so the same numbers to the last bit
        p = self.p
        xt, yt, ut, wt, xs, ys, us, ws, zx, zy, wm = y.tolist()
        Fn, _, kc, _ = self.normal_contact(xs - xt)
        Ft = -self.kappa * kc * (ys - yt)
        sp2 = us * us + ws * ws
        vabs = math.sqrt(sp2 + p["v_eps"] ** 2)
        S = math.exp(-(wm / p["V_s"]) ** 2)
        r = p["sigma0"] / p["F_c"]
        zdx = us - vabs * r * zx
        zdy = ws - vabs * r * zy
        gx, gy = self.lattice_grad(xs, ys).tolist()
        Fsx = p["sigma0"] * zx + self.sigma1 * zdx + p["F_v"] * us + S * gx
        Fsy = p["sigma0"] * zy + self.sigma1 * zdy + p["F_v"] * ws + S * gy
        V = p["V"]
        dut = (-p["k_tx"] * (xt - V * t) - p["c_t"] * (ut - V) - Fn) / p["m_tx"]
        dwt = (-p["k_ty"] * yt - p["c_t"] * wt - Ft) / p["m_ty"]
        dus = (Fn - Fsx) / p["m_s"]
        dws = (Ft - Fsy) / p["m_s"]
        return np.array([ut, wt, dut, dwt, us, ws, dus, dws, zdx, zdy, (vabs - wm) / self.tau_p])

    def rhs_1d(self, t: float, y: np.ndarray) -> np.ndarray:
        """:meth:`rhs` on the 1D state (the x components ``IX``; the y components are zero):
        the same operations on the same values, so the same numbers to the last bit as
        ``rhs(t, full)[IX]`` without building the 11-component state for every call."""
        p = self.p
        xt, ut, xs, us, zx, wm = y.tolist()
        Fn, _, kc, _ = self.normal_contact(xs - xt)
        sp2 = us * us + 0.0 * 0.0
        vabs = math.sqrt(sp2 + p["v_eps"] ** 2)
        S = math.exp(-(wm / p["V_s"]) ** 2)
        r = p["sigma0"] / p["F_c"]
        zdx = us - vabs * r * zx
        gx = self.lattice_grad(xs, 0.0)[0]
        Fsx = p["sigma0"] * zx + self.sigma1 * zdx + p["F_v"] * us + S * gx
        V = p["V"]
        dut = (-p["k_tx"] * (xt - V * t) - p["c_t"] * (ut - V) - Fn) / p["m_tx"]
        dus = (Fn - Fsx) / p["m_s"]
        return np.array([ut, dut, us, dus, zdx, (vabs - wm) / self.tau_p])

    def jac(self, t: float, y: np.ndarray) -> np.ndarray:
        """Analytic Jacobian of :meth:`rhs` (11 x 11)."""
        p = self.p
        xt, yt, ut, wt, xs, ys, us, ws, zx, zy, wm = y
        J = np.zeros((NS, NS))
        J[0, 2] = J[1, 3] = J[4, 6] = J[5, 7] = 1.0
        s = xs - xt
        _, kn, kc, dkc = self.normal_contact(s, jacobian=True)  # kn = -dFn/ds
        dy = ys - yt
        # Fn(s): dFn/dxs = -kn, dFn/dxt = +kn ; Ft = -kappa kc(s) dy
        dFn = np.zeros(NS)
        dFn[4], dFn[0] = -kn, kn
        dFt = np.zeros(NS)
        dFt[5], dFt[1] = -self.kappa * kc, self.kappa * kc
        dFt[4], dFt[0] = -self.kappa * dkc * dy, self.kappa * dkc * dy
        # substrate
        sp2 = us * us + ws * ws
        vabs = math.sqrt(sp2 + p["v_eps"] ** 2)
        S = math.exp(-(wm / p["V_s"]) ** 2)
        r = p["sigma0"] / p["F_c"]
        grad, hess = self.lattice_force(xs, ys)
        # zdot
        dz = np.zeros((2, NS))
        dz[0, 6] = 1.0 - r * zx * us / vabs
        dz[0, 7] = -r * zx * ws / vabs
        dz[1, 6] = -r * zy * us / vabs
        dz[1, 7] = 1.0 - r * zy * ws / vabs
        dz[0, 8] = dz[1, 9] = -vabs * r
        dS = np.zeros(NS)
        dS[10] = -2.0 * wm / p["V_s"] ** 2 * S
        dF = np.zeros((2, NS))
        dF[0, 8] = dF[1, 9] = p["sigma0"]
        dF += self.sigma1 * dz
        dF[0, 6] += p["F_v"]
        dF[1, 7] += p["F_v"]
        dF[0] += grad[0] * dS
        dF[1] += grad[1] * dS
        dF[:, 4] += S * hess[:, 0]
        dF[:, 5] += S * hess[:, 1]
        # tip
        J[2, 0] -= p["k_tx"] / p["m_tx"]
        J[2, 2] -= p["c_t"] / p["m_tx"]
        J[2] -= dFn / p["m_tx"]
        J[3, 1] -= p["k_ty"] / p["m_ty"]
        J[3, 3] -= p["c_t"] / p["m_ty"]
        J[3] -= dFt / p["m_ty"]
        # sample
        J[6] = (dFn - dF[0]) / p["m_s"]
        J[7] = (dFt - dF[1]) / p["m_s"]
        J[8] = dz[0]
        J[9] = dz[1]
        J[10, 6] = us / vabs / self.tau_p
        J[10, 7] = ws / vabs / self.tau_p
        J[10, 10] = -1.0 / self.tau_p
        return J

    def initial_state(self) -> np.ndarray:
        y = np.zeros(NS)
        y[4] = self.p["gap0"]
        return y

    # -- characteristic scales -----------------------------------------------------------------
    def k_series(self, load: float) -> float:
        """Stiffness from base to sample (tip spring in series with the DMT contact) at ``load``."""
        tot = load - self.contact.pull_off_force()
        # Hertz: tot = (4/3) E* sqrt(R) d^1.5
        d = (3 * tot / (4 * self.E_star * math.sqrt(self.R))) ** (2.0 / 3.0)
        kc = 2 * self.E_star * math.sqrt(self.R * d)
        return 1.0 / (1.0 / self.p["k_tx"] + 1.0 / kc)


def make_model(substrate_name: str = "mica", overrides: Mapping[str, Any] | None = None, *,
               dim: int = 1, probe: Any = None) -> PushModel:
    """Resolve parameters (Table 4.1 defaults, Table 4.2 substrate, user overrides) into a model.

    ``probe`` may be a :class:`~probedyn.lumped.reduced.ReducedProbe` (scan -> ``k_tx, m_tx, c_t``,
    lateral -> ``k_ty, m_ty``), a LumpedModel-like object (``stiffness``/``mass`` or ``k``/``m``) or
    a mapping; it replaces the Table 4.1 tip values ``k_tx``, ``m_tx`` (and ``k_ty`` = k/3,
    ``m_ty`` = m unless given).
    """
    sub = substrate(substrate_name)
    ov = dict(overrides or {})
    ov.update({k: v for k, v in _probe_fields(probe).items() if k not in ov})
    p = PARAMS.resolve(ov)
    for key in ("a", "F_s", "F_c"):
        if not p[key]:
            p[key] = sub[key]
    p["substrate"] = substrate_name.lower()
    return PushModel(p, dim=dim)


# --------------------------------------------------------------------------------------------
# Simulation
# --------------------------------------------------------------------------------------------

@dataclass
class PushResult:
    """Time series of a push (probe frame; x along the push)."""

    t: np.ndarray
    y: np.ndarray  # (11, n) full state (1D runs have zero y components)
    model: PushModel
    wall_time: float
    nfev: int

    @property
    def base(self) -> np.ndarray:
        return self.model.p["V"] * self.t

    @property
    def sample_xy(self) -> np.ndarray:
        """Sample displacement from its start (2, n)."""
        return np.vstack([self.y[4] - self.model.x0, self.y[5]])

    @property
    def sample_speed(self) -> np.ndarray:
        return np.hypot(self.y[6], self.y[7])

    def friction(self) -> np.ndarray:
        """Substrate friction force on the sample (2, n), resisting sign convention (F_sub)."""
        out = np.empty((2, self.t.size))
        for i in range(self.t.size):
            out[:, i] = self.model.forces(self.t[i], self.y[:, i])["Fsub"]
        return out

    def tip_force(self) -> np.ndarray:
        """Lateral force measured by the tip spring along the push, k_tx (V t - x_t)."""
        return self.model.p["k_tx"] * (self.base - self.y[0])


class _Radau(Radau):
    """scipy's Radau with its dense LU factorisation and solves calling LAPACK (getrf/getrs)
    directly: the same LAPACK routines scipy.linalg.lu_factor/lu_solve call, so the same
    numbers, without their per-call checks and wrappers (on these 6- and 11-unknown systems the
    wrappers cost more than the factorisation: 40 % of a push's time in scipy 1.17)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if isinstance(self.J, np.ndarray):
            self.lu, self.solve_lu = self._lu_direct, self._solve_direct

    def _lu_direct(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.nlu += 1
        if not np.isfinite(A).all():
            raise ValueError("array must not contain infs or NaNs")
        getrf = _lapack.zgetrf if A.dtype.kind == "c" else _lapack.dgetrf
        lu, piv, info = getrf(A, overwrite_a=True)
        if info < 0:  # pragma: no cover
            raise ValueError(f"illegal value in {-info}th argument of internal getrf (lu_factor)")
        return lu, piv

    @staticmethod
    def _solve_direct(LU: tuple[np.ndarray, np.ndarray], b: np.ndarray) -> np.ndarray:
        lu, piv = LU
        if not np.isfinite(b).all():
            raise ValueError("array must not contain infs or NaNs")
        getrs = _lapack.zgetrs if (lu.dtype.kind == "c" or b.dtype.kind == "c") else _lapack.dgetrs
        x, info = getrs(lu, piv, b, overwrite_b=True)
        if info != 0:  # pragma: no cover
            raise ValueError(f"illegal value in {-info}th argument of internal gesv|posv")
        return x


def simulate(model: PushModel, travel: float | None = None, *, n_out: int = 4000,
             max_step_frac: float = 0.05) -> PushResult:
    """Integrate the push over a base travel ``travel`` (default: the ``travel`` parameter or
    the pre-sliding estimate plus 14 lattice constants).

    Radau with the analytic Jacobian; ``max_step`` is ``max_step_frac`` of the time the base needs
    to cross one lattice constant, so no slip can be stepped over. Output is the solver's own steps
    (dense near slips) thinned to at most ``n_out`` points plus all slip points.
    """
    p = model.p
    if travel is None:
        travel = p["travel"] or (p["F_s"] / model.k_series(p["F_s"]) + p["a"] / 4 + p["gap0"] + 14 * p["a"])
    if not travel > 0:
        raise ParameterError(f"travel must be positive, got {travel:g} m")
    T = travel / p["V"]
    y0 = model.initial_state()
    if model.dim == 1:
        idx = np.array(IX)

        f = model.rhs_1d

        def jf(t, yy):
            full = np.zeros(NS)
            full[idx] = yy
            return model.jac(t, full)[np.ix_(idx, idx)]

        y0r = y0[idx]
    else:
        f, jf, y0r = model.rhs, model.jac, y0
    atol = np.empty(y0r.size)
    # absolute tolerances per component: positions 1e-14 m, velocities 1e-9 m/s, bristle 1e-17 m
    pos, vel, zz = 1e-14, 1e-9, 1e-17
    atol[:] = pos
    if model.dim == 1:
        atol[[1, 3]] = vel
        atol[4] = zz
        atol[5] = vel
    else:
        atol[[2, 3, 6, 7, 10]] = vel
        atol[[8, 9]] = zz
    t0 = time.perf_counter()
    sol = solve_ivp(f, (0.0, T), y0r, method=_Radau, jac=jf, rtol=p["rtol"], atol=atol,
                    max_step=max_step_frac * p["a"] / p["V"])
    wall = time.perf_counter() - t0
    if not sol.success:
        raise SolverError(f"push integration failed: {sol.message}")
    t, Y = sol.t, sol.y
    if model.dim == 1:
        full = np.zeros((NS, t.size))
        full[idx] = Y
        Y = full
    if t.size > n_out:
        # keep every point where the sample moves fast (slips), thin the rest uniformly
        fast = np.hypot(Y[6], Y[7]) > 3 * p["V"]
        keep = np.zeros(t.size, bool)
        keep[:: max(1, t.size // n_out)] = True
        keep |= fast
        keep[[0, -1]] = True
        t, Y = t[keep], Y[:, keep]
    return PushResult(t, Y, model, wall, sol.nfev)


# --------------------------------------------------------------------------------------------
# Analysis: slips, steps, regime
# --------------------------------------------------------------------------------------------

def analyse(res: PushResult, *, fast: float = 3.0, settle_lattice: float = 1.0,
            ratio_min: float = 10.0) -> dict[str, Any]:
    """Slips, step statistics and the regime of a push.

    A *slip* is a maximal interval in which the sample speed exceeds ``fast * V``; a *sticking
    point* is the sample position at the onset of a slip. Steps are the vectors between
    consecutive sticking points; the first slip (end of the pre-sliding phase) starts the
    statistics, so pre-sliding does not bias them. The regime is ``stick-slip`` when, after the
    first slip plus ``settle_lattice`` lattice periods of base travel, the sample slips at least
    twice and its fastest forward speed exceeds ``ratio_min`` times its slowest; otherwise
    ``sliding``. (Quasi-static sliding over a corrugation of strength eta < 1 modulates the speed
    between V/(1+eta) and V/(1-eta), a ratio that exceeds 10 only for eta > 0.82; a slip is a
    dynamic jump, orders of magnitude faster than V.)
    """
    m = res.model
    p = m.p
    V = p["V"]
    sp = res.sample_speed
    xy = res.sample_xy
    t = res.t
    # forward speed (along the push): excludes the backward jump of the sample into contact
    isfast = res.y[6] > fast * V
    on = np.flatnonzero(isfast[1:] & ~isfast[:-1]) + 1
    off = np.flatnonzero(~isfast[1:] & isfast[:-1]) + 1
    # a slip needs the probe to push harder than the kinetic friction: this drops the sample's
    # jump into contact (and its rebound) at the start, driven by adhesion, not by the push
    on = on[res.tip_force()[on] > p["F_c"]]
    F = res.friction()
    fx = F[0]
    out: dict[str, Any] = {
        "substrate": p["substrate"], "speed_m_s": V, "angle_deg": p["angle"], "dim": m.dim,
        "lattice_constant_m": p["a"], "F_s_N": p["F_s"], "F_c_N": p["F_c"], "F_v_Ns_m": p["F_v"],
        "wall_time_s": res.wall_time, "nfev": res.nfev,
    }
    # pre-sliding: everything before the first slip (or before the sample reaches V in sliding)
    first = on[0] if on.size else int(np.argmax(sp > 0.5 * V))
    path = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xy[0]), np.diff(xy[1])))])
    out["presliding"] = {
        "peak_friction_N": float(fx[: max(first, 1)].max()),
        "path_length_m": float(path[first]),
        "sample_displacement_m": float(xy[0, first]),
        "base_travel_m": float(res.base[first]),
    }
    t_settle = t[first] + settle_lattice * p["a"] / V
    steady = t >= t_settle
    n_slips = int(np.sum(t[on] >= t_settle))
    vf = res.y[6][steady]
    ratio = float(vf.max() / max(vf.min(), 1e-3 * V)) if vf.size else 0.0
    out["speed_ratio"] = ratio
    regime = "stick-slip" if (n_slips >= 2 and ratio > ratio_min) else "sliding"
    out["regime"] = regime
    out["n_slips"] = int(on.size)
    # steps between consecutive sticking points (slip onsets)
    pts = xy[:, on]
    steps = np.diff(pts, axis=1)
    if regime == "stick-slip" and steps.shape[1] >= 1:
        L = np.hypot(steps[0], steps[1])
        ang = np.degrees(np.arctan2(steps[1], steps[0]))
        out["step_lengths_m"] = L.tolist()
        out["step_angles_deg"] = ang.tolist()
        out["mean_step_m"] = float(L.mean())
        out["std_step_m"] = float(L.std())
        out["mean_step_over_a"] = float(L.mean() / p["a"])
        tot = pts[:, -1] - pts[:, 0]
        out["mean_direction_deg"] = float(np.degrees(np.arctan2(tot[1], tot[0])))
        out["advance_per_slip_m"] = float(np.hypot(*tot) / steps.shape[1])
        # lattice sites (potential minima) holding the sample at each sticking point
        sites = nearest_sites(m, pts)
        hops = np.diff(sites, axis=1)
        out["site_hops"] = [[int(h[0]), int(h[1])] for h in hops.T]
        # slip duration (fraction of the stick-slip period)
        offs = [off[off > i][0] for i in on if np.any(off > i)]
        dur = np.array([t[j] - t[i] for i, j in zip(on, offs)])
        per = np.diff(t[on])
        out["slip_time_fraction"] = float(dur[1:].sum() / per.sum()) if per.size else None
        out["period_s"] = float(per.mean()) if per.size else None
    else:
        out["mean_step_m"] = None
        out["mean_step_over_a"] = None
    w = steady
    out["friction_mean_N"] = float(fx[w].mean()) if w.any() else None
    out["friction_std_N"] = float(fx[w].std()) if w.any() else None
    out["friction_max_N"] = float(fx[w].max()) if w.any() else None
    out["friction_min_N"] = float(fx[w].min()) if w.any() else None
    out["kinetic_expected_N"] = p["F_c"] + p["F_v"] * V
    return out


def lattice_vectors(model: PushModel) -> np.ndarray:
    """Primitive vectors (2, 2) of the triangular lattice of minima in the probe frame (columns)."""
    a = model.p["a"]
    g = math.radians(model.p["angle"])
    return a * np.array([[math.cos(-g), math.cos(math.pi / 3 - g)], [math.sin(-g), math.sin(math.pi / 3 - g)]])


def nearest_sites(model: PushModel, pts: np.ndarray) -> np.ndarray:
    """Integer lattice coordinates (2, n) of the potential minimum nearest to each point (2, n)
    (points are sample displacements from the start site)."""
    A = lattice_vectors(model)
    frac = np.linalg.solve(A, pts)
    base = np.floor(frac)
    best = None
    bestd = None
    for d1 in (0, 1):
        for d2 in (0, 1):
            c = base + np.array([[d1], [d2]])
            dist = np.linalg.norm(A @ c - pts, axis=0)
            if best is None:
                best, bestd = c.copy(), dist
            else:
                sel = dist < bestd
                best[:, sel] = c[:, sel]
                bestd = np.minimum(bestd, dist)
    return best.astype(int)


def push(substrate_name: str = "mica", overrides: Mapping[str, Any] | None = None, *, dim: int | None = None,
         probe: Any = None, travel: float | None = None) -> tuple[PushResult, dict[str, Any]]:
    """Build, simulate and analyse one push. ``dim`` defaults to 2 when ``angle`` is non-zero."""
    ov = dict(overrides or {})
    if dim is None:
        ang = PARAMS["angle"].coerce(ov.get("angle", 0.0))
        dim = 1 if ang == 0 else 2
    model = make_model(substrate_name, ov, dim=dim, probe=probe)
    res = simulate(model, travel)
    return res, analyse(res)


def transition_speed(substrate_name: str = "mica", overrides: Mapping[str, Any] | None = None, *,
                     lo: float = _T41["V"], hi: float = 150e-6, rel_tol: float = 0.02,
                     n_lattice: float = 10.0) -> dict[str, Any]:
    """Speed at which stick-slip gives way to sliding, by bisection on the regime of pushes
    started from rest (``lo`` must be stick-slip, ``hi`` sliding; default ``lo``: the pushing
    speed of 4.1.1). Bisection in log-speed until
    ``hi/lo - 1 < rel_tol``; returns the bracket, its geometric mean and every evaluation."""
    evals = []

    def regime(V):
        ov = dict(overrides or {})
        ov["V"] = V
        model = make_model(substrate_name, ov, dim=1)
        p = model.p
        travel = p["F_s"] / model.k_series(p["F_s"]) + p["a"] / 4 + p["gap0"] + n_lattice * p["a"]
        r = analyse(simulate(model, travel))
        evals.append({"V": V, "regime": r["regime"]})
        return r["regime"]

    if regime(lo) != "stick-slip":
        raise ParameterError(f"no stick-slip at the lower speed {lo:g} m/s: cannot bracket the transition")
    if regime(hi) != "sliding":
        raise ParameterError(f"still stick-slip at the upper speed {hi:g} m/s: cannot bracket the transition")
    while hi / lo - 1 > rel_tol:
        mid = math.sqrt(lo * hi)
        if regime(mid) == "stick-slip":
            lo = mid
        else:
            hi = mid
    return {"substrate": substrate_name, "V_low_m_s": lo, "V_high_m_s": hi, "V_transition_m_s": math.sqrt(lo * hi),
            "evaluations": evals}
