"""Instrument readers on the real files (skipped when absent) and on bad files made here.

Expected values are the ones listed in shared/realdata/README.md (copied from the files'
headers by hand, not by these readers).
"""
import importlib.util
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.errors import UserError
from pfmdyn.analysis.thermal import instrument_resonances
from pfmdyn.io.instruments import read_instrument

ROOT = Path(__file__).resolve().parents[1]
_CANDIDATES = [Path(os.environ.get("PFMDYN_REALDATA", "/nonexistent")), ROOT.parent / "shared" / "realdata",
               ROOT.parents[1] / "shared" / "realdata"]
REALDATA = next((p for p in _CANDIDATES if p.is_dir()), _CANDIDATES[1])
ASYLUM = REALDATA / "asylum_pfm_images"

# README table 3: k, ThermalFrequency, ThermalQ, TuneFreqResult, TuneQResult, DriveFrequency, L, W.
ASYLUM_TABLE = {
    "IgorIBWReader_ImageStack_BTFO_DSO.ibw": (0.46538, 72969, 138.63, 368990, 213.46, 380740, 2.4e-4, 3e-5),
    "IgorIBWReader_P0089OP0027.ibw": (8.3589, 59162, 134.21, 349890, 166.43, 71000, 2.4e-4, 3e-5),
    "PTO_Funakubo0001.h5": (1.1747, 59758, 138, 371710, 312.72, 369110, 2.4e-4, 3e-5),
    "PMN28Pt0000.h5": (1, 74369, 20, 348400, 218.47, 357810, None, None),
}
FIELD_ORDER = ("spring_constant", "free_resonance", "free_quality_factor", "contact_resonance",
               "contact_quality_factor", "drive_frequency", "length", "width")
# README table 2: header Q factor and peak (or f_res) frequency of each drive sweep.
SWEEPS = {
    "20180628_SBC_3_C_4_B.txt": (3.034, 81780.70), "20180628_SBC_3_C_4_A.txt": (2.991, 81246.50),
    "20170712_RSN_3_B.txt": (3.177, 71789.15), "20170712_RSN_3_A.txt": (3.183, 71370.42),
    "20190110_ShowCase_PLL_B.txt": (2.630, 50965.09), "20190110_ShowCase_PLL_A.txt": (2.630, 50965.09),
    "20190510_LC_05_B001.dat": (6.85, 88544.3524), "20190510_LC_05_A001.dat": (5.50, 88185.4831),
}
THERMAL = REALDATA / "nsfopen_thermal_ACL-A" / "thermal.nid"


def real(path):
    if not path.is_file():
        pytest.skip(f"{path} not present")
    return path


@pytest.mark.parametrize("name", sorted(ASYLUM_TABLE))
def test_asylum_metadata_matches_the_readme(name):
    record = read_instrument(real(ASYLUM / name))
    assert record.kind == "image"
    for field, expected in zip(FIELD_ORDER, ASYLUM_TABLE[name]):
        if expected is None:
            assert field in record.missing
        else:
            assert record.fields[field] == pytest.approx(expected, rel=1e-9), field
    assert "tip_height" in record.missing       # Asylum records no tip height
    units = {c.name: c.unit for c in record.channels}
    assert units["HeightRetrace"] == "m" and units["AmplitudeRetrace"] == "m" and units["PhaseRetrace"] == "deg"
    assert all(c.shape == (256, 256) for c in record.channels)
    assert len(record.channels) == (5 if "P0089" in name else 4)


def test_thermal_tune_header_spectrum_and_fitted_mode():
    record = read_instrument(real(THERMAL))
    assert record.kind == "thermal spectrum"
    # the conditions calibrate and discrepancy take from the header, shown by inspect (they were not)
    assert "measured in air at 40 C (313.15 K)" in record.notes
    assert record.fields == pytest.approx({"spring_constant": 27.13, "free_resonance": 179.8e3,
                                           "free_quality_factor": 442.0})
    freq, asd, unit = record.spectrum
    assert unit == "m/sqrt(Hz)" and len(freq) == 8369 and freq[-1] == pytest.approx(319214)
    peak = np.argmax(np.where(freq > 1e4, asd, 0))
    assert freq[peak] == pytest.approx(179.79e3, abs=40) and asd[peak] == pytest.approx(777e-15, rel=2e-3)
    data = instrument_resonances(THERMAL, {"length": 225e-6, "width": 40e-6, "tip_height": 12e-6})
    assert data.mode.tolist() == [1] and data.condition.tolist() == ["free"]
    assert data.frequency_hz[0] == pytest.approx(179.8e3, rel=2e-3)
    assert data.quality_factor[0] == pytest.approx(442, rel=0.15) and data.metadata.spring_constant == 27.13


