"""Studies of path tracking and probe control (sections 3.2.3, 3.3.3, 3.4, 3.5): each returns a
plain dict (SI) for the CLI, the report and docs/tracking.md; none prints or plots.

* :func:`track` - one run (the CLI's ``probedyn track``): plant, path, controller, range check;
* :func:`open_loop_study` - Figs 3.8 and 3.14 (quasi-static and dynamic inverse);
* :func:`holder_stiffness_study` - Fig 3.16: residual oscillation and tracking error vs k_t and speed;
* :func:`range_study` - Figs 3.17, 3.18: range per volt, formulas beside the reduced probes;
* :func:`control_problem` - 3.5: mapping to D, J, C, K1, K2, Gamma, slow model, stability of the laws;
* :func:`controller_comparison` - Figs 3.21, 3.22: four controllers on the full model;
* :func:`epsilon_study` - Tikhonov's O(eps) (3.55-3.56) vs the observed order;
* :func:`robustness_study` - Gamma mismatch, saturation, sensor noise, 2x/5x disturbance;
* :func:`frequency_response_check` - simulator vs the closed-loop transfer function.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence

import numpy as np
import scipy.linalg as sla

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset
from probedyn.schemes.tracking import actuation as act
from probedyn.schemes.tracking import controllers as ctl
from probedyn.schemes.tracking import inversion
from probedyn.schemes.tracking.disturbance import kbr
from probedyn.schemes.tracking.paths import Path, TimedPath, Timing, circle, make_path, read_csv_path
from probedyn.schemes.tracking.plants import MechanicalPlant, scaled_stiffness, with_blocks
from probedyn.schemes.tracking.simulate import (ClosedLoop, SensorNoise, TrackingResult, closed_loop_response,
                                                simulate)

#: amplifier limits [V]: tube scanners are driven by +-200..250 V high-voltage amplifiers (e.g. the
#: PiezoDrive TD250, +-250 V); the duo-bimorph's 5 um layers by a low-voltage driver (+-20 V,
#: 4 V/um in a layer, thin-film PZT range). The tube's 50 um wall tolerates about 0.3 V/um
#: against its poling (soft PZT data sheets limit the reverse field to ~1/3 of the coercive
#: field ~0.8-1 kV/mm): +-15 V is the wall-field limit used in the robustness study.
V_AMP = {"piezotube": 200.0, "duo-bimorph": 20.0}
V_FIELD_TUBE = 15.0

#: reference paths (Figs 3.8, 3.14, 3.16, 3.21, 3.22): kind -> make_path keywords
REF_PATHS = {
    "duo-bimorph": {"line": {"size": 0.5e-6}, "circle": {"size": 0.5e-6}, "square": {"size": 0.5e-6}},
    "piezotube": {"cylinder": {"size": 0.25e-6, "height": 1e-6}, "sphere": {"size": 0.5e-6},
                  "cone": {"size": 0.5e-6, "height": 0.5e-6}},
}


#: a plant factory: ``factory(probe_name, k_t=None, overrides=None) -> MechanicalPlant``
#: (``probedyn.probes.tracking.plant_factory(body)`` builds the smart probes' plants)
PlantFactory = Callable[..., MechanicalPlant]


def check_range(plant: MechanicalPlant, path: Path, v_max: float, n: int = 4001) -> dict[str, Any]:
    """Peak quasi-static voltage of ``path`` on ``plant``; a path that needs more than ``v_max``
    raises (the actuator cannot reach it)."""
    t = np.linspace(0, path.duration, n)
    R = inversion.path_on_outputs(plant, path.derivatives(t, 0))
    u = inversion.quasi_static(plant, R[0])
    peak = np.max(np.abs(u), axis=0)
    if np.max(peak) > v_max:
        j = int(np.argmax(peak))
        raise ParameterError(f"the path needs {peak[j]:.3g} V on {plant.inputs[j]} (quasi-static), beyond the "
                             f"{v_max:g} V amplifier limit: the path is outside the actuator range "
                             f"({plant.static_gain()[j, j] * v_max:.3g} m along {plant.outputs[j]})")
    return {n_: float(p) for n_, p in zip(plant.inputs, peak)}


def build_path(spec: str, probe: str, *, speed: float | None = None, duration: float | None = None,
               size: float | None = None, ramp: float | None = None) -> Path:
    """A reference path by name (defaults of ``REF_PATHS``; ``circle``/``line``/``square`` for the
    duo-bimorph in the (y, z) plane) or a CSV file ``t,x,y,z``."""
    k = spec.strip().lower()
    if speed is not None and duration is not None:
        raise ParameterError("give the path's speed or its duration, not both (the speed sets the duration)")
    if k in ("line", "circle", "square", "cylinder", "sphere", "cone"):
        kw = dict(REF_PATHS.get(probe, {}).get(k, {"size": 0.5e-6}))
        if size is not None:
            if not (math.isfinite(size) and 0 < size <= 1e-3):
                raise ParameterError(f"path size must be in (0, 1 mm] (metres), got {size:g} m")
            kw["size"] = size
        if k in ("circle", "square") and probe == "piezotube":
            kw.setdefault("plane", "yz")
        if k in ("cylinder", "sphere", "cone") and probe == "duo-bimorph":
            raise ParameterError(f"a {k} is a 3D path; the duo-bimorph moves its tip in the (y, z) plane only")
        return make_path(k, speed=speed, duration=1.0 if duration is None else duration, ramp=ramp, **kw)
    if k.endswith(".csv") or "/" in spec or "\\" in spec:
        given = [n for n, v in (("speed", speed), ("duration", duration), ("size", size)) if v is not None]
        if given:
            raise ParameterError(f"a CSV path has its own times and coordinates: {', '.join(given)} cannot be applied")
        return read_csv_path(spec)
    raise ParameterError(f"unknown path {spec!r} (line, circle, square, cylinder, sphere, cone, or a CSV file t,x,y,z)")


def track(factory: PlantFactory, probe: str, path_spec: str, control: str = "composite", *,
          disturbance: str | None = None, disturbance_scale: float = 1.0, speed: float | None = None,
          duration: float | None = None, size: float | None = None, k_t: float | None = None,
          v_max: float | None = None, eccentricity: float | None = None, noise_rms: float = 0.0,
          overrides: dict | None = None) -> tuple[TrackingResult, dict[str, Any]]:
    """One tracking simulation (CLI ``probedyn track``): returns (result, summary)."""
    ov = dict(overrides or {})
    if eccentricity is not None:
        if probe != "piezotube":
            raise ParameterError("eccentricity applies to the piezotube")
        ov.update(delta_y=eccentricity, delta_z=eccentricity)
    plant = factory(probe, k_t=k_t, overrides=ov)
    path = build_path(path_spec, probe, speed=speed, duration=duration, size=size)
    vm = V_AMP.get(probe, 200.0) if v_max is None else float(v_max)
    qs_peaks = check_range(plant, path, vm)
    c = control.strip().lower()
    if c == "open":
        law = ctl.OpenLoop("dynamic" if path.smooth else "quasi-static").design(plant)
    else:
        law = ctl.make_controller(c).design(plant)
    st = ctl.stability(plant, law)
    if not st["stable"]:
        raise ParameterError(f"the {law.name} law is unstable on the full model (growth rate {st['max_real_per_s']:.3g} 1/s "
                             f"at {st['least_damped_hz']:.4g} Hz): see docs/tracking.md (no time-scale separation)")
    surf = None
    if not disturbance and disturbance_scale != 1.0:
        raise ParameterError("a disturbance scale applies to a disturbance: give --disturbance kbr too")
    if disturbance:
        if disturbance.strip().lower() != "kbr":
            raise ParameterError(f"unknown disturbance {disturbance!r} (known: kbr)")
        surf = kbr(disturbance_scale)
    noise = SensorNoise(noise_rms) if noise_rms != 0 else None  # SensorNoise checks the range
    res = simulate(plant, law, path, surface=surf, v_max=vm, noise=noise)
    m = res.metrics()
    summary = {"probe": probe, "path": path.describe(), "control": law.name, "stability": st,
               "metrics": m, "quasi_static_voltage_peak_V": qs_peaks, "v_max_V": vm,
               "disturbance": surf.describe() if surf else None,
               "provenance": {"plant": plant.provenance, "gains": plant.provenance.get("gains"),
                              "body": plant.provenance.get("body"), "integrator": res.info["integrator"],
                              "step_s": res.info["step_s"]},
               "frequencies_hz": plant.frequencies_hz()}
    return res, summary


# ---------------------------------------------------------------------------------------------
# open loop (Figs 3.8, 3.14)
# ---------------------------------------------------------------------------------------------


def open_loop_study(factory: PlantFactory, probe: str, *, durations: Sequence[float] = (1.0, 0.05),
                    keep: bool = False) -> dict[str, Any]:
    """Reference paths of ``probe`` tracked open loop with the quasi-static and the dynamic
    inverse at each duration: error metrics and voltage peaks (``keep``: the time histories)."""
    plant = factory(probe)
    rows, runs = [], {}
    for kind in REF_PATHS[probe]:
        for T in durations:
            path = build_path(kind, probe, duration=T)
            check_range(plant, path, V_AMP[probe])
            for inv in ("quasi-static", "dynamic"):
                law = ctl.OpenLoop(inv).design(plant)
                res = simulate(plant, law, path)
                m = res.metrics()
                rows.append({"path": kind, "duration_s": T, "inverse": inv, "max_error_m": m["max_error_m"],
                             "rms_error_m": m["rms_error_m"], "relative_max_error": m["max_error_m"] / m["path_extent_m"],
                             "axes": m["axes"], "voltage_peak_V": m["voltage_peak_V"], "extent_m": m["path_extent_m"]})
                if keep:
                    runs[(kind, T, inv)] = res
    return {"probe": probe, "rows": rows, "runs": runs, "frequencies_hz": plant.frequencies_hz(),
            "provenance": plant.provenance}


# ---------------------------------------------------------------------------------------------
# holder stiffness (Fig 3.16)
# ---------------------------------------------------------------------------------------------


def forced_response(plant: MechanicalPlant, law: ctl.Law, path: TimedPath, t: np.ndarray) -> np.ndarray:
    """Steady-state (forced) tip error during the constant-speed phase of a path whose geometry
    is a sum of sinusoids in the phase (circle, sphere): each term ``a sin(w s + phi)`` with
    ``s = v0 (t - t0)`` is a sinusoid of frequency ``w v0`` in time; its steady-state error follows
    from the closed-loop frequency response (:func:`closed_loop_response`). Linear loops only."""
    g = path.geometry
    T = path.timing
    if T.kind != "cruise" or any(term.power != 0 for term in g.terms):
        raise ParameterError("the forced response needs a cruise-timed path made of sinusoids (circle, sphere)")
    v0 = 1.0 / (T.duration - T.ramp)
    s0 = -v0 * T.ramp / 2  # s = v0 t + s0 in the constant-speed phase
    e = np.zeros((t.size, len(plant.outputs)))
    for term in g.terms:
        ax = np.asarray(term.axis)
        rhat = np.array([ax["xyz".index(a)] for a in plant.outputs], dtype=complex)
        if not np.any(rhat):
            continue
        w = term.omega * v0
        # a sin(w s + phi) = Re( a e^{i(phi - pi/2)} e^{i w s} )
        amp = term.amp * np.exp(1j * (term.phase - math.pi / 2 + term.omega * s0))
        eh = closed_loop_response(plant, law, w, rhat * amp)
        e += np.real(np.outer(np.exp(1j * w * t), eh))
    return e


def abrupt_start_bound(plant: MechanicalPlant, path: Path) -> float:
    """Upper bound of the free vibration left by an abrupt start under the quasi-static inverse.

    The quasi-static response ``q_qs = K^-1 B G0^-1 r`` jumps in velocity by
    ``Delta = K^-1 B G0^-1 r'(0+)``; the plant's velocity does not jump, so the deviation
    ``e = q - q_qs`` starts with ``e(0+) = 0``, ``e'(0+) = -Delta`` and (undamped) rings as
    ``-sum_j phi_j (phi_j^T M Delta) sin(omega_j t) / omega_j`` (mass-normalised modes). The tip
    part is bounded by ``sum_j |Cq phi_j| |phi_j^T M Delta| / omega_j``; damping only lowers it."""
    v0 = inversion.path_on_outputs(plant, path.derivatives(np.array([0.0]), 1))[1][0]
    Delta = np.linalg.solve(plant.K, plant.B @ np.linalg.solve(plant.static_gain(), v0))
    lam, Phi = sla.eigh(plant.K, plant.M)
    w = np.sqrt(lam)
    tip = np.linalg.norm(plant.Cq @ Phi, axis=0)
    return float(np.sum(tip * np.abs(Phi.T @ plant.M @ Delta) / w))


def holder_stiffness_study(factory: PlantFactory, probe: str, *, stiffnesses: Sequence[float] = (1, 2, 5, 10, 20, 50, 100),
                           path_hz: Sequence[float] = (1.0, 10.0, 100.0),
                           turns: float = 3.0, start: str = "abrupt") -> dict[str, Any]:
    """Section 3.4.1: the source's open-loop (quasi-static inverse) tracking of a circle
    (duo-bimorph, (y, z)) or a sphere (piezotube) for holder stiffness ``k_t`` in every direction
    and path repetition rates ``path_hz`` (turns per second). ``start = "abrupt"``: the tip is
    commanded at full speed from t = 0 (the velocity jumps, as a simulation fed with
    R cos(wt), R sin(wt) does); ``"smooth"``: a C^4 speed ramp of one turn.
    Per run: the residual oscillation = error minus its forced (steady-state) part, maximum over
    the second half of the run (the free vibration left by the start), the forced tracking error
    amplitude, and the total maximum error, relative to the path size; and the prediction of the
    residual from the lowest tip mode ``v / omega_tip`` (an abrupt velocity step v on a spring-mass)."""
    kind = "circle" if probe == "duo-bimorph" else "sphere"
    size = 0.5e-6
    rows = []
    for k in stiffnesses:
        plant = factory(probe, k_t=float(k))
        law = ctl.OpenLoop("quasi-static").design(plant)
        f_modes = plant.frequencies_hz()
        for fp in path_hz:
            T = turns / fp
            ramp = 0.0 if start == "abrupt" else min(1.0 / fp, T / 2)
            path = make_path(kind, size=size, duration=T, turns=turns, ramp=ramp)
            # 40 samples per period of a 10 kHz mode (stored: 40 per period of 5 kHz): the sampled
            # peak of the ringing errs by < 0.3 %
            res = simulate(plant, law, path, h=min(T / 4000, 2.5e-6), max_points=max(40000, int(2e5 * T)))
            t = res.t
            cruise = (t >= ramp) & (t <= T - ramp)
            e_forced = forced_response(plant, law, path, t[cruise])
            resid = np.linalg.norm(res.e[cruise] - e_forced, axis=1)
            tc = t[cruise]
            late = tc >= tc[0] + 0.5 * (tc[-1] - tc[0])
            v = path.peak_speed()
            v_jump = float(np.linalg.norm(path.derivatives(np.array([0.0]), 1)[1][0]))
            bound = abrupt_start_bound(plant, path) if start == "abrupt" else 0.0
            f_tip = float(np.min(f_modes))
            rows.append({"k_t": float(k), "path_hz": fp, "speed_m_per_s": v, "f_lowest_hz": f_tip,
                         "residual_m": float(np.max(resid)), "residual_late_m": float(np.max(resid[late])),
                         "forced_error_m": float(np.max(np.linalg.norm(e_forced, axis=1))),
                         "max_error_m": float(np.max(np.linalg.norm(res.e, axis=1))),
                         "residual_rel": float(np.max(resid) / size),
                         "forced_rel": float(np.max(np.linalg.norm(e_forced, axis=1)) / size),
                         "velocity_jump_m_per_s": v_jump if start == "abrupt" else 0.0,
                         "modal_bound_m": bound,
                         "predicted_residual_m": v_jump / (2 * math.pi * f_tip) if start == "abrupt" else float("nan"),
                         "decay_time_s": plant.provenance.get("tip_q", 100.0) / (math.pi * f_tip),
                         "tip_q": plant.provenance.get("tip_q")})
    return {"probe": probe, "path": kind, "size_m": size, "start": start, "rows": rows,
            "body": getattr(factory, "body", None)}


# ---------------------------------------------------------------------------------------------
# range per volt (Figs 3.17, 3.18)
# ---------------------------------------------------------------------------------------------


def range_study(factory: PlantFactory) -> dict[str, Any]:
    """Range per volt of both probes: printed formulas (3.31, 3.32, 3.34, 3.35), the corrected
    3.34, and the reduced probes' static tip stroke per volt (``Cq K^-1 B``, the plant the
    simulations use, at the holder end face with ``body = "fem"``), plus the sweeps of Figs 3.17
    (w0, h) and 3.18 (L, Re) from the formulas. The piezo FEM (issue 12) will supply the FEM values."""
    out: dict[str, Any] = {}
    for probe in ("duo-bimorph", "piezotube"):
        plant = factory(probe)
        v = plant.provenance["parameters"]
        G = plant.static_gain()
        if probe == "duo-bimorph":
            f = act.duo_bimorph_strokes(v["length"], v["width"], v["electrode_gap"], v["thickness"], plant.provenance["d31"])
            rows = [{"axis": "y", "formula": "(3.31)", "formula_m_per_V": f["y"], "plant_m_per_V": G[0, 0]},
                    {"axis": "z", "formula": "(3.32)", "formula_m_per_V": f["z"], "plant_m_per_V": G[1, 1]}]
        else:
            f = act.tube_strokes(v["length"], v["Re"], v["Ri"], plant.provenance["d31"])
            rows = [{"axis": "x (axial)", "formula": "(3.35)", "formula_m_per_V": f["x"], "plant_m_per_V": G[0, 0]},
                    {"axis": "y, z (lateral)", "formula": "(3.34) printed", "formula_m_per_V": f["lateral_printed"],
                     "plant_m_per_V": G[1, 1]},
                    {"axis": "y, z (lateral)", "formula": "(3.34) corrected, thin wall", "formula_m_per_V": f["lateral_thin"],
                     "plant_m_per_V": G[1, 1]},
                    {"axis": "y, z (lateral)", "formula": "thick wall (1/r field)", "formula_m_per_V": f["lateral_thick"],
                     "plant_m_per_V": G[1, 1]},
                    {"axis": "y, z (lateral)", "formula": "uniform field, exact annulus (gamma_matrix)",
                     "formula_m_per_V": f["lateral"], "plant_m_per_V": G[1, 1]}]
        # the formulas are for the beam/tube end; the plant's reference point may be the rigid holder's
        # end face (FEM body), which adds the end rotation to bending strokes: x (1 + 2 L_h / L)
        at_face = "FEM" in str(plant.provenance.get("body", "")) and v.get("holder") == "meshed"
        fac = act.holder_factor(v["length"], v["holder_length"]) if at_face else 1.0
        for r in rows:
            r["formula_at_plant_point_m_per_V"] = r["formula_m_per_V"] * (1.0 if r["axis"].startswith("x") else fac)
            r["plant_over_formula"] = r["plant_m_per_V"] / r["formula_at_plant_point_m_per_V"]
        out[probe] = {"rows": rows, "gains": plant.provenance["gains"], "body": plant.provenance["body"],
                      "d31": plant.provenance.get("d31"), "holder_factor": fac}
    t1, t2 = preset("table-3.1"), preset("table-3.2")
    w0s = np.linspace(1e-6, 25e-6, 25)
    hs = np.array([5e-6, 10e-6, 20e-6])
    out["fig_3_17"] = {"w0_m": w0s, "h_m": hs,
                       "y_m_per_V": np.array([[act.duo_bimorph_strokes(t1["L"], t1["w"], w0, h, t1["d31"])["y"] for w0 in w0s] for h in hs]),
                       "z_m_per_V": np.array([[act.duo_bimorph_strokes(t1["L"], t1["w"], w0, h, t1["d31"])["z"] for w0 in w0s] for h in hs])}
    Ls = np.linspace(1e-3, 10e-3, 19)
    Res = np.array([0.5e-3, 1e-3, 2e-3])
    out["fig_3_18"] = {"L_m": Ls, "Re_m": Res,
                       "lateral_m_per_V": np.array([[act.tube_strokes(L, Re, Re - 0.05e-3, t2["d31"])["lateral"] for L in Ls] for Re in Res]),
                       "lateral_printed_m_per_V": np.array([[act.tube_strokes(L, Re, Re - 0.05e-3, t2["d31"])["lateral_printed"] for L in Ls] for Re in Res]),
                       "axial_m_per_V": np.array([[act.tube_strokes(L, Re, Re - 0.05e-3, t2["d31"])["x"] for L in Ls] for Re in Res]),
                       "wall_m": 0.05e-3}
    return out


# ---------------------------------------------------------------------------------------------
# the 3.5 control problem
# ---------------------------------------------------------------------------------------------

#: the control design of section 3.5 (slow loop: Kp = kappa K_s, damping zeta; fast: zeta_f)
CONTROL_DEFAULTS = {"stiffness_ratio": 0.2, "zeta": 0.7, "zeta_fast": 0.7}


def default_laws(k: dict | None = None) -> dict[str, Any]:
    c = {**CONTROL_DEFAULTS, **(k or {})}
    return {"open (quasi-static)": ctl.OpenLoop("quasi-static"), "open (dynamic inverse)": ctl.OpenLoop("dynamic"),
            "slow (3.54)": ctl.SlowControl(c["stiffness_ratio"], c["zeta"]),
            "composite (3.50-3.54)": ctl.CompositeControl(c["stiffness_ratio"], c["zeta"], c["zeta_fast"]),
            "PID, same bandwidth": ctl.PID(c["stiffness_ratio"], c["zeta"], 1.0)}


def control_problem(plant: MechanicalPlant) -> dict[str, Any]:
    """Section 3.5 on ``plant`` (``probedyn.probes.tracking.control_plant()``): the matrices of (3.37), Gamma
    (N/V and normalised), the slow model (3.49), the boundary layer (3.57) and the stability of
    every law on the full model, plus the largest stable PID bandwidth."""
    p = plant
    b = p.blocks
    s = ctl.slow_model(b)
    G = b["G"]
    G0 = np.diag(np.diag(G))
    Gn = act.gamma_normalised(G, G0)
    bl = ctl.critical_damping(b["J"], b["K1"] + b["K2"])
    f_bl = np.sqrt(np.diag(b["K1"] + b["K2"]) / np.diag(b["J"])) / (2 * math.pi)
    laws = default_laws()
    stab = {}
    for name, c in laws.items():
        law = c.design(p)
        stab[name] = {**ctl.stability(p, law), "bandwidth_hz": law.info.get("bandwidth_hz")}
    sc = ctl.max_stable_scale(p, lambda x: ctl.PID(CONTROL_DEFAULTS["stiffness_ratio"], CONTROL_DEFAULTS["zeta"], x))
    pid_margin = ctl.PID(CONTROL_DEFAULTS["stiffness_ratio"], CONTROL_DEFAULTS["zeta"], sc / 2).design(p)
    stab["PID, 6 dB gain margin"] = {**ctl.stability(p, pid_margin), "bandwidth_hz": pid_margin.info["bandwidth_hz"],
                                     "gain": sc / 2}
    return {"D": b["D"], "J": b["J"], "C": b["C1"], "C2": b["C2"], "K1": b["K1"], "K2": b["K2"], "Gamma_N_per_V": b["Gamma"],
            "stroke_m_per_V": G, "Gamma_normalised": Gn, "Gamma_normalised_eigenvalues": np.linalg.eigvals(Gn),
            "Kstar": s["Kstar"], "slow_M": s["M"], "slow_K": s["K"], "slow_natural_hz": ctl.natural_slow_hz(p),
            "boundary_layer_hz": f_bl, "plant_hz": p.frequencies_hz(), "C_f_critical": bl,
            "mass_ratio_m_over_J": float(b["D"][0, 0] / np.min(np.diag(b["J"]))),
            "stability": stab, "pid_max_stable_gain": sc, "provenance": p.provenance}


def controller_comparison(plant: MechanicalPlant, *, paths: Sequence[str] = ("cone", "cylinder"),
                          disturbances: Sequence[float] = (0.0, 1.0), duration: float = 1.0, keep: bool = False,
                          laws: dict | None = None) -> dict[str, Any]:
    """Figs 3.21 and 3.22: every law on the full model along the conic and cylindrical paths,
    with the KBr disturbance scaled by each of ``disturbances`` (0: none). Unstable laws are
    reported with their growth rate, not simulated. Per run: RMS and max error per axis, the max
    error after the transient relative to the path extent ("within 1 %?"), peak voltages."""
    p = plant
    laws = laws or default_laws()
    rows, runs = [], {}
    designed = {}
    for name, c in laws.items():
        law = c.design(p)
        designed[name] = (law, ctl.stability(p, law))
    sc = ctl.max_stable_scale(p, lambda x: ctl.PID(CONTROL_DEFAULTS["stiffness_ratio"], CONTROL_DEFAULTS["zeta"], x))
    law6 = ctl.PID(CONTROL_DEFAULTS["stiffness_ratio"], CONTROL_DEFAULTS["zeta"], sc / 2).design(p)
    designed["PID, 6 dB gain margin"] = (law6, ctl.stability(p, law6))
    for kind in paths:
        path = build_path(kind, "piezotube", duration=duration)
        check_range(p, path, V_AMP["piezotube"])
        for ds in disturbances:
            surf = kbr(ds) if ds > 0 else None
            for name, (law, st) in designed.items():
                row = {"path": kind, "disturbance_scale": ds, "control": name, "stable": st["stable"],
                       "growth_rate_per_s": st["max_real_per_s"], "bandwidth_hz": law.info.get("bandwidth_hz")}
                if st["stable"]:
                    res = simulate(p, law, path, surface=surf, v_max=V_AMP["piezotube"])
                    m = res.metrics()
                    row.update(metrics=m, within_1_percent=bool(m["relative_max_error_after_transient"] <= 0.01),
                               wall_s=res.info["wall_s"], step_s=res.info["step_s"])
                    if keep:
                        runs[(kind, ds, name)] = res
                rows.append(row)
    return {"rows": rows, "runs": runs, "provenance": p.provenance, "pid_6db_gain": sc / 2,
            "surface": kbr(1.0).describe()}


# ---------------------------------------------------------------------------------------------
# Tikhonov's O(eps)
# ---------------------------------------------------------------------------------------------


def epsilon_study(plant: MechanicalPlant, *, eps: Sequence[float] = (1.0, 0.5, 0.25, 0.125, 0.0625), duration: float = 0.02,
                  printed: bool = True, holder_only: bool = True) -> dict[str, Any]:
    """Tracking error vs eps on the source's scaling (3.46): ``K1, K2 -> K/eps^2`` with Gamma
    scaled alike (the free stroke per volt is kept) and the damping matrices by 1/eps (so that
    every eps is the same probe in a time scaled by eps, the path is not); the laws are redesigned
    with the same (kappa, zeta, zeta_f), i.e. O(1) gains in the source's sense (C* fixed). A fast
    cone (``duration`` 20 ms, 100 turns/s) keeps the errors far above round-off. Fits the observed
    order ``p`` of max|e| ~ eps^p (least squares in log-log) per law; also reports the stability
    of composite control in the holder-only limit (K1 -> K1/eps^2 alone: the "infinitely rigid
    holder" of the text)."""
    p0 = plant
    path = build_path("cone", "piezotube", duration=duration)
    laws = {"composite (3.50-3.54)": ctl.CompositeControl(0.2, 0.7, 0.7),
            "open (quasi-static)": ctl.OpenLoop("quasi-static"),
            "slow, as printed (no feedforward) + fast": ctl.CompositeControl(0.2, 0.7, 0.7, feedforward=False)}
    if not printed:
        laws.pop("slow, as printed (no feedforward) + fast")
    rows = []
    for e in eps:
        b = p0.blocks
        pe = with_blocks(scaled_stiffness(p0, e), C1=b["C1"] / e, C2=b["C2"] / e)
        for name, c in laws.items():
            law = c.design(pe)
            st = ctl.stability(pe, law)
            row = {"eps": float(e), "control": name, "stable": st["stable"], "min_damping": st["min_damping_ratio"]}
            if st["stable"]:
                res = simulate(pe, law, path, h=duration / 40000)
                m = res.metrics()
                row.update(max_error_m=m["max_error_m"], rms_error_m=m["rms_error_m"])
            rows.append(row)
    fits = {}
    for name in laws:
        r = [x for x in rows if x["control"] == name and "max_error_m" in x]
        if len(r) >= 3:
            x = np.log([q["eps"] for q in r])
            y = np.log([q["max_error_m"] for q in r])
            fits[name] = float(np.polyfit(x, y, 1)[0])
    holder = []
    for e in (eps if holder_only else ()):
        b = p0.blocks
        pe = with_blocks(p0, K1=b["K1"] / e**2, C1=b["C1"] / e)
        st = ctl.stability(pe, ctl.CompositeControl(0.2, 0.7, 0.7).design(pe))
        holder.append({"eps": float(e), "k_t": float(pe.blocks["K1"][0, 0]), "stable": st["stable"],
                       "min_damping": st["min_damping_ratio"], "least_damped_hz": st["least_damped_hz"]})
    return {"rows": rows, "observed_order": fits, "duration_s": duration, "holder_only": holder,
            "path": path.describe()}


# ---------------------------------------------------------------------------------------------
# robustness
# ---------------------------------------------------------------------------------------------


def robustness_study(plant: MechanicalPlant, *, analytic_model: MechanicalPlant | None = None,
                     duration: float = 1.0) -> dict[str, Any]:
    """Composite control and the open-loop dynamic inverse on ``plant`` along the conic path (the
    cylinder for the disturbance cases): nominal; designed on the centred tube's Gamma (a model
    that ignores the eccentricity); designed on ``analytic_model`` (e.g. the analytic Gamma) when
    ``plant`` carries the piezo FEM's; amplifier saturation at +-200 V and at the wall-field limit
    +-15 V; sensor noise 0.1 nm and 2 nm RMS in 10 kHz (2 nm: a capacitive sensor's 20 pm/sqrt(Hz));
    KBr disturbance 1x, 2x, 5x."""
    p = plant
    c = ctl.CompositeControl(CONTROL_DEFAULTS["stiffness_ratio"], CONTROL_DEFAULTS["zeta"], CONTROL_DEFAULTS["zeta_fast"])
    o = ctl.OpenLoop("dynamic")
    cone = build_path("cone", "piezotube", duration=duration)
    cyl = build_path("cylinder", "piezotube", duration=duration)
    G = p.blocks["G"]
    centred = with_blocks(p, Gamma=p.blocks["K2"] @ np.diag(np.diag(G)))
    case = "designed on the centred tube's Gamma (diagonal), plant eccentric (5 um, 5 um)"
    rows = []

    def run(label, plant_, model_, path, **kw):
        for name, ctrl in (("composite", c), ("open (dynamic inverse)", o)):
            law = ctrl.design(model_)
            st = ctl.stability(plant_, law)
            row = {"case": label, "control": name, "path": path.name, "stable": st["stable"]}
            if st["stable"]:
                res = simulate(plant_, law, path, **kw)
                m = res.metrics()
                row.update(max_error_m=m["max_error_m"], rms_error_m=m["rms_error_m"],
                           max_after_m=m["max_error_after_transient_m"],
                           relative=m["relative_max_error_after_transient"], voltage_peak_V=m["voltage_peak_V"],
                           axes={a: v["max_m"] for a, v in m["axes"].items()})
            rows.append(row)

    run("nominal", p, p, cone, v_max=V_AMP["piezotube"])
    run("Gamma mismatch: " + case, p, centred, cone, v_max=V_AMP["piezotube"])
    if analytic_model is not None:
        run("Gamma mismatch: designed on " + str(analytic_model.provenance.get("gains", "the model")).split(",")[0]
            + ", plant with " + str(p.provenance.get("gains", "")).split(" (")[0], p, analytic_model, cone,
            v_max=V_AMP["piezotube"])
    run("saturation +-200 V (amplifier)", p, p, cone, v_max=V_AMP["piezotube"])
    run(f"saturation +-{V_FIELD_TUBE:g} V (wall field)", p, p, cone, v_max=V_FIELD_TUBE)
    run("sensor noise 0.1 nm RMS, 10 kHz", p, p, cone, v_max=V_AMP["piezotube"], noise=SensorNoise(0.1e-9, 10e3, 1))
    run("sensor noise 2 nm RMS, 10 kHz", p, p, cone, v_max=V_AMP["piezotube"], noise=SensorNoise(2e-9, 10e3, 1))
    for sc in (1.0, 2.0, 5.0):
        run(f"KBr disturbance x{sc:g}", p, p, cyl, v_max=V_AMP["piezotube"], surface=kbr(sc))
    return {"rows": rows, "provenance": p.provenance, "mismatch": case}


# ---------------------------------------------------------------------------------------------
# the simulator's independent check
# ---------------------------------------------------------------------------------------------


def foh_error_bound(cl, omega: float, Fhat: np.ndarray, h: float, n_alias: int = 50) -> float:
    """Error of the first-order-hold exponential integrator for the sinusoidal forcing
    ``Re(Fhat e^{i omega t})``: the hold turns it into the fundamental times ``sinc^2(omega h/2)``
    plus images at ``omega + k 2 pi/h`` with weights ``sinc^2((omega + k 2pi/h) h/2)`` (the
    triangle kernel's transform); the tip error is the closed loop's response to their difference
    from the exact input: ``|T(i w)| (1 - sinc^2) |Fhat| + sum_k |T(i (w + k ws))| sinc^2 |Fhat|``
    with ``T(s) = Cy (s I - A_cl)^-1``. Returns that bound [m]."""
    ws = 2 * math.pi / h
    Cy = np.hstack([cl.plant.Cq, np.zeros((cl.d, cl.plant.n))])
    I = np.eye(cl.nX)

    def resp(nu):
        x = np.linalg.solve(1j * nu * I - cl.A, Fhat)
        return float(np.linalg.norm(Cy @ x[:cl.n2] if x.shape[0] > cl.n2 else Cy @ x))

    sinc2 = lambda x: (np.sinc(x / math.pi)) ** 2  # noqa: E731  (np.sinc(x) = sin(pi x)/(pi x))
    b = resp(omega) * (1 - sinc2(omega * h / 2))
    for k in range(1, n_alias + 1):
        for sgn in (1, -1):
            nu = omega + sgn * k * ws
            b += resp(nu) * sinc2(nu * h / 2)
    return b


def frequency_response_check(plant: MechanicalPlant, *, f_path: float = 50.0, radius: float = 0.5e-6,
                             turns: float = 10.0, h: float = 2e-6, controller=None) -> dict[str, Any]:
    """For a linear closed loop (composite control on the piezotube) and a circle at ``f_path``
    turns/s in the (y, z) plane, compare the simulated error during one turn late in the
    constant-speed phase with the steady state from the closed-loop transfer function
    (:func:`forced_response`). Tolerance from the integrator: the exponential integrator is exact
    for a piecewise-linear forcing, so its only error is the first-order hold of the sinusoidal
    forcing (:func:`foh_error_bound`, summed over the path's sinusoids), plus what is left of the
    start transient, ``max|e| exp(-sigma t)`` (sigma: the closed loop's slowest decay rate), plus
    the round-off of ``y - r`` (64 ulp of the path radius)."""
    p = plant
    law = (controller or ctl.CompositeControl(0.2, 0.7, 0.7)).design(p)

    T = turns / f_path
    ramp = 2.0 / f_path
    path = TimedPath(circle(radius, "yz", turns), Timing(T, "cruise", ramp))
    res = simulate(p, law, path, h=h, max_points=10**7)
    t = res.t
    t1 = T - ramp
    last = (t > t1 - 1.0 / f_path) & (t < t1)
    e_tf = forced_response(p, law, path, t[last])
    diff = float(np.max(np.abs(res.e[last] - e_tf)))
    cl = ClosedLoop(p, law, path)
    v0 = 1.0 / (T - ramp)
    tol_foh = 0.0
    for term in path.geometry.terms:
        if term.omega == 0:
            continue
        ax = np.asarray(term.axis)
        rhat = np.array([ax["xyz".index(a)] for a in p.outputs], dtype=complex) * term.amp
        w = term.omega * v0
        R = np.array([[(1j * w) ** k * rhat] for k in range(5)])
        wu = np.asarray(law.w(R, np.array([0.0])), dtype=complex)[0]
        Fhat = cl.Bu @ wu
        tol_foh += foh_error_bound(cl, w, Fhat, h)
    lam = np.linalg.eigvals(cl.A)
    sigma = float(-lam.real.max())
    tol_tr = float(np.max(np.abs(res.e))) * math.exp(-sigma * (t1 - 1.0 / f_path - ramp))
    tol_ro = 64 * np.finfo(float).eps * radius
    tol = tol_foh + tol_tr + tol_ro
    return {"f_path_hz": f_path, "radius_m": radius, "step_s": h, "max_abs_difference_m": diff,
            "tolerance_m": tol, "tolerance_foh_m": tol_foh, "tolerance_transient_m": tol_tr, "tolerance_roundoff_m": tol_ro,
            "forced_error_amplitude_m": float(np.max(np.abs(e_tf))), "decay_rate_per_s": sigma,
            "controller": law.name, "agrees": bool(diff <= tol)}
