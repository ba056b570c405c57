"""The sample is viscoelastic: it relaxes during the indentation (cells, gels, polymers).

The contact is the linear viscoelastic half-space of :mod:`probedyn.schemes.contact.viscoelastic`
(Lee & Radok 1960 while the contact grows, Ting 1966 while it shrinks) with the relaxation modulus
of the standard linear solid ``E(t) = E_inf (1 + s e^{-t/tau})``: the baseline's fitted reduced modulus
``E*`` plays the **relaxed** modulus ``E_inf`` (what a slow indentation measures), ``s = E_0 / E_inf - 1``
the relaxation strength (instantaneous modulus ``E_0 = (1 + s) E_inf``), tau the relaxation time.
Nested: ``s = 0`` is exactly the baseline's elastic Hertz contact (tau then has no effect). Its
signature: approach and retract of different shape at the same piezo position (the retract force
lower at equal indentation, contact lost before the approach's contact point), and a hysteresis that
depends on the ramp speed. The law needs the time of every sample: the cause is offered only when
the record has a ``time_s`` column (and says so otherwise). Sphere only (no adhesion, no cone).
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

#: the relaxation strength's bound: E_0 up to 50 E_inf (hydrogels and cells relax by up to ~10x)
STRENGTH_MAX = 50.0


@CAUSES.register
class ViscoelasticSample(Cause):
    key = "viscoelastic-sample"
    kind = "force"
    title = "Viscoelastic sample (standard linear solid; Lee-Radok / Ting contact)"
    source = ("Lee & Radok (1960) and Ting (1966) for a sphere on a linear viscoelastic half-space; standard linear "
              "solid E(t) = E_inf (1 + s exp(-t/tau)); contact registry module 'viscoelastic'")
    description = ("Approach and retract contact branches of different shape (the retract force below the approach's "
                   "at equal indentation, contact lost early) from the relaxation of the sample during the ramp.")
    needs = "the time of every sample (time_s column) and a ramp time comparable with the relaxation time"
    changes = ("sample_viscoelasticity",)
    params = (CauseParam("strength", "1", 0.0, STRENGTH_MAX, 0.0, "relaxation strength E_0 / E_inf - 1"),
              CauseParam("tau", "s", 1e-6, 1e3, 1e-2, "relaxation time", scale="log"))
    #: why it is not offered on a record without times (the problem reports it)
    requires = "a time_s column (the relaxation needs the time of every sample)"

    def constrain(self, problem):
        if super().constrain(problem) is None or getattr(problem.data, "time", None) is None:
            return None
        import numpy as np

        t = problem.data.time
        dt = float(np.median(np.diff(t)))
        T = float(np.ptp(t))
        # tau resolvable from the record: from a tenth of the sampling interval (faster: the relaxed
        # modulus at every sample) to 100 x the record (slower: the instantaneous modulus throughout)
        lo, hi = 0.1 * dt, 100.0 * T
        c = ViscoelasticSample((self.params[0], CauseParam("tau", "s", lo, hi, min(max(0.1 * T, lo), hi),
                                                           "relaxation time", scale="log")))
        c._T = T
        return c

    def start_sets(self):
        T = getattr(self, "_T", 1.0)
        p = self.params[1]
        cl = lambda x: min(max(x, p.lo), p.hi)  # noqa: E731
        return [{"strength": 1.0, "tau": cl(0.1 * T)}, {"strength": 1.0, "tau": cl(0.01 * T)},
                {"strength": 3.0, "tau": cl(T)}]

    def effect(self, v, s):
        s.visco_strength = v["strength"]
        s.visco_tau = v["tau"]

    def derived(self, v, problem):
        return {"E_instantaneous_over_relaxed": 1.0 + v["strength"]}
