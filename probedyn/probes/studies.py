"""Studies of the smart probes (sections 3.4.1, 3.5.1; departure 5): each resolves a
probe of the registry by name, builds its FE model, solves it and hands the probe's own
declaration (directions, direction groups, body regions, ``rho A``: :class:`SmartProbe`) to
the reductions and references of :mod:`probedyn.lumped.smart`. Used by ``probedyn smart-*``,
``probedyn localisation``, ``probedyn eccentricity`` and the report.

What is reused instead of re-solved (docs/fem.md, "Studies: reuse", has the measured errors):

* **Same model, same answer**: :func:`solve_modes` keeps the last few solved models by the
  probe and *all* its resolved values (a small LRU in this process); the body + holder model
  (``tip = none``, the default material and holder mass) is shared by the mode panel, the
  references, the materials and the holder-mass studies and by the lumped reduction's body modes.
  A request for fewer modes than stored is served from the stored ones (the lowest modes do not
  depend on how many are asked for).
* **Same matrix, one factorisation** (:func:`probedyn.fem.eigen.reuse_factorizations`): the static
  stiffnesses of the lumped reduction reuse the factorisation of ``K``; the two holder masses of
  :func:`study_holder_mass` change only ``M``, so the shift-invert operator ``K^-1`` is
  factorised once.
* **Only a spring changes** (:func:`study_localisation`): the holder spring ``k_t`` sweep runs on a
  Rayleigh-Ritz model of the assembled probe (:class:`probedyn.lumped.ritz.RitzBasis`: its lowest
  modes at the smallest stiffness of the sweep plus static correction shapes for loads at the
  holder end face and at the tip, low-rank spring updates between them), checked against a full
  FEM re-solve at the largest stiffness; if the check fails its tolerance the sweep falls back
  to full re-solves.  The result states the reuse and the measured error.
"""

from __future__ import annotations

import json
import math
import time
from collections import OrderedDict
from typing import Any, Sequence

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.io import to_jsonable
from probedyn.fem.augmented import LumpedTip
from probedyn.fem.eigen import reuse_factorizations
from probedyn.fem.modes import ModalResult
from probedyn.lumped.ritz import LUMPED_TIP, RitzBasis
from probedyn.lumped.smart import (AX, beamlike, compare_lumped_fem, holder_displacements, localisation_sweep,
                                   observed_order, reduce_from_fem)
from probedyn.lumped.smart_analytic import EccentricSection
from probedyn.probes import get_probe
from probedyn.probes._smart import SmartProbe

#: solved models kept by :func:`solve_modes` (each holds its mesh, matrices and mode shapes)
MEMO_SIZE = 6
#: at least this many modes are solved for a memoised model (the studies ask for 4 to 8; a
#: block of the eigen-solver costs little more for 8 than for 4)
MEMO_MIN_MODES = 8
_MEMO: "OrderedDict[str, ModalResult]" = OrderedDict()

#: relative frequency error accepted for the reduced (Ritz) holder-stiffness sweep, checked
#: against a full FEM solve at the stiffest holder spring; far below the 0.1-0.3 % mesh error
RITZ_TOL = 1e-5


def _values_key(probe: SmartProbe, values: dict[str, Any]) -> str:
    return probe.key + json.dumps(to_jsonable(values), sort_keys=True)


def solve_modes(probe, values: dict[str, Any], n_modes: int) -> ModalResult:
    """The lowest ``n_modes`` modes of ``probe.build(values)``, memoised (module docstring)."""
    key = _values_key(probe, values)
    hit = _MEMO.get(key)
    if hit is None or len(hit.modes) < n_modes:
        hit = probe.build(values).modes(max(int(n_modes), MEMO_MIN_MODES))
        _MEMO[key] = hit
        while len(_MEMO) > MEMO_SIZE:
            _MEMO.popitem(last=False)
    _MEMO.move_to_end(key)
    if len(hit.modes) == n_modes:
        return hit
    return ModalResult(hit.modes[:n_modes], hit.dofs, hit.model, dict(hit.timings), hit.total_dofs, hit.solver,
                       hit.total_mass, hit.tip_point)


def clear_memo() -> None:
    """Forget the memoised models of :func:`solve_modes`."""
    _MEMO.clear()


