"""Flight and landing after the release: eqs 4.43-4.44, Figs 4.23, 4.27, 4.28.

Model (4.43). After the release the sample (mass ``M``, a point at ``(x, y)``, ``y`` its gap to
the substrate) is pulled by the probe, by the substrate and by gravity::

    M y'' = F_p cos(theta) - F_s(y) - M g,      M x'' = F_p sin(theta)

The probe's surface is the plane through the tip's mean position ``(0, D)`` tilted by
``theta``; the sample's distance to it along its normal is
``g_n = cos(theta) [(D - y) - x tan(theta)]`` and its attraction ``F_p(g_n)`` acts along the
normal ``(sin theta, cos theta)``. Two force laws (``law``):

* ``"derjaguin"`` (the print): ``F_p = H_sb R_p / (6 (g_n - zeta_0)^2)``,
  ``F_s = H_ss R_s / (6 (y - zeta_0)^2)`` with ``R_p = R_t R_s / (R_t + R_s)`` (two spheres) and
  ``R_s`` (sphere on a flat);
* ``"hamaker"``: Hamaker's full sphere-sphere (tip sphere ``R_t``) and sphere-flat laws, which
  equal the Derjaguin forms for gaps much smaller than the radii and fall off as
  ``2 H R^3 / (3 s^4)`` (sphere-flat) beyond them. Derjaguin overestimates the substrate's pull
  at 5 um by a factor ``(1 + s / (2 R))^2`` = 270 (:func:`force_budget`).

Tilt (4.44, SOURCE-NOTES 6). The printed ``tan^-1(theta) = F0 / L`` divides a force by a length;
the tilt comes from the tip's oscillation amplitude ``A_tip`` (the forced response 4.41 / the
retained modes, :func:`.release.setup_release`): ``theta = atan(A_tip / L)`` (``tilt="amplitude"``,
as SOURCE-NOTES 6 states); ``tilt="slope"`` uses the first mode's end slope instead,
``theta = atan(1.3765 A_tip / L)`` (``phi'(L) / phi(L)`` of the clamped-free mode 1).

Start of the flight. The release run (:mod:`.release`) integrates the sample's vertical motion on
the full contact and tail until the sample is beyond the tip's reach with enough energy to
escape; the flight starts there, with that height and velocity. The lateral velocity and
displacement the tilted tip imparts **during** that near-field phase (where the tip's pull is
nanonewtons) are ``tan(theta)`` times the release run's time integrals of the tip's force on
the sample (per unit mass), and are added to the start state: without them ``R_L`` would
miss the dominant part (docs/placing.md). During the flight the tip is held at its mean
position (the printed model), which is accurate once the sample is below the tip's lowest point.

Landing: ``y`` reaches ``2 zeta_0`` (the Derjaguin law's cut-off scale); ``R_L = x`` there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from probedyn.core.errors import ParameterError, SolverError

from .approach import effective_radius
from .probe import TABLE
from .release import G, ReleaseResult

LAWS = ("derjaguin", "hamaker")
TILTS = ("amplitude", "slope")
#: phi'(L) / phi(L) * L of the first clamped-free mode (2.39)
FIRST_MODE_END_SLOPE = 1.3765472


def sphere_flat_force(s, H: float, R: float, law: str = "derjaguin", zeta0: float = 0.0):
    """Attraction [N] of a sphere ``R`` at the gap ``s`` from a flat: Derjaguin
    ``H R / (6 (s - zeta0)^2)`` or Hamaker's ``2 H R^3 / (3 g^2 (g + 2R)^2)`` with ``g = s - zeta0``."""
    g = np.asarray(s, dtype=float) - zeta0
    if law == "derjaguin":
        return H * R / (6.0 * g**2)
    if law == "hamaker":
        return 2.0 * H * R**3 / (3.0 * g**2 * (g + 2.0 * R) ** 2)
    raise ParameterError(f"unknown force law {law!r} ({', '.join(LAWS)})")


def sphere_sphere_force(s, H: float, R1: float, R2: float, law: str = "derjaguin", zeta0: float = 0.0):
    """Attraction [N] of two spheres at the surface gap ``s``: Derjaguin
    ``H R / (6 g^2)`` (``R = R1 R2 / (R1 + R2)``) or Hamaker's exact sphere-sphere law,
    ``F = -dU/dd`` of ``U = -H/6 [2R1R2/(d^2-a) + 2R1R2/(d^2-b) + ln((d^2-a)/(d^2-b))]``,
    ``d`` the centre distance, ``a = (R1+R2)^2``, ``b = (R1-R2)^2``."""
    g = np.asarray(s, dtype=float) - zeta0
    if law == "derjaguin":
        return H * effective_radius(R1, R2) / (6.0 * g**2)
    if law == "hamaker":
        d = g + R1 + R2
        a, b, c = (R1 + R2) ** 2, (R1 - R2) ** 2, 2.0 * R1 * R2
        d2 = d * d
        dUdd = -(H / 6.0) * (-2 * c * d / (d2 - a) ** 2 - 2 * c * d / (d2 - b) ** 2 + 2 * d / (d2 - a) - 2 * d / (d2 - b))
        return dUdd
    raise ParameterError(f"unknown force law {law!r} ({', '.join(LAWS)})")


