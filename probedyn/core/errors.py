"""User-facing errors.

Every error a user can cause by bad input derives from :class:`ProbedynError`; the command
line prints its message on one line and exits non-zero, without a traceback.
"""


class ProbedynError(Exception):
    """Base class of errors caused by input, data or environment (not by a bug)."""

    exit_code = 2


class ParameterError(ProbedynError, ValueError):
    """An unknown, malformed or non-physical parameter."""


class GeometryError(ParameterError):
    """A geometry that cannot exist (Ri >= Re, negative sizes, micrometres typed as metres)."""


class MaterialError(ParameterError):
    """An unknown material or an inadmissible elastic tensor."""


class SolverError(ProbedynError, RuntimeError):
    """A solver that did not converge, or a discretisation too coarse for the request."""


class DataFormatError(ProbedynError, ValueError):
    """A malformed measurement or input file; the message names file, line and column."""


class SystemLibraryError(ProbedynError, RuntimeError):
    """A missing system library (for example no OpenGL for off-screen rendering)."""


class OutputError(ProbedynError):
    """An output that cannot be written (read-only or full file system, permissions, a file
    where a folder should be); raised by :mod:`probedyn.core.io`."""


class ResourceError(ProbedynError):
    """A computation that cannot fit in this machine's memory (the message gives the estimate)."""
