"""Parameter sweeps of any scheme on Dask, with results as an xarray Dataset in NetCDF.

The contract with a scheme is small:

* a **cell function** ``func(**params) -> dict[str, array]`` — a pure function of named
  parameters.  With ``vectorized=True`` (default) every grid parameter arrives as a 1D array
  holding one entry per cell of a chunk, fixed parameters as given, and each returned value
  has the cells along its first axis (further axes become extra dimensions ``NAME_dim1``...).
  With ``vectorized=False`` the function is called once per cell with scalars and returns
  scalars or arrays.  Each cell must be computed independently of the others in the call
  (that is what makes results independent of chunking and of the number of workers).
* a **grid**: ``{name: 1D array of coordinate values}``; cells are the Cartesian product, in
  C order of the dict.  Build ranges with :func:`axis` (validated) or :func:`parse_axis`.
* the **result**: an ``xarray.Dataset`` with the grid names as dimensions/coordinates.

Execution: the flattened grid is cut into chunks (a fixed number of cells each, independent
of the number of workers); every chunk is one Dask task.  By default a
``dask.distributed.LocalCluster`` with ``workers`` single-threaded workers is started
(``processes=False`` runs them as threads in this process, fine for numba ``nogil`` kernels);
``scheduler="tcp://HOST:PORT"`` uses an existing cluster instead (reachability is checked with
a short connect timeout first).  As each chunk finishes, the client writes it atomically to
``OUT.nc.parts/chunk-NNNNN.npz``; a rerun of the same sweep (same function, grid, fixed
parameters, chunk size, seed — recorded in ``manifest.json``) skips the chunks already there
(chunks are stored as ``.npz``, which is ~100x faster to write than a NetCDF file).
At the end the chunks are merged, ``OUT.nc`` is written atomically (h5netcdf engine) and the
parts folder is removed.

Randomised schemes receive a ``seed`` array (one uint64 per cell) derived from the sweep seed
and the cell's flat index only (splitmix64), so results never depend on chunk order or
worker count.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import logging
import math
import os
import re
import shutil
import socket
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from probedyn.core.errors import DataFormatError, OutputError, ParameterError, ProbedynError, SolverError
from probedyn.core.io import after_commit, as_output_error, atomic_path, read_text, write_json
from probedyn.core.resources import check_memory, fmt_bytes

__all__ = [
    "GridError",
    "SchedulerError",
    "SweepResult",
    "axis",
    "parse_axis",
    "validate_grid",
    "cell_seeds",
    "run_sweep",
    "open_sweep",
    "default_chunk_size",
    "estimate_memory",
    "probe_scheduler",
    "SweepBusyError",
]


class GridError(ParameterError):
    """A sweep grid that has no cells, inverted or non-finite ranges, or clashing names."""


class SchedulerError(ProbedynError, ConnectionError):
    """A Dask scheduler address that is malformed or cannot be reached."""


# --------------------------------------------------------------------------------------
# Grids
# --------------------------------------------------------------------------------------

_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_RESERVED = {"seed", "cell"}


def axis(name: str, lo: float, hi: float, n: int, log: bool = False) -> np.ndarray:
    """``n`` points from ``lo`` to ``hi`` (linear or logarithmic), validated.

    Raises :class:`GridError` for n < 1, non-finite ends, inverted ranges (lo > hi), a
    degenerate range with n > 1, and non-positive ends of a logarithmic axis.
    """
    try:
        n_int = int(n)
    except (TypeError, ValueError):
        raise GridError(f"grid axis '{name}': number of points must be an integer, got {n!r}") from None
    if n_int != n:
        raise GridError(f"grid axis '{name}': number of points must be an integer, got {n!r}")
    if n_int < 1:
        raise GridError(f"grid axis '{name}': {n_int} points (zero points): give at least 1")
    for v, what in ((lo, "start"), (hi, "end")):
        if not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
            raise GridError(f"grid axis '{name}': {what} {v!r} is not a finite number")
    if lo > hi:
        raise GridError(f"grid axis '{name}': inverted range {lo:g} > {hi:g} (give start <= end)")
    if lo == hi and n_int > 1:
        raise GridError(f"grid axis '{name}': empty range {lo:g}..{hi:g} cannot hold {n_int} distinct points")
    if log:
        if lo <= 0:
            raise GridError(f"grid axis '{name}': a logarithmic range needs positive ends, got {lo:g}")
        return np.geomspace(lo, hi, n_int)
    return np.linspace(lo, hi, n_int)


def parse_axis(spec: str) -> tuple[str, np.ndarray]:
    """Parse ``NAME=LO:HI:N`` (linear), ``NAME=LO:HI:N:log`` or ``NAME=V1,V2,...``."""
    if "=" not in spec:
        raise GridError(f"grid spec {spec!r}: expected NAME=LO:HI:N or NAME=V1,V2,...")
    name, rhs = (s.strip() for s in spec.split("=", 1))
    form = f"grid spec {spec!r}: expected NAME=LO:HI:N[:log] or NAME=V1,V2,..."
    if ":" in rhs:
        parts = rhs.split(":")
        if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] != "log"):
            raise GridError(form)
        try:
            lo, hi, n = float(parts[0]), float(parts[1]), float(parts[2])
        except ValueError:
            raise GridError(form) from None
        return name, axis(name, lo, hi, int(n) if n.is_integer() else n, log=len(parts) == 4)
    try:
        vals = np.array([float(x) for x in rhs.split(",") if x.strip()])
    except ValueError:
        raise GridError(form) from None
    if vals.size == 0:
        raise GridError(f"grid spec {spec!r}: no values (zero points); {form.split(': ', 1)[1]}")
    if not np.all(np.isfinite(vals)):
        raise GridError(f"grid spec {spec!r}: values must be finite numbers")
    return name, vals


def validate_grid(grid: Mapping[str, Any], fixed: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
    """Check a grid: names are identifiers, coordinates 1D, non-empty, finite, unique."""
    if not isinstance(grid, Mapping) or len(grid) == 0:
        raise GridError("the sweep grid is empty: give at least one axis")
    out: dict[str, np.ndarray] = {}
    for name, values in grid.items():
        if not isinstance(name, str) or not _NAME_RE.match(name):
            raise GridError(f"grid axis name {name!r} is not a valid identifier")
        if name in _RESERVED:
            raise GridError(f"grid axis name '{name}' is reserved")
        if fixed and name in fixed:
            raise GridError(f"'{name}' is both a grid axis and a fixed parameter")
        arr = np.asarray(values)
        if arr.ndim != 1:
            raise GridError(f"grid axis '{name}' must be one-dimensional, got shape {arr.shape}")
        if arr.size == 0:
            raise GridError(f"grid axis '{name}' has zero points")
        if arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
            raise GridError(f"grid axis '{name}' contains NaN or infinite values")
        if arr.dtype.kind not in "biufcUS":
            raise GridError(f"grid axis '{name}' must hold numbers or strings, got dtype {arr.dtype}")
        if np.unique(arr).size != arr.size:
            raise GridError(f"grid axis '{name}' has repeated values")
        out[name] = arr
    return out


def _splitmix64(x: np.ndarray) -> np.ndarray:
    x = x.astype(np.uint64)
    with np.errstate(over="ignore"):
        x = x + np.uint64(0x9E3779B97F4A7C15)
        z = x
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def cell_seeds(seed: int, flat_index: np.ndarray) -> np.ndarray:
    """Per-cell seeds: a function of (sweep seed, flat cell index) only."""
    base = _splitmix64(np.array([int(seed) & 0xFFFFFFFFFFFFFFFF], dtype=np.uint64))[0]
    with np.errstate(over="ignore"):
        return _splitmix64(np.asarray(flat_index, dtype=np.uint64) ^ base)


def default_chunk_size(n_cells: int, target_chunks: int = 64) -> int:
    """Cells per chunk: about ``target_chunks`` chunks, independent of the worker count, and at
    most :data:`MAX_CHUNK_CELLS` (a task's memory stays bounded on huge grids)."""
    return max(1, min(MAX_CHUNK_CELLS, math.ceil(n_cells / target_chunks)))


# --------------------------------------------------------------------------------------
# The task
# --------------------------------------------------------------------------------------


def _run_chunk(func: Callable, params: dict[str, np.ndarray], fixed: dict[str, Any],
               seeds: np.ndarray | None, vectorized: bool) -> dict[str, np.ndarray]:
    """Evaluate ``func`` on one chunk (runs on a worker)."""
    n = next(iter(params.values())).size
    if vectorized:
        kw = dict(params)
        kw.update(fixed)
        if seeds is not None:
            kw["seed"] = seeds
        res = func(**kw)
        if not isinstance(res, Mapping):
            raise SolverError(f"sweep function {_qualname(func)} must return a dict, got {type(res).__name__}")
        out = {}
        for k, v in res.items():
            a = np.asarray(v)
            if a.ndim == 0 and n == 1:
                a = a.reshape(1)
            if a.ndim == 0 or a.shape[0] != n:
                raise SolverError(
                    f"sweep function {_qualname(func)}: output '{k}' has shape {a.shape}, expected {n} cells first"
                )
            out[str(k)] = a
        return out
    rows: list[Mapping[str, Any]] = []
    for i in range(n):
        kw = {name: arr[i].item() if hasattr(arr[i], "item") else arr[i] for name, arr in params.items()}
        kw.update(fixed)
        if seeds is not None:
            kw["seed"] = int(seeds[i])
        r = func(**kw)
        if not isinstance(r, Mapping):
            raise SolverError(f"sweep function {_qualname(func)} must return a dict, got {type(r).__name__}")
        rows.append(r)
    keys = list(rows[0])
    for r in rows[1:]:
        if list(r) != keys:
            raise SolverError(f"sweep function {_qualname(func)} returned different keys for different cells")
    return {k: np.stack([np.asarray(r[k]) for r in rows]) for k in keys}


def _qualname(func: Callable) -> str:
    return f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', repr(func))}"


# --------------------------------------------------------------------------------------
# Persistence of chunks
# --------------------------------------------------------------------------------------


def _chunk_path(parts: Path, i: int) -> Path:
    return parts / f"chunk-{i:05d}.npz"


def _write_chunk(res: dict[str, np.ndarray], path: Path) -> None:
    """Persist one finished chunk atomically (npz: ~100x faster to write than a NetCDF file;
    the final result is NetCDF)."""
    for k, a in res.items():
        if a.dtype.kind == "O":
            raise SolverError(f"sweep output '{k}' has dtype object; return numeric or string arrays")
    with atomic_path(path, defer=False) as tmp:  # resumable state: kept even if the run fails
        with open(tmp, "wb") as fh:
            np.savez(fh, **{f"v_{k}": a for k, a in res.items()})


def _read_chunk(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k[2:]: z[k] for k in z.files}


def _write_nc(ds, path: Path) -> None:
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")


def _read_nc(path: Path):
    import xarray as xr

    with xr.open_dataset(path, engine="h5netcdf") as ds:
        return ds.load()


def _jsonable(v: Any) -> Any:
    if isinstance(v, (str, bool, int, float)) or v is None:
        return v
    if isinstance(v, (np.integer, np.floating, np.bool_)):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, Mapping):
        return {str(k): _jsonable(x) for k, x in v.items()}
    return repr(v)


