"""``probedyn report``: the main job."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from probedyn.commands._apps import app


@app.command("report")
def report(
    out: Path = typer.Option(Path("out/report"), "--out", help="Output folder."),
    quick: bool = typer.Option(False, "--quick", help="Coarser meshes and shorter runs."),
    only: Optional[List[str]] = typer.Option(None, "--only", help="Only sections whose title contains this."),
) -> None:
    """Run the default probes and schemes and write a Markdown report with figures."""
    from probedyn.report import build_report

    path = build_report(out, quick=quick, only=only)
    typer.echo(f"report written to {path}")
