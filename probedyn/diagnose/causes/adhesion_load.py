"""Friction proportional to the total load N + N_adh (adhesion or a capillary meniscus).

Parametrised so that the corrugation at the mean load N_ref stays the baseline's ``u0 N_ref``:
``U0(N) = u0 N_ref (N + N_adh) / (N_ref + N_adh)``. N_adh then changes only how the corrugation
follows the load, not its level; referred to zero load instead, every change of N_adh changes the
stick-slip pattern of every scan and the fit from the null value stalls (the pattern is not a
smooth function of the corrugation once slips skip wells).

On a mesoscale friction loop (:mod:`probedyn.diagnose.friction_loop`, whose baseline carries the FFM's
friction at the reference load to each scan's load by Amontons' law) the same parameter is Derjaguin's:
``F_k(N) = F_k(N_ref) (N + N_adh) / (N_ref + N_adh)``, the half loop's intercept on the load axis at
``-N_adh``; offered there only for scans at two or more loads (one load cannot separate the intercept from
the slope).

The stick-slip baseline has two laws of the corrugation against the load (:data:`probedyn.diagnose.friction.LOAD_LAWS`,
engine ``_baseline_law``): proportional to it (the registry's) and independent of it (the plain PT model). The cause
extends the law the baseline took: on the proportional one by N_adh as above (null 0); on the load-independent one by
the share ``s`` of the load the corrugation follows, ``U0(N) = u0 (N_ref + s (N - N_ref))`` (null 0; ``s = 1`` the
proportional law), the same linear law with the adhesion load ``N_adh = N_ref (1/s - 1)``, reported derived. A
corrugation that ignores the load is N_adh -> infinity, a limit no finite adhesion load reaches: on the proportional
baseline alone such a record read as an adhesion load many times its loads (blind friction set 2, docs/diagnose.md
9.53).
"""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class AdhesionLoad(Cause):
    key = "adhesion-load"
    kind = "friction"
    title = "Load dependence through adhesion (or a capillary meniscus)"
    source = "Derjaguin's law, section 2.2.4 (adhesion-friction coupling); registry load_params (U0 ~ load)"
    description = "The corrugation follows the total load N + N_adh instead of N: friction is finite at zero load."
    needs = "scans at two or more normal loads"
    changes = ("adhesion",)
    regimes = ("stick-slip", "loop")
    params = (CauseParam("n_adh", "N", -1.0, 1.0, 0.0, "adhesion load"),)

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        if getattr(problem, "regime", "") == "loop" and not np.ptp(problem.loads) > 0:
            return None
        lo, hi = float(problem.loads.min()), float(problem.loads.max())
        n_ref = float(problem.N_mean)
        if getattr(problem, "load_share", 1.0) == 0.0:
            # on a baseline whose corrugation does not follow the load, the cause is the share of the load it follows:
            # U0 = u0 (N_ref + s (N - N_ref)), null s = 0 (the baseline), s = 1 the registry's law, and between the
            # adhesion intercept N_ref (1/s - 1) (up to the least adhesion load of the proportional baseline's range,
            # -0.9 N_min; a corrugation that falls as the load rises, s < 0, is no adhesion intercept)
            c = AdhesionLoad((CauseParam("load_share", "1", 0.0, n_ref / (n_ref - 0.9 * lo), 0.0,
                                         "share of the load the corrugation follows (d ln U0 / d ln N at N_ref)",
                                         starts=(0.5, 1.0)),))
        else:
            c = AdhesionLoad((CauseParam("n_adh", "N", -0.9 * lo, 20.0 * hi, 0.0, "adhesion load",
                                         starts=(0.5 * hi, 3.0 * hi)),))
        c.N_ref = n_ref
        return c

    def data_starts(self, problem, ref: dict, ref_causes: tuple = ()) -> list[dict]:
        """From the recorded loop: the corrugation U0 of each scan (from the ratio of the slip drop to
        the peak force, :func:`probedyn.diagnose.friction.loop_estimate`) against its load,
        ``U0 = u0 (N + N_adh)``: a straight line whose intercept over slope is N_adh."""
        N = problem.loads
        if np.ptp(N) <= 0:
            return []
        if getattr(problem, "regime", "") == "loop":  # the half loops of the scans against their loads
            hl = []
            for i, s in enumerate(problem.data.scans):
                fwd = s.direction > 0
                hl.append(0.5 * (s.force[fwd].mean() - s.force[~fwd].mean()) if fwd.any() and (~fwd).any() else np.nan)
            ok = np.isfinite(hl)
            if ok.sum() < 2 or np.ptp(N[ok]) <= 0:
                return []
            B, A = np.polyfit(N[ok], np.asarray(hl)[ok], 1)
            return [{"n_adh": float(A / B)}] if B > 0 else []
        L = problem.loop
        B, A = np.polyfit(N, L.U0, 1)
        if not B > 0:
            return []
        n_ref = getattr(self, "N_ref", None) or float(np.mean(N))
        if "load_share" in self.names:  # U0 = A + B N = u0 (N_ref + s (N - N_ref))
            return [{"load_share": float(B * n_ref / (A + B * n_ref)), "u0": float((A + B * n_ref) / n_ref)}]
        return [{"n_adh": float(A / B), "u0": float((A + B * n_ref) / n_ref)}]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    def effect(self, v, s):
        if "load_share" in v and "load_share" in self.names:
            s.load_share += v["load_share"]
            return
        n_ref = getattr(self, "N_ref", None)
        if n_ref and getattr(s, "corrugation_follows_load", True):
            s.u0 *= n_ref / (n_ref + v["n_adh"])
        s.n_adh += v["n_adh"]

    def derived(self, v, problem):
        """The corrugation per unit total load, and how much the friction level (stick-slip: the corrugation;
        loops: the kinetic friction) changes from the lowest load to the highest, with this adhesion load and
        under the baseline's law (proportional to the load): an adhesion load far above the loads says the
        level hardly follows the load at all (a fixed corrugation is the limit N_adh -> infinity, docs 9.52)."""
        n_ref = getattr(self, "N_ref", None) or 1.0
        loads = getattr(problem, "loads", None)
        if "load_share" in self.names:  # on the load-independent baseline: the share s, n_adh = N_ref (1/s - 1)
            sh = float(v["load_share"])
            out = {"u0_per_unit_total_load_J_per_N": v["u0"] * sh, "reference_load_N": n_ref,
                   "n_adh": n_ref * (1.0 / sh - 1.0) if sh > 0 else None}
            if loads is not None and len(loads):
                lo, hi = float(np.min(loads)), float(np.max(loads))
                out["level_ratio_highest_to_lowest_load"] = (n_ref + sh * (hi - n_ref)) / (n_ref + sh * (lo - n_ref))
                out["baseline_level_ratio_highest_to_lowest_load"] = 1.0
            return out
        out = {"reference_load_N": n_ref}
        if "u0" in v:  # (a loop at one speed fits the friction level, not the corrugation)
            out["u0_per_unit_total_load_J_per_N"] = v["u0"] * n_ref / (n_ref + v["n_adh"])
        if loads is not None and len(loads) and float(np.min(loads)) > 0:
            lo, hi = float(np.min(loads)), float(np.max(loads))
            out["level_ratio_highest_to_lowest_load"] = (hi + v["n_adh"]) / (lo + v["n_adh"])
            out["baseline_level_ratio_highest_to_lowest_load"] = hi / lo
        return out
