"""Path tracking on a reduced probe (issue 10 item 3, with the piezo FEM of issue 12).

A smart probe's body (PZT beam or tube + holder, **without** the tip: the tracking plant carries
the tip on its holder springs, eq 3.37) is reduced at the holder point (the holder's end face for
a meshed holder, else the actuator's end) by :func:`probedyn.lumped.reduced.reduce_model`, on
the very mechanical model of the coupled piezoelectric FEM (:func:`probedyn.probes.piezo.piezo_model`),
and its actuation is filled from that FEM:

* ``actuation`` = modal force per volt of each retained mode and electrode,
  ``f_i,e = omega_i^2 phi_i^T M u_e`` (:func:`probedyn.probes.piezo.fill_reduced_actuation`,
  u_e the coupled static displacement per volt);
* ``actuation_static`` = ``t_j^T K u_e`` on the Ritz basis's static pseudo-modes ``t_j``
  (the static shapes of unit loads at the holder point, M-orthogonalised to the modes). Because
  ``K^-1 A^T d`` lies in the basis, the reduced static response at the holder,
  ``A T (T^T K T)^-1 T^T K u_e``, equals ``A u_e`` exactly (reciprocity): the static correction
  of the actuation.

The reduction with its actuation is cached like every reduced probe (``$PROBEDYN_CACHE/reduced``)
and saved/loaded with it (``ReducedProbe.save``/``load``).

Plants (:mod:`probedyn.schemes.tracking.plants`):

* :func:`reduced_modal_plant` - every Ritz coordinate of the reduced body (N modes, plus the static
  pseudo-modes when ``static_correction``) on the holder springs (``modal_body_plant``): its
  static tip stroke per volt is the piezo FEM's (exactly with the static correction; within the
  truncation bound ``sqrt(R_dd E_res)`` without it, docs/reduced-probes.md section 9). Open-loop
  tracking (dynamic inverse in the frequency domain) runs on it;
* :func:`reduced_two_body_plant` - the two-body model (3.37) the controllers are designed on:
  the dominant mode per direction of the reduced body at the holder (``J = U^-T U^-1``,
  ``K2 = U^-T Omega^2 U^-1``) and the stroke matrix ``G`` of the reduced probe with its static
  correction (= the piezo FEM's), ``Gamma = K2 G``.

The tracking inputs are the drive patterns of :mod:`probedyn.probes.piezo`
(``probedyn.probes.tracking.INPUT_NAMES``), each input column signed so that its own axis moves
positively (as ``fem_stroke_matrix``).
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.lumped.reduced import ReducedProbe, reduce_model
from probedyn.probes import get_probe
from probedyn.probes.piezo import fill_reduced_actuation, piezo_model, piezo_setup, static_per_volt
from probedyn.probes.reduce import cache_root, cached_reduction, reduction_key, store_reduction
from probedyn.schemes.tracking.plants import AX, SETUP, MechanicalPlant, modal_body_plant, smart_two_body

#: tracking input -> drive pattern of probes/piezo.py (probes.tracking.INPUT_NAMES)
PATTERNS = {"duo-bimorph": {"V_y": "V_y", "V_z": "V_z"}, "piezotube": {"V_x": "V_z", "V_y": "V_y", "V_z": "V_x"}}
#: bump when the meaning of a cached actuated reduction changes
ACTUATED_VERSION = 1


def body_point(values: Mapping[str, Any], name: str) -> str:
    """The holder point of the tracking plant: the holder's end face (meshed holder) or the
    actuator's end face (point holder)."""
    if values.get("holder") == "meshed":
        return "holder_end"
    return "holder_end" if name == "duo-bimorph" else "tube_end"


