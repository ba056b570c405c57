"""probedyn.core.io, core.schema and core.resources under faults: output sets, permissions,
stale temporaries, confined bounded reads, schema errors, memory refusals (fast, in-process)."""

from __future__ import annotations

import errno
import json
import os
import signal
import stat
import re
import threading
from pathlib import Path

import pytest

from probedyn.core import io as pio
from probedyn.core.errors import DataFormatError, OutputError, ResourceError
from probedyn.core.params import Param
from probedyn.core.resources import available_memory, check_memory, fmt_bytes
from probedyn.core.schema import Field, Table


@pytest.fixture(autouse=True)
def _sigint(sigint_not_ignored):
    """These tests deliver SIGINT (tests/conftest.py: sigint_not_ignored)."""


@pytest.fixture(autouse=True)
def _fresh_io_state():
    pio._cleaned.clear()
    pio._UMASK = None
    yield
    pio._UMASK = None


def _names(folder):
    return sorted(p.name for p in folder.iterdir())


# ---- output sets ------------------------------------------------------------------------------


def test_output_set_appears_all_at_once_or_not_at_all(tmp_path):
    out = tmp_path / "o"
    with pio.output_set(out) as d:
        assert d == out
        pio.write_json(d / "modes.json", {"v": 1})
        pio.write_text(d / "modes.vtu", "old vtu")
        assert _names(out) == sorted(n for n in _names(out) if "probedyn-tmp" in n)  # nothing visible yet
    assert _names(out) == ["modes.json", "modes.vtu"]
    # a second run killed (any exception, KeyboardInterrupt included) between its two files:
    # the old set stays, complete; no temporary is left
    with pytest.raises(KeyboardInterrupt):
        with pio.output_set(out) as d:
            pio.write_json(d / "modes.json", {"v": 2})
            raise KeyboardInterrupt
    assert (out / "modes.vtu").read_text() == "old vtu" and '"v": 1' in (out / "modes.json").read_text()
    assert _names(tmp_path) == ["o"] and _names(out) == ["modes.json", "modes.vtu"]
    # a complete second run replaces both files and keeps a user's own file beside them
    (out / "notes.txt").write_text("mine")
    with pio.output_set(out) as d:
        pio.write_json(d / "modes.json", {"v": 3})
        pio.write_text(d / "modes.vtu", "new vtu")
        pio.write_bytes(d / "sub" / "x.png", b"png")
    assert _names(out) == ["modes.json", "modes.vtu", "notes.txt", "sub"]
    assert (out / "modes.vtu").read_text() == "new vtu" and (out / "notes.txt").read_text() == "mine"
    assert _names(tmp_path) == ["o"]


def test_a_failed_set_removes_the_folders_it_created(tmp_path):
    with pytest.raises(RuntimeError):
        with pio.output_set(tmp_path / "a" / "b") as d:
            pio.write_json(d / "c" / "x.json", 1)
            raise RuntimeError("solver failed")
    assert _names(tmp_path) == []


def test_transaction_defers_every_write_and_after_commit_waits(tmp_path):
    done = []
    with pio.transaction():
        pio.write_json(tmp_path / "a.json", 1)
        pio.write_json(tmp_path / "x" / "b.json", 2)
        pio.write_json(tmp_path / "cache.json", 3, defer=False)  # state: at once
        pio.after_commit(lambda: done.append(sorted(p.name for p in tmp_path.rglob("*.json"))))
        assert not (tmp_path / "a.json").exists() and (tmp_path / "cache.json").exists()
        assert done == []
    assert done == [["a.json", "b.json", "cache.json"]]


def test_signal_during_commit_is_delivered_after_the_set_is_complete(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "a.json").write_text("old a")
    (out / "b.json").write_text("old b")
    real = os.replace
    calls = []

    def replace_then_signal(src, dst):
        if not calls:  # SIGINT arrives after the first rename of the commit
            signal.raise_signal(signal.SIGINT)
        calls.append(dst)
        real(src, dst)

    with pytest.raises(KeyboardInterrupt):
        with pio.output_set(out) as d:
            pio.write_text(d / "a.json", "new a")
            pio.write_text(d / "b.json", "new b")
            os.replace = replace_then_signal  # for the commit that follows the block
    os.replace = real
    assert len(calls) == 2
    assert (out / "a.json").read_text() == "new a" and (out / "b.json").read_text() == "new b"


