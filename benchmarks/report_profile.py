"""Profile the default report: wall and CPU time of each section, and what dominates inside.

Runs the sections of :data:`probedyn.report.SECTIONS` one after the other in ONE process (as the
serial report does: sections share in-process memoised solves), and records for each

* ``wall_s``: ``time.perf_counter`` around the section;
* ``cpu_s``: ``time.process_time`` of this process (all its threads: MKL/OpenMP time counts);
* ``load``: the 1-minute load average at the section's start (the machine is shared: a wall time
  means little without it; CPU time is the load-independent measure);
* with ``--profile``: the top functions of a ``cProfile`` of the section (cumulative and own time).

Results go into a JSON file (``--json``, checkpointed after each section, so an interrupted run
keeps what it measured) under the key ``--label`` (``before``, ``after``, ...), merged with what
the file already holds. Usage::

    PROBEDYN_CACHE=$(mktemp -d) .venv/bin/python benchmarks/report_profile.py --label before
    .venv/bin/python benchmarks/report_profile.py --label before-profile --profile --only pushing

cProfile slows Python-heavy code (~1.3-2x); the profiled run's times are for the split inside a
section, the plain run's for the section totals.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import sys
import tempfile
import time
from pathlib import Path

from probedyn.report import SECTIONS


def _top(prof: cProfile.Profile, n: int) -> dict[str, list[dict]]:
    st = pstats.Stats(prof, stream=io.StringIO())
    rows = []
    for (fname, line, func), (cc, nc, tt, ct, _callers) in st.stats.items():
        where = f"{Path(fname).name}:{line}({func})" if line else func
        if "site-packages" not in fname and "/probedyn/" in fname:
            where = fname.split("/probedyn/", 1)[1] + f":{line}({func})"
        rows.append({"function": where, "calls": nc, "own_s": round(tt, 3), "cum_s": round(ct, 3)})
    by_cum = sorted(rows, key=lambda r: -r["cum_s"])
    by_own = sorted(rows, key=lambda r: -r["own_s"])
    own_probedyn = [r for r in by_cum if r["function"].split(":")[0].endswith(".py")
                    and "/" in r["function"] and not r["function"].startswith("report/")]
    return {"cumulative": by_cum[:n], "own": by_own[:n], "probedyn_cumulative": own_probedyn[:n]}


def _parse_report(path: Path) -> dict:
    """Per-section wall/CPU times and the total from the end of a report.md."""
    import re

    rows, total = [], None
    text = path.read_text()
    for line in text.split("## Run times", 1)[1].splitlines():
        m = re.match(r"\|\s*(.+?)\s*\|\s*([0-9.]+)\s*\|\s*([0-9.]+)\s*\|", line)
        if m:
            rows.append({"section": m.group(1), "wall_s": float(m.group(2)), "cpu_s": float(m.group(3))})
        t = re.search(r"([0-9.]+) s wall in all", line)
        if t:
            total = float(t.group(1))
    return {"sections": rows, "sections_wall_s": total, "sum_cpu_s": round(sum(r["cpu_s"] for r in rows), 1)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--json", type=Path, default=Path(__file__).parent / "results" / "report-times-s4.json")
    ap.add_argument("--label", default="before")
    ap.add_argument("--only", action="append", help="sections whose title contains this (repeatable)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--profile", action="store_true", help="cProfile each section (top functions)")
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--outdir", type=Path, default=None, help="figures folder (default: a temporary one)")
    ap.add_argument("--from-report", type=Path, default=None,
                    help="record the run-times table of a finished report.md (e.g. a timed ./dev report "
                         "from a fresh clone) under --label instead of running the sections")
    ap.add_argument("--note", default="", help="free text stored with the run (load, cache state, ...)")
    args = ap.parse_args(argv)

    data = json.loads(args.json.read_text()) if args.json.exists() else {}
    if args.from_report:
        data[args.label] = {"note": args.note, "source": str(args.from_report), **_parse_report(args.from_report)}
        args.json.write_text(json.dumps(data, indent=1) + "\n")
        return 0
    run = {
        "note": "one process, sections in report order; machine shared (2 cores, other jobs running)",
        "cache": os.environ.get("PROBEDYN_CACHE", "~/.cache/probedyn (default)"),
        "quick": args.quick, "profiled": args.profile,
        "started": time.strftime("%Y-%m-%d %H:%M:%S"), "sections": [],
    }
    data[args.label] = run
    outdir = args.outdir or Path(tempfile.mkdtemp(prefix="report-profile-"))
    t_all, c_all = time.perf_counter(), time.process_time()
    import importlib

    for title, target in SECTIONS:
        if args.only and not any(o.lower() in title.lower() for o in args.only):
            continue
        mod_name, func_name = target.split(":")
        t_imp = time.perf_counter()
        func = getattr(importlib.import_module(mod_name), func_name)
        imp = time.perf_counter() - t_imp
        load = os.getloadavg()[0]
        prof = cProfile.Profile() if args.profile else None
        t0, c0 = time.perf_counter(), time.process_time()
        if prof:
            prof.enable()
        func(outdir, args.quick)
        if prof:
            prof.disable()
        row = {"section": title, "wall_s": round(time.perf_counter() - t0, 2),
               "cpu_s": round(time.process_time() - c0, 2), "import_s": round(imp, 2),
               "load_start": round(load, 2), "load_end": round(os.getloadavg()[0], 2)}
        if prof:
            row["profile"] = _top(prof, args.top)
        run["sections"].append(row)
        run["total_wall_s"] = round(time.perf_counter() - t_all, 1)
        run["total_cpu_s"] = round(time.process_time() - c_all, 1)
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(data, indent=1) + "\n")
        print(f"{title:55s} wall {row['wall_s']:7.1f} s  cpu {row['cpu_s']:7.1f} s  load {load:.1f}",
              file=sys.stderr, flush=True)
    run["finished"] = time.strftime("%Y-%m-%d %H:%M:%S")
    args.json.write_text(json.dumps(data, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
