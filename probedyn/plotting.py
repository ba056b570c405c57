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


def plain_ticks(fig) -> None:
    """Plain tick labels on every axis of ``fig`` (``1e-06`` instead of mathtext ``10^-6``: the
    mathtext parser dominates the drawing time of figures with many log axes) and no minor-tick
    labels on log axes."""
    pyplot()
    from matplotlib.ticker import FuncFormatter, NullFormatter

    def fmt(v, _pos):
        if v == 0:
            return "0"
        a = abs(v)
        return f"{v:.0e}".replace("e+0", "e").replace("e-0", "e-") if (a >= 1e4 or a < 1e-2) else f"{v:g}"

    for ax in fig.axes:
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale in ("log", "symlog"):
                axis.set_major_formatter(FuncFormatter(fmt))
                axis.set_minor_formatter(NullFormatter())
            else:
                axis.set_major_formatter(FuncFormatter(lambda v, _p: f"{v:g}"))


def category_colormap(colors, codes=None):
    """A colormap of one colour per category: ``(cmap, norm)`` for ``pcolormesh`` of integer
    codes (``codes`` sorted, default ``0 .. len(colors) - 1``; without a norm, ``(cmap, None)``
    maps the codes' range linearly)."""
    pyplot()
    import numpy as np
    from matplotlib.colors import BoundaryNorm, ListedColormap

    cmap = ListedColormap(list(colors))
    if codes is None:
        return cmap, None
    codes = sorted(codes)
    return cmap, BoundaryNorm(np.arange(codes[0] - 0.5, codes[-1] + 1.5), cmap.N)
