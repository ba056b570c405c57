"""How the schemes take a reduced probe (:class:`probedyn.lumped.reduced.ReducedProbe`).

One place maps the probe's directions onto each scheme's lumped parameters, so every scheme
reads a probe the same way (scheme frame: scan = the scheme's x, lateral = its y, normal):

* FFM (eqs 2.13-2.14): ``m_x, c_x, k_x`` = :meth:`ReducedProbe.lumped` ("scan"): the static
  stiffness at the apex, the effective mass and damping of the dominant scan mode; ``m_y, c_y,
  k_y`` likewise from "lateral";
* nano-pushing (Table 4.1): ``k_tx, m_tx, c_t`` from "scan", ``k_ty, m_ty`` from "lateral";
* contact: the normal static stiffness for force curves (jump-to-contact, jump-out);
* two-mass stick-slip (section 4.1.3): ``m1, k1`` of the probe and its damping ``c1``, with the
  sample ``m2``, the contact ``k2``, ``zeta2`` and the period ``a`` of Table 4.3 (or given), give
  the non-dimensional model through eqs 4.3-4.7: ``m = m1 m2/(m1+m2)``, ``k = k1 k2/(k1+k2)``,
  ``zeta1 = c1 / (2 sqrt(k m))``, ``u0 = 4 pi^2 U0 / (k a^2)``, ``v = (2 pi/a) sqrt(m/k) V`` and
  the substrate phase ``psi = 2 pi X_s(0) / a`` (eq 4.6 at t = 0: the sample's initial position
  in the potential 4.1); :func:`stickslip_scaling` returns them with their derivation.

A table probe (``ReducedProbe.from_preset``) goes through the same functions: its values are the
table's, so ``--preset`` and ``--probe table-2.1`` give the same scheme.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from probedyn.core.errors import ParameterError
from probedyn.core.presets import preset
from probedyn.lumped.reduced import ReducedProbe
from probedyn.schemes.stickslip import TwoMassModel


def _lumped(probe: ReducedProbe, direction: str):
    try:
        return probe.lumped(direction)
    except ParameterError:
        return None


def ffm_cantilever(probe: ReducedProbe) -> dict[str, float]:
    """The FFM cantilever parameters (``m_x, c_x, k_x`` [, ``m_y, c_y, k_y``]) of a probe."""
    s = _lumped(probe, "scan")
    if s is None:
        raise ParameterError(f"the {probe.source} probe has no scan-direction spring for FFM")
    out = {"m_x": s.mass, "c_x": s.damping, "k_x": s.stiffness}
    lat = _lumped(probe, "lateral")
    if lat is not None:
        out.update(m_y=lat.mass, c_y=lat.damping, k_y=lat.stiffness)
    return out


def pushing_tip(probe: ReducedProbe) -> dict[str, float]:
    """The nano-pushing tip parameters (Table 4.1 names) of a probe."""
    s = _lumped(probe, "scan")
    if s is None:
        raise ParameterError(f"the {probe.source} probe has no scan-direction spring for pushing")
    out = {"k_tx": s.stiffness, "m_tx": s.mass, "c_t": s.damping}
    lat = _lumped(probe, "lateral")
    if lat is not None:
        out.update(k_ty=lat.stiffness, m_ty=lat.mass)
    return out


def normal_stiffness(probe: ReducedProbe) -> float:
    """The static normal stiffness [N/m] at the probe's point (force curves)."""
    return probe.static_stiffness("normal")


