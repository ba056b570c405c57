"""A diagnose cause written the way a user adds one: this one file, nothing else.

Optical interference in a force curve: part of the laser light reflected by the sample reaches
the photodiode and interferes with the beam reflected by the lever, so the deflection signal
carries a fringe that repeats every half wavelength of sample travel, F_meas = F + A sin(4 pi z /
lambda + phi) (e.g. Jaschke and Butt, Rev. Sci. Instrum. 66 (1995) 1258). lambda = 670 nm (a
red AFM laser diode); A = 0 is the baseline (the cause nests it). (The catalog's own
``optical-interference`` fits the period and uses the tip-sample separation; this user's variant knows its
laser's wavelength and is keyed ``fringe-670nm``.)
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam

WAVELENGTH = 670e-9  # m


@CAUSES.register
class Fringe670(Cause):
    key = "fringe-670nm"
    kind = "force"
    title = "Optical interference fringe in the deflection signal"
    source = "F_meas = F + A sin(4 pi z / lambda + phi), lambda = 670 nm (Jaschke and Butt 1995)"
    description = "A sinusoidal fringe of period lambda/2 in the sample travel, added to the measured force."
    needs = "a ramp of a sizeable fraction of lambda/2"
    changes = ("detector",)
    params = (CauseParam("A_fringe", "N", -2e-8, 2e-8, 0.0, "fringe amplitude", starts=(2e-9, -2e-9)),
              CauseParam("phi_fringe", "rad", 0.0, 2 * math.pi, 0.0, "fringe phase at z = 0",
                         starts=(math.pi / 2, math.pi, 3 * math.pi / 2)))

    def effect(self, v, s):
        A, phi = v["A_fringe"], v["phi_fringe"]
        s.transforms.append(lambda problem, F: F + A * np.sin(4 * math.pi * problem.data.z / WAVELENGTH + phi))
