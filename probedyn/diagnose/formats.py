"""Measurement files: CSV data with a TOML sidecar.

A measurement is a TOML sidecar (``name.toml``) naming its data file (``data = "name.csv"``,
relative to the sidecar) and giving the metadata; ``probedyn diagnose`` accepts the sidecar
or the CSV (then ``name.toml`` beside it is used). Four kinds (``[measurement] kind``):

* ``modal``      -- a probe spec and measured modes: CSV columns ``family`` (flap | lateral |
  torsion), ``order`` (1, 2, ... within the family), ``frequency_Hz``; optional
  ``frequency_sigma_Hz``, ``Q``, ``Q_sigma`` and ``length_m`` (free length of that row, for
  length sweeps);
* ``spectrum``   -- ``frequency_Hz`` and ``value`` (``quantity = "psd"`` in m^2/Hz or
  ``"amplitude"`` in m); the probe spec, medium and temperature as for ``modal``; peaks are
  fitted and the modes diagnosed;
* ``timeseries`` -- ``time_s`` and ``displacement_m`` of the tip or sample; reduced to a PSD
  (Welch) and then treated as a spectrum;
* ``friction``   -- FFM scans: ``scan`` (integer id), ``position_m`` (base / support position),
  ``lateral_force_N``; optional ``time_s``. Per-scan metadata in ``[[scans]]`` tables
  (``id``, ``speed`` [m/s], ``load`` [N]); ``[probe] k_x`` [N/m] the lateral stiffness.

Sections shared by all kinds: ``[probe]`` (``length``, ``width``, ``thickness``, ``E``, ``rho``,
``nu``, optional known ``tip_mass`` [kg] and ``tip_position`` [x/L]), ``[medium]`` (``name``,
``density``, ``viscosity``, ``temperature``), ``[noise]`` (``frequency_rel``, ``Q_rel``, ``force``),
``[baseline] free`` (probe quantities calibrated in the baseline: ``E``, ``thickness``, ...).

Malformed input raises :class:`probedyn.core.errors.DataFormatError` whose message names the
file, the line and the column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from probedyn.diagnose.beam import BeamProps
from probedyn.core.errors import DataFormatError
from probedyn.core.params import load_toml

__all__ = ["read_measurement", "read_csv", "ModalData", "FrictionData", "SpectrumData", "Measurement"]

KINDS = ("modal", "spectrum", "timeseries", "friction")
FAMILIES = ("flap", "lateral", "torsion")
MEDIA = {"vacuum": (0.0, 1.8e-5), "air": (1.18, 1.85e-5), "water": (997.0, 8.9e-4)}


def read_csv(path: Path, required: list[str], optional: list[str], text_cols: tuple[str, ...] = ()) -> dict[str, Any]:
    """Read a numeric CSV with a header; '#' lines are comments.

    Returns columns as arrays (text columns as lists). Every error names file, line, column.
    """
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise DataFormatError(f"{path}: cannot read file ({exc.strerror})") from None
    header = None
    rows: list[tuple[int, list[str]]] = []
    for i, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        cells = [c.strip() for c in s.split(",")]
        if header is None:
            header = cells
            hline = i
            continue
        rows.append((i, cells))
    if header is None:
        raise DataFormatError(f"{path}, line 1, column 1: no header line (expected columns {', '.join(required)})")
    for j, name in enumerate(header, start=1):
        if name not in required and name not in optional:
            raise DataFormatError(f"{path}, line {hline}, column {j}: unknown column '{name}' "
                                  f"(allowed: {', '.join(required + optional)})")
    for name in required:
        if name not in header:
            raise DataFormatError(f"{path}, line {hline}, column {len(header) + 1}: missing required column '{name}'")
    if not rows:
        raise DataFormatError(f"{path}, line {hline + 1}, column 1: no data rows")
    cols: dict[str, list] = {h: [] for h in header}
    for lineno, cells in rows:
        if len(cells) != len(header):
            col = min(len(cells), len(header)) + 1
            raise DataFormatError(f"{path}, line {lineno}, column {col}: expected {len(header)} fields, found {len(cells)}")
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


def _col_err(data: dict, name: str, k: int, msg: str) -> DataFormatError:
    j = data["_header"].index(name) + 1
    return DataFormatError(f"{data['_path']}, line {data['_lines'][k]}, column {j} ({name}): {msg}")


def _num(meta: dict, section: str, key: str, path: Path, default: Any = None, positive: bool = False) -> Any:
    sec = meta.get(section, {})
    if not isinstance(sec, dict):
        raise DataFormatError(f"{path}: [{section}] must be a table")
    if key not in sec:
        if default is None:
            raise DataFormatError(f"{path}: missing '{key}' in [{section}]")
        return default
    v = sec[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise DataFormatError(f"{path}: [{section}] {key} must be a finite number, got {v!r}")
    if positive and v <= 0:
        raise DataFormatError(f"{path}: [{section}] {key} must be positive, got {v!r}")
    return float(v)


@dataclass
class Measurement:
    path: Path
    kind: str
    meta: dict
    description: str = ""


@dataclass
class ModalData(Measurement):
    props: BeamProps = None  # type: ignore[assignment]
    family: np.ndarray = None  # type: ignore[assignment]
    order: np.ndarray = None  # type: ignore[assignment]
    freq: np.ndarray = None  # type: ignore[assignment]
    freq_sigma: np.ndarray = None  # type: ignore[assignment]
    Q: np.ndarray = None  # type: ignore[assignment]
    Q_sigma_rel: np.ndarray = None  # type: ignore[assignment]
    length: np.ndarray = None  # type: ignore[assignment]
    rho_f: float = 0.0
    eta_f: float = 1.8e-5
    tip_mass: float = 0.0
    tip_position: float = 1.0
    free: tuple[str, ...] = ()
    noise_stated: bool = True


@dataclass
class FrictionScan:
    id: int
    speed: float
    load: float
    position: np.ndarray
    force: np.ndarray
    time: np.ndarray
    direction: np.ndarray  # +1 forward, -1 backward, per point


@dataclass
class FrictionData(Measurement):
    scans: list[FrictionScan] = field(default_factory=list)
    k_x: float = 1.0
    lattice: float = 0.5e-9
    sigma_force: float = 1e-11
    noise_stated: bool = True


@dataclass
class SpectrumData(Measurement):
    freq: np.ndarray = None  # type: ignore[assignment]
    value: np.ndarray = None  # type: ignore[assignment]
    quantity: str = "psd"
    families: tuple[str, ...] = ()


def _sidecar(path: Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise DataFormatError(f"{path}: no such file")
    if path.suffix.lower() == ".toml":
        return path
    side = path.with_suffix(".toml")
    if not side.exists():
        raise DataFormatError(f"{path}: no TOML sidecar {side.name} beside the data file")
    return side


def _props(meta: dict, path: Path) -> BeamProps:
    if "probe" not in meta:
        raise DataFormatError(f"{path}: missing [probe] table (length, width, thickness, E, rho)")
    p = BeamProps(
        length=_num(meta, "probe", "length", path, positive=True),
        width=_num(meta, "probe", "width", path, positive=True),
        thickness=_num(meta, "probe", "thickness", path, positive=True),
        E=_num(meta, "probe", "E", path, positive=True),
        rho=_num(meta, "probe", "rho", path, positive=True),
        nu=_num(meta, "probe", "nu", path, default=0.3),
    )
    for name in ("length", "width", "thickness"):
        v = getattr(p, name)
        if v > 10.0:
            raise DataFormatError(f"{path}: [probe] {name} = {v:g} m is implausible (values are SI: micrometres are 1e-6)")
    if not 1e8 <= p.E <= 2e12:
        raise DataFormatError(f"{path}: [probe] E = {p.E:g} Pa is outside [1e8, 2e12] Pa (SI units: GPa is 1e9)")
    if not 100 <= p.rho <= 25000:
        raise DataFormatError(f"{path}: [probe] rho = {p.rho:g} kg/m^3 is outside [100, 25000]")
    if not -1 < p.nu < 0.5:
        raise DataFormatError(f"{path}: [probe] nu = {p.nu:g} must be in (-1, 0.5)")
    return p


def _medium(meta: dict, path: Path) -> tuple[float, float]:
    med = meta.get("medium", {})
    name = str(med.get("name", "vacuum")).lower()
    rho0, eta0 = MEDIA.get(name, (None, None))
    if rho0 is None and ("density" not in med or "viscosity" not in med):
        raise DataFormatError(f"{path}: [medium] name '{name}' unknown ({', '.join(MEDIA)}); give density and viscosity")
    rho_f = _num(meta, "medium", "density", path, default=rho0)
    eta_f = _num(meta, "medium", "viscosity", path, default=eta0)
    if rho_f < 0 or eta_f <= 0:
        raise DataFormatError(f"{path}: [medium] density must be >= 0 and viscosity > 0")
    return rho_f, eta_f


def read_measurement(path: str | Path) -> Measurement:
    """Read a measurement (sidecar or CSV path) into a typed object."""
    side = _sidecar(Path(path))
    meta = load_toml(side)
    m = meta.get("measurement")
    if not isinstance(m, dict):
        raise DataFormatError(f"{side}: missing [measurement] table (kind, data)")
    kind = m.get("kind")
    if kind not in KINDS:
        raise DataFormatError(f"{side}: [measurement] kind must be one of {', '.join(KINDS)}, got {kind!r}")
    data = m.get("data")
    if not isinstance(data, str):
        raise DataFormatError(f"{side}: [measurement] data must name the CSV file")
    csv = (side.parent / data)
    if not csv.exists():
        raise DataFormatError(f"{side}: data file {csv} not found")
    desc = str(m.get("description", ""))
    if kind == "modal":
        return _read_modal(side, csv, meta, desc)
    if kind == "friction":
        return _read_friction(side, csv, meta, desc)
    return _read_spectrum(side, csv, meta, desc, kind)


def _noise(meta: dict, side: Path, key: str, default: float) -> tuple[float, bool]:
    if key in meta.get("noise", {}):
        return _num(meta, "noise", key, side, positive=True), True
    return default, False


def _read_modal(side: Path, csv: Path, meta: dict, desc: str) -> ModalData:
    props = _props(meta, side)
    d = read_csv(csv, ["family", "order", "frequency_Hz"],
                 ["frequency_sigma_Hz", "Q", "Q_sigma", "length_m"], text_cols=("family",))
    n = len(d["frequency_Hz"])
    fam = np.array([s.lower() for s in d["family"]])
    for k in range(n):
        if fam[k] not in FAMILIES:
            raise _col_err(d, "family", k, f"'{fam[k]}' is not one of {', '.join(FAMILIES)}")
        o = d["order"][k]
        if not (o >= 1 and float(o).is_integer()):
            raise _col_err(d, "order", k, f"order must be an integer >= 1, got {o}")
        if not d["frequency_Hz"][k] > 0:
            raise _col_err(d, "frequency_Hz", k, "frequency must be positive")
    f = d["frequency_Hz"]
    rel, stated = _noise(meta, side, "frequency_rel", 1e-3)
    sig = d.get("frequency_sigma_Hz", np.full(n, np.nan)).copy()
    for k in range(n):
        if not np.isnan(sig[k]) and sig[k] <= 0:
            raise _col_err(d, "frequency_sigma_Hz", k, "uncertainty must be positive")
    has_sig_col = "frequency_sigma_Hz" in d and not np.all(np.isnan(sig))
    sig = np.where(np.isnan(sig), rel * f, sig)
    Q = d.get("Q", np.full(n, np.nan))
    for k in range(n):
        if not np.isnan(Q[k]) and Q[k] <= 0.5:
            raise _col_err(d, "Q", k, "Q must be > 0.5")
    qrel, qstated = _noise(meta, side, "Q_rel", 0.05)
    qs = d.get("Q_sigma", np.full(n, np.nan))
    qsr = np.where(np.isnan(qs), qrel, qs / np.where(np.isnan(Q), 1.0, Q))
    L = d.get("length_m", np.full(n, np.nan))
    for k in range(n):
        if not np.isnan(L[k]) and not (0 < L[k] <= 10):
            raise _col_err(d, "length_m", k, "length must be in (0, 10] m (SI)")
    L = np.where(np.isnan(L), props.length, L)
    keys = {(a, int(b), round(c, 15)) for a, b, c in zip(fam, d["order"], L)}
    if len(keys) != n:
        raise DataFormatError(f"{csv}: the same (family, order, length) appears twice")
    rho_f, eta_f = _medium(meta, side)
    free = tuple(meta.get("baseline", {}).get("free", ()))
    for name in free:
        if name not in ("E", "rho", "thickness", "width", "length"):
            raise DataFormatError(f"{side}: [baseline] free entry '{name}' not one of E, rho, thickness, width, length")
    return ModalData(
        path=side, kind="modal", meta=meta, description=desc, props=props, family=fam,
        order=d["order"].astype(int), freq=f, freq_sigma=sig, Q=Q, Q_sigma_rel=qsr, length=L,
        rho_f=rho_f, eta_f=eta_f, tip_mass=_num(meta, "probe", "tip_mass", side, default=0.0),
        tip_position=_num(meta, "probe", "tip_position", side, default=1.0), free=free,
        noise_stated=stated or has_sig_col,
    )


def _read_friction(side: Path, csv: Path, meta: dict, desc: str) -> FrictionData:
    d = read_csv(csv, ["scan", "position_m", "lateral_force_N"], ["time_s"])
    k_x = _num(meta, "probe", "k_x", side, positive=True)
    lattice = _num(meta, "sample", "lattice", side, default=0.5e-9, positive=True)
    sig, stated = _noise(meta, side, "force", 0.0)
    scans_meta = meta.get("scans", [])
    if not isinstance(scans_meta, list) or not scans_meta:
        raise DataFormatError(f"{side}: missing [[scans]] tables (id, speed, load)")
    by_id = {}
    for i, s in enumerate(scans_meta):
        if not isinstance(s, dict) or "id" not in s or "speed" not in s:
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1} needs id and speed")
        sp, ld = s["speed"], s.get("load", 1e-9)
        if not (isinstance(sp, (int, float)) and sp > 0):
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1}: speed must be positive")
        if not (isinstance(ld, (int, float)) and ld >= 0):
            raise DataFormatError(f"{side}: [[scans]] entry {i + 1}: load must be >= 0")
        by_id[int(s["id"])] = (float(sp), float(ld))
    ids = d["scan"]
    scans = []
    for sid in dict.fromkeys(ids.astype(int).tolist()):
        idx = np.nonzero(ids == sid)[0]
        if sid not in by_id:
            raise _col_err(d, "scan", idx[0], f"scan id {sid} has no [[scans]] entry in {side.name}")
        if len(idx) < 8:
            raise _col_err(d, "scan", idx[0], f"scan {sid} has only {len(idx)} points (need >= 8)")
        if np.any(np.diff(idx) != 1):
            k = idx[np.nonzero(np.diff(idx) != 1)[0][0] + 1]
            raise _col_err(d, "scan", k, f"rows of scan {sid} are not contiguous")
        x = d["position_m"][idx]
        if np.max(np.abs(x)) > 1e-3:
            raise _col_err(d, "position_m", idx[int(np.argmax(np.abs(x)))], "position beyond 1 mm: values are SI metres")
        dx = np.diff(x)
        if np.any(dx == 0):
            raise _col_err(d, "position_m", idx[1 + int(np.nonzero(dx == 0)[0][0])], "repeated position (speed would be zero)")
        direction = np.sign(np.concatenate([dx[:1], dx]))
        sp, ld = by_id[sid]
        if "time_s" in d and not np.any(np.isnan(d["time_s"][idx])):
            t = d["time_s"][idx]
        else:
            t = np.concatenate([[0.0], np.cumsum(np.abs(dx))]) / sp
        scans.append(FrictionScan(sid, sp, ld, x, d["lateral_force_N"][idx], t, direction))
    if not stated:
        # no stated noise: estimate it from the high-frequency content (difference of neighbours)
        r = np.concatenate([np.diff(s.force) for s in scans])
        sig = float(1.4826 * np.median(np.abs(r - np.median(r))) / math.sqrt(2))
    return FrictionData(path=side, kind="friction", meta=meta, description=desc, scans=scans,
                        k_x=k_x, lattice=lattice, sigma_force=sig, noise_stated=stated)


def _read_spectrum(side: Path, csv: Path, meta: dict, desc: str, kind: str) -> SpectrumData:
    if kind == "spectrum":
        d = read_csv(csv, ["frequency_Hz", "value"], [])
        f, v = d["frequency_Hz"], d["value"]
        if np.any(np.diff(f) <= 0):
            k = int(np.nonzero(np.diff(f) <= 0)[0][0]) + 1
            raise _col_err(d, "frequency_Hz", k, "frequencies must increase")
        if np.any(v < 0):
            raise _col_err(d, "value", int(np.nonzero(v < 0)[0][0]), "spectral values must be >= 0")
        quantity = str(meta["measurement"].get("quantity", "psd"))
        if quantity not in ("psd", "amplitude"):
            raise DataFormatError(f"{side}: [measurement] quantity must be psd or amplitude")
    else:
        d = read_csv(csv, ["time_s", "displacement_m"], [])
        t, x = d["time_s"], d["displacement_m"]
        dt = np.diff(t)
        if np.any(dt <= 0):
            raise _col_err(d, "time_s", int(np.nonzero(dt <= 0)[0][0]) + 1, "times must increase")
        if np.max(np.abs(dt - dt.mean())) > 1e-3 * dt.mean():
            raise _col_err(d, "time_s", int(np.argmax(np.abs(dt - dt.mean()))) + 1, "sampling must be uniform (to 0.1 %)")
        from scipy.signal import welch

        nper = max(min(len(x) // 4, 65536), 8)  # 4 segments: resolution fs/(n/4)
        f, v = welch(x - x.mean(), fs=1.0 / dt.mean(), nperseg=nper)
        f, v = f[1:], v[1:]
        quantity = "psd"
    fam = tuple(str(s) for s in meta.get("measurement", {}).get("families", ()))
    for s in fam:
        if s not in FAMILIES:
            raise DataFormatError(f"{side}: [measurement] families entry '{s}' not one of {', '.join(FAMILIES)}")
    return SpectrumData(path=side, kind=kind, meta=meta, description=desc, freq=f, value=v, quantity=quantity, families=fam)
