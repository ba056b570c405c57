"""The baseline's load law chosen with the lead cause (engine ``_law_with_cause``), screened on friction records.

Usage: ``python benchmarks/blind_law_check.py OUT.json CASE.toml ...`` (resumable: cases already in OUT.json are
skipped). Each record is diagnosed up to the law's check after the candidate stage (step 3) and stopped there: the row
holds the lead cause, its ``-2 ln L`` nested under each law and the law the check takes. A record whose law the check
keeps ends as it did before the check existed (the check only adds fits under the other law, whose models the
registry memory keys apart); one whose law changes is run again whole under it, so only those need a full run.
Written for session 76 (docs/diagnose.md 9.61) on the multi-load records of both blind friction sets.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import probedyn.diagnose.engine as E
from probedyn.core.io import write_json
from probedyn.diagnose.problems import make_problem

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blind_run import _cpu  # noqa: E402  (CPU of this process and its worker processes)


class _Stop(Exception):
    pass


def main(out: Path, cases: list[str]) -> None:
    seen: dict = {}
    check = E._law_with_cause

    def spy(*a, **k):
        seen["row"] = check(*a, **k)
        raise _Stop

    E._law_with_cause = spy
    rows = json.loads(out.read_text()) if out.exists() else {}
    for path in cases:
        cid = Path(path).stem
        if cid in rows:
            continue
        seen.clear()
        c0 = _cpu()
        prob = make_problem(Path(path))
        try:
            res = E.diagnose(prob)
            rows[cid] = {"note": "no law check (one load)", "verdict": res["verdict"]}
        except _Stop:
            rows[cid] = {"check": seen.get("row")}
        rows[cid].update(cpu_s=_cpu() - c0, laws=list(getattr(prob, "baseline_laws", ())))
        print(cid, json.dumps(rows[cid]), flush=True)
        write_json(out, rows)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: python benchmarks/blind_law_check.py OUT.json CASE.toml ...")
    main(Path(sys.argv[1]), sys.argv[2:])
