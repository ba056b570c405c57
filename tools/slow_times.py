"""The slow tests and their times, as a markdown table, from a ``pytest --durations=0`` log (issue 15).

Run the slow tests with their durations, then turn the log into the table of
``docs/developing.md`` ("Slow tests and their times")::

    .venv/bin/python -m pytest -m slow -n 2 --durations=0 -q > slow.log
    python tools/slow_times.py slow.log

Each row is one test: its setup + call + teardown seconds (on one xdist worker; the run's wall time
is about half the total on two workers), slowest first, with its outcome where the log's short
summary names one (``-ra``: failures, errors, xfail/xpass; passed tests are not listed there).
"""

from __future__ import annotations

import collections
import re
import sys


def slow_times(log: str) -> list[tuple[str, float, str]]:
    """``[(test id, seconds, outcome)]`` slowest first from the text of a ``--durations=0`` log."""
    seconds: dict[str, float] = collections.defaultdict(float)
    for m in re.finditer(r"^([0-9.]+)s (?:call|setup|teardown)\s+(.+?)\s*$", log, re.M):
        seconds[m.group(2)] += float(m.group(1))
    outcome = {m.group(2): m.group(1).lower() for m in
               re.finditer(r"^(FAILED|ERROR|XFAIL|XPASS)\s+(.+?)(?: - .*)?$", log, re.M)}
    return sorted(((t, s, outcome.get(t, "passed")) for t, s in seconds.items()), key=lambda r: -r[1])


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: python tools/slow_times.py PYTEST_DURATIONS_LOG", file=sys.stderr)
        return 2
    with open(argv[1], encoding="utf-8") as fh:
        rows = slow_times(fh.read())
    print("| test | seconds | outcome |")
    print("|---|---:|---|")
    for t, s, o in rows:
        print(f"| `{t.removeprefix('tests/')}` | {s:.1f} | {o} |")
    print(f"| **{len(rows)} tests** | **{sum(s for _, s, _ in rows):.0f}** | |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
