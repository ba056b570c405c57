"""Measurement formats: the examples parse, malformed files name file, line and column."""

import re
from pathlib import Path

import numpy as np
import pytest

from probedyn.diagnose.formats import read_measurement
from probedyn.diagnose.spectrum import fit_peaks, sho_psd
from probedyn.core.errors import DataFormatError

EX = Path(__file__).resolve().parents[1] / "examples" / "measurements"
SIDE = """[measurement]
kind = "modal"
data = "m.csv"
[probe]
length = 200e-6
width = 30e-6
thickness = 2e-6
E = 169e9
rho = 2330.0
"""


@pytest.mark.parametrize("name", sorted(p.name for p in EX.glob("*.toml")))
def test_examples_parse(name):
    m = read_measurement(EX / name)
    assert m.kind in ("modal", "friction", "spectrum", "timeseries")


def _write(tmp_path, csv, side=SIDE):
    (tmp_path / "m.csv").write_text(csv)
    (tmp_path / "m.toml").write_text(side)
    return tmp_path / "m.toml"


@pytest.mark.parametrize("csv, line, col, what", [
    ("family,order,frequency_Hz\nflap,1,abc\n", 2, 3, "cannot read 'abc'"),
    ("family,order,frequency_Hz\nflap,1,100\nflop,2,600\n", 3, 1, "not one of"),
    ("family,order,frequency_Hz\nflap,1.5,100\n", 2, 2, "integer"),
    ("family,order,frequency_Hz\nflap,1,100,5\n", 2, 4, "expected 3 fields"),
    ("family,order,freq\nflap,1,100\n", 1, 3, "unknown column"),
    ("# comment\nfamily,order,frequency_Hz\nflap,1,-5\n", 3, 3, "positive"),
])
def test_malformed_modal_csv_names_file_line_column(tmp_path, csv, line, col, what):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, csv))
    msg = str(e.value)
    assert "m.csv" in msg and f"line {line}" in msg and f"column {col}" in msg and what in msg


def test_malformed_toml_names_line_and_column(tmp_path):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, "family,order,frequency_Hz\nflap,1,100\n", SIDE + "rho = = 3\n"))
    assert re.search(r"m\.toml.*line \d+, column \d+", str(e.value))


def test_unit_slip_rejected(tmp_path):
    with pytest.raises(DataFormatError, match="micrometres"):
        read_measurement(_write(tmp_path, "family,order,frequency_Hz\nflap,1,100\n", SIDE.replace("200e-6", "200")))


def test_friction_scan_without_metadata(tmp_path):
    (tmp_path / "f.csv").write_text("scan,position_m,lateral_force_N\n" + "".join(f"3,{i}e-10,1e-10\n" for i in range(10)))
    (tmp_path / "f.toml").write_text('[measurement]\nkind = "friction"\ndata = "f.csv"\n[probe]\nk_x = 1.0\n[[scans]]\nid = 0\nspeed = 1e-6\n')
    with pytest.raises(DataFormatError, match=r"f\.csv, line 2, column 1 \(scan\): scan id 3 has no"):
        read_measurement(tmp_path / "f.toml")


def test_sho_peak_fit_recovers_f0_and_Q():
    # synthetic averaged thermal PSD: SHO + floor with chi^2(2n)/2n scatter (n = 32 averages)
    rng = np.random.default_rng(1)
    f = np.arange(60000.0, 80000.0, 0.25)
    true = sho_psd(f, 70561.3, 2.9e4, 6e-14, 2e-9)
    psd = true * rng.chisquare(64, f.size) / 64
    (p,) = fit_peaks(f, psd)
    # standard errors from the fit; 5 sigma (plus 1e-6 relative) covers the estimate
    assert abs(p["f0_Hz"] - 70561.3) < 5 * p["f0_sigma_Hz"] + 1e-6 * 70561.3
    assert abs(p["Q"] / 2.9e4 - 1) < 5 * p["Q_sigma"] / p["Q"]
    assert p["Q_sigma"] / p["Q"] < 0.1
