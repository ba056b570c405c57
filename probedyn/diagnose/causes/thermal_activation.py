"""Thermally activated slips: the tip crosses the barrier before the athermal instability.

The FFM baseline is athermal: the tip slips where the well disappears. At a finite temperature
it slips earlier, where the Kramers rate ``f0 exp(-dE / k_B T)`` integrated over the time spent
near the instability reaches one, the earlier the slower the scan: friction then grows about
logarithmically with the speed (Gnecco et al., PRL 84, 1172 (2000); Sang et al., PRL 87, 174301
(2001)). Effect on the model: the median activated slip point of every well (from the quasi-static
barrier of the PT potential with the lever spring, see :func:`probedyn.diagnose.friction.thermal_slip_advance`),
at which the FFM integration places the tip over the saddle and lets its dynamics complete the slip.

The temperature is the declared one ([medium] temperature; 295 K if none is declared, noted);
the fitted parameter is the attempt frequency (log10 of f0/Hz; 0 = 1 Hz, no activation at
scan speeds: the null value).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


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
                         starts=(5.0, 8.0)),)

    def constrain(self, problem):
        T = problem.temperature
        if T is not None and T <= 0:
            return None
        note = "" if T is not None else "no temperature declared: 295 K assumed"
        c = ThermalActivation(note=note)
        c.T = T if T is not None else 295.0
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

    def effect(self, v, s):
        s.thermal = (getattr(self, "T", 295.0), 10.0 ** v["log10_f0"])

    def derived(self, v, problem):
        return {"attempt_frequency_Hz": 10.0 ** v["log10_f0"], "temperature_K": getattr(self, "T", 295.0)}
