"""The ``probedyn`` command line: a thin layer over the library, and the one place exit codes are made.

Exit codes and messages (one line on stderr, never a traceback for anything a user can cause):

* ``0`` success;
* ``2`` ``probedyn: error: ...`` for bad input of any kind: usage errors (no or unknown
  command, unknown option, missing argument, a value that is not a number or out of range),
  :class:`probedyn.core.errors.ProbedynError` raised by the library (bad parameters, data,
  outputs that cannot be written, missing system libraries, unreachable schedulers, models
  that cannot fit in memory), and, as a last net, ``OSError``/``MemoryError`` from the
  environment;
* ``128 + signal`` ``probedyn: interrupted`` for SIGINT (130), SIGTERM (143) and SIGHUP (129):
  the handlers below raise :class:`Interrupted` in the main thread, outputs being written are
  discarded on the way out (:mod:`probedyn.core.io` writes nothing in place), and the code is
  decided from the signal received, whatever the layers in between (typer, Dask, numba) made
  of the exception. A watchdog thread woken by the signal itself (``signal.set_wakeup_fd``, so
  it works while the main thread sits in a long native call such as a PARDISO factorisation)
  forces the exit after :data:`GRACE_S` seconds, or at once on a second signal;
* ``141`` quietly when stdout is closed early (``probedyn ... | head``);
* ``1`` with a traceback: a bug.

Outputs: every command runs in one :func:`probedyn.core.io.transaction`, so the files it writes
(``--out`` folders, the report, plots, NetCDF files) appear when it succeeds, all together, and
never when it fails or is interrupted.

Long work reported by the library through :mod:`probedyn.core.progress` (model-size estimates,
stages that take more than a few seconds) is shown on stderr while a command runs.

Usage errors are recognised by what they are (a ``ClickException``/``Exit``/``Abort`` class in
the exception's MRO), whether typer uses the ``click`` package or its own bundled copy
(``typer._click``, typer >= 0.2x); the range tested is pinned in ``pyproject.toml``.
"""

from __future__ import annotations

import errno
import importlib
import os
import select
import signal
import sys
import threading
from typing import Any


def _early_interrupt(signum: int, frame: Any) -> None:  # pragma: no cover - timing dependent
    """Until :func:`main` installs its handlers (while the commands are imported): nothing is
    written yet, so leave at once with the same line and code as later. Worker processes
    (Dask's, started with multiprocessing, import this module again) leave silently: Ctrl-C in a
    terminal reaches the whole process group, and the line is the main process's to print."""
    import multiprocessing

    if multiprocessing.parent_process() is None:
        os.write(2, b"probedyn: interrupted\n")
    os._exit(128 + signum)


# Run as the program (console script or ``python -m probedyn.cli``), not imported by a host
# process (tests, notebooks): an interrupt during the imports below is already clean.
_AS_PROGRAM = __name__ == "__main__" or os.path.basename(sys.argv[0] if sys.argv else "") == "probedyn"
if _AS_PROGRAM:
    for _s in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        # a signal ignored by whoever started us stays ignored (``cmd &`` in a script, nohup)
        if _s is not None and signal.getsignal(_s) is not signal.SIG_IGN:
            signal.signal(_s, _early_interrupt)

from probedyn.commands import COMMAND_MODULES
from probedyn.commands._apps import app
from probedyn.core import io, progress
from probedyn.core.errors import ProbedynError

for _name in COMMAND_MODULES:
    # Each module attaches its commands to the Typer apps. A module that does not exist (yet)
    # is skipped here; tests/test_cli_basics.py asserts that every listed module is present.
    try:
        importlib.import_module(_name)
    except ModuleNotFoundError as _exc:
        if _exc.name != _name:
            raise

PROG = "probedyn"
EXIT_USAGE = 2
#: seconds the main thread gets to unwind (remove temporaries, close Dask) after an interrupt
#: before the watchdog forces the exit (``PROBEDYN_INTERRUPT_GRACE_S`` overrides)
GRACE_S = 10.0
_SIGNALS = tuple(s for s in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)) if s is not None)


