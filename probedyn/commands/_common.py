"""Helpers shared by command modules: JSON vs. human output, output folders."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Callable

import typer

from probedyn.core.io import dumps, write_json

def _check_out_folder(value: Path | None) -> Path | None:
    """Before any work: ``--out DIR`` must be able to become a folder (not a file, writable parent)."""
    from probedyn.core.io import check_output_folder

    return None if value is None else check_output_folder(value)


def _check_out_file(value: Path | None) -> Path | None:
    """Before any work: ``--out FILE`` must be writable (not a folder, its folder writable)."""
    from probedyn.core.io import check_output_file

    return None if value is None else check_output_file(value)


def out_folder_option(default: Path | None = None, help: str = "Output folder for files (JSON, plots, VTU).") -> Any:
    """``--out DIR``: checked before the command works; its files appear together when it succeeds
    (the command line runs every command in one output transaction, probedyn.core.io)."""
    return typer.Option(default, "--out", help=help, callback=_check_out_folder)


def out_file_option(default: Any = None, help: str = "Output file.") -> Any:
    """``--out FILE``: checked before the command works (see :func:`out_folder_option`)."""
    return typer.Option(default, "--out", help=help, callback=_check_out_file)


JSON_OPT = typer.Option(False, "--json", help="Print machine-readable JSON on stdout.")
OUT_OPT = out_folder_option()
SET_OPT = typer.Option(None, "--set", help="Override a parameter: NAME=VALUE (SI units). Repeatable.")


def emit(result: Any, as_json: bool, human: Callable[[Any], str]) -> None:
    """Print ``result`` as JSON (``--json``) or through ``human`` as text for people."""
    if as_json:
        sys.stdout.write(dumps(result) + "\n")
    else:
        sys.stdout.write(human(result).rstrip() + "\n")


def save(out: Path | None, name: str, result: Any) -> Path | None:
    """Write ``result`` as ``out/name`` atomically when an output folder was given."""
    if out is None:
        return None
    return write_json(Path(out) / name, result)


def format_table(rows: list[dict[str, Any]], columns: list[tuple[str, str, str]] | None = None) -> str:
    """A plain-text table. ``columns`` = [(key, header, format spec)]; default: all keys."""
    if not rows:
        return "(empty)"
    if columns is None:
        columns = [(k, k, "") for k in rows[0]]
    cells = [[h for _, h, _ in columns]]
    for r in rows:
        line = []
        for key, _, spec in columns:
            v = r.get(key)
            if v is None:
                line.append("-")
            elif spec and isinstance(v, (int, float)):
                line.append(format(v, spec))
            else:
                line.append(str(v))
        cells.append(line)
    widths = [max(len(row[i]) for row in cells) for i in range(len(columns))]
    out = []
    for j, row in enumerate(cells):
        out.append("  ".join(c.rjust(w) for c, w in zip(row, widths)))
        if j == 0:
            out.append("  ".join("-" * w for w in widths))
    return "\n".join(out)
