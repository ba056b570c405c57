"""The smart probes as electromechanical models: piezoelectric regions, poling, electrode
layouts and drive patterns, and the actuation studies built on them (issue 12).

The mechanical model comes from the probe (``probe.build(values)``: mesh, materials, clamp,
holder, lumped tip); :class:`probedyn.fem.piezo.PiezoModel` adds the potential on the PZT
regions.  Regions that carry no electrodes (the holder's stiffness-tuning piezolayer) stay
purely elastic with their short-circuit stiffness c^E.

Duo-bimorph (source 3.2.1, Fig 3.5)
-----------------------------------
Layers ``upper_layer`` / ``lower_layer`` poled through the thickness; electrodes
``electrode_upper_left/right``, ``electrode_lower_left/right`` (left = +y) and
``electrode_middle`` (the interface; grounded reference).  ``poling = "parallel"`` (default:
both layers +z, the source's "four electrodes at the same voltage" bends the probe) or
``"series"`` (upper +z, lower -z).  Patterns (volts per volt of the command; a positive command
moves the tip along +z / +y; PZT has d31 < 0, so a layer extends where the field opposes its
poling):

* ``V_z`` (vertical bending, lower layer extends): parallel - all four outer electrodes at -1;
  series - upper -1, lower +1;
* ``V_y`` (lateral bending, right half (-y) extends, left half contracts): parallel -
  upper-left -1, lower-left +1, upper-right +1, lower-right -1; series - left -1, right +1.

Piezotube (source 3.3.1, Figs 3.10-3.11)
----------------------------------------
The ``tube`` poled radially outward (:func:`probedyn.fem.materials.radial_poling`); inner
electrode grounded (reference).  A positive voltage on an outer electrode makes an inward field,
against the poling: the wall under it extends and the tube bends away from it.  Layouts: ``quarters`` (``electrode_yp, zp, ym, zm``) and
``sectors`` (``electrode_sector_00 .. 11``, 30 degrees each, sector k centred at 30 k degrees
from +y towards +z).  Patterns in the **source's names** (source x = probedyn z, source y =
probedyn y, source z = the tube axis = probedyn x):

* ``V_x``: -1 on the +z quarter, +1 on the -z quarter (sectors: the three sectors of each): the
  tip moves along +z;
* ``V_y``: -1 on the +y quarter, +1 on the -y quarter: along +y;
* ``V_z``: +1 on every outer electrode: the tube extends (+x);
* sectors only: ``V_x_cos`` / ``V_y_cos``: ``V_k = -cos(theta_k - theta_axis)`` on all 12
  sectors (the pattern that maximises the bending moment per peak volt: 9.8 % more than
  quarters).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from probedyn.core.errors import GeometryError, ParameterError
from probedyn.fem.materials import radial_poling
from probedyn.fem.piezo import PiezoModel, PiezoStatic, coupling_factors, match_modes
from probedyn.fem.piezo_materials import get_piezo_material
from probedyn.lumped.actuation import GammaMatrix
from probedyn.probes import get_probe

DUO_OUTER = ("electrode_upper_left", "electrode_upper_right", "electrode_lower_left", "electrode_lower_right")
TUBE_QUARTERS = ("electrode_yp", "electrode_zp", "electrode_ym", "electrode_zm")
TUBE_SECTORS = tuple(f"electrode_sector_{k:02d}" for k in range(12))
#: sectors making up each quarter (meshes/piezotube.py QUARTERS)
_QUARTER_SECTORS = {"electrode_yp": (11, 0, 1), "electrode_zp": (2, 3, 4), "electrode_ym": (5, 6, 7),
                    "electrode_zm": (8, 9, 10)}
POLINGS = ("parallel", "series")


@dataclass(frozen=True)
class PiezoSetup:
    """Piezoelectric description of a probe (module docstring)."""

    probe: str
    regions: dict[str, Any]
    layouts: dict[str, tuple[str, ...]]
    default_layout: str
    reference: str
    patterns: dict[str, dict[str, dict[str, float]]]
    frame: dict[str, str] = field(default_factory=dict)

    def layout(self, name: str | None) -> tuple[str, ...]:
        name = self.default_layout if name is None else name
        if name not in self.layouts:
            raise ParameterError(f"{self.probe}: unknown electrode layout '{name}' (known: {', '.join(self.layouts)})")
        return self.layouts[name]

    def pattern(self, layout: str | None, name: str) -> dict[str, float]:
        lay = self.default_layout if layout is None else layout
        pats = self.patterns.get(lay, {})
        if name not in pats:
            raise ParameterError(f"{self.probe}: unknown drive pattern '{name}' for layout '{lay}' "
                                 f"(known: {', '.join(pats)})")
        return pats[name]


def _duo_setup(poling: str) -> PiezoSetup:
    if poling not in POLINGS:
        raise ParameterError(f"duo-bimorph poling must be 'parallel' or 'series', got {poling!r}")
    lower = "+z" if poling == "parallel" else "-z"
    ul, ur, ll, lr = DUO_OUTER
    if poling == "parallel":
        pats = {"V_z": {ul: -1.0, ur: -1.0, ll: -1.0, lr: -1.0},
                "V_y": {ul: -1.0, ll: 1.0, ur: 1.0, lr: -1.0}}
    else:
        pats = {"V_z": {ul: -1.0, ur: -1.0, ll: 1.0, lr: 1.0},
                "V_y": {ul: -1.0, ll: -1.0, ur: 1.0, lr: 1.0}}
    return PiezoSetup("duo-bimorph", {"upper_layer": "+z", "lower_layer": lower},
                      {"split": DUO_OUTER + ("electrode_middle",)}, "split", "electrode_middle",
                      {"split": pats}, {"x": "x (along the probe)", "y": "y (lateral)", "z": "z (vertical)"})


def _tube_setup() -> PiezoSetup:
    yp, zp, ym, zm = TUBE_QUARTERS
    quarters = {"V_x": {zp: -1.0, zm: 1.0}, "V_y": {yp: -1.0, ym: 1.0},
                "V_z": {yp: 1.0, zp: 1.0, ym: 1.0, zm: 1.0}}
    sectors: dict[str, dict[str, float]] = {}
    for pname, pat in quarters.items():
        sectors[pname] = {TUBE_SECTORS[k]: v for q, v in pat.items() for k in _QUARTER_SECTORS[q]}
    th = np.radians(30.0 * np.arange(12))
    sectors["V_x_cos"] = {TUBE_SECTORS[k]: float(np.round(-np.sin(th[k]), 15)) for k in range(12)}  # +z: 90 deg
    sectors["V_y_cos"] = {TUBE_SECTORS[k]: float(np.round(-np.cos(th[k]), 15)) for k in range(12)}
    return PiezoSetup("piezotube", {"tube": "radial"},
                      {"quarters": TUBE_QUARTERS + ("electrode_inner",),
                       "sectors": TUBE_SECTORS + ("electrode_inner",)},
                      "quarters", "electrode_inner", {"quarters": quarters, "sectors": sectors},
                      {"x": "source z (tube axis)", "y": "source y", "z": "source x"})


def piezo_setup(probe_name: str, poling: str | None = None) -> PiezoSetup:
    """The :class:`PiezoSetup` of a registered smart probe."""
    if probe_name == "duo-bimorph":
        return _duo_setup(poling or "parallel")
    if probe_name == "piezotube":
        if poling not in (None, "radial"):
            raise ParameterError(f"piezotube poling is radial, got {poling!r}")
        return _tube_setup()
    raise ParameterError(f"probe '{probe_name}' has no piezoelectric actuation (smart probes: duo-bimorph, piezotube)")


#: the element the coupled piezoelectric FEM assembles (its hexahedra are not implemented, they
#: are refused); the one place for this choice: every model that must be the piezo FEM's
#: mechanical body (the reduced actuated probe, the FEM-body plant with FEM gains) takes it here
COUPLED_ELEMENT = "tet-p2"


def coupled_values(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` with ``element = auto`` resolved to the coupled FEM's :data:`COUPLED_ELEMENT`
    (an explicit element is kept: the coupled model refuses one it cannot assemble)."""
    v = dict(values)
    if v.get("element", "auto") == "auto":
        v["element"] = COUPLED_ELEMENT
    return v


