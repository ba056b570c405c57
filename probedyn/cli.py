"""The ``probedyn`` command line: a thin layer over the library.

Errors caused by input (:class:`probedyn.core.errors.ProbedynError`) are printed on one line and
exit non-zero without a traceback; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import importlib
import sys

from probedyn.commands import COMMAND_MODULES
from probedyn.commands._apps import app
from probedyn.core.errors import ProbedynError

for _name in COMMAND_MODULES:
    # Each module attaches its commands to the Typer apps. A module that does not exist (yet)
    # is skipped here; tests/test_cli_basics.py asserts that every listed module is present.
    try:
        importlib.import_module(_name)
    except ModuleNotFoundError as _exc:
        if _exc.name != _name:
            raise


def main(argv: list[str] | None = None) -> int:
    try:
        app(args=argv, standalone_mode=False)
    except ProbedynError as exc:
        print(f"probedyn: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except SystemExit as exc:  # typer/click usage errors and --help
        return int(exc.code or 0)
    except Exception as exc:  # click exceptions in non-standalone mode
        import click

        if isinstance(exc, click.exceptions.ClickException):
            exc.show()
            return exc.exit_code
        if isinstance(exc, click.exceptions.Abort):
            print("probedyn: aborted", file=sys.stderr)
            return 1
        raise
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