def test_commit_killed_half_way_is_rolled_forward_by_the_next_run(tmp_path):
    """SIGKILL between two renames of a commit: the journal lets the next run finish them."""
    out = tmp_path / "o"
    out.mkdir()
    (out / "a.json").write_text("new a")  # renamed before the kill
    (out / "b.json").write_text("old b")
    tmp_b = out / f".b.json.probedyn-tmp-{pio._HOST}-999999-0badc0de.json"  # pid 999999: dead
    tmp_b.write_text("new b")
    journal = out / f".probedyn-commit.probedyn-tmp-{pio._HOST}-999999-0badc0de.json"
    journal.write_text(json.dumps([[str(out / "gone-a.tmp"), str(out / "a.json")], [str(tmp_b), str(out / "b.json")]]))
    removed = pio.clean_stale(out)
    assert sorted(p.name for p in removed) == sorted([journal.name, tmp_b.name])
    assert (out / "a.json").read_text() == "new a" and (out / "b.json").read_text() == "new b"
    assert _names(out) == ["a.json", "b.json"]


def test_stale_temporaries_of_dead_processes_are_removed_live_ones_kept(tmp_path):
    dead_file = tmp_path / f".x.json.probedyn-tmp-{pio._HOST}-999999-0badc0de.json"
    dead_dir = tmp_path / f".out.probedyn-tmp-{pio._HOST}-999999-0badc0de"
    live = tmp_path / f".y.json.probedyn-tmp-{pio._HOST}-{os.getppid()}-0badc0de.json"
    other_host = tmp_path / ".z.json.probedyn-tmp-abcdef-1-0badc0de.json"
    user = tmp_path / ".hidden-user-file"
    dead_file.write_text("")
    dead_dir.mkdir()
    (dead_dir / "f").write_text("")
    for p in (live, other_host, user):
        p.write_text("")
    pio.write_json(tmp_path / "x.json", 1)
    assert _names(tmp_path) == sorted([live.name, other_host.name, user.name, "x.json"])


def test_files_honour_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        pio._UMASK = None
        pio.write_json(tmp_path / "a.json", 1)
        with pio.output_set(tmp_path / "s") as d:
            pio.write_text(d / "b.txt", "x")
            with pio.atomic_path(d / "c.txt") as tmp:  # a library writing with open(): umask as well
                with open(tmp, "w") as fh:
                    fh.write("y")
        os.umask(0o077)
        pio._UMASK = None
        pio.write_json(tmp_path / "p.json", 1)
    finally:
        os.umask(old)
    mode = lambda p: stat.S_IMODE(p.stat().st_mode)  # noqa: E731
    assert mode(tmp_path / "a.json") == 0o644
    assert mode(tmp_path / "s") == 0o755
    assert mode(tmp_path / "s" / "b.txt") == 0o644 and mode(tmp_path / "s" / "c.txt") == 0o644
    assert mode(tmp_path / "p.json") == 0o600


@pytest.mark.parametrize("where", ["file-in-the-way", "parent-is-file", "folder-in-the-way"])
def test_misplaced_files_are_one_line_output_errors(tmp_path, where):
    (tmp_path / "f").write_text("x")
    (tmp_path / "d").mkdir()
    with pytest.raises(OutputError) as exc:
        if where == "file-in-the-way":
            with pio.output_set(tmp_path / "f"):
                pass
        elif where == "parent-is-file":
            pio.write_json(tmp_path / "f" / "x.json", 1)
        else:
            pio.write_json(tmp_path / "d", 1)
    assert "\n" not in str(exc.value) and str(tmp_path) in str(exc.value)
    assert _names(tmp_path) == ["d", "f"]