def build_piezo_model(probe, values: dict[str, Any], layout: str | None = None, poling: str | None = None,
                      piezo_material: str | None = None) -> tuple[PiezoModel, PiezoSetup]:
    """The coupled model of a resolved probe: ``probe.build(values)`` + the piezo set-up.

    ``piezo_material`` defaults to the probe's ``material`` value; a material without
    piezoelectric constants (e.g. ``pzt-5h-iso``) raises a one-line MaterialError."""
    setup = piezo_setup(probe.name, poling)
    mat_name = piezo_material or values.get("material", "pzt-5h")
    mat = get_piezo_material(mat_name)
    mech = probe.build(coupled_values(values))
    regions = {}
    for rname, pol in setup.regions.items():
        if pol == "radial":
            pol = radial_poling(axis_point=(0.0, 0.0, 0.0), axis_dir=(1.0, 0.0, 0.0))
        regions[rname] = (mat, pol)
    pm = PiezoModel(mech, regions, electrodes=setup.layout(layout), reference=setup.reference)
    return pm, setup


def piezo_model(name_or_toml: str, overrides: Mapping[str, Any] | None = None, layout: str | None = None,
                poling: str | None = None):
    """(probe, values, PiezoModel, PiezoSetup) for a probe name or TOML file plus overrides."""
    probe, toml_over = get_probe(name_or_toml)
    values = probe.resolve({**toml_over, **dict(overrides or {})})
    pm, setup = build_piezo_model(probe, values, layout, poling)
    return probe, values, pm, setup