def fill_actuation(rp: ReducedProbe, pm: Any) -> ReducedProbe:
    """Fill ``rp.actuation`` (retained modes, :func:`fill_reduced_actuation`) and
    ``rp.actuation_static`` (static pseudo-modes, ``t_j^T K u_e``) from the coupled model ``pm``
    whose mechanical model the reduction was made on."""
    fill_reduced_actuation(rp, pm)
    els = list(rp.actuation)
    K, M, free, n_extra = pm.mechanical_system()
    T = np.asarray(rp.ritz.T, dtype=float)
    ntot = pm.mech.ndofs_total
    if T.shape[0] == ntot + n_extra:
        T = np.vstack([T[free], T[ntot:]])
    Ts = T[:, rp.n_modes:]
    U = static_per_volt(pm, els)
    F = Ts.T @ (K @ U)
    rp.actuation_static = {e: [float(v) for v in F[:, j]] for j, e in enumerate(els)}
    # u_e^T K u_e = sum over ALL modes of f_i^2 / omega_i^2: what the truncation bound needs
    rp.provenance["actuation_energy"] = {e: float(U[:, j] @ (K @ U[:, j])) for j, e in enumerate(els)}
    return rp


def actuated_probe(name: str, overrides: Mapping[str, Any] | None = None, n_modes: int = 6,
                   cache: bool = True) -> ReducedProbe:
    """The reduced body of smart probe ``name`` (tip removed) at its holder point, with the piezo
    FEM's actuation; damping from the probe's environment damping ``mu`` (eq 3.2, body rho A).
    Cached under a content hash; ``provenance["cache"]`` says "hit" or "miss"."""
    t0 = time.perf_counter()
    if int(n_modes) != n_modes or n_modes < 1:
        raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
    p, file_ov = get_probe(name)
    if p.name not in SETUP:
        raise ParameterError(f"path tracking needs a smart probe (duo-bimorph or piezotube), got '{p.name}'")
    ov = {**file_ov, **dict(overrides or {}), "tip": "none"}
    values = p.resolve(ov)
    point = body_point(values, p.name)
    mu = float(values.get("mu", 0.0))
    key = reduction_key(p.name, values, point, int(n_modes), None, None, mu) + f"-act{ACTUATED_VERSION}"
    path = cache_root() / f"{p.name}-{key}.json"
    rp = cached_reduction(path, cache, t0, accept=lambda r: bool(r.actuation_static))
    if rp is not None:
        return rp
    _, _, pm, _ = piezo_model(p.name, ov)
    rhoA = float(p.body_rho_A(values))
    rp = reduce_model(pm.mech, point, n_modes=int(n_modes), mu=mu, mass_per_length=rhoA,
                      provenance=dict(probe=p.name, parameters={k: v for k, v in values.items()
                                                                if isinstance(v, (int, float, str)) or v is None},
                                      body="smart probe body without its tip (tip on the plant's holder springs)"))
    fill_actuation(rp, pm)
    store_reduction(rp, path, cache, t0)
    return rp


def _probe_name(rp: ReducedProbe) -> str:
    name = str(rp.provenance.get("probe", ""))
    if name not in SETUP:
        raise ParameterError(f"path tracking needs a reduced smart probe (duo-bimorph or piezotube), got {name or rp.source!r}")
    if rp.ritz is None or not rp.actuation:
        raise ParameterError("this reduced probe has no actuation: build it with probedyn.probes.reduced_tracking."
                             "actuated_probe (probedyn reduced-probe --actuation)")
    return name


def _damping_ratios(rp: ReducedProbe, omega: np.ndarray) -> np.ndarray:
    """Damping ratio of every Ritz coordinate: mass-proportional damping (eq 3.2, C = alpha M)
    stays diagonal in any M-orthonormal basis, zeta_j = alpha / (2 omega_j); Q: 1/(2Q)."""
    d = rp.damping or {}
    if d.get("kind", "").startswith("mu"):
        return (float(d["mu"]) / float(d["mass_per_length"])) / (2.0 * omega)
    if d.get("kind") == "Q":
        return np.full(omega.shape, 0.5 / float(d["Q"]))
    return np.zeros(omega.shape)


