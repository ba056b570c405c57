"""The report's section runner (probedyn/report/_runner.py): serial and parallel give the same
report, a failing section gives the one-line error and writes nothing, an interrupt leaves
nothing behind and no worker running."""

from __future__ import annotations

import _thread
import multiprocessing
import re
import threading
import time
from pathlib import Path

import pytest

import probedyn.report as R
from probedyn.cli import main as cli_main
from probedyn.core.errors import ParameterError
from probedyn.report._runner import run_sections

HERE = "report_runner_sections"  # tests/report_runner_sections.py (tests/ is on sys.path)
SECTIONS = [("First", f"{HERE}:first"), ("Second", f"{HERE}:second")]


def _body(md: str) -> str:
    """The report without its run-time table (wall times differ from run to run)."""
    return md.split("## Run times")[0]


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_serial_and_parallel_write_the_same_report(tmp_path, monkeypatch):
    monkeypatch.setattr(R, "SECTIONS", SECTIONS)
    a = R.build_report(tmp_path / "serial", quick=True, jobs=1)
    b = R.build_report(tmp_path / "parallel", quick=True, jobs=2)
    assert _body(a.read_text()) == _body(b.read_text())
    assert "first section, quick=True" in a.read_text()
    assert a.read_text().index("## First") < a.read_text().index("## Second")  # SECTIONS order
    assert _files(tmp_path / "serial") == _files(tmp_path / "parallel") == ["first.txt", "report.md", "sub/second.txt"]
    assert "on 2 worker processes" in b.read_text() and "one after the other" in a.read_text()


def test_workers_run_one_thread_each(tmp_path):
    (r,) = run_sections([("Third", f"{HERE}:third"), ("First", f"{HERE}:first")], tmp_path, False, jobs=2)[:1]
    assert r.body.endswith("threads: 1")


def test_failing_section_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(R, "SECTIONS", [SECTIONS[0], ("Failing", f"{HERE}:failing"), SECTIONS[1]])
    out = tmp_path / "out"
    with pytest.raises(ParameterError, match="a bad value in the failing section"):
        R.build_report(out, jobs=2)
    assert not out.exists() or _files(out) == []
    assert not multiprocessing.active_children()


def test_failing_section_is_one_line_on_the_command_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(R, "SECTIONS", [SECTIONS[0], ("Failing", f"{HERE}:failing")])
    out = tmp_path / "out"
    code = cli_main(["report", "--jobs", "2", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err == ["probedyn: error: a bad value in the failing section"]
    assert not out.exists() or _files(out) == []


def test_interrupt_kills_workers_and_leaves_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(R, "SECTIONS", [("Sleeping", f"{HERE}:sleeping"), SECTIONS[0]])
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.md").write_text("previous report\n")

    def interrupt_when_started():  # once the sleeping section has written into its staging folder
        t_end = time.monotonic() + 60
        while time.monotonic() < t_end and not list(out.rglob("*sleeping.txt")):
            time.sleep(0.05)
        _thread.interrupt_main()

    threading.Thread(target=interrupt_when_started, daemon=True).start()
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        R.build_report(out, jobs=2)
    assert time.monotonic() - t0 < 30  # the sleeping worker was killed, not waited for
    assert _files(out) == ["old.md"]
    assert not [p for p in out.iterdir() if re.search(r"probedyn-tmp", p.name)]
    assert not multiprocessing.active_children()


def test_real_sections_serial_and_parallel_same_markdown(tmp_path):
    """Two cheap real sections (quick mode): the same Markdown and the same figure files
    whether they run in this process or on two workers."""
    only = ["Piezoelectric actuation", "Measured data"]
    a = R.build_report(tmp_path / "serial", quick=True, only=only, jobs=1)
    b = R.build_report(tmp_path / "parallel", quick=True, only=only, jobs=2)
    assert _body(a.read_text()) == _body(b.read_text())
    assert "## Piezoelectric actuation" in _body(b.read_text()) and "## Measured data" in _body(b.read_text())
    assert _files(tmp_path / "serial") == _files(tmp_path / "parallel")
    assert len(_files(tmp_path / "parallel")) > 2  # the figures came back from the workers
