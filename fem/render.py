"""Off-screen pictures of mode shapes (pyvista/VTK), for reports and papers (source Figs 3.15–3.16).

* :func:`check_offscreen_gl` proves that an off-screen OpenGL context can be created *before*
  VTK is used in this process: a child process (``sys.executable``, time-limited) imports VTK,
  opens an off-screen render window of each candidate back-end (EGL, then OSMesa) and renders
  one frame. A library that loads but cannot make a context (libEGL without a working vendor
  driver, no OSMesa) crashes the child, not probedyn; VTK in this process is then pinned to
  the back-end that worked (``VTK_DEFAULT_OPENGL_WINDOW``). None working gives
  :class:`probedyn.core.errors.SystemLibraryError` naming the Debian packages ``libosmesa6`` /
  ``libegl1``. ``PROBEDYN_GL_BACKENDS=EGL`` (or ``OSMesa``, comma-separated) restricts the
  candidates.
* :func:`render_mode` writes one PNG per mode: the deformed shape coloured by the displacement
  magnitude (normalised to its maximum: a mode's amplitude is arbitrary), the undeformed
  outline in grey, a scalar bar and the title "mode n — family — f".
* :func:`render_panel` draws any four (or fewer) modes of any
  :class:`~probedyn.fem.modes.ModalResult` on a 2x2 grid (the smart-probe figures reuse it).

The deformation scale is chosen per mode so that the picture is readable: bending and axial
modes are scaled so the largest displacement is ``bend_fraction`` of the longest dimension of
the body; torsion so the cross-section turns by about 33 degrees (largest displacement ~0.65 of
the largest section half-size). Coordinates are drawn in micrometres.
"""

from __future__ import annotations

import ctypes
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from probedyn.core.errors import ParameterError, SystemLibraryError
from probedyn.core.io import atomic_path

