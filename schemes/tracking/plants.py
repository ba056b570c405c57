"""Plant models for path tracking: the interface every controller and simulator uses, and the
smart probes' two-body model (source eqs 3.4, 3.20, 3.37).

The interface (:class:`MechanicalPlant`) is a linear mechanical system in SI units::

    M q'' + C q' + K q = B u + E f_tip,      y = Cq q   (tip displacement),

``u`` the electrode voltages [V], ``B`` the generalised force per volt [N/V], ``f_tip`` a force on
the tip [N] (the substrate disturbance), ``E = Cq^T`` when ``q`` contains the tip. Any source of
M, C, K, B works: the analytic body, the lumped model from FEM modes (``lumped/smart.py``), a
reduced probe with the piezo FEM's actuation (issues 10, 12) - swapping the gains is one argument.

The two-body model (3.37) in probedyn axes, ``q = [q1; q2]`` (tip, holder end face)::

    D q1'' + C1 q1' + K1 (q1 - q2) = F_d
    J q2'' + C2 q2' - K1 (q1 - q2) + K2 q2 = Gamma u

* ``D = m I`` (tip mass), ``K1 = diag(k_t)`` (holder spring), ``C1`` tip damping (air; the source
  prints C on the tip's absolute velocity in 3.37: kept; not in Tables 3.1/3.2, so a quality
  factor ``tip_q`` is assumed, default 100);
* ``J, K2, C2``: the body (PZT beam/tube + holder) referred to the holder end face: from the FEM
  lumped model (``J = U^-T U^-1``, ``K2 = U^-T Omega^2 U^-1``, ``C2`` from eq 3.2; full matrices
  for an eccentric tube) or analytic (beam + holder point mass, eqs 3.1-3.3 with the exact static
  flexibility; rod for the tube's axis). The source's 3.37 has no ``C2``; it is kept (eq 3.2 with
  the tables' mu);
* ``Gamma = K2 G`` [N/V] with ``G`` the free stroke of the holder per volt (:mod:`.actuation`):
  the force on the body that gives the measured static stroke exactly, ``K2^-1 Gamma = G``.

Mapping to the source's symbols (3.37): D = m I; J = body modal mass matrix at the holder
(source: diag(M_x, M_y, M_z) of 3.1); C = C1; K_1 = K1 = diag(k_t); K_2 = K2 = body stiffness
at the holder (source: diag(k_px, k_py, k_pz) of 3.3); Gamma as above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.linalg as sla

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset
from probedyn.schemes.tracking import actuation as act

AX = {"x": 0, "y": 1, "z": 2}


@dataclass
class MechanicalPlant:
    """``M q'' + C q' + K q = B u + E f``, ``y = Cq q`` (module docstring). ``outputs``: the tip
    axes of ``y`` (e.g. ["y", "z"]); ``inputs``: voltage names; ``provenance``: where M, K, C and
    B come from (body, gains, parameters)."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    B: np.ndarray
    Cq: np.ndarray
    outputs: list[str]
    inputs: list[str]
    E: np.ndarray | None = None
    provenance: dict[str, Any] = field(default_factory=dict)
    blocks: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = self.M.shape[0]
        for name in ("M", "C", "K"):
            a = getattr(self, name)
            if a.shape != (n, n) or not np.all(np.isfinite(a)):
                raise ParameterError(f"plant matrix {name} must be a finite ({n}, {n}) array")
        if self.B.shape[0] != n or self.Cq.shape[1] != n:
            raise ParameterError("plant: B must have n rows and Cq n columns")
        if self.E is None:
            self.E = self.Cq.T.copy()

    @property
    def n(self) -> int:
        return self.M.shape[0]

    def static_gain(self) -> np.ndarray:
        """Tip displacement per volt at rest, ``Cq K^-1 B`` (n_out, n_in) [m/V]."""
        return self.Cq @ np.linalg.solve(self.K, self.B)

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, Bu, Bf, Cy) of ``x = [q; q']``."""
        n = self.n
        Minv = np.linalg.inv(self.M)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ self.K, -Minv @ self.C]])
        Bu = np.vstack([np.zeros((n, self.B.shape[1])), Minv @ self.B])
        Bf = np.vstack([np.zeros((n, self.E.shape[1])), Minv @ self.E])
        Cy = np.hstack([self.Cq, np.zeros((self.Cq.shape[0], n))])
        return A, Bu, Bf, Cy

    def frequency_response(self, omega: np.ndarray) -> np.ndarray:
        """(len(omega), n_out, n_in) tip displacement per volt at angular frequencies omega."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        out = np.empty((omega.size, self.Cq.shape[0], self.B.shape[1]), dtype=complex)
        for i, w in enumerate(omega):
            Z = -w * w * self.M + 1j * w * self.C + self.K
            out[i] = self.Cq @ np.linalg.solve(Z, self.B)
        return out

    def frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies [Hz]."""
        lam = sla.eigh(self.K, self.M, eigvals_only=True)
        return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)

    def damping_ratios(self) -> np.ndarray:
        A, *_ = self.state_space()
        lam = np.linalg.eigvals(A)
        lam = lam[np.imag(lam) > 0]
        order = np.argsort(np.abs(lam))
        return -np.real(lam[order]) / np.abs(lam[order])

    def describe(self) -> dict[str, Any]:
        return {"outputs": self.outputs, "inputs": self.inputs, "frequencies_hz": self.frequencies_hz(),
                "static_gain_m_per_V": self.static_gain(), "provenance": self.provenance}


