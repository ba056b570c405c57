"""Tracking plants of the smart probes: a probe (registry name or TOML) -> its two-body model
(3.37) for :mod:`probedyn.schemes.tracking`. This module composes the probe, its FEM body and
the analytic gains (the probes layer's job); the physics of the plant, the controllers and the
simulator are in ``schemes/tracking``.

* body (J, K2, C2 at the holder): ``analytic`` (beam or tube + the holder as a point mass,
  eqs 3.1-3.3) or ``fem`` (``lumped/smart.py: reduce_from_fem``, first body mode per direction
  at the holder end face; one FEM solve per geometry is cached for the process; with the piezo
  FEM's gains the body is built on the piezo FEM's element and mesh, ``piezo.coupled_values``,
  so that ``body="fem"`` and ``body="reduced"`` are one discretisation);
* gains: the analytic free stroke per volt (:mod:`probedyn.schemes.tracking.actuation`) at the
  holder (its end face for the FEM body, with the rigid holder's rotation), or a stroke matrix
  passed in (e.g. from the piezo FEM) - the one-line swap; ``provenance`` records which.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset
from probedyn.lumped.smart import reduce_from_fem
from probedyn.lumped.smart_analytic import end_body_first_mode_at
from probedyn.probes import get_probe
from probedyn.probes._smart import SmartProbe
from probedyn.fem.piezo_materials import get_piezo_material
from probedyn.probes.piezo import coupled_values, gamma_matrix_fem, piezo_model
from probedyn.schemes.tracking import actuation as act
from probedyn.schemes.tracking.plants import SETUP, MechanicalPlant, smart_two_body


def _probe_values(name: str, overrides: dict[str, Any] | None) -> tuple[SmartProbe, dict[str, Any]]:
    p, file_ov = get_probe(name)
    if not isinstance(p, SmartProbe) or p.name not in SETUP:
        raise ParameterError(f"path tracking needs a smart probe (duo-bimorph or piezotube), got '{p.name}'")
    return p, p.resolve({**file_ov, **(overrides or {})})


def analytic_body(probe, v: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """(J, K2, C2, info): one mode per direction, beam (or tube) + the holder as a point mass
    m_h at the end (eqs 3.1-3.3, 3.24/3.29 without rotary inertia): ``end_body_first_mode_at``
    (exact static end flexibility + one Hermite mass; tube with its Timoshenko shear
    compliance) for bending, the rod ``A/(s11 L)`` with ``m_h + m_rod/3`` along the tube axis.
    Damping (3.2): ``c = (mu / (rho A)) * (modal mass of the body without the holder)``."""
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


def _fem_body(probe: SmartProbe, v: dict[str, Any], n_body: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    vv = {**v, "tip": "lumped"}
    model = probe.build(vv)
    lm = reduce_from_fem(model, list(probe.lumped_directions), model.lumped_tip.attach, mu=vv["mu"],
                         rho_A=probe.body_rho_A(vv), body_regions=probe.body_regions, n_body=n_body, residual=False)
    if list(probe.lumped_directions) != SETUP[probe.name]["dirs"]:
        raise ParameterError(f"{probe.name}: lumped directions {probe.lumped_directions} differ from the tracking plant's")
    desc = model.describe() if hasattr(model, "describe") else {}
    info = {"body": "FEM lumped model (lumped/smart.py reduce_from_fem): first body mode per direction at the holder end face",
            "body_element": probe.element(vv), "body_modes": lm.body_modes, "validity_hz": lm.second_body_hz, "dofs": desc.get("dofs")}
    return lm.J, lm.K2, lm.C2, info


def stroke_matrix(probe: SmartProbe, v: dict[str, Any], holder_face: bool,
                  d31: float | None = None) -> tuple[np.ndarray, dict[str, Any]]:
    """Analytic free stroke per volt G [m/V] at the holder (end face if ``holder_face`` and the
    holder is meshed, else the beam/tube end) and its provenance. ``d31``: default the table's
    (Tables 3.1/3.2, |d31| = 185e-12 C/N); the piezo FEM uses the material's (-274e-12 C/N)."""
    d31 = preset(SETUP[probe.name]["table"])["d31"] if d31 is None else float(d31)
    L_h = v["holder_length"] if (holder_face and v.get("holder") == "meshed") else 0.0
    if probe.name == "duo-bimorph":
        s = act.duo_bimorph_strokes(v["length"], v["width"], v["electrode_gap"], v["thickness"], d31)
        f = act.holder_factor(v["length"], L_h)
        G = np.diag([s["y"] * f, s["z"] * f])
        src = "analytic gains: duo-bimorph (3.31), (3.32) (lumped.actuation.duo_bimorph_range)"
    else:
        G = act.eccentric_tube_stroke(v["Re"], v["Ri"], v["length"], d31, v["delta_y"], v["delta_z"], L_h)
        src = ("analytic gains: corrected 3.34/3.35 and eccentric tube 3.38-3.44 (lumped.actuation.gamma_matrix, "
               "departures 17, 21)")
    return G, {"gains": f"{src}, |d31| = {abs(d31):.4g} C/N", "d31": d31, "holder_length_in_stroke": L_h}


