"""Every file probedyn writes or reads on a user's behalf goes through here.

Writing (one mechanism for single files, one for output *sets*):

* :func:`atomic_path` / :func:`write_text` / :func:`write_json` / :func:`write_bytes`: one file,
  written to a temporary name beside the target and renamed into place (``os.replace`` is
  atomic on POSIX): a reader sees the old file or the new one, never half of one.
* :func:`output_set`: several files that belong together (``modes.json`` + ``modes.vtu``, a
  report and its figures). They are written into a *staging folder* beside the target folder;
  on success the staging folder is renamed into place (target absent) or its files are moved
  in under a commit marker (target present). A run that fails or is interrupted removes its
  staging folder, so the target keeps its previous, consistent content. A run killed with
  SIGKILL in the (sub-millisecond) move phase leaves the marker; the next probedyn run that
  writes beside the target finishes the move ("roll forward").
* Temporaries are named ``.<name>.probedyn-tmp-<host>-<pid>-<random>``; :func:`clean_stale`
  removes those of dead processes (called automatically once per folder per process).
* Permissions honour the umask (``mkstemp`` would leave 0600 files nobody else can read).
* ``OSError`` while writing (read-only or full file system, permission, a file where a folder
  should be) becomes :class:`~probedyn.core.errors.OutputError` with a one-line message.

Reading files named by users or by their data files (:func:`read_bytes`, :func:`read_text`,
:func:`load_toml`): regular files only (no FIFO, device or directory: nothing that can hang or
never end), a size limit checked before and while reading, and, when ``base`` is given, the
resolved file must lie in ``base`` or below it unless the caller allows it explicitly
(``allow_outside`` or ``allowed_roots``). Error messages name the file and a position, never
its content.

This module imports nothing else of probedyn except :mod:`probedyn.core.errors`.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import json
import math
import os
import re
import secrets
import shutil
import signal
import socket
import stat
import threading
import time
import tomllib
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

from probedyn.core.errors import DataFormatError, OutputError

__all__ = [
    "to_jsonable", "dumps", "atomic_path", "write_text", "write_json", "write_bytes", "output_set",
    "as_output_error", "clean_stale", "file_mode", "discard_active", "read_bytes", "read_text", "load_toml",
    "resolve_input", "MAX_TEXT_BYTES", "MAX_DATA_BYTES",
]


# ------------------------------------------------------------------------------------------
# JSON
# ------------------------------------------------------------------------------------------


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays, paths, dataclass-likes to JSON types (NaN -> None)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, complex):
        return {"re": obj.real, "im": obj.imag}
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "to_dict"):
        return to_jsonable(obj.to_dict())
    return obj


def dumps(obj: Any, indent: int | None = 2) -> str:
    return json.dumps(to_jsonable(obj), indent=indent)


# ------------------------------------------------------------------------------------------
# Temporaries: names, registry of this process's live ones, stale clean-up
# ------------------------------------------------------------------------------------------

_TAG = ".probedyn-tmp-"
_HOST = hashlib.sha256(socket.gethostname().encode()).hexdigest()[:6]
_TMP_RE = re.compile(r"^\.(?P<name>.*)\.probedyn-tmp-(?P<host>[0-9a-f]{6})-(?P<pid>\d+)-[0-9a-f]{8}(?P<suffix>.*)$")
_COMMIT_MARKER = ".probedyn-commit"
#: a temporary of another host (or a recycled pid) is stale after this long without change
STALE_AFTER_S = 24 * 3600.0

_active: set[Path] = set()
_active_lock = threading.Lock()
_commit_lock = threading.Lock()  # held while an output set is moved into place
_cleaned: set[Path] = set()


def _tmp_name(name: str, suffix: str = "") -> str:
    return f".{name}{_TAG}{_HOST}-{os.getpid()}-{secrets.token_hex(4)}{suffix}"


def _register(p: Path) -> None:
    with _active_lock:
        _active.add(p)


def _unregister(p: Path) -> None:
    with _active_lock:
        _active.discard(p)


def _remove(p: Path) -> None:
    with contextlib.suppress(OSError):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink()


def discard_active() -> None:
    """Remove every temporary file and staging folder this process is writing (best effort).

    Used by the command line before a forced exit on an interrupt; normal exits (including
    exceptions and KeyboardInterrupt) clean up through the context managers themselves.
    """
    _commit_lock.acquire(timeout=5.0)  # let a commit in progress finish (never released: we exit)
    with _active_lock:
        paths = list(_active)
        _active.clear()
    for p in paths:
        _remove(p)


_UMASK: int | None = None


def _umask() -> int:
    """The process umask, read without changing it (``/proc/self/status``), else set-and-restore once."""
    global _UMASK
    if _UMASK is None:
        try:
            for line in Path("/proc/self/status").read_text().splitlines():
                if line.startswith("Umask:"):
                    _UMASK = int(line.split()[1], 8)
                    break
        except OSError:
            pass
        if _UMASK is None:  # pragma: no cover - not Linux
            old = os.umask(0o022)
            os.umask(old)
            _UMASK = old
    return _UMASK


def file_mode() -> int:
    """Mode of a new regular file under the current umask (``0o666 & ~umask``)."""
    return 0o666 & ~_umask()


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def clean_stale(folder: str | Path, force: bool = False) -> list[Path]:
    """Remove temporaries left in ``folder`` by killed probedyn runs; finish interrupted commits.

    A temporary is stale when it was made on this host by a process that no longer exists, or
    when it has not changed for :data:`STALE_AFTER_S`. A stale staging folder holding a commit
    marker is moved into place first (the run was killed while committing). Returns what was
    removed or committed. Runs once per folder per process unless ``force``.
    """
    folder = Path(folder)
    key = folder.absolute()
    if key in _cleaned and not force:
        return []
    _cleaned.add(key)
    done: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return done
    now = time.time()
    for e in entries:
        m = _TMP_RE.match(e.name)
        if not m:
            continue
        pid = int(m.group("pid"))
        if m.group("host") == _HOST and pid == os.getpid():
            continue
        try:
            age = now - e.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        dead = m.group("host") == _HOST and not _pid_alive(pid)
        if not dead and age < STALE_AFTER_S:
            continue
        p = Path(e.path)
        if e.is_dir(follow_symlinks=False) and (p / _COMMIT_MARKER).exists():
            with contextlib.suppress(OSError, OutputError):
                target = Path((p / _COMMIT_MARKER).read_text(encoding="utf-8").strip())
                if target.parent.absolute() == folder.absolute():
                    _move_into(p, target)
        _remove(p)
        done.append(p)
    return done


# ------------------------------------------------------------------------------------------
# Errors while writing
# ------------------------------------------------------------------------------------------

_WRITE_ERRNOS = {
    errno.ENOSPC: "no space left on the device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.EISDIR: "it is a folder",
    errno.EEXIST: "a file of that name is in the way",
    errno.ENAMETOOLONG: "name too long",
    errno.EFBIG: "file too large",
    errno.EIO: "input/output error",
    errno.ELOOP: "too many symbolic links",
    errno.ENOTEMPTY: "a folder of that name is in the way",
}


def as_output_error(exc: OSError, target: Path) -> OutputError:
    """The one-line :class:`OutputError` for an ``OSError`` raised while writing ``target``."""
    reason = _WRITE_ERRNOS.get(exc.errno or -1) or exc.strerror or type(exc).__name__
    return OutputError(f"cannot write {target}: {reason}")


_ALWAYS_WRITE = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG}


def _is_write_error(exc: BaseException, where: Path) -> bool:
    """An OSError that comes from writing below ``where`` (full or read-only file systems always do)."""
    if not isinstance(exc, OSError) or exc.errno not in _WRITE_ERRNOS:
        return False
    if exc.errno in _ALWAYS_WRITE:
        return True
    names = [n for n in (exc.filename, getattr(exc, "filename2", None)) if n]
    return any(_within(Path(os.path.abspath(n)), where.absolute()) or Path(n).absolute() == where.absolute()
               for n in names)


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold SIGINT/SIGTERM/SIGHUP until the block ends (main thread only), then deliver them.

    Keeps a commit (a handful of renames) from being cut in two by an interrupt; the signal is
    re-raised at the end so the interrupt still happens, just after the set is consistent.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    sigs = [s for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)]
    old = {}
    for s in sigs:
        try:
            old[s] = signal.signal(s, lambda signum, frame: pending.append(signum))
        except (ValueError, OSError):  # pragma: no cover
            pass
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        for s in pending:
            signal.raise_signal(s)


# ------------------------------------------------------------------------------------------
# One file
# ------------------------------------------------------------------------------------------


def _prepare_folder(folder: Path, target: Path) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise OutputError(f"cannot write {target}: {folder} is a file, not a folder") from None
    except OSError as exc:
        raise as_output_error(exc, target) from None
    if not folder.is_dir():
        raise OutputError(f"cannot write {target}: {folder} is a file, not a folder")
    clean_stale(folder)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``.

    The temporary keeps the target's suffix (writers that choose a format by suffix work) and
    exists as an empty file when yielded. On success its mode is set from the umask, it is
    flushed to disk and renamed over ``path``; on any exception (KeyboardInterrupt included) it
    is removed. ``OSError`` from the file system becomes :class:`OutputError`.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: a folder of that name is in the way")
    _prepare_folder(path.parent, path)
    tmp = path.parent / _tmp_name(path.name, path.suffix)
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        os.close(fd)
    except OSError as exc:
        raise as_output_error(exc, path) from None
    _register(tmp)
    try:
        yield tmp
        try:
            os.chmod(tmp, file_mode())
            with contextlib.suppress(OSError):
                fd = os.open(tmp, os.O_RDONLY | os.O_CLOEXEC)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
            os.replace(tmp, path)
        except OSError as exc:
            raise as_output_error(exc, path) from None
    except BaseException as exc:
        _remove(tmp)
        if _is_write_error(exc, tmp):
            raise as_output_error(exc, path) from None  # type: ignore[arg-type]
        raise
    finally:
        _unregister(tmp)


def write_bytes(path: str | Path, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
    return Path(path)


def write_text(path: str | Path, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | Path, obj: Any) -> Path:
    return write_text(path, dumps(obj) + "\n")


# ------------------------------------------------------------------------------------------
# A set of files
# ------------------------------------------------------------------------------------------


def _files_below(folder: Path) -> list[Path]:
    out = []
    for root, _dirs, files in os.walk(folder):
        for f in files:
            if f != _COMMIT_MARKER:
                out.append(Path(root) / f)
    return sorted(out)


def _move_into(stage: Path, target: Path) -> None:
    """Move every file of ``stage`` to the same relative place in ``target`` (replacing)."""
    for src in _files_below(stage):
        rel = src.relative_to(stage)
        dst = target / rel
        if dst.parent != target:
            if dst.parent.exists() and not dst.parent.is_dir():
                raise OutputError(f"cannot write {dst}: {dst.parent} is a file, not a folder")
            dst.parent.mkdir(parents=True, exist_ok=True)
        if dst.is_dir() and not dst.is_symlink():
            raise OutputError(f"cannot write {dst}: a folder of that name is in the way")
        os.replace(src, dst)


@contextlib.contextmanager
def _dir_lock(folder: Path) -> Iterator[None]:
    """Exclusive advisory lock on a folder (serialises commits into the same parent)."""
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


@contextlib.contextmanager
def output_set(out: str | Path) -> Iterator[Path]:
    """Write a set of files into folder ``out`` all at once: yields the staging folder to write in.

    ``out`` is checked first (a file in its place, an unwritable parent raise
    :class:`OutputError` before any work is done). Files written below the staging folder
    appear in ``out`` only when the block ends without an exception, all together; other
    files already in ``out`` are left alone (files of the same name are replaced).
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OutputError(f"cannot write into {out}: it is a file, not a folder")
    parent = out.absolute().parent
    _prepare_folder(parent, out)
    stage = parent / _tmp_name(out.name)
    try:
        os.mkdir(stage, 0o777)
    except OSError as exc:
        raise as_output_error(exc, out) from None
    _register(stage)
    try:
        try:
            yield stage
        except BaseException as exc:
            _remove(stage)
            if _is_write_error(exc, stage):
                raise as_output_error(exc, out) from None  # type: ignore[arg-type]
            raise
        with _signals_deferred(), _commit_lock, _dir_lock(parent):
            try:
                if out.exists() and not out.is_dir():
                    raise OutputError(f"cannot write into {out}: it is a file, not a folder")
                try:
                    os.rename(stage, out)  # target absent (or an empty folder): one atomic step
                except OSError as exc:
                    if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                        raise
                    marker = stage / _COMMIT_MARKER
                    marker.write_text(str(out.absolute()) + "\n", encoding="utf-8")
                    _move_into(stage, out)
                    _remove(stage)
            except OSError as exc:
                _remove(stage)
                raise as_output_error(exc, out) from None
            except BaseException:
                _remove(stage)
                raise
    finally:
        _unregister(stage)