def two_body_plant(D: np.ndarray, C1: np.ndarray, K1: np.ndarray, J: np.ndarray, C2: np.ndarray, K2: np.ndarray,
                   Gamma: np.ndarray, outputs: Sequence[str], inputs: Sequence[str],
                   provenance: dict[str, Any] | None = None) -> MechanicalPlant:
    """The two-body model (3.37) with body damping ``C2`` (module docstring)."""
    d = len(outputs)
    Z = np.zeros((d, d))
    M = np.block([[D, Z], [Z, J]])
    C = np.block([[C1, Z], [Z, C2]])
    K = np.block([[K1, -K1], [-K1, K1 + K2]])
    B = np.vstack([np.zeros((d, Gamma.shape[1])), Gamma])
    Cq = np.hstack([np.eye(d), Z])
    blocks = {"D": D, "C1": C1, "K1": K1, "J": J, "C2": C2, "K2": K2, "Gamma": Gamma}
    return MechanicalPlant(M, C, K, B, Cq, list(outputs), list(inputs), None, dict(provenance or {}), blocks)


def with_blocks(plant: MechanicalPlant, **changes: np.ndarray) -> MechanicalPlant:
    """A two-body plant with some of its blocks replaced (e.g. ``Gamma=...`` or ``K1=...``)."""
    b = {**plant.blocks, **changes}
    prov = dict(plant.provenance)
    prov.setdefault("modified", []).extend(sorted(changes))
    p = two_body_plant(b["D"], b["C1"], b["K1"], b["J"], b["C2"], b["K2"], b["Gamma"], plant.outputs,
                       plant.inputs, prov)
    for k, v in b.items():  # keep extra blocks (e.g. the stroke matrix G) unless Gamma changed
        if k not in p.blocks and not (k == "G" and "Gamma" in changes):
            p.blocks[k] = v
    return p


def scaled_stiffness(plant: MechanicalPlant, eps: float, scale_gamma: bool = True) -> MechanicalPlant:
    """The singular-perturbation family (3.46): ``K1 -> K1 / eps^2``, ``K2 -> K2 / eps^2`` and, with
    ``scale_gamma``, ``Gamma -> Gamma / eps^2`` (the piezo force is stiffness x free stroke, so the
    stroke per volt stays). ``eps = 1`` is the plant itself."""
    eps = float(eps)
    if not (math.isfinite(eps) and eps > 0):
        raise ParameterError(f"eps must be positive, got {eps:g}")
    b = plant.blocks
    g = b["Gamma"] / eps**2 if scale_gamma else b["Gamma"]
    p = with_blocks(plant, K1=b["K1"] / eps**2, K2=b["K2"] / eps**2, Gamma=g)
    p.provenance["eps"] = eps
    return p


# ---------------------------------------------------------------------------------------------
# bodies (J, K2, C2 at the holder) and the smart probes' plants
# ---------------------------------------------------------------------------------------------

SETUP = {"duo-bimorph": {"dirs": ["y", "z"], "inputs": ["V_y", "V_z"], "table": "table-3.1"},
         "piezotube": {"dirs": ["x", "y", "z"], "inputs": ["V_x", "V_y", "V_z"], "table": "table-3.2"}}


