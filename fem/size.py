"""How big a FEM model will be, before it is built or solved: DOFs, memory, time.

Measured on this project's P2 tetrahedral elasticity with MKL PARDISO shift-invert
(``ElasticModel.modes``), default cantilevers of 300 µm-2 mm (2-4 elements through the
thickness), 23k-455k DOFs, 2 shared cores (issue 16, class 10):

=============================  ==========================================
tetrahedra per volume          4.9-5.7 V / h^3 (h: the mesh size)  -> 5.5
DOFs per tetrahedron           5.0-5.7                             -> 5.3
peak memory of a modal solve   150 MB + 9.0-10.4 kB per DOF        -> 10 kB
wall time (assembly + solve)   0.25-0.33 ms per DOF                -> 0.3 ms
=============================  ==========================================

The factor's fill grows faster than linearly for chunky 3D bodies (nested dissection:
~n^(4/3)), so for them the estimate is a lower bound. :func:`check_model` announces a large
model through :mod:`probedyn.core.progress` (the command line prints it) and refuses one that
cannot fit in this machine's memory (:class:`~probedyn.core.errors.ResourceError`) before any
of it is allocated.
"""

from __future__ import annotations

from probedyn.core import progress
from probedyn.core.resources import check_memory, fmt_bytes

TETS_PER_H3 = 5.5
DOFS_PER_TET = 5.3
BASE_BYTES = 150e6
BYTES_PER_DOF = 10e3
SECONDS_PER_DOF = 0.3e-3
#: models from this size on are announced before they are built
ANNOUNCE_DOFS = 100_000

__all__ = ["dofs_for_volume", "estimate", "check_model", "describe"]


def dofs_for_volume(volume: float, h: float) -> int:
    """P2 DOFs of a tetrahedral mesh of size ``h`` [m] filling ``volume`` [m^3] (estimate)."""
    return int(DOFS_PER_TET * TETS_PER_H3 * volume / h**3)


def estimate(n_dofs: float) -> tuple[float, float]:
    """(peak bytes, seconds) of assembling and solving a modal problem with ``n_dofs`` DOFs."""
    return BASE_BYTES + BYTES_PER_DOF * n_dofs, SECONDS_PER_DOF * n_dofs


def _count(n: float) -> str:
    if n >= 1e6:
        return f"{n / 1e6:.3g} million"
    if n >= 1e4:
        return f"{n / 1e3:.0f}k"
    return f"{n:.0f}"


def describe(n_dofs: float, what: str = "model") -> str:
    b, s = estimate(n_dofs)
    t = f"{s / 60:.0f} min" if s >= 120 else f"{s:.0f} s"
    return f"{what}: about {_count(n_dofs)} DOFs (P2), about {fmt_bytes(b)} and {t} to assemble and solve"


def check_model(n_dofs: float, what: str = "model", hint: str = "") -> None:
    """Announce a large model and refuse one that cannot fit in memory (see the module docstring)."""
    b, _ = estimate(n_dofs)
    check_memory(b, f"the FEM {what} (about {_count(n_dofs)} DOFs)",
                 how=f"{BYTES_PER_DOF / 1e3:.0f} kB per DOF, measured",
                 hint=hint or "use a coarser mesh (fewer elements through the thickness, a larger element_size) "
                              "or a smaller probe")
    if n_dofs >= ANNOUNCE_DOFS:
        progress.note(describe(n_dofs, what))
