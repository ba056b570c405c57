"""Checks and studies of reduced probes (issue "one pipeline"; docs/reduced-probes.md).

* :func:`apex_check` - FFM's spring at the tip apex: FEM static solves vs torsion through the tip
  height in series with lateral bending (:mod:`probedyn.lumped.apex`), normal stiffness and
  first-mode effective masses vs Euler–Bernoulli;
* :func:`truncation_check` - the reduced probe's point compliance vs the FEM's direct frequency
  response at fractions of the validity limit, with and without the static correction;
* :func:`build_vs_reuse` - wall time of a reduction from geometry and of its reuse from the cache.
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping, Sequence

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.lumped import apex as ax
from probedyn.lumped.reduced import DIRECTIONS, ReducedProbe
from probedyn.lumped.ritz import direct_compliances
from probedyn.probes import get_probe
from probedyn.probes.reduce import reduce_probe
from probedyn.schemes import pushing as pu
from probedyn.schemes.contact import get_contact_model
from probedyn.schemes.contact.force_curve import force_curve
from probedyn.schemes.ffm import FFM
from probedyn.schemes.ffm_modal import ModalFFM, line_scan, modal_participation
from probedyn.schemes.stickslip_analysis import analyze

#: the default FFM cantilever: the registry's cantilever with its default pyramid tip
FFM_CANTILEVER = {"tip_shape": "pyramid"}


def apex_check(overrides: Mapping[str, Any] | None = None, above_apex: Sequence[float] = (1e-6, 2e-6)) -> dict[str, Any]:
    """FEM vs beam references at the apex of a cantilever with a tip (module docstring).

    FEM: static stiffness along y (scan), z (normal) and x at the apex (named point ``tip``), at
    points ``above_apex`` [m] up the tip axis (where the sharp apex's mesh-dependent local
    compliance has decayed) and at the centre of the tip base (the beam alone); effective masses
    at the apex of the first lateral and flapwise modes. References: the printed form (x = L,
    no shear), the refined one (apex x, Timoshenko shear), Euler–Bernoulli masses with the tip."""
    p, _ = get_probe("cantilever")
    v = p.resolve({**FFM_CANTILEVER, **dict(overrides or {})})
    if v["tip_shape"] == "none":
        raise ParameterError("apex_check needs a tip (tip_shape pyramid or cone)")
    model = p.build(v)
    apex = np.asarray(p.tip_point(v), dtype=float)
    beam = p.beam(v)
    t0 = time.perf_counter()
    ey, ez, ex = (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)
    fem = {"apex": {"scan": model.static_stiffness("tip", ey), "normal": model.static_stiffness("tip", ez),
                    "lateral": model.static_stiffness("tip", ex)}}
    for s in above_apex:
        pt = tuple(apex + np.array([0.0, 0.0, s]))
        fem[f"apex+{s * 1e6:g}um"] = {"scan": model.static_stiffness(pt, ey), "normal": model.static_stiffness(pt, ez)}
    base = (float(apex[0]), 0.0, -v["thickness"] / 2)
    fem["tip_base"] = {"scan": model.static_stiffness(base, ey), "normal": model.static_stiffness(base, ez)}
    static_s = time.perf_counter() - t0
    res = model.modes(4)
    lat, flap = res.first("lateral"), res.first("flapwise")
    m_tip = float(model.region_masses().get("tip", 0.0))
    h = v["tip_height"]
    x_a = float(apex[0])
    printed = ax.scan_stiffness(beam, h)
    refined = ax.scan_stiffness(beam, h, x=x_a, shear=True)
    ref_normal = {"printed": ax.bending_stiffness(beam, "flapwise"),
                  "refined": ax.bending_stiffness(beam, "flapwise", x=x_a, shear=True)}
    # the tip's centroid is h/4 above its base; its mass rides on the beam at the apex's x
    m_eff_ref = ax.first_mode_effective_mass(beam, x=x_a, tip_mass=m_tip, tip_x=x_a)
    return dict(
        parameters=dict(v), dofs=model.dofs, apex=apex, x_apex=x_a, lever=printed["lever"], beta=printed["beta"],
        fem=fem, formula_printed=printed, formula_refined=refined, normal_reference=ref_normal,
        effective_mass=dict(
            scan_fem=float(lat.effective_mass_tip["y"]), normal_fem=float(flap.effective_mass_tip["z"]),
            beam_quarter_mass=0.25 * beam.mass, beam_at_apex_with_tip=m_eff_ref, tip_mass=m_tip,
            lateral_mode_hz=lat.frequency_hz, flapwise_mode_hz=flap.frequency_hz),
        static_solve_s=static_s,
    )


def truncation_check(rp: ReducedProbe, fractions: Sequence[float] = (0.5, 0.9),
                     directions: Sequence[str] = DIRECTIONS) -> list[dict[str, Any]]:
    """Point compliance of ``rp`` (undamped modal superposition, with and without the static
    correction) vs the FEM's direct frequency response at ``fractions`` of ``validity_hz``.

    Rows per direction and frequency: ``H_fem``, the two reduced values, their relative errors,
    the errors as fractions of the static compliance, and the rigorous bound of the corrected
    error ``R x^2 / (1 - x^2)`` (R: residual compliance, x = f / validity)."""
    if rp.ritz is None or rp.ritz.model is None:
        raise ParameterError("truncation_check needs a FEM-reduced probe with its model attached")
    rows = []
    f = np.asarray(fractions, dtype=float) * rp.validity_hz
    # one factorisation per frequency for all directions (they are right-hand sides of one solve)
    HH = direct_compliances(rp.ritz.model, rp.point, [rp.frame[DIRECTIONS.index(d)] for d in directions], f)
    for d, H in zip(directions, HH):
        Hc = rp.compliance(d, f, damped=False).real
        Hn = rp.compliance(d, f, static_correction=False, damped=False).real
        C = 1.0 / rp.static_stiffness(d)
        R = rp.residual_compliance(d)
        for j, x in enumerate(fractions):
            rows.append(dict(direction=d, fraction=float(x), frequency_hz=float(f[j]), H_fem=float(H[j]),
                             H_corrected=float(Hc[j]), H_modes_only=float(Hn[j]),
                             rel_err_corrected=float(Hc[j] / H[j] - 1), rel_err_modes_only=float(Hn[j] / H[j] - 1),
                             err_over_static_corrected=float((Hc[j] - H[j]) / C),
                             err_over_static_modes_only=float((Hn[j] - H[j]) / C),
                             bound_over_static=float(R * x**2 / (1 - x**2) / C), residual_share=float(R / C),
                             H_fem_over_static=float(H[j] / C)))
    return rows


def build_vs_reuse(probe: str = "cantilever", overrides: Mapping[str, Any] | None = None, n_modes: int = 6,
                   **kw: Any) -> dict[str, Any]:
    """Wall time of a reduction from geometry (mesh + modes + static solves, cache bypassed and
    then stored) and of loading it back from the cache (same process)."""
    ov = {**FFM_CANTILEVER, **dict(overrides or {})} if probe == "cantilever" else dict(overrides or {})
    t0 = time.perf_counter()
    rp = reduce_probe(probe, ov, n_modes=n_modes, cache=False, **kw)
    build = time.perf_counter() - t0
    reduce_probe(probe, ov, n_modes=n_modes, cache=True, **kw)  # store (a miss unless stored before)
    t0 = time.perf_counter()
    again = reduce_probe(probe, ov, n_modes=n_modes, cache=True, **kw)
    reuse = time.perf_counter() - t0
    return dict(build_s=build, reuse_s=reuse, ratio=build / reuse, cache=again.provenance.get("cache"),
                dofs=rp.provenance.get("dofs"), n_modes=n_modes)


# ------------------------------------------------------------------------------------------
# FFM on a reduced probe, the geometry study and the higher-modes study
# ------------------------------------------------------------------------------------------

#: damping assumed for the FEM-reduced probes of the studies (a cantilever in air; the same Q for
#: every geometry, so that the dynamic factor of the stick-slip period does not change with it)
STUDY_Q = 100.0
#: the study geometries: one parameter of the default FFM cantilever changed at a time
GEOMETRY_VARIANTS: tuple[tuple[str, float | None], ...] = (
    ("base", None), ("thickness", 3e-6), ("thickness", 5e-6), ("thickness", 15e-6), ("length", 200e-6),
    ("length", 400e-6),
    ("tip_height", 5e-6), ("tip_height", 20e-6),
)
QUICK_VARIANTS: tuple[tuple[str, float | None], ...] = (("base", None), ("thickness", 5e-6), ("tip_height", 20e-6))
COARSE = {"elements_through_thickness": 1}


def ffm_scan(probe: ReducedProbe, preset: str = "vamwcnt", n_modes: int | None = None, V: float | None = None,
             n_periods: float = 6.0, length: float | None = None, rtol: float = 1e-5) -> dict[str, Any]:
    """One FFM line scan of ``probe`` (scan direction) with the friction of an FFM preset
    (``mica`` = Table 2.1, ``vamwcnt`` = Table 2.2), the one-mode model (``n_modes=None``:
    static stiffness + dominant mode's mass and damping) or N modes + static residual.  Default
    length: the first slip ``F_s / k`` plus ``n_periods`` quasi-static periods ``(F_s - F_c)/k``
    (at least 3 F_s / k).  Predictions from the reduced probe alone: the quasi-static period
    ``(F_s - F_c)/k`` (exact for a critically damped probe; an underdamped slip overshoots and
    the period grows with it, by the same factor for every geometry of the same damping), the
    amplitude ``(F_s - F_c)(1 + exp(-pi zeta/sqrt(1 - zeta^2)))`` (the overshoot of a slip of
    an oscillator of damping ratio zeta from F_s towards F_c) and the first slip ``F_s / k``.
    Returns them, the measured stick-slip (:func:`stickslip_analysis.analyze`) and the trace."""
    base = FFM.from_preset(preset)
    fm = base.friction
    Fs, Fc = fm.values["F_s"], fm.values["F_c"]
    V = base.cantilever["V"] if V is None else float(V)
    ch = ModalFFM.from_probe(probe, fm, V, n_modes=n_modes)
    k = ch.k_static
    # at least three times the first-slip travel, so that smooth sliding is seen as such
    L = max(Fs / k + n_periods * (Fs - Fc) / k, 3.0 * Fs / k) if length is None else float(length)
    # dominant oscillator's damping ratio -> overshoot of an underdamped slip, exp(-pi z / sqrt(1 - z^2))
    i = int(np.argmax(1.0 / ch.stiffnesses))
    zeta = ch.dampings[i] / (2.0 * math.sqrt(ch.stiffnesses[i] * ch.masses[i]))
    overshoot = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2)) if zeta < 1 else 0.0
    t0 = time.perf_counter()
    r = line_scan(ch, L, rtol=rtol)
    wall = time.perf_counter() - t0
    an = analyze(r.base, r.lateral_force)
    amp = _raw_amplitude(r.base, r.lateral_force, an) if an["n_slips"] else None
    return dict(preset=preset, V=V, k_scan=k, n_modes=n_modes, labels=ch.labels, damping_ratio=zeta,
                predicted_period_m=(Fs - Fc) / k, predicted_amplitude_n=(Fs - Fc) * (1.0 + overshoot),
                predicted_first_slip_m=Fs / k,
                period_m=an["period_m"], amplitude_n=amp, first_slip_m=an["first_slip_m"], regime=an["regime"],
                n_slips=an["n_slips"], max_force_n=an["max_force_n"], min_force_n=an.get("kinetic_friction_n"),
                wall_s=wall, n_steps=r.n_steps, trace=r)


def _raw_amplitude(base: np.ndarray, force: np.ndarray, an: Mapping[str, Any]) -> float:
    """Mean peak-to-valley force of the slips on the integrator's own samples (the analysis
    resamples the trace on a uniform base grid, which under-samples the fast slips' minima)."""
    pk = list(an["peaks_m"]) + [float(base[-1])]
    amps = []
    for b0, b1 in zip(pk[:-1], pk[1:]):
        seg = (base >= b0) & (base <= b1)
        if seg.sum() >= 2:
            amps.append(float(force[seg].max() - force[seg].min()))
    return float(np.mean(amps)) if amps else math.nan


def jump_to_contact(k_normal: float, model: str = "dmt") -> dict[str, Any]:
    """Jump-to-contact of a cantilever of normal stiffness ``k_normal`` over a contact model of
    the registry (Table 4.1 tip/sample): the tail prediction ``d* = (H R / 3k)^(1/3)`` and the
    force-curve simulation."""
    m = get_contact_model(model)
    fc = force_curve(m, k_normal)
    ji, jo = fc["jump_in"], fc["jump_out"]
    pred = fc["predicted_tail_jump_gap"]
    return dict(k_normal=k_normal, model=model, predicted_gap_m=pred, tail_end_gap_m=fc["tail_end_gap"],
                predicted_jump=bool(pred > fc["tail_end_gap"]),
                jump_in=ji is not None and ji["in_tail"], jump_in_gap_m=None if ji is None else ji["gap_before"],
                jump_in_force_n=None if ji is None else ji["P_before"],
                jump_out_force_n=None if jo is None else jo["P_before"], pull_off_n=m.pull_off_force())


def pushing_prediction(k_tip: float, substrate: str = "mica") -> dict[str, Any]:
    """Nano-pushing predicted from the tip stiffness (section 4.1.1, docs/pushing.md): the tip
    spring in series with the Hertz contact at the kinetic load, ``k_s``; the step is one lattice
    constant (the pinning potential recaptures the sample in the next well: the quasi-static
    slip ``(F_s - F_c)/k_s``, reported, is about one lattice constant for every tip stiffness
    because the ~3 N/m contact dominates ``k_s``); the stick-slip -> sliding boundary from the
    quasi-static Prandtl–Tomlinson criterion ``eta(V) = 2 pi (F_s - F_c) exp(-(V/V_s)^2) / (a k_s) = 1``."""
    m = pu.make_model(substrate, {"k_tx": float(k_tip)})
    p = m.p
    ks = m.k_series(p["F_c"])
    dF = p["F_s"] - p["F_c"]
    eta0 = 2 * math.pi * dF / (p["a"] * ks)
    return dict(k_tip=k_tip, k_series=ks, eta0=eta0, lattice_m=p["a"], slip_qs_m=dF / ks,
                predicted_step_m=p["a"],
                predicted_transition_m_s=p["V_s"] * math.sqrt(math.log(eta0)) if eta0 > 1 else 0.0)


def geometry_study(variants: Sequence[tuple[str, float | None]] = GEOMETRY_VARIANTS, n_modes: int = 4,
                   mesh: Mapping[str, Any] | None = None, ffm_presets: Sequence[str] = ("vamwcnt",),
                   base_probe: ReducedProbe | None = None) -> list[dict[str, Any]]:
    """The default FFM cantilever with one of thickness, length, tip height changed (``variants``):
    per geometry the reduced stiffnesses and masses, and for each scheme the prediction from
    them and the simulation (FFM period/amplitude/regime, jump-to-contact, pushing predictions).
    ``base_probe``: an already reduced default geometry to use for the ``("base", None)`` row."""
    rows = []
    for name, value in variants:
        ov = dict(FFM_CANTILEVER, **(COARSE if mesh is None else dict(mesh)))
        if value is not None:
            ov[name] = value
        if value is None and base_probe is not None:
            rp = base_probe
        else:
            rp = reduce_probe("cantilever", ov, n_modes=n_modes, Q=STUDY_Q)
        row: dict[str, Any] = dict(variant=name, value=value, k_scan=rp.static_stiffness("scan"),
                                   k_normal=rp.static_stiffness("normal"), m_scan=rp.effective_mass("scan"),
                                   m_normal=rp.effective_mass("normal"), validity_hz=rp.validity_hz,
                                   dofs=rp.provenance.get("dofs"), build_s=rp.provenance.get("build_s"))
        for pr in ffm_presets:
            s = ffm_scan(rp, pr)
            s.pop("trace")
            row[f"ffm_{pr}"] = s
        row["contact"] = jump_to_contact(row["k_normal"])
        row["pushing"] = pushing_prediction(row["k_scan"])
        rows.append(row)
    return rows


def higher_modes_study(probe: ReducedProbe | None = None, speeds: Sequence[float] = (2e-6, 2e-4),
                       n_list: Sequence[int | None] = (None, 1, 2, 4), reference: int = 6, preset: str = "vamwcnt",
                       n_periods: float = 5.0) -> dict[str, Any]:
    """FFM scans of one probe with the one-mode model (``None``), 1, 2, 4 modes (+ static
    residual) and a reference with ``reference`` modes, at slow and fast scan speeds.

    Per run: period, amplitude, first slip, regime and their relative differences from the
    reference; the slip duration (mean time per slip with the tip faster than twice the base)
    against the period of the first mode left out (``T_next``) and the step-response velocity
    ratio of the scan modes (:func:`probedyn.schemes.ffm_modal.modal_participation`)."""
    if probe is None:
        probe = reduce_probe("cantilever", dict(FFM_CANTILEVER, **COARSE), n_modes=12, Q=STUDY_Q)
    part = modal_participation(probe, "scan")
    order = sorted(part, key=lambda r: -r["participation"])
    runs = []
    for V in speeds:
        ref = ffm_scan(probe, preset, n_modes=reference, V=V, n_periods=n_periods)
        L = ref["trace"].base[-1]
        for n in list(n_list) + [reference]:
            s = ref if n == reference else ffm_scan(probe, preset, n_modes=n, V=V, length=L)
            tr = s.pop("trace") if "trace" in s else None
            slip_t = None
            if tr is not None and s["n_slips"]:
                fast = tr.v > 2.0 * V
                dt = np.diff(tr.t)
                slip_t = float(np.sum(dt[fast[:-1]]) / s["n_slips"])
            kept = 1 if n is None else n
            nxt = order[kept] if kept < len(order) else None
            rel = {}
            for key in ("period_m", "amplitude_n", "first_slip_m"):
                a, b = s.get(key), ref.get(key)
                rel[key] = (a / b - 1) if (a is not None and b) else None
            runs.append(dict(V=V, n_modes=n, labels=s["labels"], period_m=s["period_m"], amplitude_n=s["amplitude_n"],
                             first_slip_m=s["first_slip_m"], regime=s["regime"], n_slips=s["n_slips"],
                             rel_diff=rel, slip_time_s=slip_t,
                             next_mode_period_s=None if nxt is None else 1.0 / nxt["frequency_hz"],
                             next_mode_velocity_ratio=None if nxt is None else nxt["step_velocity_ratio"],
                             wall_s=s["wall_s"]))
        ref.pop("trace", None)
    return dict(participation=part, runs=runs, validity_hz=probe.validity_hz, k_scan=probe.static_stiffness("scan"))


# ------------------------------------------------------------------------------------------
# Geometry and the pushing regime boundary; a mesh-independent apex stiffness
# ------------------------------------------------------------------------------------------

#: pushing-boundary geometries: the default FFM cantilever, a thinner one, and a soft narrow
#: contact-mode lever (400 x 15 x 2 um, ~1e5 DOFs with one element layer) whose scan spring
#: (~4 N/m: lateral bending of the narrow beam) is comparable to the ~3 N/m Hertz contact, so
#: that the tip stiffness moves the boundary
PUSH_VARIANTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("default", {}),
    ("thickness 3 um", {"thickness": 3e-6}),
    ("soft lever 400 x 15 x 2 um", {"thickness": 2e-6, "width": 15e-6, "length": 400e-6}),
)


