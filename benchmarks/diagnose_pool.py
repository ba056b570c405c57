"""A diagnosis in turn and through the engine's pool of forked workers, in one process (session 77).

Usage: ``python benchmarks/diagnose_pool.py [OUT.json] [NAME ...]`` (default
``benchmarks/results/diagnose_pool_s77.json``; names: shipped examples by file stem, default the 6-mode and one-mode
modal examples, the aluminium length sweep, the thermal spectrum in air, and the JPK force curve; the
three-scan friction example has run through the pool since session 8, friction loops stay in turn).

Each example's problem is built and diagnosed with one process (``engine.WORKERS`` set to 1 while its problem is
built) and with the pool (``engine.WORKERS``), alternating, two rounds, in this one process; the build (the FEM
baseline and its reduction, which the pool does not touch, and a spectrum's peak labelling, whose causes' fits it
runs) and the diagnosis are timed apart, and the two reports are compared with their clocks left out (they must be equal to the
last bit: every job of the pool computes what the fit in turn computes). Recorded: the wall times, their ratio (in
turn over pooled, best of the rounds each) and the equality. probedyn is imported first, as the CLI does (the first
version of this script imported numpy first and found OpenBLAS on two threads: slower, and rounding differently, 1756
evaluations of the 6-mode example instead of 1852; ``probedyn/__init__.py`` now holds it to one thread either way).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import probedyn  # noqa: F401  (first, as the CLI: it sets OpenBLAS's threads before numpy loads it)
from probedyn.core.io import write_json
import probedyn.diagnose.engine as E
from probedyn.diagnose.engine import diagnose
from probedyn.diagnose.problems import make_problem

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from diagnose_cases import untimed  # noqa: E402  (the report without its clocks)
DEFAULT = ("afm_cantilever_modes", "afm_cantilever_one_mode", "al_cantilever_length_sweep", "thermal_psd_air",
           "afm_force_curve_jpk_qi")
POOL = E.WORKERS


def one(name: str, workers: int) -> tuple[float, float, dict]:
    """Build time (a spectrum's peak labelling included, whose causes' fits go through the pool too), diagnosis time
    and report of one run with ``workers`` processes."""
    E.WORKERS = workers  # what the problems built now take (they read it at construction)
    try:
        t0 = time.perf_counter()
        prob = make_problem(ROOT / "examples" / "measurements" / f"{name}.toml")
        t1 = time.perf_counter()
        res = diagnose(prob)
        return t1 - t0, time.perf_counter() - t1, res
    finally:
        E.WORKERS = POOL


def main(out: Path, names: list[str]) -> None:
    rows = []
    for name in names:
        times: dict[int, list[float]] = {1: [], POOL: []}
        builds: dict[int, list[float]] = {1: [], POOL: []}
        reports: dict[int, dict] = {}
        for _ in range(2):
            for w in (1, POOL):
                tb, t, res = one(name, w)
                builds[w].append(round(tb, 2))
                times[w].append(round(t, 2))
                reports[w] = untimed(res)
        row = {"example": name, "in_turn_s": times[1], "pooled_s": times[POOL], "workers": POOL,
               "ratio": round(min(times[1]) / min(times[POOL]), 3), "equal": reports[1] == reports[POOL],
               "build_in_turn_s": builds[1], "build_pooled_s": builds[POOL],
               "build_ratio": round(min(builds[1]) / min(builds[POOL]), 3),
               "model_evaluations": reports[1].get("model_evaluations"), "verdict": reports[1].get("verdict")}
        print(row, flush=True)
        rows.append(row)
    write_json(out, {"benchmark": "diagnose_pool", "rows": rows})


if __name__ == "__main__":
    args = sys.argv[1:]
    out = Path(args.pop(0)) if args and args[0].endswith(".json") else ROOT / "benchmarks" / "results" / "diagnose_pool_s77.json"
    main(out, args or list(DEFAULT))
