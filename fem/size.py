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

Structured quadratic hexahedra (issue 15, ``hex-s2``: 20 nodes, a vertex couples to 81 nodes,
so a matrix row holds ~2.5x the entries of a P2-tetrahedron row, and the thin beam refined in
all three directions fills like a chunky body): measured on the cantilever, 49k-174k DOFs,
peak memory 22-27 kB per DOF -> 26 kB, 0.35-0.65 ms per DOF -> 0.6 ms (``hex-q2``, 27 nodes: 23 kB
and 0.34 ms per DOF at 61k DOFs; the hex-s2 coefficients are used).  The default hexahedral meshes are small (14k DOFs), so this
only matters for refined ones.  A structured mesh's DOFs are counted exactly before meshing
(``meshes.hexmeshes.cantilever_hex_dofs``).

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
#: (bytes per DOF, seconds per DOF) of a modal solve by element kind (module docstring)
ELEMENT_COEFFICIENTS = {"tet-p2": (BYTES_PER_DOF, SECONDS_PER_DOF), "hex-s2": (26e3, 0.6e-3),
                        "hex-q2": (26e3, 0.6e-3)}
#: models from this size on are announced before they are built
ANNOUNCE_DOFS = 100_000

__all__ = ["dofs_for_volume", "estimate", "check_model", "describe"]


def dofs_for_volume(volume: float, h: float) -> int:
    """P2 DOFs of a tetrahedral mesh of size ``h`` [m] filling ``volume`` [m^3] (estimate)."""
    return int(DOFS_PER_TET * TETS_PER_H3 * volume / h**3)


def estimate(n_dofs: float, element: str = "tet-p2") -> tuple[float, float]:
    """(peak bytes, seconds) of assembling and solving a modal problem with ``n_dofs`` DOFs."""
    b, s = ELEMENT_COEFFICIENTS.get(element, ELEMENT_COEFFICIENTS["tet-p2"])
    return BASE_BYTES + b * n_dofs, s * n_dofs


def _count(n: float) -> str:
    if n >= 1e6:
        return f"{n / 1e6:.3g} million"
    if n >= 1e4:
        return f"{n / 1e3:.0f}k"
    return f"{n:.0f}"


def describe(n_dofs: float, what: str = "model", element: str = "tet-p2") -> str:
    b, s = estimate(n_dofs, element)
    t = f"{s / 60:.0f} min" if s >= 120 else f"{s:.0f} s"
    kind = "P2" if element == "tet-p2" else element
    return f"{what}: about {_count(n_dofs)} DOFs ({kind}), about {fmt_bytes(b)} and {t} to assemble and solve"


def check_model(n_dofs: float, what: str = "model", hint: str = "", element: str = "tet-p2") -> None:
    """Announce a large model and refuse one that cannot fit in memory (see the module docstring)."""
    b, _ = estimate(n_dofs, element)
    per = ELEMENT_COEFFICIENTS.get(element, ELEMENT_COEFFICIENTS["tet-p2"])[0]
    check_memory(b, f"the FEM {what} (about {_count(n_dofs)} DOFs)",
                 how=f"{per / 1e3:.0f} kB per DOF, measured",
                 hint=hint or "use a coarser mesh (fewer elements through the thickness, a larger element_size) "
                              "or a smaller probe")
    if n_dofs >= ANNOUNCE_DOFS:
        progress.note(describe(n_dofs, what, element))
