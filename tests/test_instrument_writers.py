"""Instrument readers on files written by the field's own software, not by hand.

* ``.ibw`` by igorwriter (Igor binary waves as Asylum's software saves them: layered images
  with dimension labels, a ``Key: value`` note with ``\\r`` line ends, tunes with x-scaling);
* USID ``.h5`` by pyUSID (``write_main_dataset``, ``ArrayTranslator``);
* NSID ``.h5`` by sidpy + pyNSID, and by SciFiReaders' IgorIBWReader when it is installed.

Each file gives a correct record (channels with SI units and shapes, cantilever fields in
SI) or a one-line error naming what is missing.  Expected numbers are the ones written.
"""
import importlib.util
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.errors import UserError
from pfmdyn.analysis.thermal import instrument_resonances
from pfmdyn.io.instruments import read_instrument
from pfmdyn.io.record import si_unit

sys.path.insert(0, str(Path(__file__).parent))
from igor_files import asylum_note, igor_wave  # noqa: E402

# The writers' own deprecation notices are not the readers' concern.
pytestmark = [pytest.mark.filterwarnings("ignore::UserWarning:pyUSID"),
              pytest.mark.filterwarnings("ignore::FutureWarning:pyNSID"),
              pytest.mark.filterwarnings("ignore::UserWarning:sidpy")]

# Asylum note keys -> (value as written, pfmdyn field, SI value); a PFM lever in contact.
ASYLUM = {"SpringConstant": ("2.7193", "spring_constant", 2.7193),
          "ThermalFrequency": ("71324", "free_resonance", 71324.0),
          "ThermalQ": ("151.2", "free_quality_factor", 151.2),
          "TuneFreqResult": ("331250", "contact_resonance", 331250.0),
          "TuneQResult": ("87.5", "contact_quality_factor", 87.5),
          "DriveFrequency": ("330000", "drive_frequency", 330000.0),
          "CustomLeverLength": ("2.25e-4", "length", 2.25e-4),
          "CustomLeverWidth": ("4e-5", "width", 4e-5)}
LAYERS = {"HeightRetrace": "m", "AmplitudeRetrace": "m", "PhaseRetrace": "deg", "UserIn0Retrace": "V"}
TIP = {"tip_height": 1.4e-5}


def image_scales(unit="m", step=1e-7):
    return [(0.0, step, unit), (0.0, step, unit)]


def assert_fields(record, written: dict):
    for key, (_, field, value) in written.items():
        assert record.fields[field] == pytest.approx(value, rel=1e-12), key
    assert "tip_height" in record.missing


@pytest.mark.parametrize("end", ["\r", "\n", "\r\n"])
def test_ibw_asylum_image_layers_and_note(tmp_path, end):
    data = np.random.default_rng(1).normal(size=(16, 12, 4)).astype("f4")
    path = igor_wave(tmp_path / "PFM0001.ibw", data, "PFM0001", image_scales(), "m",
                     {2: list(LAYERS)}, asylum_note({k: v[0] for k, v in ASYLUM.items()}, end))
    record = read_instrument(path)
    assert record.kind == "image"
    # Asylum writes one data unit ('m') for every layer; phase is in degrees all the same.
    assert [(c.name, c.unit, c.shape, c.scale) for c in record.channels] == \
        [(n, u, (16, 12), 1.0) for n, u in LAYERS.items()]
    assert_fields(record, ASYLUM)
    data = instrument_resonances(path, TIP)
    assert sorted(zip(data.condition, data.frequency_hz, data.quality_factor)) == \
        [("contact", 331250.0, 87.5), ("free", 71324.0, 151.2)]
    assert data.metadata.spring_constant == 2.7193 and data.metadata.length == 2.25e-4


