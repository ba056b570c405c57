"""The thermal line of one mode in a spectrum: a simple harmonic oscillator, or a mode loaded by a viscous fluid.

Both are parametrised alike, by the mode's resonance ``f0``, its quality factor ``Q`` and the low-frequency level
``A`` of its line, so that a fit reports the quantities the probe's model predicts:

* **SHO** (vacuum, a gas; :func:`sho_psd`): ``S(f) = A f0^4 / ((f0^2 - f^2)^2 + (f f0 / Q)^2)``, area
  ``A pi f0 Q / 2`` (= ``k_B T / k_eff`` by equipartition).
* **Fluid-loaded** (:class:`FluidLine`): in a viscous fluid the mode's added mass and damping depend on frequency
  through the hydrodynamic function ``Gamma(omega)`` of the section (Sader 1998, eq 20;
  :func:`~probedyn.diagnose.hydrodynamics.sader_gamma`), and the thermal line is not an SHO. Its modal equation
  ``m (1 + a Gamma_r(omega)) x'' + c(omega) x' + k x = F_th`` with ``a = (pi / 4) rho_f w^2 / (rho t w)`` the
  fluid's mass per unit length over the lever's (the uniform beam's, as in Sader's eq 13) and
  ``c(omega) = b m a omega Gamma_i(omega)`` gives, by the fluctuation-dissipation theorem (the thermal force's
  spectrum is proportional to ``c(omega)``), the line

      S(omega) = A (c(omega) / c(omega_0)) omega_0^4 mu_0^2 / ((omega_v^2 - omega^2 mu(omega))^2 + (omega c(omega) / m)^2),

  ``mu = 1 + a Gamma_r``. ``f0`` is the loaded resonance where ``omega_v^2 = omega_0^2 mu(omega_0)`` and
  ``Q = omega_0 mu(omega_0) m / c(omega_0)`` -- the definitions of the probe model's fluid-loaded modes
  (:func:`~probedyn.diagnose.modal_model._fluid_mode`, Sader 1998 eqs 16-17) -- so ``omega_v`` and the damping
  scale ``b`` follow from ``(f0, Q)``. Near ``f0`` the line is the SHO of the same ``(f0, Q, A)``; away from it
  the added mass falls and the damping rises with the frequency's Reynolds number, a skewed line. An SHO fitted
  to a line of Q ~ 5 in water misplaces its centre by ~1 % and its Q by ~7 %, or is split into two lines by the
  doublet test (blind spectra s11 and s19, session 47). ``b`` is free: a fluid other than the declared one
  (viscosity 58 % higher in s11) changes the damping more than the added mass. The intrinsic loss is taken as the
  fluid's (``Q_int >> Q_fluid`` in a liquid). For torsional and lateral lines the flexural ``Gamma`` is an
  approximation of the frequency dependence of their loads (theirs differ by a factor of order one in their
  logarithmic slopes, a second-order change of the line's skew).
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.diagnose.hydrodynamics import sader_gamma

__all__ = ["sho_psd", "FluidLine", "SHO"]


def sho_psd(f, f0, Q, A):
    """Thermal SHO line of resonance ``f0``, quality factor ``Q`` and low-frequency level ``A``."""
    return A * f0**4 / ((f0**2 - f**2) ** 2 + (f * f0 / Q) ** 2)


class SHOLine:
    """The simple harmonic oscillator's line (:func:`sho_psd`)."""

    name = "SHO"

    def psd(self, f, f0, Q, A):
        return sho_psd(f, f0, Q, A)


SHO = SHOLine()


class FluidLine:
    """A flexural mode's line in a viscous fluid (module docstring): ``width`` [m] of the section, the fluid's
    ``rho_f`` [kg/m^3] and ``eta_f`` [Pa s], and the mass ratio ``a`` (the fluid's inviscid added mass per length
    over the lever's). ``Gamma`` is evaluated once on the spectrum's grid ``freq`` and interpolated (it is smooth in
    ln f: its change over a bin is below 1e-5 relative)."""

    name = "fluid-loaded"

    def __init__(self, freq: np.ndarray, width: float, rho_f: float, eta_f: float, a: float):
        if not (width > 0 and rho_f > 0 and eta_f > 0 and a > 0):
            raise ValueError("a fluid line needs a positive width, fluid density, viscosity and mass ratio")
        lo, hi = float(np.min(freq)), float(np.max(freq))
        self._lnf = np.linspace(math.log(max(lo, 1e-3) / 2), math.log(2 * hi), 4096)
        g = sader_gamma(2 * math.pi * np.exp(self._lnf), width, rho_f, eta_f)
        self._gr, self._gi = np.asarray(g.real, float), np.asarray(g.imag, float)
        self.a = float(a)

    def gamma(self, f):
        lf = np.log(np.asarray(f, float))
        return np.interp(lf, self._lnf, self._gr), np.interp(lf, self._lnf, self._gi)

    def psd(self, f, f0, Q, A):
        f = np.asarray(f, float)
        gr, gi = self.gamma(f)
        gr0, gi0 = self.gamma(f0)
        mu0 = 1.0 + self.a * float(gr0)
        fv2 = f0**2 * mu0  # the unloaded (vacuum) frequency squared, [Hz^2]
        # the damping per unit modal mass in Hz, c(f) / (2 pi m), proportional to f Gamma_i(f) (the fluid's) and
        # scaled so that c(f0) / (2 pi m) = f0 mu0 / Q (the definition of Q)
        c = (mu0 / (Q * float(gi0))) * f * gi
        c0 = f0 * mu0 / Q
        mu = 1.0 + self.a * gr
        return A * (c / c0) * f0**4 * mu0**2 / ((fv2 - f**2 * mu) ** 2 + (f * c) ** 2)
