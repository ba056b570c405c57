"""``python -m probedyn ARGS``: the ``probedyn`` command (:func:`probedyn.cli.main`), e.g. under a profiler."""

from probedyn.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