class Interrupted(KeyboardInterrupt):
    """Raised in the main thread by SIGINT/SIGTERM/SIGHUP while a command runs."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _say(msg: str, raw: bool = False) -> None:
    """One line on stderr; ``raw`` writes to file descriptor 2 directly (the watchdog thread)."""
    line = PROG + ": " + " ".join(str(msg).split()) + "\n"
    try:
        if raw:
            os.write(2, line.encode("utf-8", "replace"))
        else:
            sys.stderr.write(line)
            sys.stderr.flush()
    except (OSError, ValueError):
        pass


# ------------------------------------------------------------------------------------------
# Signals
# ------------------------------------------------------------------------------------------


class _SignalGuard:
    """Install interrupt handlers and the watchdog for the duration of one :func:`main` call."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._old: dict[int, Any] = {}
        self._old_wakeup = -1
        self._pipe: tuple[int, int] | None = None
        self._stop: tuple[int, int] | None = None
        self._thread: threading.Thread | None = None
        self.closing = False
        self.active = threading.current_thread() is threading.main_thread()

    def _handler(self, signum: int, frame: Any) -> None:
        if self.signum is None:
            self.signum = signum
            if not self.closing:
                raise Interrupted(signum)
        # later signals, or a signal while the handlers are being removed: let the unwinding
        # finish (the exit code still says "interrupted"); the watchdog forces the exit if needed

    def install(self) -> None:
        if not self.active:
            return
        for s in _SIGNALS:
            try:
                if signal.getsignal(s) is signal.SIG_IGN:
                    # ignored by whoever started us (a background job without job control
                    # ignores SIGINT, nohup SIGHUP): the convention is to keep ignoring it
                    continue
                self._old[s] = signal.signal(s, self._handler)
            except (OSError, ValueError):  # pragma: no cover
                pass
        try:
            r, w = os.pipe()
            os.set_blocking(w, False)
            sr, sw = os.pipe()
            self._pipe, self._stop = (r, w), (sr, sw)
            self._old_wakeup = signal.set_wakeup_fd(w, warn_on_full_buffer=False)
        except (OSError, ValueError):  # pragma: no cover
            return
        self._thread = threading.Thread(target=self._watch, name="probedyn-interrupt-watchdog", daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        assert self._pipe and self._stop
        r, sr = self._pipe[0], self._stop[0]
        seen: list[int] = []
        deadline = None
        while True:
            timeout = None if deadline is None else max(0.0, deadline - _monotonic())
            try:
                ready, _, _ = select.select([r, sr], [], [], timeout)
            except (OSError, ValueError):
                return
            if sr in ready:
                return
            if r in ready:
                try:
                    data = os.read(r, 64)
                except OSError:
                    return
                new = [b for b in data if b in _SIGNALS]
                if not new:
                    continue
                seen += new
                if deadline is None:
                    deadline = _monotonic() + _grace_s()
                if len(seen) >= 2:  # a second interrupt: do not wait any longer
                    self._force(seen[0])
            elif deadline is not None and _monotonic() >= deadline:
                self._force(seen[0])

    def _force(self, signum: int) -> None:
        _say("interrupted", raw=True)
        io.discard_active()
        os._exit(128 + signum)

    def uninstall(self) -> None:
        self.closing = True
        if not self.active:
            return
        for s, h in self._old.items():
            try:
                signal.signal(s, h)
            except (OSError, ValueError):  # pragma: no cover
                pass
        if self._pipe is not None:
            try:
                signal.set_wakeup_fd(self._old_wakeup)
            except (OSError, ValueError):  # pragma: no cover
                pass
        if self._stop is not None:
            os.write(self._stop[1], b"x")
        if self._thread is not None:
            self._thread.join(timeout=5)
        for fds in (self._pipe, self._stop):
            for fd in fds or ():
                try:
                    os.close(fd)
                except OSError:
                    pass


def _grace_s() -> float:
    try:
        g = float(os.environ.get("PROBEDYN_INTERRUPT_GRACE_S", GRACE_S))
    except ValueError:
        return GRACE_S
    return g if g >= 0 else GRACE_S


def _monotonic() -> float:
    import time

    return time.monotonic()


# ------------------------------------------------------------------------------------------
# Recognising click/typer exceptions by what they are
# ------------------------------------------------------------------------------------------


def _is(obj: Any, *names: str) -> bool:
    """Whether a class of ``obj``'s MRO has one of ``names`` (click's classes, whichever copy)."""
    return any(c.__name__ in names for c in type(obj).__mro__)


def _command_path(exc: BaseException) -> str:
    ctx = getattr(exc, "ctx", None)
    path = getattr(ctx, "command_path", None) if ctx is not None else None
    return path or PROG


def _usage_message(exc: BaseException) -> str:
    path = _command_path(exc)
    if _is(exc, "NoArgsIsHelpError"):
        ctx = getattr(exc, "ctx", None)
        names: list[str] = []
        try:
            names = [n for n in ctx.command.list_commands(ctx) if not ctx.command.get_command(ctx, n).hidden]
        except Exception:  # pragma: no cover - defensive: message without the list
            pass
        listing = f" (commands: {', '.join(names)})" if names else ""
        return f"'{path}' needs a command{listing}; see '{path} --help'"
    try:
        msg = exc.format_message()  # type: ignore[attr-defined]
    except Exception:  # pragma: no cover
        msg = str(exc)
    msg = " ".join(str(msg).split()) or type(exc).__name__
    return f"{msg} (see '{path} --help')" if _is(exc, "UsageError") else msg


_CLICK_TREE: Any = None


def _finite(prm: Any) -> None:
    """Make the option or argument ``prm`` refuse NaN and infinities: no probedyn option has a
    meaning for them, and a NaN passes every ``x < lo or x > hi`` range check downstream (a
    result computed from nonsense). Wraps the parameter's ``process_value`` (click 8 and typer's
    bundled click alike); the error is click's own ``BadParameter`` (one usage line, exit 2)."""
    import math

    process = prm.process_value
    base = next(c for c in type(prm).__mro__ if c.__name__ == "Parameter")
    package = base.__module__.rsplit(".", 1)[0]
    bad_parameter = importlib.import_module(package + ".exceptions").BadParameter

    def checked(ctx: Any, value: Any) -> Any:
        v = process(ctx, value)
        items = v if isinstance(v, (list, tuple)) else (v,)
        for x in items:
            if isinstance(x, float) and not math.isfinite(x):
                raise bad_parameter(f"{x!r} is not a finite number", ctx=ctx, param=prm)
        return v

    prm.process_value = checked


def _harden(cmd: Any) -> None:
    """Walk the click tree once: every option and argument refuses NaN/inf (:func:`_finite`)."""
    for prm in getattr(cmd, "params", ()):
        _finite(prm)
    for sub in getattr(cmd, "commands", {}).values():
        _harden(sub)


def _tree() -> Any:
    """The click command tree of ``app``, built once (the commands are all registered at import)."""
    global _CLICK_TREE
    if _CLICK_TREE is None:
        import typer

        _CLICK_TREE = typer.main.get_command(app)
        _harden(_CLICK_TREE)
    return _CLICK_TREE


def _missing_command(argv: list[str]) -> str | None:
    """The usage error for ``probedyn [GROUP...]`` without a command, the same for every click version
    (click < 8.2 prints the help and exits 0 for ``no_args_is_help``; 8.2+ raises)."""
    cmd: Any = _tree()
    path = [PROG]
    tokens = list(argv)
    while hasattr(cmd, "commands"):
        if not tokens:
            names = [n for n, c in cmd.commands.items() if not getattr(c, "hidden", False)]
            where = " ".join(path)
            return f"'{where}' needs a command (commands: {', '.join(names)}); see '{where} --help'"
        tok = tokens.pop(0)
        if tok.startswith("-") or tok not in cmd.commands:
            return None  # an option (--help) or an unknown command: click reports it
        cmd = cmd.commands[tok]
        path.append(tok)
    return None


def _environment_message(exc: BaseException) -> str | None:
    """One line for an ``OSError``/``MemoryError`` that escaped the library (the last net)."""
    if isinstance(exc, MemoryError):
        return ("out of memory: the computation needs more memory than this machine has available; "
                "reduce the problem size")
    if isinstance(exc, OSError) and exc.errno is not None:
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror or os.strerror(exc.errno)}{where}"
    return None


