"""The ``--probe`` option every scheme command shares: a reduced probe from a registry name, a
TOML probe file, a saved reduced probe (``.json``) or a source table (``table-2.1`` ...)."""

from __future__ import annotations

from typing import Any, Optional

import typer

PROBE_OPT = typer.Option(
    None, "--probe",
    help="Probe the scheme runs on: a registry probe (cantilever, duo-bimorph, piezotube), a TOML probe file, "
         "a saved reduced probe (.json) or a source table (table-2.1, table-2.2, table-4.1, table-4.3). "
         "It is reduced from its FEM (cached) and its scan/lateral/normal springs, masses and damping replace "
         "the preset's.")
PROBE_SET_OPT = typer.Option(None, "--probe-set", help="Probe parameter NAME=VALUE (SI units), e.g. "
                                                        "tip_shape=pyramid. Repeatable.")
PROBE_MODES_OPT = typer.Option(6, "--probe-modes", help="Retained modes of the reduced probe.")
PROBE_Q_OPT = typer.Option(100.0, "--probe-q", help="Quality factor of the reduced probe's modes (air).")


def load_probe(spec: Optional[str], sets: Optional[list[str]] = None, n_modes: int = 6, Q: float | None = 100.0):
    """The :class:`~probedyn.lumped.reduced.ReducedProbe` of ``--probe`` (None without one)."""
    if spec is None:
        if sets:
            from probedyn.core.errors import ParameterError

            raise ParameterError("--probe-set needs --probe")
        return None
    import math

    from probedyn.core.errors import ParameterError
    from probedyn.core.params import parse_sets
    from probedyn.probes.reduce import resolve_probe

    # checked whatever the probe (a table or saved probe has its own modes and damping: the
    # options must still make sense, not be dropped silently when they do not)
    if not 1 <= n_modes <= 50:
        raise ParameterError(f"--probe-modes must lie in 1..50, got {n_modes}")
    if Q is not None and not (math.isfinite(Q) and Q > 0):
        raise ParameterError(f"--probe-q must be positive, got {Q:g}")

    return resolve_probe(spec, parse_sets(sets), n_modes=n_modes, Q=Q)


def probe_line(summary: dict[str, Any] | None) -> str:
    """One line naming the probe a scheme ran on (for the human output)."""
    if not summary:
        return ""
    parts = [f"probe: {summary.get('probe')} ({summary.get('source')})"]
    for d in ("scan", "lateral", "normal"):
        v = summary.get(d)
        if v:
            s = f"{d} k = {v['static_stiffness']:.4g} N/m"
            if v.get("effective_mass") is not None:
                s += f", m = {v['effective_mass']:.3g} kg"
            parts.append(s)
    if summary.get("dofs"):
        parts.append(f"{summary['dofs']} DOFs, mesh {summary.get('mesh_key')}")
    return "; ".join(parts)
