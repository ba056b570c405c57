"""FFM studies built on :mod:`probedyn.schemes.ffm` (section 2.1.5), shared by the command line
and the report:

* :func:`run_ffm_to_regime`: the preset's scan, extended when it ends before the first slip
  (departure "Tables 2.1/2.2 vs the scans": the first slip needs ``F_s / k_x`` of base
  travel) so that the stick-slip regime is measured; the preset's own scan is reported too;
* :func:`deviation_2d_1d`: the full 2D model (2.10)-(2.12), (2.14), (2.16) against the 1D
  reduction, largest difference of the lateral force;
* :func:`pt_trace`: a Prandtl–Tomlinson scan on the mica lattice by the Tomlinson parameter eta;
* :func:`fit_recovery`: a synthetic mica trace with Gaussian noise, fitted back.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from probedyn.core.presets import preset as table
from probedyn.schemes import ffm as F
from probedyn.schemes import fit as FT


def run_ffm_to_regime(preset: str = "mica", model: str = "bristle", overrides: Mapping[str, Any] | None = None,
                      length: float | None = None, probe: Any = None) -> tuple[F.ScanResult, dict[str, Any]]:
    """:func:`probedyn.schemes.ffm.run_ffm`; without an explicit ``length``, a scan of the
    preset's range that stays in pre-sliding is extended to ``1.05 F_s/k_x + 4 (F_s - F_c)/k_x``
    (the first slip plus four periods) and the summary gets ``preset_scan`` (the preset range's
    regime, maximum force and slips, and a note saying why the scan was extended).  ``probe``: a
    reduced probe driving the cantilever (:func:`probedyn.schemes.ffm.run_ffm`)."""
    ov = dict(overrides or {})
    note = None
    if probe is not None and length is None:
        # the preset's scan range was chosen for the table's soft spring; a probe's own spring sets
        # the scale: the first slip plus eight quasi-static periods
        ffm = F.FFM.from_preset(preset, model, ov, probe=probe)
        lv = ffm.friction.levels()
        if lv:
            k = ffm.cantilever["k_x"]
            length = 1.05 * lv[0] / k + 8.0 * (lv[0] - lv[1]) / k
            note = (f"scan length set by the probe's spring: 1.05 F_s/k_x + 8 (F_s-F_c)/k_x = {length * 1e9:.4g} nm "
                    f"(the preset's range is {ffm.cantilever['length'] * 1e9:.4g} nm)")
    res, summary = F.run_ffm(preset, model, ov, length=length, probe=probe)
    if note:
        summary["scan_note"] = note
    if length is None and summary["regime"] == "presliding" and summary.get("first_slip_estimate_m"):
        source = {k: summary[k] for k in ("scan_length_m", "regime", "max_force_n", "n_slips")}
        auto = 1.05 * summary["first_slip_estimate_m"] + 4.0 * (summary["period_estimate_m"] or 0.0)
        res, summary = F.run_ffm(preset, model, ov, length=max(auto, summary["scan_length_m"]), probe=probe)
        summary["preset_scan"] = {
            **source,
            "note": f"no slip within the preset's {source['scan_length_m'] * 1e9:.3g} nm scan: the first slip "
                    f"needs F_s/k_x = {summary['first_slip_estimate_m'] * 1e9:.4g} nm of base travel "
                    "(docs/source-departures.md, Tables 2.1/2.2 vs the scans); the scan was extended to "
                    "measure the stick-slip",
        }
    return res, summary


def deviation_2d_1d(preset: str = "mica", length: float = 80e-9, n_out: int = 3000) -> float:
    """Largest |difference| [N] of the lateral force between the full 2D model and the 1D
    reduction over ``length`` (the y-motion relaxes in ~c_y/k_y and then leaves x alone)."""
    full = F.line_scan_2d(F.FFM.from_preset(preset), length, n_out=n_out)
    one = F.line_scan(F.FFM.from_preset(preset), length)
    return float(np.max(np.abs(np.interp(full["base"], one.base, one.lateral_force) - full["lateral_force"])))


def pt_trace(eta: float, n_lattice: float = 6, preset: str = "mica") -> F.ScanResult:
    """A 1D Prandtl–Tomlinson line scan with the cantilever of ``preset`` on the mica lattice
    (Table 4.2), ``U0 = eta k_x a^2 / (4 pi^2)``, over ``n_lattice`` lattice constants."""
    a = table("table-4.2-mica")["a"]
    k = F.FFM.from_preset(preset).cantilever["k_x"]
    U0 = eta * k * a * a / (4 * math.pi**2)
    return F.line_scan(F.FFM.from_preset(preset, "pt", {"U0": U0, "a": a}), n_lattice * a)


def fit_recovery(true: Mapping[str, float] | None = None, length: float = 90e-9, n_points: int = 1500,
                 noise: float = 0.05e-9, seed: int = 1) -> dict[str, Any]:
    """Fit F_s and F_c back from a synthetic mica trace (FFM model with the ``true`` levels,
    resampled at ``n_points`` base positions, Gaussian noise of ``noise`` N). Returns the fit
    of :func:`probedyn.schemes.fit.fit_trace` and ``rows`` (parameter, true, fit, 1-sigma,
    relative error)."""
    true = dict(true or {"F_s": 13.4e-9, "F_c": 12.6e-9})
    cant = table("table-2.1")
    r = F.line_scan(F.FFM.from_preset("mica", overrides=true), length)
    b = np.linspace(0, length, n_points)
    rng = np.random.default_rng(seed)
    fn = np.interp(b, r.base, r.lateral_force) + rng.normal(0, noise, b.size)
    fr = FT.fit_trace(FT.Trace(base=b, force=fn, meta=dict(speed=cant["V"], k_x=cant["k_x"])), noise=None)
    rows = [dict(name=n, true=true[n], fit=fr["values"][n], err=fr["uncertainties"][n],
                 rel=(fr["values"][n] - true[n]) / true[n]) for n in ("F_s", "F_c")]
    return {**fr, "rows": rows, "noise_n": noise, "n_points": n_points}
