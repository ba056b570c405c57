"""Every file probedyn writes or reads on a user's behalf goes through here.

Writing: one mechanism for one file and for sets of files.

* :func:`atomic_path` / :func:`write_text` / :func:`write_json` / :func:`write_bytes`: a file is
  written to a temporary name beside its target, then renamed into place (``os.replace`` is
  atomic on POSIX): a reader sees the old file or the new one, never half of one.
* A **transaction** (:func:`transaction`, or :func:`output_set` for one folder) defers those
  renames: every file written while it is open stays under its temporary name until the block
  ends. Without an exception, all of them are renamed into place together (a journal listing
  the renames is written first, SIGINT/SIGTERM/SIGHUP are held until the renames are done);
  with an exception, KeyboardInterrupt included, all temporaries are removed and folders the
  transaction created are removed again when empty. So ``modes.json`` and ``modes.vtu``, or a
  report and its figures, appear together or not at all, and an interrupted run leaves the
  previous outputs untouched. The command line runs every command in one transaction
  (:mod:`probedyn.cli`). A run killed with SIGKILL during the renames (microseconds) leaves
  its journal; the next probedyn run writing into that folder completes them ("roll forward").
  Caches and resumable state (mesh cache, a sweep's finished chunks) are written with
  ``defer=False``: they are kept even when the run fails.
* Temporaries and journals are named ``.<name>.probedyn-tmp-<host>-<pid>-<random>``;
  :func:`clean_stale` removes those of dead processes (automatically, once per folder per
  process, before anything is written there).
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Sequence

import numpy as np

from probedyn.core.errors import DataFormatError, OutputError

__all__ = [
    "to_jsonable", "dumps", "atomic_path", "write_text", "write_json", "write_bytes", "transaction",
    "output_set", "make_dirs", "check_output_folder", "check_output_file", "after_commit", "as_output_error", "clean_stale", "file_mode",
    "discard_active", "read_bytes", "read_text", "load_toml", "resolve_input", "MAX_TEXT_BYTES",
    "MAX_DATA_BYTES",
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
_JOURNAL = "probedyn-commit"  # the <name> of a journal: .probedyn-commit.probedyn-tmp-...
#: a temporary of another host (or a recycled pid) is stale after this long without change
STALE_AFTER_S = 24 * 3600.0

_active: set[Path] = set()
_active_lock = threading.Lock()
_commit_lock = threading.Lock()  # held while a transaction renames its files into place
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
    """Remove every temporary this process is writing or holding for a commit (best effort).

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


def _replay(journal: Path) -> None:
    """Finish the renames a killed commit listed in ``journal`` (those whose temporary remains)."""
    with contextlib.suppress(OSError, ValueError, TypeError):
        for tmp, final in json.loads(journal.read_text(encoding="utf-8")):
            if os.path.exists(tmp):
                os.replace(tmp, final)


def clean_stale(folder: str | Path, force: bool = False) -> list[Path]:
    """Remove temporaries left in ``folder`` by killed probedyn runs; finish interrupted commits.

    A temporary is stale when it was made on this host by a process that no longer exists, or
    when it has not changed for :data:`STALE_AFTER_S`. A stale commit journal is replayed first
    (the run was killed while renaming its files into place). Returns what was removed. Runs
    once per folder per process unless ``force``.
    """
    folder = Path(folder)
    key = folder.absolute()
    if key in _cleaned and not force:
        return []
    _cleaned.add(key)
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return []
    now = time.time()
    stale = []
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
        if dead or age >= STALE_AFTER_S:
            stale.append((m.group("name") == _JOURNAL, Path(e.path)))
    for is_journal, p in sorted(stale, key=lambda t: not t[0]):  # journals first
        if is_journal:
            _replay(p)
        _remove(p)
    return [p for _, p in stale]


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
_ALWAYS_WRITE = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG}


def as_output_error(exc: OSError, target: Path) -> OutputError:
    """The one-line :class:`OutputError` for an ``OSError`` raised while writing ``target``."""
    reason = _WRITE_ERRNOS.get(exc.errno or -1) or exc.strerror or type(exc).__name__
    return OutputError(f"cannot write {target}: {reason}")


def _is_write_error(exc: BaseException, where: Path) -> bool:
    """An OSError that comes from writing ``where`` (full or read-only file systems always do)."""
    if not isinstance(exc, OSError) or exc.errno not in _WRITE_ERRNOS:
        return False
    if exc.errno in _ALWAYS_WRITE:
        return True
    names = [n for n in (exc.filename, getattr(exc, "filename2", None)) if n]
    return any(Path(os.path.abspath(n)) == where.absolute() for n in names)


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
    old = {}
    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
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
# Transactions
# ------------------------------------------------------------------------------------------


