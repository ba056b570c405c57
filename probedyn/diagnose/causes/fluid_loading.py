"""Fluid loading: added mass and damping of a surrounding fluid (Sader's hydrodynamic function).

If the measurement declares its medium ([medium]), the baseline already carries that medium's
loading, air and vacuum fix density and viscosity, and the cause means an *excess* hydrodynamic
load (a squeeze film near a surface, a meniscus, a denser gas): one factor on the declared load
(null 1). In a declared vacuum there is no fluid and the cause does not apply. Only an
undeclared medium is fitted with its density and viscosity.
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class FluidLoading(Cause):
    key = "fluid-loading"
    kind = "modal"
    title = "Fluid loading (undeclared medium, or excess load on the declared one)"
    source = "J. E. Sader, J. Appl. Phys. 84, 64 (1998), eqs 17, 20, 21, 25"
    description = ("Added mass (pi/4) rho_f w^2 Gamma_r per length and damping from Gamma_i on the flapwise modes: "
                   "lowers them by 1/sqrt(1 + (pi rho_f w / 4 rho t) Gamma_r) and sets their Q.")
    needs = "Q values, or several flapwise modes plus another family (Gamma depends on frequency)"
    changes = ("medium",)
    params = (
        CauseParam("rho_f", "kg/m^3", 0.0, 3000.0, 0.0, "fluid density", starts=(1.2, 1000.0)),
        CauseParam("eta_f", "Pa s", 1e-6, 0.1, 1.8e-5, "fluid viscosity", scale="log", starts=(1e-3,)),
    )

    def constrain(self, problem):
        if not problem.supports("fluid"):
            return None
        med = problem.declared_medium
        if med is None:
            return self
        if med[0] == 0.0:
            return None  # declared vacuum: no fluid
        c = FluidLoading((CauseParam("load_factor", "1", 0.0, 30.0, 1.0,
                                     "hydrodynamic load / that of the declared medium", starts=(3.0,)),),
                         note=f"medium declared ({problem.medium_name}): the cause is an excess load on it")
        return c

    def effect(self, v, s):
        if "load_factor" in v and len(self.params) == 1:
            s.fluid_factor *= v["load_factor"]
        else:
            s.medium = (v["rho_f"], v["eta_f"])

    def derived(self, v, problem):
        return {}