# ---------------------------------------------------------------------------------------------
# static actuation
# ---------------------------------------------------------------------------------------------

def tip_displacement(pm: PiezoModel, res: PiezoStatic) -> np.ndarray:
    """Displacement (3,) [m] of the probe tip: the lumped tip DOFs if the model has a lumped tip
    (statically they move with the holder end face), else the model's tip attachment."""
    if res.extra.size >= 3:
        return np.asarray(res.extra[:3], dtype=float)
    return res.displacement_at(pm.tip)


@dataclass
class Actuation:
    """A static actuation result (one drive)."""

    probe: str
    voltages: dict[str, float]
    tip: np.ndarray
    points: dict[str, np.ndarray]
    charges: dict[str, float]
    potentials: dict[str, float]
    dofs: int
    solver: str
    timings: dict[str, float]
    result: PiezoStatic = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {"probe": self.probe, "voltages": self.voltages, "tip_displacement_m": self.tip,
                "displacements_m": self.points, "electrode_charges_C": self.charges,
                "electrode_potentials_V": self.potentials, "dofs": self.dofs, "solver": self.solver,
                "timings": self.timings}


def resolve_drive(setup: PiezoSetup, layout: str | None, pattern: str | None = None,
                  electrodes: Sequence[str] = (), volts: float | Sequence[float] = 1.0) -> dict[str, float]:
    """Electrode voltages from a pattern (scaled by ``volts``) or from electrode names with one
    voltage each (or one voltage for all)."""
    lay = setup.layout(layout)
    v = np.atleast_1d(np.asarray(volts, dtype=float))
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"voltages must be finite, got {volts}")
    if pattern is not None:
        if electrodes:
            raise ParameterError("give a drive pattern or electrodes, not both")
        if v.size != 1:
            raise ParameterError("a pattern takes one voltage")
        return {k: float(a * v[0]) for k, a in setup.pattern(layout, pattern).items()}
    if not electrodes:
        raise ParameterError("no drive: give a pattern or at least one electrode")
    if v.size not in (1, len(electrodes)):
        raise ParameterError(f"{len(electrodes)} electrodes but {v.size} voltages")
    out = {}
    for i, e in enumerate(electrodes):
        if e not in lay:
            raise GeometryError(f"unknown electrode '{e}' for {setup.probe} (layout electrodes: {', '.join(lay)})")
        out[e] = float(v[0] if v.size == 1 else v[i])
    return out


