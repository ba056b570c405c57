"""Are the adhesion laws' nested fits at their optimum in the contact point? (session 41, docs/diagnose.md 9.27)

Usage: ``python benchmarks/curves_contact_point_scan.py SEED [SEED ...] > OUT.jsonl``

For each force-curve rate-study case (hidden effects: seeds 2000 + i with ``CURVE_EFFECTS[i]``; noise-only:
6000 + i; white noise as in the rate study), the baseline and each adhesion law's nested fit from the engine's
starts, then four re-fits from that optimum with the contact point ``z_c`` moved by -2, -1, +1, +2 median sample
intervals. One JSON line per case: ``{law: [nested chi2, best chi2 of the nested and the four re-fits]}``. A
lower second number is a local minimum the starts stopped in. Results of session 41:
``benchmarks/results/curves_contact_point_scan_s41.jsonl`` (18 cases: no fit improved by more than 0.10).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import probedyn  # noqa: F401  (before numpy: thread settings)

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from diagnose_truth_curves import CURVE_EFFECTS, make_curve_case  # noqa: E402

from probedyn.diagnose.engine import Fitter  # noqa: E402
from probedyn.diagnose.forcecurve import ForceCurveProblem  # noqa: E402
from probedyn.diagnose.formats import read_measurement  # noqa: E402

SHIFTS = (-2, -1, 1, 2)


def scan(seed: int) -> dict:
    effect = None if seed >= 6000 else CURVE_EFFECTS[(seed - 2000) % len(CURVE_EFFECTS)]
    with tempfile.TemporaryDirectory() as tmp:
        path, _ = make_curve_case(Path(tmp), seed, effect)
        prob = ForceCurveProblem(read_measurement(path))
    F = Fitter(prob)
    base = F.baseline()
    dz = float(np.median(prob.dz))
    row = {"seed": seed, "effect": effect, "base": base.chi2}
    for c in prob.causes:
        if "adhesion" not in c.changes:
            continue
        f = F.nested(base, (c,))
        best = f.chi2
        for sh in SHIFTS:
            v = dict(f.values, z_c=f.values["z_c"] + sh * dz)
            best = min(best, F.fit(f.causes, [v]).chi2)
        row[c.key] = [round(f.chi2, 3), round(best, 3)]
    return row


if __name__ == "__main__":
    for s in sys.argv[1:]:
        print(json.dumps(scan(int(s))), flush=True)
