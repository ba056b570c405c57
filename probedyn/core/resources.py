"""Memory available to this process, and refusing work that cannot fit before allocating it.

:func:`available_memory` is the smaller of the kernel's ``MemAvailable`` (``/proc/meminfo``)
and the room left under the process's cgroup limit (v2 ``memory.max`` - ``memory.current``, or
v1 ``memory.limit_in_bytes`` - ``memory.usage_in_bytes``). :func:`check_memory` raises
:class:`~probedyn.core.errors.ResourceError` with the estimate and what is available when an
estimate exceeds :data:`USABLE_FRACTION` of it, so a user sees "needs ~320 GB, 21 GB available"
instead of a MemoryError traceback, an OOM kill or hours of swapping.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Iterator, Mapping

from probedyn.core.errors import ResourceError

#: share of the available memory one computation may plan to use
USABLE_FRACTION = 0.8


def _read(path: str) -> str | None:
    try:
        return Path(path).read_text().strip()
    except OSError:
        return None


def _cgroup_room() -> int | None:
    """Bytes left under this process's cgroup memory limit, or None without a limit."""
    rel = ""
    text = _read("/proc/self/cgroup") or ""
    for line in text.splitlines():
        parts = line.split(":", 2)
        if len(parts) == 3 and (parts[1] == "" or "memory" in parts[1].split(",")):
            rel = parts[2]
            if parts[1] == "":
                break
    for root in (f"/sys/fs/cgroup{rel}", "/sys/fs/cgroup"):
        mx, cur = _read(f"{root}/memory.max"), _read(f"{root}/memory.current")
        if mx and cur and mx != "max":
            try:
                return max(0, int(mx) - int(cur))
            except ValueError:
                pass
        mx, cur = _read(f"{root}/memory.limit_in_bytes"), _read(f"{root}/memory.usage_in_bytes")
        if mx and cur:
            try:
                lim = int(mx)
                if lim < 1 << 60:  # v1 "no limit" is a huge number
                    return max(0, lim - int(cur))
            except ValueError:
                pass
    return None


def available_memory() -> int:
    """Bytes this process can still allocate without swapping (see the module docstring)."""
    avail = None
    for line in (_read("/proc/meminfo") or "").splitlines():
        if line.startswith("MemAvailable:"):
            avail = int(line.split()[1]) * 1024
            break
    if avail is None:  # pragma: no cover - not Linux
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError):
            avail = 1 << 62
    room = _cgroup_room()
    return min(avail, room) if room is not None else avail


def fmt_bytes(n: float) -> str:
    """``3.2 GB`` (decimal units, 2-3 significant digits)."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def check_memory(nbytes: float, what: str, how: str = "", hint: str = "") -> None:
    """Raise :class:`ResourceError` if ``nbytes`` exceed the usable share of available memory.

    ``what`` names the computation, ``how`` how the estimate was made (e.g. "1e10 cells x 32 B"),
    ``hint`` what the user can change.
    """
    avail = available_memory()
    if nbytes > USABLE_FRACTION * avail:
        est = f"about {fmt_bytes(nbytes)}" + (f" ({how})" if how else "")
        raise ResourceError(
            f"{what} needs {est} of memory; {fmt_bytes(avail)} are available"
            + (f": {hint}" if hint else "")
        )


@contextlib.contextmanager
def environment(env: Mapping[str, str]) -> Iterator[None]:
    """Set the variables of ``env`` for the duration of the block, then restore each one (or
    remove it if it was unset). For settings read when a process or library starts, e.g. the
    thread counts handed to the report's worker processes."""
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