def actuate(pm: PiezoModel, setup: PiezoSetup, voltages: Mapping[str, float], points: Sequence[str] = (),
            solver: str = "indefinite") -> Actuation:
    """Static response to electrode ``voltages`` (others of the layout grounded)."""
    res = pm.static(voltages, others="ground", solver=solver)
    pts = {p: res.displacement_at(p) for p in points}
    return Actuation(setup.probe, dict(voltages), tip_displacement(pm, res), pts, res.charges, res.potentials,
                     res.dofs, res.solver, res.timings, res)


def run_actuation(name_or_toml: str, overrides: Mapping[str, Any] | None = None, pattern: str | None = None,
                  electrodes: Sequence[str] = (), volts: float | Sequence[float] = 1.0, layout: str | None = None,
                  poling: str | None = None, solver: str = "indefinite") -> tuple[Actuation, dict[str, Any]]:
    """One actuation from a probe name/TOML, overrides and a drive (pattern or electrodes with
    voltages; the drive is validated before any FEM work).  Returns the :class:`Actuation`
    (displacements also at the holder end and the actuator end) and the resolved parameters."""
    probe, toml_over = get_probe(name_or_toml)
    values = probe.resolve({**toml_over, **dict(overrides or {})})
    setup = piezo_setup(probe.name, poling)
    drive = resolve_drive(setup, layout, pattern, electrodes, volts)
    pm, setup = build_piezo_model(probe, values, layout, poling)
    mech = pm.mech
    known = set(mech.mesh.boundaries or {}) | set(mech.bundle.points)
    pts = [q for q in ("holder_end", "tube_end" if probe.name == "piezotube" else "free_end_centre") if q in known]
    return actuate(pm, setup, drive, pts, solver), values


def blocked_force(pm: PiezoModel, voltages: Mapping[str, float], where: str, solver: str = "indefinite") -> dict[str, Any]:
    """Blocked force [N] at the face ``where`` (area-averaged attachment) under ``voltages``.

    With the 3x3 compliance C of the face at held electrode voltages (three unit-force solves,
    one factorisation with the drive) and the free displacement u: ``blocked_force`` =
    ``-C^-1 u`` (all three components of the face held) and ``blocked_force_axis`` [d] =
    ``-u[d] / C[d, d]`` (only component d held, the others free; d = the largest component of u)."""
    cases = [dict(voltages)] + [{k: 0.0 for k in voltages}] * 3
    forces = [{}] + [{where: tuple(np.eye(3)[j])} for j in range(3)]
    res = pm.static_many(cases, forces, others="ground", solver=solver)
    free = res[0].displacement_at(where)
    C = np.column_stack([r.displacement_at(where) for r in res[1:]])
    d = int(np.argmax(np.abs(free)))
    axis = np.zeros(3)
    axis[d] = -free[d] / C[d, d]
    return {"where": where, "free_displacement": free, "compliance": C, "blocked_force": -np.linalg.solve(C, free),
            "blocked_force_axis": axis, "axis": "xyz"[d]}


def actuation_table(pm: PiezoModel, setup: PiezoSetup, layout: str | None = None, points: Sequence[str] = (),
                    solver: str = "indefinite") -> list[dict[str, Any]]:
    """Tip displacement per volt for every drive pattern of the layout."""
    rows = []
    lay = setup.default_layout if layout is None else layout
    for pname, pat in setup.patterns[lay].items():
        a = actuate(pm, setup, pat, points, solver)
        rows.append({"pattern": pname, "voltages": pat, "tip_m_per_V": a.tip,
                     **{f"{p}_m_per_V": a.points[p] for p in points}, "dofs": a.dofs,
                     "solve_s": a.timings.get("solve_s")})
    return rows


