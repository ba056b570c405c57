"""Noise-only cases on a thin lever: does the modal diagnosis claim its own mesh error as a cause?

Usage: ``python benchmarks/diagnose_rates_thin.py N OUT.json``. Truth: the converged unstretched
FEM of the 200 x 30 x 2 um Si lever (``tests/data/thin_lever_reference.json``, how it was made is in
the file; 183 k / 304 k DOFs, computed once: hidden effects on this lever would need one such truth
each, ~4 GiB and minutes per case, not run), six frequencies (flapwise 1-4, lateral 1, torsion 1)
with 1e-3 relative noise (seeds 1..N), vacuum declared. The diagnosis builds its own stretched
FEM (s = 6.3, 6.4 k DOFs at the default refinement budget) once and shares it between the cases.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from probedyn.diagnose.engine import diagnose
from probedyn.diagnose.formats import read_measurement
from probedyn.diagnose.modal import ModalProblem

REF = json.loads((Path(__file__).resolve().parents[1] / "tests" / "data" / "thin_lever_reference.json").read_text())
MODES = [("flapwise", 1), ("flapwise", 2), ("flapwise", 3), ("flapwise", 4), ("lateral", 1), ("torsion", 1)]


def main(n: int, out: str) -> dict:
    g = REF["geometry_m"]
    rows, bases = [], None
    with tempfile.TemporaryDirectory() as d:
        for seed in range(1, n + 1):
            rng = np.random.default_rng(seed)
            lines = ["family,order,frequency_Hz"]
            for fa, o in MODES:
                lines.append(f"{fa},{o},{REF['frequencies_hz'][fa][o - 1] * (1 + 1e-3 * rng.standard_normal()):.10g}")
            (Path(d) / f"thin_{seed}.csv").write_text("\n".join(lines) + "\n")
            toml = Path(d) / f"thin_{seed}.toml"
            toml.write_text(f'[measurement]\nkind = "modal"\ndata = "thin_{seed}.csv"\n\n[probe]\nname = "cantilever"\n'
                            f"length = {g['length']!r}\nwidth = {g['width']!r}\nthickness = {g['thickness']!r}\n\n"
                            f'[medium]\nname = "vacuum"\n\n[noise]\nfrequency_rel = 0.001\n')
            c0 = time.process_time()
            prob = ModalProblem(read_measurement(toml), bases=bases)
            bases = prob.bases
            res = diagnose(prob)
            rows.append({"seed": seed, "verdict": res["verdict"], "findings": [f["cause"] for f in res["findings"]],
                         "baseline_p": res["baseline"]["p_value"], "cpu_s": time.process_time() - c0})
            print(json.dumps(rows[-1]), flush=True)
    b = next(iter(bases.values()))
    summary = {"n_null": len(rows), "false_discoveries": sum(1 for r in rows if r["findings"]),
               "fem_dofs": b.model.dofs, "stretch": b.stretch, "discretisation": b.disc_note,
               "cpu_median_s": float(np.median([r["cpu_s"] for r in rows]))}
    Path(out).write_text(json.dumps({"summary": summary, "rows": rows}, indent=1))
    return summary


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]), sys.argv[2]), indent=1))
