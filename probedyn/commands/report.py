"""``probedyn report``: the main job."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import out_folder_option


@app.command("report")
def report(
    out: Path = out_folder_option(Path("out/report"), "Output folder."),
    quick: bool = typer.Option(False, "--quick", help="Coarser meshes and shorter runs."),
    only: Optional[List[str]] = typer.Option(None, "--only", help="Only sections whose title contains this."),
) -> None:
    """Run the default probes and schemes and write a Markdown report with figures."""
    from probedyn.report import build_report

    path = build_report(out, quick=quick, only=only)
    typer.echo(f"report written to {path}")
