"""Measurement files: a CSV of data with a TOML sidecar, validated before anything is computed.

``probedyn diagnose`` accepts the sidecar (``name.toml``) or its CSV (then ``name.toml`` beside it
is read). The sidecar names the data file (``[measurement] data``) and says what was measured.
Every key is checked: an unknown table or key is an error that suggests the closest known one
(``[probe] thicknes`` -> did you mean 'thickness'?); values are SI and checked for plausibility
(a thickness of 2 m, kHz typed as Hz, ``Q_sigma = 0``, a negative frequency, a duplicated mode, a
tip position outside [0, 1] are one-line errors naming file, line and column where there is one).

Kinds (``[measurement] kind``) and their CSV columns:

===============  ===========================================================================
``modal``        ``family`` (flapwise | lateral | torsion | axial; "flap" accepted), ``order``,
                 ``frequency_Hz``; optional ``frequency_sigma_Hz``, ``Q``, ``Q_sigma``, ``length_m``
``spectrum``     ``frequency_Hz``, ``value`` (``[measurement] quantity`` = ``psd`` [m^2/Hz] or
                 ``amplitude`` [m/sqrt(Hz)]; ``averages`` = periodograms averaged)
``timeseries``   ``time_s``, ``displacement_m`` (uniform sampling; reduced to a Welch PSD)
``friction``     ``scan``, ``position_m`` (support position), ``lateral_force_N``; optional
                 ``time_s``; per scan a ``[[scans]]`` table (``id``, ``speed`` m/s, ``load`` N)
``force``        ``z_m`` (piezo position, increasing towards the sample) and ``force_N`` or
                 ``deflection_m`` or ``deflection_V``; optional ``segment`` (0 approach, 1 retract)
===============  ===========================================================================

Tables:

* ``[probe]`` (modal, spectrum, timeseries): ``name`` = a registered probe (default
  ``cantilever``) or ``file`` = a probe TOML (relative to the sidecar), then that probe's own
  parameters (``probedyn params``; ``E``, ``rho``, ``nu`` accepted for youngs_modulus, density,
  poisson_ratio); ``known`` = quantities measured independently (no cause may change them:
  thickness, width, length, modulus, density, mass, clamp); ``tip_position`` (x/L of a declared
  ``tip_mass``, default 1).
* ``[medium]``: ``name`` (vacuum, air, nitrogen, water, ethanol) or ``density`` and
  ``viscosity``; ``temperature`` [K]. A declared medium is part of the baseline.
* ``[noise]``: ``frequency_rel``, ``Q_rel`` (modal), ``force`` [N] (friction, force curves);
  ``correlation`` (friction, force curves): the noise's lag-one correlation between consecutive
  samples, 0 ... 0.95, where measured (e.g. from a record off the surface): AR(1) noise taken as
  declared instead of estimated (:mod:`probedyn.diagnose.noise`).
* ``[baseline]``: ``free`` = quantities calibrated by the baseline fit (thickness, width,
  length, modulus, density; friction: nothing else).
* modal, spectrum, timeseries: ``[static]`` ``spring_constant`` [N/m] = a measured static spring constant of the lever at the
  probe's declared length, for a load at its free end along the thickness (a reference lever, a force
  standard; not a thermal tune, which infers it from mode 1), ``sigma`` [N/m] its 1-sigma uncertainty
  (default :data:`STATIC_K_REL_DEFAULT` = 5 % of it).
* friction: ``[lever]`` ``k_x`` [N/m], optionally ``k_y`` [N/m] (the stiffness across the scan), ``m_x`` [kg],
  ``c_x`` [N s/m] or ``Q_x``; ``[sample]``
  ``lattice`` [m]; ``[measurement] sampling`` = ``point`` or ``interval-mean``.
* force: ``[lever]`` ``k`` [N/m], ``sensitivity`` [m/V] (for deflection_V); ``[tip]``
  ``radius`` [m], ``E``, ``nu``; ``[sample]`` ``E``, ``nu``.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.core.errors import DataFormatError, ProbedynError
from probedyn.core.io import MAX_DATA_BYTES, read_text, resolve_input
from probedyn.core.params import load_toml
from probedyn.diagnose.hydrodynamics import MEDIA
from probedyn.diagnose.noise import RHO_MAX

__all__ = ["read_measurement", "read_csv", "Measurement", "ModalData", "SpectrumData", "FrictionData",
           "FrictionScan", "ForceData", "FAMILIES", "KINDS"]

KINDS = ("modal", "spectrum", "timeseries", "friction", "force")
STATIC_K_REL_DEFAULT = 0.05  # default relative uncertainty of a declared static spring constant
F_MAX = 1e11  # Hz: above any mechanical mode of a probe (a 1 um silicon beam's first mode is ~ 1e9 Hz)
ORDER_MAX = 50  # highest mode order of one family the diagnosis resolves
FAMILIES = ("flapwise", "lateral", "torsion", "axial")
FAMILY_ALIASES = {"flap": "flapwise", "flexural": "flapwise", "vertical": "flapwise", "torsional": "torsion",
                  "twist": "torsion", "in-plane": "lateral", "longitudinal": "axial"}
PROBE_ALIASES = {"E": "youngs_modulus", "rho": "density", "nu": "poisson_ratio"}
QUANTITIES = ("thickness", "width", "length", "modulus", "density", "mass", "clamp", "stress", "medium",
              "temperature", "tip_radius", "adhesion", "lattice", "scanner", "detector", "drag",
              "topography")

_MEASUREMENT_KEYS = ("kind", "data", "description", "source", "licence", "quantity", "averages", "families",
                     "sampling", "segments")
#: what a spectrum's (or time series') values record: the tip's displacement (an interferometer, or any PSD
#: calibrated in displacement at the free end), or an optical lever's deflection signal, the lever's slope at the
#: laser spot times the static calibration (InvOLS) of an end load
DETECTORS = ("displacement", "optical-lever")

TABLES: dict[str, dict[str, tuple[str, ...]]] = {
    "measurement": {"*": _MEASUREMENT_KEYS, "spectrum": (*_MEASUREMENT_KEYS, "detector", "spot"),
                    "timeseries": (*_MEASUREMENT_KEYS, "detector", "spot")},
    "medium": {"*": ("name", "density", "viscosity", "temperature")},
    "noise": {"modal": ("frequency_rel", "Q_rel"), "spectrum": ("frequency_rel", "Q_rel"),
              "timeseries": ("frequency_rel", "Q_rel"), "friction": ("force", "force_part", "correlation"),
              "force": ("force", "deflection", "correlation")},
    "baseline": {"*": ("free",)},
    "lever": {"friction": ("k_x", "k_y", "m_x", "c_x", "Q_x"), "force": ("k", "sensitivity", "f0", "Q")},
    "sample": {"friction": ("lattice",), "force": ("E", "nu")},
    "tip": {"force": ("radius", "E", "nu")},
    "static": {"*": ("spring_constant", "sigma")},
}
KIND_TABLES = {
    "modal": ("measurement", "probe", "medium", "noise", "baseline", "static"),
    "spectrum": ("measurement", "probe", "medium", "noise", "baseline", "static"),
    "timeseries": ("measurement", "probe", "medium", "noise", "baseline", "static"),
    "friction": ("measurement", "lever", "sample", "medium", "noise", "baseline", "scans"),
    "force": ("measurement", "lever", "tip", "sample", "medium", "noise", "baseline"),
}


def _did_you_mean(name: str, known) -> str:
    close = difflib.get_close_matches(str(name), list(known), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else f" (known: {', '.join(known)})"


#: field separators an instrument export uses, in the order they are looked for in the header line (none of
#: them: fields separated by runs of blanks, as a space-aligned text export)
SEPARATORS = (",", ";", "\t")


def _separator(header_line: str) -> str | None:
    return next((c for c in SEPARATORS if c in header_line), None)


def read_csv(path: Path, required: list[str], optional: list[str], text_cols: tuple[str, ...] = ()) -> dict[str, Any]:
    """Read a numeric CSV with a header; '#' lines are comments. Columns as arrays (text columns
    as lists); every error names file, line and column. The field separator is the header's: a comma,
    else a semicolon, else a tab, else runs of blanks (:data:`SEPARATORS`); the decimal mark is a point
    (a decimal comma is refused as an unreadable number, never reinterpreted)."""
    # a regular file of bounded size, UTF-8 (FIFOs, devices and folders refused before opening)
    lines = read_text(path, what="data file", max_bytes=MAX_DATA_BYTES).splitlines()
    header = None
    hline = 0
    sep: str | None = ","
    rows: list[tuple[int, list[str]]] = []
    for i, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        if header is None:
            sep = _separator(s)
        cells = [c.strip() for c in s.split(sep)]
        if header is None:
            header, hline = cells, i
            continue
        rows.append((i, cells))
    if header is None:
        raise DataFormatError(f"{path}, line 1, column 1: no header line (expected columns {', '.join(required)})")
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise DataFormatError(f"{path}, line {hline}, column {header.index(dup) + 1}: column '{dup}' appears twice")
    for j, name in enumerate(header, start=1):
        if name not in required and name not in optional:
            raise DataFormatError(f"{path}, line {hline}, column {j}: unknown column '{name}'"
                                  + _did_you_mean(name, required + optional))
    for name in required:
        if name not in header:
            raise DataFormatError(f"{path}, line {hline}, column {len(header) + 1}: missing required column '{name}'")
    if not rows:
        raise DataFormatError(f"{path}, line {hline + 1}, column 1: no data rows")
    cols: dict[str, list] = {h: [] for h in header}
    for lineno, cells in rows:
        if len(cells) != len(header):
            raise DataFormatError(f"{path}, line {lineno}, column {min(len(cells), len(header)) + 1}: expected "
                                  f"{len(header)} fields, found {len(cells)}")
        for j, (name, c) in enumerate(zip(header, cells), start=1):
            if name in text_cols:
                cols[name].append(c)
                continue
            if c == "":
                cols[name].append(math.nan)
                continue
            try:
                v = float(c)
            except ValueError:
                raise DataFormatError(f"{path}, line {lineno}, column {j} ({name}): cannot read '{c}' as a number") from None
            if not math.isfinite(v):
                raise DataFormatError(f"{path}, line {lineno}, column {j} ({name}): value '{c}' is not finite")
            cols[name].append(v)
    out: dict[str, Any] = {k: (v if k in text_cols else np.asarray(v, dtype=float)) for k, v in cols.items()}
    out["_lines"] = np.array([ln for ln, _ in rows])
    out["_header"] = header
    out["_path"] = path
    return out


def col_error(data: dict, name: str, k: int, msg: str) -> DataFormatError:
    j = data["_header"].index(name) + 1
    return DataFormatError(f"{data['_path']}, line {data['_lines'][k]}, column {j} ({name}): {msg}")


# ------------------------------------------------------------------------------------------
# Typed measurements
# ------------------------------------------------------------------------------------------


@dataclass
class Measurement:
    path: Path
    kind: str
    meta: dict
    description: str = ""
    medium: tuple[float, float] | None = None  # declared (rho_f, eta_f); None = not declared
    medium_name: str | None = None
    temperature: float | None = None
    known: frozenset = frozenset()
    free: tuple[str, ...] = ()
    #: the noise's lag-one correlation between consecutive samples as declared ([noise] correlation); None:
    #: not declared (estimated from the record where it has recording sequences)
    noise_correlation: float | None = None


@dataclass
class ModalData(Measurement):
    probe: Any = None
    probe_values: dict = field(default_factory=dict)
    family: np.ndarray = None  # type: ignore[assignment]
    order: np.ndarray = None  # type: ignore[assignment]
    freq: np.ndarray = None  # type: ignore[assignment]
    freq_sigma: np.ndarray = None  # type: ignore[assignment]
    Q: np.ndarray = None  # type: ignore[assignment]
    Q_sigma_rel: np.ndarray = None  # type: ignore[assignment]
    length: np.ndarray = None  # type: ignore[assignment]
    known_mass: tuple[float, float] | None = None  # (kg, x/L) not at the free end
    static: tuple[float, float] | None = None  # measured static spring constant and its sigma [N/m] (end load)
    noise_stated: bool = True
    csv: dict | None = None


@dataclass
class SpectrumData(Measurement):
    probe: Any = None
    probe_values: dict = field(default_factory=dict)
    freq: np.ndarray = None  # type: ignore[assignment]
    value: np.ndarray = None  # type: ignore[assignment]
    quantity: str = "psd"
    averages: int | None = None
    families: tuple[str, ...] = ()
    freq_rel: float = 1e-6
    known_mass: tuple[float, float] | None = None
    static: tuple[float, float] | None = None  # as ModalData.static
    detector: str = "displacement"  # one of DETECTORS
    spot: float = 1.0  # an optical lever's laser spot, x / L from the clamp


@dataclass
class FrictionScan:
    id: int
    speed: float
    load: float
    position: np.ndarray
    force: np.ndarray
    time: np.ndarray
    direction: np.ndarray  # +1 trace (forward), -1 retrace, per sample
    height: np.ndarray | None = None  # the topography the instrument recorded with each sample [m] (optional)


@dataclass
class FrictionData(Measurement):
    scans: list[FrictionScan] = field(default_factory=list)
    k_x: float = 1.0
    k_y: float | None = None  # the lever's lateral stiffness across the scan [N/m], where declared
    m_x: float | None = None
    c_x: float | None = None
    Q_x: float | None = None
    lattice: float = 0.5e-9
    sigma_force: float = 1e-11
    sampling: str = "interval-mean"
    noise_stated: bool = True
    #: what the stated ``[noise] force`` covers: "total" (every source, the tip's thermal motion included: its mean
    #: square is shared out by the thermal force noise's own pattern) or "detector" (the thermal force noise is added)
    noise_part: str = "total"
    #: "stick-slip" (samples resolve the lattice: :mod:`..friction`) or "loop" (each sample averages many lattice
    #: periods: :mod:`..friction_loop`), from the sample spacing and the declared lattice
    regime: str = "stick-slip"


@dataclass
class ForceData(Measurement):
    z: np.ndarray = None  # type: ignore[assignment]
    force: np.ndarray = None  # type: ignore[assignment]
    segment: np.ndarray = None  # type: ignore[assignment]
    k: float = 1.0
    sensitivity: float | None = None
    tip_radius: float = 20e-9
    E_tip: float = 169e9
    nu_tip: float = 0.28
    E_sample: float | None = None
    nu_sample: float = 0.3
    sigma_force: float | None = None
    noise_stated: bool = True
    time: np.ndarray | None = None  # recording time [s] (column time_s); None: the row order at uniform sampling


# ------------------------------------------------------------------------------------------
# Sidecar
# ------------------------------------------------------------------------------------------


def _sidecar(path: Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise DataFormatError(f"{path}: no such file")
    if not path.is_file():
        raise DataFormatError(f"{path}: not a regular file (a measurement is a TOML sidecar or its CSV)")
    if path.suffix.lower() == ".toml":
        return path
    side = path.with_suffix(".toml")
    if not side.exists():
        raise DataFormatError(f"{path}: no TOML sidecar {side.name} beside the data file")
    return side


def _num(meta: dict, section: str, key: str, path: Path, default: Any = None, positive: bool = False,
         lo: float | None = None, hi: float | None = None, unit: str = "") -> Any:
    sec = meta.get(section, {})
    if key not in sec:
        if default is None:
            raise DataFormatError(f"{path}: missing '{key}' in [{section}]")
        return default
    v = sec[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise DataFormatError(f"{path}: [{section}] {key} must be a finite number, got {v!r}")
    if positive and v <= 0:
        raise DataFormatError(f"{path}: [{section}] {key} must be positive, got {v!r}")
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        hint = " (values are SI)" if unit else ""
        raise DataFormatError(f"{path}: [{section}] {key} = {v:g} {unit} is outside the plausible range "
                              f"[{lo:g}, {hi:g}] {unit}{hint}".replace("  ", " "))
    return float(v)


def _validate_tables(meta: dict, side: Path, kind: str) -> None:
    allowed = KIND_TABLES[kind]
    for t, v in meta.items():
        if t not in allowed:
            raise DataFormatError(f"{side}: unknown table [{t}] for a {kind} measurement" + _did_you_mean(t, allowed))
        if t in ("probe", "scans"):
            continue
        if not isinstance(v, dict):
            raise DataFormatError(f"{side}: [{t}] must be a table")
        keys = TABLES[t].get(kind, TABLES[t].get("*", ()))
        for k in v:
            if k not in keys:
                raise DataFormatError(f"{side}: unknown key '{k}' in [{t}]" + _did_you_mean(k, keys))


def read_measurement(path: str | Path) -> Measurement:
    """Read and validate a measurement (sidecar or CSV path) into a typed object."""
    side = _sidecar(Path(path))
    meta = load_toml(side)
    m = meta.get("measurement")
    if not isinstance(m, dict):
        raise DataFormatError(f"{side}: missing [measurement] table (kind, data)")
    kind = m.get("kind")
    if kind not in KINDS:
        raise DataFormatError(f"{side}: [measurement] kind must be one of {', '.join(KINDS)}, got {kind!r}"
                              + (_did_you_mean(kind, KINDS) if isinstance(kind, str) else ""))
    _validate_tables(meta, side, kind)
    data = m.get("data")
    if not isinstance(data, str):
        raise DataFormatError(f"{side}: [measurement] data must name the CSV file")
    # the data file is confined to the sidecar's folder (a sidecar cannot make probedyn read
    # /etc/passwd or a device); existence and file type are checked when it is read
    csv = resolve_input(data, side.parent, what=f"{side.name}: data file")
    if not csv.exists():
        raise DataFormatError(f"{side}: data file {csv} not found")
    common = _common(meta, side, kind)
    if kind == "modal":
        return _read_modal(side, csv, meta, common)
    if kind == "friction":
        from probedyn.diagnose.friction import read_friction

        return read_friction(side, csv, meta, common)
    if kind == "force":
        from probedyn.diagnose.forcecurve import read_force

        return read_force(side, csv, meta, common)
    return _read_spectrum(side, csv, meta, common, kind)


def _common(meta: dict, side: Path, kind: str) -> dict[str, Any]:
    out: dict[str, Any] = {"path": side, "kind": kind, "meta": meta,
                           "description": str(meta["measurement"].get("description", ""))}
    med = meta.get("medium")
    if med is not None:
        name = med.get("name")
        if name is not None:
            name = str(name).lower()
            if name not in MEDIA:
                raise DataFormatError(f"{side}: [medium] name '{name}' unknown" + _did_you_mean(name, MEDIA)
                                      + "; or give density and viscosity")
            rho0, eta0 = MEDIA[name]
        else:
            rho0 = eta0 = None
        if "density" in med or "viscosity" in med:
            rho_f = _num(meta, "medium", "density", side, default=rho0, lo=0.0, hi=2.5e4, unit="kg/m^3")
            eta_f = _num(meta, "medium", "viscosity", side, default=eta0, positive=True, lo=1e-6, hi=10.0, unit="Pa s")
            if rho_f is None or eta_f is None:
                raise DataFormatError(f"{side}: [medium] needs a name or both density and viscosity")
        else:
            rho_f, eta_f = rho0, eta0
        if name is not None or "density" in med:
            out["medium"] = (float(rho_f), float(eta_f))
            out["medium_name"] = name or "declared fluid"
        if "temperature" in med:
            # friction: 0 K declares an athermal record (a simulation's), where no slip is activated; spectra need
            # thermal motion and fluids a real temperature, hence 1 mK there
            lo = 0.0 if kind == "friction" else 1e-3
            out["temperature"] = _num(meta, "medium", "temperature", side, lo=lo, hi=2000.0, unit="K")
    free = meta.get("baseline", {}).get("free", ())
    if isinstance(free, str) or not all(isinstance(x, str) for x in free):
        raise DataFormatError(f"{side}: [baseline] free must be a list of names")
    for q in free:
        if q not in QUANTITIES:
            raise DataFormatError(f"{side}: [baseline] free entry '{q}' is not a quantity" + _did_you_mean(q, QUANTITIES))
    if len(set(free)) != len(free):
        raise DataFormatError(f"{side}: [baseline] free lists a quantity twice")
    out["free"] = tuple(free)
    if "correlation" in meta.get("noise", {}):
        out["noise_correlation"] = _num(meta, "noise", "correlation", side, lo=0.0, hi=RHO_MAX)
    return out


def probe_from_meta(meta: dict, side: Path) -> tuple[Any, dict, frozenset, tuple[float, float] | None]:
    """The registered probe, its resolved parameter values, the declared known quantities and a
    known point mass not at the free end."""
    from probedyn.probes import get_probe

    sec = dict(meta.get("probe") or {})
    if not sec:
        raise DataFormatError(f"{side}: missing [probe] table (name = a registered probe, and its parameters)")
    known = sec.pop("known", [])
    if isinstance(known, str) or not all(isinstance(x, str) for x in known):
        raise DataFormatError(f"{side}: [probe] known must be a list of quantity names")
    for q in known:
        if q not in QUANTITIES:
            raise DataFormatError(f"{side}: [probe] known entry '{q}' is not a quantity" + _did_you_mean(q, QUANTITIES))
    tip_pos = sec.pop("tip_position", None)
    name = sec.pop("name", None)
    pfile = sec.pop("file", None)
    if name is not None and pfile is not None:
        raise DataFormatError(f"{side}: [probe] give name or file, not both")
    try:
        if pfile is not None:
            probe, over = get_probe(str(side.parent / str(pfile)))
        else:
            probe, over = get_probe(str(name or "cantilever"))
    except ProbedynError as exc:
        msg = str(exc)
        if "unknown probe" in msg and "did you mean" not in msg:
            from probedyn.probes import list_probes

            msg += _did_you_mean(str(name), list_probes())
        raise DataFormatError(f"{side}: [probe] {msg}") from None
    for k, v in sec.items():
        key = PROBE_ALIASES.get(k, k)
        if key not in probe.params:
            raise DataFormatError(f"{side}: unknown key '{k}' in [probe] for probe '{probe.name}'"
                                  + _did_you_mean(k, [p.name for p in probe.params] + ["name", "file", "known",
                                                                                      "tip_position"]))
        over[key] = v
    known_mass = None
    if tip_pos is not None:
        if isinstance(tip_pos, bool) or not isinstance(tip_pos, (int, float)) or not 0.0 <= tip_pos <= 1.0:
            raise DataFormatError(f"{side}: [probe] tip_position = {tip_pos!r} must be a fraction x/L in [0, 1]")
        if float(tip_pos) < 1.0 and over.get("tip_mass"):
            known_mass = (float(over.pop("tip_mass")), float(tip_pos))
    try:
        values = probe.resolve(over)
    except ProbedynError as exc:
        msg = f"{side}: [probe] {exc}"
        big = [k for k, v in over.items() if k in probe.params and probe.params[k].unit == "m"
               and isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 1e-3 and k in str(exc)]
        if big:
            v = over[big[0]]
            msg += f" (values are SI metres: {v:g} um is {v * 1e-6:g} m)"
        raise DataFormatError(msg) from None
    return probe, values, frozenset(known), known_mass


def _families(data: dict, name: str) -> np.ndarray:
    out = []
    for k, s in enumerate(data[name]):
        f = FAMILY_ALIASES.get(s.lower(), s.lower())
        if f not in FAMILIES:
            raise col_error(data, name, k, f"'{s}' is not a mode family" + _did_you_mean(s.lower(), FAMILIES))
        out.append(f)
    return np.array(out)


def _noise(meta: dict, side: Path, key: str, default: float, lo: float, hi: float, unit: str = "") -> tuple[float, bool]:
    if key in meta.get("noise", {}):
        return _num(meta, "noise", key, side, positive=True, lo=lo, hi=hi, unit=unit), True
    return default, False


def _read_modal(side: Path, csv: Path, meta: dict, common: dict) -> ModalData:
    probe, values, known, known_mass = probe_from_meta(meta, side)
    d = read_csv(csv, ["family", "order", "frequency_Hz"], ["frequency_sigma_Hz", "Q", "Q_sigma", "length_m"],
                 text_cols=("family",))
    n = len(d["frequency_Hz"])
    fam = _families(d, "family")
    f = d["frequency_Hz"]
    for k in range(n):
        o = d["order"][k]
        if not (o >= 1 and float(o).is_integer()):
            raise col_error(d, "order", k, f"order must be an integer >= 1, got {o:g}")
        if not f[k] > 0:
            raise col_error(d, "frequency_Hz", k, f"frequency must be positive, got {f[k]:g} Hz")
        if f[k] > F_MAX:
            raise col_error(d, "frequency_Hz", k, f"frequency {f[k]:g} Hz is above {F_MAX:g} Hz: not a mechanical "
                                                  "mode of a probe (values are Hz)")
        if o > ORDER_MAX:
            raise col_error(d, "order", k, f"order {o:g} is beyond {ORDER_MAX} (a mode order counts the modes of one "
                                           "family from 1)")
    rel, stated = _noise(meta, side, "frequency_rel", 1e-3, 1e-9, 0.5)
    sig = d.get("frequency_sigma_Hz", np.full(n, np.nan)).copy()
    for k in range(n):
        if not np.isnan(sig[k]) and not sig[k] > 0:
            raise col_error(d, "frequency_sigma_Hz", k, f"uncertainty must be positive, got {sig[k]:g}")
        if not np.isnan(sig[k]) and sig[k] > 0.5 * f[k]:
            raise col_error(d, "frequency_sigma_Hz", k, f"uncertainty {sig[k]:g} Hz exceeds half the frequency")
    has_sig = "frequency_sigma_Hz" in d and not np.all(np.isnan(sig))
    sig = np.where(np.isnan(sig), rel * f, sig)
    Q = d.get("Q", np.full(n, np.nan))
    for k in range(n):
        if not np.isnan(Q[k]) and not (0.5 < Q[k] < 1e9):
            raise col_error(d, "Q", k, f"Q = {Q[k]:g} is not a quality factor in (0.5, 1e9)")
    qrel, _ = _noise(meta, side, "Q_rel", 0.05, 1e-6, 5.0)
    qs = d.get("Q_sigma", np.full(n, np.nan))
    for k in range(n):
        if not np.isnan(qs[k]):
            if not qs[k] > 0:
                raise col_error(d, "Q_sigma", k, f"Q_sigma must be positive, got {qs[k]:g}")
            if np.isnan(Q[k]):
                raise col_error(d, "Q_sigma", k, "Q_sigma given without a Q")
    qsr = np.where(np.isnan(qs), qrel, qs / np.where(np.isnan(Q), 1.0, Q))
    L = d.get("length_m", np.full(n, np.nan))
    lo, hi = probe.params["length"].lo if "length" in probe.params else None, None
    for k in range(n):
        if not np.isnan(L[k]) and not (0 < L[k] <= 100):
            raise col_error(d, "length_m", k, f"length {L[k]:g} m is not a length in (0, 100] m (SI)")
    if "length" in values:
        L = np.where(np.isnan(L), values["length"], L)
    elif not np.all(np.isnan(L)):
        raise DataFormatError(f"{csv}: length_m given but probe '{probe.name}' has no length parameter")
    else:
        L = np.full(n, np.nan)
    seen: dict[tuple, int] = {}
    for k, key in enumerate(zip(fam, d["order"].astype(int), np.round(np.nan_to_num(L), 15))):
        if key in seen:
            raise col_error(d, "order", k, f"mode {key[0]} {key[1]} appears twice (first on line {d['_lines'][seen[key]]})")
        seen[key] = k
    return ModalData(**common, probe=probe, probe_values=values, family=fam, order=d["order"].astype(int), freq=f,
                     freq_sigma=sig, Q=Q, Q_sigma_rel=qsr, length=L, known=known, known_mass=known_mass,
                     static=_static(meta, side), noise_stated=stated or has_sig, csv=d)


def _read_spectrum(side: Path, csv: Path, meta: dict, common: dict, kind: str) -> SpectrumData:
    probe, values, known, known_mass = probe_from_meta(meta, side)
    mm = meta["measurement"]
    if kind == "spectrum":
        d = read_csv(csv, ["frequency_Hz", "value"], [])
        f, v = d["frequency_Hz"], d["value"]
        if np.any(f <= 0):
            raise col_error(d, "frequency_Hz", int(np.nonzero(f <= 0)[0][0]), "frequencies must be positive")
        if np.any(np.diff(f) <= 0):
            raise col_error(d, "frequency_Hz", int(np.nonzero(np.diff(f) <= 0)[0][0]) + 1, "frequencies must increase")
        if np.any(f > F_MAX):
            raise col_error(d, "frequency_Hz", int(np.nonzero(f > F_MAX)[0][0]), f"frequency above {F_MAX:g} Hz: not "
                                                                                 "a mechanical mode of a probe (values are Hz)")
        if np.any(v < 0):
            raise col_error(d, "value", int(np.nonzero(v < 0)[0][0]), "spectral values must be >= 0")
        if len(v) < 16 or not np.ptp(v) > 0:
            raise DataFormatError(f"{csv}: the data cannot inform the fit: " + (
                f"{len(v)} spectral values (need >= 16)" if len(v) < 16 else "the spectrum is flat (no peak)"))
        quantity = str(mm.get("quantity", "psd"))
        if quantity not in ("psd", "amplitude"):
            raise DataFormatError(f"{side}: [measurement] quantity must be psd or amplitude" + _did_you_mean(quantity, ("psd", "amplitude")))
        if quantity == "amplitude":
            v = v**2
        averages = mm.get("averages")
        if averages is not None and (isinstance(averages, bool) or not isinstance(averages, int) or averages < 1):
            raise DataFormatError(f"{side}: [measurement] averages must be an integer >= 1")
    else:
        d = read_csv(csv, ["time_s", "displacement_m"], [])
        t, x = d["time_s"], d["displacement_m"]
        if len(t) < 64:
            raise DataFormatError(f"{csv}: the data cannot inform the fit: {len(t)} samples (a spectrum needs >= 64)")
        if not np.ptp(x) > 0:
            raise DataFormatError(f"{csv}: the data cannot inform the fit: the displacement is constant")
        dt = np.diff(t)
        if np.any(dt <= 0):
            raise col_error(d, "time_s", int(np.nonzero(dt <= 0)[0][0]) + 1, "times must increase")
        if np.max(np.abs(dt - dt.mean())) > 1e-3 * dt.mean():
            raise col_error(d, "time_s", int(np.argmax(np.abs(dt - dt.mean()))) + 1, "sampling must be uniform (to 0.1 %)")
        from scipy.signal import welch

        nseg = 8  # Hann windows with 50 % overlap: 2 N / nperseg - 1 = 8 segments
        nper = max(16, int(2 * len(x) / (nseg + 1)))
        f, v = welch(x - x.mean(), fs=1.0 / dt.mean(), nperseg=min(nper, len(x)))
        f, v = f[1:], v[1:]
        quantity = "psd"
        averages = nseg
    fams = mm.get("families", ())
    if isinstance(fams, str) or not all(isinstance(x, str) for x in fams):
        raise DataFormatError(f"{side}: [measurement] families must be a list of family names")
    fam = []
    for s in fams:
        ff = FAMILY_ALIASES.get(s.lower(), s.lower())
        if ff not in FAMILIES:
            raise DataFormatError(f"{side}: [measurement] families entry '{s}' is not a family" + _did_you_mean(s, FAMILIES))
        fam.append(ff)
    rel, _ = _noise(meta, side, "frequency_rel", 1e-6, 1e-12, 0.5)
    detector, spot = _detector(mm, side)
    return SpectrumData(**common, probe=probe, probe_values=values, freq=f, value=v, quantity=quantity,
                        averages=averages, families=tuple(fam), known=known, known_mass=known_mass, freq_rel=rel,
                        static=_static(meta, side), detector=detector, spot=spot)


def _detector(mm: dict, side: Path) -> tuple[str, float]:
    """``[measurement] detector`` (:data:`DETECTORS`, default displacement) and an optical lever's ``spot`` (x / L
    of the laser spot, in (0, 1], default 1: the free end)."""
    det = mm.get("detector", "displacement")
    if det not in DETECTORS:
        raise DataFormatError(f"{side}: [measurement] detector must be one of {', '.join(DETECTORS)}"
                              + _did_you_mean(str(det), DETECTORS))
    if "spot" not in mm:
        return det, 1.0
    if det != "optical-lever":
        raise DataFormatError(f"{side}: [measurement] spot is the optical lever's laser spot: declare "
                              f"detector = \"optical-lever\" with it")
    sp = mm["spot"]
    if isinstance(sp, bool) or not isinstance(sp, (int, float)) or not 0.05 <= float(sp) <= 1.0:
        raise DataFormatError(f"{side}: [measurement] spot must be the laser spot's x / L from the clamp, in [0.05, 1]")
    return det, float(sp)


def _static(meta: dict, side: Path) -> tuple[float, float] | None:
    """``[static]``: a measured static spring constant [N/m] and its 1-sigma uncertainty (default
    :data:`STATIC_K_REL_DEFAULT` of it), or None."""
    if "static" not in meta:
        return None
    k = _num(meta, "static", "spring_constant", side, positive=True, lo=1e-6, hi=1e7, unit="N/m")
    if "sigma" not in meta["static"]:
        return k, STATIC_K_REL_DEFAULT * k
    return k, _num(meta, "static", "sigma", side, positive=True, lo=1e-3 * k, hi=k, unit="N/m")
