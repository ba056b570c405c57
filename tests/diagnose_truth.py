"""Truth generators for the diagnosis tests and the rate study (tests only; never imported by probedyn).

Every truth is produced by a path independent of the diagnosis:

* **modal**: probedyn's 3D FEM on a *finer mesh* than the diagnosis uses (3 instead of 2 elements
  through the thickness), with the hidden effect built into the mesh or the matrices by code
  here -- a point mass on a mesh *vertex* (the diagnosis interpolates a point of its mass path),
  lumped nodal springs on the clamp-face nodes (the diagnosis uses a consistent face foundation
  and a Ritz reduction), a *re-meshed* thicker / wider / longer lever (the diagnosis stretches its
  mesh), another Young's modulus, a geometric stiffness assembled here, and fluid loading by this
  module's own hydrodynamic function on the exact uniform-beam relation; plus a Timoshenko beam
  (``probedyn.lumped.beam``) for the bending families;
* **friction** and **force curves**: see the later sections of this module.

The measurement written for the diagnosis holds only what an experimentalist has: the nominal
spec, the measured values, the stated noise. The truth stays with the test.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.special import kve

HERE = Path(__file__).resolve().parent
CACHE = HERE / "data" / "diagnose_modal_truth.json"

# levers of the study: (name, probe overrides) -- long, short-and-wide, narrow
LEVERS = {
    "A": dict(length=300e-6, width=30e-6, thickness=10e-6),
    "B": dict(length=100e-6, width=40e-6, thickness=10e-6),
    "C": dict(length=150e-6, width=20e-6, thickness=10e-6),
}
MODES = [("flapwise", 1), ("flapwise", 2), ("flapwise", 3), ("flapwise", 4), ("lateral", 1), ("torsion", 1)]
MODAL_EFFECTS = ["point-mass", "clamp-compliance", "thickness-error", "width-error", "length-error",
                 "modulus-error", "axial-prestress", "fluid-loading"]
TRUTH_ETT = 3  # elements through the thickness of the truth meshes (the diagnosis: 2)
E_SI, NU_SI, RHO_SI = 169e9, 0.28, 2330.0


# ------------------------------------------------------------------------------------------
# Hydrodynamic function (own copy; Sader 1998 eqs 20-21)
# ------------------------------------------------------------------------------------------


def gamma_rect(omega, b, rho_f, eta_f):
    re = min(max(rho_f * omega * b * b / (4 * eta_f), 1e-6), 1e4)
    s = np.sqrt(1j * re)
    gc = 1 + 4j * kve(1, -1j * s) / (s * kve(0, -1j * s))
    t = math.log10(re)
    om_r = (0.91324 - 0.48274 * t + 0.46842 * t**2 - 0.12886 * t**3 + 0.044055 * t**4 - 0.0035117 * t**5
            + 0.00069085 * t**6) / (1 - 0.56964 * t + 0.48690 * t**2 - 0.13444 * t**3 + 0.045155 * t**4
                                    - 0.0035862 * t**5 + 0.00069085 * t**6)
    om_i = (-0.024134 - 0.029256 * t + 0.016294 * t**2 - 0.00010961 * t**3 + 0.000064577 * t**4
            - 0.000044510 * t**5) / (1 - 0.59702 * t + 0.55182 * t**2 - 0.18357 * t**3 + 0.079156 * t**4
                                     - 0.014369 * t**5 + 0.0028361 * t**6)
    g = (om_r + 1j * om_i) * gc
    return float(g.real), float(abs(g.imag))


def fluid_loaded(f_vac, w, t, rho, rho_f, eta_f):
    """Exact uniform-beam fluid loading of one flapwise mode: omega_f = omega_v / sqrt(1 + T Gamma_r(omega_f)),
    Q = (1/T + Gamma_r) / Gamma_i with T = pi rho_f w / (4 rho t) (Sader eq 25)."""
    T = math.pi * rho_f * w / (4 * rho * t)
    om_v = 2 * math.pi * f_vac
    om = om_v
    for _ in range(200):
        gr, _ = gamma_rect(om, w, rho_f, eta_f)
        new = om_v / math.sqrt(1 + T * gr)
        if abs(new - om) < 1e-14 * om:
            break
        om = new
    gr, gi = gamma_rect(om, w, rho_f, eta_f)
    return om / (2 * math.pi), (1 / T + gr) / gi


# ------------------------------------------------------------------------------------------
# FEM truths with the effect built in
# ------------------------------------------------------------------------------------------


def _probe():
    from probedyn.probes import get_probe

    return get_probe("cantilever")[0]


def _families_pick(freqs, fams, modes):
    out = []
    for fa, o in modes:
        idx = [i for i, x in enumerate(fams) if x == fa]
        out.append(freqs[idx[o - 1]] if len(idx) >= o else math.nan)
    return np.array(out)


def _solve_custom(model, K, M, n, clamped: bool):
    """Eigen-solve a (possibly unclamped) model with extra matrices; FEM classification."""
    from probedyn.fem import elasticity as el
    from probedyn.fem.eigen import shift_invert_eigsh
    from probedyn.fem.modes import classify_shapes

    free = model.free_dofs if clamped else np.arange(model.ndofs_total)
    res = shift_invert_eigsh(K[free][:, free].tocsr(), M[free][:, free].tocsr(), n, sigma=0.0)
    Phi = np.zeros((model.ndofs_total, len(res.eigenvalues)))
    Phi[free] = res.vectors
    w = el.lumped_weights(model.mesh, model.elem_density)
    fams, _ = classify_shapes(model.basis.doflocs, w, Phi.reshape(model.n_nodes, 3, -1), axis=model.beam_axis)
    return np.sqrt(np.maximum(res.eigenvalues, 0)) / (2 * math.pi), fams


def _geometric_stiffness(model, sigma):
    """sigma * int (d_x u).(d_x v) dV, assembled here with scikit-fem (scalar P2 Laplacian along x)."""
    from skfem import Basis, BilinearForm, ElementTetP2

    basis = Basis(model.mesh, ElementTetP2(), intorder=2)

    @BilinearForm
    def gxx(u, v, w):
        return u.grad[0] * v.grad[0]

    return sigma * sp.kron(gxx.assemble(basis), sp.identity(3), format="csr")


def _face_nodal_areas(model, face):
    """Lumped nodal areas of a face: the diagonal of its consistent P2 face mass, scaled to the
    face area (HRZ lumping; every node gets a positive share)."""
    from skfem import BilinearForm, ElementTetP2, FacetBasis

    fb = FacetBasis(model.mesh, ElementTetP2(), facets=np.asarray(model.mesh.boundaries[face]), intorder=4)

    @BilinearForm
    def mass(u, v, w):
        return u * v

    S = mass.assemble(fb)
    d = S.diagonal()
    area = float(S.sum())
    return d * (area / d.sum())


def fem_truth(lever: str, effect: str | None, params: dict, ett: int = TRUTH_ETT, n_modes: int = 12) -> dict:
    """Vacuum frequencies [Hz] of the MODES of lever ``lever`` carrying ``effect`` (FEM, ``ett``
    elements through the thickness). Fluid loading is applied afterwards (:func:`fluid_loaded`)."""
    from probedyn.fem.model import PointMass

    probe = _probe()
    geo = dict(LEVERS[lever])
    over = dict(geo, elements_through_thickness=ett)
    if effect == "thickness-error":
        over["thickness"] = geo["thickness"] * params["t_ratio"]
    elif effect == "width-error":
        over["width"] = geo["width"] * params["w_ratio"]
    elif effect == "length-error":
        over["length"] = geo["length"] + params["dL"]
    elif effect == "modulus-error":
        over["youngs_modulus"] = E_SI * params["e_ratio"]
    values = probe.resolve(over)
    model = probe.build(values)
    extra = {}
    if effect == "point-mass":
        p = model.mesh.p
        target = np.array([params["xi"] * geo["length"], 0.0, 0.0])
        j = int(np.argmin(np.linalg.norm(p - target[:, None], axis=0)))
        node = p[:, j]
        model.point_masses.append(PointMass(tuple(node), params["mass"]))
        extra["xi_node"] = float(node[0] / geo["length"])
        model._K = model._M = None
    K, M = model.assemble()
    clamped = True
    if effect == "clamp-compliance":
        L, t = geo["length"], geo["thickness"]
        kn = E_SI / (L * params["c_rot"])
        kt = E_SI * t * t / (12 * L**3 * params["c_trans"]) if params["c_trans"] > 0 else kn * 1e6
        a = _face_nodal_areas(model, "clamp")
        d = np.zeros(model.ndofs_total)
        d[0::3] = kn * a  # normal (x) springs, lumped per node
        d[1::3] = kt * a
        d[2::3] = kt * a
        K = (K + sp.diags(d)).tocsr()
        clamped = False
    if effect == "axial-prestress":
        K = (K + _geometric_stiffness(model, params["sigma"])).tocsr()
    f, fams = _solve_custom(model, K, M, n_modes, clamped)
    return {"freqs": _families_pick(f, fams, MODES).tolist(), "fem_families": fams, "dofs": int(model.dofs), **extra}


def timoshenko_truth(lever: str) -> dict:
    """Bending frequencies of the lever as a Timoshenko beam (shear + rotary inertia)."""
    from probedyn.lumped import beam as bm

    g = LEVERS[lever]
    b = bm.RectBeam(g["length"], g["width"], g["thickness"], E_SI, NU_SI, RHO_SI)
    fl = bm.timoshenko_frequencies(b, "flapwise", 4)
    la = bm.timoshenko_frequencies(b, "lateral", 2)
    return {"freqs": [*fl, la[0], math.nan]}


# ------------------------------------------------------------------------------------------
# Cache of FEM truths (keyed by lever, effect, parameters, mesh)
# ------------------------------------------------------------------------------------------


def _key(lever, effect, params, ett) -> str:
    s = json.dumps([lever, effect, {k: round(float(v), 12) for k, v in sorted(params.items())}, ett])
    return hashlib.sha1(s.encode()).hexdigest()[:16]


def cached_fem_truth(lever, effect, params, ett=TRUTH_ETT, compute: bool = True) -> dict:
    cache = json.loads(CACHE.read_text()) if CACHE.exists() else {}
    k = _key(lever, effect, params, ett)
    if k in cache:
        return cache[k]
    if not compute:
        raise KeyError(f"FEM truth {lever} {effect} {params} not cached (run tests/diagnose_truth.py)")
    out = fem_truth(lever, effect, params, ett)
    out.update(lever=lever, effect=effect, params=params, ett=ett)
    cache = json.loads(CACHE.read_text()) if CACHE.exists() else {}
    cache[k] = out
    CACHE.parent.mkdir(exist_ok=True)
    tmp = CACHE.with_suffix(".tmp")
    tmp.write_text(json.dumps(cache, indent=0, sort_keys=True))
    os.replace(tmp, CACHE)
    return out


# ------------------------------------------------------------------------------------------
# Cases: effect magnitudes, noise, files
# ------------------------------------------------------------------------------------------


def probe_mass(lever):
    g = LEVERS[lever]
    return RHO_SI * g["length"] * g["width"] * g["thickness"]


def draw_modal_effect(effect: str, lever: str, rng) -> dict:
    """A random magnitude from about the detection limit up (1e-3 frequency noise)."""
    g = LEVERS[lever]
    sgn = rng.choice([-1.0, 1.0])
    if effect == "point-mass":
        return {"mass": float(probe_mass(lever) * 10 ** rng.uniform(np.log10(0.005), np.log10(0.2))),
                "xi": float(rng.uniform(0.4, 1.0))}
    if effect == "clamp-compliance":
        return {"c_rot": float(10 ** rng.uniform(-2.5, -1.0)),
                "c_trans": float(10 ** rng.uniform(-4.0, -2.5)) if rng.uniform() < 0.5 else 0.0}
    if effect == "thickness-error":
        return {"t_ratio": float(1 + sgn * rng.uniform(0.02, 0.15))}
    if effect == "width-error":
        return {"w_ratio": float(1 + sgn * rng.uniform(0.03, 0.2))}
    if effect == "length-error":
        return {"dL": float(sgn * rng.uniform(0.01, 0.08) * g["length"])}
    if effect == "modulus-error":
        return {"e_ratio": float(1 + sgn * rng.uniform(0.03, 0.3))}
    if effect == "axial-prestress":
        s_cr = math.pi**2 * E_SI * g["thickness"] ** 2 / (48 * g["length"] ** 2)
        v = -rng.uniform(0.1, 0.6) if rng.uniform() < 0.3 else 10 ** rng.uniform(np.log10(0.2), np.log10(5))
        return {"sigma": float(v * s_cr)}
    if effect == "fluid-loading":
        name = str(rng.choice(["water", "ethanol", "air"]))
        rho_f, eta_f = {"water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3), "air": (1.18, 1.85e-5)}[name]
        return {"medium": name, "rho_f": rho_f, "eta_f": eta_f}
    raise ValueError(effect)


def make_modal_case(outdir: Path, seed: int, effect: str | None, lever: str = "A", *, noise: float = 1e-3,
                    q_noise: float = 0.05, with_Q: bool | None = None, declared_medium: str | None = "vacuum",
                    truth_kind: str = "fem", compute: bool = True) -> tuple[Path, dict]:
    """Write a modal measurement of lever ``lever`` with a hidden ``effect`` (None: noise only)."""
    rng = np.random.default_rng(seed)
    params = draw_modal_effect(effect, lever, rng) if effect else {}
    g = LEVERS[lever]
    if truth_kind == "timoshenko":
        tr = timoshenko_truth(lever)
        modes = MODES[:5]
        f = np.array(tr["freqs"][:5])
    else:
        fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
        tr = cached_fem_truth(lever, effect if effect != "fluid-loading" else None, fem_params, compute=compute)
        modes = MODES
        f = np.array(tr["freqs"])
    Q_int = float(10 ** rng.uniform(3, 4.5))
    Q = np.full(len(modes), Q_int)
    if effect == "fluid-loading":
        declared_medium = None  # the experimentalist did not declare it: the diagnosis must find it
    medium = params.get("medium") if effect == "fluid-loading" else declared_medium
    if medium in ("air", "water", "ethanol"):
        rho_f, eta_f = {"water": (997.0, 8.9e-4), "ethanol": (789.0, 1.07e-3), "air": (1.18, 1.85e-5)}[medium]
        for k, (fa, _) in enumerate(modes):
            if fa == "flapwise":
                f[k], qf = fluid_loaded(f[k], g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
                Q[k] = 1 / (1 / Q_int + 1 / qf)
    if with_Q is None:
        with_Q = bool(rng.uniform() < 0.5) or effect == "fluid-loading"
    f_meas = f * (1 + noise * rng.standard_normal(len(f)))
    Q_meas = Q * np.exp(q_noise * rng.standard_normal(len(f)))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"modal_{seed}"
    rows = ["family,order,frequency_Hz" + (",Q" if with_Q else "")]
    for (fa, o), ff, qq in zip(modes, f_meas, Q_meas):
        if np.isfinite(ff):
            rows.append(f"{fa},{o},{ff:.10g}" + (f",{qq:.6g}" if with_Q else ""))
    (outdir / f"{name}.csv").write_text("\n".join(rows) + "\n")
    med = "" if declared_medium is None else f'[medium]\nname = "{declared_medium}"\n'
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "modal"\ndata = "{name}.csv"\n\n[probe]\nname = "cantilever"\n'
        f"length = {g['length']!r}\nwidth = {g['width']!r}\nthickness = {g['thickness']!r}\n\n{med}\n"
        f"[noise]\nfrequency_rel = {noise!r}\nQ_rel = {q_noise!r}\n")
    truth = {"effect": effect, "params": params, "lever": lever, "truth_kind": truth_kind, "Q_int": Q_int,
             **{k: v for k, v in tr.items() if k in ("xi_node",)}}
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# Thermal spectra
# ------------------------------------------------------------------------------------------


def make_spectrum_case(outdir: Path, seed: int, effect: str | None, lever: str = "A", *, medium: str = "air",
                       spur: bool = True, averages: int = 64, temperature: float = 295.0,
                       compute: bool = True) -> tuple[Path, dict]:
    """Thermal PSD of the lever's first three flapwise modes in ``medium`` (FEM truth + this module's
    Sader loading, equipartition areas k_B T / k_n with k_n = m_beam omega_n^2 / 4, the tip-referred
    modal stiffness of a uniform cantilever), a white + 1/f detector background, an optional
    electronic spur (a sinusoid: one bin wide) below f1, and the chi^2 scatter of ``averages``
    averaged periodograms."""
    rng = np.random.default_rng(seed)
    params = draw_modal_effect(effect, lever, rng) if effect else {}
    if effect == "fluid-loading":
        params = {"medium": medium, "rho_f": 0.0, "eta_f": 0.0}  # the declared medium is the truth
        effect = None
    g = LEVERS[lever]
    tr = cached_fem_truth(lever, effect, params, compute=compute)
    f_vac = np.array(tr["freqs"][:4])  # flapwise 1-4
    rho_f, eta_f = {"air": (1.18, 1.85e-5), "water": (997.0, 8.9e-4), "vacuum": (0.0, 1.8e-5)}[medium]
    Q_int = float(10 ** rng.uniform(3.5, 4.5))
    fs, Qs = [], []
    for fv in f_vac[:3]:
        if rho_f > 0:
            f1, qf = fluid_loaded(fv, g["width"], g["thickness"], RHO_SI, rho_f, eta_f)
        else:
            f1, qf = fv, math.inf
        fs.append(f1)
        Qs.append(1 / (1 / Q_int + 1 / qf))
    T = temperature
    kB = 1.380649e-23
    m_b = probe_mass(lever)
    if effect == "point-mass":
        m_b += 0.0
    f_hi = 1.25 * fs[2]
    freq = np.linspace(fs[0] * 0.1, f_hi, 40000)
    df = freq[1] - freq[0]
    psd = np.zeros_like(freq)
    for f0, Q in zip(fs, Qs):
        k = m_b * (2 * math.pi * f0) ** 2 / 4
        A = 2 * kB * T / (math.pi * k * f0 * Q)
        psd += A / ((1 - (freq / f0) ** 2) ** 2 + (freq / (f0 * Q)) ** 2)
    white = 1e-4 * float(psd[np.argmin(abs(freq - fs[0]))]) / Qs[0] ** 0 * 1e-3
    psd += white * (1 + (fs[0] / freq))
    truth = {"effect": effect, "params": params, "lever": lever, "f": fs, "Q": Qs, "Q_int": Q_int}
    if spur:
        f_sp = fs[0] * rng.uniform(0.15, 0.8)
        j = int(np.argmin(abs(freq - f_sp)))
        psd[j] += 300 * psd[j] * rng.uniform(1, 10)
        truth["spur_Hz"] = float(freq[j])
    psd = psd * rng.gamma(averages, 1.0 / averages, size=len(psd))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"spectrum_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([freq, psd]), delimiter=",", header="frequency_Hz,value",
               comments="", fmt="%.10g")
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "spectrum"\ndata = "{name}.csv"\nquantity = "psd"\naverages = {averages}\n\n'
        f'[probe]\nname = "cantilever"\nlength = {g["length"]!r}\nwidth = {g["width"]!r}\nthickness = {g["thickness"]!r}\n\n'
        f'[medium]\nname = "{medium}"\ntemperature = {T!r}\n\n[noise]\nfrequency_rel = 1e-6\n')
    return outdir / f"{name}.toml", truth


if __name__ == "__main__":  # precompute the FEM truths of the rate study (slow: about one FEM solve each)
    import sys

    from diagnose_cases import modal_cases  # noqa: E402  (tests/diagnose_cases.py)

    n_eff = int(sys.argv[1]) if len(sys.argv) > 1 else 56
    n_null = int(sys.argv[2]) if len(sys.argv) > 2 else 56
    for case in modal_cases(n_eff, n_null):
        if case["truth_kind"] == "fem":
            rng = np.random.default_rng(case["seed"])
            eff = case["effect"]
            params = draw_modal_effect(eff, case["lever"], rng) if eff else {}
            fem_params = {k: v for k, v in params.items() if k not in ("medium", "rho_f", "eta_f")}
            out = cached_fem_truth(case["lever"], eff if eff != "fluid-loading" else None, fem_params)
            print(case["seed"], eff, case["lever"], out["freqs"][:2], flush=True)
