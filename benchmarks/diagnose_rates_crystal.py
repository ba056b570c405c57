"""Does the modal diagnosis find a lever that is single-crystal silicon, declared as isotropic silicon?

Usage: ``python benchmarks/diagnose_rates_crystal.py N OUT.json`` (resumable, as
``benchmarks/diagnose_rates.py``): ``benchmarks/diagnose_rates_effect.py crystal-anisotropy N OUT.json``.

Truth (tests/diagnose_truth.py): probedyn's FEM of the lever meshed with the **cubic** material
``silicon-110`` (C11, C12, C44 of Hopcroft et al. 2010 rotated to the lever's axes, x || [110]),
4 layers of 20-node hexahedra, solved directly -- not the cause's interpolated stiffness -- plus
1e-3 frequency noise on the six modes (flapwise 1-4, lateral 1, torsion 1); the sidecar declares the
catalog's isotropic "silicon" (E = 169 GPa, nu = 0.28). Levers cycle through A (300 x 30 x 10 um),
B (100 x 40 x 10), C (narrow) and three more geometries; seeds 9000 + i (noise, Q).

Reported: the first finding is ``crystal-anisotropy`` (correct first), it is in the first finding's
confounded group, and the fitted fraction ``a_crystal`` against the truth's 1.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_rates_effect import study  # noqa: E402

if __name__ == "__main__":
    n = int(sys.argv[1])
    out = sys.argv[2] if len(sys.argv) > 2 else "benchmarks/results/diagnose_rates_crystal.json"
    print(json.dumps(study("crystal-anisotropy", n, out), indent=1, default=float))