def _signature(func, grid, fixed, chunk_size, seed, vectorized) -> str:
    h = hashlib.sha256()
    h.update(_qualname(func).encode())
    for name, arr in grid.items():
        h.update(name.encode())
        h.update(str(arr.dtype).encode())
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(json.dumps(_jsonable(dict(fixed)), sort_keys=True).encode())
    h.update(f"{chunk_size}|{seed}|{vectorized}".encode())
    return h.hexdigest()


# --------------------------------------------------------------------------------------
# Scheduler: address, handshake, workers, health during the run
# --------------------------------------------------------------------------------------

_ADDR_RE = re.compile(r"^(?:(tcp|tls)://)?(\[[0-9a-fA-F:]+\]|[A-Za-z0-9_.\-]+):(\d{1,5})/?$")


def _tls_security():
    """Dask's TLS settings from its configuration (``distributed.comm.tls.*``), or an error."""
    import dask
    from distributed.security import Security

    ca = dask.config.get("distributed.comm.tls.ca-file", None)
    cert = dask.config.get("distributed.comm.tls.client.cert", None)
    if not ca or not cert:
        raise SchedulerError(
            "a tls:// scheduler needs TLS certificates: set distributed.comm.tls.ca-file and "
            "distributed.comm.tls.client.cert (and .key) in Dask's configuration, or use tcp:// "
            "(for example through an SSH tunnel)"
        )
    return Security()


