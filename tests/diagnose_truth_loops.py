"""Independent truth for mesoscale friction loops (:mod:`probedyn.diagnose.friction_loop`).

A tip slides with Coulomb friction ``mu`` on a polymer-like surface (islands of a second phase as
Gaussian-edged plateaus of 5-60 nm height; a flat, tilted surface for the noise-only cases), under the
vertical load ``L`` the feedback holds plus an adhesion ``A`` along the surface normal. The lateral force
is the tip's **force balance on the incline solved as a 2 x 2 linear system** at 8 points per sample
interval and averaged (interval means), its own code path: no use of probedyn's slope law or FFM. Where the
support turns, the tip sticks until the lever's force has run from one direction's friction to the other's
(:func:`_with_reversal`, on a fine grid of its own). The
lateral channel reads ``g`` times the force plus a zero offset and white noise; the height channel
records the surface shifted by the feedback's lag (forward in the trace, backward in the retrace) plus
noise. Optional friction contrast: the islands' friction coefficient differs by a factor 0.6-1.5.

Hidden effect ``surface-slope``: the islands (the expected coupling is ``c = g``, the calibration
factor; to first order, :mod:`probedyn.diagnose.causes.surface_slope`). Noise-only: a flat surface
tilted by up to 1 %, the same plane under every line (a constant slope is an offset), heights recorded
with their noise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _surface(rng, x, flat: bool, tilt: float):
    """Heights [m] and the island indicator (0..1) at positions x (the sample's plane tilted by ``tilt``:
    the same for every line)."""
    if flat:
        return tilt * (x - x.mean()), np.zeros_like(x)
    L = float(np.ptp(x))
    ind = np.zeros_like(x)
    for _ in range(rng.integers(3, 9)):
        c, w, e = rng.uniform(0, L), rng.uniform(0.3e-6, 2.5e-6), rng.uniform(0.15e-6, 0.6e-6)
        ind = np.maximum(ind, 0.5 * (np.tanh((x - x[0] - c + w / 2) / e) - np.tanh((x - x[0] - c - w / 2) / e)))
    return tilt * (x - x.mean()) + rng.uniform(5e-9, 60e-9) * ind, ind


def _balance(L, A, mu, d, theta):
    """Horizontal force of the lever on the tip: solve the tip's equilibrium on an incline of angle theta
    for (F_x, R), R the repulsion along the normal n = (-sin, cos), friction mu R against the motion d."""
    s, c = np.sin(theta), np.cos(theta)
    n = len(theta)
    M = np.zeros((n, 2, 2))
    b = np.zeros((n, 2))
    # x: F_x + A s - R s - mu R d c = 0 ;  z: -L - A c + R c - mu R d s = 0
    M[:, 0, 0] = 1.0
    M[:, 0, 1] = -s - mu * d * c
    b[:, 0] = -A * s
    M[:, 1, 1] = c - mu * d * s
    b[:, 1] = L + A * c
    return np.linalg.solve(M, b[..., None])[:, 0, 0]


def _with_reversal(sub: np.ndarray, other: np.ndarray, d: float, k_x: float, dx: float, m: int = 256) -> np.ndarray:
    """Interval means of the lateral force of one direction ``d`` with its reversal: the support turns half an
    interval before the first sample, and the tip sticks there while the lever's force runs, at ``k_x`` per metre
    of support travel, from the other direction's sliding force (``other``: the same line scanned the other
    way before, a raster) until it reaches this direction's; then it slides. ``sub``: the sliding force at the
    8 sub-points of every interval (as positions increase). The intervals the stick reaches are averaged over
    ``m`` points each, on the sliding force interpolated between the sub-points."""
    n = sub.shape[0]
    F = sub.mean(axis=1)
    run = sub if d > 0 else sub[::-1, ::-1]  # in the order of the motion
    F_prev = other[0, 0] if d > 0 else other[-1, -1]
    span = 2.0 * float(np.max(np.abs(sub))) / k_x
    K = min(n, int(np.ceil(span / dx)) + 1)
    u_sub = (np.arange(K)[:, None] + (np.arange(8) + 0.5)[None, :] / 8).ravel() * dx
    u = (np.arange(K * m) + 0.5) / m * dx
    slide = np.interp(u, u_sub, run[:K].ravel())
    ramp = F_prev + d * k_x * u
    stuck = ~np.maximum.accumulate(d * ramp >= d * slide)
    f = np.where(stuck, ramp, slide).reshape(K, m).mean(axis=1)
    if d > 0:
        F[:K] = f
    else:
        F[n - K:] = f[::-1]
    return F


def make_loop_case(folder: Path, seed: int, effect: str | None,
                   load_factors: tuple[float, ...] | None = None,
                   adhesion_ratio: float | None = None, drift_rate: float = 0.0,
                   contact_stiffness: float | None = None, overrides: dict | None = None) -> tuple[Path, dict]:
    """One loop record. ``load_factors``: the scans' loads as multiples of the drawn load ``L`` (cycled over
    the scans, at least one scan each; default: every scan at ``L``, the draws of earlier sessions).
    ``adhesion_ratio``: the adhesion load as a multiple of ``L`` instead of the drawn 0-0.5 (0: none).
    ``effect``: None (flat surface), ``"surface-slope"`` (relief), ``"adhesion-load"`` (flat; the adhesion
    is the hidden effect, which scans at two loads can show). ``drift_rate`` [N/s]: the lateral channel's zero
    drifts linearly in time on one clock through the record (trace, retrace, next line; a ``time_s`` column is
    then written, each sample at the middle of its interval); 0: no drift and no time column, as before.
    ``contact_stiffness`` [N/m]: the tip-sample contact's lateral stiffness in series with the lever, which the
    stick at each reversal then rises at, ``(1/k_x + 1/k_c)^-1`` (None: a rigid contact, as before).
    ``overrides``: drawn values replaced (``k_x`` [N/m], ``length`` [m], ``n`` samples per line, ``sigma`` [N]); the
    other draws stay those of the seed."""
    rng = np.random.default_rng([seed, 23])
    n_scans = int(rng.integers(1, 4))
    factors = tuple(load_factors) if load_factors else (1.0,)
    n_scans = max(n_scans, len(factors))
    n = int(rng.choice([128, 256, 512]))
    length = rng.uniform(5e-6, 25e-6)
    speed = 10 ** rng.uniform(np.log10(2e-6), np.log10(2e-5))
    k_x = 10 ** rng.uniform(np.log10(5.0), np.log10(50.0))
    L = rng.uniform(5e-9, 50e-9)
    mu0 = rng.uniform(0.1, 0.6)
    A = rng.uniform(0.0, 0.5) * L
    if adhesion_ratio is not None:
        A = adhesion_ratio * L
    g = rng.uniform(0.7, 1.4) if rng.random() < 0.5 else 1.0
    contrast = rng.uniform(0.6, 1.5) if rng.random() < 0.5 else 1.0
    sigma = rng.uniform(0.01, 0.05) * mu0 * (L + A)
    h_noise = rng.uniform(0.05e-9, 0.5e-9)
    lag = int(rng.integers(0, 3))
    zero = rng.uniform(-50e-9, 50e-9)
    ov = dict(overrides or {})
    k_x, length, n, sigma = (ov.pop("k_x", k_x), ov.pop("length", length), int(ov.pop("n", n)), ov.pop("sigma", sigma))
    if ov:
        raise ValueError(f"unknown overrides: {', '.join(ov)}")
    x = np.linspace(0.0, length, n)
    dx = x[1] - x[0]
    sub = (np.arange(8) + 0.5) / 8 - 0.5
    rows = []
    clock = 0.0
    dt = (length / (n - 1)) / speed
    flat = effect in (None, "adhesion-load")
    tilt = rng.uniform(-0.01, 0.01)
    loads = [L * factors[(sid - 1) % len(factors)] for sid in range(1, n_scans + 1)]
    for sid in range(1, n_scans + 1):
        Ls = loads[sid - 1]
        xs = (x[:, None] + sub[None, :] * dx).ravel()
        h_true, ind = _surface(rng, np.concatenate([x, xs]), flat, tilt)
        h_pts, h_sub, ind_sub = h_true[:n], h_true[n:], ind[n:]
        theta = np.arctan(np.gradient(h_sub, xs))
        mu = mu0 * (1.0 + (contrast - 1.0) * ind_sub)
        bal = {d: _balance(Ls, A, mu, d, theta).reshape(n, 8) for d in (1.0, -1.0)}
        for d in (1.0, -1.0):
            k_stick = k_x if contact_stiffness is None else 1.0 / (1.0 / k_x + 1.0 / contact_stiffness)
            F = _with_reversal(bal[d], bal[-d], d, k_stick, dx)
            sig = g * F + zero + sigma * rng.standard_normal(n)
            hrec = np.roll(h_pts, int(d) * lag)
            if lag:
                hrec[:lag] = h_pts[:lag] if d > 0 else hrec[:lag]
                hrec[-lag:] = h_pts[-lag:] if d < 0 else hrec[-lag:]
            hrec = hrec + h_noise * rng.standard_normal(n)
            order = list(range(n) if d > 0 else range(n - 1, -1, -1))
            t_rec = clock + (np.arange(n) + 0.5) * dt
            clock += n * dt
            rows += [(sid, x[j], sig[j] + drift_rate * t_rec[k], hrec[j], t_rec[k]) for k, j in enumerate(order)]
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    name = f"loop_{seed}"
    with open(folder / f"{name}.csv", "w") as fh:
        if drift_rate:
            fh.write("scan,position_m,lateral_force_N,height_m,time_s\n")
            fh.writelines(f"{s},{xx:.9e},{f:.9e},{h:.9e},{t:.9e}\n" for s, xx, f, h, t in rows)
        else:
            fh.write("scan,position_m,lateral_force_N,height_m\n")
            fh.writelines(f"{s},{xx:.9e},{f:.9e},{h:.9e}\n" for s, xx, f, h, _ in rows)
    scans = "".join(f"[[scans]]\nid = {s}\nspeed = {speed:.6e}\nload = {loads[s - 1]:.6e}\n" for s in range(1, n_scans + 1))
    (folder / f"{name}.toml").write_text(
        f'[measurement]\nkind = "friction"\ndata = "{name}.csv"\nsampling = "interval-mean"\n'
        f"[lever]\nk_x = {k_x:.6g}\n[medium]\nname = \"air\"\n{scans}")
    params = {"c_slope": g} if effect == "surface-slope" else {"n_adh": A} if effect == "adhesion-load" else {}
    if drift_rate:
        params = {**params, "drift": drift_rate * (2 * n - 1) * dt}  # over one scan, its first to its last sample
    truth = {"effect": effect, "params": params, "drift_rate": drift_rate, "g": g, "mu": mu0, "A": A, "L": L,
             "contrast": contrast, "sigma": sigma, "loads": loads, "lag": lag, "k_x": k_x, "speed": speed, "n": n, "scans": n_scans,
             "k_contact": contact_stiffness}
    return folder / f"{name}.toml", truth