# ------------------------------------------------------------------------------------------
# Reading: confined, bounded, regular files only
# ------------------------------------------------------------------------------------------

#: default limit for text inputs (TOML sidecars, probe files)
MAX_TEXT_BYTES = 4 * 1024**2
#: default limit for data files (CSV traces, spectra)
MAX_DATA_BYTES = 256 * 1024**2


def _within(path: Path, root: Path) -> bool:
    try:
        path.relative_to(root)
        return True
    except ValueError:
        return False


def resolve_input(path: str | Path, base: str | Path | None = None, *, what: str = "file",
                  allow_outside: bool = False, allowed_roots: Iterable[str | Path] = ()) -> Path:
    """The path a user or a data file names, resolved (relative to ``base`` if given) and confined.

    With ``base`` (the folder of the file that names ``path``), the resolved path (symbolic
    links followed) must be ``base`` or below it, or below one of ``allowed_roots``, unless
    ``allow_outside``. Without ``base`` the path is taken as given (the user typed it).
    """
    p = Path(path)
    if base is not None and not p.is_absolute():
        p = Path(base) / p
    if base is None or allow_outside:
        return p
    real = Path(os.path.realpath(p))
    roots = [Path(os.path.realpath(base))] + [Path(os.path.realpath(r)) for r in allowed_roots]
    if not any(_within(real, r) for r in roots):
        raise DataFormatError(
            f"{what} {path} lies outside the folder {base} of the file that names it; data files must "
            "be in that folder or below it (or be allowed explicitly)"
        )
    return p


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _mib(n: float) -> str:
    return f"{n / 1024**2:.3g} MiB"


