"""FFM friction traces: a quasi-static Prandtl-Tomlinson trace model and the friction problem.

Baseline trace model (documented in docs/diagnose.md). The tip at x is held by the lateral
spring k_x to the support (base) position X and sits in the periodic surface potential
U(x) = -U0 cos(2 pi (x - phi) / a). Quasi-statically the tip is in equilibrium
k_x (X - x) = F0 sin(2 pi (x - phi) / a), F0 = 2 pi U0 / a, and the measured lateral force is
F = k_x (X - x). On the stable branch of well n, X(x) = x + (F0/k_x) sin(2 pi (x - phi)/a) is
monotonic, so x(X) is found by bisection for all points at once (no time stepping). The tip
stays in its well until the branch ends at x_c = (a / 2 pi) arccos(-1/eta),
eta = 2 pi F0 / (k_x a) = 4 pi^2 U0 / (k_x a^2) (where k_x + U''(x) = 0: the athermal instability), and then slips into the next well (single
slips: valid for 1 < eta < ~4.6 with damping near critical; eta <= 1 gives smooth sliding).
This is the 1D limit the source uses to interpret stick-slip (section 2.1.4, and
SOURCE-NOTES item 12 on the period of the sawtooth), here written as a closed-form branch
inversion so that a whole trace costs a few vectorised operations.

Baseline free parameters: the corrugation per load mu_c = F0 / N (Amontons: F0 proportional to
the normal load) and the lattice period a, shared by all scans; the lattice registry phi of
each scan is a nuisance parameter estimated in closed form from the data's Fourier component
at the lattice frequency (a pure shift of a periodic trace multiplies that component by
exp(-2 pi i phi / a)). Forces are whitened by the stated noise sigma_F (or, when not stated,
by a robust estimate from neighbour differences).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.formats import FrictionData

__all__ = ["pt_trace", "FrictionProblem"]

N_BLOCKS = 2  # cross-validation blocks per scan (contiguous in time: forward and backward)


_TABLES: dict = {}


def _branch_table(F0k, a, xlo, xhi, m=1500):
    """Tabulated inverse of the stable branch X(x) = x + F0k sin(2 pi x / a), x in [xlo, xhi].

    Chebyshev-clustered nodes resolve the square-root behaviour of the inverse near the
    branch ends; linear interpolation error is below 1e-6 a for m = 1500 (checked against the
    bisection of the test-suite's sequential tracker).
    """
    key = (F0k, a, xlo, xhi, m)
    hit = _TABLES.get(key)
    if hit is None:
        t = 0.5 * (1 - np.cos(np.linspace(0.0, np.pi, m)))
        x = xlo + (xhi - xlo) * t
        hit = (x + F0k * np.sin(2 * np.pi * x / a), x)
        if len(_TABLES) > 512:
            _TABLES.clear()
        _TABLES[key] = hit
    return hit


def _G(u, F0k, a):
    """Antiderivative for the branch integral: int u dU = [u U(u) - u^2/2 + F0k a/(2 pi) cos(2 pi u/a)]."""
    U = u + F0k * np.sin(2 * np.pi * u / a)
    return u * U - 0.5 * u * u + F0k * a / (2 * np.pi) * np.cos(2 * np.pi * u / a)


def pt_trace(X, direction, *, F0, k, a, phi=0.0, slip_frac=1.0, boxcar=True):
    """Quasi-static PT lateral force along a scan (vectorised per direction segment).

    ``X`` support positions, ``direction`` +1/-1 per point (segments of constant direction are
    scanned in order), ``slip_frac`` in (0, 1]: the tip slips when it reaches
    ``slip_frac * x_c`` past the well centre (1 = athermal instability; < 1 = thermally
    activated early slip).

    With ``boxcar`` (default) each sample is the *mean* force over its sampling interval (from
    the midpoint to the previous sample to the midpoint to the next one, within the segment):
    an integrating detector. The mean is exact: on a branch, int x dX follows by parts from
    X(x) = x + (F0/k) sin(2 pi x / a), and an interval containing a slip is split at it. This
    makes the model continuous in its parameters (a point-sampled sawtooth moves its slips
    from sample to sample in steps, which defeats least squares). Without ``boxcar`` the force
    at the sample positions is returned.
    """
    X = np.asarray(X, float)
    direction = np.asarray(direction)
    eta = 2 * math.pi * F0 / (k * a)  # = 4 pi^2 U0 / (k a^2): stability k + U'' > 0
    F0k = F0 / k
    if eta > 1.0:
        xc = a / (2 * math.pi) * math.acos(-1.0 / eta)
    else:
        xc = a / 2.0
    xj = max(min(slip_frac, 1.0), 1e-3) * xc if eta > 1.0 else xc
    Xj0 = xj + F0k * math.sin(2 * math.pi * xj / a)
    tabX, tabx = _branch_table(F0k, a, -xc, xj)
    F = np.empty_like(X)
    cuts = np.nonzero(np.diff(direction) != 0)[0] + 1
    starts = np.concatenate([[0], cuts]); ends = np.concatenate([cuts, [len(X)]])
    n_prev = None
    for s, e in zip(starts, ends):
        d = 1.0 if direction[s] >= 0 else -1.0
        Xp = d * (X[s:e] - phi)  # mirrored, phase-free coordinates (increasing)
        n_start = np.round(Xp[0] / a) if n_prev is None else d * n_prev

        def well(Xq):
            return np.maximum(n_start, np.ceil((Xq - Xj0) / a))

        def xloc(Xq, n):  # tip position relative to the centre of well n
            return np.interp(Xq - n * a, tabX, tabx)

        n = well(Xp)
        if not boxcar or len(Xp) < 2:
            F[s:e] = d * k * (Xp - n * a - xloc(Xp, n))
        else:
            mid = 0.5 * (Xp[1:] + Xp[:-1])
            lo = np.concatenate([[Xp[0]], mid]); hi = np.concatenate([mid, [Xp[-1]]])
            nl, nh = well(lo), well(hi)
            # split point: end of well nl's branch (if the interval contains a slip)
            B = np.where(nh > nl, nl * a + Xj0, hi)
            ul, uB = xloc(lo, nl), xloc(np.minimum(B, hi), nl)
            I1 = _G(uB, F0k, a) - _G(ul, F0k, a) + 0.0  # int u dU on well nl (local coordinates)
            Ix1 = I1 + nl * a * (B - lo)
            uB2, uh = xloc(B, nh), xloc(hi, nh)
            Ix2 = np.where(nh > nl, _G(uh, F0k, a) - _G(uB2, F0k, a) + nh * a * (hi - B), 0.0)
            width = hi - lo
            xmean = np.where(width > 0, (Ix1 + Ix2) / np.where(width > 0, width, 1.0), n * a + xloc(Xp, n))
            Xmean = np.where(width > 0, 0.5 * (lo + hi), Xp)
            F[s:e] = d * k * (Xmean - xmean)
        n_prev = d * n[-1]
    return F


def _registry(trace, X, direction, target, w, a) -> float:
    """Lattice registry phi of one scan (a nuisance parameter), in closed form plus one parabola.

    A lattice shift phi shifts the steady part of the trace, so the Fourier components at 1/a
    of model (phi = 0) and data obey c_d = c_m exp(-2 pi i phi / a); summing the cross
    spectra c_m conj(c_d) of the forward and backward segments (Hann window, the first 1.5 a
    of travel after each start/reversal left out as transient) gives phi without the
    cancellation of the two directions' fundamentals. The sum of squares is then minimised by
    two parabolas through phi, phi +- h (h = 0.004 a, then 0.001 a): the start transients bias
    the Fourier estimate by ~0.3 % of a, and the least-squares minimum is that sharp.
    """
    f0 = trace(0.0)
    cuts = np.nonzero(np.diff(direction) != 0)[0] + 1
    starts = np.concatenate([[0], cuts]); ends = np.concatenate([cuts, [len(X)]])
    acc = 0.0 + 0.0j
    for s_, e_ in zip(starts, ends):
        idx = np.arange(s_, e_)[np.abs(X[s_:e_] - X[s_]) > 1.5 * a]
        if len(idx) < 8:
            continue
        e = np.exp(-2j * np.pi * X[idx] / a) * np.hanning(len(idx))
        acc += np.sum(f0[idx] * e) * np.conj(np.sum(target[idx] * e))
    span = float(np.ptp(X))
    if acc == 0 or span < 4 * a:  # noqa: SIM114
        # too few periods for the Fourier estimate (e.g. the second train of a small scan
        # angle): best of a 16-point grid over one period
        grid = np.arange(16) * a / 16
        sse = [float(np.sum((target - w * trace(g)) ** 2)) for g in grid]
        phi = float(grid[int(np.argmin(sse))])
        h0 = a / 32
    else:
        phi = (a / (2 * np.pi)) * float(np.angle(acc))
        h0 = 4e-3 * a
    for h in dict.fromkeys((h0, h0 / 4, 1e-3 * a)):
        sse = [float(np.sum((target - w * trace(phi + d)) ** 2)) for d in (-h, 0.0, h)]
        den = sse[0] - 2 * sse[1] + sse[2]
        if den > 0:
            phi += float(np.clip(0.5 * h * (sse[0] - sse[2]) / den, -2 * h, 2 * h))
    return phi


class FrictionProblem:
    kind = "friction"
    unit = "N"
    n_folds = 4  # K-fold cross-validation over the scan blocks

    def __init__(self, data: FrictionData):
        self.data = data
        sc = data.scans
        self.n_scans = len(sc)
        self.speeds = np.array([s.speed for s in sc])
        self.loads = np.array([s.load for s in sc])
        self.v_max = float(self.speeds.max())
        self.N_mean = float(self.loads.mean()) if self.loads.mean() > 0 else 1e-9
        self.force = np.concatenate([s.force for s in sc])
        self.sigma = data.sigma_force if data.sigma_force > 0 else 1e-12
        self.F_ref = data.k_x * data.lattice  # natural force scale k_x a
        gid = []
        for i, s in enumerate(sc):
            m = len(s.force)
            gid.append(i * N_BLOCKS + np.minimum((np.arange(m) * N_BLOCKS) // m, N_BLOCKS - 1))
        self.groups = np.concatenate(gid)
        self.group_labels = [f"scan {s.id}" for s in sc]
        a0 = self._period_estimate()
        self.a_start = a0
        f_amp = float(np.sqrt(2) * np.std(self.force))
        mu0 = max(min(f_amp / self.N_mean, 1e3), 1e-5)
        self.base_params = [
            CauseParam("mu_c", "1 (F0 / N)", 1e-6, 1e4, (mu0,), "corrugation force per normal load", scale="log"),
            CauseParam("a", "m", 0.7 * a0, 1.4 * a0, (a0,), "lattice period"),
        ]
        self.causes = [c() for c in catalog("friction")]
        self.t_mid = [0.5 * (s.time[0] + s.time[-1]) for s in sc]
        self.t_span = [max(s.time[-1] - s.time[0], 1e-12) for s in sc]

    def _period_estimate(self) -> float:
        """Lattice period from the periodogram of the traces (search 0.5 - 2 x nominal)."""
        a_nom = self.data.lattice
        cand = a_nom * np.linspace(0.5, 2.0, 601)
        power = np.zeros_like(cand)
        for s in self.data.scans:
            fwd = s.direction > 0
            for sel in (fwd, ~fwd):
                if sel.sum() < 8:
                    continue
                x = s.position[sel]; f = s.force[sel] - s.force[sel].mean()
                E = np.exp(-2j * np.pi * np.outer(1.0 / cand, x))
                power += np.abs(E @ f) ** 2
        return float(cand[int(np.argmax(power))])

    # ------------------------------------------------------------------ model
    def state(self, values: dict[str, float], causes=()) -> dict[str, Any]:
        s = dict(mu_c=values.get("mu_c", self.base_params[0].starts[0]), a=values.get("a", self.a_start),
                 n_adh=0.0, slip_b=0.0, bow=0.0, offset=0.0, drift=0.0, visc=0.0, theta=0.0)
        for c in causes:
            c.apply(values, s)
        return s

    def predict_scan(self, s: dict[str, Any], scan, data_force=None, phases=None, record=None):
        """Model force of one scan; the lattice phase(s) come from the data when given."""
        d = self.data
        k, a = d.k_x, s["a"]
        F0 = s["mu_c"] * max(scan.load + s["n_adh"] * self.N_mean, 0.0)
        slip = 1.0 + s["slip_b"] * math.log(scan.speed / self.v_max)
        X = scan.position
        if s["bow"]:
            x0, x1 = X.min(), X.max()
            X = X + s["bow"] * (X - x0) * (x1 - X) / max(x1 - x0, 1e-30)
        th = math.radians(s["theta"])
        trains = [(math.cos(th), X * math.cos(th))]
        if th > 0:
            trains.append((math.sin(th), X * math.sin(th)))
        i = self.data.scans.index(scan)
        F = self.F_ref * (s["visc"] * (scan.speed / self.v_max) * scan.direction
                          + s["offset"] + s["drift"] * (scan.time - self.t_mid[i]) / self.t_span[i])
        for j, (w, Xt) in enumerate(trains):
            if F0 <= 0 or w <= 0:
                continue
            trace = lambda ph: pt_trace(Xt, scan.direction, F0=F0, k=k, a=a, phi=ph, slip_frac=slip)  # noqa: E731
            if phases is not None:
                phi = phases[j]
            elif data_force is not None:
                phi = _registry(trace, Xt, scan.direction, data_force - F, w, a)
            else:
                phi = 0.0
            if record is not None:
                record.append(phi)
            fj = trace(phi)
            F = F + w * fj
        return F

    def residuals(self, values: dict[str, float], causes=(), nuisance=None, record=None) -> np.ndarray:
        """Whitened residuals; ``record`` (a list) receives the per-scan lattice registries,
        ``nuisance`` (such a list) imposes them instead of profiling them out."""
        s = self.state(values, causes)
        out = []
        for i, sc in enumerate(self.data.scans):
            rec = [] if record is not None else None
            ph = nuisance[i] if nuisance is not None else None
            out.append((sc.force - self.predict_scan(s, sc, sc.force, phases=ph, record=rec)) / self.sigma)
            if record is not None:
                record.append(rec)
        return np.concatenate(out)

    def physical_residual_rms(self, r: np.ndarray) -> float:
        return float(np.sqrt(np.mean(r**2)) * self.sigma)

    # ------------------------------------------------------------ structure
    def structure(self, r: np.ndarray) -> dict[str, Any]:
        out: dict[str, Any] = {"scans": []}
        pos = 0
        means = []
        for sc in self.data.scans:
            m = len(sc.force)
            rr = r[pos:pos + m]; pos += m
            rc = rr - rr.mean()
            den = float(np.sum(rc**2)) or 1.0
            ac = [float(np.sum(rc[:-L] * rc[L:]) / den) for L in range(1, 11)]
            # Ljung-Box Q on 10 lags: white residuals give chi^2(10)
            from scipy.stats import chi2

            Q = m * (m + 2) * sum(c * c / (m - L) for L, c in enumerate(ac, start=1))
            fwd = sc.direction > 0
            half = 0.5 * (sc.force[fwd].mean() - sc.force[~fwd].mean()) if fwd.any() and (~fwd).any() else float(np.mean(sc.force * sc.direction))
            # dominant period of the residual along the scan
            x = sc.position
            per = np.linspace(0.2, 3.0, 281) * self.a_start
            E = np.exp(-2j * np.pi * np.outer(1.0 / per, x))
            pw = np.abs(E @ rc) ** 2
            means.append(float(rr.mean()))
            out["scans"].append({"scan": sc.id, "speed": sc.speed, "load": sc.load, "mean_residual_sigma": float(rr.mean()),
                                 "rms_sigma": float(np.sqrt(np.mean(rr**2))), "lag1_autocorr": ac[0],
                                 "ljung_box_p": float(chi2.sf(Q, 10)), "mean_friction_N": float(half),
                                 "residual_period_m": float(per[int(np.argmax(pw))])})
        fr = np.array([s_["mean_friction_N"] for s_ in out["scans"]])
        for key, xv in (("ln_speed", np.log(self.speeds)), ("load", self.loads)):
            if np.ptp(xv) > 0 and len(xv) >= 3:
                A = np.vstack([np.ones_like(xv), xv - xv.mean()]).T
                coef, res, *_ = np.linalg.lstsq(A, fr, rcond=None)
                out[f"friction_vs_{key}_slope"] = float(coef[1])
        return out

    # ------------------------------------------------- separating measurement
    def candidate_measurements(self, sa: dict, sb: dict) -> list[dict[str, Any]]:
        """Hypothetical extra scans (speed x10, /10, load x2, a second scan later) and their separation."""
        ref = self.data.scans[int(np.argmax(self.speeds))]
        out = []
        variants = [("a scan at 10x the highest speed", 10.0, 1.0), ("a scan at 1/10 of the lowest speed", 0.1 * self.speeds.min() / ref.speed, 1.0),
                    ("a scan at twice the highest load", 1.0, 2.0 * self.loads.max() / max(ref.load, 1e-30)),
                    ("a scan at half the lowest load", 1.0, 0.5 * self.loads.min() / max(ref.load, 1e-30))]
        from probedyn.diagnose.formats import FrictionScan

        for label, fs, fl in variants:
            sc = FrictionScan(-1, ref.speed * fs, ref.load * fl, ref.position, ref.force, ref.time / fs, ref.direction)
            self.data.scans.append(sc); self.t_mid.append(self.t_mid[0]); self.t_span.append(self.t_span[0] / fs)
            try:
                fa = self.predict_scan(sa, sc, ref.force)
                fb = self.predict_scan(sb, sc, ref.force)
            finally:
                self.data.scans.pop(); self.t_mid.pop(); self.t_span.pop()
            ma = float(np.mean(fa * sc.direction)); mb = float(np.mean(fb * sc.direction))
            sep = float(np.sqrt(np.mean((fa - fb) ** 2)) / self.sigma * math.sqrt(len(fa)))
            out.append({"measure": label, "a": ma, "b": mb, "unit": "N (mean friction)", "separation_sigma": sep})
        return sorted(out, key=lambda r: -r["separation_sigma"])

    def describe_data(self) -> dict[str, Any]:
        return {"kind": "friction", "scans": self.n_scans, "points": int(len(self.force)),
                "speeds": sorted(set(self.speeds.tolist())), "loads": sorted(set(self.loads.tolist())),
                "k_x": self.data.k_x, "sigma_force": self.sigma, "noise_stated": self.data.noise_stated,
                "lattice_estimate": self.a_start}