def pushing_boundary(overrides: Mapping[str, Any] | None = None, substrate: str = "mica", n_modes: int = 4,
                     rel_tol: float = 0.02, label: str = "") -> dict[str, Any]:
    """The stick-slip -> sliding speed of nano-pushing (section 4.1.1) with the tip of a
    FEM-reduced cantilever (``schemes.probe_hooks.pushing_tip``: static scan stiffness, effective
    mass and damping at the apex): **predicted** from the reduced stiffness by the quasi-static
    Prandtl–Tomlinson criterion (:func:`pushing_prediction`, the tip spring in series with the
    Hertz contact) and **simulated** by bisection on pushes from rest
    (``schemes.pushing.transition_speed``, ``rel_tol`` bracket; the upper end is raised from 1.6
    to 6.4 x the prediction while still stick-slip), plus the mean step of a push at the default
    speed (3 um/s) against one lattice constant."""
    ov = dict(FFM_CANTILEVER, **COARSE)
    ov.update(dict(overrides or {}))
    rp = reduce_probe("cantilever", ov, n_modes=n_modes, Q=STUDY_Q)
    tip = pu_tip(rp)
    pred = pushing_prediction(tip["k_tx"], substrate)
    Vp = pred["predicted_transition_m_s"]
    t0 = time.perf_counter()
    _, an = pu.push(substrate, dict(tip))
    tr = None
    for hi in (1.6, 3.2, 6.4):  # widen the bracket upwards while the top is still stick-slip
        try:
            tr = pu.transition_speed(substrate, dict(tip), lo=0.8 * Vp, hi=hi * Vp, rel_tol=rel_tol)
            break
        except ParameterError as exc:
            if "upper speed" not in str(exc) or hi == 6.4:
                raise
    return dict(label=label, overrides={k: v for k, v in (overrides or {}).items()}, dofs=rp.provenance.get("dofs"),
                tip=tip, prediction=pred, step_m=an.get("mean_step_m"),
                step_lengths_over_a=[float(x) / pred["lattice_m"] for x in an.get("step_lengths_m", [])],
                site_hops=an.get("site_hops"), n_slips=an.get("n_slips"),
                tip_damping_ratio=tip["c_t"] / (2 * math.sqrt(tip["k_tx"] * tip["m_tx"])), step_over_a=(an.get("mean_step_m") or math.nan) / pred["lattice_m"],
                regime_slow=an.get("regime"), V_sim_m_s=tr["V_transition_m_s"], V_bracket_m_s=(tr["V_low_m_s"], tr["V_high_m_s"]),
                ratio_sim_over_pred=tr["V_transition_m_s"] / Vp, evaluations=tr["evaluations"],
                wall_s=time.perf_counter() - t0)


