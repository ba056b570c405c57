"""Keep Python's interrupt handlers installed across native libraries that reset them.

``gmsh.initialize()`` and ``gmsh.finalize()`` set SIGTERM and SIGHUP back to the default action
at the C level while Python still reports its own handler (measured with ``sigaction``; PARDISO,
numba, Dask, VTK and matplotlib leave them alone). A SIGTERM during meshing would then kill the
process without the command line's clean exit (``probedyn: interrupted``, temporaries removed).
gmsh also sets SIGPIPE back to the default action (Python ignores it and raises BrokenPipeError
instead; seen in /proc/self/status SigIgn): a later write to a pipe whose reader is gone (a
killed worker process, ``probedyn ... | head``) then killed the whole process with signal 13.
:func:`reassert_handlers` installs the Python-level handlers again; call it after such a library
call (in the main thread; elsewhere it does nothing).
"""

from __future__ import annotations

import signal
import threading

__all__ = ["reassert_handlers"]

_SIGNALS = tuple(s for s in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None),
                              getattr(signal, "SIGPIPE", None)) if s is not None)


def reassert_handlers() -> None:
    """Install again, at the C level, the handler Python believes each interrupt signal (and
    SIGPIPE: ignored) has."""
    if threading.current_thread() is not threading.main_thread():
        return
    for s in _SIGNALS:
        h = signal.getsignal(s)
        if h is not None:  # None: installed outside Python, nothing to restore
            try:
                signal.signal(s, h)
            except (OSError, ValueError):  # pragma: no cover
                pass
