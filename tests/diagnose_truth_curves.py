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

Hidden effects: ``adhesion-dmt`` (the tail's range zeta_0 drawn, 0.15-0.5 nm), ``adhesion-jkr``, ``adhesion-md`` (lambda drawn; Maugis' own Dugdale zone out of contact since session 45, departure 47), ``jump-to-
contact`` (DMT on a soft lever: the van der Waals gradient exceeds k well before contact),
``tip-radius-error`` (the declared radius is wrong; the sample modulus is declared),
``deflection-drift`` (a drift of the deflection in time), ``tip-shape`` (the registry's blunted cone,
half-angle 15-35 deg, on a soft sample indented 1.2-4 times deeper than the cap's edge depth R cot^2(alpha),
where the flanks carry the load), ``piezo-hysteresis`` (the retract's true piezo position offset by
0.5-5 nm from the recorded one), ``deflection-sensitivity`` (:data:`CALIBRATION_EFFECTS`: the recorded
deflection a factor 1.05-1.5 or its inverse times the lever's true one). Noise-only cases: Hertz + the linear
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
#: detector effects (seeds 2200 + i, alternating; their draws come from a second stream of the seed so the
#: 2000-series above is unchanged): the lever's hydrodynamic drag in water after Alcaraz et al. (2002),
#: ``6 pi eta a_eff^2 / (s + h_eff)`` at the piezo velocity of a fast ramp, and the optical lever's
#: interference, ``A cos(4 pi s cos(theta) / lambda + phi)`` with an AFM laser's wavelength; both on a
#: 0.4-1.5 um non-contact baseline, recorded with times, water declared in half of the cases
DETECTOR_EFFECTS = ["hydrodynamic-drag", "optical-interference"]
EXPECTED.update({"hydrodynamic-drag": ("hydrodynamic-drag", "b_drag"),
                 "optical-interference": ("optical-interference", "period")})
LASERS_M = (635e-9, 670e-9, 785e-9, 830e-9, 850e-9)
#: calibration effects (seeds 2300 + i; drawn from a third stream of the seed): the deflection sensitivity
#: (InvOLS) declared in the sidecar is ``s_ratio`` times the true one, 5-50 % off either way, so every recorded
#: deflection (and force) is that factor times the lever's true deflection
CALIBRATION_EFFECTS = ["deflection-sensitivity"]
EXPECTED["deflection-sensitivity"] = ("deflection-sensitivity", "s_ratio")
ETA_WATER = 8.9e-4


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



def _as_recorded(Fm, noise: float, k: float, rng):
    """The force record as an instrument exports it, drawn from ``rng``: deflection in V (with a drawn
    sensitivity), deflection in m, or force; returns (column name, sensitivity, column, the sidecar's
    noise line)."""
    fmt = ["deflection_V", "deflection_m", "force_N"][int(rng.integers(3))]
    sens = float(rng.uniform(20e-9, 100e-9))
    if fmt == "deflection_V":
        return fmt, sens, Fm / (k * sens), f"deflection = {noise / (k * sens)!r}"
    if fmt == "deflection_m":
        return fmt, sens, Fm / k, f"deflection = {noise / k!r}"
    return fmt, sens, Fm, f"force = {noise!r}"

def correlated(e: np.ndarray, rho: float) -> np.ndarray:
    """AR(1) noise of unit marginal variance and lag-one correlation ``rho`` from the white draws ``e`` (one
    chain in recording order: ``x_0 = e_0``, ``x_i = rho x_(i-1) + sqrt(1 - rho^2) e_i``); ``rho = 0``
    returns ``e`` itself (the white cases' stream is unchanged)."""
    if rho == 0.0:
        return e
    x = np.empty(len(e))
    x[0] = e[0]
    c = math.sqrt(1.0 - rho * rho)
    for i in range(1, len(e)):
        x[i] = rho * x[i - 1] + c * e[i]
    return x


def power_law_spectrum(n: int, alpha: float) -> np.ndarray:
    """``|H(f)|^2 = f^-alpha`` on ``numpy.fft.rfftfreq(n)`` (the zero frequency given the first one's power, so
    that the process is stationary with a finite mean), scaled to unit marginal variance: the spectrum of
    :func:`power_law`'s noise."""
    f = np.fft.rfftfreq(n)
    f[0] = f[1]
    s2 = f ** -alpha
    return s2 / float(np.fft.irfft(s2, n)[0])


def power_law_covariance(n: int, alpha: float) -> np.ndarray:
    """The exact covariance of :func:`power_law`'s ``n`` samples: circulant, ``c(j) = irfft(|H|^2)[j]``."""
    c = np.fft.irfft(power_law_spectrum(n, alpha), n)
    j = np.arange(n)
    return c[(j[None, :] - j[:, None]) % n]


def power_law(e: np.ndarray, alpha: float) -> np.ndarray:
    """Noise of power spectral density ``~ 1/f^alpha`` (alpha = 1: flicker, "1/f", noise; 2: a random walk) and
    unit marginal variance, from the white draws ``e``: the circular convolution of ``e`` with the filter
    ``sqrt(power_law_spectrum)`` (stationary over the record; its covariance is
    :func:`power_law_covariance`). A detector's 1/f noise has more power at the record's scale than any AR(1)
    noise with the same point-to-point statistics."""
    n = len(e)
    return np.fft.irfft(np.fft.rfft(e) * np.sqrt(power_law_spectrum(n, alpha)), n)


def make_curve_case(outdir: Path, seed: int, effect: str | None, *, n: int = 300,
                    noise_rho: float = 0.0, state_noise: bool = True,
                    declare_rho: float | None = None, noise_alpha: float | None = None,
                    white_floor: float | None = None, retract_noise: float = 1.0) -> tuple[Path, dict]:
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
        if law == "dmt":  # the tail's range, from its own stream (the other draws unchanged): Israelachvili's
            # 0.165 nm cut-off to half a nanometre, around the registry's 0.375 nm (session 25: a blind
            # generator's 0.165 nm tail was named Maugis-Dugdale while the diagnosis held the range fixed)
            params["z0"] = float(10 ** np.random.default_rng([seed, 31]).uniform(math.log10(0.15e-9), math.log10(0.5e-9)))
            kw["z0"] = params["z0"]
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
    aux = np.random.default_rng([seed, 17])  # the detector effects' own stream
    if effect in DETECTOR_EFFECTS:
        z_far = z_c - float(aux.uniform(0.4e-6, 1.5e-6))
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
    seg = np.concatenate([np.zeros(n, int), np.ones(n, int)])
    sep = F / k - (z - z_c)  # the tip's height above the undeformed surface (-delta in contact)
    detector = np.zeros(len(F))
    if effect == "hydrodynamic-drag":  # a fast ramp in water (Alcaraz et al. 2002)
        v = float(10 ** aux.uniform(math.log10(30e-6), math.log10(300e-6)))
        t = np.arange(2 * n) * (z_top - z_far) / (n - 1) / v
        a_eff, h_eff = float(aux.uniform(20e-6, 50e-6)), float(aux.uniform(2e-6, 10e-6))
        b = 6 * math.pi * ETA_WATER * a_eff**2 / (np.maximum(sep, 0.0) + h_eff)
        detector = b * np.where(seg == 0, v, -v)
        params.update(b_drag=6 * math.pi * ETA_WATER * a_eff**2 / h_eff, h_eff=h_eff, velocity=v)
    elif effect == "optical-interference":
        lam = float(aux.choice(LASERS_M))
        period = lam / (2 * math.cos(math.radians(float(aux.uniform(0.0, 15.0)))))
        A = noise * float(10 ** aux.uniform(-0.3, 0.7))
        detector = A * np.cos(2 * math.pi * sep / period + float(aux.uniform(0, 2 * math.pi)))
        params.update(period=period, amplitude=A)
    gain = 1.0
    if effect == "deflection-sensitivity":
        cal = np.random.default_rng([seed, 53])
        gain = float(math.exp(cal.choice([-1, 1]) * cal.uniform(math.log(1.05), math.log(1.5))))
        params["s_ratio"] = gain
    clean = gain * F + b0 + b1 * z + drift * tau + detector
    e = rng.standard_normal(len(F))
    # the sidecar states the marginal sigma; ``noise_alpha``: 1/f^alpha noise instead of AR(1)
    Fm = clean + noise * (correlated(e, noise_rho) if noise_alpha is None else power_law(e, noise_alpha))
    if white_floor is not None:  # a detector: a white floor carrying this share of the variance under the slow
        # noise (its own stream: every other draw unchanged; the marginal sigma stays ``noise``)
        floor = np.random.default_rng([seed, 43]).standard_normal(len(F))
        Fm = clean + math.sqrt(1.0 - white_floor) * (Fm - clean) + math.sqrt(white_floor) * noise * floor
    if retract_noise != 1.0:  # the retract recorded at a higher rate than the approach, through a wider
        # detector bandwidth: its noise this many times the approach's (the JPK QI curve: 5 and 50 kHz, 4.3x)
        Fm = clean + (Fm - clean) * np.where(seg == 1, retract_noise, 1.0)
    fmt, sens, col, noise_line = _as_recorded(Fm, noise, k, rng)
    with_time = bool(rng.integers(2)) or effect == "hydrodynamic-drag"
    water = effect in DETECTOR_EFFECTS and bool(aux.integers(2))
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
        f"E = {E_TIP!r}\nnu = {NU_TIP!r}\n{sample}\n" + (f"[noise]\n{noise_line}\n" if state_noise else "")
        + (("" if state_noise else "[noise]\n") + f"correlation = {declare_rho!r}\n" if declare_rho is not None else "")
        + ('\n[medium]\nname = "water"\n' if water else ""))
    truth = {"effect": effect, "params": params, "k": k, "E_s": E_s, "z_c": z_c, "b0": b0, "b1": b1, "noise": noise,
             "noise_rho": noise_rho, "noise_alpha": noise_alpha, "white_floor": white_floor, "retract_noise": retract_noise, "noise_stated": state_noise, "R_nom": R_nom, "declared_E": declare_E, "format": fmt, "time_column": with_time, "snap_in": snap_in,
             "water_declared": water, "force_clean": clean}  # the noise-free record [N] (for the detectability criterion; not written)
    return outdir / f"{name}.toml", truth


