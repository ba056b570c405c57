"""Count the function lines of ``probedyn/commands/`` by what they do (issue 9).

Every top-level function (nested functions count with their parent) is put in one class:

* ``command``  – a Typer command (decorated ``@<app>.command(...)``) or a helper that only
  parses arguments or formats output for people (names like ``_human``, ``*_text``,
  ``_floats``, ``_parse_*``, ``_load_target``, ``_sets``, ``_mode_rows``, and
  the output helpers of ``_common.py``: ``emit``, ``save``, ``format_table``, ``markdown_table``);
* ``prose``    – report prose: ``report_section``/``section``/``report_markdown``;
* ``plotting`` – draws figures: name ``plot_*``/``_plot*``/``_mpl``/``_savefig``/``_panel``
  or a body that uses matplotlib / pyplot;
* ``analysis`` – anything else (computations that belong in the library).

Run: ``python tools/command_lines.py [DIR ...]`` (default ``probedyn/commands``); prints one
row per file and the totals. Re-run after a change to compare.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

IO_NAMES = re.compile(r"^(emit|save|format_table|markdown_table|_?human.*|.*_text|_floats|_sets|_parse_.*|_load_target|_mode_rows|rng|text)$")
PLOT_NAMES = re.compile(r"^(plot_.*|_plot.*|_mpl|_savefig|_panel|savefig)$")
PROSE_NAMES = re.compile(r"^(report_section|section|report_markdown)$")
CLASSES = ("command", "prose", "plotting", "analysis")


def _is_command(fn: ast.FunctionDef) -> bool:
    for d in fn.decorator_list:
        f = d.func if isinstance(d, ast.Call) else d
        if isinstance(f, ast.Attribute) and f.attr == "command":
            return True
    return False


def classify(fn: ast.FunctionDef, src: str) -> str:
    if _is_command(fn):
        return "command"
    if PROSE_NAMES.match(fn.name):
        return "prose"
    body = ast.get_source_segment(src, fn) or ""
    if PLOT_NAMES.match(fn.name) or "matplotlib" in body or "plt." in body:
        return "plotting"
    if IO_NAMES.match(fn.name):
        return "command"
    return "analysis"


def count(path: Path) -> dict[str, int]:
    src = path.read_text()
    tree = ast.parse(src)
    out = dict.fromkeys(CLASSES, 0)
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            start = min([node.lineno] + [d.lineno for d in node.decorator_list])
            out[classify(node, src)] += node.end_lineno - start + 1
    return out


def main(argv: list[str]) -> int:
    dirs = [Path(a) for a in argv] or [Path("probedyn/commands")]
    files = sorted(f for d in dirs for f in (d.rglob("*.py") if d.is_dir() else [d]))
    tot = dict.fromkeys(CLASSES, 0)
    print(f"{'file':<40}" + "".join(f"{c:>10}" for c in CLASSES) + f"{'total':>10}")
    for f in files:
        c = count(f)
        for k in CLASSES:
            tot[k] += c[k]
        print(f"{str(f):<40}" + "".join(f"{c[k]:>10}" for k in CLASSES) + f"{sum(c.values()):>10}")
    print(f"{'TOTAL':<40}" + "".join(f"{tot[k]:>10}" for k in CLASSES) + f"{sum(tot.values()):>10}")
    rest = sum(tot.values()) - tot["command"]
    print(f"\nfunction lines: {sum(tot.values())}; command definitions {tot['command']}; "
          f"not command definitions {rest} (prose {tot['prose']}, plotting {tot['plotting']}, "
          f"analysis {tot['analysis']})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
