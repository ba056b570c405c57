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
    jobs: Optional[int] = typer.Option(None, "--jobs", min=1,
                                       help="Sections run at once on worker processes (default: "
                                            "$PROBEDYN_REPORT_JOBS or 2 on 2+ cores; 1 = one after the other)."),
) -> None:
    """Run the default probes and schemes and write a Markdown report with figures."""
    from probedyn.report import build_report

    path = build_report(out, quick=quick, only=only, jobs=jobs)
    typer.echo(f"report written to {path}")
