"""Every shipped measurement of ``examples/measurements`` through ``probedyn diagnose`` end to end.

Usage: ``python benchmarks/diagnose_examples.py [OUT.json] [NAME ...]`` (default
``benchmarks/results/diagnose_examples.json``; names select examples by file stem, e.g.
``afm_cantilever_modes``). Each example runs in a fresh process through the
CLI (``probedyn diagnose FILE --json``), as a user would; recorded per example: the verdict, the
findings in order with their fitted parameters (value, sigma), the confounded group, the baseline
chi-square and dof, the held-out RMS before and after where the result carries them, and wall and
CPU time of the whole process (the machine may be shared: CPU time is the comparable number; the
load average at the end is stored). The table of docs/diagnose.md section 5 is written from this
file; the hidden effects of the synthetic examples are stated in their sidecars (examples/make_examples.py).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "measurements"


def _child_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_one(toml: Path) -> dict:
    exe = Path(sys.executable).with_name("probedyn")
    cpu0, t0 = _child_cpu(), time.perf_counter()
    proc = subprocess.run([str(exe), "diagnose", str(toml), "--json"], capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _child_cpu() - cpu0
    row = {"example": toml.stem, "rc": proc.returncode, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1)}
    if proc.returncode != 0:
        row["error"] = proc.stderr.strip().splitlines()[-1:] if proc.stderr else []
        return row
    res = json.loads(proc.stdout)
    base, final = res.get("baseline", {}), res.get("final") or {}
    row.update(
        kind=res.get("kind"),
        verdict=res.get("verdict"),
        findings=[f.get("cause") for f in res.get("findings", [])],
        parameters={f.get("cause"): {k: [v.get("value"), v.get("sigma")] for k, v in (f.get("parameters") or {}).items()
                                     if isinstance(v, dict)} for f in res.get("findings", [])},
        confounded=[g.get("causes") for g in res.get("confounded") or []],
        baseline_chi2=base.get("chi2"),
        baseline_dof=base.get("dof"),
        baseline_heldout_rms=base.get("heldout_rms"),
        final_chi2=final.get("chi2"),
        final_dof=final.get("dof"),
        final_rms=final.get("residual_rms"),
        heldout_rms_before=final.get("heldout_rms_before", base.get("heldout_rms")),
        heldout_rms_after=final.get("heldout_rms"),
        model_evaluations=res.get("model_evaluations"),
    )
    return row


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else ROOT / "benchmarks" / "results" / "diagnose_examples.json"
    names = set(argv[1:])
    rows = []
    for toml in sorted(EXAMPLES.glob("*.toml")):
        if names and toml.stem not in names:
            continue
        row = run_one(toml)
        rows.append(row)
        print(json.dumps(row), flush=True)
    tmp = out.with_suffix(".tmp")
    tmp.write_text(json.dumps({"rows": rows, "load": os.getloadavg()}, indent=1) + "\n")
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