#: Off-screen GL back-ends VTK can use without a display: (name, VTK window class, sonames).
_GL_CANDIDATES: list[tuple[str, str, tuple[str, ...]]] = [
    ("EGL", "vtkEGLRenderWindow", ("libEGL.so.1", "libEGL.so")),
    ("OSMesa", "vtkOSOpenGLRenderWindow", ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")),
]

_GL_BACKEND: str | None = None
#: seconds the child process may take to import VTK and render one frame
GL_CHECK_TIMEOUT_S = 90.0

# Run in a child process: open an off-screen window of the class named by
# VTK_DEFAULT_OPENGL_WINDOW, render one frame, report the class VTK really used.
_GL_PROBE = r"""
import sys
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (registers the OpenGL window classes)
from vtkmodules.vtkRenderingCore import vtkRenderWindow, vtkRenderer
w = vtkRenderWindow()
w.SetOffScreenRendering(1)
w.SetSize(8, 8)
w.AddRenderer(vtkRenderer())
w.Render()
ok = bool(w.SupportsOpenGL()) if hasattr(w, "SupportsOpenGL") else True
sys.stdout.write("PROBEDYN-GL %s %d\n" % (w.GetClassName(), ok))
sys.stdout.flush()
w.Finalize()
"""


def _loadable(sonames: Sequence[str]) -> bool:
    for so in sonames:
        try:
            ctypes.CDLL(so)
            return True
        except OSError:
            continue
    return False


def _probe_backend(window_class: str) -> tuple[str | None, str]:
    """Try ``window_class`` in a child process: (class VTK used, or None; reason if it failed)."""
    import signal
    import subprocess
    import sys

    env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW=window_class)
    try:
        cp = subprocess.run([sys.executable, "-c", _GL_PROBE], env=env, capture_output=True, text=True,
                            timeout=GL_CHECK_TIMEOUT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return None, f"no frame within {GL_CHECK_TIMEOUT_S:g} s"
    except OSError as exc:
        return None, f"cannot start a check process ({exc.strerror})"
    if cp.returncode < 0:
        try:
            name = signal.Signals(-cp.returncode).name
        except ValueError:
            name = f"signal {-cp.returncode}"
        return None, f"creating a context crashed ({name})"
    for line in cp.stdout.splitlines():
        if line.startswith("PROBEDYN-GL "):
            _, used, ok = line.split()
            if ok == "1":
                return used, ""
            return None, f"{used} has no usable OpenGL"
    return None, f"check process failed (exit {cp.returncode})"


def check_offscreen_gl() -> str:
    """Return the off-screen GL back-end proven to work ("EGL" or "OSMesa"); raise if there is none.

    The proof runs in a child process (see the module docstring), once per process. With a
    display (``$DISPLAY`` set) VTK's own choice is kept and only checked.
    """
    global _GL_BACKEND
    if _GL_BACKEND is not None:
        return _GL_BACKEND
    wanted = {w.strip().lower() for w in os.environ.get("PROBEDYN_GL_BACKENDS", "").split(",") if w.strip()}
    candidates = [c for c in _GL_CANDIDATES if not wanted or c[0].lower() in wanted]
    reasons = []
    by_class = {cls: name for name, cls, _ in _GL_CANDIDATES}
    for name, window_class, sonames in candidates:
        if not _loadable(sonames):
            reasons.append(f"{name}: library not found")
            continue
        used, why = _probe_backend(window_class)
        if used is None:
            reasons.append(f"{name}: {why}")
            continue
        if used not in by_class and os.environ.get("DISPLAY"):
            _GL_BACKEND = used  # a display's own window class (X): fine
            return used
        if by_class.get(used) not in [c[0] for c in candidates]:
            reasons.append(f"{name}: VTK fell back to {used}")
            continue
        if not os.environ.get("DISPLAY"):
            os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = used
        _GL_BACKEND = by_class[used]
        return _GL_BACKEND
    detail = "; ".join(reasons) if reasons else "no back-end selected by PROBEDYN_GL_BACKENDS"
    raise SystemLibraryError(
        f"no working off-screen OpenGL for rendering ({detail}); install the Debian package libosmesa6 "
        "(or a working libegl1 driver, libegl-mesa0); ./dev setup does it"
    )


def _pyvista():
    check_offscreen_gl()
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


# --------------------------------------------------------------------------------------------
# Fields
# --------------------------------------------------------------------------------------------


def mode_vertex_field(result: Any, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (N, 3) [m], tets (E, 4), displacement (N, 3)) of mode ``index`` at the mesh vertices.

    Uses ``result.model.vertex_displacement(shape)`` when the model offers it (the P2 field at
    the corner nodes of the straight-sided tets); otherwise the vertex DOFs of the basis.
    """
    model = result.model
    mesh = model.bundle.mesh
    shape = np.asarray(result.modes[index].shape)
    if hasattr(model, "vertex_displacement"):
        u = np.asarray(model.vertex_displacement(shape))
    else:
        u = shape[model.basis.nodal_dofs].T
    nv = mesh.t.max() + 1  # vertices (a curved MeshHex2 also stores its higher-order geometry nodes)
    u = u[:nv].reshape(nv, 3) if u.shape != (nv, 3) else u
    return mesh.p[:, :nv].T.copy(), mesh.t.T.copy(), u


#: VTK hexahedron vertex order = scikit-fem MeshHex order permuted (skfem.io.meshio.HEX_MAPPING)
_VTK_HEX = (0, 3, 6, 2, 1, 5, 7, 4)


def _grid(pv, points: np.ndarray, cells_in: np.ndarray):
    """Linear tetrahedra (E, 4) or hexahedra (E, 8, scikit-fem vertex order) as a pyvista grid."""
    k = cells_in.shape[1]
    conn = cells_in[:, list(_VTK_HEX)] if k == 8 else cells_in
    cells = np.hstack([np.full((conn.shape[0], 1), k, dtype=np.int64), conn.astype(np.int64)]).ravel()
    ctype = pv.CellType.HEXAHEDRON if k == 8 else pv.CellType.TETRA
    celltypes = np.full(conn.shape[0], ctype, dtype=np.uint8)
    return pv.UnstructuredGrid(cells, celltypes, points)


def deformation_scale(points: np.ndarray, u: np.ndarray, family: str, bend_fraction: float = 0.12) -> float:
    """Factor applied to ``u`` for display (see module docstring)."""
    umax = float(np.linalg.norm(u, axis=1).max())
    if umax == 0.0:
        return 0.0
    ext = np.ptp(points, axis=0)
    if family == "torsion":
        # the section half-size perpendicular to the axis of the body
        axis = int(np.argmax(ext))
        half = 0.5 * max(ext[i] for i in range(3) if i != axis)
        return 0.65 * half / umax
    return bend_fraction * ext.max() / umax


# --------------------------------------------------------------------------------------------
# Drawing
# --------------------------------------------------------------------------------------------

_UM = 1e6  # draw in micrometres


def _title(result: Any, i: int) -> str:
    m = result.modes[i]
    f = float(m.frequency_hz)
    if f >= 1e6:
        fs = f"{f / 1e6:.4g} MHz"
    elif f >= 1e3:
        fs = f"{f / 1e3:.4g} kHz"
    else:
        fs = f"{f:.4g} Hz"
    return f"Mode {int(m.index)}: {m.family}, {fs}"  # Mode.index is 1-based


#: Viewing direction (from the scene towards the camera) per family: a side view shows
#: flapwise (z) bending, a top view lateral (y) bending, an oblique view from the free end
#: shows the twisted end section of a torsion mode.
_VIEW = {
    "flapwise": (0.30, -1.0, 0.32),
    "axial": (0.30, -1.0, 0.32),
    "lateral": (0.30, -0.40, 1.0),
    "torsion": (1.0, -0.55, 0.42),
    "other": (0.55, -1.0, 0.62),
}


def _camera(pl, points_um: np.ndarray, family: str, zoom: float) -> None:
    """Point the camera along the family's view direction and fit the deformed + undeformed body."""
    lo, hi = points_um.min(axis=0), points_um.max(axis=0)
    c = 0.5 * (lo + hi)
    d = np.asarray(_VIEW.get(family, _VIEW["other"]), dtype=float)
    d /= np.linalg.norm(d)
    up = (0.0, 0.0, 1.0) if abs(d[2]) < 0.9 else (0.0, 1.0, 0.0)
    if family == "lateral":
        up = (0.0, 1.0, 0.0)
    pl.camera_position = [tuple(c + 3.0 * np.ptp(points_um, axis=0).max() * d), tuple(c), up]
    pl.reset_camera(bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
    pl.camera.zoom(zoom)


def _draw(pl, pv, result: Any, i: int, title: str | None, font_size: int, bar_style: str = "horizontal",
          zoom: float = 1.6) -> None:
    points, tets, u = mode_vertex_field(result, i)
    fam = result.modes[i].family
    s = deformation_scale(points, u, fam)
    grid = _grid(pv, points * _UM, tets)
    surf = grid.extract_surface(algorithm="dataset_surface")
    mag = np.linalg.norm(u, axis=1)
    mag = mag / (mag.max() or 1.0)
    ids = surf.point_data["vtkOriginalPointIds"]
    surf.point_data["|u| / max"] = mag[ids]
    outline = surf.extract_feature_edges(feature_angle=30, boundary_edges=True, manifold_edges=False,
                                         non_manifold_edges=False)
    deformed = surf.copy()
    deformed.points = surf.points + s * _UM * u[ids]
    pl.add_mesh(outline, color="#555555", line_width=1.5)
    if bar_style == "vertical":  # small, one per panel (scalar-bar titles must be unique per plotter)
        sbar = dict(title="disp/max" + " " * i, n_labels=2, fmt="%.0f", vertical=True, height=0.45, width=0.035,
                    position_x=0.93, position_y=0.12, title_font_size=font_size - 2,
                    label_font_size=font_size - 2, color="black")
    else:
        sbar = dict(title="displacement magnitude / maximum", n_labels=2, fmt="%.1f", vertical=False,
                    height=0.06, width=0.5, position_x=0.25, position_y=0.04, title_font_size=font_size - 2,
                    label_font_size=font_size - 4, color="black")
    bar = bar_style != "none"
    pl.add_mesh(deformed, scalars="|u| / max", cmap="viridis", clim=(0.0, 1.0), smooth_shading=True,
                split_sharp_edges=True, show_scalar_bar=bar, scalar_bar_args=sbar if bar else None,
                specular=0.2)
    pl.add_text(title if title is not None else _title(result, i), position="upper_edge", font_size=font_size,
                color="black")
    _camera(pl, np.vstack([surf.points, deformed.points]), fam, zoom)
    pl.add_axes(line_width=3, labels_off=False, color="black", viewport=(0.0, 0.0, 0.14, 0.22))


def render_mode(result: Any, index: int, path: str | Path, window_size: tuple[int, int] = (1400, 700),
                title: str | None = None) -> Path:
    """Write a PNG of mode ``index`` (0-based) of ``result``; return the path."""
    if not 0 <= index < len(result.modes):
        raise ParameterError(f"mode {index} not in the result (it has {len(result.modes)} modes)")
    pv = _pyvista()
    pl = pv.Plotter(off_screen=True, window_size=list(window_size))
    pl.set_background("white")
    _draw(pl, pv, result, index, title, 16, "horizontal")
    pl.enable_anti_aliasing("ssaa")
    with atomic_path(path) as tmp:
        pl.screenshot(str(tmp))
    pl.close()
    return Path(path)


def render_modes(result: Any, outdir: str | Path, n: int | None = None, prefix: str = "mode") -> list[Path]:
    """One PNG per mode for the first ``n`` modes: ``outdir/{prefix}_{k}.png`` (k from 1)."""
    n = len(result.modes) if n is None else min(n, len(result.modes))
    return [render_mode(result, i, Path(outdir) / f"{prefix}_{i + 1}.png") for i in range(n)]


def render_panel(result: Any, path: str | Path, modes: Sequence[int] = (0, 1, 2, 3),
                 window_size: tuple[int, int] = (1800, 1000), titles: Sequence[str] | None = None) -> Path:
    """A 2x2 panel (fewer if fewer modes) of the given modes (0-based) of any ModalResult."""
    modes = [m for m in modes if 0 <= m < len(result.modes)][:4]
    if not modes:
        raise ParameterError("render_panel: no valid mode index")
    pv = _pyvista()
    shape = (1, len(modes)) if len(modes) <= 2 else (2, 2)
    pl = pv.Plotter(off_screen=True, window_size=list(window_size), shape=shape, border=False)
    for k, m in enumerate(modes):
        pl.subplot(k // shape[1], k % shape[1])
        pl.set_background("white")
        _draw(pl, pv, result, m, titles[k] if titles else None, 13, "vertical", zoom=1.45)
    pl.enable_anti_aliasing("ssaa")
    with atomic_path(path) as tmp:
        pl.screenshot(str(tmp))
    pl.close()
    return Path(path)