# ---------------------------------------------------------------------------------------------
# eccentricity coupling of the piezotube from the FEM
# ---------------------------------------------------------------------------------------------

def _tube_gamma_voltages(j: int) -> dict[str, float]:
    """Electrode voltages of unit input u_j (source frame; GammaMatrix docstring): quarters
    Q+x = zp, Q-x = zm, Q+y = yp, Q-y = ym."""
    yp, zp, ym, zm = TUBE_QUARTERS
    if j == 0:
        return {zp: -1.0, zm: 1.0}
    if j == 1:
        return {yp: -1.0, ym: 1.0}
    return {yp: 1.0, zp: 1.0, ym: 1.0, zm: 1.0}


def gamma_matrix_fem(overrides: Mapping[str, Any] | None = None, where: str = "tube_end",
                     reference: np.ndarray | None = None, solver: str = "indefinite") -> GammaMatrix:
    """The voltage -> tube-end displacement map of the piezotube from the coupled FEM
    (:class:`~probedyn.lumped.actuation.GammaMatrix`, source frame), for the probe parameters
    ``overrides`` (bore offset ``delta_z`` = source delta_x, ``delta_y`` = source delta_y; the
    holder does not change a static response to voltages, so ``holder = "point"`` is the
    default here).  ``reference``: the concentric tube's diagonal (computed with the same mesh
    settings when omitted).  Three solves sharing one factorisation."""
    ov = {"holder": "point", "tip": "none", **dict(overrides or {})}
    probe, values, pm, setup = piezo_model("piezotube", ov, layout="quarters")
    D = _gamma_columns(pm, where, solver)
    if reference is None:
        if values["delta_y"] == 0 and values["delta_z"] == 0:
            reference = np.diag(D).copy()
        else:
            ov0 = {**ov, "delta_y": 0.0, "delta_z": 0.0}
            _, _, pm0, _ = piezo_model("piezotube", ov0, layout="quarters")
            reference = np.diag(_gamma_columns(pm0, where, solver)).copy()
    return GammaMatrix(D, np.asarray(reference, dtype=float),
                       f"FEM: coupled P2 piezo model, {pm.mechanical_system()[0].shape[0] + pm.n_phi} DOFs, "
                       f"Re={values['Re']:g} Ri={values['Ri']:g} L={values['length']:g} "
                       f"delta=({values['delta_z']:g}, {values['delta_y']:g}) m (source x, y), face '{where}'")


def _gamma_columns(pm: PiezoModel, where: str, solver: str) -> np.ndarray:
    res = pm.static_many([_tube_gamma_voltages(j) for j in range(3)], others="ground", solver=solver)
    D = np.zeros((3, 3))
    for j, r in enumerate(res):
        u = r.displacement_at(where)  # probedyn (x axial, y, z)
        D[:, j] = [u[2], u[1], u[0]]  # source (x = pd z, y = pd y, z = pd x)
    return D


# ---------------------------------------------------------------------------------------------
# modes: short / open circuit, coupling factors, modal actuation
# ---------------------------------------------------------------------------------------------

def coupling_table(pm: PiezoModel, n_modes: int = 6, solver: str = "indefinite") -> dict[str, Any]:
    """Short- and open-circuit modes and ``k_eff^2`` per mode (open-circuit modes matched to the
    short-circuit ones by the largest modal assurance)."""
    t0 = time.perf_counter()
    sc = pm.modes(n_modes, "short", solver=solver)
    t1 = time.perf_counter()
    oc = pm.modes(n_modes, "open", solver=solver)
    t2 = time.perf_counter()
    _, M, free, n_extra = pm.mechanical_system()
    A = np.vstack([sc.shapes[free], sc.extra.T]) if n_extra else sc.shapes[free]
    B = np.vstack([oc.shapes[free], oc.extra.T]) if n_extra else oc.shapes[free]
    j = match_modes(M, A, B)
    f_oc = oc.frequencies_hz[j]
    k2 = coupling_factors(sc.frequencies_hz, f_oc)
    rows = [{"mode": i + 1, "family": sc.families[i], "f_sc_hz": float(sc.frequencies_hz[i]),
             "f_oc_hz": float(f_oc[i]), "shift": float(f_oc[i] / sc.frequencies_hz[i] - 1.0),
             "k_eff2": float(k2[i])} for i in range(len(k2))]
    return {"rows": rows, "dofs": sc.dofs, "solver": sc.solver, "modal_s_short": t1 - t0, "modal_s_open": t2 - t1,
            "short": sc, "open": oc}


