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
# the smart probes' two-body plant from plain data (the probe-dependent parts - resolving a
# probe, its FEM body, its analytic strokes - live in probedyn/probes/tracking.py)
# ---------------------------------------------------------------------------------------------

SETUP = {"duo-bimorph": {"dirs": ["y", "z"], "inputs": ["V_y", "V_z"], "table": "table-3.1"},
         "piezotube": {"dirs": ["x", "y", "z"], "inputs": ["V_x", "V_y", "V_z"], "table": "table-3.2"}}


def smart_two_body(J: np.ndarray, K2: np.ndarray, C2: np.ndarray, G: np.ndarray, tip_mass: float, k_t: Sequence[float],
                   dirs: Sequence[str], inputs: Sequence[str], tip_q: float = 100.0,
                   provenance: dict[str, Any] | None = None) -> MechanicalPlant:
    """The two-body plant (3.37) from the body at the holder (J, K2, C2), the free stroke matrix
    G [m/V] at the holder, the tip mass and holder springs ``k_t`` (one per direction) and the tip
    quality factor ``tip_q`` (tip damping ``c = sqrt(k_t m) / Q``; an assumption: the source's
    tables give none). ``Gamma = K2 G``."""
    if not (math.isfinite(tip_q) and tip_q > 0):
        raise ParameterError(f"tip quality factor must be positive, got {tip_q:g}")
    m = float(tip_mass)
    kt = np.asarray(k_t, dtype=float)
    if kt.shape != (len(dirs),) or np.any(~np.isfinite(kt)) or np.any(kt <= 0):
        raise ParameterError(f"holder stiffness must be {len(dirs)} positive values, got {k_t}")
    G = np.asarray(G, dtype=float)
    if G.shape != (len(dirs), len(inputs)):
        raise ParameterError(f"the stroke matrix must be ({len(dirs)}, {len(inputs)}) [m/V], got {G.shape}")
    D = m * np.eye(len(dirs))
    K1 = np.diag(kt)
    C1 = np.diag(np.sqrt(kt * m) / tip_q)
    prov = {**(provenance or {}), "tip_mass": m, "k_t": kt, "tip_q": tip_q}
    p = two_body_plant(D, C1, K1, J, C2, K2, K2 @ G, dirs, inputs, prov)
    p.blocks["G"] = G
    return p


def modal_body_plant(omega: np.ndarray, zeta: np.ndarray, Phi: np.ndarray, actuation: np.ndarray, tip_mass: float,
                     k_t: Sequence[float], dirs: Sequence[str], inputs: Sequence[str], tip_q: float = 100.0,
                     provenance: dict[str, Any] | None = None) -> MechanicalPlant:
    """A body with any number r of retained modes (a reduced probe: several modes per direction)
    carrying the tip on the holder springs. Modal coordinates ``eta`` (mass-normalised modes,
    ``omega`` [rad/s], damping ratios ``zeta``), holder displacement ``Phi eta`` (``Phi``: (d, r)
    participation of each mode at the holder point along ``dirs``), modal force per volt
    ``actuation`` (r, n_in) [N/V]; ``q = [q_tip (d); eta (r)]``::

        M = [[m I, 0], [0, I]],  K = [[Kt, -Kt Phi], [-Phi^T Kt, Omega^2 + Phi^T Kt Phi]],
        C = [[C1, 0], [0, diag(2 zeta omega)]],  B = [[0], [actuation]].

    With r = d modes and ``Phi = U`` this is the two-body model (3.37) in other coordinates
    (``J = U^-T U^-1``, ``K2 = U^-T Omega^2 U^-1``). Controllers are designed on a two-body model
    and may drive this plant (the retained higher modes are then unmodelled dynamics); the open
    loop uses the frequency-domain inverse."""
    omega = np.asarray(omega, dtype=float)
    zeta = np.broadcast_to(np.asarray(zeta, dtype=float), omega.shape)
    Phi = np.asarray(Phi, dtype=float)
    Act = np.asarray(actuation, dtype=float)
    r, d = omega.size, len(dirs)
    if Phi.shape != (d, r) or Act.shape != (r, len(inputs)):
        raise ParameterError(f"modal plant: Phi must be ({d}, {r}) and actuation ({r}, {len(inputs)})")
    if np.any(~np.isfinite(omega)) or np.any(omega <= 0):
        raise ParameterError("modal plant: natural frequencies must be positive")
    kt = np.asarray(k_t, dtype=float)
    if kt.shape != (d,) or np.any(kt <= 0):
        raise ParameterError(f"holder stiffness must be {d} positive values, got {k_t}")
    m = float(tip_mass)
    Kt = np.diag(kt)
    M = np.block([[m * np.eye(d), np.zeros((d, r))], [np.zeros((r, d)), np.eye(r)]])
    K = np.block([[Kt, -Kt @ Phi], [-Phi.T @ Kt, np.diag(omega**2) + Phi.T @ Kt @ Phi]])
    C = np.block([[np.diag(np.sqrt(kt * m) / tip_q), np.zeros((d, r))], [np.zeros((r, d)), np.diag(2 * zeta * omega)]])
    B = np.vstack([np.zeros((d, Act.shape[1])), Act])
    Cq = np.hstack([np.eye(d), np.zeros((d, r))])
    prov = {**(provenance or {}), "tip_mass": m, "k_t": kt, "tip_q": tip_q, "retained_modes": r}
    return MechanicalPlant(M, C, K, B, Cq, list(dirs), list(inputs), None, prov, {})