def _probe_values(name: str, overrides: dict[str, Any] | None):
    from probedyn.probes import get_probe

    p, file_ov = get_probe(name)
    if p.name not in SETUP:
        raise ParameterError(f"path tracking needs a smart probe (duo-bimorph or piezotube), got '{p.name}'")
    return p, p.resolve({**file_ov, **(overrides or {})})


def analytic_body(probe, v: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """(J, K2, C2, info): one mode per direction, beam (or tube) + the holder as a point mass
    m_h at the end (eqs 3.1-3.3, 3.24/3.29 without rotary inertia): ``end_body_first_mode_at``
    (exact static end flexibility + one Hermite mass; tube with its Timoshenko shear
    compliance) for bending, the rod ``A/(s11 L)`` with ``m_h + m_rod/3`` along the tube axis.
    Damping (3.2): ``c = (mu / (rho A)) * (modal mass of the body without the holder)``."""
    from probedyn.lumped.smart_analytic import end_body_first_mode_at

    m_h = probe.holder_mass(v)
    rows = {}
    if probe.name == "duo-bimorph":
        b = probe.beam(v)
        rhoA = b.rho * b.A
        for d in ("y", "z"):
            M, k = end_body_first_mode_at(b.EI(d), rhoA, b.L, m_h, 0.0, 0.0, 0.0)
            rows[d] = (M, k, v["mu"] / rhoA * (M - m_h))
        info = {"body": "analytic: beam + holder point mass (3.1-3.3, exact static flexibility)"}
    else:
        t = probe.tube(v)
        rhoA = t.rho * t.A
        nu = float(np.clip(-probe.pzt(v).S[0, 1] / probe.pzt(v).S[0, 0], 0.0, 0.49))
        cs = t.shear_compliance(probe.s66(v), nu)
        M, k = end_body_first_mode_at(t.I(True) / t.s11, rhoA, t.L, m_h, 0.0, 0.0, 0.0, cs)
        ka, Ma = t.A / (t.s11 * t.L), m_h + t.mass / 3
        rows["x"] = (Ma, ka, v["mu"] / rhoA * (Ma - m_h))
        rows["y"] = rows["z"] = (M, k, v["mu"] / rhoA * (M - m_h))
        info = {"body": "analytic: tube (exact annulus, shear) + holder point mass; rod along the axis"}
    dirs = SETUP[probe.name]["dirs"]
    J = np.diag([rows[d][0] for d in dirs])
    K2 = np.diag([rows[d][1] for d in dirs])
    C2 = np.diag([rows[d][2] for d in dirs])
    return J, K2, C2, info


_FEM_BODIES: dict[tuple, tuple] = {}
_TIP_KEYS = ("tip", "tip_mass", "k_tx", "k_ty", "k_tz")


def fem_body(probe, v: dict[str, Any], n_body: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """(J, K2, C2, info) of the lumped model assembled from the FEM body modes
    (:func:`probedyn.lumped.smart.reduce_from_fem`, the holder end face as reference point).
    The body does not depend on the tip (mass, holder springs), so one FEM solve per probe
    geometry is kept for the process (sweeps over k_t reuse it)."""
    key = (probe.name, n_body, tuple(sorted((k, x) for k, x in v.items() if k not in _TIP_KEYS)))
    if key not in _FEM_BODIES:
        _FEM_BODIES[key] = _fem_body(probe, v, n_body)
    J, K2, C2, info = _FEM_BODIES[key]
    return J.copy(), K2.copy(), C2.copy(), dict(info)


def _fem_body(probe, v: dict[str, Any], n_body: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    from probedyn.lumped.smart import PROBE_SETUP, _body_rho_A, reduce_from_fem

    vv = {**v, "tip": "lumped"}
    model = probe.build(vv)
    setup = PROBE_SETUP[probe.name]
    lm = reduce_from_fem(model, setup["directions"], model.lumped_tip.attach, mu=vv["mu"],
                         rho_A=_body_rho_A(probe, vv), body_regions=setup["body"], n_body=n_body, residual=False)
    desc = model.describe() if hasattr(model, "describe") else {}
    info = {"body": "FEM lumped model (lumped/smart.py reduce_from_fem): first body mode per direction at the holder end face",
            "body_modes": lm.body_modes, "validity_hz": lm.second_body_hz, "dofs": desc.get("dofs")}
    return lm.J, lm.K2, lm.C2, info


def stroke_matrix(probe, v: dict[str, Any], holder_face: bool) -> tuple[np.ndarray, dict[str, Any]]:
    """Analytic free stroke per volt G [m/V] at the holder (end face if ``holder_face`` and the
    holder is meshed, else the beam/tube end) and its provenance."""
    d31 = preset(SETUP[probe.name]["table"])["d31"]
    L_h = v["holder_length"] if (holder_face and v.get("holder") == "meshed") else 0.0
    if probe.name == "duo-bimorph":
        s = act.duo_bimorph_strokes(v["length"], v["width"], v["electrode_gap"], v["thickness"], d31)
        f = act.holder_factor(v["length"], L_h)
        G = np.diag([s["y"] * f, s["z"] * f])
        src = "analytic gains: duo-bimorph (3.31), (3.32) as printed (piezo-moment derivation)"
    else:
        G = act.eccentric_tube_stroke(v["Re"], v["Ri"], v["length"], d31, v["delta_y"], v["delta_z"], L_h)
        src = ("analytic gains: tube axial (3.35), lateral (3.34) with its factor 2 removed (exact annulus, "
               "SOURCE-NOTES 8), eccentricity from the free piezo strain on the eccentric annulus (3.38-3.44 corrected)")
    return G, {"gains": src, "d31": d31, "holder_length_in_stroke": L_h}


def smart_plant(name: str, overrides: dict[str, Any] | None = None, *, body: str = "analytic", k_t: float | None = None,
                tip_q: float = 100.0, gains: np.ndarray | None = None, gains_source: str | None = None) -> MechanicalPlant:
    """The two-body tracking plant (3.37) of ``duo-bimorph`` or ``piezotube``.

    ``body = "analytic" | "fem"`` selects J, K2, C2; ``k_t`` overrides the holder spring in every
    modelled direction (section 3.4.1); ``tip_q``: quality factor of the tip on its spring (tip
    damping ``c = sqrt(k_t m) / Q``, an assumption: Tables 3.1/3.2 give none); ``gains``: a stroke
    matrix G [m/V] to use instead of the analytic one (e.g. from the piezo FEM), with
    ``gains_source`` naming it - the one-line swap."""
    probe, v = _probe_values(name, overrides)
    dirs, inputs = SETUP[probe.name]["dirs"], SETUP[probe.name]["inputs"]
    if body == "analytic":
        J, K2, C2, info = analytic_body(probe, v)
        holder_face = False
    elif body == "fem":
        J, K2, C2, info = fem_body(probe, v)
        holder_face = True
    else:
        raise ParameterError(f"body must be 'analytic' or 'fem', got {body!r}")
    if gains is None:
        G, ginfo = stroke_matrix(probe, v, holder_face)
    else:
        G = np.asarray(gains, dtype=float)
        if G.shape != (len(dirs), len(inputs)):
            raise ParameterError(f"gains must be a ({len(dirs)}, {len(inputs)}) stroke matrix [m/V]")
        ginfo = {"gains": gains_source or "user-supplied stroke matrix"}
    if not (math.isfinite(tip_q) and tip_q > 0):
        raise ParameterError(f"tip quality factor must be positive, got {tip_q:g}")
    m = float(v["tip_mass"])
    kt = np.array([float(k_t) if k_t is not None else float(v[f"k_t{d}"]) for d in dirs])
    if np.any(~np.isfinite(kt)) or np.any(kt <= 0):
        raise ParameterError(f"holder stiffness must be positive, got {kt}")
    D = m * np.eye(len(dirs))
    K1 = np.diag(kt)
    C1 = np.diag(np.sqrt(kt * m) / tip_q)
    Gamma = K2 @ G
    prov = {"probe": probe.name, **info, **ginfo, "tip_mass": m, "k_t": kt, "tip_q": tip_q,
            "parameters": {k: v[k] for k in v if isinstance(v[k], (int, float, str))}}
    p = two_body_plant(D, C1, K1, J, C2, K2, Gamma, dirs, inputs, prov)
    p.blocks["G"] = G
    return p
