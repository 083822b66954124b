"""Nanosurf frequency sweeps (.nid) as older software writes them, read and fitted as spectra.

easyScan 2 writes a sweep's header without blank lines between sections and counts channels it
did not save (``Gr0-Count=3`` with only ``Gr0-Ch2`` listed); NSFopen cannot read such a file.
The files here are written from that layout with the sweep of a damped oscillator (not the
beam pfmdyn fits), quantised to 16 bits, with noise; expected numbers are the ones written.
"""
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from schema_check import validate  # noqa: E402

from pfmdyn import cli  # noqa: E402
from pfmdyn.io.instruments import read_instrument  # noqa: E402

RANGE_V = 20.0


def write_sweep_nid(path, frequency, amplitude, peak_hz, environment=None, listed=2, count=3, bits=16,
                    drop=()):
    """An easyScan 2 frequency sweep: the amplitude (V) on ``bits`` signed integers over +-10 V."""
    fields = {"Points": str(len(frequency)), "Lines": "1", "SaveBits": str(bits)}
    lines = ["[DataSet]", "Version=2", "GroupCount=1", "Gr0-Name=Frequency sweep", "Gr0-ID=256", f"Gr0-Count={count}",
             f"Gr0-Ch{listed}=DataSet-0:{listed}", "SetInfos=DataSet-Info", "[DataSet-Info]", "-- Bodeplot --=--------",
             f"Freq. peak={peak_hz / 1e3:.6g}kHz", "Excitation ampl.=284mV", "-- Global --=--------",
             "Op. mode=Dynamic Force", "Head type=EZ2-AFM"]
    lines += [f"Measurement environment={environment}"] if environment else []
    lines += [f"[DataSet-0:{listed}]", "Version=2"] + [f"{k}={v}" for k, v in fields.items() if k not in drop]
    lines += ["Frame=Frequency sweep", "CurLine=0", "Dim0Name=Frequency", "Dim0Unit=Hz",
              f"Dim0Range={frequency[-1] - frequency[0]:.10g}", f"Dim0Min={frequency[0]:.10g}", "Dim1Range=1",
              "Dim1Min=0", "Dim2Name=Amplitude", "Dim2Unit=V", f"Dim2Range={RANGE_V:g}", f"Dim2Min={-RANGE_V / 2:g}",
              "SaveMode=Binary", "SaveSign=Signed", "SaveOrder=Intel", "[SetView]", "ViewCount=1"]
    scale = 2.0**bits
    stored = np.round((amplitude + RANGE_V / 2) / RANGE_V * scale - scale / 2).astype(f"<i{max(bits, 8) // 8}")
    path.write_bytes(("\r\n".join(lines) + "\r\n#!").encode("latin-1") + stored.tobytes())
    return path


def oscillator_sweep(f0, q, rng, points=301, span=6.0):
    """|response| of a damped oscillator driven at its base over +-span/q around f0 (from 0.2 f0 at
    least), in V, with noise of 0.5 % of its peak."""
    f = np.linspace(f0 * max(1 - span / q, 0.2), f0 * (1 + span / q), points)
    u = f / f0
    amplitude = 0.2 * u**2 / np.sqrt((1 - u**2) ** 2 + (u / q) ** 2) / q
    return f, amplitude + 0.001 * rng.standard_normal(points)