def stickslip_scaling(probe: ReducedProbe, U0: float, V: float = 0.0, x_s0: float = 0.0,
                      sample: Mapping[str, float] | None = None) -> dict[str, Any]:
    """Non-dimensional two-mass model (eqs 4.3-4.7) of ``probe`` pushing a sample on a substrate
    of corrugation amplitude ``U0`` [J] (eq 4.1) at speed ``V`` [m/s], the sample starting at
    ``x_s0`` [m] in the potential.  ``sample``: ``m2, k2, zeta2, a`` (default Table 4.3).

    Returns the SI inputs, ``m``, ``k``, ``u0``, ``v``, ``psi``, ``zeta1``, ``zeta2``, the mass
    and stiffness ratios of eq 4.7, and ``derivation``: one line per formula with its numbers."""
    s = _lumped(probe, "scan")
    if s is None:
        raise ParameterError(f"the {probe.source} probe has no scan-direction spring for the stick-slip model")
    t43 = preset("table-4.3")
    smp = {k: t43[k] for k in ("m2", "k2", "zeta2", "a")}
    for key, val in dict(sample or {}).items():
        if key not in smp:
            import difflib

            close = difflib.get_close_matches(key, list(smp), n=1)
            raise ParameterError(f"unknown sample parameter {key!r}" + (f" (did you mean {close[0]!r}?)" if close else "")
                                 + f" (known: {', '.join(smp)})")
        try:
            smp[key] = float(val)
        except (TypeError, ValueError):
            raise ParameterError(f"sample parameter {key} must be a number, got {val!r}") from None
    if not (math.isfinite(smp["zeta2"]) and smp["zeta2"] >= 0):
        raise ParameterError(f"zeta2 must be >= 0, got {smp['zeta2']!r}")
    if not math.isfinite(x_s0):
        raise ParameterError(f"x_s0 must be finite, got {x_s0!r}")
    for name in ("m2", "k2", "a"):
        if not (math.isfinite(smp[name]) and smp[name] > 0):
            raise ParameterError(f"{name} must be positive, got {smp[name]!r}")
    if not (math.isfinite(U0) and U0 >= 0):
        raise ParameterError(f"U0 must be >= 0 J, got {U0!r}")
    if not (math.isfinite(V) and V >= 0):
        raise ParameterError(f"V must be >= 0 m/s, got {V!r}")
    m1, k1, c1 = s.mass, s.stiffness, s.damping
    m2, k2, a = float(smp["m2"]), float(smp["k2"]), float(smp["a"])
    m = m1 * m2 / (m1 + m2)
    k = k1 * k2 / (k1 + k2)
    zeta1 = c1 / (2.0 * math.sqrt(k * m))
    u0 = 4.0 * math.pi**2 * U0 / (k * a * a)
    T = math.sqrt(m / k)
    v = 2.0 * math.pi / a * T * V
    psi = (2.0 * math.pi * x_s0 / a) % (2.0 * math.pi)
    d = [
        f"probe ({probe.source}, scan direction at '{probe.point}'): m1 = {m1:.4g} kg (effective mass of mode "
        f"{s.mode}), k1 = {k1:.4g} N/m (static), c1 = {c1:.4g} N s/m",
        f"sample and contact ({'Table 4.3' if not sample else 'given'}): m2 = {m2:.4g} kg, k2 = {k2:.4g} N/m, "
        f"zeta2 = {smp['zeta2']:.4g}, a = {a:.4g} m",
        f"(4.5)  m = m1 m2/(m1+m2) = {m:.4g} kg;  k = k1 k2/(k1+k2) = {k:.4g} N/m",
        f"(4.3)  time unit sqrt(m/k) = {T:.4g} s",
        f"(4.7)  zeta1 = c1/(2 sqrt(k m)) = {zeta1:.4g};  m1/m = {m1 / m:.4g}, m2/m = {m2 / m:.4g}, "
        f"k1/k = {k1 / k:.6g}, k2/k = {k2 / k:.6g}",
        f"(4.7)  u0 = 4 pi^2 U0/(k a^2) = 4 pi^2 x {U0:.4g} J / ({k:.4g} N/m x ({a:.4g} m)^2) = {u0:.4g}",
        f"(4.6)  v = (2 pi/a) sqrt(m/k) V = {v:.4g}  (V = {V:.4g} m/s)",
        f"(4.6)  psi = 2 pi X_s(0)/a mod 2 pi = {psi:.4g}  (X_s(0) = {x_s0:.4g} m)",
    ]
    return dict(m1=m1, k1=k1, c1=c1, m2=m2, k2=k2, a=a, U0=U0, V=V, x_s0=x_s0, m=m, k=k, time_unit_s=T,
                zeta1=zeta1, zeta2=float(smp["zeta2"]), u0=u0, v=v, psi=psi, mass_ratios=(m1 / m, m2 / m),
                stiffness_ratios=(k1 / k, k2 / k), probe=probe.summary(), derivation=d)


def two_mass_model(scaling: Mapping[str, Any]):
    """The :class:`probedyn.schemes.stickslip.TwoMassModel` of a :func:`stickslip_scaling` result
    (its parameter ranges apply: e.g. a probe damping far above Table 4.3's gives zeta1 > 100,
    which is refused with the value in the message)."""
    return TwoMassModel(m1=scaling["m1"], m2=scaling["m2"], k1=scaling["k1"], k2=scaling["k2"],
                        zeta1=scaling["zeta1"], zeta2=scaling["zeta2"], a=scaling["a"])


__all__ = ["ffm_cantilever", "pushing_tip", "normal_stiffness", "stickslip_scaling", "two_mass_model"]
