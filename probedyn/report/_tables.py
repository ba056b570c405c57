"""Markdown tables and number formats shared by the report sections.

Column spec: a ``format`` spec (``".5g"``, ``"+.2f"``), ``"hz"`` / ``"hzN"`` for a frequency
through :func:`probedyn.plotting.fmt_hz` (5 or N significant digits, unit in the cell: the
one frequency format of the report), or ``""`` for ``str``. Missing values print as "–".
"""

from __future__ import annotations

from typing import Any

from probedyn.plotting import fmt_hz


def cell(v: Any, spec: str) -> str:
    """One table cell."""
    if v is None:
        return "–"
    if spec.startswith("hz") and isinstance(v, (int, float)):
        return fmt_hz(float(v), int(spec[2:]) if spec[2:] else 5)
    if spec and isinstance(v, (int, float)) and not isinstance(v, bool):
        return format(v, spec)
    return str(v)


def markdown_table(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]]) -> str:
    """``columns`` = [(key, header, spec)]; a Markdown table with right-aligned columns."""
    head = "| " + " | ".join(h for _, h, _ in columns) + " |"
    sep = "|" + "|".join("---:" for _ in columns) + "|"
    body = ["| " + " | ".join(cell(r.get(key), spec) for key, _, spec in columns) + " |" for r in rows]
    return "\n".join([head, sep, *body])