@pytest.mark.parametrize("name", sorted(SWEEPS))
def test_drive_sweeps_header_fit(name):
    record = read_instrument(real(REALDATA / "pyimd_cantilever_sweeps" / name))
    q, f = SWEEPS[name]
    assert record.kind == "spectrum"
    assert record.fields["free_quality_factor"] == pytest.approx(q, abs=6e-4)
    # a Cytomass header's peak-amplitude frequency is read as the amplitude peak it is, not as the resonance
    assert record.fields["amplitude_peak" if name.endswith(".txt") else "free_resonance"] == pytest.approx(f, abs=6e-3)
    assert name.endswith(".dat") or "free_resonance" not in record.fields
    assert [c.unit for c in record.channels][1] == "deg"
    # the amplitude in the unit the sweep reader of discrepancy gives: Nanonis's 'm' through its default
    # input calibration of 1 m/V are the detector's volts (README table 2)
    assert [c.unit for c in record.channels][0] == "V"
    assert any("input calibration is 1E+0 m/V" in n for n in record.notes) == name.endswith(".dat")
    assert any("'Peak amplitude frequency'" in n for n in record.notes) == name.endswith(".txt")


def test_image_gives_free_and_contact_mode_with_q_and_asks_for_tip_height():
    path = real(ASYLUM / "IgorIBWReader_P0089OP0027.ibw")
    with pytest.raises(UserError, match="tip height not in IgorIBWReader_P0089OP0027.ibw$"):
        instrument_resonances(path)
    data = instrument_resonances(path, {"tip_height": 12e-6})
    assert data.condition.tolist() == ["free", "contact"] and data.mode.tolist() == [1, 1]
    assert data.frequency_hz.tolist() == [59162, 349890] and data.quality_factor.tolist() == [134.21, 166.43]
    assert (data.metadata.spring_constant, data.metadata.length, data.metadata.tip_height) == (8.3589, 2.4e-4, 12e-6)
    assert instrument_resonances(path, {"tip_height": 1e-5, "spring_constant": 3.0}).metadata.spring_constant == 3.0


def test_inspect_exits_0_on_every_real_file_and_writes_numbers(tmp_path):
    files = sorted(p for p in REALDATA.glob("*/*") if p.suffix in (".ibw", ".h5", ".nid", ".txt", ".dat", ".csv"))
    if not files:
        pytest.skip("shared/realdata not present")
    for path in files:
        out = tmp_path / (path.name + ".json")
        assert cli.main(["inspect", str(path), "--json", str(out)]) == 0, path
        doc = json.loads(out.read_text())
        assert all(isinstance(v["value"], float) and v["status"] == "file" for v in doc["results"].values())
        missing = [n for n in doc["notes"] if n.startswith("not in the file: ")]
        assert not missing or set(missing[0][len("not in the file: "):].split(", ")).isdisjoint(doc["results"])


def write_nsid(path, metadata: dict, group="Measurement_000/Channel_000"):
    """A minimal NSID image as pyNSID writes it: a main dataset plus original_metadata attributes."""
    import h5py
    with h5py.File(path, "w") as h5:
        g = h5.require_group(group)
        d = g.create_dataset("Channel_000", data=np.zeros((4, 4), dtype="f4"))
        d.attrs.update({"quantity": "AmplitudeRetrace", "units": "m", "data_type": "IMAGE"})
        g.create_group("original_metadata").attrs.update(metadata)
    return path


def one_line_error(capsys, argv, words):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pfmdyn {argv[0]}: error:") and err.count("\n") == 1 and words in err, err


def test_bad_files_give_one_line_errors_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "out.json"
    garbage = tmp_path / "garbage.ibw"
    garbage.write_bytes(bytes(range(256)) * 3)
    one_line_error(capsys, ["inspect", str(garbage), "--json", str(out)], "not a readable Igor binary wave")
    empty = tmp_path / "empty.h5"
    import h5py
    with h5py.File(empty, "w") as h5:
        h5.create_group("Something").attrs["x"] = 1
    one_line_error(capsys, ["inspect", str(empty), "--json", str(out)], "no pycroscopy dataset")
    not_h5 = tmp_path / "text.h5"
    not_h5.write_text("hello")
    one_line_error(capsys, ["inspect", str(not_h5), "--json", str(out)], "not a readable HDF5 file")
    bad_nid = tmp_path / "bad.nid"
    bad_nid.write_bytes(b"[DataSet]\r\nVersion=2\r\n#!" + b"\x00" * 7)
    one_line_error(capsys, ["inspect", str(bad_nid), "--json", str(out)], "bad.nid")
    assert not out.exists()


