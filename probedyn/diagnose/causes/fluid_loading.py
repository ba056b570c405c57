"""Fluid loading: added mass and damping of a surrounding fluid (Sader's hydrodynamic function).

If the measurement declares its medium ([medium]), the baseline already carries that medium's
loading. Air and vacuum fix density and viscosity, and the cause means an *excess* hydrodynamic
load (a squeeze film near a surface, a meniscus, a denser gas): one factor on the declared load
(null 1). A declared liquid (density >= ``LIQUID_MIN_DENSITY``) is fitted with its density and viscosity, nulls
at the declared values: a liquid's viscosity is far less certain than a gas's (temperature, composition), and
the same factor on both is the excess load. In a declared vacuum the cause is a **residual gas**: air at a pressure p (null 0, at most
1.2 bar: a chamber is not pumped above the ambient pressure), its density ``rho_air p / p_atm``, its viscosity
air's (independent of the pressure in continuum flow), at the declared temperature (else room temperature), and
**rarefied**: where the mean free path is not small against the width (Knudsen number lambda / w above ~0.1: below
~10 mbar for levers wider than 20 um) the continuum load, whose damping does not vanish with the pressure, is scaled
by the free-molecular damping, proportional to it (:mod:`probedyn.diagnose.hydrodynamics`). A residual gas
damps each flapwise mode by about the same rate, so its Q grows with the frequency, where a lever's intrinsic loss
(thermoelastic, below the Zener frequency) lowers the higher modes' Q. Only an undeclared medium is fitted with its
density and viscosity.
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam
from probedyn.diagnose.hydrodynamics import MEDIA, ROOM_TEMPERATURE

P_ATM = 101325.0  # Pa: the pressure of MEDIA["air"]
#: a declared medium this dense is a liquid (a gas at 100 bar is ~120 kg/m^3; the lightest common liquids ~600)
LIQUID_MIN_DENSITY = 300.0


@CAUSES.register
class FluidLoading(Cause):
    key = "fluid-loading"
    gas_T = ROOM_TEMPERATURE  # a residual gas's temperature [K] (constrain: the declared one)
    kind = "modal"
    title = "Fluid loading (undeclared medium, or excess load on the declared one)"
    source = ("J. E. Sader, J. Appl. Phys. 84, 64 (1998), eqs 17, 20, 21, 25; lateral: Stokes's second problem "
              "(Landau & Lifshitz, Fluid Mechanics, section 24); a rarefied gas: free-molecular momentum transfer "
              "(W. E. Christian, Vacuum 16, 175 (1966), with diffuse re-emission), Cunningham's slip form between")
    description = ("Added mass (pi/4) rho_f w^2 Gamma_r per length and damping from Gamma_i on the flapwise modes: "
                   "lowers them by 1/sqrt(1 + (pi rho_f w / 4 rho t) Gamma_r) and sets their Q; the lateral modes "
                   "drag the fluid by their faces' Stokes layers (added mass rho_f delta / 2 per face area); torsion "
                   "is not loaded.")
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
            # declared vacuum: the fluid a vacuum can hold is a residual gas (air at pressure p, rarefied)
            c = FluidLoading((CauseParam("p_gas", "Pa", 0.0, 1.2 * P_ATM, 0.0, "residual gas (air) pressure",
                                         starts=(1e3, P_ATM)),),
                             note="vacuum declared: the cause is a residual gas, air at pressure p (rarefied below "
                                  "~10 mbar: free-molecular damping)")
            T = getattr(getattr(problem, "data", None), "temperature", None)
            c.gas_T = float(T) if T else ROOM_TEMPERATURE
            return c
        if med[0] >= LIQUID_MIN_DENSITY:
            # declared liquid: its density and viscosity, nulls at the declared values (a liquid's viscosity is
            # its least certain property: water's falls 2 % per kelvin, a 15 % glycerol solution's is 1.6 x
            # water's at 3.7 % more density -- a load factor on both cannot follow that; the same factor on both
            # keeps the Reynolds number and scales the load, so the excess load is inside this pair)
            rho, eta = med
            return FluidLoading((CauseParam("rho_f", "kg/m^3", 0.0, 3000.0, rho, "liquid density",
                                            starts=(rho,)),
                                 CauseParam("eta_f", "Pa s", 1e-6, 0.1, eta, "liquid viscosity", scale="log",
                                            starts=(2.0 * eta, 0.5 * eta))),
                                note=f"liquid declared ({problem.medium_name}): its density and viscosity, "
                                     "nulls at the declared values")
        c = FluidLoading((CauseParam("load_factor", "1", 0.0, 30.0, 1.0,
                                     "hydrodynamic load / that of the declared medium", starts=(3.0,)),),
                         note=f"medium declared ({problem.medium_name}): the cause is an excess load on it")
        return c

    def effect(self, v, s):
        if "load_factor" in v and len(self.params) == 1:
            s.fluid_factor *= v["load_factor"]
        elif "p_gas" in v and len(self.params) == 1:
            rho_air, eta_air = MEDIA["air"]
            s.medium = (rho_air * v["p_gas"] / P_ATM, eta_air)
            s.gas = (v["p_gas"], self.gas_T)
        else:
            s.medium = (v["rho_f"], v["eta_f"])

    def derived(self, v, problem):
        return {}
