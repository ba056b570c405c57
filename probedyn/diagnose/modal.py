"""The modal diagnosis problem: measured modes against the reduced beam model.

Residuals are whitened: ``(f_meas - f_model) / sigma_f`` for every mode and
``(ln Q_meas - ln Q_model) / (sigma_Q / Q)`` for every measured Q, so that a correct model
with correctly stated noise gives residuals ~ N(0, 1) and chi^2 ~ chi^2(dof). The
cross-validation groups are the modes (a mode's frequency and Q are held out together).

Baseline (step 1): the nominal beam of the probe spec, with the declared medium and known tip
mass, clamped at the root. Its free parameters are the intrinsic quality factor Q_int
(1/Q = 1/Q_int + 1/Q_fluid, the same loss factor for every mode) when Q values are given, and
any probe quantities listed in ``[baseline] free`` (as ratios to the nominal value).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from probedyn.diagnose.beam import BeamFE, BeamProps, solve_family
from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.formats import ModalData

_BASE_RATIO = {"E": "E_scale", "rho": "rho_scale", "thickness": "t", "width": "w", "length": "L"}
_CAUSE_OF_FREE = {"thickness": "thickness-error", "width": "width-error", "length": "length-error", "E": "anisotropy"}


class ModalProblem:
    kind = "modal"
    unit = "relative frequency"

    def __init__(self, data: ModalData):
        self.data = data
        self.props: BeamProps = data.props
        self.nominal_EI_flap = data.props.EI("flap")
        n_max = {fam: int(data.order[data.family == fam].max()) for fam in set(data.family)}
        self.n_max = n_max
        beta_max = (max(n_max.values()) - 0.5) * math.pi + 2.0
        # Hermite cubic eigenvalue error ~ (beta h)^4 / 720 -> beta h < 0.45: f error < ~3e-5
        self.fe = BeamFE(max(16, int(math.ceil(beta_max / 0.45))))
        self._cache: dict = {}  # family solutions keyed by their inputs (a parameter change
        # re-solves only the families it affects: torsion is reused by every bending cause)
        self.n = len(data.freq)
        hasQ = ~np.isnan(data.Q)
        self.q_idx = np.nonzero(hasQ)[0]
        self.groups = np.concatenate([np.arange(self.n), self.q_idx])
        self.group_labels = [f"{fa} {o}" + (f" @L={L:.3g} m" if len(set(data.length)) > 1 else "")
                             for fa, o, L in zip(data.family, data.order, data.length)]
        base: list[CauseParam] = []
        if len(self.q_idx):
            q0 = float(np.median(data.Q[hasQ]))
            base.append(CauseParam("Q_int", "1", 1.0, 1e9, (q0,), "intrinsic quality factor (same loss factor for all modes)", scale="log"))
        for name in data.free:
            base.append(CauseParam(_BASE_RATIO[name], "1", 0.5, 1.5, (1.0,), f"{name} / nominal (calibrated)"))
        self.base_params = base
        excluded = {_CAUSE_OF_FREE[n] for n in data.free if n in _CAUSE_OF_FREE}
        self.causes = [c() for c in catalog("modal") if c.id not in excluded]

    # ------------------------------------------------------------------ model
    def state(self, values: dict[str, float], causes=()) -> dict[str, Any]:
        d = self.data
        mu0 = d.tip_mass / (self.props.rho * self.props.area * self.props.length)
        s: dict[str, Any] = dict(t=1.0, w=1.0, L=1.0, e_bend=1.0, E_scale=1.0, rho_scale=1.0,
                                 k_rot=math.inf, k_trans=math.inf,
                                 masses=[(mu0, d.tip_position)] if mu0 else [], p=0.0,
                                 rho_f=d.rho_f, eta_f=d.eta_f, Q_int=math.inf)
        for k in ("E_scale", "rho_scale", "t", "w", "L", "Q_int"):
            if k in values:
                s[k] = values[k]
        for c in causes:
            c.apply(values, s)
        return s

    def predict(self, s: dict[str, Any], family=None, order=None, length=None) -> tuple[np.ndarray, np.ndarray]:
        d, P = self.data, self.props
        family = d.family if family is None else np.asarray(family)
        order = d.order if order is None else np.asarray(order)
        length = d.length if length is None else np.asarray(length)
        f = np.empty(len(family)); Q = np.empty(len(family))
        m_nom = P.rho * P.area * P.length
        EIn, Ln = self.nominal_EI_flap, P.length
        for Lc in np.unique(length):
            props = BeamProps(Lc * s["L"], P.width * s["w"], P.thickness * s["t"], P.E * s["E_scale"],
                              P.rho * s["rho_scale"], P.nu)
            sel_c = length == Lc
            for fam in np.unique(family[sel_c]):
                sel = sel_c & (family == fam)
                nm = int(order[sel].max())
                masses = tuple((mu * m_nom, xi) for mu, xi in s["masses"])
                if fam == "torsion":
                    key = (fam, nm, props.length, props.width, props.thickness, props.E, props.rho)
                else:
                    key = (fam, nm, props.length, props.width, props.thickness, props.E, props.rho, s["k_rot"],
                           s["k_trans"], masses, s["p"], s["rho_f"] if fam == "flap" else 0.0,
                           s["eta_f"] if fam == "flap" else 0.0, s["e_bend"])
                hit = self._cache.get(key)
                if hit is None:
                    hit = solve_family(
                        self.fe, props, fam, nm,
                        k_rot=s["k_rot"] * EIn / Ln, k_trans=s["k_trans"] * EIn / Ln**3,
                        extra_masses=masses, axial_force=s["p"] * EIn / Ln**2,
                        rho_f=s["rho_f"], eta_f=s["eta_f"], E_bend=props.E * s["e_bend"])
                    if len(self._cache) > 20000:
                        self._cache.clear()
                    self._cache[key] = hit
                ff, qq = hit
                if len(ff) < nm:
                    ff = np.concatenate([ff, np.full(nm - len(ff), np.nan)]); qq = np.concatenate([qq, np.full(nm - len(qq), np.nan)])
                f[sel] = ff[order[sel] - 1]
                with np.errstate(divide="ignore"):
                    Q[sel] = 1.0 / (1.0 / s["Q_int"] + 1.0 / qq[order[sel] - 1])
        return f, Q

    def residuals(self, values: dict[str, float], causes=()) -> np.ndarray:
        d = self.data
        f, Q = self.predict(self.state(values, causes))
        r = (d.freq - f) / d.freq_sigma
        if len(self.q_idx):
            i = self.q_idx
            r = np.concatenate([r, (np.log(d.Q[i]) - np.log(Q[i])) / d.Q_sigma_rel[i]])
        return np.where(np.isfinite(r), r, 1e6)

    def physical_residual_rms(self, r: np.ndarray) -> float:
        """RMS relative frequency error of the frequency part of a whitened residual."""
        rel = r[: self.n] * self.data.freq_sigma / self.data.freq
        return float(np.sqrt(np.mean(rel**2)))

    # ------------------------------------------------------------ structure
    def structure(self, r: np.ndarray) -> dict[str, Any]:
        """Trend of the frequency residuals against mode order per family; family means."""
        d = self.data
        rf = r[: self.n]
        out: dict[str, Any] = {"by_family": {}, "rows": []}
        for k in range(self.n):
            out["rows"].append({"mode": self.group_labels[k], "f_meas_Hz": d.freq[k],
                                "residual_sigma": rf[k], "residual_rel": rf[k] * d.freq_sigma[k] / d.freq[k]})
        for fam in np.unique(d.family):
            sel = d.family == fam
            x = d.order[sel].astype(float); y = rf[sel]
            item = {"n": int(sel.sum()), "mean_sigma": float(np.mean(y))}
            if sel.sum() >= 3 and np.ptp(x) > 0:
                A = np.vstack([np.ones_like(x), x - x.mean()]).T
                coef, *_ = np.linalg.lstsq(A, y, rcond=None)
                item["slope_per_order_sigma"] = float(coef[1])
                # slope t-statistic with unit-variance residuals (whitened data)
                item["slope_t"] = float(coef[1] * math.sqrt(np.sum((x - x.mean()) ** 2)))
            out["by_family"][str(fam)] = item
        if len(self.q_idx):
            out["Q_residual_sigma"] = r[self.n:].tolist()
        signs = np.sign(rf[rf != 0])
        out["runs_of_sign"] = int(1 + np.sum(signs[1:] != signs[:-1])) if len(signs) else 0
        return out

    # ------------------------------------------------- separating measurement
    def candidate_measurements(self, sa: dict, sb: dict) -> list[dict[str, Any]]:
        """Observables not yet measured, with both models' predictions and the separation in sigma."""
        d = self.data
        rel = float(np.median(d.freq_sigma / d.freq))
        have = {(fa, int(o)) for fa, o, L in zip(d.family, d.order, d.length) if L == self.props.length}
        cands = [(fa, o) for fa, nmax in (("flap", 6), ("lateral", 2), ("torsion", 2)) for o in range(1, nmax + 1)
                 if (fa, o) not in have]
        out = []
        if cands:
            fam = np.array([c[0] for c in cands]); order = np.array([c[1] for c in cands])
            L = np.full(len(cands), self.props.length)
            fa_, qa = self.predict(sa, fam, order, L)
            fb_, qb = self.predict(sb, fam, order, L)
            for k, (fa, o) in enumerate(cands):
                sep = abs(fa_[k] - fb_[k]) / (rel * 0.5 * (fa_[k] + fb_[k]))
                out.append({"measure": f"{fa} mode {o} frequency", "a": fa_[k], "b": fb_[k], "unit": "Hz", "separation_sigma": sep})
        # Q of the measured flap modes if Q was not measured
        if not len(self.q_idx):
            fl = d.family == "flap"
            if fl.any():
                _, qa = self.predict(sa); _, qb = self.predict(sb)
                for k in np.nonzero(fl)[0][:3]:
                    if np.isfinite(qa[k]) or np.isfinite(qb[k]):
                        a, b = qa[k], qb[k]
                        sep = abs(math.log(min(a, 1e12)) - math.log(min(b, 1e12))) / 0.05
                        out.append({"measure": f"Q of {self.group_labels[k]}", "a": a, "b": b, "unit": "1", "separation_sigma": sep})
        return sorted(out, key=lambda r: -r["separation_sigma"])

    def describe_data(self) -> dict[str, Any]:
        d = self.data
        return {"kind": "modal", "modes": self.n, "with_Q": int(len(self.q_idx)),
                "families": sorted(set(d.family.tolist())), "lengths": sorted(set(d.length.tolist())),
                "noise_stated": d.noise_stated}
