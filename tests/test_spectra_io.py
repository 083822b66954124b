"""Reading frequency-bias CSV files: metadata, both response formats, and one-line errors for bad input."""
import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.errors import UserError
from pfmdyn.io.spectra import frequency_group_starts, read_spectra

GOOD = """\
# instrument: MFP-3D
# spring_constant_n_per_m: 4.5
# free-text comments without a colon are ignored
frequency_hz,bias_v,x,y,temperature_k
1000,-1,1.0,0.5,300
1000,1,3.0,-0.5,300

2000,1,2.0,0.0,300
2000,-1,0.0,2.0,300
"""


def write(tmp_path, text, name="data.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_metadata_rows_and_ignores_extra_columns(tmp_path):
    data = read_spectra(write(tmp_path, GOOD))
    assert data.metadata == {"instrument": "MFP-3D", "spring_constant_n_per_m": "4.5"}
    assert data.frequency_hz.tolist() == [1000, 1000, 2000, 2000]
    assert data.bias_v.tolist() == [-1, 1, -1, 1]
    assert data.response.tolist() == [1 + 0.5j, 3 - 0.5j, 2j, 2]
    assert frequency_group_starts(data.frequency_hz).tolist() == [0, 2]


def test_polar_columns_give_the_complex_response(tmp_path):
    text = "frequency_hz,bias_v,amplitude,phase_deg\n1e3,0,2,90\n1e3,1,1,180\n"
    data = read_spectra(write(tmp_path, text))
    np.testing.assert_allclose(data.response, [2j, -1], atol=1e-15)
    assert data.response_columns == ("amplitude", "phase_deg") and data.metadata == {}


def test_byte_order_mark_and_spaces_are_tolerated(tmp_path):
    text = "\ufefffrequency_hz, bias_v, x, y\n1e3, 0, 1, 0\n1e3, 1, 2, 0\n"
    (tmp_path / "bom.csv").write_text(text, encoding="utf-8")
    assert read_spectra(tmp_path / "bom.csv").response.tolist() == [1, 2]


HEADER = "frequency_hz,bias_v,x,y\n"
BAD_INPUTS = {
    "empty file": ("", "line 1: the file is empty"),
    "only comments": ("# a: 1\n# b: 2\n", "line 2: no header line"),
    "misspelled column": ("frequncy_hz,bias_v,x,y\n1,0,1,1\n",
                          "line 1: missing column 'frequency_hz' (found 'frequncy_hz': did you mean 'frequency_hz'?)"),
    "misspelled response column": ("frequency_hz,bias_v,amplitude,phase\n1,0,1,1\n",
                                   "line 1: missing column 'phase_deg' (found 'phase': did you mean 'phase_deg'?)"),
    "missing column": ("frequency_hz,bias_v,x\n1,0,1\n", "line 1: missing column 'y'; expected frequency_hz, bias_v"),
    "response pairs that disagree": ("frequency_hz,bias_v,x,y,amplitude,phase_deg\n1,0,1,0,1,0\n1,1,1,0,1,90\n",
                                     "line 3: x, y and amplitude, phase_deg give different responses"),
    "duplicate column": ("frequency_hz,bias_v,x,y,x\n", "line 1: column 'x' appears more than once"),
    "no data rows": (HEADER, "line 1: header but no data rows"),
    "NaN cell": (HEADER + "1,0,1,1\n1,1,nan,1\n", "line 3: column 'x' is 'nan'; a finite number is required"),
    "empty cell": (HEADER + "1,0,1,1\n1,1,,1\n", "line 3: column 'x' is empty"),
    "non-numeric cell": (HEADER + "1,0,1,1\n1,1,1,1.2.3\n", "line 3: column 'y': '1.2.3' is not a number"),
    "short row": (HEADER + "1,0,1,1\n1,1,1\n", "line 3: expected 4 fields as in the header, found 3"),
    "negative frequency": (HEADER + "-5,0,1,1\n-5,1,1,1\n", "line 2: frequency_hz must be positive, got -5"),
    "negative amplitude": ("frequency_hz,bias_v,amplitude,phase_deg\n1,0,1,0\n1,1,-1,0\n",
                           "line 3: amplitude must be non-negative"),
    "one bias": (HEADER + "1,0,1,1\n1,1,1,1\n2,0,1,1\n3,0,1,1\n3,1,1,1\n",
                 "line 4: only one bias value at frequency 2 Hz"),
    "one bias, repeated": (HEADER + "1,0,1,1\n1,0,2,2\n", "line 3: duplicate row for frequency 1 Hz and bias 0 V (first at line 2)"),
    "duplicate row": ("# k: v\n" + HEADER + "1,0,1,1\n1,1,1,1\n1,0,2,2\n",
                      "line 5: duplicate row for frequency 1 Hz and bias 0 V (first at line 3)"),
    "comment after header": (HEADER + "1,0,1,1\n# late: 1\n1,1,1,1\n", "line 3: comment lines are only allowed before the header"),
    "metadata key twice": ("# k: 1\n# k: 2\n" + HEADER + "1,0,1,1\n1,1,1,1\n", "line 2: metadata key 'k' given twice"),
}


@pytest.mark.parametrize("case", BAD_INPUTS, ids=list(BAD_INPUTS))
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, case):
    text, expected = BAD_INPUTS[case]
    path = write(tmp_path, text)
    out = tmp_path / "out"
    status = cli.main(["deconvolve", str(path), "--surface-potential", "0", "--out", str(out)])
    captured = capsys.readouterr()
    assert status == 2
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"pfmdyn deconvolve: error: {path}, ")
    assert expected in lines[0]
    assert not out.exists()


