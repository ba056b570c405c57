"""The optical lever's deflection sensitivity (InvOLS, m/V) is miscalibrated.

The photodiode records a voltage; the deflection is that voltage times the sensitivity ``s`` [m/V]
(the inverse optical-lever sensitivity, InvOLS), usually taken from the constant-compliance slope of a
curve on a hard sample, and the force is ``k`` times the deflection. With a declared sensitivity ``g``
times the true one, every recorded deflection -- and force -- is ``g`` times the true value, while the
lever's equilibrium is set by the true deflection:

    F_rec = g F,    delta = z - z_c - F / k = z - z_c - F_rec / (g k).

In the recorded force the contact law is ``g P`` (absorbed by ``E*`` and ``W`` where they are fitted:
Hertz ``g E*``, adhesion ``g W``), but the lever's compliance is ``1 / (g k)`` instead of the declared
``1 / k``: the signature is the contact branch's slope ``dF_rec / dz = g k k_c / (k_c + k)`` (``k_c`` the
contact stiffness), which exceeds ``k`` -- impossible for any elastic contact behind a lever of stiffness
``k`` -- when ``g > 1`` on a hard sample, and the snap-in and pull-off folds (``P' = -k`` in true force).
On a soft sample (``k_c << k``) the compliance is invisible and a miscalibration cannot be told from the
modulus (or, with the modulus declared, from the tip radius, ``sqrt R``).

A spring-constant error alone is no cause here: with the sensitivity right, ``F_rec = h F`` at the true
deflection ``F_rec / k_declared``, i.e. the law ``h P`` behind the declared lever -- exactly a modulus
``h E*`` and adhesion ``h W``, or with the modulus declared a tip radius ``h^2 R`` with adhesion ``W / h``
(Hertz, DMT, JKR and Maugis-Dugdale alike: their scales ``pi W R`` and ``(pi^2 W^2 R / K^2)^(1/3)``).
A single force curve cannot name it (``tests/test_diagnose_forcecurve.py`` checks the equivalence).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class DeflectionSensitivity(Cause):
    key = "deflection-sensitivity"
    kind = "force"
    title = "Deflection sensitivity (InvOLS) miscalibrated"
    source = ("measurement chain: F_rec = g F with the lever at delta = z - z_c - F / k (optical-lever "
              "sensitivity; Butt, Cappella & Kappl, Surf. Sci. Rep. 59 (2005) 1)")
    description = ("The recorded deflection and force are g times the true ones (declared / true sensitivity): "
                   "the contact branch is steeper or shallower than a lever of the declared stiffness allows.")
    needs = "a contact branch whose stiffness is not far below the lever's (a hard sample), or the folds"
    changes = ("sensitivity",)
    params = (CauseParam("s_ratio", "1", 0.5, 2.0, 1.0, "declared / true deflection sensitivity", scale="log",
                         starts=(0.8, 1.25)),)

    def data_starts(self, problem, ref: dict, mask=None) -> list[dict]:
        """From the approach's contact (its points past the fitted contact point): the deepest fifth's recorded
        slope ``S = g k k_c / (k + k_c)`` bounds ``g >= S / k`` (equal on a rigid sample); for that ``g`` and the
        two multi-start values, the true force ``F = (F_rec - baseline) / g`` at the lever's penetration
        ``delta = z - z_c - F / k`` gives the modulus of the Hertz law through them (least squares of
        ``F = (4/3) E* sqrt(R) delta^1.5``), where the modulus is fitted. The baseline's own modulus is no start:
        a branch steeper than the lever (``g > 1`` on a hard sample) drove it towards the rigid-sample limit,
        where its gradient vanishes (calibration seed 2321 stopped there, 50 sigma from the true g)."""
        d = problem.data
        m = (d.segment == 0) & (d.z > ref["z_c"])
        if mask is not None:
            m &= np.asarray(mask, bool)
        idx = np.flatnonzero(m)
        if len(idx) < 10:
            return []
        z = d.z[idx]
        Fx = d.force[idx] - ref.get("b0", 0.0) - ref.get("b1", 0.0) * z
        deep = np.argsort(z)[-max(5, len(idx) // 5):]
        S = float(np.polyfit(z[deep], Fx[deep], 1)[0])
        p = self.params[0]
        Ep = next((q for q in problem.base_params if q.name == "E_star"), None)
        R = d.tip_radius * ref.get("r_ratio", 1.0)
        out = []
        for g in dict.fromkeys([min(max(S / d.k, p.lo), p.hi), *p.starts]):
            st = {"s_ratio": g}
            if Ep is not None and "E_star" in ref:
                F = Fx / g
                dl = z - ref["z_c"] - F / d.k
                ok = (dl > 0) & (F > 0)
                if ok.sum() >= 5:
                    x = dl[ok] ** 1.5
                    c = float(np.sum(F[ok] * x) / np.sum(x * x))
                    st["E_star"] = min(max(c / (4.0 / 3.0 * math.sqrt(R)), Ep.lo), Ep.hi)
            out.append(st)
        return out

    def effect(self, v, s):
        s.gain *= v["s_ratio"]

    def derived(self, v, problem):
        sens = problem.data.sensitivity
        return {"sensitivity_m_per_V": sens / v["s_ratio"]} if sens else {}