@pytest.mark.parametrize("err_no,phrase", [(errno.ENOSPC, "no space left"), (errno.EROFS, "read-only"),
                                           (errno.EDQUOT, "quota"), (errno.EACCES, "permission denied")])
def test_write_errors_inside_a_set_become_output_errors(tmp_path, err_no, phrase):
    with pytest.raises(OutputError, match=phrase):
        with pio.output_set(tmp_path / "o") as d:
            pio.write_json(d / "small.json", {})
            with pio.atomic_path(d / "big.vtu") as tmp:  # a writer failing half-way
                raise OSError(err_no, os.strerror(err_no), str(tmp))
    assert _names(tmp_path) == []


def test_a_read_error_inside_a_set_is_not_disguised_as_a_write_error(tmp_path):
    with pytest.raises(PermissionError):
        with pio.output_set(tmp_path / "o"):
            raise PermissionError(errno.EACCES, "Permission denied", "/etc/shadow-like-input")
    assert _names(tmp_path) == []


def test_concurrent_sets_into_one_folder_never_mix(tmp_path):
    out = tmp_path / "o"
    errors = []

    def writer(k):
        try:
            for _ in range(15):
                with pio.output_set(out) as d:
                    for name in ("a", "b", "c"):
                        pio.write_text(d / name, str(k))
        except Exception as exc:  # pragma: no cover
            errors.append(exc)

    ths = [threading.Thread(target=writer, args=(k,)) for k in range(3)]
    for t in ths:
        t.start()
    for t in ths:
        t.join()
    assert not errors
    vals = {(out / n).read_text() for n in ("a", "b", "c")}
    assert len(vals) == 1  # the last committed set, whole
    assert _names(tmp_path) == ["o"]


# ---- confined, bounded reading -------------------------------------------------------------------


def test_reader_refuses_devices_fifos_folders_and_big_files(tmp_path):
    os.mkfifo(tmp_path / "fifo")
    with open(tmp_path / "big", "wb") as fh:
        fh.truncate(5 * 1024**2)
    for path, phrase in (("/dev/zero", "device"), (tmp_path / "fifo", "FIFO"), (tmp_path, "folder"),
                         (tmp_path / "big", "limit"), (tmp_path / "none", "no such file")):
        with pytest.raises(DataFormatError, match=phrase):
            pio.read_bytes(path, max_bytes=1024**2)


def test_reader_confines_paths_named_by_a_data_file(tmp_path):
    side = tmp_path / "meas"
    (side / "sub").mkdir(parents=True)
    (side / "sub" / "ok.csv").write_text("a,b\n")
    secret = tmp_path / "secret.txt"
    secret.write_text("root:x:0:0:the first line must never be echoed\n")
    (side / "link.csv").symlink_to(secret)
    assert pio.read_text("sub/ok.csv", side) == "a,b\n"
    for bad in ("../secret.txt", str(secret), "link.csv", "sub/../../secret.txt"):
        with pytest.raises(DataFormatError, match="outside the folder") as exc:
            pio.read_text(bad, side)
        assert "root:" not in str(exc.value)
    assert pio.read_text("../secret.txt", side, allow_outside=True).startswith("root:")
    assert pio.read_text("../secret.txt", side, allowed_roots=[tmp_path]).startswith("root:")


def test_non_utf8_is_located_not_echoed(tmp_path):
    p = tmp_path / "x.toml"
    p.write_bytes(b'a = 1\nname = "secret \xff value"\n')
    with pytest.raises(DataFormatError) as exc:
        pio.load_toml(p)
    assert "x.toml:2:16: not UTF-8" in str(exc.value) and "secret" not in str(exc.value)


# ---- schema --------------------------------------------------------------------------------------

MEDIUM = Table({"name": Field(str, choices=("vacuum", "air", "water")),
                "temperature": Field(float, param=Param("temperature", 293.15, "K", lo=1.0, hi=2000.0))})
SIDE = Table({"medium": Field(dict, table=MEDIUM), "free": Field(list, item=str, unique=True),
              "noise": Field(dict, table=Table({"force": Field(float, param=Param("force", 0.0, "N", lo=0.0))})),
              "families": Field(list, item=str, min_items=1), "scan": Field(int, required=True)})


