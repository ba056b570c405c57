"""fem.render: the off-screen GL check and the mode pictures."""

import numpy as np
import pytest

from probedyn.core.errors import SystemLibraryError
from probedyn.fem import render


def test_missing_gl_library_gives_clear_error(monkeypatch):
    # Hide both back-ends: the check must raise (VTK itself would segfault) and name the packages.
    monkeypatch.setattr(render, "_GL_CANDIDATES", [
        ("EGL", "vtkEGLRenderWindow", ("libEGL-not-here.so.1",)),
        ("OSMesa", "vtkOSOpenGLRenderWindow", ("libOSMesa-not-here.so.8",)),
    ])
    with pytest.raises(SystemLibraryError) as exc:
        render.check_offscreen_gl()
    msg = str(exc.value)
    assert "libosmesa6" in msg and "libegl1" in msg and "\n" not in msg


def test_deformation_scale_by_family():
    # bending: largest displacement = 12 % of the longest side; torsion: 0.65 x section half-size
    pts = np.array([[0, 0, 0], [300, 0, 0], [0, 30, 0], [0, 0, 10]], float)
    u = np.array([[0, 0, 0], [0, 0, 2.0], [0, 0, 0], [0, 0, 0]])
    assert render.deformation_scale(pts, u, "flapwise") * 2.0 == pytest.approx(0.12 * 300)
    assert render.deformation_scale(pts, u, "torsion") * 2.0 == pytest.approx(0.65 * 15)


def _not_blank(path):
    import matplotlib.image as mpimg

    img = mpimg.imread(str(path))[..., :3]
    grey = img.mean(axis=2)
    # a blank (all-background) picture has zero variance; a drawn beam covers > 2 % of the
    # pixels with colours far from the white background
    return grey.var() > 1e-3 and (grey < 0.8).mean() > 0.02


@pytest.mark.render
def test_mode_pngs_and_panel(tmp_path):
    from probedyn.probes import get_probe

    p, _ = get_probe("cantilever")
    values = p.resolve({"elements_through_thickness": 2})
    result = p.build(values).modes(4)
    files = render.render_modes(result, tmp_path, 2)
    panel = render.render_panel(result, tmp_path / "panel.png")
    for f in [*files, panel]:
        assert f.exists() and f.stat().st_size > 10_000
        assert _not_blank(f), f