# ------------------------------------------------------------------------------------------
# Entry point
# ------------------------------------------------------------------------------------------


def _dispatch(argv: list[str] | None) -> tuple[int, str | None]:
    """Run the command; return (exit code, one-line error message or None)."""
    missing = _missing_command(sys.argv[1:] if argv is None else argv)
    if missing:
        return EXIT_USAGE, f"error: {missing}"
    try:
        rv = _tree().main(args=argv, standalone_mode=False, prog_name=PROG)
    except ProbedynError as exc:
        return exc.exit_code, f"error: {exc}"
    except SystemExit as exc:  # a library or command that calls sys.exit
        code = exc.code
        if code is None or isinstance(code, int):
            return int(code or 0), None
        return EXIT_USAGE, f"error: {code}"
    except KeyboardInterrupt:
        raise
    except BaseException as exc:
        if _is(exc, "Exit") and hasattr(exc, "exit_code"):  # --help, --version, ctx.exit(n)
            return int(getattr(exc, "exit_code") or 0), None
        if _is(exc, "ClickException"):
            return EXIT_USAGE, f"error: {_usage_message(exc)}"
        if _is(exc, "Abort"):
            return EXIT_USAGE, "error: aborted (end of input)"
        if isinstance(exc, OSError) and exc.errno == errno.EPIPE:
            return 128 + signal.SIGPIPE, None
        msg = _environment_message(exc)
        if msg is not None and isinstance(exc, (OSError, MemoryError)):
            return EXIT_USAGE, f"error: {msg}"
        raise
    if isinstance(rv, int) and not isinstance(rv, bool):
        return rv, None  # typer returns 130 for a KeyboardInterrupt it swallowed
    return 0, None


