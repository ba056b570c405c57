"""Desired tip paths for path tracking (source sections 3.2.3, 3.3.3, 3.4.1, 3.5.4).

A path gives the desired tip displacement ``r(t)`` (3,) in the probe axes (probedyn: x along the
probe / tube axis, y lateral, z normal to the substrate), measured from the tip's rest position,
together with its time derivatives up to the fourth order: the quasi-static inverse needs ``r``,
the slow control's feedforward ``r, r', r''``, and the exact dynamic inverse of the two-body
probe (force on the body, tip behind a spring: relative degree 4) needs ``r''''``.

Construction: a **geometry** ``r(s)`` parametrised by a phase ``s`` in [0, 1] with analytic
derivatives ``d^k r / ds^k`` (k <= 4), and a **timing law** ``s(t)`` with analytic derivatives;
the time derivatives follow from Faa di Bruno's formula (``TimedPath.derivatives``).

* Geometries (all start at the origin, the rest position): ``line``, ``circle`` (through the
  origin), ``square`` (rest-to-rest sides: the tip stops at every corner, so the path is smooth),
  ``cylinder`` (a helix: circles in a plane plus an advance along the axis), ``cone`` (a conical
  helix from the apex), ``sphere`` (a spiral from the north pole to the south pole). The curved
  ones are sums of terms ``a s^p sin(w s + phi)`` (p = 0, 1), differentiated exactly.
* Timing laws: ``rest_to_rest`` (the C^4 smoothstep of degree 9: s, s', ..., s'''' continuous,
  derivatives 1-4 zero at both ends) and ``cruise`` (speed ramped up over ``ramp`` with the same
  smoothstep, constant, ramped down; ``ramp = 0`` is an abrupt start, the velocity jumps, as in a
  quasi-static simulation driven by ``R cos(wt), R sin(wt)`` from t = 0).
* :class:`CsvPath`: points with times from a file, interpolated by a quintic spline with zero
  velocity and acceleration at both ends (C^4 inside), validated (columns, finite numbers,
  strictly increasing times, units) with one-line errors.

All quantities SI (m, s).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path as FsPath
from typing import Any, Sequence

import numpy as np
from numpy.polynomial import Polynomial
from scipy.interpolate import make_interp_spline

from probedyn.core.io import MAX_DATA_BYTES, read_text
from probedyn.core.errors import DataFormatError, ParameterError

AXES = {"x": 0, "y": 1, "z": 2}
ORDER = 4  # highest derivative every path provides

#: C^4 smoothstep of degree 9: S(0)=0, S(1)=1, S^(k)(0)=S^(k)(1)=0 for k=1..4
SMOOTHSTEP9 = Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])


def _unit(axis: str | Sequence[float]) -> np.ndarray:
    if isinstance(axis, str):
        a = axis.strip().lower()
        if a not in AXES:
            raise ParameterError(f"axis must be x, y or z, got {axis!r}")
        e = np.zeros(3)
        e[AXES[a]] = 1.0
        return e
    e = np.asarray(axis, dtype=float)
    n = float(np.linalg.norm(e))
    if e.shape != (3,) or not math.isfinite(n) or n == 0:
        raise ParameterError(f"axis must be a non-zero 3-vector, got {axis!r}")
    return e / n


def _pos(name: str, v: float, lo: float = 0.0, hi: float = math.inf, allow_zero: bool = False) -> float:
    v = float(v)
    if not math.isfinite(v) or v < lo or v > hi or (v == 0 and not allow_zero):
        raise ParameterError(f"{name} must be in ({lo:g}, {hi:g}], got {v:g}")
    return v


# ---------------------------------------------------------------------------------------------
# timing laws
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Timing:
    """Phase ``s(t)`` on [0, ``duration``] with ``s(0) = 0``, ``s(duration) = 1``.

    ``kind = "rest_to_rest"``: ``s = S9(t/T)``; ``kind = "cruise"``: constant phase speed between
    smoothstep ramps of length ``ramp`` (0: abrupt start and stop); ``kind = "linear"``: s = t/T
    (for geometries that stop by themselves, e.g. the square's corners). Before 0 and after
    ``duration`` the phase is held (the tip rests).
    """

    duration: float
    kind: str = "cruise"
    ramp: float = 0.0

    def __post_init__(self) -> None:
        _pos("path duration [s]", self.duration, hi=1e5)
        if self.kind not in ("rest_to_rest", "cruise", "linear"):
            raise ParameterError(f"timing kind must be rest_to_rest, cruise or linear, got {self.kind!r}")
        if self.kind == "cruise" and not (0 <= self.ramp <= self.duration / 2):
            raise ParameterError(f"ramp time {self.ramp:g} s must be in [0, duration/2 = {self.duration / 2:g}] s")

    @property
    def smooth(self) -> bool:
        """True when s(t) has four continuous derivatives (an exact dynamic inverse exists)."""
        return self.kind == "rest_to_rest" or (self.kind == "cruise" and self.ramp > 0)

    def derivatives(self, t: np.ndarray, order: int = ORDER) -> np.ndarray:
        """(order+1, n): s, s', ..., s^(order) at times ``t``."""
        t = np.asarray(t, dtype=float)
        T = self.duration
        out = np.zeros((order + 1, t.size))
        if self.kind == "rest_to_rest":
            x = np.clip(t / T, 0.0, 1.0)
            inside = (t > 0) & (t < T)
            p = SMOOTHSTEP9
            out[0] = p(x)
            for k in range(1, order + 1):
                p = p.deriv()
                out[k] = np.where(inside, p(x) / T**k, 0.0)
            return out
        if self.kind == "linear":
            out[0] = np.clip(t / T, 0.0, 1.0)
            if order >= 1:
                out[1] = np.where((t >= 0) & (t <= T), 1.0 / T, 0.0)
            return out
        Tr = self.ramp
        v0 = 1.0 / (T - Tr)  # integral of the speed profile = v0 (T - Tr) (symmetric smoothstep: mean 1/2)
        if Tr == 0:
            out[0] = np.clip(t / T, 0.0, 1.0)
            if order >= 1:
                out[1] = np.where((t >= 0) & (t <= T), v0, 0.0)
            return out
        S = SMOOTHSTEP9
        Sint = S.integ()  # integral from 0: Sint(1) = 1/2
        up = (t > 0) & (t < Tr)
        mid = (t >= Tr) & (t <= T - Tr)
        down = (t > T - Tr) & (t < T)
        x_up = np.clip(t / Tr, 0, 1)
        x_dn = np.clip((T - t) / Tr, 0, 1)
        s = np.where(t <= 0, 0.0, np.where(t >= T, 1.0, 0.0))
        s = np.where(up, v0 * Tr * Sint(x_up), s)
        s = np.where(mid, v0 * (Tr / 2 + (t - Tr)), s)
        s = np.where(down, 1.0 - v0 * Tr * Sint(x_dn), s)
        out[0] = s
        if order >= 1:
            out[1] = np.where(up, v0 * S(x_up), 0.0) + np.where(mid, v0, 0.0) + np.where(down, v0 * S(x_dn), 0.0)
        p = S
        for k in range(2, order + 1):
            p = p.deriv()
            out[k] = np.where(up, v0 * p(x_up) / Tr ** (k - 1), 0.0) \
                + np.where(down, v0 * p(x_dn) * (-1.0 / Tr) ** (k - 1), 0.0)
        return out

    def describe(self) -> dict[str, Any]:
        return {"duration_s": self.duration, "kind": self.kind, "ramp_s": self.ramp}


# ---------------------------------------------------------------------------------------------
# geometries
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Term:
    """``amp * s^power * sin(omega s + phase)`` along the unit vector ``axis`` (power 0 or 1)."""

    amp: float
    omega: float
    phase: float
    power: int
    axis: tuple[float, float, float]

    def derivative(self, s: np.ndarray, k: int) -> np.ndarray:
        """k-th derivative in s (scalar profile, shape of s)."""
        w, ph, a = self.omega, self.phase, self.amp
        g = lambda j: (w**j) * np.sin(w * s + ph + j * math.pi / 2)  # noqa: E731  (d^j/ds^j sin)
        if self.power == 0:
            return a * g(k) if (k == 0 or w != 0) else np.zeros_like(s)
        # s * g: d^k = s g^(k) + k g^(k-1)
        val = s * g(k) if (k == 0 or w != 0) else np.zeros_like(s)
        if k >= 1:
            val = val + k * (g(k - 1) if (k - 1 == 0 or w != 0) else np.zeros_like(s))
        return a * val


@dataclass(frozen=True)
class Geometry:
    """A curve ``r(s) = sum of terms``, s in [0, 1], starting at the origin."""

    name: str
    terms: tuple[Term, ...]
    params: dict[str, Any] = field(default_factory=dict)
    default_timing: str = "cruise"

    def derivatives(self, s: np.ndarray, order: int = ORDER) -> np.ndarray:
        """(order+1, n, 3): d^k r / ds^k."""
        s = np.asarray(s, dtype=float)
        out = np.zeros((order + 1, s.size, 3))
        for term in self.terms:
            e = np.asarray(term.axis)
            for k in range(order + 1):
                out[k] += np.outer(term.derivative(s, k), e)
        return out

    def length_estimate(self, n: int = 4001) -> float:
        s = np.linspace(0, 1, n)
        r = self.derivatives(s, 0)[0]
        return float(np.sum(np.linalg.norm(np.diff(r, axis=0), axis=1)))


@dataclass(frozen=True)
class SquareGeometry:
    """Square of side ``side`` in the plane (e1, e2), starting at a corner (the origin); each side
    is a rest-to-rest smoothstep in the phase (the tip stops at the corners, so velocity and
    acceleration stay continuous)."""

    side: float
    e1: tuple[float, float, float]
    e2: tuple[float, float, float]
    name: str = "square"
    default_timing: str = "linear"

    @property
    def params(self) -> dict[str, Any]:
        return {"side_m": self.side, "e1": list(self.e1), "e2": list(self.e2)}

    def derivatives(self, s: np.ndarray, order: int = ORDER) -> np.ndarray:
        s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
        a, e1, e2 = self.side, np.asarray(self.e1), np.asarray(self.e2)
        corners = np.array([0 * e1, a * e1, a * (e1 + e2), a * e2, 0 * e1])
        k = np.minimum((4 * s).astype(int), 3)
        u = 4 * s - k
        edge = corners[k + 1] - corners[k]
        out = np.zeros((order + 1, s.size, 3))
        p = SMOOTHSTEP9
        out[0] = corners[k] + p(u)[:, None] * edge
        for j in range(1, order + 1):
            p = p.deriv()
            out[j] = (4.0**j) * p(u)[:, None] * edge
        return out

    def length_estimate(self, n: int = 0) -> float:
        return 4 * self.side


def _plane(plane: str) -> tuple[np.ndarray, np.ndarray]:
    p = plane.strip().lower()
    if len(p) != 2 or p[0] == p[1] or any(c not in AXES for c in p):
        raise ParameterError(f"plane must be two different axes among x, y, z (e.g. 'yz'), got {plane!r}")
    return _unit(p[0]), _unit(p[1])


def _third(e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    return np.cross(e1, e2)


def line(end: Sequence[float]) -> Geometry:
    """Straight line from the origin to ``end`` [m]."""
    e = np.asarray(end, dtype=float)
    n = float(np.linalg.norm(e))
    if e.shape != (3,) or not math.isfinite(n) or n == 0:
        raise ParameterError(f"line end must be a non-zero 3-vector in metres, got {end!r}")
    return Geometry("line", (Term(n, 0.0, math.pi / 2, 1, tuple(e / n)),), {"end_m": e.tolist()}, "rest_to_rest")


def circle(radius: float, plane: str = "yz", turns: float = 1.0) -> Geometry:
    """Circle of ``radius`` through the origin in ``plane`` (centre at -radius e1):
    ``r = R [(cos(2 pi n s) - 1) e1 + sin(2 pi n s) e2]``."""
    R = _pos("circle radius [m]", radius, hi=1e-2)
    n = _pos("turns", turns, hi=1e4)
    e1, e2 = _plane(plane)
    w = 2 * math.pi * n
    terms = (Term(R, w, math.pi / 2, 0, tuple(e1)), Term(-R, 0.0, math.pi / 2, 0, tuple(e1)),
             Term(R, w, 0.0, 0, tuple(e2)))
    return Geometry("circle", terms, {"radius_m": R, "plane": plane, "turns": n})


def cylinder(radius: float, length: float, plane: str = "xz", turns: float = 2.0) -> Geometry:
    """Helix on a cylinder: circles of ``radius`` in ``plane`` and an advance ``length`` along the
    plane's normal (the cylinder's axis; ``plane = "xz"``: axis along y, parallel to the substrate)."""
    R = _pos("cylinder radius [m]", radius, hi=1e-2)
    Lc = _pos("cylinder length [m]", length, hi=1e-2)
    n = _pos("turns", turns, hi=1e4)
    e1, e2 = _plane(plane)
    e3 = _third(e1, e2)
    w = 2 * math.pi * n
    terms = (Term(R, w, math.pi / 2, 0, tuple(e1)), Term(-R, 0.0, math.pi / 2, 0, tuple(e1)),
             Term(R, w, 0.0, 0, tuple(e2)), Term(Lc, 0.0, math.pi / 2, 1, tuple(e3)))
    return Geometry("cylinder", terms, {"radius_m": R, "length_m": Lc, "plane": plane, "turns": n})


def cone(radius: float, height: float, plane: str = "xy", turns: float = 2.0) -> Geometry:
    """Conical helix from the apex (the origin): radius growing linearly to ``radius`` in
    ``plane`` while advancing ``height`` along the plane's normal (``plane = "xy"``: the cone's
    axis is z, normal to the substrate): ``r = R s [cos(2 pi n s) e1 + sin(2 pi n s) e2] + H s e3``."""
    R = _pos("cone radius [m]", radius, hi=1e-2)
    H = _pos("cone height [m]", height, hi=1e-2, allow_zero=True)
    n = _pos("turns", turns, hi=1e4)
    e1, e2 = _plane(plane)
    e3 = _third(e1, e2)
    w = 2 * math.pi * n
    terms = [Term(R, w, math.pi / 2, 1, tuple(e1)), Term(R, w, 0.0, 1, tuple(e2))]
    if H > 0:
        terms.append(Term(H, 0.0, math.pi / 2, 1, tuple(e3)))
    return Geometry("cone", tuple(terms), {"radius_m": R, "height_m": H, "plane": plane, "turns": n})


def sphere(radius: float, plane: str = "xy", turns: float = 3.0) -> Geometry:
    """Spiral on a sphere of ``radius`` from its north pole (the origin; centre at -R e3) to its
    south pole: polar angle ``pi s``, azimuth ``2 pi n s`` in ``plane``. Products of sines are
    written as sums (``sin a cos b = (sin(a+b) + sin(a-b))/2``) so every term is a sinusoid."""
    R = _pos("sphere radius [m]", radius, hi=1e-2)
    n = _pos("turns", turns, hi=1e4)
    e1, e2 = _plane(plane)
    e3 = _third(e1, e2)
    a, b = math.pi, 2 * math.pi * n
    terms = (Term(R / 2, a + b, 0.0, 0, tuple(e1)), Term(R / 2, a - b, 0.0, 0, tuple(e1)),
             Term(R / 2, a - b, math.pi / 2, 0, tuple(e2)), Term(-R / 2, a + b, math.pi / 2, 0, tuple(e2)),
             Term(R, a, math.pi / 2, 0, tuple(e3)), Term(-R, 0.0, math.pi / 2, 0, tuple(e3)))
    return Geometry("sphere", terms, {"radius_m": R, "plane": plane, "turns": n})


def square(side: float, plane: str = "yz") -> SquareGeometry:
    a = _pos("square side [m]", side, hi=1e-2)
    e1, e2 = _plane(plane)
    return SquareGeometry(a, tuple(e1), tuple(e2))


# ---------------------------------------------------------------------------------------------
# timed paths
# ---------------------------------------------------------------------------------------------


class Path:
    """Interface: ``derivatives(t, order) -> (order+1, n, 3)``, ``duration``, ``smooth``,
    ``describe()``."""

    name: str = "path"
    duration: float = 0.0
    smooth: bool = True

    def derivatives(self, t: np.ndarray, order: int = ORDER) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def position(self, t: np.ndarray) -> np.ndarray:
        return self.derivatives(np.atleast_1d(t), 0)[0]

    def used_axes(self, tol: float = 1e-12) -> list[str]:
        """Axes along which the path moves (max |r_i| > tol * max |r|)."""
        t = np.linspace(0, self.duration, 2001)
        r = self.position(t)
        m = np.max(np.abs(r), axis=0)
        big = float(m.max())
        return [a for a, i in AXES.items() if m[i] > tol * big]

    def extent(self) -> float:
        t = np.linspace(0, self.duration, 2001)
        return float(np.max(np.abs(self.position(t))))

    def peak_speed(self) -> float:
        t = np.linspace(0, self.duration, 4001)
        return float(np.max(np.linalg.norm(self.derivatives(t, 1)[1], axis=1)))

    def describe(self) -> dict[str, Any]:  # pragma: no cover - interface
        raise NotImplementedError


class TimedPath(Path):
    """A geometry travelled with a timing law (module docstring)."""

    def __init__(self, geometry, timing: Timing) -> None:
        self.geometry = geometry
        self.timing = timing
        self.name = geometry.name
        self.duration = timing.duration
        self.smooth = timing.smooth or (timing.kind == "linear" and isinstance(geometry, SquareGeometry))

    def derivatives(self, t: np.ndarray, order: int = ORDER) -> np.ndarray:
        """Faa di Bruno up to the fourth derivative:
        r' = r1 s1; r'' = r2 s1^2 + r1 s2; r''' = r3 s1^3 + 3 r2 s1 s2 + r1 s3;
        r'''' = r4 s1^4 + 6 r3 s1^2 s2 + r2 (3 s2^2 + 4 s1 s3) + r1 s4 (rk = d^k r/ds^k)."""
        if order > ORDER:
            raise ParameterError(f"paths provide derivatives up to order {ORDER}")
        t = np.atleast_1d(np.asarray(t, dtype=float))
        S = self.timing.derivatives(t, ORDER)
        R = self.geometry.derivatives(S[0], ORDER)
        s1, s2, s3, s4 = (S[k][:, None] for k in range(1, 5))
        r1, r2, r3, r4 = R[1], R[2], R[3], R[4]
        out = np.empty((order + 1, t.size, 3))
        out[0] = R[0]
        full = [R[0], r1 * s1, r2 * s1**2 + r1 * s2, r3 * s1**3 + 3 * r2 * s1 * s2 + r1 * s3,
                r4 * s1**4 + 6 * r3 * s1**2 * s2 + r2 * (3 * s2**2 + 4 * s1 * s3) + r1 * s4]
        for k in range(order + 1):
            out[k] = full[k]
        return out

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "geometry": dict(self.geometry.params), "timing": self.timing.describe(),
                "length_m": self.geometry.length_estimate(), "smooth": self.smooth}


class CsvPath(Path):
    """Points ``(t, x, y, z)`` [s, m] from a CSV file (module docstring)."""

    name = "csv"

    def __init__(self, t: np.ndarray, r: np.ndarray, source: str = "<array>", lines: Sequence[int] | None = None) -> None:
        t = np.asarray(t, dtype=float)
        r = np.asarray(r, dtype=float)
        if t.ndim != 1 or r.shape != (t.size, 3):
            raise DataFormatError(f"{source}: expected columns t, x, y, z")
        if t.size < 4:
            raise DataFormatError(f"{source}: a path needs at least 4 points, got {t.size}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(r))):
            raise DataFormatError(f"{source}: non-finite value in the path")
        dt = np.diff(t)
        if np.any(dt <= 0):
            i = int(np.nonzero(dt <= 0)[0][0])
            where = f"{source}:{lines[i + 1]}" if lines is not None else f"{source}: row {i + 2}"
            raise DataFormatError(f"{where}: times must increase strictly (t = {t[i + 1]:g} s after {t[i]:g} s)")
        if t[0] != 0:
            raise DataFormatError(f"{source}: the first time must be 0 s (got {t[0]:g} s)")
        big = float(np.max(np.abs(r)))
        if big > 1e-3:
            raise DataFormatError(f"{source}: coordinates up to {big:g} m: a tip path is in metres and within 1 mm "
                                  "(micrometres typed as metres?)")
        if t[-1] > 1e5:  # the limit of every path's duration (Timing)
            raise DataFormatError(f"{source}: the path lasts {t[-1]:g} s, beyond 1e5 s (times in seconds?)")
        self.t_points, self.r_points, self.source = t, r, source
        self.duration = float(t[-1])
        self.spline = make_interp_spline(t, r, k=5, bc_type=([(1, np.zeros(3)), (2, np.zeros(3))],
                                                             [(1, np.zeros(3)), (2, np.zeros(3))]))
        self.smooth = True
        self.name = f"csv:{FsPath(source).name}"

    def derivatives(self, t: np.ndarray, order: int = ORDER) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        tc = np.clip(t, 0.0, self.duration)
        out = np.empty((order + 1, t.size, 3))
        inside = ((t >= 0) & (t <= self.duration))[:, None]
        for k in range(order + 1):
            v = self.spline(tc, nu=k)
            out[k] = v if k == 0 else np.where(inside, v, 0.0)
        return out

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "source": self.source, "points": int(self.t_points.size),
                "duration_s": self.duration, "interpolation": "quintic spline, zero velocity and acceleration at the ends"}


def read_csv_path(path: str | FsPath) -> CsvPath:
    """Read ``t, x, y, z`` (s, m) from a CSV file; an optional header line naming the columns
    ``t,x,y,z`` is allowed, ``#`` starts a comment. One-line :class:`DataFormatError` on bad input."""
    p = FsPath(path)
    rows: list[list[float]] = []
    lines: list[int] = []
    # a regular file of bounded size (no FIFO, device or folder), UTF-8 (bad bytes located, not echoed)
    text = read_text(p, what="path file", max_bytes=MAX_DATA_BYTES)
    header_seen = False
    for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        if not cells or all(c == "" for c in cells) or cells[0].startswith("#"):
            continue
        if len(cells) != 4:
            raise DataFormatError(f"{p}:{lineno}: expected 4 columns t,x,y,z (s, m), got {len(cells)}")
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            if not rows and not header_seen and [c.lower() for c in cells] == ["t", "x", "y", "z"]:
                header_seen = True
                continue
            bad = next(c for c in cells if not _is_float(c))
            raise DataFormatError(f"{p}:{lineno}: cannot read {bad!r} as a number") from None
        rows.append(vals)
        lines.append(lineno)
    if not rows:
        raise DataFormatError(f"{p}: no data rows (expected t,x,y,z in s, m)")
    a = np.asarray(rows)
    return CsvPath(a[:, 0], a[:, 1:], str(p), lines)


def _is_float(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


# ---------------------------------------------------------------------------------------------
# reference paths of the source's figures
# ---------------------------------------------------------------------------------------------

PATH_KINDS = ("line", "circle", "square", "cylinder", "sphere", "cone")


def make_path(kind: str, *, size: float = 0.5e-6, duration: float = 1.0, speed: float | None = None,
              turns: float | None = None, plane: str | None = None, ramp: float | None = None,
              height: float | None = None) -> TimedPath:
    """A built-in path of characteristic ``size`` [m] (radius or side). ``speed`` [m/s] (mean
    tip speed along the path) overrides ``duration``. Default planes: circle/square ``yz``
    (the duo-bimorph's plane), cone/sphere ``xy`` (axis z, normal to the substrate), cylinder
    ``xz`` (axis y, parallel to the substrate, as in Fig 3.22). ``ramp``: cruise ramp time [s]
    (default duration/10)."""
    k = kind.strip().lower()
    if k == "line":
        g = line([0.0, size, size])
    elif k == "circle":
        g = circle(size, plane or "yz", turns or 1.0)
    elif k == "square":
        g = square(size, plane or "yz")
    elif k == "cylinder":
        g = cylinder(size, height if height is not None else 2 * size, plane or "xz", turns or 2.0)
    elif k == "sphere":
        g = sphere(size, plane or "xy", turns or 3.0)
    elif k == "cone":
        g = cone(size, height if height is not None else size, plane or "xy", turns or 2.0)
    else:
        raise ParameterError(f"unknown path {kind!r} (known: {', '.join(PATH_KINDS)}, or a CSV file)")
    if speed is not None:
        v = _pos("path speed [m/s]", speed, hi=10.0)
        duration = g.length_estimate() / v
    tk = g.default_timing
    if tk == "cruise":
        timing = Timing(duration, "cruise", duration / 10 if ramp is None else ramp)
    else:
        timing = Timing(duration, tk)
    return TimedPath(g, timing)
