"""Thermal spectra with hidden effects, for the spectrum diagnosis' rate study and tests (tests only).

The truth is independent of the diagnosis and reuses the modal truths of ``diagnose_truth``:

* **modes**: probedyn's 3D FEM on the finer, unstretched truth mesh (4 layers of 20-node hexahedra)
  with the hidden effect built into the mesh or the matrices (:func:`diagnose_truth.fem_truth`:
  a point mass on a mesh vertex, lumped springs on the clamp-face nodes, a re-meshed thicker /
  wider / longer lever, another modulus, a geometric stiffness), solved directly; or, for some
  nulls, a Timoshenko beam (``probedyn.lumped.beam``: bending families only);
* **what the detector sees**: the displacement of one mesh node at the free end, a quarter width
  off the axis on the top face, along a direction tilted by ``DETECTOR_TILT`` from the thickness
  axis towards the width (an optical spot off the centreline with some lateral cross-talk: the
  flapwise modes, the torsional mode through the off-axis spot and the lateral mode through the tilt);
* **equipartition**: mode n's area in the one-sided displacement PSD is ``k_B T d_n^2 / omega_n^2``
  with ``d_n`` the mass-normalised shape's displacement at the spot along the detector direction
  (``k_B T / k_n`` of the mode seen there), its line the thermal SHO of quality factor ``Q_n``
  (one internal loss factor for every mode, ``1/Q = 1/Q_int + 1/Q_fluid`` for the flapwise modes in
  a fluid, Sader's exact uniform-beam loading by ``diagnose_truth.fluid_loaded``);
* **instrument**: white + 1/f detector background, electronic spurs (sinusoids: all their power in
  one bin, anywhere in the band), and the averaged periodogram's statistics (every bin the true PSD
  times a Gamma(N, 1/N) factor for N averages).

The sidecar holds what an experimentalist has: the nominal probe, the declared medium (or none),
the temperature, the number of averages, the stated frequency uncertainty.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import os
from pathlib import Path

import numpy as np

import diagnose_truth as dt
from diagnose_truth import (LEVERS, MODES, RHO_SI, draw_modal_effect, fem_truth, fluid_loaded, lateral_fluid_loaded,
                            torsion_fluid_loaded)
from diagnose_truth_curves import K_B
SPECTRUM_EFFECTS = ["point-mass", "clamp-compliance", "thickness-error", "width-error", "length-error",
                    "modulus-error", "axial-prestress", "fluid-loading"]
DETECTOR_TILT = math.radians(10.0)
FLUIDS = {"air": (1.18, 1.85e-5), "water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3)}
SHIPPED = Path(__file__).resolve().parent / "data" / "diagnose_spectrum_truth.json"
CACHE_DIR = Path(os.environ.get("PROBEDYN_TRUTH_CACHE", Path.home() / ".cache" / "probedyn-truths")) / "spectra"


def detector(model):
    """Node at the free end, a quarter width off the axis, on the top face; direction tilted by
    DETECTOR_TILT from the thickness axis towards the width axis."""
    X = np.asarray(model.basis.doflocs)[:, :: (model.basis.doflocs.shape[1] // model.n_nodes)]
    ax = int(model.beam_axis)
    wa, ta = (ax + 1) % 3, (ax + 2) % 3
    lo, hi = X.min(axis=1), X.max(axis=1)
    target = np.empty(3)
    target[ax] = hi[ax]
    target[wa] = lo[wa] + 0.75 * (hi[wa] - lo[wa])
    target[ta] = hi[ta]
    j = int(np.argmin(np.linalg.norm((X - target[:, None]) / np.maximum(hi - lo, 1e-30)[:, None], axis=0)))
    e = np.zeros(3)
    e[ta], e[wa] = math.cos(DETECTOR_TILT), math.sin(DETECTOR_TILT)
    return j, e


def _code_hash() -> str:
    src = inspect.getsource(dt.fem_truth) + inspect.getsource(dt._solve_custom) + inspect.getsource(detector)
    return hashlib.sha1(src.encode()).hexdigest()[:10]


def _spectrum_key(lever: str, effect: str | None, params: dict) -> tuple[dict, str | None, str]:
    """(the FEM's parameters, its effect, the cache key) of a spectrum truth: lever, effect, parameters, mesh,
    the truth code and an effect's revision (``diagnose_truth.TRUTH_REVISION``)."""
    fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
    eff = effect if effect != "fluid-loading" else None
    items = [lever, eff, {k: round(float(v), 12) for k, v in sorted(fem_params.items())}, dt.TRUTH_ETT, _code_hash()]
    if eff in dt.TRUTH_REVISION:
        items.append(dt.TRUTH_REVISION[eff])
    return fem_params, eff, hashlib.sha1(json.dumps(items).encode()).hexdigest()[:16]


def spectrum_fem_truth(lever: str, effect: str | None, params: dict) -> dict:
    """FEM truth (frequencies and detector displacements of MODES), cached on disk keyed by the
    lever, effect, parameters and the truth code."""
    fem_params, eff, h = _spectrum_key(lever, effect, params)
    shipped = json.loads(SHIPPED.read_text()) if SHIPPED.exists() else {}
    if h in shipped:  # the default tests' truths ship with the repository (no FEM solve in a fast test)
        return shipped[h]
    path = CACHE_DIR / f"{h}.json"
    if path.exists():
        return json.loads(path.read_text())
    out = fem_truth(lever, eff, fem_params, detector=detector)
    out = {k: out[k] for k in ("freqs", "detector_disp", "dofs", *(["xi_node"] if "xi_node" in out else []))}
    CACHE_DIR.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(out))
    os.replace(tmp, path)
    return out


