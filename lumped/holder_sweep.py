"""The lumped smart-probe model (eq 3.37) over the holder stiffness, and modes of two variants
of a probe paired by family (used by the holder-stiffness and holder-mass studies of
section 3.4.1 and of departure 5 in docs/source-departures.md).

* :func:`lumped_holder_sweep` re-solves the same lumped model (the body's J, K_2, C_2 and the
  tip mass m from :func:`probedyn.lumped.smart.reduce_from_fem`) with the holder springs of
  the swept directions set to each k: the lumped counterpart of the FEM sweep of
  :func:`probedyn.lumped.smart.localisation_sweep` (no FEM re-solve).
* :func:`pair_by_family` pairs two lists of modes by family and order within the family, so a
  ratio of frequencies always compares the same kind of mode.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import numpy as np

from probedyn.lumped.smart import SmartLumpedModel


def lumped_holder_sweep(lumped: dict[str, Any], ks: Sequence[float], sweep_dirs: Iterable[str],
                        n: int = 40) -> dict[str, list]:
    """Frequencies [Hz] of the lumped model ``lumped`` (the dict of
    :meth:`SmartLumpedModel.to_dict`) for ``n`` holder stiffnesses spaced geometrically over
    the range of ``ks``; springs of the directions in ``sweep_dirs`` take the swept value, the
    others keep theirs. Returns ``{"k": [n], "f": [n][2 d]}`` (all lumped modes, ascending)."""
    dirs = list(lumped["directions"])
    sweep = set(sweep_dirs)
    kk = np.geomspace(min(ks), max(ks), n)
    out = []
    for k in kk:
        kt = np.array([k if d in sweep else kt0 for d, kt0 in zip(dirs, lumped["kt"])], dtype=float)
        lm = SmartLumpedModel(dirs, np.asarray(lumped["J"]), np.asarray(lumped["K2"]), np.asarray(lumped["C2"]),
                              float(lumped["m"]), kt)
        out.append(lm.modes()[0])
    return {"k": kk.tolist(), "f": np.array(out).tolist()}


def pair_by_family(a: Sequence[tuple[str, float]], b: Sequence[tuple[str, float]]) -> list[dict[str, Any]]:
    """Pair modes ``(family, frequency)`` of two variants by family and order within it.

    One row per mode of ``a`` in its order, then the modes of ``b`` left unpaired:
    ``{"family", "order", "f_a", "f_b", "ratio" = f_b / f_a}`` (``None`` where the other
    variant has no mode of that family and order among the modes given)."""
    def ranked(modes):
        seen: dict[str, int] = {}
        out = []
        for fam, f in modes:
            seen[fam] = seen.get(fam, 0) + 1
            out.append((fam, seen[fam], float(f)))
        return out

    ra, rb = ranked(a), ranked(b)
    lookup_b = {(fam, k): f for fam, k, f in rb}
    rows, used = [], set()
    for fam, k, f in ra:
        fb = lookup_b.get((fam, k))
        if fb is not None:
            used.add((fam, k))
        rows.append({"family": fam, "order": k, "f_a": f, "f_b": fb, "ratio": fb / f if fb is not None else None})
    for fam, k, f in rb:
        if (fam, k) not in used:
            rows.append({"family": fam, "order": k, "f_a": None, "f_b": f, "ratio": None})
    return rows
