"""The command line as a whole: every command module is present and errors are one line."""

import importlib
import subprocess
import sys

import pytest

from probedyn.cli import main
from probedyn.commands import COMMAND_MODULES
from probedyn.report import SECTIONS


@pytest.mark.parametrize("name", COMMAND_MODULES)
def test_every_command_module_imports(name):
    importlib.import_module(name)


@pytest.mark.parametrize("title,target", SECTIONS)
def test_every_report_section_exists(title, target):
    mod, func = target.split(":")
    assert callable(getattr(importlib.import_module(mod), func))


def test_help_lists_the_main_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for cmd in ("modes", "compare", "reduce", "render", "params", "simulate", "contact",
                "sweep", "stickslip", "diagnose", "report"):
        assert cmd in out


def test_user_error_is_one_line_without_traceback():
    proc = subprocess.run(
        [sys.executable, "-m", "probedyn.cli", "modes", "cantilever", "--set", "length=-1"],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("probedyn: error:"), proc.stderr
    assert "Traceback" not in proc.stderr


def test_diagnose_noise_model_is_checked_before_reading(capsys):
    """``probedyn diagnose --noise`` takes auto or white; anything else is a one-line usage error (exit 2)."""
    assert main(["diagnose", "no-such-file.toml", "--noise", "pink"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("probedyn: error:") and "--noise" in err[0]