def tilt_angle(A_tip: float, L: float, tilt: str = "amplitude") -> float:
    """(4.44) corrected (SOURCE-NOTES 6): ``atan(A_tip / L)`` or ``atan(1.3765 A_tip / L)``."""
    if tilt not in TILTS:
        raise ParameterError(f"unknown tilt rule {tilt!r} ({', '.join(TILTS)})")
    if not (A_tip >= 0 and L > 0):
        raise ParameterError("tilt: the amplitude must be >= 0 and the length positive")
    return math.atan((FIRST_MODE_END_SLOPE if tilt == "slope" else 1.0) * A_tip / L)


@dataclass(frozen=True)
class Flight:
    """The flight model (4.43): sample mass ``M``, probe at height ``D`` tilted by ``theta``."""

    M: float
    D: float
    theta: float
    H_sb: float
    H_ss: float
    R_t: float
    R_s: float
    zeta0: float
    g: float = G
    law: str = "derjaguin"

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ParameterError(f"unknown force law {self.law!r} ({', '.join(LAWS)})")
        for name in ("M", "D", "H_sb", "H_ss", "R_t", "R_s", "zeta0"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"flight: {name} must be positive, got {v}")

    @classmethod
    def table(cls, **kw) -> "Flight":
        """Table 4.4's values for everything not given (``theta`` defaults to 0)."""
        base = dict(M=float(TABLE["M1"]), D=float(TABLE["D"]), theta=0.0, H_sb=float(TABLE["H_sb"]),
                    H_ss=float(TABLE["H_ss"]), R_t=float(TABLE["R_t"]), R_s=float(TABLE["R_s"]),
                    zeta0=float(TABLE["zeta0"]))
        base.update(kw)
        return cls(**base)

    def normal_gap(self, x, y):
        return math.cos(self.theta) * ((self.D - np.asarray(y)) - np.asarray(x) * math.tan(self.theta))

    def probe_force(self, x, y):
        return sphere_sphere_force(self.normal_gap(x, y), self.H_sb, self.R_t, self.R_s, self.law, self.zeta0)

    def substrate_force(self, y):
        return sphere_flat_force(y, self.H_ss, self.R_s, self.law, self.zeta0)

    def rhs(self, t, u):
        x, y, vx, vy = u
        Fp = float(self.probe_force(x, y))
        Fs = float(self.substrate_force(y))
        return [vx, vy, Fp * math.sin(self.theta) / self.M, (Fp * math.cos(self.theta) - Fs) / self.M - self.g]

    def fly(self, y0: float, vy0: float, x0: float = 0.0, vx0: float = 0.0, t_max: float | None = None,
            rtol: float = 1e-10, n_out: int = 400) -> dict[str, Any]:
        """Integrate from ``(x0, y0)`` with ``(vx0, vy0)`` until ``y = 2 zeta_0`` (landing; returns
        ``R_L = x``), until the sample reaches the probe (``g_n = 2 zeta_0``: recaptured) or ``t_max``."""
        if not (2 * self.zeta0 < y0 < self.D):
            raise ParameterError(f"flight start height {y0:.4g} m must lie between the substrate and the probe")
        if t_max is None:
            # free fall from D under gravity alone bounds the time from above (attraction only adds)
            t_max = 10.0 * math.sqrt(2.0 * self.D / self.g) + 10.0 * self.D / max(abs(vy0), 1e-12)

        def land(t, u):
            return u[1] - 2.0 * self.zeta0

        land.terminal, land.direction = True, -1

        def back(t, u):
            return float(self.normal_gap(u[0], u[1])) - 2.0 * self.zeta0

        back.terminal, back.direction = True, -1
        sol = solve_ivp(self.rhs, (0.0, t_max), [x0, y0, vx0, vy0], method="DOP853", rtol=rtol,
                        atol=[1e-15, 1e-15, 1e-12, 1e-12], events=[land, back], dense_output=True)
        if not sol.success:
            raise SolverError(f"flight integration failed: {sol.message}")
        if len(sol.t_events[0]):
            status, tl = "landed", float(sol.t_events[0][0])
        elif len(sol.t_events[1]):
            status, tl = "recaptured", float(sol.t_events[1][0])
        else:
            status, tl = "airborne", float(sol.t[-1])
        # output on a grid dense at the start (fast near-field phase) and uniform later
        tt = np.unique(np.concatenate([np.geomspace(max(tl, 1e-300) * 1e-6, tl, n_out // 2),
                                       np.linspace(0.0, tl, n_out // 2)]))
        X = sol.sol(tt)
        return {"status": status, "t_flight_s": tl, "R_L_m": float(X[0, -1]) if status == "landed" else math.nan,
                "t_s": tt, "x_m": X[0], "y_m": X[1], "vx_m_s": X[2], "vy_m_s": X[3]}


def force_budget(M: float | None = None, D: float | None = None, heights=None, law: str = "derjaguin") -> list[dict[str, float]]:
    """What dominates the flight: probe attraction, substrate attraction and gravity [N] at
    several heights ``y`` above the substrate (probe at ``D``, no tilt)."""
    fl = Flight.table(**({"M": M} if M is not None else {}), **({"D": D} if D is not None else {}), law=law)
    ys = np.asarray(heights if heights is not None else [1e-9, 1e-8, 1e-7, 0.5 * fl.D, fl.D - 1e-7,
                                                           fl.D - 1e-8, fl.D - 1e-9], float)
    rows = []
    for y in ys:
        Fp = float(fl.probe_force(0.0, y))
        Fs = float(fl.substrate_force(y))
        Fg = fl.M * fl.g
        rows.append({"law": law, "y_m": float(y), "gap_to_probe_m": fl.D - float(y), "probe_n": Fp,
                     "substrate_n": Fs, "gravity_n": Fg,
                     "dominant": max((("probe", Fp), ("substrate", Fs), ("gravity", Fg)), key=lambda p: p[1])[0]})
    return rows


def gravity_crossover(M: float | None = None, law: str = "hamaker", H: float | None = None,
                      R: float | None = None) -> float:
    """Gap [m] beyond which gravity exceeds the substrate's attraction on the sample."""
    M = float(TABLE["M1"] if M is None else M)
    H = float(TABLE["H_ss"] if H is None else H)
    R = float(TABLE["R_s"] if R is None else R)
    z0 = float(TABLE["zeta0"])
    f = lambda s: math.log(sphere_flat_force(s, H, R, law, z0) / (M * G))  # noqa: E731
    return float(brentq(f, 2 * z0, 1.0, xtol=1e-15, rtol=1e-12))


@dataclass
class Landing:
    """A release run followed by its flight: outcome, landing radius and the trajectories."""

    release: ReleaseResult
    theta: float
    flight: dict[str, Any] | None
    start: dict[str, float] = field(default_factory=dict)

    @property
    def R_L(self) -> float:
        return self.flight["R_L_m"] if self.flight else math.nan

    def to_dict(self) -> dict[str, Any]:
        out = {"outcome": self.release.outcome, "theta_rad": self.theta, "R_L_m": self.R_L, "start": self.start}
        if self.flight:
            out["flight"] = {"status": self.flight["status"], "t_flight_s": self.flight["t_flight_s"]}
        return out


def land(release: ReleaseResult, tilt: str = "amplitude", law: str = "derjaguin", H_sb: float | None = None,
         near_field: bool = True) -> Landing:
    """The flight after a released run (no flight for other outcomes). ``near_field=False``
    drops the lateral impulse of the near-field phase (the printed model's start)."""
    s = release.setup
    if law not in LAWS:
        raise ParameterError(f"unknown force law {law!r} ({', '.join(LAWS)})")
    theta = tilt_angle(s.A, s.probe.L, tilt)
    if release.code != 2:
        return Landing(release, theta, None)
    fl = Flight(M=s.M, D=s.D, theta=theta, H_sb=float(TABLE["H_sb"] if H_sb is None else H_sb), H_ss=s.H_ss,
                R_t=float(TABLE["R_t"]), R_s=s.R_s, zeta0=float(TABLE["zeta0"]), g=s.g, law=law)
    tn = math.tan(theta)
    x0 = tn * release.probe_impulse_length_m if near_field else 0.0
    vx0 = tn * release.probe_impulse_velocity_m_s if near_field else 0.0
    start = {"x0_m": x0, "y0_m": release.sample_height_m, "vx0_m_s": vx0, "vy0_m_s": release.sample_velocity_m_s}
    res = fl.fly(release.sample_height_m, release.sample_velocity_m_s, x0, vx0)
    return Landing(release, theta, res, start)


__all__ = ["Flight", "Landing", "land", "tilt_angle", "sphere_flat_force", "sphere_sphere_force", "force_budget",
           "gravity_crossover", "LAWS", "TILTS", "FIRST_MODE_END_SLOPE"]
