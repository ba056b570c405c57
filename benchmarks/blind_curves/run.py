"""The diagnosis on the third blind force-curve set (docs/diagnose.md 9.30), scored against its key.

Usage: ``python benchmarks/blind_curves/gen.py OUT_DIR`` (the 32 cases and ``KEY.json``, fixed seed), then
``python benchmarks/blind_curves/run.py OUT_DIR [RESULTS.json]`` (default ``OUT_DIR/results.json``; resumable:
cases already in it are skipped). Expected cause: the key's effect; ``jump-to-contact`` is DMT's van der Waals
tail (as in ``benchmarks/diagnose_rates_curves.py``); ``none`` expects no finding. Reported per case: verdict,
first finding, group, the main parameter against the truth, CPU time; and the totals: correct first over the
hidden cases, correct in the group, false discoveries (any finding on a null), nulls not read as
*no significant discrepancy*.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from probedyn.diagnose.engine import run

EXPECTED = {"adhesion-dmt": "adhesion-dmt", "adhesion-jkr": "adhesion-jkr", "adhesion-md": "adhesion-md",
            "jump-to-contact": "adhesion-dmt", "tip-radius-error": "tip-radius-error", "none": None}


def main(out_dir: Path, results: Path) -> dict:
    key = {c["id"]: c for c in json.loads((out_dir / "KEY.json").read_text())["cases"]}
    rows = json.loads(results.read_text()) if results.exists() else {}
    for cid, k in sorted(key.items()):
        if cid in rows:
            continue
        c0 = time.process_time()
        res = run(out_dir / "cases" / f"{cid}.toml")
        f = res["findings"]
        first = f[0]["cause"] if f else None
        row = {"effect": k["effect"], "expected": EXPECTED[k["effect"]], "verdict": res["verdict"],
               "findings": [x["cause"] for x in f], "group": [first, *f[0].get("confounded_with", [])] if f else [],
               "parameters": {n: p.get("value") for n, p in f[0]["parameters"].items()} if f else {},
               "baseline_p": res["baseline"]["p_value"], "targeted_test": res["baseline"].get("targeted_test"),
               "noise_model": res["method"]["noise"].get("model"), "cpu_s": time.process_time() - c0}
        main_p = {"tip-radius-error": ("r_ratio", k.get("r_ratio"))}.get(k["effect"], ("W", k.get("W")))
        if first == row["expected"] and main_p[1] and main_p[0] in row["parameters"]:
            row["parameter_error"] = row["parameters"][main_p[0]] / main_p[1] - 1.0
        rows[cid] = row
        tmp = results.with_suffix(".tmp")
        tmp.write_text(json.dumps(rows, indent=1, default=float))
        os.replace(tmp, results)
        print(cid, k["effect"], row["verdict"], row["group"], f"{row['cpu_s']:.0f} s", flush=True)
    hidden = [r for r in rows.values() if r["expected"]]
    nulls = [r for r in rows.values() if not r["expected"]]
    errs = sorted(abs(r["parameter_error"]) for r in hidden if "parameter_error" in r)
    return {"hidden": len(hidden), "correct_first": sum(r["findings"][:1] == [r["expected"]] for r in hidden),
            "correct_in_group": sum(r["expected"] in r["group"] for r in hidden),
            "nulls": len(nulls), "false_discoveries": sum(bool(r["findings"]) for r in nulls),
            "nulls_not_clean": [c for c, r in rows.items() if not r["expected"] and r["verdict"] != "no-significant-discrepancy"],
            "median_parameter_error": errs[len(errs) // 2] if errs else None,
            "misses": {c: (r["effect"], r["group"]) for c, r in rows.items()
                       if r["expected"] and r["findings"][:1] != [r["expected"]]}}


if __name__ == "__main__":
    d = Path(sys.argv[1])
    print(json.dumps(main(d, Path(sys.argv[2]) if len(sys.argv) > 2 else d / "results.json"), indent=1))
