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

from probedyn.lumped import apex as ax
from probedyn.lumped.reduced import DIRECTIONS, ReducedProbe
from probedyn.lumped.ritz import direct_compliance
from probedyn.probes import get_probe
from probedyn.probes.reduce import reduce_probe

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
        from probedyn.core.errors import ParameterError

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


def truncation_check(rp: ReducedProbe, fractions: Sequence[float] = (0.5, 0.9)) -> list[dict[str, Any]]:
    """Point compliance of ``rp`` (undamped modal superposition, with and without the static
    correction) vs the FEM's direct frequency response at ``fractions`` of ``validity_hz``.

    Rows per direction and frequency: ``H_fem``, the two reduced values, their relative errors,
    the errors as fractions of the static compliance, and the rigorous bound of the corrected
    error ``R x^2 / (1 - x^2)`` (R: residual compliance, x = f / validity)."""
    if rp.ritz is None or rp.ritz.model is None:
        from probedyn.core.errors import ParameterError

        raise ParameterError("truncation_check needs a FEM-reduced probe with its model attached")
    rows = []
    f = np.asarray(fractions, dtype=float) * rp.validity_hz
    for i, d in enumerate(DIRECTIONS):
        H = direct_compliance(rp.ritz.model, rp.point, rp.frame[i], f)
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
                             bound_over_static=float(R * x**2 / (1 - x**2) / C), residual_share=float(R / C)))
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