_FEM_GAINS: dict[tuple, tuple] = {}


def fem_stroke_matrix(probe: SmartProbe, v: dict[str, Any], holder_face: bool) -> tuple[np.ndarray, dict[str, Any]]:
    """Free stroke per volt G [m/V] from the coupled piezoelectric FEM (``probes/piezo.py``, the
    material's d31): the tube's ``gamma_matrix_fem`` (quarters) and the duo-bimorph's ``V_y``,
    ``V_z`` patterns, at the holder end face (meshed holder) or the actuator's end (point holder),
    columns signed so that the diagonal is positive. Cached per geometry for the process."""
    key = (probe.name, holder_face, tuple(sorted((k, x) for k, x in v.items() if k not in _TIP_KEYS)))
    if key not in _FEM_GAINS:
        ov = {k: x for k, x in v.items() if k not in _TIP_KEYS}
        ov["tip"] = "none"
        if probe.name == "piezotube":
            where = "holder_end" if (holder_face and v.get("holder") == "meshed") else "tube_end"
            g = gamma_matrix_fem(ov, where=where)
            G = act.to_probedyn(g)
            info = {"gains": f"piezo FEM gains ({g.source})", "gains_where": where}
        else:
            where = "holder_end"  # the holder's end face, or the beam's end face for a point holder
            if not holder_face:
                ov["holder"] = "point"
            _, _, pm, setup = piezo_model(probe.name, ov)
            res = pm.static_many([setup.pattern(None, "V_y"), setup.pattern(None, "V_z")], others="ground")
            G = np.array([[r.displacement_at(where)[i] for r in res] for i in (1, 2)])
            info = {"gains": f"piezo FEM gains (coupled P2 model, {res[0].dofs} DOFs, patterns V_y, V_z, face '{where}')",
                    "gains_where": where}
        G = G * np.sign(np.diag(G))[None, :]
        info["d31"] = float(get_piezo_material(v["material"]).d[2, 0])
        _FEM_GAINS[key] = (G, info)
    G, info = _FEM_GAINS[key]
    return G.copy(), dict(info)