def test_ibw_note_missing_keys_and_nan_are_missing_not_zero(tmp_path, capsys):
    note = asylum_note({"SpringConstant": "NaN", "TuneFreqResult": "331250\0\0", "ThermalQ": "0"})
    path = igor_wave(tmp_path / "bare.ibw", np.ones((16, 12, 2), "f4"), "bare", image_scales(), "m",
                     {2: ["HeightTrace", "PhaseTrace"]}, note)
    record = read_instrument(path)
    assert record.fields == {"contact_resonance": 331250.0}
    with pytest.raises(UserError, match="free resonance not in bare.ibw$"):
        instrument_resonances(path, TIP)
    out = tmp_path / "d.json"
    assert cli.main(["discrepancy", str(path), "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "give --" in err and not out.exists()
    # No note at all: an image with every field missing, still no error to inspect it.
    bare = read_instrument(igor_wave(tmp_path / "nonote.ibw", np.ones((8, 8), "f4"), "HeightTrace",
                                     image_scales(), "m"))
    assert bare.kind == "image" and not bare.fields and bare.channels[0].unit == "m"
    assert bare.instrument == "Igor binary wave" and record.instrument == "Asylum Research (Igor binary wave)"


@pytest.mark.parametrize("unicode", [True, False])
def test_ibw_non_ascii_note_and_units(tmp_path, unicode):
    """Igor 7+ writes UTF-8 (igorwriter's default); Igor 6 and old Asylum versions Latin-1/Windows."""
    note = asylum_note({"SpringConstant": "0.5", "CustomLeverLength": "225 µm", "DriveFrequency": "312.5 kHz",
                        "CustomLeverWidth": "35 furlong"})
    path = igor_wave(tmp_path / "u.ibw", np.ones((16, 12), "f4"), "HeightRetrace", image_scales("µm", 0.1),
                     "nm", note=note, unicode=unicode)
    record = read_instrument(path)
    assert record.kind == "image"
    assert [(c.name, c.unit, c.scale) for c in record.channels] == [("HeightRetrace", "m", 1e-9)]
    assert record.fields == {"spring_constant": 0.5, "length": pytest.approx(2.25e-4),
                             "drive_frequency": 312500.0}
    assert any("CustomLeverWidth '35 furlong'" in n and "lever width" in n for n in record.notes)


@pytest.mark.parametrize("axis, data_unit, factor", [("Hz", "m", 1.0), ("kHz", "nm", 1e-9), ("MHz", "pm", 1e-12)])
def test_ibw_tune_spectrum_in_si(tmp_path, axis, data_unit, factor):
    """A 1-D tune: amplitude against drive frequency, x-scaling in the instrument's unit."""
    f_hz = np.linspace(2.8e5, 3.6e5, 81)
    scale = {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6}[axis]
    amplitude = 1.0 / np.abs(3.3e5**2 - f_hz**2 + 1j * f_hz * 3.3e5 / 80) * 1e9
    path = igor_wave(tmp_path / "tune.ibw", amplitude, "Amp", [(f_hz[0] / scale, (f_hz[1] - f_hz[0]) / scale, axis)],
                     data_unit, note=asylum_note({"TuneFreqResult": "330000"}))
    record = read_instrument(path)
    freq, values, unit = record.spectrum
    assert record.kind == "spectrum" and unit == "m" and record.channels[0].scale == factor
    np.testing.assert_allclose(freq, f_hz, rtol=1e-9)
    np.testing.assert_allclose(values, amplitude * factor, rtol=1e-6)
    assert freq[np.argmax(values)] == pytest.approx(3.3e5, rel=2e-3)


def test_ibw_tune_columns_and_complex(tmp_path):
    f0, df = 3.0e5, 500.0
    rng = np.random.default_rng(2)
    columns = igor_wave(tmp_path / "cols.ibw", rng.random((40, 2)), "Tune", [(f0, df, "Hz")], "V",
                        {1: ["Amplitude", "Phase"]})
    record = read_instrument(columns)
    assert record.kind == "spectrum"
    assert [(c.name, c.unit, c.shape) for c in record.channels] == [("Amplitude", "V", (40,)), ("Phase", "deg", (40,))]
    z = (rng.random(40) + 1j * rng.random(40)).astype("c8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # no ComplexWarning: the imaginary part is kept
        freq, values, unit = read_instrument(igor_wave(tmp_path / "c.ibw", z, "Resp", [(f0, df, "Hz")], "mV")).spectrum
    assert unit == "V" and np.iscomplexobj(values)
    np.testing.assert_allclose(values, z * 1e-3, rtol=1e-6)
    assert freq[-1] == f0 + 39 * df


def test_ibw_stacks(tmp_path):
    rng = np.random.default_rng(3)
    spectral = igor_wave(tmp_path / "be.ibw", rng.random((8, 6, 30)).astype("f4"), "BE",
                         image_scales() + [(300.0, 1.0, "kHz")], "V")
    record = read_instrument(spectral)
    assert record.kind == "spectrum" and [(c.unit, c.shape) for c in record.channels] == [("V", (8, 6, 30))]
    assert "30 frequencies (300000 to 329000 Hz)" in record.notes[0]
    # Pixels without a length unit: still a spectrum at each pixel, not 30 channels.
    plain = read_instrument(igor_wave(tmp_path / "be2.ibw", rng.random((8, 6, 30)), "BE", [(0, 1, ""), (0, 1, ""),
                                                                                         (3e5, 1e3, "Hz")]))
    assert plain.kind == "spectrum" and [c.shape for c in plain.channels] == [(8, 6, 30)]
    frames = read_instrument(igor_wave(tmp_path / "t.ibw", rng.random((8, 6, 5)), "Movie",
                                       image_scales() + [(0.0, 2.0, "s")], "nm"))
    assert frames.kind == "image" and [(c.name, c.unit, c.shape, c.scale) for c in frames.channels] == \
        [("Movie", "m", (8, 6, 5), 1e-9)]


def test_ibw_units_not_si_are_kept_and_said(tmp_path):
    record = read_instrument(igor_wave(tmp_path / "a.ibw", np.ones((8, 8)), "Counts", image_scales(), "cts"))
    assert record.channels[0].unit == "cts" and record.channels[0].scale == 1.0
    assert any("'cts' is not an SI unit" in n for n in record.notes)
    sidpy_default = nsid_dataset(np.ones((4, 4)), "Count", "Count", "generic",
                                 [("x", np.arange(4.0), "m", "spatial"), ("y", np.arange(4.0), "m", "spatial")], "IMAGE")
    record = read_instrument(write_nsid(tmp_path / "g.h5", {"Count": sidpy_default}))
    assert record.channels[0].unit == "generic" and any("'generic' is not an SI unit" in n for n in record.notes)


@pytest.mark.parametrize("text, expected", [
    ("kHz", ("Hz", 1e3)), ("nm", ("m", 1e-9)), ("pN/nm", ("N/m", 1e-3)), ("mV", ("V", 1e-3)),
    ("um", ("m", 1e-6)), ("µm", ("m", 1e-6)), ("nm/V", ("m/V", 1e-9)), ("pm/V", ("m/V", 1e-12)),
    ("fm/√Hz", ("m/sqrt(Hz)", 1e-15)), ("nm/sqrt(Hz)", ("m/sqrt(Hz)", 1e-9)), ("Å", ("m", 1e-10)),
    ("nN", ("N", 1e-9)), ("N/m", ("N/m", 1.0)), ("°", ("deg", 1.0)), ("", ("", 1.0)),
    ("pm/rtHz", ("m/sqrt(Hz)", 1e-12)), ("V/Hz^0.5", ("V/sqrt(Hz)", 1.0)), ("mm^2", ("m^2", 1e-6)),
    ("a.u.", None), ("counts", None), ("kfoo", None), ("m/", None)])
def test_prefixed_units_to_si(text, expected):
    got = si_unit(text)
    if expected is None:
        assert got is None
    else:
        assert got[0] == expected[0] and got[1] == pytest.approx(expected[1], rel=1e-12)


def test_sweep_columns_and_header_in_khz(tmp_path):
    path = tmp_path / "sweep.txt"
    f = np.linspace(70.0, 75.0, 11)
    rows = "\n".join(f"{x:.3f}\t{1e3 / (1 + (x - 72.5) ** 2):.6f}\t{x:.1f}" for x in f)
    path.write_text("Q factor:\t3.1\nPeak amplitude frequency (kHz):\t72.5\nSweep data\n"
                    f"Frequency (kHz)\tAmplitude (mV)\tPhase (deg)\n{rows}\n")
    record = read_instrument(path)
    assert record.fields == {"amplitude_peak": 72500.0, "free_quality_factor": 3.1}
    freq, values, unit = record.spectrum
    assert unit == "V" and freq[0] == 70000.0 and values.max() == pytest.approx(1.0)


# --- pycroscopy HDF5 ---------------------------------------------------------------------

@pytest.fixture
def usid(monkeypatch):
    """pyUSID 0.0.12 calls numpy.product, which NumPy 2 removed: give it back for the test."""
    if not hasattr(np, "product"):
        monkeypatch.setattr(np, "product", np.prod, raising=False)
    return pytest.importorskip("pyUSID")


def write_usid_be(path, usid, unit="Hz", positions=(4, 3), attrs=None):
    """Band excitation as pycroscopy keeps it: complex response, positions x frequencies."""
    import h5py
    f = np.linspace(300.0, 340.0, 24) * (1.0 if unit == "kHz" else 1e3)
    n = int(np.prod(positions))
    rng = np.random.default_rng(4)
    response = (rng.normal(size=(n, 24)) + 1j * rng.normal(size=(n, 24))).astype("c8")
    with h5py.File(path, "w") as h5:
        meas = h5.create_group("Measurement_000")
        meas.attrs.update(attrs or {})
        usid.hdf_utils.write_main_dataset(
            meas.create_group("Channel_000"), response, "Raw_Data", "Piezoresponse", "V",
            [usid.Dimension("X", "m", np.arange(positions[0]) * 1e-7),
             usid.Dimension("Y", "m", np.arange(positions[1]) * 1e-7)],
            [usid.Dimension("Frequency", unit, f)])
    return path, response


@pytest.mark.parametrize("unit", ["Hz", "kHz"])
def test_usid_band_excitation_written_by_pyusid(tmp_path, usid, unit):
    attrs = {"BE_center_frequency_[Hz]": "3.2e5", "SpringConstant": 1.8, "ThermalFrequency": 65000.0,
             "TuneFreqResult": "320 kHz"}
    path, _ = write_usid_be(tmp_path / "be.h5", usid, unit, attrs=attrs)
    record = read_instrument(path)
    assert record.kind == "spectrum" and record.instrument == "pycroscopy HDF5 (USID)"
    assert [(c.name, c.unit, c.shape) for c in record.channels] == [("Piezoresponse", "V", (12, 24))]
    assert record.fields == {"spring_constant": 1.8, "free_resonance": 65000.0,
                             "contact_resonance": 320000.0, "drive_frequency": 3.2e5}
    assert "12 spectra of 24 frequencies (300000 to 340000 Hz)" in record.notes[0]
    assert instrument_resonances(path, {"length": 2e-4, "width": 3e-5, **TIP}).frequency_hz.tolist() == \
        [65000.0, 320000.0]
    # Without cantilever attributes: the same data, every field missing, a one-line error.
    bare, response = write_usid_be(tmp_path / "bare.h5", usid, unit, positions=(1, 1),
                                   attrs={"BE_center_frequency_[Hz]": "n/a"})
    record = read_instrument(bare)
    assert not record.fields and any("BE_center_frequency_[Hz] 'n/a' not understood" in n for n in record.notes)
    freq, values, unit_out = record.spectrum
    assert unit_out == "V" and freq[0] == 3e5 and freq[-1] == pytest.approx(3.4e5)
    np.testing.assert_allclose(values, response[0], rtol=1e-6)
    with pytest.raises(UserError, match="free resonance not in bare.h5$"):
        instrument_resonances(bare)


def test_usid_image_by_array_translator(tmp_path, usid):
    path = tmp_path / "height.h5"
    data = np.random.default_rng(5).normal(size=(12, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        usid.io.ArrayTranslator().translate(
            str(path), "AFM", data, "Height", "nm",
            [usid.Dimension("X", "um", np.arange(4) * 0.1), usid.Dimension("Y", "um", np.arange(3) * 0.1)],
            [usid.Dimension("arb", "a.u.", 1)])
    record = read_instrument(path)
    assert record.kind == "image" and [(c.name, c.unit, c.scale) for c in record.channels] == [("Height", "m", 1e-9)]
    assert len(record.missing) == len(record.missing + tuple(record.fields))


def nsid_dataset(data, title, quantity, units, dims, data_type, original_metadata=None, metadata=None):
    sidpy = pytest.importorskip("sidpy")
    ds = sidpy.Dataset.from_array(data, title=title)
    for i, (name, values, unit, kind) in enumerate(dims):
        ds.set_dimension(i, sidpy.Dimension(values, name, units=unit, quantity=name, dimension_type=kind))
    ds.units, ds.quantity, ds.data_type = units, quantity, data_type
    ds.original_metadata = dict(original_metadata or {})
    ds.metadata = dict(metadata or {})
    return ds


def write_nsid(path, datasets: dict):
    pyNSID = pytest.importorskip("pyNSID")
    import h5py
    with h5py.File(path, "w") as h5:
        for i, (name, ds) in enumerate(datasets.items()):
            pyNSID.hdf_io.write_nsid_dataset(ds, h5.create_group(f"Measurement_000/Channel_{i:03d}"),
                                             main_data_name=name)
    return path


def test_nsid_images_with_asylum_metadata(tmp_path):
    """As SciFiReaders' IgorIBWReader keeps an Asylum note: numbers as numbers, text as text."""
    note = {k: (float(v[0]) if "e" not in v[0] else v[0]) for k, v in ASYLUM.items()}
    dims = [("x", np.arange(16) * 1e-8, "m", "spatial"), ("y", np.arange(12) * 1e-8, "m", "spatial")]
    rng = np.random.default_rng(6)
    datasets = {name: nsid_dataset(rng.random((16, 12)), name, "Height" if "Height" in name else "Phase",
                                   "nm" if "Height" in name else "deg", dims, "IMAGE", note,
                                   {"experiment": {"tip": "PPP-EFM"}})
                for name in ("HeightTrace", "HeightRetrace", "PhaseRetrace")}
    path = write_nsid(tmp_path / "asylum.h5", datasets)
    record = read_instrument(path)
    assert record.kind == "image" and record.instrument == "pycroscopy HDF5 (NSID)"
    assert [(c.name, c.unit, c.shape, c.scale) for c in record.channels] == [
        ("Height (HeightTrace)", "m", (16, 12), 1e-9), ("Height (HeightRetrace)", "m", (16, 12), 1e-9),
        ("Phase", "deg", (16, 12), 1.0)]
    assert_fields(record, ASYLUM)
    # The whole Asylum note kept as one text attribute, as some converters do.
    whole = nsid_dataset(np.ones((16, 12)), "HeightRetrace", "HeightRetrace", "m", dims, "IMAGE",
                         {"note": asylum_note({k: v[0] for k, v in ASYLUM.items()})})
    assert_fields(read_instrument(write_nsid(tmp_path / "whole.h5", {"HeightRetrace": whole})), ASYLUM)
    out = tmp_path / "r.json"
    assert cli.main(["inspect", str(path), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["results"]["contact_resonance"] == {"value": 331250.0, "stderr": None, "unit": "Hz", "status": "file",
                                                   "why": "read from the input file"}
    assert any(n.startswith("channel ") and "stored values x 1e-09" in n for n in doc["notes"])


def test_nsid_spectrum_in_khz_and_pm(tmp_path):
    f_khz = np.linspace(60.0, 80.0, 41)
    amplitude = 50.0 / np.sqrt((1 - (f_khz / 71.0) ** 2) ** 2 + (f_khz / 71.0 / 120) ** 2)
    tune = nsid_dataset(amplitude, "Tune", "Amplitude", "pm", [("frequency", f_khz, "kHz", "spectral")], "SPECTRUM")
    record = read_instrument(write_nsid(tmp_path / "tune.h5", {"Tune": tune}))
    freq, values, unit = record.spectrum
    assert record.kind == "spectrum" and unit == "m"
    np.testing.assert_allclose(freq, f_khz * 1e3)
    np.testing.assert_allclose(values, amplitude * 1e-12)
    # A spectrum whose axis has no frequency unit is said so, not guessed.
    loops = nsid_dataset(amplitude, "Loop", "Amplitude", "pm", [("bias", f_khz, "V", "spectral")], "SPECTRUM")
    record = read_instrument(write_nsid(tmp_path / "loop.h5", {"Loop": loops}))
    assert record.spectrum is None and "no frequency unit" in record.notes[0]
    # Band excitation as a spectral image (x, y, frequency in MHz).
    cube = nsid_dataset(np.ones((3, 2, 5), "c8"), "BE", "Response", "mV",
                        [("x", np.arange(3.0), "um", "spatial"), ("y", np.arange(2.0), "um", "spatial"),
                         ("frequency", np.linspace(0.30, 0.34, 5), "MHz", "spectral")], "SPECTRAL_IMAGE")
    record = read_instrument(write_nsid(tmp_path / "cube.h5", {"BE": cube}))
    assert record.kind == "spectrum" and [(c.unit, c.scale) for c in record.channels] == [("V", 1e-3)]
    assert "6 spectra of 5 frequencies (300000 to 340000 Hz)" in record.notes[0]


def _scifireaders_ibw():
    """SciFiReaders' IgorIBWReader, loaded alone (the package imports every reader's dependencies)."""
    spec = importlib.util.find_spec("SciFiReaders")
    if spec is None:
        pytest.skip("SciFiReaders is not installed")
    path = next(iter(spec.submodule_search_locations)) + "/readers/microscopy/spm/afm/igor_ibw.py"
    module_spec = importlib.util.spec_from_file_location("_scifi_igor_ibw", path)
    module = importlib.util.module_from_spec(module_spec)
    try:
        module_spec.loader.exec_module(module)
    except ImportError as exc:
        pytest.skip(f"SciFiReaders' Igor reader cannot be imported: {exc}")
    return module.IgorIBWReader


def test_ibw_to_nsid_through_scifireaders_agrees(tmp_path):
    """igorwriter .ibw -> SciFiReaders -> pyNSID .h5: both files give the same record."""
    reader = _scifireaders_ibw()
    data = np.random.default_rng(7).normal(size=(16, 12, 4)).astype("f4")
    ibw = igor_wave(tmp_path / "PFM0002.ibw", data, "PFM0002", image_scales(), "m", {2: list(LAYERS)},
                    asylum_note({k: v[0] for k, v in ASYLUM.items()}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        datasets = reader(str(ibw)).read()
    for ds in datasets.values():       # its bookkeeping entries are not HDF5 attributes
        ds.original_metadata = {k: v for k, v in ds.original_metadata.items() if isinstance(v, (int, float, str))}
    h5 = write_nsid(tmp_path / "PFM0002.h5", datasets)
    direct, converted = read_instrument(ibw), read_instrument(h5)
    assert converted.fields == direct.fields
    assert [(c.name, c.unit, c.shape) for c in converted.channels] == \
        [(c.name, c.unit, c.shape) for c in direct.channels]


def test_ibw_force_curve_columns_and_stale_label_bytes(tmp_path):
    """Asylum force curves: columns Raw, Defl, ZSnsr against time.  Igor leaves stale bytes
    after each label's NUL (its buffer held a longer label before); they are not the name."""
    t = np.arange(200) * 1e-4
    curve = np.column_stack([np.sin(t), np.cos(t), t]).astype("f4")
    path = igor_wave(tmp_path / "Force0001.ibw", curve, "Force0001", [(0.0, 1e-4, "s")], "m",
                     {1: ["Raw", "Defl", "ZSnsr"]}, asylum_note({"SpringConstant": "0.81"}))
    raw = path.read_bytes()
    path.write_bytes(raw.replace(b"Defl\0\0\0\0\0\0", b"Defl\0ectio").replace(b"Raw\0\0\0", b"Raw\0ac"))
    record = read_instrument(path)
    assert record.kind == "curve" and record.fields == {"spring_constant": 0.81}
    assert [(c.name, c.unit, c.shape) for c in record.channels] == [(n, "m", (200,)) for n in ("Raw", "Defl", "ZSnsr")]


def test_ibw_long_names_version_7(tmp_path):
    """Igor Pro 8+ saves waves with long names as version 7, which igor2 itself refuses."""
    igorwriter = pytest.importorskip("igorwriter")
    wave = igorwriter.IgorWave(np.ones((8, 8, 2), "f4"), name="PFM_scan_of_the_PZT_film_at_room_temperature",
                               long_name_support=True)
    for dim in "xy":
        wave.set_dimscale(dim, 0.0, 1e-7, "m")
    wave.set_dimlabel(2, 0, "HeightRetrace")
    wave.set_dimlabel(2, 1, "PhaseRetrace")
    wave.set_note(asylum_note({"SpringConstant": "2.5"}))
    wave.save(str(tmp_path / "long.ibw"))
    record = read_instrument(tmp_path / "long.ibw")
    assert [(c.name, c.unit) for c in record.channels] == [("HeightRetrace", "m"), ("PhaseRetrace", "deg")]
    assert record.fields == {"spring_constant": 2.5}


def _version2_wave(path, values, x0, dx, x_unit, data_unit, note=b""):
    """An Igor 1-4 era (version 2) binary wave, byte by byte from the format's description:
    a 16-byte binary header, the 126-byte wave header whose last 16 bytes are the first of the
    data, the data padded by those 16 bytes, then the note."""
    import struct
    data = np.asarray(values, "<f4").tobytes() + bytes(16)
    wave = struct.pack("<hl20shhl4s4slhddhhhddccllL2sLl", 2, 0, b"tune", 0, 0, 0, data_unit, x_unit, len(values), 0,
                       dx, x0, 0, 0, 0, 0.0, 0.0, b"\0", b"\0", 0, 0, 0, b"\0\0", 0, 0)
    head = struct.pack("<hlllh", 2, len(wave) + len(data), len(note), 0, 0) + wave
    check = -sum(struct.unpack(f"<{len(head) // 2}h", head))        # the header's int16 words sum to zero
    head = struct.pack("<hlllh", 2, len(wave) + len(data), len(note), 0, (check + 2**15) % 2**16 - 2**15) + wave
    path.write_bytes(head + data + note)
    return path


def test_ibw_version_2_spectrum(tmp_path):
    """Versions 1-3 give the point count as npnts (no nDim): a 1-D tune saved by an old Igor."""
    f_khz = np.linspace(280.0, 360.0, 41)
    amplitude = 1e3 / np.abs(330.0**2 - f_khz**2 + 1j * f_khz * 330.0 / 50)
    path = _version2_wave(tmp_path / "old.ibw", amplitude, f_khz[0], f_khz[1] - f_khz[0], b"kHz", b"nm",
                          b"SpringConstant: 2.5\r")
    record = read_instrument(path)
    freq, values, unit = record.spectrum
    np.testing.assert_allclose(freq, f_khz * 1e3, rtol=1e-9)
    np.testing.assert_allclose(values, amplitude.astype("f4") * 1e-9, rtol=1e-6)
    assert unit == "m" and record.fields == {"spring_constant": 2.5}


def test_ibw_axis_in_unknown_unit_is_said(tmp_path):
    record = read_instrument(igor_wave(tmp_path / "h.ibw", np.ones(20), "Amp", [(1.0, 1.0, "Hertz")], "V"))
    assert record.kind == "curve" and record.spectrum is None
    assert any("'Hertz', which pfmdyn cannot convert" in n for n in record.notes)
    # Units longer than 3 bytes are 'extended', each dimension's in turn: read apart, not run together.
    image = read_instrument(igor_wave(tmp_path / "a.ibw", np.ones((8, 6)), "HeightTrace",
                                      image_scales("Angstrom", 5.0), "Angstrom"))
    assert image.kind == "image" and [(c.unit, c.scale) for c in image.channels] == [("m", 1e-10)]


def test_usid_beps_frequency_and_dc_steps(tmp_path, usid):
    """Switching spectroscopy (BEPS): the frequency row repeats for each DC step."""
    import h5py
    path = tmp_path / "beps.h5"
    f = np.linspace(3.0e5, 3.4e5, 10)
    with h5py.File(path, "w") as h5:
        usid.hdf_utils.write_main_dataset(
            h5.create_group("Measurement_000/Channel_000"), np.ones((6, 40), "c8"), "Raw_Data", "Piezoresponse",
            "mV", [usid.Dimension("X", "m", np.arange(3) * 1e-7), usid.Dimension("Y", "m", np.arange(2) * 1e-7)],
            [usid.Dimension("Frequency", "Hz", f), usid.Dimension("DC_Offset", "V", np.linspace(-5, 5, 4))])
    record = read_instrument(path)
    assert record.kind == "spectrum" and [(c.unit, c.scale) for c in record.channels] == [("V", 1e-3)]
    assert "24 spectra of 10 frequencies (300000 to 340000 Hz)" in record.notes[0]


@pytest.mark.parametrize("spelling", ["names", "older"])
def test_pfmdyn_map_layout_and_root_attributes(tmp_path, spelling):
    """The plain layout ``pfmdyn map`` reads: response (ny, nx, n_freq), frequency_hz, root attributes
    (under their names, or the older spellings with units, read as the names)."""
    import h5py
    path = tmp_path / "map.h5"
    attrs = {"spring_constant": 3.1, "length": 2.25e-4, "tip_height": 1.2e-5, "free_resonance": 7.1e4}
    if spelling == "older":
        attrs = dict(zip(("spring_constant_n_per_m", "length_m", "tip_height_m", "free_resonance_hz"), attrs.values()))
    with h5py.File(path, "w") as h5:
        h5["response"] = np.ones((3, 4, 16), "c8")
        h5["frequency_hz"] = np.linspace(3e5, 3.3e5, 16)
        h5.attrs.update(attrs)
    record = read_instrument(path)
    assert record.kind == "spectrum" and record.instrument == "HDF5 (pfmdyn map layout)"
    assert record.fields == {"spring_constant": 3.1, "length": 2.25e-4, "tip_height": 1.2e-5,
                             "free_resonance": 7.1e4}
    assert "12 spectra of 16 frequencies (300000 to 330000 Hz)" in record.notes[0]


def test_damaged_hdf5_is_one_line(tmp_path, monkeypatch, capsys):
    """HDF5 raises RuntimeError on broken B-trees and heaps (seen on files with flipped bytes)."""
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "broken.h5"
    with h5py.File(path, "w") as h5:
        h5["x"] = np.ones(3)

    def broken(self, func):
        raise RuntimeError("Object visitation failed (incorrect B-tree node type)")
    monkeypatch.setattr(h5py.Group, "visititems", broken)
    assert cli.main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "broken.h5: could not interpret the file (RuntimeError" in err


def test_nanosurf_thermal_tune_in_prefixed_units(tmp_path):
    """nsfopen's own thermal tune, its axis units rewritten as kHz and nm/sqrt(Hz): scaled to SI."""
    spec = importlib.util.find_spec("NSFopen")
    if spec is None:
        pytest.skip("nsfopen is not installed")
    source = next(iter(spec.submodule_search_locations)) + "/example/Spring_Constant/thermal.nid"
    raw = Path(source).read_bytes()
    assert raw.count(b"Dim0Unit=Hz") == 2 and raw.count(b"Dim2Unit=m/") == 2
    path = tmp_path / "thermal_khz.nid"
    path.write_bytes(raw.replace(b"Dim0Unit=Hz", b"Dim0Unit=kHz").replace(b"Dim2Unit=m/", b"Dim2Unit=nm/"))
    original, prefixed = read_instrument(source), read_instrument(path)
    assert prefixed.spectrum[2] == original.spectrum[2] == "m/sqrt(Hz)"
    # Relabelled, the same stored numbers mean kHz and nm/sqrt(Hz).
    np.testing.assert_allclose(prefixed.spectrum[0], original.spectrum[0] * 1e3)
    np.testing.assert_allclose(prefixed.spectrum[1], original.spectrum[1] * 1e-9)
    assert [c.scale for c in prefixed.channels][:1] == [1e-9]


def test_ibw_thermal_tune_gives_the_free_mode(tmp_path):
    """A thermal tune saved as a wave: amplitude spectral density in pm/sqrt(Hz) against Hz."""
    f = np.arange(8001) * 50.0
    f0, q = 7.13e4, 151.0
    sho = np.sqrt(1.0 / ((f0**2 - f**2) ** 2 + (f * f0 / q) ** 2)) * f0**2      # 1 at low frequency
    asd_pm = (0.02 * sho + 0.05) * np.random.default_rng(8).gamma(100, 0.01, f.size)
    note = asylum_note({"SpringConstant": "2.7193", "CustomLeverLength": "2.25e-4", "CustomLeverWidth": "4e-5"})
    path = igor_wave(tmp_path / "Thermal.ibw", asd_pm, "ThermalData", [(0.0, 50.0, "Hz")], "pm/sqrt(Hz)", note=note)
    record = read_instrument(path)
    assert record.kind == "thermal spectrum" and record.spectrum[2] == "m/sqrt(Hz)"
    data = instrument_resonances(path, TIP)
    assert data.condition.tolist() == ["free"] and data.mode.tolist() == [1]
    assert data.frequency_hz[0] == pytest.approx(f0, rel=2e-3) and data.quality_factor[0] == pytest.approx(q, rel=0.15)
    assert data.metadata.spring_constant == 2.7193