def test_unreadable_files_are_one_line_errors(tmp_path, capsys):
    missing = tmp_path / "missing.csv"
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    for path, expected in ((missing, "cannot read the file"), (binary, "not a UTF-8 text file")):
        assert cli.main(["deconvolve", str(path), "--surface-potential", "0", "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(path) in err and expected in err
    assert not (tmp_path / "o").exists()


def test_any_row_order_reads_the_same_set_of_rows(tmp_path):
    """Instrument order (one sweep per bias), frequency-grouped and shuffled rows are one table;
    an identical repeated row is kept once."""
    rng = np.random.default_rng(4)
    rows = [(f, v, f * v + 1.0, f - v) for v in (-1.0, 0.5, 2.0) for f in (3e3, 1e3, 2e3, 5e3)]
    orders = {"instrument": rows, "grouped": sorted(rows),
              "shuffled": [rows[i] for i in rng.permutation(len(rows))] + [rows[0]]}
    read = {}
    for name, order in orders.items():
        text = HEADER + "".join(f"{f!r},{v!r},{x!r},{y!r}\n" for f, v, x, y in order)
        read[name] = read_spectra(write(tmp_path, text, f"{name}.csv"))
    for data in read.values():
        assert data.frequency_hz.tolist() == read["grouped"].frequency_hz.tolist()
        assert data.bias_v.tolist() == read["grouped"].bias_v.tolist()
        assert data.response.tolist() == read["grouped"].response.tolist()
    assert read["grouped"].frequency_hz.tolist()[:3] == [1e3, 1e3, 1e3]


SPELLINGS = {
    # header, separator, how the canonical rows (f Hz, V, x, y) are written in that file
    "aliases, kHz": ("Frequency (kHz),Bias (V),Real,Imag", ",", lambda f, v, x, y: (f / 1e3, v, x, y)),
    "suffix units, mV": ("freq_mhz;bias_mv;x_pm;y_pm", ";", lambda f, v, x, y: (f / 1e6, 1e3 * v, x, y)),
    "columns reordered, tab": ("Y\tV\tf\tX", "\t", lambda f, v, x, y: (y, v, f, x)),
    "spaces": ("f_hz  V_dc  re  im", "  ", lambda f, v, x, y: (f, v, x, y)),
    "polar, radians": ("frequency_hz,bias_v,R,Phase (rad)", ",",
                       lambda f, v, x, y: (f, v, abs(x + 1j * y), np.angle(x + 1j * y))),
    "polar, degrees, trailing comma": ("frequency_hz,dc,amp,theta_deg,", ",",
                                       lambda f, v, x, y: (f, v, abs(x + 1j * y), np.degrees(np.angle(x + 1j * y)), "")),
    # what pfmdyn diagram --csv writes: the response per volt of drive
    "per volt, as pfmdyn diagram writes": ("frequency_hz,bias_v,amplitude_m_per_v,phase_deg,piezo_share", ",",
                                           lambda f, v, x, y: (f, v, abs(x + 1j * y),
                                                               np.degrees(np.angle(x + 1j * y)), 0.5)),
}


@pytest.mark.parametrize("case", SPELLINGS, ids=list(SPELLINGS))
def test_column_spellings_units_and_separators_read_the_same(tmp_path, case):
    """What researchers write (aliases, units in the name, any column order and separator,
    Windows line ends, '%' comments) reads as the canonical table, in SI units."""
    header, sep, row = SPELLINGS[case]
    rng = np.random.default_rng(7)
    canonical = [(f, v, x, y) for v in (-1.5, 2.0) for f, x, y in
                 zip([1.1e4, 3.3e4, 2.2e4], rng.standard_normal(3), rng.standard_normal(3))]
    lines = ["% instrument = MFP-3D", header] + [sep.join(repr(float(c)) if c != "" else "" for c in row(*r))
                                                  for r in canonical]
    path = tmp_path / "d.csv"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    data = read_spectra(path)
    expected = sorted(canonical)
    assert data.metadata == {"instrument": "MFP-3D"}
    np.testing.assert_allclose(data.frequency_hz, [r[0] for r in expected], rtol=1e-12)
    np.testing.assert_allclose(data.bias_v, [r[1] for r in expected], rtol=1e-12)
    np.testing.assert_allclose(data.response, [r[2] + 1j * r[3] for r in expected], rtol=1e-9)


def test_decimal_comma_with_semicolons_and_a_phase_without_unit(tmp_path):
    path = write(tmp_path, "frequency_hz;bias_v;x;y\n1000,5;-1;0,25;1e-3\n1000,5;1;2;0\n")
    data = read_spectra(path)
    assert data.frequency_hz.tolist() == [1000.5, 1000.5] and data.response[0] == 0.25 + 1e-3j
    # X, Y, R, theta as a lock-in exports them: x, y are read.
    data = read_spectra(write(tmp_path, "f;V;X;Y;R;Theta (deg)\n10;-1;0;2;2;90\n10;1;1;0;1;0,0001\n"))
    assert data.response.tolist() == [2j, 1] and data.response_columns == ("x", "y")
    # A units line under the header, as spreadsheet exports write it.
    data = read_spectra(write(tmp_path, "freq,bias,amplitude,phase\nkHz,mV,pm,(deg)\n10,-1000,2,90\n10,1000,1,0\n"))
    assert data.frequency_hz.tolist() == [1e4, 1e4] and data.bias_v.tolist() == [-1, 1]
    np.testing.assert_allclose(data.response, [2j, 1], atol=1e-15)
    # Degrees or radians cannot be told from the numbers: a unitless phase is an error.
    with pytest.raises(UserError, match="missing column 'phase_deg'"):
        read_spectra(write(tmp_path, "frequency_hz,bias_v,amplitude,phase\n1,0,1,1\n1,1,1,1\n"))


def test_sweeps_whose_frequencies_differ_by_rounding_share_the_setpoints(tmp_path):
    """An instrument-order file whose second sweep writes f0 + i df computed another way
    (relative differences 1e-13) has two biases at each frequency, not one."""
    f = 1e4 + 37.1 * np.arange(30)
    g = f * (1 + 1e-13 * np.random.default_rng(2).standard_normal(f.size))
    text = HEADER + "".join(f"{float(a)!r},0,1,0\n" for a in f) + "".join(f"{float(b)!r},1,2,0\n" for b in g)
    data = read_spectra(write(tmp_path, text))
    assert len(np.unique(data.frequency_hz)) == 30
    np.testing.assert_allclose(np.unique(data.frequency_hz), f, rtol=1e-12)
    # Interleaved sweeps (half a step apart) are different setpoints.
    text = HEADER + "".join(f"{float(a)!r},0,1,0\n" for a in f) + "".join(f"{float(a) + 18.55!r},1,2,0\n" for a in f)
    assert len(np.unique(read_spectra(write(tmp_path, text), 1).frequency_hz)) == 60


def test_biases_read_back_with_jitter_are_one_bias_per_sweep(tmp_path):
    """Every row its own bias (an instrument's read-back, 1 mV jitter): the sweeps' biases."""
    rng = np.random.default_rng(5)
    f = 1e4 + 50.0 * np.arange(20)
    text = HEADER + "".join(f"{float(a)!r},{v + 1e-3 * rng.standard_normal()!r},{v},1\n"
                            for v in (-2.0, 0.0, 2.0) for a in f)
    data = read_spectra(write(tmp_path, text))
    assert sorted(set(np.round(data.bias_v, 2).tolist())) == [-2.0, 0.0, 2.0] and len(np.unique(data.bias_v)) == 3
    np.testing.assert_allclose(data.response.real, np.round(data.bias_v), atol=0.01)
