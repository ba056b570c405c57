"""Optical interference in the deflection signal (the laser light the sample reflects into the detector).

Part of the optical lever's laser passes the lever (or is transmitted through it) and reflects off the
sample; what reaches the photodiode interferes with the beam the lever reflects. The path difference is
twice the lever's height above the sample, so the recorded deflection carries a wave periodic in the
tip-sample separation ``s`` with period ``lambda / 2`` (``lambda / (2 cos theta)`` at incidence angle
theta): 320-340 nm for the red (635-670 nm) lasers, 390-430 nm for the 780-850 nm superluminescent
diodes most AFMs use. Far from the sample ``s`` follows the piezo, so the wave is periodic in z and the
same on approach and retract whatever their speeds; in contact ``s = -delta`` barely moves, so the wave
freezes (Jaschke & Butt 1995, Rev. Sci. Instrum. 66, 1258; the standard remedy is a sinusoidal baseline
correction, e.g. Sunday et al. 2011). Fitted as ``a_c cos(2 pi s / P) + a_s sin(2 pi s / P)`` (amplitude
and phase as two linear parameters), the period P bounded by the lasers' range, 250-700 nm. Nested:
``a_c = a_s = 0`` is the baseline (P is then not identifiable: reported so). Offered only when the
non-contact baseline is at least one shortest period long: over less, the wave is a smooth curve that trades
off against the contact branch and absorbs its misfit; for the same reason the amplitude is bounded by what
the far baseline shows (:meth:`ForceCurveProblem._far_baseline`: twice the RMS above the noise of its
residual from a line, plus five standard errors). Starting periods from a
least-squares periodogram of the far baseline of both segments (data-derived, three best peaks).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

#: the wave's period in the separation [m]: lambda / 2 of the AFM lasers (635-1310 nm at 0-15 deg incidence
#: would reach 680 nm; 250 nm leaves room below the shortest visible lasers' 320 nm)
PERIOD_RANGE = (250e-9, 700e-9)


@CAUSES.register
class OpticalInterference(Cause):
    key = "optical-interference"
    kind = "force"
    title = "Optical interference in the deflection signal (a wave periodic in the tip-sample separation)"
    source = ("Jaschke & Butt (1995) Rev. Sci. Instrum. 66, 1258; measurement: F_meas = F + a_c cos(2 pi s / P) "
              "+ a_s sin(2 pi s / P), s the tip-sample separation, P = lambda / 2")
    description = ("A sinusoidal wave in the non-contact baseline, periodic in z with a period of a few hundred nm, "
                   "identical on approach and retract, frozen in contact.")
    needs = "a non-contact baseline at least one period (250 nm) long, before the snap-in and the pull-off"
    changes = ("detector",)
    params = (CauseParam("a_c", "N", -1.0, 1.0, 0.0, "cosine amplitude"),
              CauseParam("a_s", "N", -1.0, 1.0, 0.0, "sine amplitude"),
              CauseParam("period", "m", PERIOD_RANGE[0], PERIOD_RANGE[1], 400e-9, "period in the separation (lambda / 2)"))

    #: why it is not offered on a record with a short non-contact baseline (the problem reports it)
    requires = "a non-contact baseline at least one period (250 nm) long"

    def constrain(self, problem):
        if super().constrain(problem) is None:
            return None
        # a wave is told from the contact law only by the non-contact baseline: over less than one period
        # it is a smooth curve that trades off against the contact branch (s = -delta there), and its
        # amplitude is then bounded by nothing but the force range
        far = problem.far
        if far["length"] < PERIOD_RANGE[0] or far["rms"] is None:
            return None
        # the wave is the same in and out of contact: its amplitude is what the far baseline shows (a line's
        # residual RMS of A / sqrt(2) above the noise), bounded at twice that plus five standard errors of a
        # quadrature fitted to the far points -- so it cannot grow to absorb a misfit of the contact branch
        sig = problem.sigma
        A = 2.0 * math.sqrt(2.0 * max(far["rms"] ** 2 - sig**2, 0.0)) + 5.0 * sig * math.sqrt(2.0 / far["n"])
        c = OpticalInterference((CauseParam("a_c", "N", -A, A, 0.0, "cosine amplitude"),
                                 CauseParam("a_s", "N", -A, A, 0.0, "sine amplitude"),
                                 self.params[2]))
        c._problem = problem
        return c

    def start_sets_from(self, ref_values):
        """Starts at the three best periods of a least-squares periodogram of the record's far baseline
        (both segments, the points the amplitude bound is taken from, ``problem.far``: before the contact
        point, the snap-in and the pull-off, where ``s ~ z_c - z`` with the reference fit's contact point),
        each with the periodogram's amplitudes; a line in z is fitted with each period (the baseline's offset
        and tilt)."""
        pr = getattr(self, "_problem", None)
        if pr is None:
            return [{"a_c": 0.0, "a_s": 0.0, "period": p} for p in (320e-9, 420e-9, 560e-9)]
        d = pr.data
        zc = float(ref_values.get("z_c", np.median(d.z)))
        far = pr.far["mask"]
        if far.sum() < 20:
            return []
        s = zc - d.z[far]
        y = d.force[far]
        y = y - np.polyval(np.polyfit(d.z[far], y, 1), d.z[far])
        span = float(np.ptp(s))
        # periods on a grid fine enough that the phase over the far baseline moves by < 1/8 cycle per step
        n = int(np.clip(8 * span * (1 / PERIOD_RANGE[0] - 1 / PERIOD_RANGE[1]), 24, 400))
        periods = 1.0 / np.linspace(1 / PERIOD_RANGE[1], 1 / PERIOD_RANGE[0], n)
        gain = np.empty(n)
        amps = np.empty((n, 2))
        for i, P in enumerate(periods):
            A = np.column_stack([np.cos(2 * math.pi * s / P), np.sin(2 * math.pi * s / P), np.ones_like(s), s])
            coef, *_ = np.linalg.lstsq(A, y, rcond=None)
            gain[i] = float(np.sum(y**2) - np.sum((y - A @ coef) ** 2))
            amps[i] = coef[:2]
        peaks = [i for i in range(n) if (i == 0 or gain[i] >= gain[i - 1]) and (i == n - 1 or gain[i] >= gain[i + 1])]
        peaks = sorted(peaks, key=lambda i: -gain[i])[:3]
        lim = self.params[0].hi
        return [{"a_c": float(np.clip(amps[i, 0], -lim, lim)), "a_s": float(np.clip(amps[i, 1], -lim, lim)),
                 "period": float(periods[i])} for i in peaks]

    def effect(self, v, s):
        s.optical = s.optical + ((v["a_c"], v["a_s"], v["period"]),)

    def derived(self, v, problem):
        return {"amplitude_N": math.hypot(v["a_c"], v["a_s"]), "laser_wavelength_m_at_normal_incidence": 2.0 * v["period"]}