def smart_probe(name: str, overrides: dict[str, Any] | None = None) -> tuple[SmartProbe, dict[str, Any]]:
    """A smart probe of the registry (by key or TOML file) and its resolved values."""
    p, file_ov = get_probe(name)
    if not isinstance(p, SmartProbe):
        raise ParameterError(f"'{p.key}' is not a smart probe (a probe with a holder and a lumped tip: "
                             f"duo-bimorph or piezotube)")
    return p, p.resolve({**file_ov, **(overrides or {})})


def study_lumped(name: str, overrides: dict[str, Any] | None = None, n_modes: int = 10) -> dict[str, Any]:
    """Lumped model from FEM body modes vs FEM of the assembled probe (tip lumped)."""
    p, v = smart_probe(name, {**(overrides or {}), "tip": "lumped"})
    model = p.build(v)
    attach = model.lumped_tip.attach
    # the body modes are those of the same probe without a tip (a shared, memoised model)
    body = solve_modes(p, {**v, "tip": "none"}, 8)
    with reuse_factorizations():  # the static stiffnesses (one per direction) share K's factorisation
        lm = reduce_from_fem(model, p.lumped_directions, attach, mu=v["mu"], rho_A=p.body_rho_A(v),
                             body_regions=p.body_regions, n_body=8, body_result=_rebind(body, model))
    res = model.modes(n_modes)
    rows = compare_lumped_fem(model, lm, res, attach, p.direction_groups)
    return {"probe": p.key, "values": v, "lumped": lm.to_dict(), "rows": rows, "fem": res}


def study_localisation(name: str, stiffnesses: Sequence[float], overrides: dict[str, Any] | None = None,
                       n_modes: int = 4, reduced: bool = True) -> dict[str, Any]:
    """Section 3.4.1: FEM over holder stiffness (the holder springs in the lateral/vertical
    directions of the probe are set to k; the tip stays lumped). ``reduced``: solve the sweep
    on a Ritz model checked against a full solve at the largest k (module docstring); the
    result's ``reuse`` says what was done and the measured error."""
    p, v = smart_probe(name, {**(overrides or {}), "tip": "lumped"})
    model = p.build(v)
    ks = [float(k) for k in stiffnesses]
    if not ks:
        raise ParameterError("the holder-stiffness sweep needs at least one stiffness")
    if not reduced or len(ks) < 3:
        rows = localisation_sweep(model, ks, p.sweep_directions, n_modes, p.body_regions, p.direction_groups)
        return {"probe": p.key, "values": v, "rows": rows, "reuse": "none (full FEM solve per stiffness)"}
    t0 = time.perf_counter()
    solver, check = _ritz_sweep(model, ks, p.sweep_directions, n_modes)
    rows = localisation_sweep(model, ks, p.sweep_directions, n_modes, p.body_regions, p.direction_groups, solve=solver)
    check["seconds"] = time.perf_counter() - t0
    if check["max_rel_error"] > RITZ_TOL:  # the reduced model is not good enough: re-solve in full
        rows = localisation_sweep(model, ks, p.sweep_directions, n_modes, p.body_regions, p.direction_groups)
        check["fallback"] = "full FEM solve per stiffness"
    return {"probe": p.key, "values": v, "rows": rows, "reuse": check}


def _rebind(result: ModalResult, model) -> ModalResult:
    """``result`` (modes of an identical model) attached to ``model`` (same mesh and DOFs)."""
    if result.model is model:
        return result
    if result.model.ndofs_total != model.ndofs_total:
        raise SolverError("internal: memoised modes do not belong to this mesh")
    return ModalResult(result.modes, result.dofs, model, dict(result.timings), result.total_dofs, result.solver,
                       result.total_mass, result.tip_point)