def input_matrix(rp: ReducedProbe, name: str, static_correction: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """(omega (r,), Phi (d, r) at the holder along the plant's axes, actuation (r, n_in) [N/V],
    inputs) of the reduced body; input columns signed so the static stroke matrix has a positive
    diagonal."""
    dirs, inputs = SETUP[name]["dirs"], SETUP[name]["inputs"]
    setup = piezo_setup(name)
    els = list(rp.actuation)
    P = np.array([[setup.pattern(None, PATTERNS[name][i]).get(e, 0.0) for i in inputs] for e in els])
    A = rp.actuation_matrix(els, static_correction) @ P
    r = A.shape[0]
    omega = np.sqrt(np.diag(rp.ritz.K))[:r]
    Phi = rp.ritz.operator(rp.point)[[AX[d] for d in dirs], :r]
    G = Phi @ (A / omega[:, None] ** 2)
    s = np.sign(np.diag(G))
    s[s == 0] = 1.0
    return omega, Phi, A * s[None, :], list(inputs)


def static_stroke(rp: ReducedProbe, static_correction: bool = True) -> np.ndarray:
    """Static holder (= tip) stroke per volt G [m/V] of the reduced body, (d, n_in):
    ``Phi Omega^-2 F``."""
    name = _probe_name(rp)
    omega, Phi, A, _ = input_matrix(rp, name, static_correction)
    return Phi @ (A / omega[:, None] ** 2)


def _tip(values: Mapping[str, Any], name: str, k_t: float | None) -> tuple[float, list[float]]:
    dirs = SETUP[name]["dirs"]
    return float(values["tip_mass"]), [float(k_t) if k_t is not None else float(values[f"k_t{d}"]) for d in dirs]


def reduced_modal_plant(rp: ReducedProbe, k_t: float | None = None, tip_q: float = 100.0,
                        static_correction: bool = True, overrides: Mapping[str, Any] | None = None) -> MechanicalPlant:
    """The reduced body (all its Ritz coordinates) carrying the tip on the holder springs
    (``modal_body_plant``); tip mass and springs from the probe's parameters (``overrides`` on
    top, e.g. ``tip_mass``), ``k_t`` in every direction if given."""
    name = _probe_name(rp)
    p, _ = get_probe(name)
    values = p.resolve({**rp.provenance.get("parameters", {}), **dict(overrides or {})})
    omega, Phi, A, inputs = input_matrix(rp, name, static_correction)
    m, kt = _tip(values, name, k_t)
    prov = {"probe": name, "body": f"reduced probe: {rp.n_modes} FEM modes"
            + (f" + {len(omega) - rp.n_modes} static pseudo-modes" if static_correction else "")
            + f" at '{rp.point}' ({rp.provenance.get('dofs')} DOFs)",
            "gains": "piezo FEM modal forces per volt (probes/reduced_tracking.py)"
            + (" with the static correction" if static_correction else ", modes only"),
            "reduced_probe": rp.summary(), "parameters": {k: v for k, v in values.items() if isinstance(v, (int, float, str))}}
    return modal_body_plant(omega, _damping_ratios(rp, omega), Phi, A, m, kt, SETUP[name]["dirs"], inputs, tip_q, prov)


def reduced_two_body_plant(rp: ReducedProbe, k_t: float | None = None, tip_q: float = 100.0,
                           overrides: Mapping[str, Any] | None = None, G: np.ndarray | None = None,
                           gains_source: str | None = None) -> MechanicalPlant:
    """The two-body model (3.37) of the reduced body: per plant direction the retained mode with
    the largest static-compliance share at the holder (``U`` = their holder displacements along
    the plant axes), ``J = U^-T U^-1``, ``K2 = U^-T Omega^2 U^-1``, ``C2 = U^-T 2 zeta Omega U^-1``,
    and ``Gamma = K2 G`` with ``G`` the reduced probe's static stroke per volt including the
    static correction (the piezo FEM's), or the stroke matrix ``G`` given (``gains_source``)."""
    name = _probe_name(rp)
    p, _ = get_probe(name)
    values = p.resolve({**rp.provenance.get("parameters", {}), **dict(overrides or {})})
    dirs, inputs = SETUP[name]["dirs"], SETUP[name]["inputs"]
    n = rp.n_modes
    omega = np.sqrt(np.diag(rp.ritz.K))[:n]
    Phi = rp.ritz.operator(rp.point)[[AX[d] for d in dirs], :n]
    share = Phi**2 / omega[None, :] ** 2
    chosen: list[int] = []
    for i in range(len(dirs)):
        order = [j for j in np.argsort(-share[i]) if j not in chosen]
        chosen.append(int(order[0]))
    U = Phi[:, chosen]
    if abs(np.linalg.det(U)) < 1e-12 * np.prod(np.linalg.norm(U, axis=0)):
        raise ParameterError("the dominant body modes at the holder are not independent along the plant axes")
    Ui = np.linalg.inv(U)
    w = omega[chosen]
    z = _damping_ratios(rp, w)
    J = Ui.T @ Ui
    K2 = Ui.T @ np.diag(w**2) @ Ui
    C2 = Ui.T @ np.diag(2 * z * w) @ Ui
    if G is None:
        G = static_stroke(rp, static_correction=True)
        gains_source = "piezo FEM stroke per volt of the reduced probe (modes + static correction)"
    G = np.asarray(G, dtype=float)
    m, kt = _tip(values, name, k_t)
    prov = {"probe": name, "body": f"reduced probe: dominant body mode per direction at '{rp.point}' "
            f"(modes {[c + 1 for c in chosen]}, {rp.provenance.get('dofs')} DOFs)",
            "gains": gains_source or "user-supplied stroke matrix", "reduced_probe": rp.summary(), "validity_hz": rp.validity_hz,
            "parameters": {k: v for k, v in values.items() if isinstance(v, (int, float, str))}}
    return smart_two_body(J, K2, C2, G, m, kt, dirs, inputs, tip_q, prov)


def truncation_bound(rp: ReducedProbe) -> np.ndarray:
    """Bound on the static stroke error of the modes-only plant, (d, n_in) [m/V]: by
    Cauchy-Schwarz over the discarded modes, ``|sum_{i>N} phi_i,d f_i / omega_i^2| <=
    sqrt(R_dd) sqrt(E_res)`` with ``R_dd`` the residual compliance of the holder point along d
    and ``E_res = u^T K u - sum_{i<=N} f_i^2/omega_i^2`` the actuation's static field energy not
    in the retained modes (``u^T K u = sum_all f_i^2/omega_i^2``)."""
    name = _probe_name(rp)
    dirs, inputs = SETUP[name]["dirs"], SETUP[name]["inputs"]
    setup = piezo_setup(name)
    els = list(rp.actuation)
    energy = rp.provenance.get("actuation_energy")
    if not energy:
        raise ParameterError("this reduced probe has no actuation energy (rebuild it with actuated_probe)")
    n = rp.n_modes
    omega = np.sqrt(np.diag(rp.ritz.K))[:n]
    Fm = rp.actuation_matrix(els, static_correction=False)
    # energies of patterns need the cross terms u_e^T K u_f: the pseudo-modes + modes span them
    # only partly, so bound per electrode and combine with the triangle inequality
    R = np.array([rp.ritz.static_compliance(rp.point)[AX[d], AX[d]] - float(np.sum(rp.ritz.operator(rp.point)[AX[d], :n] ** 2 / omega**2))
                  for d in dirs])
    Eres = np.array([max(float(energy[e]) - float(np.sum(Fm[:, j] ** 2 / omega**2)), 0.0) for j, e in enumerate(els)])
    per_e = np.sqrt(np.maximum(R, 0.0))[:, None] * np.sqrt(Eres)[None, :]
    P = np.array([[abs(setup.pattern(None, PATTERNS[name][i]).get(e, 0.0)) for i in inputs] for e in els])
    return per_e @ P


__all__ = ["actuated_probe", "fill_actuation", "reduced_modal_plant", "reduced_two_body_plant", "static_stroke",
           "truncation_bound", "body_point", "PATTERNS"]