def test_easyscan2_sweep_is_read_from_its_layout(tmp_path):
    f, a = oscillator_sweep(1.79e5, 300.0, np.random.default_rng(1))
    path = write_sweep_nid(tmp_path / "sweep.nid", f, a, 179405.0)
    if importlib.util.find_spec("NSFopen"):
        from NSFopen.read import read
        with pytest.raises(Exception):      # the reason pfmdyn reads the layout itself
            read(str(path))
    record = read_instrument(path)
    assert record.kind == "spectrum" and record.fields == {"free_resonance": 179405.0}
    frequency, values, unit = record.spectrum
    assert unit == "V" and len(frequency) == len(f)
    np.testing.assert_allclose(frequency, f, rtol=1e-9)
    np.testing.assert_allclose(values, a, atol=RANGE_V / 2**16)
    out = tmp_path / "inspect.json"
    assert cli.main(["inspect", str(path), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["results"]["free_resonance"]["value"] == 179405.0


def silicon_lever(rng):
    """A rectangular silicon lever drawn by its geometry (L 100-500 um, width L/10, thickness 0.5-7 um),
    kept when k is in 0.05-50 N/m: (k, L, width, first resonance in vacuum, thickness)."""
    while True:
        length, thickness = rng.uniform(100e-6, 500e-6), 10 ** rng.uniform(np.log10(0.5e-6), np.log10(7e-6))
        width = length / 10
        k = 169e9 * width * thickness**3 / (4 * length**3)
        f0 = 1.8751**2 / (2 * np.pi) * np.sqrt(169e9 * thickness**2 / (12 * 2330.0 * length**4))
        if 0.05 <= k <= 50:
            return k, length, width, f0, thickness


@pytest.mark.parametrize("seed", [3, 4])
def test_nid_sweep_is_fitted_as_a_spectrum(tmp_path, capsys, seed):
    """Drawn silicon levers swept in air, their Q below the air's (~ 2500 t/b): the fit finds the written peak."""
    rng = np.random.default_rng(seed)
    k, length, width, f0, thickness = silicon_lever(rng)
    q = rng.uniform(5, min(500.0, 500 * thickness / width))
    f, a = oscillator_sweep(f0, q, rng)
    path = write_sweep_nid(tmp_path / "sweep.nid", f, a, f0, environment="Air")
    out = tmp_path / "fit.json"
    assert cli.main(["discrepancy", str(path), "--spring-constant", f"{k:.6g}", "--length", f"{length:.6g}",
                     "--width", f"{width:.6g}", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    fit = json.loads(out.read_text())
    validate(fit)
    # the header's "Freq. peak" is a peak: beside our amplitude peak, not our resonance
    assert "in air" in text and (f"instrument: amplitude peak {float(f'{f0 / 1e3:.6g}') * 1e3:,.0f} Hz "
                                 f"(ours {fit['results']['amplitude_peak']['value']:,.0f} Hz)").replace(",", " ") in text
    assert fit["lever"]["medium"]["status"] == "file" and set(fit["fit"]["instrument"]) == {"amplitude_peak", "disagrees"}
    # the amplitude of a base-driven oscillator peaks at f0 / sqrt(1 - 1 / (2 q**2))
    # (a broad peak is placed less sharply: the beam's fluid damping grows with frequency, an oscillator's does not)
    results = fit["results"]
    assert results["amplitude_peak"]["value"] == pytest.approx(f0 / np.sqrt(1 - 0.5 / q**2), rel=max(2e-4, 0.05 / q))
    assert results["free_quality_factor"]["value"] == pytest.approx(q, rel=0.1)
    assert fit["fit"]["gap"]["value"] < 2 and "unexplained" not in fit["fit"]


@pytest.mark.parametrize("change, problem", [
    ({"drop": ("Points",)}, "its header has no 'Points'"),
    ({"bits": 8}, "saved with 8 bits"),
    ({"listed": 5, "count": 3}, "holds no data sets"),
])
def test_unknown_nid_variants_end_in_one_line(tmp_path, capsys, change, problem):
    f, a = oscillator_sweep(5e4, 100.0, np.random.default_rng(2))
    path = write_sweep_nid(tmp_path / "odd.nid", f, a, 5e4, **change)
    out = tmp_path / "out.json"
    assert cli.main(["inspect", str(path), "--json", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "odd.nid" in err and problem in err and not out.exists()


def test_truncated_nid_sweep_names_the_missing_bytes(tmp_path, capsys):
    f, a = oscillator_sweep(5e4, 100.0, np.random.default_rng(2))
    path = write_sweep_nid(tmp_path / "cut.nid", f, a, 5e4)
    path.write_bytes(path.read_bytes()[:-10])
    assert cli.main(["discrepancy", str(path), "--spring-constant", "2", "--length", "2e-4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "602 bytes, 592 are left" in err


def test_nid_sweeps_compared_with_a_figure(tmp_path, capsys):
    """Two sweeps of one lever, the second's peak lower by 0.3 %: a mass is named, both are drawn."""
    rng = np.random.default_rng(7)
    k, length, width, f0, thickness = silicon_lever(rng)
    q = min(300.0, 400 * thickness / width)
    f, a = oscillator_sweep(f0, q, rng)
    u = f / (0.997 * f0)
    shifted = 0.2 * u**2 / np.sqrt((1 - u**2) ** 2 + (u / q) ** 2) / q + 0.001 * rng.standard_normal(f.size)
    before = write_sweep_nid(tmp_path / "before.nid", f, a, f0, environment="Air")
    after = write_sweep_nid(tmp_path / "after.nid", f, shifted, 0.997 * f0, environment="Air")
    figure, out = tmp_path / "pair.png", tmp_path / "pair.json"
    assert cli.main(["discrepancy", str(after), "--reference", str(before), "--spring-constant", f"{k:.6g}",
                     "--length", f"{length:.6g}", "--width", f"{width:.6g}", "--plot", str(figure),
                     "--json", str(out)]) == 0
    assert figure.read_bytes()[:4] == b"\x89PNG"
    result = json.loads(out.read_text())
    validate(result)
    assert result["missing_effects"] == ["added_mass"] and result["results"]["added_mass"]["value"] > 0
    before_hz, after_hz = result["results"]["free_resonance"]["value"]
    assert after_hz / before_hz == pytest.approx(0.997, abs=3e-4)
