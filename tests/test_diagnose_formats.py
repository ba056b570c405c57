"""Measurement files: every malformed or implausible input is a one-line error naming where it is."""

import math
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


@pytest.mark.parametrize("sep", [";", "\t", " ", "   "])
def test_instrument_separators_read_as_the_comma_file(tmp_path, sep):
    """Semicolon (spreadsheet exports with a decimal comma locale), tab and blank-aligned exports read exactly
    as the comma file; the separator is the header's."""
    ref = read_measurement(_write(tmp_path, CSV))
    other = read_measurement(_write(tmp_path, CSV.replace(",", sep)))
    assert list(other.family) == list(ref.family) and list(other.order) == list(ref.order)
    assert list(other.freq) == list(ref.freq)


def test_a_decimal_comma_is_refused_not_reinterpreted(tmp_path):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, CSV.replace(",", ";").replace("6.2e5", "6,2e5")))
    assert "line 2, column 3" in str(e.value) and "cannot read '6,2e5'" in str(e.value)


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
    (SIDE.replace("frequency_rel = 1e-3", "correlation = 0.5"), "unknown key"),  # no recording sequences
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


# ---- issue 16, class 6: nonsense refused with one line, never a verdict ---------------------

FR_SIDE = ('[measurement]\nkind = "friction"\ndata = "f.csv"\n[lever]\nk_x = 1.0\n[noise]\nforce = 5e-12\n'
           '[[scans]]\nid = 0\nspeed = 1e-8\nload = 2e-9\n')


def _friction_csv(force):
    rows = ["scan,position_m,lateral_force_N"]
    x = [i * 5e-11 for i in range(40)]
    rows += [f"0,{xx:.6e},{force(i):.6e}" for i, xx in enumerate(x)]
    return "\n".join(rows) + "\n"


@pytest.mark.parametrize("csv, side, what", [
    # micrometres typed as metres: refused with the SI hint (the 2 um lever typed as "2")
    (CSV, SIDE.replace("thickness = 10e-6", "thickness = 2"), "values are SI metres: 2 um is 2e-06 m"),
    (CSV.replace("6.2e5", "1e308"), SIDE, "above 1e+11 Hz"),
    (CSV.replace("6.2e5", "-6.2e5"), SIDE, "frequency must be positive"),
    (CSV.replace("flapwise,2,", "flapwise,100000,"), SIDE, "order 100000 is beyond"),
    (CSV, SIDE + '[baseline]\nfree = ["thickness", "thickness"]\n', "lists a quantity twice"),
    (CSV, SIDE.replace("[probe]\n", "[probe]\ntip_mass = 1e-12\ntip_position = -0.2\n"), "in [0, 1]"),
    (CSV, SIDE + "[medium]\nnmae = \"water\"\n", "did you mean 'name'"),
    (CSV, SIDE.replace('data = "m.csv"', 'data = "../../../../../../etc/passwd"'), "outside"),
])
def test_class6_modal_inputs_refused(tmp_path, csv, side, what):
    with pytest.raises(DataFormatError) as e:
        read_measurement(_write(tmp_path, csv, side))
    msg = str(e.value)
    assert what in msg and "\n" not in msg and "root:" not in msg


def test_class6_spectrum_frequencies(tmp_path):
    side = ('[measurement]\nkind = "spectrum"\ndata = "m.csv"\n' + PROBE)
    for csv, what in [("frequency_Hz,value\n-1,1\n2,1\n", "frequencies must be positive"),
                      ("frequency_Hz,value\n1,1\n1e308,1\n", r"above 1e\+11 Hz"),
                      ("frequency_Hz,value\n" + "".join(f"{1e3 * (i + 1)},0\n" for i in range(40)), "cannot inform")]:
        with pytest.raises(DataFormatError, match=what):
            read_measurement(_write(tmp_path, csv, side))


@pytest.mark.parametrize("force, what", [(lambda i: 0.0, r"constant \(all zero\)"), (lambda i: 1e-10, "constant")])
def test_class6_flat_friction_cannot_inform(tmp_path, force, what):
    (tmp_path / "f.csv").write_text(_friction_csv(force))
    (tmp_path / "f.toml").write_text(FR_SIDE)
    with pytest.raises(DataFormatError, match=f"cannot inform the fit: .*{what}"):
        read_measurement(tmp_path / "f.toml")


def test_zero_kelvin_declares_an_athermal_friction_record_only(tmp_path):
    """0 K is a friction record's athermal declaration (a simulation's: ``schemes`` PT at temperature 0): no
    activation is offered, neither as a cause nor as a baseline term. A spectrum or a fluid needs a real
    temperature, so a modal record at 0 K is refused."""
    (tmp_path / "f.csv").write_text(_friction_csv(lambda i: 1e-10 * math.sin(0.8 * i)))
    (tmp_path / "f.toml").write_text(FR_SIDE.replace("[noise]", "[medium]\ntemperature = 0\n[noise]"))
    prob = make_problem(tmp_path / "f.toml")
    assert prob.temperature == 0.0 and not prob.declared_terms
    assert "thermal-activation" not in [c.key for c in prob.causes]
    with pytest.raises(DataFormatError, match=r"temperature = 0 K is outside the plausible range \[0.001, 2000\]"):
        read_measurement(_write(tmp_path, side=SIDE + "[medium]\ntemperature = 0\n"))