@dataclass
class _Transaction:
    roots: list[Path] | None                       # None: every deferred write
    pending: dict[Path, Path] = field(default_factory=dict)   # final -> temporary
    created: list[Path] = field(default_factory=list)         # folders made, outermost first
    after: list[Callable[[], Any]] = field(default_factory=list)

    def covers(self, path: Path) -> bool:
        if self.roots is None:
            return True
        a = path.absolute()
        return any(a == r or _within(a, r) for r in self.roots)


_local = threading.local()  # each thread has its own stack of open transactions


def _stack() -> list[_Transaction]:
    st = getattr(_local, "stack", None)
    if st is None:
        st = _local.stack = []
    return st


def _current(path: Path) -> _Transaction | None:
    for tx in reversed(_stack()):
        if tx.covers(path):
            return tx
    return None


def make_dirs(folder: str | Path) -> Path:
    """``mkdir -p`` for outputs: inside a transaction, folders it creates are removed again (when
    empty) if the transaction fails. A file in the way is :class:`OutputError`."""
    folder = Path(folder)
    missing = []
    p = folder.absolute()
    while not p.exists() and p != p.parent:
        missing.append(p)
        p = p.parent
    if p.exists() and not p.is_dir():
        raise OutputError(f"cannot write into {folder}: {p} is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise OutputError(f"cannot write into {folder}: it is a file, not a folder") from None
    except OSError as exc:
        raise as_output_error(exc, folder) from None
    if not folder.is_dir():
        raise OutputError(f"cannot write into {folder}: it is a file, not a folder")
    tx = _current(folder)
    if tx is not None:
        tx.created.extend(reversed(missing))
    return folder


def _writable_ancestor(path: Path, what: Path) -> None:
    """The nearest existing ancestor of ``path`` must be a folder this process can write in."""
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    if not p.is_dir():
        raise OutputError(f"cannot write {what}: {p} is a file, not a folder")
    if not os.access(p, os.W_OK | os.X_OK):
        try:  # access() says why only through errno: EROFS or EACCES
            os.statvfs(p)
            ro = bool(os.statvfs(p).f_flag & os.ST_RDONLY)
        except OSError:
            ro = False
        raise OutputError(f"cannot write {what}: {'read-only file system' if ro else 'permission denied'} ({p})")


def check_output_folder(folder: str | Path) -> Path:
    """Fail early (before any work) if ``folder`` cannot become an output folder; creates nothing."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"cannot write into {folder}: it is a file, not a folder")
    _writable_ancestor(folder, folder)
    return folder


def check_output_file(path: str | Path) -> Path:
    """Fail early (before any work) if the file ``path`` cannot be written; creates nothing."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: a folder of that name is in the way")
    if path.parent.exists() and not path.parent.is_dir():
        raise OutputError(f"cannot write {path}: {path.parent} is a file, not a folder")
    _writable_ancestor(path.parent, path)
    return path


def after_commit(action: Callable[[], Any]) -> None:
    """Run ``action`` once the current transaction has put its files in place (at once without one).

    For clean-ups that must not happen unless the outputs exist (a sweep removes its chunks
    only once the merged NetCDF file is in place).
    """
    st = _stack()
    tx = st[-1] if st else None
    if tx is None:
        action()
    else:
        tx.after.append(action)


def _rollback(tx: _Transaction) -> None:
    for tmp in tx.pending.values():
        _remove(tmp)
        _unregister(tmp)
    tx.pending.clear()
    for d in reversed(tx.created):  # innermost first; only if empty
        with contextlib.suppress(OSError):
            d.rmdir()


