"""Real data for the spectrum and force-curve kinds (numbers quoted in docs/diagnose.md).

1. The Marohn-lab Brownian PSD (examples/measurements/brownian_psd_vacuum.csv, see its .md): the peak
   found by :func:`probedyn.diagnose.spectrum.detect_peaks`, its SHO line on a white + 1/f background by
   maximum likelihood of the 32-times averaged periodogram (:func:`fit_line`), the stiffness from
   equipartition ``k = k_B T / area`` -- against the authors' own fit (independent reference). Held-out
   error: the bins are split into even and odd; each model (background only = "before", line +
   background = "after") is fitted on one half and its deviance residuals are evaluated on the other;
   the held-out RMS is 1 for a model consistent with the chi^2_{2N}/(2N) statistics.
2. The JPK QI force curve (examples/measurements/afm_force_curve_jpk_qi.toml): the full diagnosis.

Usage: ``python benchmarks/diagnose_realdata_curves.py [OUT.json]``.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from probedyn.diagnose.engine import run
from probedyn.diagnose.spectrum import K_B, detect_peaks, fit_line, gamma_deviance_residuals, log_scatter, sho_psd

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples" / "measurements"
N_AVG, T = 32, 298.0
AUTHORS = {"f0_Hz": 70561.35, "f0_sigma_Hz": 0.04, "Q": 2.9e4, "Q_sigma": 0.1e4, "k_N_per_m": 22.3, "k_sigma": 0.8}


def _heldout(freq, psd, fit):
    """Held-out deviance RMS of background-only and line+background models (even/odd bins)."""
    f0, Q, A = fit["f0_Hz"], fit["Q"], fit["area_m2"] * 2 / (math.pi * fit["f0_Hz"] * fit["Q"])
    B0 = fit["white_floor"]

    def model(u, f, line):
        bg = 10 ** u[0] + 10 ** u[1] * (f[0] / f)
        return bg + (sho_psd(f, u[2], 10 ** u[3], 10 ** u[4]) if line else 0.0)

    out = {}
    for line in (False, True):
        u0 = np.array([math.log10(B0), math.log10(B0) - 3, f0, math.log10(Q), math.log10(A)])
        u0 = u0 if line else u0[:2]
        rms = []
        for tr, te in ((0, 1), (1, 0)):
            ft, pt = freq[tr::2], psd[tr::2]
            lo = np.array([u0[0] - 6, u0[1] - 6, f0 - 20 * f0 / Q, 2.0, u0[-1] - 3])[: len(u0)] if line else u0 - 6
            hi = np.array([u0[0] + 6, u0[1] + 6, f0 + 20 * f0 / Q, 6.0, u0[-1] + 3])[: len(u0)] if line else u0 + 6
            r = least_squares(lambda u: gamma_deviance_residuals(pt, model(u, ft, line), N_AVG), u0, bounds=(lo, hi),
                              x_scale=[0.3, 0.3, f0 / Q, 0.1, 0.1][: len(u0)])
            fe, pe = freq[te::2], psd[te::2]
            rms.append(float(np.sqrt(np.mean(gamma_deviance_residuals(pe, model(r.x, fe, line), N_AVG) ** 2))))
        out["after" if line else "before"] = float(np.mean(rms))
    return out


def brownian() -> dict:
    d = np.genfromtxt(EX / "brownian_psd_vacuum.csv", delimiter=",", skip_header=1)
    freq, psd = d[:, 0], d[:, 1]
    s_log = log_scatter(psd, N_AVG)
    t0, c0 = time.perf_counter(), time.process_time()
    idx = detect_peaks(freq, psd, s_log)
    fits = [fit_line(freq, psd, i, s_log, N_AVG) for i in idx]
    main = max(fits, key=lambda f: f["area_m2"])
    k = K_B * T / main["area_m2"]
    # the area's relative standard error from the fit's Q and amplitude errors is not reported
    # separately by fit_line: the bootstrap-free estimate is the Q error (area ~ A Q)
    res = {"peaks": [{k_: f[k_] for k_ in ("f0_Hz", "Q", "fwhm_bins", "area_m2")} for f in fits], "f0_Hz": main["f0_Hz"], "f0_sigma_Hz": main["f0_sigma_Hz"],
           "Q": main["Q"], "Q_sigma": main["Q_sigma"], "fwhm_bins": main["fwhm_bins"],
           "area_m2": main["area_m2"], "k_equipartition_N_per_m": k, "chi2_per_dof": main["chi2_per_dof"],
           "heldout_deviance_rms": _heldout(freq, psd, main), "authors": AUTHORS,
           "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    return res


def jpk() -> dict:
    t0, c0 = time.perf_counter(), time.process_time()
    r = run(EX / "afm_force_curve_jpk_qi.toml")
    fin = r["final"]
    return {"verdict": r["verdict"], "verdict_reasons": r["verdict_reasons"],
            "baseline": {k: r["baseline"][k] for k in ("chi2", "dof", "p_value", "residual_rms", "heldout_rms")},
            "baseline_parameters": {k: v.get("value") for k, v in r["baseline"]["parameters"].items() if k != "_conditioning"},
            "sigma_force_N": r["data"]["sigma_force_N"],
            "findings": [{"cause": f["cause"], "evidence": f["evidence"], "flags": f["flags"],
                          "parameters": {k: (v["value"], v.get("sigma")) for k, v in f["parameters"].items()},
                          "derived": f["derived"], "confounded_with": f["confounded_with"]} for f in r["findings"]],
            "candidates": [{"cause": c["cause"], "evidence": c["evidence"], "delta_chi2": c["delta_chi2"]} for c in r["candidates"]],
            "final": {k: fin.get(k) for k in ("chi2", "dof", "p_value", "residual_rms", "heldout_rms", "heldout_rms_before",
                                                "heldout_p_value")},
            "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "benchmarks" / "results" / "diagnose_realdata_curves.json"
    what = sys.argv[2:] or ["brownian", "jpk"]
    data = json.loads(out.read_text()) if out.exists() else {}
    for w in what:
        data[w] = {"brownian": brownian, "jpk": jpk}[w]()
        out.write_text(json.dumps(data, indent=1, default=float))
    print(json.dumps(data, indent=1, default=float))
