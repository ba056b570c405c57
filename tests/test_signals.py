"""gmsh resets signal dispositions at the C level; probedyn puts Python's back (core/signals.py).

SIGPIPE matters most: Python ignores it (a write to a pipe with no reader raises BrokenPipeError),
and a process where gmsh had set it back to the default died silently with signal 13 the next time
it wrote to a closed pipe (a killed report worker's queue, ``probedyn ... | head``)."""

from __future__ import annotations

import signal
from pathlib import Path

import pytest

from probedyn.meshes._gmsh import gmsh_session


def _ignored(signum: int) -> bool:
    """What the kernel does with ``signum`` for this process (not what Python believes)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("SigIgn:"):
            return bool(int(line.split()[1], 16) & (1 << (signum - 1)))
    pytest.skip("no /proc/self/status")


def test_a_gmsh_session_leaves_sigpipe_ignored():
    assert _ignored(signal.SIGPIPE)  # Python's start-up state
    with gmsh_session("signals-test") as gmsh:
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
    assert _ignored(signal.SIGPIPE)