@contextlib.contextmanager
def _folder_locks(folders: Iterable[Path]) -> Iterator[None]:
    """Exclusive advisory locks on folders, in a fixed order: commits into the same folders by
    several processes happen one after the other, never interleaved."""
    with contextlib.ExitStack() as stack:
        for d in sorted({Path(f).absolute() for f in folders}):
            try:
                fd = os.open(d, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
            except OSError:
                continue
            stack.callback(os.close, fd)
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield


def _commit(tx: _Transaction) -> None:
    if tx.pending:
        items = list(tx.pending.items())
        first = items[0][0]
        with _signals_deferred(), _commit_lock, _folder_locks(f.parent for f, _ in items):
            journal = None

            def drop_journal() -> None:
                if journal is not None:
                    with contextlib.suppress(OSError):
                        journal.unlink()

            try:
                if len(items) > 1:  # one rename is atomic by itself
                    journal = first.parent / _tmp_name(_JOURNAL, ".json")
                    fd = os.open(journal, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
                    with os.fdopen(fd, "w", encoding="utf-8") as fh:
                        json.dump([[str(t.absolute()), str(f.absolute())] for f, t in items], fh)
                        fh.flush()
                        os.fsync(fh.fileno())
                for final, tmp in items:
                    if final.is_dir() and not final.is_symlink():
                        raise OutputError(f"cannot write {final}: a folder of that name is in the way")
                    os.replace(tmp, final)
                    _unregister(tmp)
            except OSError as exc:
                drop_journal()
                _rollback(tx)
                raise as_output_error(exc, first) from None
            except BaseException:
                drop_journal()
                _rollback(tx)
                raise
            drop_journal()
        tx.pending.clear()
    for action in tx.after:
        action()


@contextlib.contextmanager
def transaction(roots: Iterable[str | Path] | None = None) -> Iterator[_Transaction]:
    """Defer the renames of files written while the block runs (below ``roots``, or all); see
    the module docstring. Nested transactions covering a path join the outer one."""
    tx = _Transaction([Path(r).absolute() for r in roots] if roots is not None else None)
    st = _stack()
    st.append(tx)
    try:
        try:
            yield tx
        finally:
            st.remove(tx)
    except BaseException:
        _rollback(tx)
        raise
    outer = None
    if tx.pending or tx.after or tx.created:
        outer = next((o for o in reversed(st)
                      if all(o.covers(f) for f in tx.pending) and (tx.roots is None) <= (o.roots is None)), None)
    if outer is not None:  # nested: the outer transaction commits (or rolls back) everything
        outer.pending.update(tx.pending)
        outer.created.extend(tx.created)
        outer.after.extend(tx.after)
        return
    _commit(tx)


@contextlib.contextmanager
def output_set(out: str | Path) -> Iterator[Path]:
    """Write a set of files into folder ``out``, all at once or not at all; yields ``out``.

    ``out`` is checked and created first (a file in its place, an unwritable parent raise
    :class:`OutputError` before any work is done). Files written below ``out`` through this
    module appear when the block ends without an exception, together; other files already in
    ``out`` are left alone (files of the same name are replaced).
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OutputError(f"cannot write into {out}: it is a file, not a folder")
    with transaction([out]):
        make_dirs(out)
        clean_stale(out)
        yield out


# ------------------------------------------------------------------------------------------
# One file
# ------------------------------------------------------------------------------------------


def _prepare_folder(folder: Path, target: Path) -> None:
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"cannot write {target}: {folder} is a file, not a folder")
    p = folder.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    if not p.is_dir():
        raise OutputError(f"cannot write {target}: {p} is a file, not a folder")
    make_dirs(folder)
    clean_stale(folder)


@contextlib.contextmanager
def atomic_path(path: str | Path, defer: bool = True) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends, rename it to ``path``.

    The temporary keeps the target's suffix (writers that choose a format by suffix work) and
    exists as an empty file when yielded. On success its mode is set from the umask and it is
    flushed to disk; inside a :func:`transaction` covering ``path`` (and ``defer``) the rename
    waits for the transaction's end, otherwise it happens at once. On any exception
    (KeyboardInterrupt included) the temporary is removed. ``OSError`` from the file system
    becomes :class:`OutputError`.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"cannot write {path}: a folder of that name is in the way")
    _prepare_folder(path.parent, path)
    tmp = path.parent / _tmp_name(path.name, path.suffix)
    keep = False
    try:
        # registered before it exists and created inside the try: an interrupt at any bytecode
        # from here on removes it (it used to leave a temporary, and so the folder, when it
        # came between the creation and the registration)
        _register(tmp)
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
            os.close(fd)
        except OSError as exc:
            raise as_output_error(exc, path) from None
        yield tmp
        try:
            os.chmod(tmp, file_mode())
            with contextlib.suppress(OSError):
                fd = os.open(tmp, os.O_RDONLY | os.O_CLOEXEC)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
            tx = _current(path) if defer else None
            if tx is not None:
                old = tx.pending.pop(path.absolute(), None)
                if old is not None:  # written twice in one transaction: the last one counts
                    _remove(old)
                    _unregister(old)
                tx.pending[path.absolute()] = tmp
                keep = True
            else:
                os.replace(tmp, path)
        except OSError as exc:
            raise as_output_error(exc, path) from None
    except BaseException as exc:
        _remove(tmp)
        if _is_write_error(exc, tmp):
            raise as_output_error(exc, path) from None  # type: ignore[arg-type]
        raise
    finally:
        if not keep:
            _unregister(tmp)


def write_bytes(path: str | Path, data: bytes, defer: bool = True) -> Path:
    with atomic_path(path, defer=defer) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
    return Path(path)


def write_text(path: str | Path, text: str, defer: bool = True) -> Path:
    return write_bytes(path, text.encode("utf-8"), defer=defer)


def write_json(path: str | Path, obj: Any, defer: bool = True) -> Path:
    return write_text(path, dumps(obj) + "\n", defer=defer)


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