def pu_tip(rp: ReducedProbe) -> dict[str, float]:
    """Nano-pushing's tip parameters of a reduced probe (``schemes.probe_hooks.pushing_tip``)."""
    from probedyn.schemes.probe_hooks import pushing_tip

    return pushing_tip(rp)


def pushing_boundary_study(variants: Sequence[tuple[str, Mapping[str, Any]]] = PUSH_VARIANTS,
                           substrate: str = "mica") -> list[dict[str, Any]]:
    """:func:`pushing_boundary` for each geometry; the prediction's *shift* between geometries
    (``V_pred / V_pred(first)``) against the simulated one is the check that the geometry acts
    through the reduced stiffness as predicted."""
    rows = [pushing_boundary(ov, substrate, label=name) for name, ov in variants]
    for r in rows:
        r["pred_shift"] = r["prediction"]["predicted_transition_m_s"] / rows[0]["prediction"]["predicted_transition_m_s"]
        r["sim_shift"] = r["V_sim_m_s"] / rows[0]["V_sim_m_s"]
    return rows


def observed_order(h: Sequence[float], q: Sequence[float]) -> tuple[float, float]:
    """Observed convergence order p and the Richardson limit of ``q(h) = q* + C h^p`` from three
    (h, q) pairs (any refinement ratios): solves ``(q1 - q2)/(q2 - q3) = (h1^p - h2^p)/(h2^p - h3^p)``."""
    from scipy.optimize import brentq

    h1, h2, h3 = (float(x) for x in h[-3:])
    q1, q2, q3 = (float(x) for x in q[-3:])
    ratio = (q1 - q2) / (q2 - q3)
    f = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - ratio  # noqa: E731
    try:
        p = brentq(f, 0.05, 12.0)
    except ValueError:
        return math.nan, math.nan
    C = (q2 - q3) / (h2**p - h3**p)
    return float(p), float(q3 - C * h3**p)