def _ritz_sweep(model, ks: Sequence[float], directions: Sequence[str], n_modes: int):
    """A solver for :func:`probedyn.lumped.smart.localisation_sweep` on a Ritz model of the
    assembled probe (module docstring) and the check of the reduced frequencies against a full
    FEM solve at the largest stiffness: (solve(model, n), check dict)."""
    lt0 = model.lumped_tip
    attach = lt0.attach
    base = list(lt0.stiffness)
    for d in directions:
        base[AX[d]] = min(base[AX[d]], min(ks))
    n_basis = max(2 * n_modes, n_modes + 6)
    model.lumped_tip = LumpedTip(lt0.mass, tuple(base), attach)
    try:
        with reuse_factorizations():  # the static shapes use the factorisation of the modes' solve
            rb = RitzBasis.from_model(model, n_basis, attachments=[(LUMPED_TIP, "xyz"), (attach, "xyz")])
    finally:
        model.lumped_tip = lt0
    Ka, Ma, free, A = model.augmented()
    nf = free.size
    T = np.vstack([rb.T[free], rb.T[model.ndofs_total:]])  # basis in the augmented unknowns

    def solve(m, n):
        dk = np.asarray(m.lumped_tip.stiffness, dtype=float) - np.asarray(base)
        if np.any(dk < -1e-12 * np.abs(base).max()):
            raise SolverError("internal: the reduced holder sweep needs stiffnesses above its base")
        springs = [(attach, LUMPED_TIP, float(dk[c]), np.eye(3)[c]) for c in range(3) if dk[c] > 0]
        sol = rb.solve(springs=springs, n=n)
        return m.result_from(sol.omega ** 2, T @ sol.shapes, {"reduced_r": rb.r}, f"ritz(r={rb.r})")

    # the check: a full FEM solve at the stiffest spring of the sweep
    kmax = list(lt0.stiffness)
    for d in directions:
        kmax[AX[d]] = max(ks)
    model.lumped_tip = LumpedTip(lt0.mass, tuple(kmax), attach)
    try:
        full = model.modes(n_modes)
        red = solve(model, n_modes)
    finally:
        model.lumped_tip = lt0
    err = np.abs(red.frequencies_hz / full.frequencies_hz - 1)
    return solve, {"method": f"Ritz: {rb.n_modes} modes at k = {min(ks):g} N/m + {rb.r - rb.n_modes} static shapes "
                             f"(holder end face, tip), holder spring as a low-rank update",
                   "r": rb.r, "checked_at_k": max(ks), "max_rel_error": float(err.max()),
                   "rel_errors": err.tolist(), "tolerance": RITZ_TOL}


def study_materials(name: str, overrides: dict[str, Any] | None = None, n_modes: int = 4) -> dict[str, Any]:
    """First modes with transversely isotropic PZT-5H and with the isotropic E = 1/s11 option."""
    out = {}
    for mat in ("pzt-5h", "pzt-5h-iso"):
        p, v = smart_probe(name, {**(overrides or {}), "material": mat})
        out[mat] = solve_modes(p, v, n_modes)
    rows = []
    for a, b in zip(out["pzt-5h"].modes, out["pzt-5h-iso"].modes):
        rows.append({"mode": a.index, "family": a.family, "aniso_hz": a.frequency_hz, "iso_hz": b.frequency_hz,
                     "family_iso": b.family, "rel_diff": (b.frequency_hz - a.frequency_hz) / a.frequency_hz})
    return {"probe": name, "rows": rows}


def study_convergence(name: str, sizes: Sequence[float], overrides: dict[str, Any] | None = None,
                      n_modes: int = 4) -> dict[str, Any]:
    """First ``n_modes`` frequencies on meshes with element sizes ``sizes`` (constant ratio),
    observed order and extrapolated values per mode."""
    levels = []
    for s in sizes:
        p, v = smart_probe(name, {**(overrides or {}), "element_size": s})
        t0 = time.perf_counter()
        model = p.build(v)
        res = model.modes(n_modes)
        levels.append({"element_size": s, "dofs": res.dofs, "seconds": time.perf_counter() - t0,
                       "frequencies_hz": [m.frequency_hz for m in res.modes],
                       "families": [m.family for m in res.modes]})
    ratio = sizes[0] / sizes[1]
    modes = []
    if len(levels) >= 3:
        for i in range(n_modes):
            f = [lv["frequencies_hz"][i] for lv in levels]
            p_, fx = observed_order(f, ratio)
            modes.append({"mode": i + 1, "family": levels[-1]["families"][i], "f_finest_hz": f[-1],
                          "f_extrapolated_hz": fx, "observed_order": p_,
                          "rel_change_last": (f[-1] - f[-2]) / f[-1]})
    return {"probe": name, "levels": levels, "ratio": ratio, "modes": modes}