def electrode_modes(name_or_toml: str, overrides: Mapping[str, Any] | None = None, n_modes: int = 6,
                    electrodes: str = "both", solver: str = "indefinite") -> dict[str, Any]:
    """Coupled modes of a probe with its electrodes ``short``, ``open`` or ``both`` (then with
    the shifts and k_eff^2 per mode, :func:`coupling_table`); a JSON-ready dict."""
    if electrodes not in ("short", "open", "both"):
        raise ParameterError(f"--electrodes must be short, open or both, got {electrodes!r}")
    probe, values, pm, setup = piezo_model(name_or_toml, overrides)
    if electrodes == "both":
        t = coupling_table(pm, n_modes, solver)
        return {"probe": probe.name, "electrodes": "both", "dofs": t["dofs"], "solver": t["solver"],
                "rows": t["rows"], "reference_electrode": pm.reference, "parameters": values}
    m = pm.modes(n_modes, electrodes, solver=solver)
    rows = [{"mode": i + 1, "frequency_hz": float(f), "family": fam}
            for i, (f, fam) in enumerate(zip(m.frequencies_hz, m.families))]
    return {"probe": probe.name, "electrodes": electrodes, "dofs": m.dofs, "solver": m.solver, "modes": rows,
            "timings": m.timings, "reference_electrode": pm.reference, "parameters": values}


@dataclass
class ModalActuation:
    """Modal force per volt of each electrode (for reduced probes).

    ``frequencies_hz`` (k,), ``modal_force`` (k, n_e) [N/V per unit modal coordinate of the
    mass-normalised modes], ``tip_shapes`` (k, 3) modal displacement at the tip, so the tip
    displacement per volt of electrode e is ``sum_i tip_shapes[i] modal_force[i, e] / omega_i^2``
    statically; ``static_tip`` (n_e, 3) the exact static response (coupled solve) and
    ``truncation`` (n_e,) the relative error of the k-mode sum at the tip."""

    electrodes: list[str]
    frequencies_hz: np.ndarray
    modal_force: np.ndarray
    tip_shapes: np.ndarray
    static_tip: np.ndarray
    modal_static_tip: np.ndarray
    truncation: np.ndarray
    loads: np.ndarray = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {"electrodes": self.electrodes, "frequencies_hz": self.frequencies_hz,
                "modal_force_N_per_V": self.modal_force, "tip_shapes": self.tip_shapes,
                "static_tip_m_per_V": self.static_tip, "modal_static_tip_m_per_V": self.modal_static_tip,
                "truncation": self.truncation}


def modal_actuation(pm: PiezoModel, n_modes: int = 8, electrodes: Sequence[str] | None = None,
                    solver: str = "indefinite") -> ModalActuation:
    """Load vector per volt of each electrode (the others grounded), its projection on the
    short-circuit modes, and the static check of the modal sum at the tip."""
    els = list(electrodes) if electrodes is not None else [e for e in pm.electrodes if e != pm.reference]
    F, free = pm.actuation_loads(els)
    modes = pm.modes(n_modes, "short", solver=solver)
    _, _, _, n_extra = pm.mechanical_system()
    Phi = np.vstack([modes.shapes[free], modes.extra.T]) if n_extra else modes.shapes[free]
    Q = Phi.T @ F  # (k, n_e)
    tip = np.asarray(modes.tip_displacement, dtype=float)  # (k, 3)
    om2 = (2 * np.pi * modes.frequencies_hz) ** 2
    modal_static = np.einsum("ic,ie,i->ec", tip, Q, 1.0 / om2)
    stat = np.array([tip_displacement(pm, r) for r in pm.static_many([{e: 1.0} for e in els], others="ground",
                                                                        solver=solver)])
    trunc = np.linalg.norm(modal_static - stat, axis=1) / np.maximum(np.linalg.norm(stat, axis=1), 1e-300)
    return ModalActuation(els, modes.frequencies_hz, Q, tip, stat, modal_static, trunc, F)