def test_truncated_real_ibw_is_a_one_line_error(tmp_path, capsys):
    source = real(ASYLUM / "IgorIBWReader_ImageStack_BTFO_DSO.ibw").read_bytes()
    # Header (64 bytes), data (1 048 896), note (20 662), layer labels (160): cut inside each.
    for size in (100, len(source) // 2, 1048896 + 10000, 64 + 1048896 + 20662 + 100):
        cut = tmp_path / f"cut{size}.ibw"
        cut.write_bytes(source[:size])
        out = tmp_path / "out.json"
        one_line_error(capsys, ["inspect", str(cut), "--json", str(out)], f"cut{size}.ibw")
        assert not out.exists()


def test_image_without_spring_constant(tmp_path, capsys):
    path = write_nsid(tmp_path / "nok.h5", {"ThermalFrequency": 6e4, "ThermalQ": 120.0, "TuneFreqResult": 3.5e5,
                                            "TuneQResult": 200.0, "SpringConstant": "NaN"})
    record = read_instrument(path)
    assert record.kind == "image" and "spring_constant" in record.missing
    assert record.fields["contact_resonance"] == 3.5e5
    with pytest.raises(UserError, match="spring constant not in nok.h5$"):
        instrument_resonances(path, {"tip_height": 1e-5, "length": 2e-4, "width": 3e-5})
    out = tmp_path / "k.json"
    one_line_error(capsys, ["stiffness", str(path), "--json", str(out)], "give --spring-constant")
    assert not out.exists()
    # Given on the command line, the same file is fine (ratio 5.83 needs a lateral spring: Mindlin's by default).
    assert cli.main(["stiffness", str(path), "--spring-constant", "2", "--length", "2e-4", "--tip-height", "1e-5",
                     "--json", str(out)]) == 0
    assert json.loads(out.read_text())["lever"]["spring_constant"] == {"value": 2.0, "stderr": None, "unit": "N/m",
                                                                      "status": "given"}


def test_usid_band_excitation_is_a_spectrum(tmp_path):
    import h5py
    path = tmp_path / "be.h5"
    with h5py.File(path, "w") as h5:
        meas = h5.create_group("Measurement_000")
        meas.attrs.update({"BE_center_frequency_[Hz]": 3.2e5, "SpringConstant": 2.5})
        g = meas.create_group("Channel_000")
        spec = g.create_dataset("Spectroscopic_Values", data=np.linspace(3e5, 3.4e5, 8)[None, :])
        spec.attrs["units"] = ["Hz"]
        raw = g.create_dataset("Raw_Data", data=np.zeros((16, 8), dtype="c8"))
        raw.attrs.update({"quantity": "Piezoresponse", "units": "V", "Spectroscopic_Values": spec.ref})
    record = read_instrument(path)
    assert record.kind == "spectrum" and record.instrument.endswith("(USID)")
    assert record.fields == {"spring_constant": 2.5, "drive_frequency": 3.2e5}
    assert [(c.name, c.unit, c.shape) for c in record.channels] == [("Piezoresponse", "V", (16, 8))]


def test_missing_extra_is_named(monkeypatch, tmp_path):
    path = tmp_path / "x.ibw"
    path.write_bytes(b"\0" * 64)
    monkeypatch.setitem(sys.modules, "igor2", None)
    with pytest.raises(UserError, match=r"pip install 'pfmdyn\[files\]'"):
        read_instrument(path)


def test_empty_and_unknown_files(tmp_path):
    empty = tmp_path / "empty.nid"
    empty.write_bytes(b"")
    with pytest.raises(UserError, match="the file is empty"):
        read_instrument(empty)
    with pytest.raises(UserError, match="unknown instrument file type '.spm'"):
        read_instrument(tmp_path / "scan.spm")
    with pytest.raises(UserError, match="no such file"):
        read_instrument(tmp_path / "absent.ibw")


@pytest.mark.parametrize("text, words", [
    ("# c\nfrequency_hz,asd_m_per_sqrthz,fit_m_per_sqrthz\n1000,1e-13,1e-13\n1038,1.1e", "line 4: 2 values"),
    ("frequency_hz,asd_m_per_sqrthz\n1000,1e-13\n1038,1.1e\n", "line 3: column 'asd_m_per_sqrthz'"),
    ("frequency_hz,asd_m_per_sqrthz\n", "line 1: header but no data rows"),
])
def test_inspect_of_a_truncated_or_empty_csv_says_so(text, words, tmp_path):
    """As calibrate and discrepancy say of the same file: a truncated row is no data point."""
    path = tmp_path / "tune.csv"
    path.write_text(text)
    with pytest.raises(UserError, match=words):
        read_instrument(path)


def test_a_table_under_a_text_name_a_directory_and_text_without_a_table(tmp_path):
    """inspect reads pfmdyn's table under a .txt name as discrepancy and stiffness do; a directory and
    text with no frequency column are named as what they are."""
    table = tmp_path / "res.txt"
    table.write_text("# spring_constant: 2\nmode,condition,frequency_hz\n1,free,60000\n1,contact,300000\n")
    record = read_instrument(table)
    assert record.kind == "resonance metadata" and record.fields["spring_constant"] == 2.0
    with pytest.raises(UserError, match="a directory, not an instrument file"):
        read_instrument(tmp_path)
    (tmp_path / "notes.txt").write_text("hello\nworld\n")
    with pytest.raises(UserError, match="no frequency column"):
        read_instrument(tmp_path / "notes.txt")


def test_a_value_no_probe_has_is_left_out_and_said(tmp_path, capsys):
    """A negative spring constant was dropped in silence ('no spring constant in ...'), a length of 225 (um
    written as m) taken: discrepancy fitted a 225 m lever.  Both are left out with a note that inspect shows and
    every command that then lacks them repeats."""
    pytest.importorskip("igorwriter")
    sys.path.insert(0, str(Path(__file__).parent))
    from igor_files import asylum_note, igor_wave
    note = {"SpringConstant": "-2", "ThermalFrequency": "70000", "TuneFreqResult": "350000",
            "CustomLeverLength": "225"}
    path = igor_wave(tmp_path / "scan.ibw", np.ones((4, 4, 1), "f4"), "scan", [(0, 1e-8, "m"), (0, 1e-8, "m")], "m",
                     {2: ["HeightRetrace"]}, asylum_note(note))
    record = read_instrument(path)
    assert "spring_constant" not in record.fields and "length" not in record.fields
    assert record.left_out() == [
        "spring constant -2 N/m in the file left out: spring_constant must be in (0.0001, 10000] N/m, got -2.0",
        "lever length 225 m in the file left out: length must be in (1e-06, 0.01] m, got 225.0"]
    assert cli.main(["discrepancy", str(path), "--tip-height", "1e-5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "(spring constant -2 N/m in the file left out" in err and "lever length 225 m" in err
    assert cli.main(["stiffness", str(path)]) == 2
    captured = capsys.readouterr()
    assert "note: spring constant -2 N/m in the file left out" in captured.out and captured.err.count("\n") == 1


def test_inspect_reads_a_contact_frequency_map_that_map_and_stiffness_read(tmp_path):
    """pfmdyn's own map of contact resonances (it said 'no pycroscopy dataset found')."""
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "fc.h5"
    with h5py.File(path, "w") as h:
        h["contact_frequency_hz"] = np.full((3, 4), 3e5)
        h.attrs.update({"spring_constant_n_per_m": 2.0, "free_resonance_hz": 7.5e4})
    record = read_instrument(path)
    assert record.kind == "image" and [(c.name, c.unit, c.shape) for c in record.channels] == [
        ("contact_frequency_hz", "Hz", (3, 4))]
    assert record.fields == {"spring_constant": 2.0, "free_resonance": 7.5e4}
    assert any("a map of contact resonances" in note for note in record.notes)


_NSFOPEN = importlib.util.find_spec("NSFopen")
NSFOPEN_EXAMPLES = sorted(Path(_NSFOPEN.origin).parent.glob("example/*/*.nid")) if _NSFOPEN else []


@pytest.mark.skipif(not NSFOPEN_EXAMPLES, reason="nsfopen's example files are not installed")
def test_nanosurf_examples_inspect_with_each_channel_unit_from_its_own_header():
    """The example files nsfopen ships (images, thermal tune, force spectroscopy with curves
    of unequal length and processed data sets): each channel's unit from its own header."""
    units = {}
    for path in NSFOPEN_EXAMPLES:
        for channel in read_instrument(path).channels:
            units.setdefault(channel.name.split()[-1], set()).add(channel.unit)
    assert units["Phase"] == {"deg"} and units["Amplitude"] == {"V"}
    assert units["Deflection"] == {"m", "N"} and units["Density"] == {"m/sqrt(Hz)"}
    spectroscopy = read_instrument(next(p for p in NSFOPEN_EXAMPLES if p.stem == "spectroscopy"))
    curves = [c for c in spectroscopy.channels if c.name.startswith("Spec")]
    assert len(curves) == 4 and all(c.shape == (100, 1024) for c in curves)
