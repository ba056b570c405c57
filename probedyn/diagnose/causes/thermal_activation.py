"""Thermally activated slips: the tip crosses the barrier before the athermal instability.

The FFM baseline is athermal: the tip slips where the well disappears. At a finite temperature
it slips earlier, where the Kramers rate ``f0 exp(-dE / k_B T)`` integrated over the time spent
near the instability reaches one, the earlier the slower the scan: friction then grows about
logarithmically with the speed (Gnecco et al., PRL 84, 1172 (2000); Sang et al., PRL 87, 174301
(2001)). Effect on the model: the median activated slip point of every well (from the quasi-static
barrier of the PT potential with the lever spring, see :func:`probedyn.diagnose.friction.thermal_slip_advance`),
at which the FFM integration places the tip over the saddle and lets its dynamics complete the slip. Between
slips, at a declared temperature, every model's force is the Boltzmann mean over the tip's well, below the
quasi-static branch towards the slip (:func:`probedyn.diagnose.friction.thermal_mean_shift`, a declared condition of
the baseline, with or without this term; docs/diagnose.md 9.55).

The temperature is the declared one ([medium] temperature; 295 K if none is declared, noted);
the fitted parameter is the attempt frequency (log10 of f0/Hz; 0 = 1 Hz, no activation at
scan speeds: the null value).

A *declared* temperature implies the activation: every Langevin tip at a finite temperature slips
early, at 1 K still by more than interval means resolve (blind friction nulls at 0.3-2 K: chi^2 of the
athermal model 1.2-8 x n). The effect is then a term of the baseline, carried where the data show it
(``declared``, engine ``_declared_terms``), with the attempt frequency a baseline parameter, and no
cause to discover; the cause proper is a record whose temperature is not declared.
"""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


#: attempt frequencies [log10 Hz] of the starts relative to the reference model (:meth:`ThermalActivation.reference_starts`)
REFERENCE_F0 = (5.0, 7.0, 9.0)
#: factors of an adhesion load's start over which the activation's ridge is walked where the load is free
#: (:meth:`ThermalActivation.ridge_starts`), and the number of the best (by the peaks' misfit) kept
ADHESION_GRID = np.geomspace(0.25, 2.0, 13)
RIDGE_JOINT_KEEP = 6
#: the profile sweep's step in log10 f0 (engine Fitter.swept): an activated slip moves by about a sample interval
#: per 0.1-0.3 decade of f0 (blind f07: basins at 3.5, 3.8 and 4.2), so a coarser step can pass a basin
SWEEP_DEX = 0.1


