"""The reduced probe: what every scheme takes as "the probe".

A :class:`ReducedProbe` describes the probe as seen at one point (the tip apex, the holder,
...) in the scheme's frame: three orthonormal directions ``scan``, ``lateral``, ``normal``
given in probe coordinates (for a cantilever along x with thickness z: scan = y, the FFM scan
direction across the beam, which loads the torsion through the tip height; lateral = x, along
the beam; normal = z).

Content (SI units)
------------------
* ``modes``: the N retained FEM modes, each with its frequency, family, damping ratio and its
  mass-normalised displacement at the point in the frame, ``phi = (phi_s, phi_l, phi_n)``
  [kg^-1/2].  Per direction d they give the modal oscillators referred to the point
  (eqs 3.1-3.3 generalised, as :mod:`probedyn.lumped.reduce`):

      m_i,d = 1 / phi_i,d^2,   k_i,d = omega_i^2 m_i,d,   c_i,d = 2 zeta_i omega_i m_i,d,

  and the participation ``p_i,d = (phi_i,d^2 / omega_i^2) / C_dd``: the share of the point's
  static compliance carried by mode i.
* ``static_compliance``: the 3 x 3 compliance at the point from a FEM static solve (unit loads
  along the frame axes; ``static_stiffness(d) = 1 / C_dd``, the other components free).
* The residual (static correction) ``R = C - sum_i phi_i phi_i^T / omega_i^2``: the flexibility
  of the discarded modes, so that modal superposition reproduces the dynamic compliance

      H_dd(omega) = sum_i phi_i,d^2 / (omega_i^2 - omega^2 + 2 i zeta_i omega_i omega) + R_dd

  below ``validity_hz``, the frequency of the first discarded mode (:meth:`compliance`).
* ``ritz``: the :class:`~probedyn.lumped.ritz.RitzBasis` (modes + static shapes at the point)
  for attached masses and springs anywhere (nano-placing, holder studies).
* ``actuation``: modal force per volt per electrode, ``{electrode: [f_1, ..., f_N]}`` [N/V]
  (filled by the piezoelectric FEM; empty otherwise); ``actuation_static``: the same for the
  Ritz basis's static pseudo-modes (``t_j^T K u_e``, u_e the coupled static field per volt), the
  static correction of the actuation: with it the reduced static response at the point is the
  piezo FEM's exactly (the point's static shapes are in the basis, so by reciprocity the
  Galerkin output there is exact; :meth:`actuation_matrix`).
* ``provenance``: probe key, parameters, mesh hash, DOFs, source ("FEM" or "Table x.y"),
  probedyn version, build time.

Damping: a quality factor Q gives ``zeta_i = 1/(2Q)`` for every mode; the source's environment
damping mu [N s/m^2] (eq 3.2: ``c_i = mu int phi_i^2``, i.e. mass-proportional damping
``c / m = mu / (rho A)`` on the beam) gives ``zeta_i = (mu / rho A)(1 - s_i) / (2 omega_i)``
with ``s_i`` the mode's kinetic-energy share in point masses (they carry no distributed drag).

A table preset (:meth:`ReducedProbe.from_preset`) is a reduced probe with one mode per
direction the table gives (``m``, ``k``, ``c`` of that direction); its source says so, its
static stiffness is the table's ``k`` and it has no validity limit and no Ritz basis.

Files: :meth:`save` writes ``NAME.json`` (everything but the Ritz matrices) and, with a Ritz
basis, ``NAME.ritz.npz`` beside it (its SHA-256 is recorded in the JSON); both atomically.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import time
from importlib import metadata
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from probedyn.core.errors import DataFormatError, ParameterError
from probedyn.core.io import MAX_DATA_BYTES, read_bytes, read_text, to_jsonable, write_bytes, write_json
from probedyn.core.presets import preset as get_preset
from probedyn.lumped.ritz import RitzBasis

FORMAT = "probedyn-reduced-probe"
FORMAT_VERSION = 1
DIRECTIONS = ("scan", "lateral", "normal")
#: cantilever-like probes (beam axis x, thickness z): FFM scans across the beam (y)
DEFAULT_FRAME = {"scan": (0.0, 1.0, 0.0), "lateral": (1.0, 0.0, 0.0), "normal": (0.0, 0.0, 1.0)}
#: a mode takes part in a direction if it carries at least this share of the static compliance
MIN_PARTICIPATION = 1e-6


def _version() -> str:
    """probedyn's version from the installed distribution's metadata (``probedyn.__version__``
    would be an import of the top package from a lower layer)."""
    try:
        return metadata.version("probedyn")
    except metadata.PackageNotFoundError:  # pragma: no cover - running from a bare checkout
        return "unknown"


def frame_matrix(frame: Mapping[str, Sequence[float]] | None) -> np.ndarray:
    """Rows = unit vectors of scan, lateral, normal in probe coordinates (orthonormal)."""
    fr = dict(DEFAULT_FRAME if frame is None else frame)
    missing = [d for d in DIRECTIONS if d not in fr]
    if missing:
        raise ParameterError(f"frame needs the directions {', '.join(DIRECTIONS)} (missing: {', '.join(missing)})")
    R = np.array([np.asarray(fr[d], dtype=float).reshape(3) for d in DIRECTIONS])
    n = np.linalg.norm(R, axis=1)
    if not np.all(n > 0):
        raise ParameterError("frame directions must be non-zero vectors")
    R = R / n[:, None]
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise ParameterError("frame directions scan, lateral, normal must be mutually orthogonal")
    return R


def _dir_index(direction: str) -> int:
    try:
        return DIRECTIONS.index(direction)
    except ValueError:
        raise ParameterError(f"unknown direction {direction!r} (known: {', '.join(DIRECTIONS)})") from None


@dataclass
class RetainedMode:
    """One retained mode seen at the point: ``shape`` = mass-normalised displacement at the
    point along (scan, lateral, normal) [kg^-1/2]."""

    index: int
    frequency_hz: float
    family: str
    shape: np.ndarray
    damping_ratio: float = 0.0

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.frequency_hz

    def to_dict(self) -> dict[str, Any]:
        return dict(index=self.index, frequency_hz=self.frequency_hz, family=self.family,
                    shape=[float(v) for v in self.shape], damping_ratio=self.damping_ratio)


@dataclass
class Oscillator:
    """A single-DOF model referred to the point along one direction: ``mass`` [kg],
    ``damping`` [N s/m], ``stiffness`` [N/m]; ``mode`` the FEM mode it comes from (0 for a
    table), ``participation`` its share of the static compliance."""

    mass: float
    damping: float
    stiffness: float
    mode: int = 0
    frequency_hz: float = math.nan
    participation: float = math.nan
    family: str = ""

    @property
    def damping_ratio(self) -> float:
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))

    def to_dict(self) -> dict[str, Any]:
        return dict(mass=self.mass, damping=self.damping, stiffness=self.stiffness, mode=self.mode,
                    frequency_hz=self.frequency_hz, participation=self.participation, family=self.family)


@dataclass
class ReducedProbe:
    """See the module docstring.  Build from a probe's FEM with
    ``probedyn.probes.reduce.reduce_probe(...)`` or from a table with :meth:`from_preset`."""

    point: str
    frame: np.ndarray
    modes: list[RetainedMode]
    static_compliance: np.ndarray
    validity_hz: float | None = None
    damping: dict[str, Any] = field(default_factory=lambda: {"kind": "none"})
    ritz: RitzBasis | None = field(default=None, repr=False)
    actuation: dict[str, list[float]] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)
    directions: tuple[str, ...] = DIRECTIONS
    actuation_static: dict[str, list[float]] = field(default_factory=dict)

    def actuation_matrix(self, electrodes: Sequence[str] | None = None,
                         static_correction: bool = True) -> np.ndarray:
        """Generalised force per volt [N/V] on the Ritz coordinates, (r, n_electrodes): the
        retained modes' ``actuation`` and, with ``static_correction``, the static pseudo-modes'
        ``actuation_static`` (r = the Ritz basis's columns; else r = N retained modes)."""
        if not self.actuation:
            raise ParameterError("this reduced probe has no actuation (fill it from the piezo FEM: "
                                 "probedyn.probes.reduced_tracking.actuated_probe)")
        els = list(self.actuation) if electrodes is None else list(electrodes)
        missing = [e for e in els if e not in self.actuation]
        if missing:
            raise ParameterError(f"no actuation for electrode(s) {', '.join(missing)} (known: {', '.join(self.actuation)})")
        A = np.array([self.actuation[e] for e in els], dtype=float).T
        if static_correction:
            if self.ritz is None or not self.actuation_static:
                raise ParameterError("this reduced probe has no static correction of its actuation")
            A = np.vstack([A, np.array([self.actuation_static[e] for e in els], dtype=float).T])
        return A

    # ---- per-direction views ------------------------------------------------------------
    @property
    def source(self) -> str:
        return str(self.provenance.get("source", "FEM"))

    @property
    def n_modes(self) -> int:
        return len(self.modes)

    def _check(self, direction: str) -> int:
        i = _dir_index(direction)
        if direction not in self.directions:
            raise ParameterError(f"the {self.source} probe has no {direction} data (it has: "
                                 f"{', '.join(self.directions)}); use a probe reduced from the FEM")
        return i

    def static_stiffness(self, direction: str) -> float:
        """``1 / C_dd`` [N/m]: force along d at the point over the displacement along d."""
        i = self._check(direction)
        return float(1.0 / self.static_compliance[i, i])

    def residual_compliance(self, direction: str) -> float:
        """``C_dd - sum_i phi_i,d^2 / omega_i^2`` [m/N]: flexibility of the discarded modes."""
        i = self._check(direction)
        return float(self.static_compliance[i, i] - sum(m.shape[i] ** 2 / m.omega**2 for m in self.modes))

    def direction_modes(self, direction: str, min_participation: float = MIN_PARTICIPATION) -> list[Oscillator]:
        """The retained modes that move the point along ``direction`` (participation above
        ``min_participation``), each as its oscillator referred to the point, by frequency."""
        i = self._check(direction)
        C = self.static_compliance[i, i]
        out = []
        for m in self.modes:
            phi = float(m.shape[i])
            if phi == 0.0:
                continue
            p = phi**2 / m.omega**2 / C
            if p < min_participation:
                continue
            mass = 1.0 / phi**2
            out.append(Oscillator(mass=mass, damping=2.0 * m.damping_ratio * m.omega * mass,
                                  stiffness=m.omega**2 * mass, mode=m.index, frequency_hz=m.frequency_hz,
                                  participation=p, family=m.family))
        return out

    def dominant_mode(self, direction: str) -> Oscillator:
        """The retained mode with the largest share of the static compliance along d."""
        osc = self.direction_modes(direction, 0.0)
        if not osc:
            raise ParameterError(f"no retained mode moves the point along {direction}")
        return max(osc, key=lambda o: o.participation)

    def effective_mass(self, direction: str) -> float:
        """Effective mass [kg] at the point of the dominant mode along d (``1/phi_d^2``)."""
        return self.dominant_mode(direction).mass

    def lumped(self, direction: str) -> Oscillator:
        """The single-DOF model a one-mode scheme uses along d: the **static** stiffness (FEM
        static solve: the spring a slow scan loads), the effective mass of the dominant mode and
        that mode's damping."""
        osc = self.dominant_mode(direction)
        return Oscillator(mass=osc.mass, damping=osc.damping, stiffness=self.static_stiffness(direction),
                          mode=osc.mode, frequency_hz=osc.frequency_hz, participation=osc.participation,
                          family=osc.family)

    def oscillators(self, direction: str, n: int | None = None) -> tuple[list[Oscillator], float]:
        """The ``n`` modes with the largest participation along d (by frequency) and the
        residual compliance [m/N] that makes their series sum the static compliance:
        ``u_d = sum_i u_i + r F`` with ``m_i u_i'' + c_i u_i' + k_i u_i = F``."""
        i = self._check(direction)
        osc = self.direction_modes(direction, 0.0)
        if n is not None:
            if n < 1:
                raise ParameterError(f"number of modes must be >= 1, got {n}")
            osc = sorted(sorted(osc, key=lambda o: -o.participation)[:n], key=lambda o: o.frequency_hz)
        r = float(self.static_compliance[i, i] - sum(1.0 / o.stiffness for o in osc))
        return osc, max(r, 0.0)

    def compliance(self, direction: str, frequency_hz: float | np.ndarray, static_correction: bool = True,
                   damped: bool = True) -> np.ndarray:
        """Dynamic compliance ``u_d / F_d`` [m/N] at the point by modal superposition of the
        retained modes (+ the residual when ``static_correction``)."""
        i = self._check(direction)
        w = 2.0 * math.pi * np.asarray(frequency_hz, dtype=float)
        H = np.zeros(w.shape, dtype=complex)
        for m in self.modes:
            z = m.damping_ratio if damped else 0.0
            H += m.shape[i] ** 2 / (m.omega**2 - w**2 + 2j * z * m.omega * w)
        if static_correction:
            H += self.residual_compliance(direction)
        return H

    # ---- table presets --------------------------------------------------------------------
    @classmethod
    def from_preset(cls, key: str) -> "ReducedProbe":
        """The probe of a source table as a reduced probe whose source is the table.

        ``table-2.1`` / ``table-2.2`` (FFM: scan = x of eq 2.13, lateral = y of eq 2.14),
        ``table-4.1`` (nano-pushing tip: k_tx, k_ty, m_tx, m_ty, c_t), ``table-4.3`` (two-mass
        model: the probe is m1, k1 with c1 = 2 zeta1 sqrt(k m), eq 4.7, k and m the series
        values of eq 4.5)."""
        pr = get_preset(key)
        if pr.key in ("table-2.1", "table-2.2"):
            dirs = {"scan": (pr["m_x"], pr["c_x"], pr["k_x"]), "lateral": (pr["m_y"], pr["c_y"], pr["k_y"])}
        elif pr.key == "table-4.1":
            dirs = {"scan": (pr["m_tx"], pr["c_t"], pr["k_tx"]), "lateral": (pr["m_ty"], pr["c_t"], pr["k_ty"])}
        elif pr.key == "table-4.3":
            m1, k1, m2, k2 = pr["m1"], pr["k1"], pr["m2"], pr["k2"]
            m, k = m1 * m2 / (m1 + m2), k1 * k2 / (k1 + k2)
            dirs = {"scan": (m1, 2.0 * pr["zeta1"] * math.sqrt(k * m), k1)}
        else:
            raise ParameterError(f"preset {pr.key!r} does not describe a probe at its tip (probe presets: "
                                 "table-2.1, table-2.2, table-4.1, table-4.3); reduce the probe's FEM instead")
        modes, C = [], np.zeros((3, 3))
        for j, (d, (m, c, k)) in enumerate(dirs.items()):
            i = _dir_index(d)
            shape = np.zeros(3)
            shape[i] = 1.0 / math.sqrt(m)
            omega = math.sqrt(k / m)
            modes.append(RetainedMode(index=j + 1, frequency_hz=omega / (2 * math.pi), family=d, shape=shape,
                                      damping_ratio=c / (2.0 * math.sqrt(k * m))))
            C[i, i] = 1.0 / k
        src = pr.source.split(" (")[0]
        return cls(point="tip", frame=frame_matrix(None), modes=modes, static_compliance=C, validity_hz=None,
                   damping={"kind": "table", "source": src},
                   provenance=dict(source=src, preset=pr.key, title=pr.title, probedyn_version=_version(),
                                   parameters=dict(pr.data)),
                   directions=tuple(d for d in DIRECTIONS if d in dirs))

    # ---- serialisation --------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (everything but the Ritz matrices), with the per-direction
        views (static stiffness, effective mass, modal oscillators) for readers."""
        views = {}
        for d in self.directions:
            try:
                lump = self.lumped(d).to_dict()
            except ParameterError:
                lump = None
            views[d] = dict(static_stiffness=self.static_stiffness(d), residual_compliance=self.residual_compliance(d),
                            lumped=lump, modes=[o.to_dict() for o in self.direction_modes(d)])
        return dict(format=FORMAT, format_version=FORMAT_VERSION, point=self.point,
                    frame={d: self.frame[i].tolist() for i, d in enumerate(DIRECTIONS)},
                    directions=list(self.directions), validity_hz=self.validity_hz, damping=self.damping,
                    modes=[m.to_dict() for m in self.modes], static_compliance=self.static_compliance.tolist(),
                    actuation=self.actuation, actuation_static=self.actuation_static,
                    provenance=self.provenance, per_direction=views,
                    ritz=None if self.ritz is None else self.ritz.describe())

    def summary(self) -> dict[str, Any]:
        """Short provenance + the numbers a scheme uses (for JSON output of commands)."""
        out = dict(source=self.source, point=self.point, validity_hz=self.validity_hz,
                   probe=self.provenance.get("probe", self.provenance.get("preset")),
                   mesh_key=self.provenance.get("mesh_key"), dofs=self.provenance.get("dofs"),
                   n_modes=self.n_modes)
        for d in self.directions:
            try:
                lump = self.lumped(d)
                out[d] = dict(static_stiffness=self.static_stiffness(d), effective_mass=lump.mass,
                              damping=lump.damping, mode=lump.mode, frequency_hz=lump.frequency_hz)
            except ParameterError:
                out[d] = dict(static_stiffness=self.static_stiffness(d))
        return out

    def save(self, path: str | Path, include_basis: bool = True, defer: bool = True) -> Path:
        """Write ``path`` (JSON) and, with a Ritz basis, ``<stem>.ritz.npz`` beside it.

        Both go through :mod:`probedyn.core.io` (atomic): inside an output transaction
        (every CLI command runs in one) they appear when it commits; ``defer=False`` (a cache
        entry) writes them at once."""
        path = Path(path)
        if path.suffix != ".json":
            raise ParameterError(f"reduced probe files end in .json, got {path.name}")
        d = self.to_dict()
        if self.ritz is not None:
            npz = path.with_name(path.stem + ".ritz.npz")
            fh = io.BytesIO()  # an in-memory archive (no file): hashed before the deferred write
            np.savez(fh, **self.ritz.to_arrays(include_basis=include_basis))
            blob = fh.getvalue()
            # hash the bytes in memory: inside an output transaction the rename is deferred
            write_bytes(npz, blob, defer=defer)
            d["ritz_file"] = npz.name
            d["ritz_sha256"] = hashlib.sha256(blob).hexdigest()
            d["ritz_meta"] = to_jsonable(self.ritz.meta)
        write_json(path, d, defer=defer)
        return path

    @classmethod
    def load(cls, path: str | Path) -> "ReducedProbe":
        """Read a file written by :meth:`save` (the Ritz basis is checked against its hash)."""
        path = Path(path)
        # a regular file of bounded size (no FIFO or device), UTF-8; then JSON
        text = read_text(path, what="reduced-probe file", max_bytes=MAX_DATA_BYTES)
        try:
            d = json.loads(text)
        except ValueError as exc:
            raise DataFormatError(f"{path}: not a reduced-probe file ({exc})") from None
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise DataFormatError(f"{path}: not a reduced-probe file (format {d.get('format') if isinstance(d, dict) else None!r})")
        if int(d.get("format_version", 0)) > FORMAT_VERSION:
            raise DataFormatError(f"{path}: written by a newer probedyn (format {d['format_version']})")
        try:
            frame = np.array([d["frame"][k] for k in DIRECTIONS], dtype=float)
            modes = [RetainedMode(int(m["index"]), float(m["frequency_hz"]), str(m["family"]),
                                  np.asarray(m["shape"], dtype=float), float(m["damping_ratio"])) for m in d["modes"]]
            C = np.asarray(d["static_compliance"], dtype=float)
            ritz = None
            if d.get("ritz_file"):
                npz = path.with_name(d["ritz_file"])  # beside the JSON file (a name, not a path)
                blob = read_bytes(npz, path.parent, what="Ritz file", max_bytes=MAX_DATA_BYTES)
                if hashlib.sha256(blob).hexdigest() != d.get("ritz_sha256"):
                    raise DataFormatError(f"{npz}: Ritz file does not match the hash recorded in {path.name}")
                with np.load(npz, allow_pickle=False) as z:
                    ritz = RitzBasis.from_arrays({k: z[k] for k in z.files}, meta=d.get("ritz_meta"))
            return cls(point=str(d["point"]), frame=frame, modes=modes, static_compliance=C,
                       validity_hz=d.get("validity_hz"), damping=d.get("damping", {"kind": "none"}), ritz=ritz,
                       actuation={k: list(v) for k, v in (d.get("actuation") or {}).items()},
                       provenance=d.get("provenance", {}), directions=tuple(d.get("directions", DIRECTIONS)),
                       actuation_static={k: list(v) for k, v in (d.get("actuation_static") or {}).items()})
        except (KeyError, TypeError, ValueError, OSError) as exc:
            raise DataFormatError(f"{path}: malformed reduced-probe file ({exc})") from None


# ------------------------------------------------------------------------------------------
# Construction from an FE model (probe-agnostic; the probe registry side is probes/reduce.py)
# ------------------------------------------------------------------------------------------

def damping_ratios(omega: np.ndarray, Q: float | None = None, mu: float | None = None,
                   mass_per_length: float | None = None, point_mass_share: np.ndarray | None = None) -> tuple[np.ndarray, dict]:
    """Modal damping ratios from a quality factor ``Q`` or the environment damping ``mu`` of
    eq 3.2 (module docstring).  Neither: undamped."""
    omega = np.asarray(omega, dtype=float)
    if Q is not None and mu is not None:
        raise ParameterError("give either a quality factor Q or an environment damping mu, not both")
    if Q is not None:
        if not (math.isfinite(Q) and Q > 0):
            raise ParameterError(f"quality factor Q must be positive, got {Q}")
        return np.full(omega.shape, 0.5 / Q), {"kind": "Q", "Q": float(Q)}
    if mu is not None:
        if not (math.isfinite(mu) and mu >= 0):
            raise ParameterError(f"environment damping mu must be >= 0, got {mu}")
        if not mass_per_length or mass_per_length <= 0:
            raise ParameterError("mu damping (eq 3.2) needs the mass per unit length rho A of the beam")
        s = np.zeros_like(omega) if point_mass_share is None else np.asarray(point_mass_share, dtype=float)
        alpha = mu / mass_per_length
        return alpha * (1.0 - s) / (2.0 * omega), {"kind": "mu (eq 3.2)", "mu": float(mu),
                                                    "mass_per_length": float(mass_per_length)}
    return np.zeros(omega.shape), {"kind": "none"}


def reduce_model(model: Any, point: str, n_modes: int = 6, frame: Mapping[str, Sequence[float]] | None = None,
                 Q: float | None = None, mu: float | None = None, mass_per_length: float | None = None,
                 provenance: Mapping[str, Any] | None = None, families: Sequence[str] | None = None,
                 solver: str = "auto") -> ReducedProbe:
    """A :class:`ReducedProbe` of an FE model at ``point``: ``n_modes + 1`` FEM modes (the last
    one gives ``validity_hz``), the Ritz basis of the first ``n_modes`` with static shapes at
    the point along the frame axes, and the point's static compliance from the FEM static
    solves ``K^-1 A^T d`` (the same solves that make the static shapes).  ``families``: the
    FEM's mode classification (optional, for labels)."""
    t0 = time.perf_counter()
    R = frame_matrix(frame)
    full = RitzBasis.from_model(model, n_modes + 1, attachments=[(point, R)], solver=solver)
    validity = float(full.frequencies_hz[n_modes])
    # the FEM static solves K^-1 A^T d (loads along the frame axes): displacement U (3, 3) in
    # probe axes, column j for the load along frame axis j, so C_frame = R U
    resp = full.meta["static_response"][str(point)]
    C = R @ np.asarray(resp["displacement"], dtype=float)
    ritz = full.truncate(n_modes)  # n modes + static shapes, no second eigen-solve
    B = ritz.operator(point)[:, :n_modes]  # (3, n) probe axes
    phi = R @ B  # frame components
    share = None
    pms = list(getattr(model, "point_masses", None) or [])
    if pms or getattr(model, "lumped_tip", None) is not None:
        share = np.zeros(n_modes)
        for pm in pms:
            u = ritz.operator(pm.point)[:, :n_modes]
            share += pm.mass * (u**2).sum(axis=0)
        lt = getattr(model, "lumped_tip", None)
        if lt is not None:
            u = ritz.operator("lumped_tip")[:, :n_modes]
            share += lt.mass * (u**2).sum(axis=0)
    omega = ritz.omega[:n_modes]
    zeta, dinfo = damping_ratios(omega, Q=Q, mu=mu, mass_per_length=mass_per_length, point_mass_share=share)
    fams = list(families) if families is not None else [""] * n_modes
    modes = [RetainedMode(index=i + 1, frequency_hz=float(omega[i] / (2 * math.pi)), family=fams[i] if i < len(fams) else "",
                          shape=phi[:, i].copy(), damping_ratio=float(zeta[i])) for i in range(n_modes)]
    Cf = C
    prov = dict(source="FEM", probedyn_version=_version(), dofs=ritz.meta.get("dofs"),
                mesh_key=ritz.meta.get("mesh_key"), n_modes=n_modes, point=point,
                reduction_s=time.perf_counter() - t0)
    prov.update(provenance or {})
    return ReducedProbe(point=point, frame=R, modes=modes, static_compliance=0.5 * (Cf + Cf.T), validity_hz=validity,
                        damping=dinfo, ritz=ritz, provenance=prov)
