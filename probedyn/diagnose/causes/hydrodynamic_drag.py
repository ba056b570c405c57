"""Hydrodynamic drag on the lever during the ramp (force curves in liquid, or fast ramps in air).

The fluid opposes the lever's motion with a force proportional to its velocity; the optical lever
records it as a deflection. Far from the sample the approach (moving towards it) reads a repulsive
offset and the retract an attractive one, so the two non-contact baselines split by ``b (v_approach +
v_retract)``: at the same z, whatever the time each segment took -- a split that follows the ramp speed
(the signature a drift in time or a tilt cannot make). Near the surface the fluid is squeezed and the
drag grows; Alcaraz et al. (2002, Langmuir 18, 716) measured the drag coefficient of rectangular and
V-shaped levers against the tip-sample distance ``s`` and found

    b(s) = 6 pi eta a_eff^2 / (s + h_eff),

the Stokes drag of a sphere of effective radius ``a_eff`` at an effective height ``h_eff`` (the tip
height plus a fraction of the lever's width). Fitted here as ``b(s) = b_drag h_eff / (max(s, 0) + h_eff)``
with ``b_drag = b(0)``, the coefficient at contact, and ``h_eff``; ``h_eff`` much larger than the ramp makes
the drag constant (its upper bound, 1 m, is that limit; its lower, 1 um, the shortest tip). The drag
at the far baseline is bounded by the split the far baselines show (twice it plus five standard errors):
the drag cannot grow to absorb a misfit of the contact branches. The velocity is the piezo's (the lever's base;
:attr:`ForceCurveProblem.velocity`, from the record's times), also in contact (Alcaraz's and
Janovjak et al.'s 2004 correction). Nested: ``b_drag = 0`` is the baseline. Not offered without a
``time_s`` column (no velocity) or in a declared vacuum (no fluid).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

#: the drag law's smallest effective height [m]: it includes the tip height (Alcaraz et al. 2002: 1.6-7 um)
H_EFF_MIN = 1e-6


@CAUSES.register
class HydrodynamicDrag(Cause):
    key = "hydrodynamic-drag"
    kind = "force"
    title = "Hydrodynamic drag on the lever (velocity-dependent baseline; Alcaraz et al. 2002)"
    source = ("Alcaraz, Buscemi, Puig-de-Morales, Colchero, Baro, Navajas (2002) Langmuir 18, 716: "
              "b(s) = 6 pi eta a_eff^2 / (s + h_eff); measurement: F_meas = F + b(s) dz/dt")
    description = ("Approach and retract baselines split in proportion to the ramp speed (repulsive on the approach, "
                   "attractive on the retract), growing towards the surface.")
    needs = "the time of every sample (time_s column) and a ramp fast enough that b v exceeds the noise"
    changes = ("drag",)
    params = (CauseParam("b_drag", "N s/m", 0.0, 1.0, 0.0, "drag coefficient at contact b(0)"),
              CauseParam("h_eff", "m", 1e-6, 1.0, 1.0, "effective height of the drag law", scale="log"))
    #: why it is not offered on a record without times (the problem reports it)
    requires = "a time_s column (the drag needs the piezo velocity) and a non-contact baseline on both segments"

    def constrain(self, problem):
        if super().constrain(problem) is None or getattr(problem, "velocity", None) is None:
            return None
        med = getattr(problem, "declared_medium", None)
        if med is not None and med[0] == 0.0:
            return None  # a declared vacuum: no fluid to drag the lever
        far = problem.far
        if far["rms"] is None:
            return None
        d = problem.data
        vm = np.abs(problem.velocity)
        v_sum = float(np.median(vm[d.segment == 0]) + np.median(vm[d.segment == 1]))
        # the drag is read off the far baselines' split b (v_a + v_r) (same z, opposite velocities): b at the
        # far baseline is bounded by twice the measured split plus five of its standard errors; at contact
        # it grows by (s + h_eff) / h_eff, s up to the baseline's length, with h_eff at least 1 um (the tip
        # height is part of it: Alcaraz et al. found 1.6-7 um)
        b_far = 2.0 * (abs(far["split"]) + 5.0 * far["split_se"]) / max(v_sum, 1e-300)
        b_hi = b_far * (1.0 + far["length"] / H_EFF_MIN)
        c = HydrodynamicDrag((CauseParam("b_drag", "N s/m", 0.0, b_hi, 0.0, "drag coefficient at contact b(0)",
                                         starts=(min(abs(far["split"]) / max(v_sum, 1e-300), b_hi),)),
                              CauseParam("h_eff", "m", H_EFF_MIN, 1.0, 1.0, "effective height of the drag law",
                                         scale="log", starts=(10e-6,))))
        return c

    def effect(self, v, s):
        s.drag_b = v["b_drag"]
        s.drag_h = v["h_eff"]

    def derived(self, v, problem):
        out = {}
        med = getattr(problem, "declared_medium", None)
        if med is not None and med[1] > 0 and v["h_eff"] < 0.99:
            out["a_eff_m"] = math.sqrt(v["b_drag"] * v["h_eff"] / (6.0 * math.pi * med[1]))  # Alcaraz's effective radius
        return out
