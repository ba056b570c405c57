"""Cheap stand-in report sections for tests/test_report_runner.py (imported by the report's
worker processes by name, like the real sections): each writes a figure-like file and returns
Markdown naming it."""

from __future__ import annotations

import os
import time
from pathlib import Path

from probedyn.core.errors import ParameterError
from probedyn.core.io import write_text


def first(outdir: Path, quick: bool) -> str:
    write_text(Path(outdir) / "first.txt", "first\n")
    return f"first section, quick={quick}\n\n![first](first.txt)"


def second(outdir: Path, quick: bool) -> str:
    write_text(Path(outdir) / "sub" / "second.txt", "second\n")
    return "second section: pid-independent text"


def third(outdir: Path, quick: bool) -> str:
    return "third section, threads: " + os.environ.get("OMP_NUM_THREADS", "unset")


def failing(outdir: Path, quick: bool) -> str:
    write_text(Path(outdir) / "half.txt", "written before the failure\n")
    raise ParameterError("a bad value in the failing section")


def sleeping(outdir: Path, quick: bool) -> str:
    write_text(Path(outdir) / "sleeping.txt", "before the sleep\n")
    time.sleep(60)
    return "never"
