"""Off-screen rendering of mode shapes (pyvista/VTK)."""

import numpy as np
import pytest

from probedyn.errors import SystemLibraryError
from probedyn.fem import render
from probedyn.probes import get_probe


@pytest.mark.render
def test_panel_png_is_a_real_picture(tmp_path):
    p, _ = get_probe("cantilever")
    values = p.resolve({"elements_through_thickness": 1})
    result = p.build(values).modes(4)
    path = render.render_panel(result, tmp_path / "panel.png")
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.shape[0] > 500 and img.shape[1] > 500
    # not blank: the coloured beam covers a visible share of the white background
    non_white = np.mean(np.any(img[..., :3] < 0.9, axis=-1))
    assert 0.005 < non_white < 0.9
    assert img[..., :3].std() > 0.02


def test_missing_gl_library_is_a_clear_error(monkeypatch):
    # VTK segfaults without OpenGL: the check must raise before pyvista is imported
    monkeypatch.setattr(render, "_loadable", lambda sonames: False)
    with pytest.raises(SystemLibraryError, match="libosmesa6|libegl1"):
        render.check_offscreen_gl()