def check_scheduler_address(address: str, timeout: float = 3.0) -> str:
    """Validate ``tcp://HOST:PORT`` (``tls://``, or ``HOST:PORT``) and check that something listens there."""
    if not isinstance(address, str) or not address.strip():
        raise SchedulerError("empty Dask scheduler address (expected tcp://HOST:PORT)")
    address = address.strip()
    m = _ADDR_RE.match(address)
    if not m:
        raise SchedulerError(f"malformed Dask scheduler address {address!r} (expected tcp://HOST:PORT)")
    proto, host, port = m.group(1) or "tcp", m.group(2).strip("[]"), int(m.group(3))
    if not 0 < port < 65536:
        raise SchedulerError(f"Dask scheduler address {address!r}: port {port} out of range")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except socket.gaierror as exc:
        raise SchedulerError(f"cannot reach Dask scheduler at {address}: unknown host ({exc.strerror})") from None
    except (OSError, TimeoutError) as exc:
        reason = getattr(exc, "strerror", None) or type(exc).__name__
        raise SchedulerError(
            f"cannot reach Dask scheduler at {address}: {reason} within {timeout:g} s "
            "(is `dask scheduler` running there and the port open?)"
        ) from None
    return f"{proto}://{m.group(2)}:{port}"


def probe_scheduler(address: str, timeout: float = 5.0, security=None) -> dict[str, Any]:
    """Speak Dask's protocol to ``address`` (bounded by ``timeout``); return its identity.

    Something that accepts TCP but is not a Dask scheduler (a silent listener, an HTTP server,
    a Dask worker) gives :class:`SchedulerError` instead of a hang.
    """
    import asyncio

    from distributed.comm import connect

    async def ask() -> Any:
        kw = security.get_connection_args("client") if security is not None else {}
        comm = await connect(address, timeout=timeout, **kw)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        info = asyncio.run(asyncio.wait_for(ask(), timeout=timeout))
    except (asyncio.TimeoutError, TimeoutError):
        raise SchedulerError(
            f"{address} accepts connections but did not answer as a Dask scheduler within {timeout:g} s "
            "(wrong port, or not a Dask scheduler?)"
        ) from None
    except Exception as exc:  # handshake or decoding failed: something else listens there
        raise SchedulerError(
            f"{address} is not a Dask scheduler (the Dask handshake failed: {type(exc).__name__})"
        ) from None
    if not isinstance(info, Mapping) or info.get("type") != "Scheduler":
        kind = info.get("type") if isinstance(info, Mapping) else type(info).__name__
        raise SchedulerError(f"{address} answers as a Dask {kind}, not a scheduler: give the scheduler's address")
    return dict(info)