@pytest.mark.parametrize("data,phrase", [
    ({"scan": 1, "medium": {"nmae": "water"}}, r"\[medium\] unknown key 'nmae' \(did you mean 'name'\?\)"),
    ({"scan": 1, "noise": 5}, r"'noise' must be a table, got an integer"),
    ({"scan": 1, "families": 5}, r"'families' must be an array, got an integer"),
    ({"scan": "3"}, r"'scan' must be an integer, got a string"),
    ({"scan": 1, "free": ["mu", "mu"]}, r"'free' lists an entry twice"),
    ({"scan": 1, "medium": {"temperature": True}}, r"must be a number, got a boolean"),
    ({"scan": 1, "medium": {"temperature": 1e308}}, r"outside the plausible range"),
    ({"scan": 1, "medium": {"temperature": float("nan")}}, r"finite"),
    ({"scan": 1, "noise": {"force": -1.0}}, r"outside the plausible range \(at least 0 N\)"),
    ({"scan": 1, "medium": {"name": "watr"}}, r"one of vacuum, air, water \(did you mean 'water'\?\)"),
    ({}, r"missing key 'scan'"),
    ({"scan": 1, "familes": ["flap"]}, r"did you mean 'families'"),
])
def test_schema_errors_name_file_table_and_key(data, phrase):
    with pytest.raises(DataFormatError, match=phrase) as exc:
        SIDE.validate(data, "m.toml")
    assert str(exc.value).startswith("m.toml:") and "\n" not in str(exc.value)


def test_schema_accepts_and_converts_good_tables():
    v = SIDE.validate({"scan": 2.0, "medium": {"name": "air", "temperature": 300}, "free": ["a", "b"]}, "m.toml")
    assert v == {"scan": 2, "medium": {"name": "air", "temperature": 300.0}, "free": ["a", "b"]}


# ---- memory ----------------------------------------------------------------------------------------


def test_memory_refusal_states_the_estimate_and_what_is_available():
    avail = available_memory()
    assert 1e8 < avail < 1e14
    check_memory(avail * 0.1, "a small thing")
    with pytest.raises(ResourceError, match=r"a sweep needs about .* \(1e\+10 cells x 32 B\) of memory; .* are available"):
        check_memory(3.2e11, "a sweep", how="1e+10 cells x 32 B")
    assert fmt_bytes(3.2e11) == "320 GB" and fmt_bytes(512) == "512 B"


# ---- every writer goes through probedyn.core.io ---------------------------------------------------

_WRITERS = re.compile(r"(\.savefig\(|\.screenshot\(|meshio\.write\(|\.to_netcdf\(|\bopen\([^)]*[\"'][wax]b?[\"']|"
                      r"\.write_text\(|\.write_bytes\(|np\.save[z]?(_compressed)?\()")
_TMP_ARG = re.compile(r"(\.savefig|\.screenshot|meshio\.write|\.to_netcdf|\bopen|np\.save[z]?(?:_compressed)?)"
                      r"\(\s*(str\()?(tmp|fh)\b")


def test_every_file_is_written_through_core_io():
    """Outputs are atomic, umask-honouring and part of the command's transaction only if written
    through probedyn.core.io: any other writer must write the temporary that io.atomic_path yields."""
    root = Path(__file__).resolve().parents[1]
    bad = []
    for folder in ("probedyn", "fem", "lumped", "meshes", "schemes"):
        for f in sorted((root / folder).rglob("*.py")):
            if f.relative_to(root).as_posix() == "probedyn/core/io.py":
                continue
            for n, line in enumerate(f.read_text().splitlines(), 1):
                code = line.split("#")[0]
                if _WRITERS.search(code) and not _TMP_ARG.search(code):
                    bad.append(f"{f.relative_to(root)}:{n}: {line.strip()}")
    assert not bad, "files written outside probedyn.core.io:\n" + "\n".join(bad)