def read_bytes(path: str | Path, base: str | Path | None = None, *, what: str = "file",
               max_bytes: int = MAX_DATA_BYTES, allow_outside: bool = False,
               allowed_roots: Sequence[str | Path] = ()) -> bytes:
    """Read a whole regular file of at most ``max_bytes``; see :func:`resolve_input` for ``base``.

    Refuses FIFOs, devices, sockets and folders before opening them (no hang, no endless
    read), re-checks the opened file (a swap between the check and the open is caught) and
    stops reading at ``max_bytes`` + 1 (a file that grows while read).
    """
    p = resolve_input(path, base, what=what, allow_outside=allow_outside, allowed_roots=allowed_roots)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise DataFormatError(f"{what} {p}: no such file") from None
    except OSError as exc:
        raise DataFormatError(f"{what} {p}: cannot read ({exc.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise DataFormatError(f"{what} {p} is {_kind(st.st_mode)}; a regular file is needed")
    if st.st_size > max_bytes:
        raise DataFormatError(f"{what} {p} is {_mib(st.st_size)}, more than the limit of {_mib(max_bytes)}")
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    except OSError as exc:
        raise DataFormatError(f"{what} {p}: cannot read ({exc.strerror})") from None
    try:
        st2 = os.fstat(fd)
        if not stat.S_ISREG(st2.st_mode) or (st2.st_dev, st2.st_ino) != (st.st_dev, st.st_ino):
            raise DataFormatError(f"{what} {p} changed while being opened; a regular file is needed")
        if base is not None and not allow_outside:  # the file actually opened, links resolved
            with contextlib.suppress(OSError):
                resolve_input(os.readlink(f"/proc/self/fd/{fd}"), base, what=what, allowed_roots=allowed_roots)
        chunks = []
        total = 0
        while True:
            b = os.read(fd, min(1 << 20, max_bytes + 1 - total))
            if not b:
                break
            chunks.append(b)
            total += len(b)
            if total > max_bytes:
                raise DataFormatError(f"{what} {p} is larger than the limit of {_mib(max_bytes)}")
        return b"".join(chunks)
    except OSError as exc:
        raise DataFormatError(f"{what} {p}: cannot read ({exc.strerror})") from None
    finally:
        os.close(fd)


def read_text(path: str | Path, base: str | Path | None = None, *, what: str = "file",
              max_bytes: int = MAX_TEXT_BYTES, **kw: Any) -> str:
    """:func:`read_bytes` decoded as UTF-8 (a BOM is accepted); a bad byte is located, not shown."""
    data = read_bytes(path, base, what=what, max_bytes=max_bytes, **kw)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        name = Path(path) if base is None else resolve_input(path, base, allow_outside=True)
        raise DataFormatError(
            f"{what} {name}:{line}:{col}: not UTF-8 text (save the file as UTF-8)"
        ) from None


def load_toml(path: str | Path, base: str | Path | None = None, *, what: str = "TOML file",
              max_bytes: int = MAX_TEXT_BYTES, **kw: Any) -> dict[str, Any]:
    """Read a TOML file through :func:`read_text`; syntax errors name file, line and column."""
    text = read_text(path, base, what=what, max_bytes=max_bytes, **kw)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DataFormatError(f"{path}: {exc}") from None
