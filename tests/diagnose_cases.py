"""The case lists of the rate study (benchmarks/diagnose_rates.py) and the default tests: seeds,
effects, levers, truth models. Seeds are fixed so that the FEM truths can be cached."""

from __future__ import annotations

import numpy as np

from diagnose_truth import LEVERS, MODAL_EFFECTS


def untimed(report):
    """A diagnosis report with its clocks (keys ending in ``_s``) left out and its arrays as lists: two runs of one
    diagnosis compare equal where they computed the same numbers (the engine's pool against the fits in turn)."""
    if isinstance(report, dict):
        return {k: untimed(v) for k, v in report.items() if not str(k).endswith("_s")}
    if isinstance(report, (list, tuple)):
        return [untimed(v) for v in report]
    return report.tolist() if isinstance(report, np.ndarray) else report


def modal_cases(n_effect: int = 56, n_null: int = 56) -> list[dict]:
    levers = list(LEVERS)
    out = []
    for i in range(n_effect):
        out.append({"seed": 1000 + i, "effect": MODAL_EFFECTS[i % len(MODAL_EFFECTS)],
                    "lever": levers[(i // len(MODAL_EFFECTS)) % len(levers)], "truth_kind": "fem"})
    for i in range(n_null):
        # a third of the nulls from the Timoshenko beam (a truth of another model form) on every
        # lever in turn (i = 6, 7, 8, 15, 16, 17, ...), the rest FEM
        out.append({"seed": 5000 + i, "effect": None, "lever": levers[i % len(levers)],
                    "truth_kind": "timoshenko" if (i // len(levers)) % 3 == 2 else "fem",
                    "declared_medium": "air" if i % 4 == 1 else "vacuum"})
    return out