class _Failed(Exception):
    """Internal: the command failed; roll its outputs back."""


def _run_in_transaction(argv: list[str] | None) -> tuple[int, str | None]:
    """Run the command in one output transaction (:func:`probedyn.core.io.transaction`): every
    file it writes appears when it succeeds, all together; when it fails or is interrupted,
    none does and the previous outputs stay as they were."""
    result: tuple[int, str | None] = (1, None)
    try:
        with io.transaction():
            result = _dispatch(argv)
            if result[0] != 0:
                raise _Failed
    except _Failed:
        pass
    except ProbedynError as exc:  # the commit itself failed (a full disk at the last moment)
        result = (exc.exit_code, f"error: {exc}")
    return result


def main(argv: list[str] | None = None) -> int:
    """Run ``probedyn ARGV``; return the exit code (see the module docstring)."""
    guard = _SignalGuard()
    code, msg = 1, None
    try:
        try:
            guard.install()
            with progress.listening(progress.stderr_listener()):
                code, msg = _run_in_transaction(argv)
        except KeyboardInterrupt as exc:
            if guard.signum is None:  # a KeyboardInterrupt raised without our handler
                guard.signum = getattr(exc, "signum", signal.SIGINT)
        except BaseException:
            if guard.signum is None:
                raise
            # an interrupt turned into another exception on its way up (a library that wraps
            # what it catches): the signal decides the exit code
    finally:
        guard.uninstall()
        if _AS_PROGRAM:
            # the work is over: an interrupt while the interpreter shuts down (which resets
            # Python's handlers to the default action) must not turn a finished run into a
            # death by signal; ignored signals stay ignored through the shutdown
            for s in _SIGNALS:
                signal.signal(s, signal.SIG_IGN)
    if guard.signum is not None:
        _say("interrupted")
        return 128 + guard.signum
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
        return 128 + signal.SIGPIPE
    except OSError:
        pass
    if code == 128 + signal.SIGPIPE:
        _silence_stdout()
    if msg:
        _say(msg)
    return code


def _silence_stdout() -> None:
    """stdout's reader went away: point fd 1 at /dev/null so the interpreter's final flush is quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
