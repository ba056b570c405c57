"""The one plotting leaf shared by the command line and the report (library modules never plot).

* :func:`pyplot` returns matplotlib's pyplot on the off-screen Agg backend (selected once, here);
* :func:`savefig` writes a figure atomically (temporary file in the target folder, then rename),
  so a killed run never leaves a corrupt picture under its final name, and closes it;
* :data:`UNIT` and :func:`axis_label` write units the way a paper prints them (µm, not um);
* :func:`fmt_hz` formats every frequency the same way in tables, titles and captions.

Conventions for every figure: each axis has a label with its unit, each line a legend entry,
and the caption beside the figure says what is drawn and with which model.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from probedyn.core.io import atomic_path

#: unit glyphs as printed (µ is U+00B5)
UNIT = {"um": "µm", "nm": "nm", "mm": "mm", "m": "m", "pm": "pm", "A": "Å", "us": "µs", "ms": "ms", "s": "s",
        "Hz": "Hz", "kHz": "kHz", "MHz": "MHz", "nN": "nN", "pN": "pN", "uN": "µN", "N": "N", "N/m": "N/m",
        "V": "V", "kg": "kg", "deg": "°", "rad": "rad", "um/s": "µm/s", "nm/s": "nm/s", "nm/V": "nm/V"}

_PLT: Any = None


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    global _PLT
    if _PLT is None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        plt.rcParams.update({"figure.dpi": 110, "savefig.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
                             "legend.fontsize": "small", "axes.formatter.use_mathtext": True})
        _PLT = plt
    return _PLT


def savefig(fig, path: str | Path) -> Path:
    """Write ``fig`` atomically to ``path`` (format from the suffix) and close it."""
    path = Path(path)
    plt = pyplot()
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=path.suffix.lstrip(".") or "png", bbox_inches="tight")
    finally:
        plt.close(fig)
    return path


def axis_label(quantity: str, unit: str = "") -> str:
    """``"tip deflection [µm]"`` from ``("tip deflection", "um")``."""
    u = UNIT.get(unit, unit)
    return f"{quantity} [{u}]" if u else quantity


def fmt_um(x_m: float, digits: int = 4) -> str:
    """A length given in metres, printed in micrometres: ``fmt_um(5e-6) == "5 µm"``."""
    return f"{x_m * 1e6:.{digits}g} µm"


def fmt_hz(f: float, digits: int = 5) -> str:
    """A frequency with its unit chosen by magnitude, ``digits`` significant: 152.75 kHz."""
    if f is None or not math.isfinite(f):
        return "–"
    a = abs(f)
    for scale, unit in ((1e9, "GHz"), (1e6, "MHz"), (1e3, "kHz")):
        if a >= scale:
            return f"{f / scale:.{digits}g} {unit}"
    return f"{f:.{digits}g} Hz"
