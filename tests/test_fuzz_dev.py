"""``./dev`` on a machine without a usable Python venv (issue 16, class 11), without root or network.

The script is run from a scratch copy with ``PYTHON`` pointing at a stand-in interpreter and a
fake ``apt-get``/``apt-cache``/``sudo`` first on ``PATH`` (they log their arguments and change
nothing): what matters is what ``./dev`` decides, says and leaves behind.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _exe(path: Path, text: str) -> Path:
    path.write_text(text)
    path.chmod(0o755)
    return path


@pytest.fixture
def box(tmp_path):
    """A scratch project (dev + pyproject) and a bin folder with fakes."""
    proj = tmp_path / "proj"
    proj.mkdir()
    shutil.copy(ROOT / "dev", proj / "dev")
    shutil.copy(ROOT / "pyproject.toml", proj / "pyproject.toml")
    fake = tmp_path / "bin"
    fake.mkdir()
    log = tmp_path / "apt.log"
    for tool in ("apt-get", "apt-cache"):
        _exe(fake / tool, f'#!/bin/sh\necho "{tool} $*" >> {log}\nexit 0\n')
    _exe(fake / "sudo", '#!/bin/sh\nexec "$@"\n')
    # a Python without ensurepip: a real interpreter for everything but ensurepip
    _exe(fake / "py-noensurepip", f'#!/bin/sh\ncase "$*" in *ensurepip*) exit 1 ;; esac\nexec {sys.executable} "$@"\n')
    return proj, fake, log


def _dev(proj, fake, *args, python=None):
    env = {**os.environ, "PATH": f"{fake}:{os.environ['PATH']}", "PYTHON": str(python or fake / "py-noensurepip")}
    return subprocess.run(["bash", str(proj / "dev"), *args], capture_output=True, text=True, env=env, timeout=120)


def test_python_without_ensurepip_installs_python3_venv_and_leaves_no_venv(box):
    proj, fake, log = box
    r = _dev(proj, fake, "setup")
    assert r.returncode == 1
    assert "cannot create virtual environments (no venv/ensurepip module)" in r.stderr
    assert "apt-get install -y -qq python3-venv" in log.read_text()  # the package was asked for
    assert "still has no ensurepip after installing python3-venv" in r.stderr  # the fake changed nothing
    assert not (proj / ".venv").exists()


def test_missing_python_is_installed_or_named(box):
    proj, fake, log = box
    r = _dev(proj, fake, "test", python=proj / "no" / "python3")
    assert r.returncode == 1 and "install -y -qq python3 python3-venv" in log.read_text()
    assert "is still not found after installing python3" in r.stderr and not (proj / ".venv").exists()


def test_a_broken_venv_is_detected_and_rebuilt(box):
    proj, fake, log = box
    # what `python3 -m venv` leaves without python3-venv: an interpreter but no pip
    (proj / ".venv" / "bin").mkdir(parents=True)
    _exe(proj / ".venv" / "bin" / "python", '#!/bin/sh\necho "No module named pip" >&2\nexit 1\n')
    r = _dev(proj, fake, "test")
    assert "is incomplete or broken" in r.stderr and "rebuilding it" in r.stderr
    assert r.returncode == 1 and not (proj / ".venv").exists()  # rebuilt, failed (no ensurepip), removed


def test_without_root_or_sudo_the_packages_are_named(box, tmp_path):
    proj, fake, log = box
    if os.geteuid() != 0:
        (fake / "sudo").unlink()
        r = _dev(proj, fake, "setup")
        assert r.returncode == 1 and "not root and no sudo: please run  apt-get install python3-venv" in r.stderr
    else:  # as root, apt-get is used directly
        r = _dev(proj, fake, "setup")
        assert "apt-get install -y -qq python3-venv" in log.read_text()


def test_unknown_dev_command_is_a_usage_error(box):
    proj, fake, _ = box
    r = _dev(proj, fake, "frobnicate")
    assert r.returncode == 2 and r.stderr.startswith("usage: ./dev")


def test_pyproject_licence_and_pins():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "BSD-3-Clause"  # SPDX string, not the deprecated table
    assert "setuptools>=77" in meta["build-system"]["requires"][0]  # the first version that reads it
    deps = {d.split(">")[0].split("=")[0].split("<")[0].strip(): d for d in meta["project"]["dependencies"]}
    from importlib.metadata import version

    from packaging.specifiers import SpecifierSet

    for name in ("typer", "click"):
        spec = SpecifierSet(deps[name][len(name):].split("#")[0].strip())
        assert version(name) in spec, f"installed {name} {version(name)} outside the tested range {spec}"