def ship_truth(lever: str, effect: str | None, params: dict) -> None:
    """Add one FEM truth to the file shipped with the tests (``SHIPPED``)."""
    out = spectrum_fem_truth(lever, effect, params)
    shipped = json.loads(SHIPPED.read_text()) if SHIPPED.exists() else {}
    shipped[_spectrum_key(lever, effect, params)[2]] = out
    SHIPPED.write_text(json.dumps(shipped, indent=0, sort_keys=True))


def timoshenko_spectrum_truth(lever: str) -> dict:
    """Bending modes of the lever as a Timoshenko beam; detector displacement of the uniform beam's
    mass-normalised shape at the free end (2 / sqrt(m)) projected on the detector direction."""
    tr = dt.timoshenko_truth(lever)
    m = dt.probe_mass(lever)
    tip = 2.0 / math.sqrt(m)
    disp = [tip * math.cos(DETECTOR_TILT)] * 4 + [tip * math.sin(DETECTOR_TILT), math.nan]
    return {"freqs": tr["freqs"], "detector_disp": disp}


def thermal_lines(freq, f0s, Qs, areas) -> np.ndarray:
    """One-sided PSD of thermally driven SHO lines of given areas [m^2] (int S df = area)."""
    S = np.zeros_like(freq)
    for f0, Q, A in zip(f0s, Qs, areas):
        S += A * (2.0 / (math.pi * f0 * Q)) / ((1 - (freq / f0) ** 2) ** 2 + (freq / (f0 * Q)) ** 2)
    return S