# ------------------------------------------------------------------------------------------
# A viscoelastic sample (standard linear solid): brute-force Lee-Radok / Ting with the lever
# ------------------------------------------------------------------------------------------

#: the viscoelastic cases' effect name, cause and main parameter (seeds 2100 + i: the 2000-series generator
#: above is unchanged)
VISCO_EFFECT = "viscoelastic-sample"
EXPECTED[VISCO_EFFECT] = ("viscoelastic-sample", "strength")


def visco_lever_truth(t, z_rel, k: float, E_inf: float, s: float, tau: float, R: float, refine: int = 4):
    """Force on a lever (stiffness k) over a standard-linear-solid half-space ``E(t) = E_inf (1 + s e^{-t/tau})``
    indented by a sphere of radius R, along the piezo record ``z_rel(t)`` (towards the sample, 0 at the
    undeformed surface) -- written independently of :mod:`probedyn.schemes.contact.viscoelastic`: the
    hereditary integrals are **summed by brute force** (O(N^2), Stieltjes sums with the kernel at the
    midpoint of every step) on a grid ``refine`` times finer than the samples (the piezo path linear in
    between); while the contact grows (Lee & Radok 1960) the lever equation ``delta + P / k = z_rel`` is
    solved for delta by Brent's method; after the largest contact (Ting 1966) for the time t1 at which
    ``int_{t1}^{t} E(t - u) d delta(u) = 0`` (its condition solved for delta(t) at given t1, the lever
    equation for t1 by Brent's method); the contact is lost when no t1 after the first touch satisfies
    it (no adhesion). Returns the force at the samples."""
    from scipy.optimize import brentq

    t = np.asarray(t, float)
    z_rel = np.asarray(z_rel, float)
    tf = np.concatenate([np.linspace(t[i], t[i + 1], refine + 1)[:-1] for i in range(len(t) - 1)] + [t[-1:]])
    zf = np.interp(tf, t, z_rel)
    cg = 4.0 / 3.0 * math.sqrt(R)
    g = lambda d: cg * max(d, 0.0) ** 1.5  # noqa: E731
    E = lambda x: E_inf * (1.0 + s * np.exp(-x / tau))  # noqa: E731
    N = len(tf)
    dl = np.zeros(N)  # surface displacement under the tip (tip position while in contact)
    gl = np.zeros(N)
    F = np.zeros(N)
    m = -1  # last index of the growing contact
    t0 = None  # index of the step in which the contact starts
    lost = False
    for n in range(N):
        if lost or (t0 is None and zf[n] <= 0.0):
            dl[n] = min(zf[n], 0.0) if t0 is None else 0.0
            continue
        if t0 is None:
            t0 = n - 1 if n > 0 else 0
            dl[t0] = 0.0
            gl[t0] = 0.0
        tm = 0.5 * (tf[t0 + 1:n + 1] + tf[t0:n]) if n > t0 else np.zeros(0)
        w = E(tf[n] - tm)  # kernel at the midpoints of steps t0 .. n-1 -> n
        # growing contact: P = sum w (g_j - g_{j-1}) with the last increment unknown
        hist_g = float(np.dot(w[:-1], np.diff(gl[t0:n]))) if n - t0 > 1 else 0.0

        def lever_grow(d):
            return d + (hist_g + w[-1] * (g(d) - gl[n - 1])) / k - zf[n]

        d_prev_max = dl[m] if m >= 0 else 0.0
        if lever_grow(d_prev_max) <= 0.0:  # the root lies beyond the largest contact so far: Lee-Radok
            hi = max(zf[n], d_prev_max) + 1e-12
            d = brentq(lever_grow, d_prev_max, hi, xtol=1e-16, rtol=1e-13) if lever_grow(hi) > 0 else hi
            dl[n], gl[n] = d, g(d)
            F[n] = hist_g + w[-1] * (gl[n] - gl[n - 1])
            m = n
            continue
        # shrinking contact (Ting): t1 = t0 + x (x in [0, m - t0] in steps of the loading history)
        dd_load = np.diff(dl[t0:m + 1])
        dg_load = np.diff(gl[t0:m + 1])
        dd_un = np.diff(dl[m:n])  # unloading increments m -> n-1 (known)

        def at_t1(x):
            j = int(min(math.floor(x), m - t0 - 1)) if m > t0 else 0
            f = x - j
            # partial step j (t0+j .. t0+j+1): the part after t1 counts in Ting's condition, before it in P
            full_after = slice(j + 1, None)
            c_load = float(np.dot(w[full_after][: len(dd_load) - j - 1], dd_load[j + 1:])) + w[j] * (1 - f) * dd_load[j]
            c_un = float(np.dot(w[m - t0:n - t0 - 1], dd_un)) if n - 1 > m else 0.0
            P = float(np.dot(w[:j], dg_load[:j])) + w[j] * f * dg_load[j]
            # Ting's condition with the last increment (n-1 -> n) unknown: solved for delta_n
            d_n = dl[n - 1] - (c_load + c_un) / w[-1]
            return d_n, P

        def lever_shrink(x):
            d_n, P = at_t1(x)
            return d_n + P / k - zf[n]

        X = float(m - t0)
        if lever_shrink(0.0) >= 0.0:  # contact lost: the tip is above the recovering surface
            lost = True
            continue
        x = brentq(lever_shrink, 0.0, X, xtol=1e-13) if lever_shrink(X) > 0 else X
        dl[n], F[n] = at_t1(x)
    return np.interp(t, tf, F)


