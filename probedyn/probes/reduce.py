"""Reduced probes of the registry's probes: geometry -> FEM -> :class:`ReducedProbe`, cached.

``reduce_probe("cantilever", {"tip_shape": "pyramid"})`` meshes the probe, solves its modes and
the static loads at the point, and returns a :class:`~probedyn.lumped.reduced.ReducedProbe`
(source "FEM").  ``probe`` is a registry name, a TOML probe file, or a saved reduced probe
(``.json``, loaded as is).  A reduction is stored under a hash of everything it depends on
(probe key, resolved parameters, point, frame, number of modes, damping, the reduction's format
version) in ``$PROBEDYN_CACHE/reduced`` (default ``~/.cache/probedyn/reduced``), so it is
computed once and reused (:func:`resolve_probe` is what the schemes' ``--probe`` option calls).

Defaults per probe (``SCHEME_FRAMES``, ``default_point``): the point is the lumped tip of a smart
probe with ``tip = "lumped"``, else the named point ``tip`` (the apex of a cantilever's tip, or
the lower free-end edge without one), else the model's tip attachment.  The frame of a probe
along x with its thickness along z (cantilever, duo-bimorph) is scan = y, lateral = x,
normal = z; the piezotube stands on its axis (x = the source's z): normal = x, scan = y,
lateral = z.  (These belong to the probe classes; they live here until the probes declare them.)
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from probedyn.core.errors import ParameterError
from probedyn.core.io import to_jsonable
from probedyn.fem import elasticity as el
from probedyn.fem.modes import classify_shapes
from probedyn.lumped.reduced import FORMAT_VERSION, ReducedProbe, damping_ratios, frame_matrix, reduce_model
from probedyn.probes import get_probe

SCHEME_FRAMES: dict[str, dict[str, tuple[float, float, float]]] = {
    "piezotube": {"scan": (0.0, 1.0, 0.0), "lateral": (0.0, 0.0, 1.0), "normal": (1.0, 0.0, 0.0)},
}
#: bump when the meaning of a cached reduction changes
REDUCTION_VERSION = 1


def cache_root() -> Path:
    """``$PROBEDYN_CACHE/reduced`` or ``~/.cache/probedyn/reduced`` (created on demand)."""
    env = os.environ.get("PROBEDYN_CACHE")
    d = (Path(env) if env else Path.home() / ".cache" / "probedyn") / "reduced"
    d.mkdir(parents=True, exist_ok=True)
    return d



def cached_reduction(path: Path, cache: bool, t0: float,
                     accept: Callable[[ReducedProbe], bool] | None = None) -> ReducedProbe | None:
    """The reduction stored at ``path`` if ``cache`` and it loads (and ``accept`` approves it),
    with ``provenance`` saying "hit", the file and the load time; ``None`` otherwise (a corrupt or
    stale entry is rebuilt by the caller and overwritten)."""
    if not (cache and path.exists()):
        return None
    try:
        rp = ReducedProbe.load(path)
    except Exception:  # corrupt or stale entry: rebuild
        return None
    if accept is not None and not accept(rp):
        return None
    rp.provenance = dict(rp.provenance, cache="hit", cache_file=str(path), load_s=time.perf_counter() - t0)
    return rp


def store_reduction(rp: ReducedProbe, path: Path, cache: bool, t0: float) -> None:
    """Record the build time and cache state in ``rp.provenance`` and, if ``cache``, store it at
    ``path`` at once (a cache entry is kept even if the run that built it fails later)."""
    rp.provenance["build_s"] = time.perf_counter() - t0
    rp.provenance["cache"] = "miss" if cache else "off"
    if cache:
        rp.save(path, defer=False)
        rp.provenance["cache_file"] = str(path)

def default_point(model: Any) -> str:
    if getattr(model, "lumped_tip", None) is not None:
        return "lumped_tip"
    if "tip" in getattr(model.bundle, "points", {}):
        return "tip"
    return str(model.tip)


def _mass_per_length(probe: Any, values: Mapping[str, Any]) -> float | None:
    beam = getattr(probe, "beam", None)
    if beam is None:
        return None
    try:
        return float(beam(values).mass_per_length)
    except Exception:
        return None


def reduction_key(probe_key: str, values: Mapping[str, Any], point: str | None, n_modes: int,
                  frame: Any, Q: float | None, mu: float | None) -> str:
    blob = json.dumps(to_jsonable(dict(probe=probe_key, values=dict(values), point=point, n_modes=int(n_modes),
                                       frame=None if frame is None else np.asarray(frame_matrix(frame)).round(12),
                                       Q=Q, mu=mu, v=REDUCTION_VERSION, fmt=FORMAT_VERSION)),
                      sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def reduce_probe(probe: str | Path = "cantilever", overrides: Mapping[str, Any] | None = None, *,
                 point: str | None = None, n_modes: int = 6, frame: Mapping[str, Sequence[float]] | None = None,
                 Q: float | None = None, mu: float | None = None, cache: bool = True,
                 solver: str = "auto") -> ReducedProbe:
    """The reduced probe of a registry probe (or TOML probe file) with ``overrides``.

    ``n_modes`` retained modes (validity limit = mode n_modes + 1); ``Q`` or ``mu`` (eq 3.2,
    needs a beam-like probe for rho A) set the modal damping; ``cache``: reuse/store the
    reduction under its content hash (``provenance["cache"]`` says "hit" or "miss"); a hit comes
    with its FE model attached (the mesh from the mesh cache; nothing is assembled until used)."""
    t0 = time.perf_counter()
    damping_ratios(np.ones(1), Q=Q, mu=mu, mass_per_length=1.0)  # validate before any FEM work
    if frame is not None:
        frame_matrix(frame)
    if int(n_modes) != n_modes or n_modes < 1:
        raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
    p, file_over = get_probe(probe)
    over = {**file_over, **dict(overrides or {})}
    values = p.resolve(over)
    if frame is None:
        frame = SCHEME_FRAMES.get(p.name)
    key = reduction_key(p.name, values, point, n_modes, frame, Q, mu)
    path = cache_root() / f"{p.name}-{key}.json"
    rp = cached_reduction(path, cache, t0)
    if rp is not None:
        # the FE model (mesh from its cache, assembly deferred until used) comes back too, so a
        # cached probe can attach masses at coordinates and be checked against the FEM
        model = p.build(values)
        if model.bundle.key == rp.provenance.get("mesh_key") and rp.ritz is not None:
            rp.ritz.model = model
        return rp
    model = p.build(values)
    pt = point or default_point(model)
    mpl = _mass_per_length(p, values) if mu is not None else None
    if mu is not None and mpl is None:
        raise ParameterError(f"mu damping (eq 3.2) needs a beam-like probe with rho A; probe {p.name!r} has none: use Q")
    rp = reduce_model(model, pt, n_modes=n_modes, frame=frame, Q=Q, mu=mu, mass_per_length=mpl, solver=solver,
                      provenance=dict(probe=p.name, parameters=dict(values),
                                      toml=str(probe) if str(probe).endswith(".toml") else None))
    fams = _families(model, rp)
    for m, f in zip(rp.modes, fams):
        m.family = f
    store_reduction(rp, path, cache, t0)
    rp.ritz.model = model
    return rp


def _families(model: Any, rp: ReducedProbe) -> list[str]:
    """Mode families (flapwise, lateral, torsion, ...) of the retained modes, by the FEM's
    cross-section classification (:func:`probedyn.fem.modes.classify_shapes`)."""
    n = rp.n_modes
    T = rp.ritz.T[: model.ndofs_total, :n]
    weights = el.lumped_weights(model.mesh, model.elem_density)
    fams, _ = classify_shapes(model.basis.doflocs, weights, T.reshape(model.n_nodes, 3, n), axis=model.beam_axis)
    return fams


def resolve_probe(spec: str | Path | ReducedProbe, overrides: Mapping[str, Any] | None = None,
                  **kw: Any) -> ReducedProbe:
    """What a scheme's ``--probe`` accepts: a :class:`ReducedProbe`, a saved reduced probe
    (``.json``), a table preset (``table-2.1``), a registry probe name or a TOML probe file."""
    if isinstance(spec, ReducedProbe):
        return spec
    s = str(spec)
    if s.endswith(".json"):
        if overrides:
            raise ParameterError("a saved reduced probe cannot take parameter overrides; reduce the probe again")
        return ReducedProbe.load(s)
    if s.lower().startswith("table-"):
        if overrides:
            raise ParameterError("a table probe cannot take parameter overrides")
        return ReducedProbe.from_preset(s)
    return reduce_probe(s, overrides, **kw)


def attach_model(rp: ReducedProbe) -> ReducedProbe:
    """Rebuild the FE model of a loaded FEM-reduced probe and attach it to its Ritz basis (so
    that masses and springs can be attached at coordinates); the mesh must hash the same."""
    if rp.ritz is None or rp.source != "FEM":
        raise ParameterError("only a FEM-reduced probe with a Ritz basis has a model to attach")
    p, _ = get_probe(rp.provenance["probe"])
    model = p.build(p.resolve(rp.provenance["parameters"]))
    if model.bundle.key != rp.provenance.get("mesh_key"):
        raise ParameterError("the rebuilt mesh differs from the one this probe was reduced on")
    rp.ritz.model = model
    return rp