def apex_patch_convergence(radius: float = 4e-6, layers: Sequence[int] = (1, 2, 3),
                           overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Static stiffness at the apex of the default FFM cantilever's tip for a load spread over the
    tip surface within ``radius`` of the apex (Hertz-like weight, :func:`probedyn.lumped.apex.apex_patch_operator`)
    on meshes of ``layers`` element layers through the thickness (h = t / layers), beside the
    point-load value at the apex (which diverges like 1/h); observed order and Richardson limit
    of the patch values."""
    p, _ = get_probe("cantilever")
    rows = []
    for n in layers:
        v = p.resolve({**FFM_CANTILEVER, **dict(overrides or {}), "elements_through_thickness": int(n)})
        model = p.build(v)
        apex = np.asarray(p.tip_point(v), dtype=float)
        t0 = time.perf_counter()
        A, info = ax.apex_patch_operator(model, apex, radius)
        ks, kn, kl = ax.patch_stiffness(model, A, [(0, 1, 0), (0, 0, 1), (1, 0, 0)])
        rows.append(dict(layers=int(n), h=v["thickness"] / n, dofs=model.dofs, k_scan=ks, k_normal=kn, k_lateral=kl,
                         k_scan_point=model.static_stiffness("tip", (0.0, 1.0, 0.0)), patch_facets=info["facets"],
                         patch_area=info["area"], solve_s=time.perf_counter() - t0))
    out: dict[str, Any] = dict(radius=radius, rows=rows)
    if len(rows) >= 3:
        h = [r["h"] for r in rows]
        for key in ("k_scan", "k_normal", "k_scan_point"):
            out[f"order_{key}"], out[f"limit_{key}"] = observed_order(h, [r[key] for r in rows])
    return out
