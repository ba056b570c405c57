"""Progress of long computations: announced by the library, shown by the command line.

Library code never prints (see docs/developing.md); it reports instead:

* :func:`note` for an estimate worth knowing before a long step starts ("model: 3.4 million
  DOFs, about 33 GB"),
* :func:`stage` around a step that may take long ("factorising K (227k DOFs)"),

and does nothing else. Nothing is shown unless a listener is installed: the command line
installs :func:`stderr_listener` for the duration of a command, which prints notes at once and,
for a stage still running after :data:`FIRST_S` seconds, one line then and every
:data:`EVERY_S` seconds after (``probedyn: factorising K (227k DOFs) ... 30 s``), from a
daemon thread, so it also speaks while the main thread sits in a long native call.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from typing import Callable, Iterator, Protocol

__all__ = ["note", "stage", "listening", "stderr_listener", "Listener"]

#: a stage still running after this many seconds is announced
FIRST_S = 5.0
#: then once every this many seconds
EVERY_S = 15.0


class Listener(Protocol):
    def note(self, message: str) -> None: ...
    def begin(self, name: str) -> object: ...
    def end(self, token: object) -> None: ...


_listener: Listener | None = None


def note(message: str) -> None:
    """Report a one-line fact about the work ahead (an estimate); shown by the CLI."""
    if _listener is not None:
        _listener.note(message)


@contextlib.contextmanager
def stage(name: str) -> Iterator[None]:
    """Mark a step that may take long; the CLI shows it if it does."""
    if _listener is None:
        yield
        return
    token = _listener.begin(name)
    try:
        yield
    finally:
        _listener.end(token)


@contextlib.contextmanager
def listening(listener: Listener | None) -> Iterator[None]:
    """Install ``listener`` for the duration of the block (the previous one is restored)."""
    global _listener
    old, _listener = _listener, listener
    try:
        yield
    finally:
        _listener = old


class stderr_listener:
    """Prints ``probedyn: ...`` lines on stderr (see the module docstring)."""

    def __init__(self, write: Callable[[str], None] | None = None, first_s: float | None = None,
                 every_s: float | None = None):
        self._write = write or self._stderr
        self.first_s = FIRST_S if first_s is None else first_s
        self.every_s = EVERY_S if every_s is None else every_s

    @staticmethod
    def _stderr(line: str) -> None:
        try:
            sys.stderr.write(line + "\n")
            sys.stderr.flush()
        except (OSError, ValueError):
            pass

    def note(self, message: str) -> None:
        self._write(f"probedyn: {message}")

    def begin(self, name: str) -> object:
        stop = threading.Event()
        t0 = time.monotonic()

        def beat() -> None:
            wait = self.first_s
            while not stop.wait(wait):
                self._write(f"probedyn: {name} ... {time.monotonic() - t0:.0f} s")
                wait = self.every_s

        th = threading.Thread(target=beat, name="probedyn-progress", daemon=True)
        th.start()
        return stop, th

    def end(self, token: object) -> None:
        stop, th = token  # type: ignore[misc]
        stop.set()
        th.join(timeout=1.0)
