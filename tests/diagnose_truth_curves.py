"""Truth generators for force curves as an instrument records them (tests and benchmarks only).

A lever of stiffness ``k`` approaches a sample with the piezo (``z``, increasing towards the
sample) and retracts; the photodiode records the deflection (in V with the sidecar's
sensitivity [m/V], or in m), with a tilted, offset baseline (a virtual deflection of the optical
lever) and white noise. The tip-sample law is one of probedyn's contact registry models
(:mod:`probedyn.schemes.contact`: DMT with its van der Waals tail, JKR, Maugis-Dugdale) or
plain Hertz; the lever's equilibrium along the ramp is followed here by **continuation**
(Newton from the previous point, a bracketing search for the next stable root where the branch
ends: the jump to contact where the force gradient exceeds k, the pull-off) -- a path
independent of the diagnosis, which locates the equilibria on envelopes of the contact curve.

Hidden effects: ``adhesion-dmt``, ``adhesion-jkr``, ``adhesion-md`` (lambda drawn), ``jump-to-
contact`` (DMT on a soft lever: the van der Waals gradient exceeds k well before contact),
``tip-radius-error`` (the declared radius is wrong; the sample modulus is declared),
``deflection-drift`` (a drift of the deflection in time), ``tip-shape`` (the registry's blunted cone,
half-angle 15-35 deg, on a soft sample indented 1.2-4 times deeper than the cap's edge depth R cot^2(alpha),
where the flanks carry the load), ``piezo-hysteresis`` (the retract's true piezo position offset by
0.5-5 nm from the recorded one). Noise-only cases: Hertz + the linear
lever only (with the same tilted baseline, formats and noise). The sample modulus is declared in
half of the other cases, whatever their effect, so the sidecar does not betray the truth.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from diagnose_truth import _continuation_curve

CURVE_EFFECTS = ["adhesion-dmt", "adhesion-jkr", "adhesion-md", "jump-to-contact", "tip-radius-error",
                 "deflection-drift", "tip-shape", "piezo-hysteresis"]
#: the cause that explains each effect, and its main parameter (for the recovery error)
EXPECTED = {"adhesion-dmt": ("adhesion-dmt", "W"), "adhesion-jkr": ("adhesion-jkr", "W"),
            "adhesion-md": ("adhesion-md", "W"), "jump-to-contact": ("adhesion-dmt", "W"),
            "tip-radius-error": ("tip-radius-error", "r_ratio"), "deflection-drift": ("deflection-drift", "drift"),
            "tip-shape": ("tip-shape", "alpha"), "piezo-hysteresis": ("piezo-hysteresis", "dz")}
E_TIP, NU_TIP, NU_S = 169e9, 0.28, 0.3


def _monotone_curve(z_rel, P, k: float) -> np.ndarray:
    """Equilibrium force of a lever on a monotone, non-adhesive law (P >= 0, P' >= 0): the unique
    root of ``delta + P(delta) / k = z_rel`` by bisection in ``[z_rel - P(z_rel) / k, z_rel]``
    (P >= 0 puts the root below z_rel; P(root) <= P(z_rel) above the lower end), vectorised."""
    z_rel = np.asarray(z_rel, float)
    hi = z_rel.copy()
    lo = z_rel - np.asarray(P(np.maximum(z_rel, 0.0)), float) / k
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        g = mid + np.asarray(P(mid), float) / k - z_rel
        lo, hi = np.where(g < 0, mid, lo), np.where(g < 0, hi, mid)
    return np.asarray(P(0.5 * (lo + hi)), float)


def make_curve_case(outdir: Path, seed: int, effect: str | None, *, n: int = 300) -> tuple[Path, dict]:
    from probedyn.schemes.contact import get_contact_model
    from probedyn.schemes.contact.base import MAUGIS_206

    rng = np.random.default_rng(seed)
    k = float(10 ** rng.uniform(-0.5, 1.0))  # 0.3 - 10 N/m
    if effect == "jump-to-contact":
        k = float(10 ** rng.uniform(-1.3, -0.7))  # 0.05 - 0.2 N/m: a long snap-in
    R_nom = float(rng.choice([8e-9, 20e-9, 30e-9]))
    E_s = float(10 ** rng.uniform(8.5, 10.5))  # 0.3 - 30 GPa
    noise = float(10 ** rng.uniform(-10.3, -9.7))  # 0.05 - 0.2 nN
    declare_E = bool(rng.integers(2)) or effect == "tip-radius-error"
    params: dict = {}
    R = R_nom
    if effect == "tip-radius-error":
        params["r_ratio"] = float(10 ** (rng.choice([-1, 1]) * rng.uniform(0.15, 0.5)))
        R = R_nom * params["r_ratio"]
    Es_star = 1 / ((1 - NU_TIP**2) / E_TIP + (1 - NU_S**2) / E_s)
    law = {"adhesion-dmt": "dmt", "jump-to-contact": "dmt", "adhesion-jkr": "jkr", "adhesion-md": "md"}.get(effect)
    if law:
        params["W"] = float(10 ** rng.uniform(-2.0, -0.7))  # 0.01 - 0.2 J/m^2
        kw = dict(E_t=E_TIP, nu_t=NU_TIP, E_s=E_s, nu_s=NU_S, R_t=R, R_s=0.0, W=params["W"])
        if law == "md":
            params["lam"] = float(10 ** rng.uniform(-0.5, 0.5))
            K = 4 / 3 * Es_star
            kw["z0"] = MAUGIS_206 / params["lam"] * (params["W"] ** 2 * R / (math.pi * K * K)) ** (1 / 3)
        model = get_contact_model(law, **kw)
        Pl = lambda d: model.force(d, "loading")  # noqa: E731
        Pu = lambda d: model.force(d, "unloading")  # noqa: E731
    else:
        Pl = Pu = lambda d: 4 / 3 * Es_star * math.sqrt(R) * np.maximum(d, 0.0) ** 1.5  # noqa: E731
    Fmax = float(rng.uniform(15e-9, 60e-9))
    dmax = (Fmax / (4 / 3 * Es_star * math.sqrt(R))) ** (2 / 3)
    if effect == "tip-shape":  # a soft sample indented by the flanks of a blunted cone
        E_s = float(10 ** rng.uniform(6.0, 7.5))  # 1 - 30 MPa
        Es_star = 1 / ((1 - NU_TIP**2) / E_TIP + (1 - NU_S**2) / E_s)
        params["alpha"] = float(rng.uniform(15.0, 35.0))
        cone = get_contact_model("cone", E_t=E_TIP, nu_t=NU_TIP, E_s=E_s, nu_s=NU_S, R_t=R, R_s=0.0,
                                 alpha=math.radians(params["alpha"]))
        dmax = float(rng.uniform(1.2, 4.0)) * R / math.tan(math.radians(params["alpha"])) ** 2
        Fmax = float(cone.force(dmax))
        Pl = Pu = lambda d: cone.force(d)  # noqa: E731
    z_c = float(rng.uniform(-5e-9, 5e-9))
    z_top = z_c + dmax + Fmax / k
    z_far = z_c - max(40e-9, 1.5 * Fmax / k)  # far enough that the retract's pull-off lands out of range
    z_app = np.linspace(z_far, z_top, n)
    z_ret = z_app[::-1]
    dz = 0.0
    if effect == "piezo-hysteresis":  # the retract's true position = recorded + dz
        dz = float(rng.choice([-1, 1]) * 10 ** rng.uniform(-9.3, -8.3))
        params["dz"] = dz
    if effect == "tip-shape":  # a monotone law without adhesion: one equilibrium per z, no jumps
        F_app = _monotone_curve(z_app - z_c, Pl, k)
        F_ret = _monotone_curve(z_ret - z_c, Pu, k)
    else:
        F_app = _continuation_curve(z_app - z_c, Pl, k, z_far - z_c)
        F_ret = _continuation_curve(z_ret + dz - z_c, Pu, k, z_top + dz - z_c - F_app[-1] / k)
    z = np.concatenate([z_app, z_ret])
    F = np.concatenate([F_app, F_ret])
    jumps = np.abs(np.diff(F_app))
    snap_in = bool(jumps.max() > 10 * noise and F_app[int(np.argmax(jumps))] < 0)
    b0 = float(rng.normal(0, 5e-9))
    b1 = float(rng.normal(0, 0.02) * k)  # tilt: up to a few % of the lever's deflection
    t = np.arange(2 * n) * float(rng.uniform(1e-3, 5e-3))  # uniform sampling (s)
    tau = (t - 0.5 * (t[0] + t[-1])) / (t[-1] - t[0])
    drift = 0.0
    if effect == "deflection-drift":
        drift = float(rng.choice([-1, 1]) * 10 ** rng.uniform(-9.3, -8.3))  # 0.5 - 5 nN over the recording
        params["drift"] = drift
    clean = F + b0 + b1 * z + drift * tau
    Fm = clean + noise * rng.standard_normal(len(F))
    seg = np.concatenate([np.zeros(n, int), np.ones(n, int)])
    fmt = ["deflection_V", "deflection_m", "force_N"][int(rng.integers(3))]
    sens = float(rng.uniform(20e-9, 100e-9))
    if fmt == "deflection_V":
        col, noise_line = Fm / (k * sens), f"deflection = {noise / (k * sens)!r}"
    elif fmt == "deflection_m":
        col, noise_line = Fm / k, f"deflection = {noise / k!r}"
    else:
        col, noise_line = Fm, f"force = {noise!r}"
    with_time = bool(rng.integers(2))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"curve_{seed}"
    cols = [z, col, seg] + ([t] if with_time else [])
    header = f"z_m,{fmt},segment" + (",time_s" if with_time else "")
    np.savetxt(outdir / f"{name}.csv", np.column_stack(cols), delimiter=",", header=header, comments="",
               fmt=["%.10e", "%.10e", "%d"] + (["%.6e"] if with_time else []))
    sample = f"\n[sample]\nE = {E_s!r}\nnu = {NU_S!r}\n" if declare_E else ""
    lever = f"k = {k!r}\n" + (f"sensitivity = {sens!r}\n" if fmt == "deflection_V" else "")
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "force"\ndata = "{name}.csv"\n\n[lever]\n{lever}\n[tip]\nradius = {R_nom!r}\n'
        f"E = {E_TIP!r}\nnu = {NU_TIP!r}\n{sample}\n[noise]\n{noise_line}\n")
    truth = {"effect": effect, "params": params, "k": k, "E_s": E_s, "z_c": z_c, "b0": b0, "b1": b1, "noise": noise,
             "R_nom": R_nom, "declared_E": declare_E, "format": fmt, "time_column": with_time, "snap_in": snap_in,
             "force_clean": clean}  # the noise-free record [N] (for the detectability criterion; not written)
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# Thermal spectra of the probe's FEM modes
# ------------------------------------------------------------------------------------------

K_B = 1.380649e-23


def fem_thermal_modes(overrides: dict, n_modes: int = 8) -> list[dict]:
    """Flapwise modes of the probe's FEM (``overrides`` of the registered cantilever): frequency and
    the modal stiffness at the tip along the thickness (what a deflection detector at the tip
    sees: ``k_n = omega_n^2 / phi_n(tip)^2`` for mass-normalised modes)."""
    from probedyn.probes import get_probe

    probe, _ = get_probe("cantilever")
    model = probe.build(probe.resolve(overrides))
    res = model.modes(n_modes)
    return [{"f": md.frequency_hz, "k": md.effective_stiffness_tip["z"]} for md in res.modes
            if md.family == "flapwise" and math.isfinite(md.effective_stiffness_tip.get("z", math.inf))]


def thermal_psd(freq: np.ndarray, modes: list[dict], Qs: list[float], T: float) -> np.ndarray:
    """One-sided displacement PSD [m^2/Hz] of the thermally driven modes (equipartition: the
    area of mode n is k_B T / k_n; SHO line of quality factor Q_n)."""
    S = np.zeros_like(freq)
    for md, Q in zip(modes, Qs):
        f0, k = md["f"], md["k"]
        A = 2 * K_B * T / (math.pi * k * f0 * Q)
        S += A / ((1 - (freq / f0) ** 2) ** 2 + (freq / (f0 * Q)) ** 2)
    return S


def make_fem_spectrum_case(outdir: Path, seed: int, overrides: dict, *, spur_rel: float | None = 0.3,
                           Q: float = 300.0, averages: int = 32, T: float = 295.0, n_peaks: int = 2,
                           truth_overrides: dict | None = None, modes: list[dict] | None = None,
                           calibration: float = 1.0, freq_scale: float = 1.0) -> tuple[Path, dict]:
    """Thermal PSD of the first ``n_peaks`` flapwise FEM modes in vacuum (Q given: internal
    damping), a white + 1/f detector background, an optional electronic spur (a sinusoid: all
    its power in one bin) at ``spur_rel`` x f1, and the periodogram statistics of ``averages``
    averages (each bin: the true PSD times chi^2 with 2 x averages degrees of freedom / (2 x
    averages), i.e. a Gamma(averages, 1/averages) factor -- not Gaussian). The FEM of the truth
    is ``truth_overrides`` (e.g. a finer mesh) or ``overrides``."""
    rng = np.random.default_rng(seed)
    modes = modes or fem_thermal_modes(truth_overrides or overrides)
    # a hidden frequency shift (e.g. an added mass or a thinner lever: all modes by one factor here)
    modes = [{"f": m["f"] * freq_scale, "k": m["k"]} for m in modes[:n_peaks]]
    f_hi = 1.3 * modes[-1]["f"]
    df = modes[0]["f"] / Q / 6.0  # the narrowest line spans 6 bins
    freq = np.arange(0.1 * modes[0]["f"], f_hi, df)
    Qs = [Q] * len(modes)
    S = thermal_psd(freq, modes, Qs, T)
    peak1 = 2 * K_B * T * Q / (math.pi * modes[0]["k"] * modes[0]["f"])
    white = 1e-3 * peak1 / Q  # the line stands ~ Q x 1000 above the floor
    S = S + white * (1 + modes[0]["f"] / freq)
    truth = {"modes": modes, "Q": Qs, "white": white}
    if spur_rel is not None:
        j = int(np.argmin(abs(freq - spur_rel * modes[0]["f"])))
        S[j] += 0.3 * peak1  # a sinusoid: its power in one bin
        truth["spur_Hz"] = float(freq[j])
    S = calibration * S  # a detector sensitivity error scales the whole PSD (thermal lines and floor)
    truth["calibration"] = calibration
    truth["freq_scale"] = freq_scale
    S = S * rng.gamma(averages, 1.0 / averages, size=len(S))
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"fem_spectrum_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([freq, S]), delimiter=",", header="frequency_Hz,value",
               comments="", fmt="%.10g")
    probe = "".join(f"{k} = {v!r}\n" for k, v in overrides.items())
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "spectrum"\ndata = "{name}.csv"\nquantity = "psd"\naverages = {averages}\n\n'
        f'[probe]\nname = "cantilever"\n{probe}\n[medium]\nname = "vacuum"\ntemperature = {T!r}\n\n'
        f'[noise]\nfrequency_rel = 1e-6\n')
    return outdir / f"{name}.toml", truth
