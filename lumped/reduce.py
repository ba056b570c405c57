"""Reduction of FEM modes to lumped (single-DOF-per-mode) models at the tip: eqs 3.1–3.3 generalised.

The source builds the lumped parameters of mode i from a beam mode shape ``phi_i(x)``:

* (3.1) ``M_i = rho A int phi_i^2 dx``,
* (3.2) ``c_i = mu int phi_i^2 dx`` (``mu`` = environment damping per unit length, N s/m^2),
* (3.3) ``k_i = M_i omega_i^2``.

These are the mass, damping and stiffness of the mode *referred to the coordinate in which the
mode is normalised*. The source normalises (3.11) so that ``|phi(L)| = 2`` (then
``int phi^2 = L`` and M_i = rho A L, the full beam mass); referred to the tip displacement,
which is what a tip-sample force acts on, the same mode has ``m_eff = rho A L / 4``. probedyn
always refers the lumped model to the tip displacement in the mode's dominant direction d:

    m_eff = phi^T M phi / phi_tip,d^2,   k_eff = omega^2 m_eff,

with the 3D FEM mass matrix M (eqs 3.1/3.3 with the FEM mode; for a beam mode they coincide
with (3.1) normalised to phi(L) = 1). The mode is taken from :class:`probedyn.fem.modes.Mode`
(``effective_mass_tip`` is exactly this quotient). The damping (3.2) is mass-proportional along
the beam, ``c / M = mu / (rho A)``, so its generalisation is

    c_eff = (mu / (rho A)) m_eff,beam,

where ``m_eff,beam`` excludes point masses (a tip mass carries no distributed drag; the
``mu dv/dt`` term printed in the end condition 3.8 has the units of a force per length and is
dropped). Alternatively a quality factor gives ``c_eff = sqrt(k_eff m_eff) / Q``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Iterable

import numpy as np

from probedyn.core.errors import ParameterError

DIRECTION_OF_FAMILY = {"flapwise": "z", "lateral": "y", "axial": "x"}
_AXES = "xyz"


@dataclass
class LumpedModel:
    """Lumped single-DOF model of one mode at the tip, SI units.

    ``direction``: tip displacement component the model is referred to (x, y or z);
    ``mass`` [kg], ``stiffness`` [N/m], ``damping`` [N s/m] (None without mu or Q),
    ``quality_factor`` and ``damping_ratio`` (derived from the damping), ``frequency_hz`` of the
    undamped mode, ``mass_fraction`` = m_eff / total mass of the model.
    """

    mode: int
    family: str
    direction: str
    frequency_hz: float
    omega: float
    mass: float
    stiffness: float
    damping: float | None = None
    quality_factor: float | None = None
    damping_ratio: float | None = None
    mass_fraction: float | None = None
    damping_source: str = "none"
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class Reduction:
    """All lumped models of a modal result plus the static tip stiffness check."""

    models: list[LumpedModel]
    static: dict[str, Any] = field(default_factory=dict)
    damping: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"modes": [m.to_dict() for m in self.models], "static": self.static, "damping": self.damping}


def dominant_direction(mode: Any) -> str:
    """The lumped-model direction of a mode: z flapwise, y lateral, x axial; else largest tip component."""
    d = DIRECTION_OF_FAMILY.get(mode.family)
    if d is not None:
        return d
    tip = np.abs(np.asarray(mode.tip_displacement, dtype=float))
    return _AXES[int(np.argmax(tip))]


def _point_mass_share(result: Any, mode: Any, direction: str) -> float:
    """``sum_p m_p |phi(x_p)|^2 / phi_tip,d^2``: the part of m_eff carried by point masses [kg]."""
    model = getattr(result, "model", None)
    pms = list(getattr(model, "point_masses", None) or [])
    if not pms:
        return 0.0
    k = _AXES.index(direction)
    tip = float(np.asarray(mode.tip_displacement, dtype=float)[k])
    if tip == 0.0:
        return 0.0
    total = 0.0
    for pm in pms:
        u = np.asarray(model.displacement_at(mode.shape, pm.point), dtype=float)
        total += float(pm.mass) * float(u @ u)
    return total / tip**2


def check_damping(mu: float | None = None, Q: float | None = None) -> None:
    """Refuse a damping specification before any work: at most one of ``mu`` (>= 0) and ``Q`` (> 0)."""
    if mu is not None and Q is not None:
        raise ParameterError("give either an environment damping mu or a quality factor Q, not both")
    if mu is not None and (not math.isfinite(mu) or mu < 0):
        raise ParameterError(f"environment damping mu must be >= 0, got {mu}")
    if Q is not None and (not math.isfinite(Q) or Q <= 0):
        raise ParameterError(f"quality factor Q must be positive, got {Q}")


def reduce_mode(result: Any, mode: Any, *, mu: float | None = None, Q: float | None = None,
                mass_per_length: float | None = None, total_mass: float | None = None,
                direction: str | None = None) -> LumpedModel:
    """Lumped model of one :class:`~probedyn.fem.modes.Mode` (eqs 3.1–3.3 generalised, see module doc).

    ``mu`` [N s/m^2] with ``mass_per_length`` = rho A [kg/m] gives (3.2); ``Q`` gives
    ``c = sqrt(k m)/Q``. Give at most one. A mode with (numerically) no tip motion in
    ``direction`` has no lumped model there: mass and stiffness are ``inf`` and a note says so.
    """
    check_damping(mu, Q)
    d = direction or dominant_direction(mode)
    tip = np.asarray(mode.tip_displacement, dtype=float)
    m_eff = float(mode.effective_mass_tip[d])
    note = ""
    if not math.isfinite(m_eff) or abs(tip[_AXES.index(d)]) < 1e-6 * max(np.abs(tip).max(), 1e-300):
        m_eff = math.inf
        note = f"no tip motion along {d}: not a lumped mode in this direction"
    omega = float(mode.omega)
    k_eff = omega**2 * m_eff
    c = zeta = q = None
    src = "none"
    if math.isfinite(m_eff):
        if mu is not None:
            if not mass_per_length or mass_per_length <= 0:
                raise ParameterError("mu damping (eq 3.2) needs the mass per unit length rho A of the beam")
            m_beam = m_eff - _point_mass_share(result, mode, d)
            c = mu / mass_per_length * m_beam
            src = "mu (eq 3.2)"
        elif Q is not None:
            c = math.sqrt(k_eff * m_eff) / Q
            src = "Q"
        if c is not None:
            zeta = c / (2.0 * math.sqrt(k_eff * m_eff))
            q = math.inf if c == 0 else math.sqrt(k_eff * m_eff) / c
    return LumpedModel(
        mode=int(mode.index), family=str(mode.family), direction=d,
        frequency_hz=float(mode.frequency_hz), omega=omega, mass=m_eff, stiffness=k_eff,
        damping=c, quality_factor=q, damping_ratio=zeta,
        mass_fraction=(m_eff / total_mass) if (total_mass and math.isfinite(m_eff)) else None,
        damping_source=src, note=note,
    )


def reduce_modes(result: Any, *, mu: float | None = None, Q: float | None = None,
                 mass_per_length: float | None = None, total_mass: float | None = None,
                 modes: Iterable[int] | None = None) -> list[LumpedModel]:
    """Lumped models of the modes of a :class:`~probedyn.fem.modes.ModalResult` (all, or ``modes``)."""
    sel = list(result.modes) if modes is None else [result.modes[i] for i in modes]
    return [reduce_mode(result, m, mu=mu, Q=Q, mass_per_length=mass_per_length, total_mass=total_mass) for m in sel]