def study_eccentricity(deltas: Sequence[float], angle_deg: float = 45.0, overrides: dict[str, Any] | None = None,
                       probe: str = "piezotube", n_modes: int = 4) -> dict[str, Any]:
    """Piezotube with its bore offset by ``delta`` along ``angle_deg`` (from +y towards +z; the
    source's delta_x = delta_y case is 45 degrees, |offset| = sqrt(2) delta there... here
    ``delta`` is the magnitude of the offset). For each delta: the lateral pair (f_low,
    f_high), its split, the direction of the lower mode (holder end face motion), the
    Euler-Bernoulli prediction of both from the exact eccentric section, and the lateral
    stiffness coupling ``K_yz / sqrt(K_yy K_zz)`` of the 2x2 lumped lateral model in the
    electrode axes, and the axial-lateral coupling ``|K_x,lat| / sqrt(K_xx K_lat)`` of the 3x3
    model (lateral pair + axial mode) at the holder end face: the section's centroid moves by
    ``A_i delta / A`` off the axis, so an axial load on the holder bends the tube (the FEM
    counterparts of the off-diagonal terms of Gamma, eqs 3.38-3.44)."""
    rows = []
    a = math.radians(angle_deg)
    for d in deltas:
        dy, dz = d * math.cos(a), d * math.sin(a)
        p, v = smart_probe(probe, {**(overrides or {}), "delta_y": dy, "delta_z": dz, "tip": "none"})
        if not hasattr(p, "tube"):
            raise ParameterError(f"the eccentricity study needs a tube probe (piezotube), not '{p.key}'")
        res = solve_modes(p, v, n_modes)  # delta = 0 is the memoised body + holder model
        model = res.model
        lat = [i for i, m in enumerate(res.modes) if beamlike(m) and m.family != "axial"][:2]
        ax = [i for i, m in enumerate(res.modes) if m.family == "axial"][:1]
        if len(lat) < 2:
            raise SolverError("eccentricity: the lateral pair was not found among the lowest modes")
        uh_all = holder_displacements(model, res, "holder_end")
        uh = uh_all[lat][:, 1:]
        f = np.array([res.modes[i].frequency_hz for i in lat])
        ang = math.degrees(math.atan2(uh[0, 1], uh[0, 0])) % 180.0
        Ui = np.linalg.inv(uh.T)  # rows: directions y, z; columns: modes
        K2 = Ui.T @ np.diag((2 * np.pi * f) ** 2) @ Ui
        c_xl = float("nan")
        if ax:  # 3x3 (x, y, z) stiffness at the holder from the pair + the axial mode
            idx = ax + lat
            U3 = uh_all[idx].T
            U3i = np.linalg.inv(U3)
            K3 = U3i.T @ np.diag([res.modes[i].omega ** 2 for i in idx]) @ U3i
            c_xl = float(math.hypot(K3[0, 1], K3[0, 2]) / math.sqrt(K3[0, 0] * 0.5 * (K3[1, 1] + K3[2, 2])))
        sec = EccentricSection(v["Re"], v["Ri"], dy, dz)
        A_i, A = math.pi * v["Ri"] ** 2, math.pi * (v["Re"] ** 2 - v["Ri"] ** 2)
        split = f[1] / f[0] - 1
        rows.append({"delta": d, "delta_y": dy, "delta_z": dz, "f_low_hz": f[0], "f_high_hz": f[1],
                     "split": split, "split_predicted": sec.frequency_split(),
                     "angle_low_deg": ang if d > 0 else None, "angle_predicted_deg": sec.lower_mode_angle_deg() if d > 0 else None,
                     "coupling_yz": float(K2[0, 1] / math.sqrt(K2[0, 0] * K2[1, 1])),
                     "coupling_axial_lateral": c_xl, "centroid_offset": A_i * d / A,
                     "families": [m.family for m in res.modes]})
    return {"angle_deg": angle_deg, "rows": rows}


def study_holder_mass(name: str, overrides: dict[str, Any] | None = None, n_modes: int = 4) -> dict[str, Any]:
    """departure 5: the first modes of body + holder (no tip) with the holder mass of
    the table (m_h) and with the mass of the holder geometry."""
    out, masses = {}, {}
    with reuse_factorizations():  # only the holder's density (M) differs: K is factorised once
        for src in ("table", "geometry"):
            p, v = smart_probe(name, {**(overrides or {}), "holder_mass_source": src, "tip": "none"})
            out[src] = solve_modes(p, v, n_modes)
            masses[src] = p.holder_mass(v)
    rows = []
    for a, b in zip(out["table"].modes, out["geometry"].modes):
        rows.append({"mode": a.index, "family_table": a.family, "table_hz": a.frequency_hz,
                     "family_geometry": b.family, "geometry_hz": b.frequency_hz, "ratio": b.frequency_hz / a.frequency_hz})
    return {"probe": name, "holder_mass": masses, "rows": rows}
