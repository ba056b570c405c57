"""The diagnosis on a blind set (force curves, spectra, friction records), scored against the generator's key.

Usage: ``python benchmarks/blind_run.py OUT_DIR [RESULTS.json]`` (default ``OUT_DIR/results.json``; resumable:
cases already in it are skipped). ``OUT_DIR`` is what a blind generator wrote: ``OUT_DIR/cases/<id>.toml`` (+ CSV)
and ``OUT_DIR/KEY.json`` = ``{"cases": [{"id", "effect", <true parameters>...}]}``. The generators are written by
helpers from the documented formats and catalog only (docs/diagnose.md §1, §3), never from probedyn's code:
``benchmarks/blind_curves`` (session 44), ``benchmarks/blind_spectra`` and ``benchmarks/blind_friction``
(session 46).

Expected cause: the key's effect (a catalog key); ``jump-to-contact`` is DMT's van der Waals tail (as in
``benchmarks/diagnose_rates_curves.py``); ``none`` expects no finding. Reported per case: verdict, findings, the
first finding's group, its fitted parameters and, for every parameter the key states under the catalog's name,
the relative error of the fit; CPU time (the diagnosis' worker processes included); the declared conditions'
terms the baseline took on. Totals: correct first over the hidden cases, correct in the group, false
discoveries (any finding on a null), nulls not read as *no significant discrepancy*, the median relative error of
the first parameter the key states (the cause's main parameter), every miss.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from probedyn.diagnose.causes import CAUSES
from probedyn.diagnose.engine import run

ALIASES = {"jump-to-contact": "adhesion-dmt", "none": None}


def expected_cause(effect: str) -> str | None:
    return ALIASES.get(effect, effect)


def _parameter_errors(expected: str, fitted: dict, key: dict) -> dict:
    """Relative error of each fitted parameter the key states under the catalog's name (additive where the
    null is zero and the truth is too: then the absolute difference). A key that states the offset at its record's
    middle as well as at its clock's zero is compared at the middle, where the catalog defines it (§3)."""
    out = {}
    for p in CAUSES.get(expected).params:
        t = key.get(p.name)
        if p.name == "offset":  # the catalog's offset is the zero at the record clock's middle (docs/diagnose.md §3)
            t = next((key[k] for k in ("offset_at_record_mid", "offset_at_record_middle_N") if k in key), t)
        if t is None or p.name not in fitted or fitted[p.name] is None:
            continue
        out[p.name] = fitted[p.name] / t - 1.0 if t != 0 else fitted[p.name] - t
    return out


def _cpu() -> float:
    """CPU seconds of this process and its reaped children (the diagnosis' worker processes)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def score_case(case_toml: Path, key: dict) -> dict:
    c0 = _cpu()
    res = run(case_toml)
    f = res["findings"]
    first = f[0]["cause"] if f else None
    exp = expected_cause(key["effect"])
    row = {"effect": key["effect"], "expected": exp, "verdict": res["verdict"],
           "findings": [x["cause"] for x in f], "group": [first, *f[0].get("confounded_with", [])] if f else [],
           # a parameter a finding reports as derived (an adhesion load on the load-independent baseline, which the
           # cause fits as the share of the load the corrugation follows)
           "parameters": ({**{n: v for n, v in (f[0].get("derived") or {}).items() if isinstance(v, (int, float))},
                           **{n: p.get("value") for n, p in f[0]["parameters"].items()}} if f else {}),
           "baseline_p": res["baseline"]["p_value"], "targeted_test": res["baseline"].get("targeted_test"),
           "noise_model": (res["method"].get("noise") or {}).get("model"), "cpu_s": _cpu() - c0,
           # effects the declared conditions imply, taken into the baseline (thermal activation at a declared
           # temperature, docs/diagnose.md 9.44): no finding, by design
           "baseline_terms": [t["term"] for t in res["baseline"].get("declared_terms") or () if t["taken"]]}
    if first == exp and exp is not None:
        row["parameter_errors"] = _parameter_errors(exp, row["parameters"], key)
        if row["parameter_errors"]:
            row["parameter_error"] = next(iter(row["parameter_errors"].values()))
    return row


def summarize(rows: dict) -> dict:
    hidden = [r for r in rows.values() if r["expected"]]
    nulls = [r for r in rows.values() if not r["expected"]]
    errs = sorted(abs(r["parameter_error"]) for r in hidden if "parameter_error" in r)
    return {"hidden": len(hidden), "correct_first": sum(r["findings"][:1] == [r["expected"]] for r in hidden),
            "correct_in_group": sum(r["expected"] in r["group"] for r in hidden),
            "nulls": len(nulls), "false_discoveries": sum(bool(r["findings"]) for r in nulls),
            "nulls_not_clean": [c for c, r in rows.items() if not r["expected"] and r["verdict"] != "no-significant-discrepancy"],
            "median_parameter_error": errs[len(errs) // 2] if errs else None,
            "misses": {c: (r["effect"], r["group"]) for c, r in rows.items()
                       if r["expected"] and r["findings"][:1] != [r["expected"]]},
            "misses_in_baseline": [c for c, r in rows.items() if r["expected"] and r["findings"][:1] != [r["expected"]]
                                   and r["expected"] in r.get("baseline_terms", ())]}


def main(out_dir: Path, results: Path) -> dict:
    key = {c["id"]: c for c in json.loads((out_dir / "KEY.json").read_text())["cases"]}
    rows = json.loads(results.read_text()) if results.exists() else {}
    for cid, k in sorted(key.items()):
        if cid in rows:
            continue
        row = score_case(out_dir / "cases" / f"{cid}.toml", k)
        rows[cid] = row
        tmp = results.with_suffix(".tmp")
        tmp.write_text(json.dumps(rows, indent=1, default=float))
        os.replace(tmp, results)
        print(cid, k["effect"], row["verdict"], row["group"], f"{row['cpu_s']:.0f} s", flush=True)
    return summarize(rows)


if __name__ == "__main__":
    d = Path(sys.argv[1])
    print(json.dumps(main(d, Path(sys.argv[2]) if len(sys.argv) > 2 else d / "results.json"), indent=1))
