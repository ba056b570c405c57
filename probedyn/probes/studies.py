"""Studies of the smart probes (sections 3.4.1, 3.5.1; departure 5): each resolves a
probe of the registry by name, builds its FE model, solves it and hands the probe's own
declaration (directions, direction groups, body regions, ``rho A``: :class:`SmartProbe`) to
the reductions and references of :mod:`probedyn.lumped.smart`. Used by ``probedyn smart-*``,
``probedyn localisation``, ``probedyn eccentricity`` and the report.
"""

from __future__ import annotations

import math
import time
from typing import Any, Sequence

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.lumped.smart import (compare_lumped_fem, holder_displacements, localisation_sweep, observed_order,
                                   reduce_from_fem)
from probedyn.lumped.smart_analytic import EccentricSection
from probedyn.probes import get_probe
from probedyn.probes._smart import SmartProbe


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
    lm = reduce_from_fem(model, p.lumped_directions, attach, mu=v["mu"], rho_A=p.body_rho_A(v),
                         body_regions=p.body_regions, n_body=8)
    res = model.modes(n_modes)
    rows = compare_lumped_fem(model, lm, res, attach, p.direction_groups)
    return {"probe": p.key, "values": v, "lumped": lm.to_dict(), "rows": rows, "fem": res}


def study_localisation(name: str, stiffnesses: Sequence[float], overrides: dict[str, Any] | None = None,
                       n_modes: int = 4) -> dict[str, Any]:
    """Section 3.4.1: FEM over holder stiffness (the holder springs in the lateral/vertical
    directions of the probe are set to k; the tip stays lumped)."""
    p, v = smart_probe(name, {**(overrides or {}), "tip": "lumped"})
    model = p.build(v)
    rows = localisation_sweep(model, stiffnesses, p.sweep_directions, n_modes, p.body_regions, p.direction_groups)
    return {"probe": p.key, "values": v, "rows": rows}


def study_materials(name: str, overrides: dict[str, Any] | None = None, n_modes: int = 4) -> dict[str, Any]:
    """First modes with transversely isotropic PZT-5H and with the isotropic E = 1/s11 option."""
    out = {}
    for mat in ("pzt-5h", "pzt-5h-iso"):
        p, v = smart_probe(name, {**(overrides or {}), "material": mat})
        res = p.build(v).modes(n_modes)
        out[mat] = res
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
        model = p.build(v)
        res = model.modes(n_modes)
        lat = [i for i, m in enumerate(res.modes) if m.family in ("lateral", "flapwise")][:2]
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
    for src in ("table", "geometry"):
        p, v = smart_probe(name, {**(overrides or {}), "holder_mass_source": src, "tip": "none"})
        out[src] = p.build(v).modes(n_modes)
        masses[src] = p.holder_mass(v)
    rows = []
    for a, b in zip(out["table"].modes, out["geometry"].modes):
        rows.append({"mode": a.index, "family_table": a.family, "table_hz": a.frequency_hz,
                     "family_geometry": b.family, "geometry_hz": b.frequency_hz, "ratio": b.frequency_hz / a.frequency_hz})
    return {"probe": name, "holder_mass": masses, "rows": rows}