def static_per_volt(pm: PiezoModel, electrodes: Sequence[str], solver: str = "indefinite") -> np.ndarray:
    """Static displacement per volt of each electrode (the others of the layout grounded) on the
    mechanical unknowns (free DOFs + lumped-tip DOFs): (n_mech, n_e), one factorisation."""
    K, M, free, n_extra = pm.mechanical_system()
    res = pm.static_many([{e: 1.0} for e in electrodes], others="ground", solver=solver)
    return np.column_stack([np.concatenate([r.u[free], r.extra]) for r in res])


def project_actuation(pm: PiezoModel, Phi: np.ndarray, omega: np.ndarray, electrodes: Sequence[str],
                      solver: str = "indefinite") -> np.ndarray:
    """Modal force per volt [N/V] of each electrode on given mass-normalised modes ``Phi``
    (n_mech, k) with circular frequencies ``omega`` (k,), e.g. the elastic modes of a reduced
    probe: ``f_i,e = omega_i^2 phi_i^T M u_e`` with ``u_e`` the coupled static displacement per
    volt.  Then ``sum_i phi_i f_i,e / omega_i^2`` over all modes is exactly ``u_e`` (the modal
    expansion of the true static response), whatever stiffness the modes were computed with
    (the elastic c^E stiffness of a mechanical model lacks the induced-potential stiffening of
    the coupled one, ~1 %); truncated, the usual static correction applies."""
    K, M, free, n_extra = pm.mechanical_system()
    Phi = np.asarray(Phi, dtype=float)
    if Phi.shape[0] != K.shape[0]:
        raise ParameterError(f"modes have {Phi.shape[0]} rows, the model has {K.shape[0]} mechanical unknowns")
    U = static_per_volt(pm, electrodes, solver)
    return (np.asarray(omega, dtype=float) ** 2)[:, None] * (Phi.T @ (M @ U))


def fill_reduced_actuation(reduced, pm: PiezoModel, electrodes: Sequence[str] | None = None,
                           solver: str = "indefinite") -> dict[str, list[float]]:
    """Fill ``reduced.actuation`` = {electrode: [modal force per volt of each retained mode]}
    [N/V] of a reduced probe (issue 10's ``ReducedProbe``; duck-typed: ``reduced.ritz`` a
    :class:`~probedyn.lumped.ritz.RitzBasis` of the same mechanical model, whose first
    ``len(reduced.modes)`` columns are the mass-normalised retained modes) from the coupled model
    ``pm`` (:func:`project_actuation`).  A scheme then drives mode i with ``sum_e f_i,e V_e``.
    ``electrodes``: default every electrode of the layout but the grounded reference."""
    rb = reduced.ritz
    if rb is None:
        raise ParameterError("this reduced probe has no Ritz basis (a table preset has no electrodes)")
    n = len(reduced.modes)
    K, M, free, n_extra = pm.mechanical_system()
    if rb.T is None:
        raise ParameterError("this reduced probe was loaded without its Ritz basis vectors (T)")
    T = np.asarray(rb.T, dtype=float)
    ntot = pm.mech.ndofs_total
    if T.shape[0] == ntot + n_extra:  # full FEM coordinates (RitzBasis.T): keep the unknowns
        T = np.vstack([T[free], T[ntot:]])
    if T.shape[0] != K.shape[0]:
        raise ParameterError(f"reduced probe basis has {T.shape[0]} rows, the piezo model {K.shape[0]} mechanical "
                             f"unknowns: build both from the same probe parameters")
    els = list(electrodes) if electrodes is not None else [e for e in pm.electrodes if e != pm.reference]
    f = project_actuation(pm, T[:, :n], np.asarray(rb.omega[:n], dtype=float), els, solver)
    reduced.actuation = {e: [float(v) for v in f[:, j]] for j, e in enumerate(els)}
    return reduced.actuation