def _n_workers(client, timeout: float) -> int | None:
    """Running workers known to the scheduler, or None if it did not answer within ``timeout``."""
    try:
        info = client.sync(client.scheduler.identity, n_workers=-1, callback_timeout=timeout)
    except Exception:
        return None
    workers = info.get("workers", {}) if isinstance(info, Mapping) else {}
    return sum(1 for w in workers.values() if not isinstance(w, Mapping) or w.get("status", "running") == "running")


_DASK_LOGGERS = ("distributed", "distributed.worker", "distributed.scheduler", "distributed.nanny",
                 "distributed.core", "distributed.client", "distributed.comm", "distributed.batched",
                 "distributed.utils_perf", "distributed.worker_memory")


class _DaskAsyncioNoise(logging.Filter):
    """Drops asyncio's reports about Dask's own event-loop tasks ("Task exception was never
    retrieved", "Task was destroyed but it is pending!"): a client whose worker or scheduler
    died leaves such tasks behind (a gather waiting for a chunk that is being recomputed), and
    asyncio would print them with a traceback long after the sweep reported the failure."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        if exc is not None and type(exc).__module__.split(".")[0] in ("distributed", "tornado"):
            return False
        try:
            msg = record.getMessage()
        except Exception:
            return True
        return f"{os.sep}distributed{os.sep}" not in msg


_ASYNCIO_FILTER = _DaskAsyncioNoise()


@contextlib.contextmanager
def _quiet_dask() -> Any:
    """Silence Dask's own logging: a sweep reports failures itself, once, on one line.

    Not restored afterwards: a client that lost its scheduler keeps logging from its event-loop
    thread after the sweep has returned (reconnection attempts, "closing client"), and its
    orphaned tasks are reported by asyncio when they are garbage-collected. Only Dask's loggers
    and asyncio's records about Dask's tasks are affected.
    """
    import distributed  # noqa: F401  (its import configures these loggers: set them after)

    for name in _DASK_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    aio = logging.getLogger("asyncio")
    if _ASYNCIO_FILTER not in aio.filters:
        aio.addFilter(_ASYNCIO_FILTER)
    yield


def _cluster_problem(client, where: str) -> str | None:
    """What is wrong with the cluster now (one phrase), or None if the scheduler answers with workers."""
    if client.status != "running":
        return f"lost the connection to the Dask scheduler ({where})"
    n = _n_workers(client, timeout=5.0)
    if n is None:
        return f"the Dask scheduler ({where}) does not answer"
    if n == 0:
        return f"the Dask scheduler ({where}) has no workers left (they died or left)"
    return None


def _connect(scheduler: str | None, workers: int, processes: bool, threads_per_worker: int,
             connect_timeout: float, worker_timeout: float):
    """Return (client, cluster-or-None); a remote scheduler is checked for being one, with workers."""
    from dask.distributed import Client, LocalCluster

    if scheduler:
        addr = check_scheduler_address(scheduler, timeout=connect_timeout)
        security = _tls_security() if addr.startswith("tls://") else None
        probe_scheduler(addr, timeout=connect_timeout, security=security)
        try:
            client = Client(addr, timeout=connect_timeout, set_as_default=False,
                            **({"security": security} if security is not None else {}))
        except Exception as exc:
            raise SchedulerError(f"cannot connect to Dask scheduler at {addr}: {type(exc).__name__}: "
                                 f"{' '.join(str(exc).split())}") from None
        try:
            deadline = time.monotonic() + worker_timeout
            while True:
                n = _n_workers(client, timeout=max(connect_timeout, 2.0))
                if n:
                    break
                if time.monotonic() > deadline:
                    what = "did not answer" if n is None else "has no workers"
                    raise SchedulerError(
                        f"the Dask scheduler at {addr} {what} (waited {worker_timeout:g} s); "
                        f"start workers with `dask worker {addr}`"
                    )
                time.sleep(0.25)
        except BaseException:
            _close(client, None)
            raise
        return client, None
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=threads_per_worker,
        processes=processes,
        dashboard_address=None,
        silence_logs=logging.CRITICAL + 1,
    )
    return Client(cluster, set_as_default=False), cluster


def _close(client, cluster) -> None:
    """Close the client and a local cluster within bounded times, whatever state they are in."""
    with contextlib.suppress(BaseException):
        if client is not None:
            client.close(timeout=5)
    with contextlib.suppress(BaseException):
        if cluster is not None:
            cluster.close(timeout=10)


# --------------------------------------------------------------------------------------
# The output's lock and the parts folder
# --------------------------------------------------------------------------------------


class SweepBusyError(ProbedynError):
    """Another process is writing the same sweep output."""


@contextlib.contextmanager
def _sweep_lock(out: Path):
    """Exclusive lock on ``out`` for the whole run (a lock file beside it, removed at the end)."""
    lock = out.with_name(f".{out.name}.probedyn-lock")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise as_output_error(exc, out) from None
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise as_output_error(exc, out) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                holder = os.read(fd, 32).decode("ascii", "replace").strip()
            except OSError:
                holder = ""
            os.close(fd)
            who = f" (pid {holder})" if holder.isdigit() else ""
            raise SweepBusyError(
                f"another probedyn sweep{who} is writing {out}; wait for it to finish or choose another output file"
            ) from None
        try:
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the previous holder removed the file between our open and lock: retry
    try:
        with contextlib.suppress(OSError):  # the holder's pid is for the message only (a full disk: no pid)
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(lock)
        os.close(fd)


def _existing_chunks(parts: Path, n_chunks: int) -> set[int]:
    return {i for i in range(n_chunks) if _chunk_path(parts, i).exists()}


def _resume_state(parts: Path, sig: str, n_chunks: int, restart: bool) -> set[int]:
    """Chunks of this sweep already in ``parts``; refuses chunks of another sweep.

    An empty parts folder, or one without chunks (a run stopped before its first chunk), is
    not "another sweep": it is reused.
    """
    if not parts.exists():
        return set()
    if not parts.is_dir():
        raise OutputError(f"cannot write {parts}: it is a file, not a folder")
    if restart:
        shutil.rmtree(parts)
        return set()
    if not any(parts.glob("chunk-*.npz")):
        return set()
    try:
        old = json.loads(read_text(parts / "manifest.json", what="sweep manifest", max_bytes=1 << 20))
    except (ProbedynError, ValueError):
        old = None
    if not isinstance(old, Mapping):
        raise ParameterError(
            f"{parts} holds chunks but no readable manifest, so they cannot be matched to this sweep; "
            "remove the folder or rerun with restart"
        )
    if old.get("signature") != sig:
        raise ParameterError(
            f"{parts} holds chunks of a different sweep (function, grid, fixed parameters or chunk "
            "size differ); remove it or rerun with restart"
        )
    return _existing_chunks(parts, n_chunks)


# --------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------

#: cells per chunk at most (bounds the memory of one task, whatever the grid)
MAX_CHUNK_CELLS = 1 << 18
#: result bytes per cell assumed when a cell function does not declare ``sweep_bytes_per_cell``
DEFAULT_BYTES_PER_CELL = 8


def estimate_memory(n_cells: int, n_axes: int, bytes_per_cell: int) -> int:
    """Bytes the client needs to merge a sweep: the outputs about 3 times (chunks, merged array,
    NetCDF encoding) plus one 8-byte coordinate index per axis and cell."""
    return int(n_cells) * (3 * int(bytes_per_cell) + 8 * int(n_axes))


@dataclass
class SweepResult:
    dataset: Any  # xarray.Dataset
    path: Path | None
    chunks_total: int
    chunks_run: list[int] = field(default_factory=list)
    chunks_skipped: list[int] = field(default_factory=list)
    elapsed: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "path": str(self.path) if self.path else None,
            "chunks_total": self.chunks_total,
            "chunks_run": len(self.chunks_run),
            "chunks_skipped": len(self.chunks_skipped),
            "elapsed_s": self.elapsed,
            "variables": list(self.dataset.data_vars),
            "dims": dict(self.dataset.sizes),
        }


def run_sweep(
    func: Callable[..., Mapping[str, Any]],
    grid: Mapping[str, Any],
    *,
    fixed: Mapping[str, Any] | None = None,
    out: str | Path | None = None,
    vectorized: bool = True,
    chunk_size: int | None = None,
    workers: int = 2,
    scheduler: str | None = None,
    processes: bool = True,
    threads_per_worker: int = 1,
    progress: bool = True,
    seed: int | None = None,
    restart: bool = False,
    connect_timeout: float = 3.0,
    worker_timeout: float = 30.0,
    attrs: Mapping[str, Any] | None = None,
) -> SweepResult:
    """Run ``func`` over the Cartesian ``grid`` on Dask; see the module docstring.

    ``out``: NetCDF file (written atomically); its finished chunks persist in ``out.parts/``
    so an interrupted or failed run resumes; ``restart=True`` discards them. Only one process
    at a time writes a given ``out`` (a second one gets :class:`SweepBusyError`).
    ``worker_timeout``: how long a scheduler may have no worker (at the start, or because
    workers died) or not answer before the run fails. Errors: :class:`GridError` for bad
    grids, :class:`SchedulerError` for a bad/unreachable/failing scheduler,
    :class:`~probedyn.core.errors.ResourceError` for a result that cannot fit in memory, the
    scheme's own :class:`~probedyn.core.errors.ProbedynError` if it raises one, else
    :class:`SolverError`.
    """
    fixed = dict(fixed or {})
    g = validate_grid(grid, fixed)
    if "seed" in fixed:
        raise GridError("'seed' is reserved: pass the sweep seed as seed=")
    if not isinstance(workers, (int, np.integer)) or isinstance(workers, bool) or workers < 1:
        raise ParameterError(f"workers must be a positive integer, got {workers!r}")
    for name, v in (("connect_timeout", connect_timeout), ("worker_timeout", worker_timeout)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a positive number of seconds, got {v!r}")
    shape = tuple(a.size for a in g.values())
    n_cells = math.prod(shape)
    per_cell = int(getattr(func, "sweep_bytes_per_cell", DEFAULT_BYTES_PER_CELL))
    check_memory(estimate_memory(n_cells, len(shape), per_cell), f"a sweep of {n_cells:.4g} cells",
                 how=f"{n_cells:.4g} cells x {3 * per_cell + 8 * len(shape)} B",
                 hint="use fewer grid points")
    if chunk_size is None:
        chunk_size = default_chunk_size(n_cells)
    if not isinstance(chunk_size, (int, np.integer)) or isinstance(chunk_size, bool) or chunk_size < 1:
        raise ParameterError(f"chunk_size must be a positive integer, got {chunk_size!r}")
    if out is not None:
        out = Path(out)
        if out.suffix != ".nc":
            raise ParameterError(f"sweep output {out} must end in .nc")
        if out.is_dir():
            raise OutputError(f"cannot write {out}: a folder of that name is in the way")
        with _sweep_lock(out):
            return _run_locked(func, g, fixed, out, vectorized, int(chunk_size), int(workers), scheduler,
                               processes, threads_per_worker, progress, seed, restart, connect_timeout,
                               worker_timeout, attrs)
    return _run_locked(func, g, fixed, None, vectorized, int(chunk_size), int(workers), scheduler, processes,
                       threads_per_worker, progress, seed, restart, connect_timeout, worker_timeout, attrs)


def _run_locked(func, g, fixed, out, vectorized, chunk_size, workers, scheduler, processes, threads_per_worker,
                progress, seed, restart, connect_timeout, worker_timeout, attrs) -> SweepResult:
    import xarray as xr

    t0 = time.perf_counter()
    names = list(g)
    shape = tuple(a.size for a in g.values())
    n_cells = math.prod(shape)
    n_chunks = math.ceil(n_cells / chunk_size)
    sig = _signature(func, g, fixed, chunk_size, seed, vectorized)
    parts = out.with_name(out.name + ".parts") if out is not None else None
    done = _resume_state(parts, sig, n_chunks, restart) if parts is not None else set()

    def chunk_params(i: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
        start, stop = i * chunk_size, min(n_cells, (i + 1) * chunk_size)
        flat = np.arange(start, stop)
        idx = np.unravel_index(flat, shape)
        return {nm: g[nm][ix] for nm, ix in zip(names, idx)}, flat

    results: dict[int, dict[str, np.ndarray]] = {}
    todo = [i for i in range(n_chunks) if i not in done]
    if todo:
        with _quiet_dask():
            client, cluster = _connect(scheduler, workers, processes, threads_per_worker, connect_timeout,
                                       worker_timeout)
            try:
                if parts is not None:  # only now: a failed connection leaves nothing behind
                    try:
                        parts.mkdir(parents=True, exist_ok=True)
                    except OSError as exc:
                        raise as_output_error(exc, parts) from None
                    write_json(parts / "manifest.json", defer=False, obj=
                               {"signature": sig, "function": _qualname(func), "n_chunks": n_chunks,
                                "chunk_size": chunk_size, "shape": list(shape), "names": names})
                _execute(client, func, fixed, vectorized, seed, sig, todo, done, n_chunks, n_cells, chunk_size,
                         chunk_params, parts, results, progress, out, scheduler, worker_timeout)
            finally:
                _close(client, cluster)

    # Merge
    if parts is not None:
        pieces = [_read_chunk(_chunk_path(parts, i)) for i in range(n_chunks)]
        merged = {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}
    else:
        merged = {k: np.concatenate([results[i][k] for i in range(n_chunks)]) for k in results[0]}
    data = {}
    for k, a in merged.items():
        extra = a.shape[1:]
        data[k] = (tuple(names) + tuple(f"{k}_dim{j}" for j in range(1, a.ndim)), a.reshape(shape + extra))
    ds = xr.Dataset(data, coords={nm: g[nm] for nm in names})
    ds.attrs.update(
        {
            "probedyn_function": _qualname(func),
            "probedyn_signature": sig,
            "chunk_size": int(chunk_size),
            "n_chunks": int(n_chunks),
            "fixed_parameters": json.dumps(_jsonable(fixed), sort_keys=True),
        }
    )
    if seed is not None:
        ds.attrs["seed"] = int(seed)
    for k, v in (attrs or {}).items():
        if isinstance(v, (list, tuple)):
            v = np.asarray(v)
        if isinstance(v, np.ndarray) and v.ndim == 1 and v.size > 0 and v.dtype.kind in "iuf":
            ds.attrs[k] = v
        else:
            ds.attrs[k] = v if isinstance(v, (str, int, float)) else json.dumps(_jsonable(v))
    if out is not None:
        _write_nc(ds, out)
        # the chunks go only once the NetCDF file is in place (at the end of the command's
        # transaction: an interrupt before that keeps them for resumption)
        after_commit(lambda: shutil.rmtree(parts, ignore_errors=True))
    return SweepResult(ds, out, n_chunks, chunks_run=todo, chunks_skipped=sorted(done),
                       elapsed=time.perf_counter() - t0)


#: seconds between health checks of the scheduler and its workers while waiting for chunks
POLL_S = 1.0


def _execute(client, func, fixed, vectorized, seed, sig, todo, done, n_chunks, n_cells, chunk_size, chunk_params,
             parts, results, progress, out, scheduler, worker_timeout) -> None:
    """Submit the chunks, persist each as it finishes, and watch the cluster's health."""
    from distributed import as_completed
    from tqdm.auto import tqdm

    run_id = uuid.uuid4().hex[:8]
    index: dict[str, int] = {}
    pending = set()
    for i in todo:
        params, flat = chunk_params(i)
        seeds = cell_seeds(seed, flat) if seed is not None else None
        fut = client.submit(_run_chunk, func, params, fixed, seeds, vectorized,
                            key=f"probedyn-sweep-{sig[:10]}-{run_id}-{i}", pure=False)
        index[fut.key] = i
        pending.add(fut)
    finished = 0
    where = scheduler or "the local Dask cluster"

    def kept() -> str:
        if parts is None:
            return "no partial results are kept without an output file"
        n = len(done) + finished
        return f"{n} of {n_chunks} chunks are kept in {parts}; run the same command again to resume"

    bar = tqdm(total=n_chunks, initial=len(done), disable=not progress, unit="chunk",
               desc=f"sweep {out.name if out else ''}".strip())
    unhealthy_since: float | None = None
    last_check = time.monotonic()
    try:
        # results are gathered on the client's event loop (with_results), never by a blocking
        # call here: a worker that dies while one of its finished chunks is fetched makes Dask
        # recompute that chunk, and this loop keeps watching the cluster's health meanwhile
        ac = as_completed(list(pending), loop=client.loop, with_results=True, raise_errors=False)
        while pending:
            fin = ac.next_batch(block=False)
            if not fin:
                time.sleep(0.05)
            for fut, res in fin:
                pending.discard(fut)
                i = index[fut.key]
                if fut.status == "error":
                    exc = fut.exception(timeout=10)
                    for f in pending:
                        f.cancel()
                    if isinstance(exc, ProbedynError):
                        raise exc
                    start = i * chunk_size
                    cells = f"cells {start}..{min(n_cells, start + chunk_size) - 1}"
                    if type(exc).__name__ == "KilledWorker":
                        raise SolverError(f"sweep chunk {i} ({cells}) killed the Dask workers that ran it "
                                          f"(out of memory or a crash); {kept()}") from None
                    raise SolverError(
                        f"sweep chunk {i} ({cells}) failed: {type(exc).__name__}: {' '.join(str(exc).split())}; "
                        f"{kept()}"
                    ) from exc
                if isinstance(res, BaseException):  # cancelled: a worker or the scheduler went away
                    # (not the future's status: a chunk fetched, then lost with its worker, is "lost")
                    why = _cluster_problem(client, where) or "the Dask worker running it died or left"
                    raise SchedulerError(f"sweep chunk {i} was lost: {why}; {kept()}")
                if parts is not None:
                    _write_chunk(res, _chunk_path(parts, i))
                else:
                    results[i] = res
                fut.release()  # saved: a worker lost later must not make Dask recompute it
                finished += 1
                bar.update(1)
            now = time.monotonic()
            if pending and now - last_check >= POLL_S:
                last_check = now
                problem = _cluster_problem(client, where)
                if problem is None:
                    unhealthy_since = None
                elif unhealthy_since is None:
                    unhealthy_since = now
                elif now - unhealthy_since > worker_timeout:
                    raise SchedulerError(f"{problem} for {worker_timeout:g} s; {kept()}")
    except BaseException as exc:
        # the scheduler died while a finished chunk was being fetched: Dask's CommClosedError (an
        # OSError without errno) or FutureCancelledError ("scheduler-connection-lost", an
        # asyncio CancelledError, a BaseException); our own writes raise OutputError, not OSError
        if isinstance(exc, ProbedynError):  # ours, already worded (SchedulerError is a ConnectionError)
            raise
        names = {c.__name__ for c in type(exc).__mro__}
        if isinstance(exc, (OSError, TimeoutError)) or names & {"CancelledError", "CommClosedError"}:
            problem = _cluster_problem(client, where) or f"a Dask call failed although the scheduler ({where}) answers"
            raise SchedulerError(f"{problem} ({type(exc).__name__}); {kept()}") from None
        raise
    finally:
        bar.close()


def open_sweep(path: str | Path):
    """Read a sweep result written by :func:`run_sweep` (loaded into memory)."""
    path = Path(path)
    if not path.exists():
        raise ParameterError(f"{path}: no such sweep file")
    if not path.is_file():
        raise DataFormatError(f"{path}: not a regular file")
    try:
        return _read_nc(path)
    except Exception as exc:  # malformed / not NetCDF
        raise DataFormatError(f"{path}: not a readable NetCDF sweep file ({type(exc).__name__})") from None