def smart_plant(name: str, overrides: dict[str, Any] | None = None, *, body: str = "analytic", k_t: float | None = None,
                tip_q: float = 100.0, gains: str | np.ndarray = "analytic", gains_source: str | None = None,
                d31: float | None = None) -> MechanicalPlant:
    """The two-body tracking plant (3.37) of ``duo-bimorph`` or ``piezotube``.

    ``body = "analytic" | "fem" | "reduced" | "reduced-modal"`` selects J, K2, C2 (``reduced``: the
    two-body model of the probe's reduced body with the piezo FEM's actuation filled in,
    :mod:`probedyn.probes.reduced_tracking`; ``reduced-modal``: every Ritz coordinate of that
    reduced body, open loop only - its gains are the piezo FEM's, ``gains`` is ignored); ``k_t`` overrides the holder spring in every
    modelled direction (section 3.4.1); ``tip_q``: quality factor of the tip on its spring (tip
    damping ``c = sqrt(k_t m) / Q``, an assumption: Tables 3.1/3.2 give none); ``gains``:
    ``"analytic"`` (:func:`stroke_matrix`, ``d31`` default the table's), ``"fem"`` (the coupled
    piezo FEM, :func:`fem_stroke_matrix`) or a stroke matrix G [m/V] named by ``gains_source``."""
    probe, v = _probe_values(name, overrides)
    dirs, inputs = SETUP[probe.name]["dirs"], SETUP[probe.name]["inputs"]
    if body in ("reduced", "reduced-modal"):
        from probedyn.probes import reduced_tracking as rt  # composes piezo FEM + reduction (heavy)

        tip_ov = {k: x for k, x in (overrides or {}).items() if k in _TIP_KEYS}
        rp = rt.actuated_probe(name, {k: x for k, x in (overrides or {}).items() if k not in _TIP_KEYS})
        if body == "reduced-modal":
            return rt.reduced_modal_plant(rp, k_t=k_t, tip_q=tip_q, overrides=tip_ov)
        if isinstance(gains, str) and gains == "fem":
            return rt.reduced_two_body_plant(rp, k_t=k_t, tip_q=tip_q, overrides=tip_ov)
        if isinstance(gains, str) and gains == "analytic":
            G, ginfo = stroke_matrix(probe, v, True, d31)
            plant = rt.reduced_two_body_plant(rp, k_t=k_t, tip_q=tip_q, overrides=tip_ov, G=G, gains_source=ginfo["gains"])
            plant.provenance.update({k: x for k, x in ginfo.items() if k != "gains"})
            return plant
        if isinstance(gains, str):
            raise ParameterError(f"gains must be 'analytic', 'fem' or a stroke matrix, got {gains!r}")
        return rt.reduced_two_body_plant(rp, k_t=k_t, tip_q=tip_q, overrides=tip_ov, G=gains,
                                         gains_source=gains_source or "user-supplied stroke matrix")
    if body == "analytic":
        J, K2, C2, info = analytic_body(probe, v)
        holder_face = False
    elif body == "fem":
        # with the piezo FEM's gains the body is the piezo FEM's mechanical model (its element and
        # mesh): body and stroke from one discretisation, the reduced body's (reduced_tracking)
        fem_gains = isinstance(gains, str) and gains == "fem"
        J, K2, C2, info = fem_body(probe, coupled_values(v) if fem_gains else v)
        holder_face = True
    else:
        raise ParameterError(f"body must be 'analytic', 'fem', 'reduced' or 'reduced-modal', got {body!r}")
    if isinstance(gains, str) and gains == "analytic":
        G, ginfo = stroke_matrix(probe, v, holder_face, d31)
    elif isinstance(gains, str) and gains == "fem":
        G, ginfo = fem_stroke_matrix(probe, v, holder_face)
    elif isinstance(gains, str):
        raise ParameterError(f"gains must be 'analytic', 'fem' or a stroke matrix, got {gains!r}")
    else:
        G = np.asarray(gains, dtype=float)
        if G.shape != (len(dirs), len(inputs)):
            raise ParameterError(f"gains must be a ({len(dirs)}, {len(inputs)}) stroke matrix [m/V]")
        ginfo = {"gains": gains_source or "user-supplied stroke matrix"}
    kt = [float(k_t) if k_t is not None else float(v[f"k_t{d}"]) for d in dirs]
    prov = {"probe": probe.name, **info, **ginfo, "input_source_names": INPUT_NAMES[probe.name],
            "parameters": {k: v[k] for k in v if isinstance(v[k], (int, float, str))}}
    return smart_two_body(J, K2, C2, G, v["tip_mass"], kt, dirs, inputs, tip_q, prov)


def plant_factory(body: str = "analytic", tip_q: float = 100.0, gains: str = "analytic"):
    """A ``factory(probe, k_t=None, overrides=None) -> MechanicalPlant`` for the studies of
    :mod:`probedyn.schemes.tracking.studies` (``gains``: "analytic" or "fem")."""
    def factory(probe: str, k_t: float | None = None, overrides: dict[str, Any] | None = None) -> MechanicalPlant:
        return smart_plant(probe, overrides, body=body, k_t=k_t, tip_q=tip_q, gains=gains)

    factory.body = body  # type: ignore[attr-defined]
    factory.gains = gains  # type: ignore[attr-defined]
    return factory


#: the tracking inputs in the source's and probes/piezo.py's names
INPUT_NAMES = {"duo-bimorph": {"V_y": "V_y", "V_z": "V_z"},
               "piezotube": {"V_x": "u_z (all quarters, axial; piezo pattern V_z)", "V_y": "u_y (piezo pattern V_y)",
                             "V_z": "u_x (piezo pattern V_x)"}}

#: the piezotube of section 3.5 (Re = 0.5 mm, Ri = 0.45 mm, delta_x = delta_y = 5 um, k_t = 10 N/m)
CONTROL_PLANT = {"delta": 5e-6, "k_t": 10.0}


def control_plant(body: str = "analytic", k_t: float | None = None, delta: float | None = None,
                  gains: str | np.ndarray = "analytic", gains_source: str | None = None,
                  d31: float | None = None) -> MechanicalPlant:
    """The piezotube of section 3.5: Re = 0.5 mm, Ri = 0.45 mm, delta_x = delta_y = 5 um (probedyn
    delta_z = delta_y = delta), holder k_t (default 10 N/m, the probe's manipulation stiffness)."""
    d = CONTROL_PLANT["delta"] if delta is None else float(delta)
    kt = CONTROL_PLANT["k_t"] if k_t is None else float(k_t)
    return smart_plant("piezotube", {"delta_y": d, "delta_z": d}, body=body, k_t=kt, gains=gains,
                       gains_source=gains_source, d31=d31)
