"""Validation of input tables (TOML sidecars, probe files, JSON) against a declared schema.

A :class:`Table` declares the keys a table may hold, each a :class:`Field` with its type, and
for numbers a :class:`~probedyn.core.params.Param` (unit and plausible range: the same checks
as probe parameters). :meth:`Table.validate` returns the checked values and raises
:class:`~probedyn.core.errors.DataFormatError` on the first problem, with one line naming the
file, the table and the key:

* an unknown key (a misspelling must not silently fall back to a default): the closest known
  key is suggested (``did you mean 'name'?``);
* a value of the wrong type (``noise = 5`` where a table is expected, a string where a number
  is, ``true`` where a number is: TOML booleans are not numbers here);
* a number outside its plausible range or not finite; an array with repeated entries where
  they must be unique; a string that is not one of the allowed choices.

Messages name types, never echo strings from the file. Example::

    MEDIUM = Table({"name": Field(str, choices=("vacuum", "air", "water")),
                    "temperature": Field(float, param=Param("temperature", 293.15, "K", lo=1, hi=2000))})
    SIDE = Table({"medium": Field(dict, table=MEDIUM), "free": Field(list, item=str, unique=True)})
    values = SIDE.validate(load_toml(path), where=str(path))
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from probedyn.core.errors import DataFormatError, ParameterError
from probedyn.core.params import Param

__all__ = ["Field", "Table", "did_you_mean", "check_keys", "type_name"]


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``known``, or ``""``."""
    close = difflib.get_close_matches(str(name), [str(k) for k in known], n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def type_name(v: Any) -> str:
    """The TOML name of a value's type, for messages."""
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, int):
        return "an integer"
    if isinstance(v, float):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, Mapping):
        return "a table"
    if isinstance(v, (list, tuple)):
        return "an array"
    return f"a {type(v).__name__}"


def _where(where: str, path: str) -> str:
    return f"{where}: [{path}]" if path else f"{where}:"


def check_keys(data: Mapping[str, Any], known: Iterable[str], where: str = "", path: str = "") -> None:
    """Raise on the first key of ``data`` not in ``known`` (with a did-you-mean)."""
    known = list(known)
    for k in data:
        if k not in known:
            listing = f"; known keys: {', '.join(known)}" if known else ""
            raise DataFormatError(f"{_where(where, path)} unknown key '{k}'{did_you_mean(k, known)}{listing}")


_KIND_NAME = {float: "a number", int: "an integer", str: "a string", bool: "a boolean (true/false)",
              list: "an array", dict: "a table"}


@dataclass(frozen=True)
class Field:
    """One key of a :class:`Table`.

    ``kind``: float, int, str, bool, list or dict. ``param``: range/unit checks for numbers
    (its ``name`` is only used in messages). ``item``: element kind of a list (float, int, str);
    ``unique``: no repeated elements; ``min_items``: at least this many. ``table``: the
    :class:`Table` a dict must satisfy. ``choices``: allowed strings.
    """

    kind: type = float
    required: bool = False
    doc: str = ""
    param: Param | None = None
    item: type | None = None
    unique: bool = False
    min_items: int = 0
    table: "Table | None" = None
    choices: tuple[str, ...] | None = None

    def check(self, v: Any, key: str, where: str, path: str) -> Any:
        at = f"{_where(where, path)} '{key}'"
        v = _check_kind(v, self.kind, at)
        if self.kind in (float, int):
            return self._number(v, key, at)
        if self.kind is str and self.choices is not None and v not in self.choices:
            raise DataFormatError(f"{at} must be one of {', '.join(self.choices)}{did_you_mean(v, self.choices)}")
        if self.kind is list:
            out = []
            for i, x in enumerate(v):
                if self.item is not None:
                    x = _check_kind(x, self.item, f"{at}[{i}]")
                    if self.item in (float, int):
                        x = self._number(x, key, f"{at}[{i}]")
                out.append(x)
            if len(out) < self.min_items:
                raise DataFormatError(f"{at} needs at least {self.min_items} entries, got {len(out)}")
            if self.unique:
                seen = set()
                for x in out:
                    if x in seen:
                        what = f" {x!r}" if not isinstance(x, str) else ""
                        raise DataFormatError(f"{at} lists an entry{what} twice; entries must be unique")
                    seen.add(x)
            return out
        if self.kind is dict and self.table is not None:
            return self.table.validate(v, where, f"{path}.{key}" if path else key)
        return v

    def _number(self, v: Any, key: str, at: str) -> Any:
        if not math.isfinite(v):
            raise DataFormatError(f"{at} must be a finite number")
        if self.param is not None:
            try:
                return self.param.coerce(v)
            except ParameterError as exc:
                raise DataFormatError(f"{at}: {exc}") from None
        return v


def _check_kind(v: Any, kind: type, at: str) -> Any:
    ok = {
        float: isinstance(v, (int, float)) and not isinstance(v, bool),
        int: isinstance(v, int) and not isinstance(v, bool),
        str: isinstance(v, str),
        bool: isinstance(v, bool),
        list: isinstance(v, (list, tuple)),
        dict: isinstance(v, Mapping),
    }.get(kind, isinstance(v, kind))
    if kind is int and isinstance(v, float) and not isinstance(v, bool) and math.isfinite(v) and v.is_integer():
        return int(v)
    if not ok:
        raise DataFormatError(f"{at} must be {_KIND_NAME.get(kind, kind.__name__)}, got {type_name(v)}")
    return float(v) if kind is float else v


class Table:
    """The keys a table may hold (see the module docstring)."""

    def __init__(self, fields: Mapping[str, Field], allow_extra: bool = False):
        self.fields = dict(fields)
        self.allow_extra = allow_extra

    def validate(self, data: Any, where: str = "", path: str = "") -> dict[str, Any]:
        """Checked values of ``data`` (only the keys present; defaults are the caller's business)."""
        if not isinstance(data, Mapping):
            raise DataFormatError(f"{_where(where, path)} must be a table, got {type_name(data)}")
        if not self.allow_extra:
            check_keys(data, self.fields, where, path)
        out: dict[str, Any] = {}
        for k, f in self.fields.items():
            if k in data:
                out[k] = f.check(data[k], k, where, path)
            elif f.required:
                raise DataFormatError(f"{_where(where, path)} missing key '{k}'" + (f" ({f.doc})" if f.doc else ""))
        if self.allow_extra:
            out.update({k: v for k, v in data.items() if k not in self.fields})
        return out
