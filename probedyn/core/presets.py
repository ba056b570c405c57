"""The source's parameter tables as named, cited presets: the one place where a table value is
typed.

Every value here is SI and carries the table it comes from. Where the printed table is wrong or
incomplete, the value used is the corrected one and ``notes`` says what changed and why (the
same item number as docs/source-departures.md). Models read their defaults from here
(``preset("table-2.1")["k_x"]``); nothing else in probedyn types a table constant. A value
printed in two tables (Table 4.1 repeats Table 2.1's tip mass, damping and V_s) is a row of
each table; a value printed once is typed once (the mica lattice parameter lives in Table 4.2
only).

=================  ===============================================================  ==========
key                what                                                              source
=================  ===============================================================  ==========
``table-2.1``      FFM cantilever + generalised-bristle friction, mica                Table 2.1
``table-2.2``      FFM cantilever + generalised-bristle friction, VAMWCNT array       Table 2.2
``table-3.1``      duo-bimorph probe (path tracking)                                  Table 3.1
``table-3.2``      piezotube probe (path tracking)                                    Table 3.2
``table-4.1``      nano-pushing probe, sample, tip-sample contact                     Table 4.1
``table-4.2-mica`` mica substrate: lattice parameter and friction levels              Table 4.2
``table-4.2-hopg`` HOPG substrate: lattice parameter and friction levels              Table 4.2
``table-4.3``      two-mass stick-slip model                                          Table 4.3
``table-4.4``      vibrational nano-placing                                           Table 4.4
=================  ===============================================================  ==========
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Iterator, Mapping

from probedyn.core.errors import ParameterError

__all__ = ["Preset", "preset", "preset_names", "PRESETS"]


@dataclass(frozen=True)
class Preset(Mapping[str, Any]):
    """A read-only mapping of parameter name -> SI value with its provenance.

    ``units`` gives the unit of every value; ``notes`` records corrections of the print
    (keyed by parameter name) and assumptions (key ``"*"``)."""

    key: str
    source: str
    title: str
    data: Mapping[str, Any]
    units: Mapping[str, str]
    notes: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        missing = set(self.data) - set(self.units)
        if missing:  # pragma: no cover - a programming error in this file
            raise ValueError(f"preset {self.key}: no unit for {sorted(missing)}")
        object.__setattr__(self, "data", MappingProxyType(dict(self.data)))

    def __getitem__(self, name: str) -> Any:
        try:
            return self.data[name]
        except KeyError:
            raise ParameterError(f"preset {self.key!r} has no parameter {name!r} "
                                 f"(it has: {', '.join(self.data)})") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.data)

    def __len__(self) -> int:
        return len(self.data)

    def pick(self, *names: str, **rename: str) -> dict[str, Any]:
        """A plain dict of some values; ``rename`` maps a new name to a preset name."""
        out = {n: self[n] for n in names}
        out.update({new: self[old] for new, old in rename.items()})
        return out

    def describe(self) -> dict[str, Any]:
        return {"key": self.key, "source": self.source, "title": self.title,
                "values": dict(self.data), "units": dict(self.units), "notes": dict(self.notes)}


def _p(key: str, source: str, title: str, rows: list[tuple[str, Any, str]], notes: dict[str, str] | None = None) -> Preset:
    return Preset(key, source, title, {n: v for n, v, _ in rows}, {n: u for n, _, u in rows}, notes or {})


_FFM_NOTE_FNU = "printed in N; a viscous coefficient is N s/m (as Table 2.2): source-departures item 'Table 2.1, F_nu'"

PRESETS: dict[str, Preset] = {p.key: p for p in [
    _p("table-2.1", "Table 2.1 (section 2.1.5.1)", "FFM of mica: cantilever and generalised-bristle friction", [
        ("m_x", 1.98e-18, "kg"), ("m_y", 1.98e-18, "kg"),
        ("c_x", 7e-9, "N s/m"), ("c_y", 7e-9, "N s/m"),
        ("k_x", 0.2, "N/m"), ("k_y", 0.1, "N/m"),
        ("sigma0_x", 1e4, "N/m"), ("sigma0_y", 1e4, "N/m"),
        ("V_s", 1e-5, "m/s"),
        ("F_v_x", 1e-7, "N s/m"), ("F_v_y", 1e-7, "N s/m"),
        ("F_s_x", 12.95e-9, "N"), ("F_s_y", 12.95e-9, "N"),
        ("F_c_x", 12.45e-9, "N"), ("F_c_y", 12.45e-9, "N"),
        # scan of 2.1.5.1 (text, not the table)
        ("V", 2e-6, "m/s"), ("scan_length", 10e-9, "m"), ("normal_load", 141.75e-9, "N"),
    ], {"F_v_x": _FFM_NOTE_FNU, "F_v_y": _FFM_NOTE_FNU,
        "V": "2000 nm/s, text of 2.1.5.1", "scan_length": "10 nm x 10 nm scan, text of 2.1.5.1",
        "normal_load": "normal load of the mica experiment, text of 2.1.5.1",
        "*": "the mica lattice parameter is Table 4.2's: preset('table-4.2-mica')['a']"}),
    _p("table-2.2", "Table 2.2 (section 2.1.5.2)", "FFM of a VAMWCNT array: cantilever and friction", [
        ("m_x", 2.25e-17, "kg"), ("m_y", 2.25e-17, "kg"),
        ("c_x", 7e-9, "N s/m"), ("c_y", 7e-9, "N s/m"),
        ("k_x", 0.1, "N/m"), ("k_y", 0.05, "N/m"),
        ("sigma0_x", 3e5, "N/m"), ("sigma0_y", 3e5, "N/m"),
        ("V_s", 1e-5, "m/s"),
        ("F_v_x", 1e-7, "N s/m"), ("F_v_y", 1e-7, "N s/m"),
        ("F_s_x", 1.5e-7, "N"), ("F_s_y", 1.5e-7, "N"),
        ("F_c_x", 0.6e-7, "N"), ("F_c_y", 0.6e-7, "N"),
        ("V", 2e-6, "m/s"), ("scan_length", 1e-6, "m"),
    ], {"V": "scan speed not stated in 2.1.5.2: 2 um/s assumed (as 2.1.5.1)",
        "scan_length": "1 um x 1 um scan, text of 2.1.5.2"}),
    _p("table-3.1", "Table 3.1 (section 3.2)", "duo-bimorph probe", [
        ("m_h", 2e-7, "kg"), ("m", 0.5e-7, "kg"), ("L_h", 50e-6, "m"),
        ("k_y2", 0.1, "N/m"), ("k_z2", 10.0, "N/m"), ("L", 300e-6, "m"),
        ("w", 30e-6, "m"), ("w0", 5e-6, "m"), ("rho", 7800.0, "kg/m^3"),
        ("h", 10e-6, "m"), ("d31", -185e-12, "C/N"), ("s11_E", 16.5e-12, "m^2/N"),
    ], {"s11_E": "printed 20.7e-12 m/N is PZT-5H's s33; s11 = 16.5e-12 m^2/N (source-departures 'Tables 3.1/3.2, s11')",
        "d31": "printed +185e-12; d31 of PZT-5H is negative (-274e-12 data sheet; the table's magnitude is kept)",
        "m_h": "about 1700x the geometric mass of a 50 um PZT holder (departure 5): offered beside the geometric mass"}),
    _p("table-3.2", "Table 3.2 (sections 3.3, 3.5)", "piezotube probe", [
        ("m_h", 0.02e-3, "kg"), ("rho", 7800.0, "kg/m^3"), ("mu", 0.1, "N s/m^2"),
        ("R_e", 0.5e-3, "m"), ("R_i", 0.45e-3, "m"), ("s11_E", 16.5e-12, "m^2/N"),
        ("L", 5e-3, "m"), ("d31", -185e-12, "C/N"),
    ], {"R_i": "printed 0.3e-3 m; section 3.5 and Figs 3.21-3.22 use R_i = 0.45 mm, R_e = 0.5 mm",
        "s11_E": "printed 20.7e-12 m/N is s33 (as Table 3.1)",
        "d31": "printed +185e-12; negative for PZT (magnitude kept)"}),
    _p("table-4.1", "Table 4.1 (section 4.1.1)", "nano-pushing: probe, sample and contact", [
        ("sigma0", 1e4, "N/m"), ("m_s", 4e-17, "kg"), ("k_tx", 30.0, "N/m"),
        ("m_tx", 1.98e-18, "kg"), ("m_ty", 1.98e-18, "kg"), ("k_ty", 10.0, "N/m"),
        ("nu_t", 0.33, ""), ("E_t", 200e9, "Pa"), ("R_t", 50e-9, "m"),
        ("nu_s", 0.33, ""), ("E_s", 0.27e9, "Pa"), ("R_s", 160e-9, "m"),
        ("H", 1.452e-20, "J"), ("c_t", 7e-9, "N s/m"), ("V_s", 1e-5, "m/s"),
        ("V", 3e-6, "m/s"),
    ], {"V": "pushing speed 3 um/s, text of 4.1.1"}),
    _p("table-4.2-mica", "Table 4.2", "mica substrate for nano-pushing", [
        ("a", 5.19e-10, "m"), ("F_s", 2.2e-9, "N"), ("F_c", 6e-10, "N"),
    ]),
    _p("table-4.2-hopg", "Table 4.2", "HOPG substrate for nano-pushing", [
        ("a", 2.55e-10, "m"), ("F_s", 1.2e-9, "N"), ("F_c", 5e-10, "N"),
    ]),
    _p("table-4.3", "Table 4.3 (section 4.1.3)", "two-mass stick-slip model", [
        ("m1", 2e-11, "kg"), ("k1", 1.0, "N/m"), ("zeta1", 0.1, ""),
        ("m2", 2e-12, "kg"), ("k2", 1e-5, "N/m"), ("zeta2", 1.0, ""),
        ("a", 1.59e-7, "m"),
    ], {"a": "not given; 159 nm is implied by u0 = 25 <-> 1 eV and the speeds of Fig 4.10 (docs/stickslip.md)"}),
    _p("table-4.4", "Table 4.4 (section 4.2)", "vibrational nano-placing", [
        ("M1", 2e-18, "kg"), ("m", 2e-12, "kg"), ("omega", 2.5e3, "rad/s"),
        ("k", 1.0, "N/m"), ("mu", 0.1, "N s/m^2"), ("lambda", 2.0, ""),
        ("R_t", 50e-9, "m"), ("R_s", 160e-9, "m"), ("D", 5e-6, "m"),
        ("H_sb", 19.95e-20, "J"), ("H_ss", 13.2e-20, "J"), ("F_0", 5e-7, "N"),
        ("zeta0", 3.75e-10, "m"), ("L", 2e-3, "m"), ("M2", 2e-18, "kg"),
    ], {"m": "far lighter than a 2 mm cantilever (departure 35): offered beside the geometric mass",
        "mu": "printed without unit; read as the damping factor of eq 3.2 (N s/m^2)"}),
]}


def preset_names() -> list[str]:
    return list(PRESETS)


def preset(key: str) -> Preset:
    """The preset ``key`` (e.g. ``"table-2.1"``); unknown keys raise with a did-you-mean."""
    k = str(key).strip().lower()
    if k not in PRESETS:
        close = difflib.get_close_matches(k, list(PRESETS), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ParameterError(f"unknown preset {key!r} (known: {', '.join(PRESETS)}){hint}")
    return PRESETS[k]