@pytest.mark.parametrize("noise, what", [
    ('force = 5e-12\nforce_part = "thermal"\n', "force_part must be 'total' .* or 'detector'"),
    ('force_part = "detector"\n', r"force_part says what \[noise\] force covers: state force too"),
])
def test_what_the_stated_friction_noise_covers_is_checked(tmp_path, noise, what):
    """``[noise] force_part`` says whether the stated force noise is the samples' total (default) or the detector's
    alone (the tip's thermal force noise then comes on top at a declared temperature): any other value, or the key
    without a stated noise, is refused with the reason."""
    (tmp_path / "f.csv").write_text(_friction_csv(lambda i: 1e-10 * math.sin(0.8 * i)))
    (tmp_path / "f.toml").write_text(FR_SIDE.replace("force = 5e-12\n", noise))
    with pytest.raises(DataFormatError, match=what):
        read_measurement(tmp_path / "f.toml")
    ok = FR_SIDE.replace("force = 5e-12\n", 'force = 5e-12\nforce_part = "detector"\n')
    (tmp_path / "f.toml").write_text(ok)
    assert read_measurement(tmp_path / "f.toml").noise_part == "detector"


def test_class6_flat_force_curve_cannot_inform(tmp_path):
    (tmp_path / "c.csv").write_text("z_m,force_N\n" + "".join(f"{i * 1e-10:.3e},0\n" for i in range(50)))
    (tmp_path / "c.toml").write_text('[measurement]\nkind = "force"\ndata = "c.csv"\n[lever]\nk = 1.0\n')
    with pytest.raises(DataFormatError, match="cannot inform the fit: the force is constant"):
        read_measurement(tmp_path / "c.toml")


def test_class6_cli_one_line_exit_2(tmp_path, capsys):
    from probedyn.cli import main

    assert main(["diagnose", str(_write(tmp_path, CSV.replace("6.2e5", "1e308")))]) == 2
    err = capsys.readouterr().err
    assert err.startswith("probedyn: error: ") and err.count("\n") == 1
    assert main(["diagnose", "/dev/zero"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def _hertz_curve(sign: float, with_segment: bool) -> str:
    """Approach and retract of a 1 N/m lever on a Hertz sample (contact at z = 0), z written times ``sign``."""
    import numpy as np

    z = np.linspace(-50e-9, 20e-9, 100)
    # lever + Hertz in series: Z(delta) = delta + P(delta)/k, inverted on a fine grid of delta
    dd = np.linspace(0.0, 20e-9, 4001)
    P = 4 / 3 * 1e9 * np.sqrt(20e-9) * dd**1.5
    F = np.where(z > 0, np.interp(z, dd + P / 1.0, P), 0.0)
    zz, FF = np.concatenate([z, z[::-1]]), np.concatenate([F, F[::-1]])
    seg = np.repeat([0, 1], len(z))
    head = "z_m,force_N" + (",segment" if with_segment else "") + "\n"
    rows = (f"{sign * a:.6e},{b:.6e}" + (f",{s}" if with_segment else "") + "\n" for a, b, s in zip(zz, FF, seg))
    return head + "".join(rows)


@pytest.mark.parametrize("with_segment", [True, False])
def test_force_curve_piezo_axis_pointing_away_from_the_sample_is_refused(tmp_path, with_segment):
    side = '[measurement]\nkind = "force"\ndata = "c.csv"\n[lever]\nk = 1.0\n[noise]\nforce = 1e-10\n'
    (tmp_path / "c.toml").write_text(side)
    (tmp_path / "c.csv").write_text(_hertz_curve(+1.0, with_segment))
    m = read_measurement(tmp_path / "c.toml")  # the right sign reads
    assert m.segment.sum() == 100
    (tmp_path / "c.csv").write_text(_hertz_curve(-1.0, with_segment))  # a height column exported as is
    with pytest.raises(DataFormatError, match="z_m must increase towards the sample"):
        read_measurement(tmp_path / "c.toml")


def _with_time(curve: str, times) -> str:
    lines = curve.strip().split("\n")
    return "\n".join([lines[0] + ",time_s"] + [f"{x},{t:.9g}" for x, t in zip(lines[1:], times)]) + "\n"


@pytest.mark.parametrize("clock, expect", [
    ("continuous", None),
    ("turnaround", None),  # the turning sample recorded in both segments, at one instant
    ("restart", None),  # a clock per segment (JPK's segment time)
    ("backwards", "times must increase within a segment"),
    ("nan", r"line 9, column 4 \(time_s\): value 'nan' is not finite"),
])
def test_force_curve_clock(tmp_path, clock, expect):
    import numpy as np

    dt = 1e-3
    t = np.arange(200) * dt
    if clock == "turnaround":
        t[100:] -= dt
    elif clock == "restart":
        t[100:] = np.arange(100) * dt
    elif clock == "backwards":
        t[150], t[151] = t[151], t[150]
    elif clock == "nan":
        t[7] = np.nan
    (tmp_path / "c.toml").write_text('[measurement]\nkind = "force"\ndata = "c.csv"\n[lever]\nk = 1.0\n'
                                     '[noise]\nforce = 1e-10\n')
    (tmp_path / "c.csv").write_text(_with_time(_hertz_curve(+1.0, True), t))
    if expect:
        with pytest.raises(DataFormatError, match=expect):
            read_measurement(tmp_path / "c.toml")
        return
    m = read_measurement(tmp_path / "c.toml")
    # one clock: non-decreasing through the file, strictly increasing within each segment, the retract's steps kept
    assert np.all(np.diff(m.time) >= 0) and np.all(np.diff(m.time[:100]) > 0) and np.all(np.diff(m.time[100:]) > 0)
    assert np.allclose(np.diff(m.time[100:]), dt)
    assert m.time[100] - m.time[99] == pytest.approx({"continuous": dt, "turnaround": 0.0, "restart": dt}[clock])