@CAUSES.register
class ThermalActivation(Cause):
    key = "thermal-activation"
    kind = "friction"
    title = "Thermally activated slips (friction ~ ln v)"
    source = "Kramers rate with the quasi-static PT barrier; Gnecco et al. 2000, Sang et al. 2001; source 2.1.4"
    description = ("Slips happen before the athermal instability, the earlier the slower the scan: lower peak "
                   "forces and a friction that grows with ln(speed).")
    needs = "scans at two or more speeds (better: over a decade)"
    changes = ("temperature",)
    params = (CauseParam("log10_f0", "log10(Hz)", 0.0, 13.0, 0.0, "attempt frequency f0 (log10 of f0 / 1 Hz)",
                         starts=(5.0, 8.0), sweep=SWEEP_DEX),)

    def constrain(self, problem):
        T = problem.temperature
        if T is not None and T <= 0:
            return None
        note = "" if T is not None else "no temperature declared: 295 K assumed"
        c = ThermalActivation(note=note)
        c.T = T if T is not None else 295.0
        c.declared = T is not None
        return c

    def start_sets_from(self, ref: dict[str, float]) -> list[dict[str, float]]:
        """Starts with activation on AND a larger corrugation: an athermal fit of activated data
        lowers u0 to bring the slips forward (by 40 % on a 300 K truth), so activation started at
        the athermal fit's u0 only moves further from the data (the stick-slip pattern is not a
        smooth function of u0 and f0 far from the optimum). Corrugation factors 1.3-2 span a peak
        force lowered by activation by 25-50 %; f0 = 1e5 Hz is the order of the lever-tip
        attempt frequency, 1e8 Hz a stiff contact's."""
        if "u0" not in ref:
            return [{"log10_f0": 5.0}, {"log10_f0": 8.0}]
        return [{"log10_f0": lf, "u0": ref["u0"] * fac} for lf, fac in ((5.0, 1.6), (5.0, 1.3), (8.0, 1.6), (5.0, 2.0))]

    def data_starts(self, problem, ref: dict) -> list[dict]:
        """The two best starts of :meth:`_peak_ridge` by the recorded peaks' misfit, and the reference's own
        corrugation raised by the peak lowering of each of :data:`REFERENCE_F0` (:meth:`reference_starts`)."""
        return ([{"log10_f0": lf, "u0": u0} for _, lf, u0 in sorted(self._peak_ridge(problem, ref))[:2]]
                + self.reference_starts(problem, ref))

    def reference_starts(self, problem, ref: dict) -> list[dict]:
        """Starts relative to the model being extended: at attempt frequency f0 the median activated slip of the
        slowest scan comes at a peak force lower than the athermal instability's by the ratio ``phi`` (the
        quasi-static barrier, :func:`probedyn.diagnose.friction.thermal_hazard`); the reference already fits the
        peaks athermally, so the activated model starts at its corrugation over ``phi``. At 300 K ``phi`` is
        0.45-0.8, the factors the declared starts guess; on a cold record (0.5 K) it is 1. The
        recorded peaks' ridge (:meth:`_peak_ridge`) misses such a record when the reference carries a
        calibration factor: blind f24 (0.5 K, g = 0.9) had no start near its activation (log10 f0 6.1, chi^2
        2027 -> 1479 on 1440 samples), and its slips' 0.3 pm scatter stood at 6-8 sigma in the interval means
        that hold them."""
        import math

        from probedyn.diagnose.friction import _barrier_table, thermal_hazard
        if "u0" not in ref:
            return []
        T = getattr(self, "T", 295.0)
        a = float(ref.get("a", problem.a_slip))
        Neff = _effective_loads(problem, ref)
        i0 = int(np.argmin(problem.speeds / np.maximum(Neff, 1e-30)))
        U0 = float(ref["u0"]) * float(Neff[i0])
        tab = _barrier_table(U0, a, problem.data.k_x, 200)
        if tab is None:
            return []
        X, dE, _, _, xm = tab
        Fb = 2 * math.pi / a * U0 * np.sin(2 * math.pi / a * xm)
        top = float(np.max(Fb))  # the athermal peak (the branch's force passes its maximum just before the instability)
        out = []
        for lf in REFERENCE_F0:
            H = thermal_hazard(tab, float(problem.speeds[i0]), T, 10.0**lf)
            peak = top if H[-1] < math.log(2.0) else min(float(np.max(Fb[H <= math.log(2.0)])), top)
            if peak > 0 and top > 0:
                out.append({"log10_f0": lf, "u0": float(ref["u0"]) * top / peak})
        return out

    def ridge_starts(self, problem, ref: dict) -> list[dict]:
        """Every whole decade of the attempt frequency on the ridge of :meth:`_peak_ridge` (the corrugation that
        gives the slowest scan's recorded peak at that frequency), for the problem to rank by the whole model's
        chi-square: f0 and u0 trade along that ridge, and the peaks alone, read quasi-statically, may rank a
        wrong stretch of it first (a blind generator's 300 K record, session 30: the best two at 10^9.5-10^10 Hz,
        u0 16 % high, where the fit from them stalled; the truth near 10^5.5 Hz, chi^2 879 against 2566). Best first
        by the peaks' misfit."""
        if "load_share" in ref:  # the adhesion cause on the load-independent baseline: its share s, N_adh = N_ref (1/s - 1)
            return self._share_ridge(problem, ref)
        n0 = float(ref.get("n_adh", 0.0))
        if "n_adh" not in ref or not n0 > 0:
            return [{"log10_f0": lf, "u0": u0} for _, lf, u0 in sorted(self._peak_ridge(problem, ref))
                    if float(lf).is_integer()]
        # a model whose adhesion load is free (an adhesion cause beside the activation): the scans' peaks at two
        # loads and two speeds fix the load and the attempt frequency together (activation lowers the slow scans'
        # peaks, adhesion the low load's share), so the ridge is also walked over the load, about the start's:
        # own seed 2002 at a declared 300 K, whose loop read 28 nN for its 13.5 nN (the activated peaks read
        # athermally), fitted from there to 6.3 nN with the attempt frequency 1.6 decades low (chi^2 19 037; from
        # 13.5 nN and 10^5.5 Hz: 13.24 nN, chi^2 2708 on 1731 dof)
        scored = sorted((sc, lf, u0, n) for n in n0 * ADHESION_GRID
                        for sc, lf, u0 in self._peak_ridge(problem, {**ref, "n_adh": float(n)}))
        return [{"log10_f0": lf, "u0": u0, "n_adh": n} for _, lf, u0, n in scored[:RIDGE_JOINT_KEEP]]

    def _share_ridge(self, problem, ref: dict) -> list[dict]:
        """:meth:`ridge_starts`' joint walk over the adhesion load where the adhesion cause is the share ``s`` of the
        load the corrugation follows (on the load-independent baseline, :mod:`.adhesion_load`): the same grid of
        adhesion loads about the start's, ``N_adh = N_ref (1/s - 1)``, as shares ``s = N_ref / (N_ref + N_adh)``
        (own seed 2002 at a declared 300 K, session 68: without the walk, 27 nN for 13.5). A share at or above 1 (no
        positive adhesion load) walks the shares themselves."""
        s0 = float(ref["load_share"])
        if not s0 > 0:
            return [{"log10_f0": lf, "u0": u0} for _, lf, u0 in sorted(self._peak_ridge(problem, ref))
                    if float(lf).is_integer()]
        n_ref = float(getattr(problem, "N_mean", np.mean(problem.loads)))
        shares = (n_ref / (n_ref + n_ref * (1.0 / s0 - 1.0) * ADHESION_GRID) if s0 < 1.0 else s0 * ADHESION_GRID)
        scored = sorted((sc, lf, u0, sh) for sh in shares
                        for sc, lf, u0 in self._peak_ridge(problem, {**ref, "load_share": float(sh)}))
        return [{"log10_f0": lf, "u0": u0, "load_share": sh} for _, lf, u0, sh in scored[:RIDGE_JOINT_KEEP]]

    def _peak_ridge(self, problem, ref: dict) -> list[tuple[float, float, float]]:
        """From the recorded loop: the peak force of every scan (half the trace-retrace difference
        of the peaks) against the quasi-static activated slip point. For each attempt frequency on
        a grid (1e2-1e13 Hz) the corrugation per unit load that gives the slowest scan's peak, then
        the misfit of all the scans' peaks (the other speed and load): the best two frequencies.
        Activation lowers the peak, the more the slower the scan; the athermal fit's corrugation is
        too low by the lowering (up to 40 %) and its slips misplaced, too far from this basin."""
        import math

        from probedyn.diagnose.friction import _barrier_table, thermal_hazard

        L = problem.loop
        d = problem.data
        T = getattr(self, "T", 295.0)
        a = float(ref.get("a", problem.a_slip))
        q = 2 * math.pi / a
        Neff = np.maximum(_effective_loads(problem, ref), 1e-30)
        i0 = int(np.argmin(problem.speeds / problem.loads))
        u_ath = float(L.U0[i0] / Neff[i0])
        ugrid = u_ath * np.geomspace(1.0, 4.0, 41)  # activation only lowers the peak
        # per scan and corrugation: the stick branch (support X, force) and its barrier to the next well
        tabs = []
        for N in Neff:
            row = []
            for u in ugrid:
                U0 = u * N
                tab = _barrier_table(U0, a, d.k_x, 200)
                if tab is None:
                    row.append(None)
                    continue
                X, dE, _, _, xm = tab
                row.append((X, dE, q * U0 * np.sin(q * xm)))
            tabs.append(row)

        def peak(i: int, j: int, f0: float) -> float:
            """Median activated peak force of scan i at corrugation ugrid[j]."""
            t = tabs[i][j]
            if t is None:
                return 0.0
            Fb = t[2]
            H = thermal_hazard(t, problem.speeds[i], T, f0)
            return float(Fb[-1] if H[-1] < math.log(2.0) else np.interp(math.log(2.0), H, Fb))

        scored = []
        for lf in np.arange(2.0, 13.01, 0.5):
            f0 = 10.0**lf
            P = np.array([[peak(i, j, f0) for j in range(len(ugrid))] for i in range(len(problem.loads))])
            p0 = P[i0]
            if not (p0[0] <= L.peak[i0] <= p0[-1]) or np.any(np.diff(p0) <= 0):
                continue
            lu = float(np.interp(L.peak[i0], p0, np.log(ugrid)))
            pred = np.array([np.interp(lu, np.log(ugrid), P[i]) for i in range(len(P))])
            scored.append((float(np.sum((pred / L.peak - 1.0) ** 2)), float(lf), math.exp(lu)))
        return scored

    def effect(self, v, s):
        s.thermal = (getattr(self, "T", 295.0), 10.0 ** v["log10_f0"])

    def derived(self, v, problem):
        return {"attempt_frequency_Hz": 10.0 ** v["log10_f0"], "temperature_K": getattr(self, "T", 295.0)}


def _effective_loads(problem, ref: dict) -> np.ndarray:
    """The load each scan's corrugation is proportional to under the problem's law, with the adhesion load or load
    share ``ref`` holds (:meth:`probedyn.diagnose.friction.FrictionProblem.effective_loads`)."""
    if hasattr(problem, "effective_loads"):
        return problem.effective_loads(ref)
    return problem.loads + float(ref.get("n_adh", 0.0))