# ---------------------------------------------------------------------------------------------
# range studies (source Figs 3.17, 3.18) and the eccentricity study (Fig 3.20)
# ---------------------------------------------------------------------------------------------

#: parameters the range studies vary, per probe (probe parameter names)
RANGE_PARAMETERS = {"duo-bimorph": ("electrode_gap", "thickness"), "piezotube": ("length", "Re")}


def range_point(name: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """FEM deflection per volt of the bare actuator (holder as a point, no tip) for every drive
    pattern of the default layout, at the actuator's end face (duo-bimorph: x = L; piezotube:
    the tube end), in probedyn axes [m/V]; with the DOFs and the solve time."""
    ov = {"holder": "point", **dict(overrides or {})}
    ov.setdefault("tip", "none")
    probe, values, pm, setup = piezo_model(name, ov)
    where = "holder_end" if name == "duo-bimorph" else "tube_end"
    pats = setup.patterns[setup.default_layout]
    t0 = time.perf_counter()
    res = pm.static_many(list(pats.values()), others="ground")
    out = {p: r.displacement_at(where) for p, r in zip(pats, res)}
    return {"values": {k: values[k] for k in RANGE_PARAMETERS[name]}, "per_volt": out, "dofs": res[0].dofs,
            "solve_s": time.perf_counter() - t0, "where": where}


def gamma_study(deltas: Sequence[float], overrides: Mapping[str, Any] | None = None,
                direction: Sequence[float] = (1.0, 1.0)) -> list[dict[str, Any]]:
    """Gamma from the FEM and from the corrected formula for bore offsets
    ``(delta_x, delta_y) = d * direction`` (source frame) for every ``d`` in ``deltas``; the
    default ``direction = (1, 1)`` is section 3.5.4's ``delta_x = delta_y``.  The FEM's concentric
    reference is computed once with the same mesh settings."""
    from probedyn.lumped.actuation import gamma_matrix

    ov = dict(overrides or {})
    probe, _ = get_probe("piezotube")
    values = probe.resolve({"holder": "point", "tip": "none", **ov})
    G0 = gamma_matrix_fem({**ov, "delta_y": 0.0, "delta_z": 0.0})
    ref = np.diag(G0.displacement).copy()
    d31 = float(get_piezo_material(values["material"]).d[2, 0])
    ux, uy = (float(c) for c in direction)
    rows = []
    for d in deltas:
        dx, dy = d * ux, d * uy
        t0 = time.perf_counter()
        G = G0 if d == 0 else gamma_matrix_fem({**ov, "delta_z": dx, "delta_y": dy}, reference=ref)
        t_fem = time.perf_counter() - t0
        F = gamma_matrix(values["Re"], values["Ri"], values["length"], dx, dy, d31=d31, material=values["material"])
        rows.append({"delta": d, "delta_x": dx, "delta_y": dy, "fem": G, "formula": F, "fem_s": t_fem})
    return rows


__all__ = ["PiezoSetup", "piezo_setup", "build_piezo_model", "piezo_model", "Actuation", "actuate", "resolve_drive",
           "blocked_force", "actuation_table", "gamma_matrix_fem", "coupling_table", "ModalActuation",
           "modal_actuation", "tip_displacement", "TUBE_QUARTERS", "TUBE_SECTORS", "DUO_OUTER", "POLINGS",
           "RANGE_PARAMETERS", "range_point", "gamma_study", "static_per_volt", "project_actuation",
           "fill_reduced_actuation", "run_actuation",
           "electrode_modes"]