def make_visco_case(outdir: Path, seed: int, *, n: int = 300) -> tuple[Path, dict]:
    """A Hertz sphere on a soft **viscoelastic** sample (standard linear solid, relaxed modulus E_inf
    1-30 MPa, relaxation strength s = E_0 / E_inf - 1 in 0.05-2, relaxation time tau 0.02-2 x the
    approach time), approach and retract at speeds differing by a factor 1, 3 or 10 (the JPK QI example:
    10), recorded with times (the law needs them), a tilted offset baseline and white noise as
    :func:`make_curve_case`; truth by :func:`visco_lever_truth`. The declared sample modulus (half of
    the cases) is the relaxed one."""
    rng = np.random.default_rng(seed)
    k = float(10 ** rng.uniform(-0.5, 1.0))
    R = float(rng.choice([8e-9, 20e-9, 30e-9]))
    E_s = float(10 ** rng.uniform(6.0, 7.5))
    noise = float(10 ** rng.uniform(-10.3, -9.7))
    declare_E = bool(rng.integers(2))
    s = float(10 ** rng.uniform(math.log10(0.05), math.log10(2.0)))
    Es_star = 1 / ((1 - NU_TIP**2) / E_TIP + (1 - NU_S**2) / E_s)
    Fmax = float(rng.uniform(15e-9, 60e-9))
    dmax = (Fmax / (4 / 3 * Es_star * math.sqrt(R))) ** (2 / 3)
    z_c = float(rng.uniform(-5e-9, 5e-9))
    z_top = z_c + dmax + Fmax / k
    z_far = z_c - max(40e-9, 1.5 * Fmax / k)
    dt_app = float(rng.uniform(1e-3, 5e-3))
    speed_ratio = float(rng.choice([1.0, 3.0, 10.0]))
    T_app = n * dt_app
    tau = float(T_app * 10 ** rng.uniform(math.log10(0.02), math.log10(2.0)))
    z_app = np.linspace(z_far, z_top, n)
    z_ret = z_app[::-1]
    t = np.concatenate([np.arange(n) * dt_app, (n - 1) * dt_app + np.arange(1, n + 1) * dt_app / speed_ratio])
    z = np.concatenate([z_app, z_ret])
    F = visco_lever_truth(t, z - z_c, k, Es_star, s, tau, R)
    b0 = float(rng.normal(0, 5e-9))
    b1 = float(rng.normal(0, 0.02) * k)
    clean = F + b0 + b1 * z
    Fm = clean + noise * rng.standard_normal(len(F))
    seg = np.concatenate([np.zeros(n, int), np.ones(n, int)])
    fmt, sens, col, noise_line = _as_recorded(Fm, noise, k, rng)
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    name = f"curve_{seed}"
    np.savetxt(outdir / f"{name}.csv", np.column_stack([z, col, seg, t]), delimiter=",",
               header=f"z_m,{fmt},segment,time_s", comments="", fmt=["%.10e", "%.10e", "%d", "%.9e"])
    sample = f"\n[sample]\nE = {E_s!r}\nnu = {NU_S!r}\n" if declare_E else ""
    lever = f"k = {k!r}\n" + (f"sensitivity = {sens!r}\n" if fmt == "deflection_V" else "")
    (outdir / f"{name}.toml").write_text(
        f'[measurement]\nkind = "force"\ndata = "{name}.csv"\n\n[lever]\n{lever}\n[tip]\nradius = {R!r}\n'
        f"E = {E_TIP!r}\nnu = {NU_TIP!r}\n{sample}\n[noise]\n{noise_line}\n")
    truth = {"effect": VISCO_EFFECT, "params": {"strength": s, "tau": tau}, "k": k, "E_s": E_s, "z_c": z_c, "b0": b0,
             "b1": b1, "noise": noise, "R_nom": R, "declared_E": declare_E, "format": fmt, "time_column": True,
             "speed_ratio": speed_ratio, "snap_in": False, "force_clean": clean}
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
