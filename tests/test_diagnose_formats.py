"""Measurement files: every malformed or implausible input is a one-line error naming where it is."""

from pathlib import Path

import pytest

from probedyn.core.errors import DataFormatError
from probedyn.diagnose.formats import read_measurement
from probedyn.diagnose.problems import make_problem

EX = Path(__file__).resolve().parents[1] / "examples" / "measurements"
PROBE = '[probe]\nname = "cantilever"\nlength = 150e-6\nwidth = 20e-6\nthickness = 10e-6\nelements_through_thickness = 1\n'
SIDE = '[measurement]\nkind = "modal"\ndata = "m.csv"\n' + PROBE + '[noise]\nfrequency_rel = 1e-3\n'
# a lever of this size has f1 = 0.62 MHz (FEM)
CSV = "family,order,frequency_Hz\nflapwise,1,6.2e5\nflapwise,2,3.8e6\nlateral,1,1.2e6\n"


def _write(tmp_path, csv=CSV, side=SIDE):
    (tmp_path / "m.csv").write_text(csv)
    (tmp_path / "m.toml").write_text(side)
    return tmp_path / "m.toml"


@pytest.mark.parametrize("name", sorted(p.name for p in EX.glob("*.toml")))
def test_examples_parse(name):
    m = read_measurement(EX / name)
    assert m.kind in ("modal", "friction", "spectrum", "timeseries", "force")


@pytest.mark.parametrize("csv, where, what", [
    ("family,order,frequency_Hz\nflapwise,1,abc\n", "line 2, column 3", "cannot read 'abc'"),
    ("family,order,frequency_Hz\nflapwise,1,100\nflapwse,2,600\n", "line 3, column 1", "did you mean 'flapwise'"),
    ("family,order,frequency_Hz\nflapwise,1,-5\n", "line 2, column 3", "frequency must be positive"),
    ("family,order,frequency_Hz\nflapwise,1.5,100\n", "line 2, column 2", "integer"),
    ("family,order,frequency_Hz\nflapwise,1,100\nflap,1,101\n", "line 3, column 2", "appears twice"),
    ("family,order,frequency_Hz,Q,Q_sigma\nflapwise,1,100,50,0\n", "line 2, column 5", "Q_sigma must be positive"),
    ("family,order,frequency_Hz,Q\nflapwise,1,100,0.1\n", "line 2, column 4", "not a quality factor"),
    ("family,order,frequency_Hz,lenght_m\nflapwise,1,100,1\n", "line 1, column 4", "did you mean 'length_m'"),
    ("family,order,frequency_Hz\nflapwise,1,100,7\n", "line 2, column 4", "expected 3 fields"),
])
def test_csv_errors_name_line_and_column(tmp_path, csv, where, what):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, csv))
    msg = str(e.value)
    assert where in msg and what in msg and "\n" not in msg


@pytest.mark.parametrize("side, what", [
    (SIDE.replace("thickness = 10e-6", "thickness = 2"), "outside the plausible range"),  # 2 m thick
    (SIDE.replace("thickness = 10e-6", "thicknes = 10e-6"), "did you mean 'thickness'"),
    (SIDE.replace("[noise]", "[nosie]"), "did you mean 'noise'"),
    (SIDE.replace("frequency_rel = 1e-3", "frequency_rell = 1e-3"), "did you mean 'frequency_rel'"),
    (SIDE.replace("frequency_rel = 1e-3", "frequency_rel = 0"), "must be positive"),
    (SIDE + "[medium]\nname = \"watter\"\n", "did you mean 'water'"),
    (SIDE.replace('kind = "modal"', 'kind = "modall"'), "did you mean 'modal'"),
    (SIDE.replace("[probe]\n", "[probe]\ntip_mass = 1e-12\ntip_position = 1.5\n"), "tip_position"),
    (SIDE + "[baseline]\nfree = [\"thicknes\"]\n", "did you mean 'thickness'"),
    (SIDE.replace('name = "cantilever"', 'name = "cantileverr"'), "did you mean 'cantilever'"),
])
def test_sidecar_errors_are_one_line(tmp_path, side, what):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, side=side))
    assert what in str(e.value) and "\n" not in str(e.value)


def test_khz_typed_as_hz(tmp_path):
    csv = "family,order,frequency_Hz\nflapwise,1,620\nflapwise,2,3800\n"
    with pytest.raises(DataFormatError, match=r"kHz typed as Hz"):
        make_problem(_write(tmp_path, csv))


def test_fit_the_data_cannot_inform(tmp_path):
    """E and rho enter frequencies only as E/rho: calibrating both is refused, naming them."""
    from probedyn.diagnose.engine import diagnose

    side = SIDE + '[baseline]\nfree = ["modulus", "density"]\n'
    with pytest.raises(DataFormatError, match=r"cannot inform the baseline parameters cal_modulus, cal_density"):
        diagnose(make_problem(_write(tmp_path, side=side)))
