"""Declared parameters with units, defaults and plausibility ranges.

Models, probes and schemes declare their parameters as :class:`Param` objects; the command
line's ``--set NAME=VALUE``, TOML probe files and ``probedyn params`` all go through here, so
unit mistakes (micrometres typed as metres) are caught in one place.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

from probedyn.core.errors import ParameterError


@dataclass(frozen=True)
class Param:
    """One parameter: SI unit, default, meaning and the range a physical value lies in.

    ``lo``/``hi`` bound physically plausible values (exclusive of the nonsense a unit slip
    produces); ``positive`` rejects zero and negative values with a dedicated message.
    ``kind`` is ``float``, ``int``, ``str`` or ``bool``; ``choices`` restricts strings.
    """

    name: str
    default: Any
    unit: str = ""
    doc: str = ""
    lo: float | None = None
    hi: float | None = None
    positive: bool = False
    kind: type = float
    choices: tuple[str, ...] | None = None
    source: str = ""  # equation / table reference in the source thesis

    def coerce(self, value: Any) -> Any:
        """Convert ``value`` (possibly a string from the command line) and validate it."""
        if value is None:
            return None
        try:
            if self.kind is bool and isinstance(value, str):
                low = value.strip().lower()
                if low not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError(value)
                v: Any = low in ("true", "1", "yes")
            elif self.kind is int and isinstance(value, str):
                v = int(float(value))
            else:
                v = self.kind(value)
        except (TypeError, ValueError):
            raise ParameterError(
                f"parameter '{self.name}': cannot read {value!r} as {self.kind.__name__}"
            ) from None
        if self.choices is not None and v not in self.choices:
            raise ParameterError(
                f"parameter '{self.name}': {v!r} is not one of {', '.join(self.choices)}"
            )
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if not math.isfinite(v):
                raise ParameterError(f"parameter '{self.name}' must be finite, got {v}")
            if self.positive and v <= 0:
                raise ParameterError(
                    f"parameter '{self.name}' must be positive, got {v:g} {self.unit}".rstrip()
                )
            if self.lo is not None and v < self.lo:
                raise ParameterError(self._range_msg(v))
            if self.hi is not None and v > self.hi:
                raise ParameterError(self._range_msg(v))
        return v

    def _range_msg(self, v: float) -> str:
        if self.lo is not None and self.hi is not None:
            rng = f"the plausible range [{self.lo:g}, {self.hi:g}] {self.unit}".rstrip()
        elif self.hi is not None:
            rng = f"the plausible range (at most {self.hi:g} {self.unit})".replace(" )", ")")
        else:
            rng = f"the plausible range (at least {self.lo:g} {self.unit})".replace(" )", ")")
        msg = f"parameter '{self.name}' = {v:g} {self.unit} is outside {rng}".replace("  ", " ")
        if self.unit == "m" and self.hi is not None and v > self.hi:
            msg += f" (values are SI: did you mean {v:g}e-6 m, i.e. micrometres?)"
        return msg


@dataclass
class ParamSet:
    """An ordered collection of :class:`Param` with resolution of user overrides."""

    params: list[Param] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._by_name = {p.name: p for p in self.params}

    def __iter__(self):
        return iter(self.params)

    def __contains__(self, name: str) -> bool:
        return name in self._by_name

    def __getitem__(self, name: str) -> Param:
        return self._by_name[name]

    def defaults(self) -> dict[str, Any]:
        return {p.name: p.default for p in self.params}

    def resolve(self, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Defaults updated with ``overrides``; unknown names and bad values raise."""
        values = self.defaults()
        for name, value in (overrides or {}).items():
            if name not in self._by_name:
                import difflib

                known = ", ".join(self._by_name)
                close = difflib.get_close_matches(str(name), list(self._by_name), n=1, cutoff=0.6)
                hint = f" (did you mean '{close[0]}'?)" if close else ""
                raise ParameterError(f"unknown parameter '{name}'{hint} (known: {known})")
            values[name] = self._by_name[name].coerce(value)
        return values

    def table(self) -> list[dict[str, Any]]:
        """Rows for ``probedyn params``: name, unit, default, description, source."""
        return [
            {
                "name": p.name,
                "unit": p.unit,
                "default": p.default,
                "description": p.doc,
                "source": p.source,
                "range": [p.lo, p.hi] if (p.lo is not None or p.hi is not None) else None,
                "choices": list(p.choices) if p.choices else None,
            }
            for p in self.params
        ]


def parse_sets(items: Iterable[str] | None) -> dict[str, str]:
    """Parse command-line ``NAME=VALUE`` strings into a dict (values stay strings)."""
    out: dict[str, str] = {}
    for item in items or ():
        if "=" not in item:
            raise ParameterError(f"--set expects NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        name = name.strip()
        if not name:
            raise ParameterError(f"--set expects NAME=VALUE, got {item!r}")
        out[name] = value.strip()
    return out


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file (regular file, size-limited, UTF-8: :func:`probedyn.core.io.load_toml`);
    syntax errors name the file, line and column."""
    from probedyn.core.io import load_toml as _load_toml

    return _load_toml(path)