def make_spectrum_case(outdir: Path, seed: int, effect: str | None, lever: str = "A", *, truth_kind: str = "fem",
                       declared_medium: str | None = "vacuum", T: float = 295.0, params: dict | None = None,
                       name: str | None = None, f_max: float | None = None,
                       noise_free: bool = False) -> tuple[Path, dict]:
    """Write a thermal spectrum of lever ``lever`` with a hidden ``effect`` (None: noise only).

    ``effect = "fluid-loading"``: the lever is in water, ethanol or air and the medium is not declared. Otherwise the
    truth is in ``declared_medium`` (vacuum or air; in air Sader loading of the flapwise modes).
    ``params``: the effect's parameters (default: drawn from ``seed``; the seed's draws are consumed either
    way, so the instrument draws are the same); ``name``: the file stem (default ``spectrum_<seed>``);
    ``f_max``: the detector's bandwidth [Hz] (default: 1.2 x the highest of flapwise 3, lateral 1, torsion 1);
    ``noise_free``: the expected PSD without the periodogram's scatter (the same draws are consumed and the same
    averages declared: the detectability criterion's record)."""
    rng = np.random.default_rng(seed)
    drawn = draw_modal_effect(effect, lever, rng) if effect else {}
    params = dict(drawn if params is None else params)
    if effect == "fluid-loading":
        declared_medium = None  # the fluid (water, ethanol or air, as the modal study) is not declared
    medium = params.get("medium") if effect == "fluid-loading" else declared_medium
    tr = timoshenko_spectrum_truth(lever) if truth_kind == "timoshenko" else spectrum_fem_truth(lever, effect, params)
    g = dt.lever_geometry(lever)
    f = np.array(tr["freqs"], float)
    d = np.array(tr["detector_disp"], float)
    Q_int = float(10 ** rng.uniform(2.3, 3.0))
    Q = np.full(len(f), Q_int)
    if medium in FLUIDS:
        rho_f, eta_f = FLUIDS[medium]
        for k, (fa, _) in enumerate(MODES):
            if fa == "flapwise":
                f[k], qf = fluid_loaded(f[k], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
            elif fa == "lateral":
                f[k], qf = lateral_fluid_loaded(f[k], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
            elif fa == "torsion":
                f[k], qf = torsion_fluid_loaded(f[k], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
    ok = np.isfinite(f) & np.isfinite(d)
    # the band: up to 1.2 x the highest of flapwise 3, lateral 1, torsion 1 (a detector bandwidth)
    key = [i for i, m in enumerate(MODES) if m in (("flapwise", 3), ("lateral", 1), ("torsion", 1)) and ok[i]]
    f_hi = 1.2 * max(f[i] for i in key) if f_max is None else float(f_max)
    inband = ok & (f < f_hi / 1.05)
    f1 = f[0]
    df = float(np.min(f[inband] / Q[inband])) / 5.0  # the narrowest line spans 5 bins
    freq = np.arange(0.1 * f1, f_hi, df)
    areas = K_B * T * d**2 / (2 * math.pi * f) ** 2
    S = thermal_lines(freq, f[inband], Q[inband], areas[inband])
    peak1 = areas[0] * 2 * Q[0] / (math.pi * f1)
    white = peak1 / 10 ** rng.uniform(4.5, 6.0)
    fc = f1 * rng.uniform(0.2, 1.0)
    S = S + white * (1 + fc / freq)
    spurs = []
    for _ in range(int(rng.integers(0, 3))):
        j = int(rng.integers(len(freq)))
        S[j] += 10 ** rng.uniform(1.0, 3.0) * white * (1 + fc / freq[j]) * 5.0
        spurs.append(float(freq[j]))
    averages = int(rng.choice([16, 32, 64]))
    scatter = rng.gamma(averages, 1.0 / averages, size=len(S))
    S = S if noise_free else S * scatter
    f_rel = float(rng.choice([1e-4, 3e-4, 1e-3]))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = name or f"spectrum_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([freq, S]), delimiter=",", header="frequency_Hz,value",
               comments="", fmt="%.10g")
    med = "" if declared_medium is None else f'name = "{declared_medium}"\n'
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "spectrum"\ndata = "{name}.csv"\nquantity = "psd"\naverages = {averages}\n\n'
        f'[probe]\nname = "cantilever"\nlength = {g["length"]!r}\nwidth = {g["width"]!r}\n'
        f'thickness = {g["thickness"]!r}\n\n[medium]\n{med}temperature = {T!r}\n\n'
        f"[noise]\nfrequency_rel = {f_rel!r}\n")
    truth = {"effect": effect, "params": params, "lever": lever, "truth_kind": truth_kind, "Q_int": Q_int,
             "medium": medium, "declared_medium": declared_medium, "averages": averages, "frequency_rel": f_rel,
             "modes": [{"family": fa, "order": o, "f": float(ff), "Q": float(q), "area_m2": float(a)}
                       for (fa, o), ff, q, a, ib in zip(MODES, f, Q, areas, inband) if ib],
             "spurs_Hz": spurs, "white": white, **{k: v for k, v in tr.items() if k == "xi_node"}}
    return outdir / f"{name}.toml", truth


def spectrum_cases(n_effect: int = 50, n_null: int = 50) -> list[dict]:
    """Seeds 3000 + i (effects cycling, levers A, B, C cycling every 8, a quarter declared in air --
    rotating over the effects -- except the hidden fluid) and nulls 7000 + i (levers in turn; every third triple Timoshenko; every
    fourth declared in air)."""
    levers = list(LEVERS)
    out = []
    for i in range(n_effect):
        eff = SPECTRUM_EFFECTS[i % len(SPECTRUM_EFFECTS)]
        out.append({"seed": 3000 + i, "effect": eff, "lever": levers[(i // len(SPECTRUM_EFFECTS)) % len(levers)],
                    "truth_kind": "fem", "declared_medium": "air" if ((i // len(SPECTRUM_EFFECTS) + i) % 4 == 3 and eff != "fluid-loading")
                    else "vacuum"})
    for i in range(n_null):
        out.append({"seed": 7000 + i, "effect": None, "lever": levers[i % len(levers)],
                    "truth_kind": "timoshenko" if (i // len(levers)) % 3 == 2 else "fem",
                    "declared_medium": "air" if i % 4 == 1 else "vacuum"})
    return out
