"""``pfmdyn map --model sho`` on USID band-excitation files written by pyUSID, and the fit in BGlib's layout.

The spectra are the SHO evaluated here by hand (BGlib's form, not pfmdyn's generated function)
at random resonance frequencies and Q (5-500) with complex Gaussian noise, in bands sized as BE
users size them (a few line widths); the beam-fit file uses the finite-element beam
(``tests/fe_beam.py``).  A spectrum is right when its frequency is within 2e-4 and its Q within
3 % of the SHO that made it (the best SHO description of the noise-free response).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

h5py = pytest.importorskip("h5py")
pytest.importorskip("zarr")
pytest.importorskip("dask")
xarray = pytest.importorskip("xarray")
sys.path.insert(0, str(Path(__file__).parent))

from fe_beam import FEBeam  # noqa: E402
from pfmdyn.cli import main  # noqa: E402
from pfmdyn.maps import open_result  # noqa: E402

pytestmark = [pytest.mark.filterwarnings("ignore::UserWarning:pyUSID"),
              pytest.mark.filterwarnings("ignore::FutureWarning"),
              pytest.mark.filterwarnings("ignore::DeprecationWarning")]
FIELDS = ["Amplitude [V]", "Frequency [Hz]", "Quality Factor", "Phase [rad]", "R2 Criterion"]
NY, NX = 12, 16


@pytest.fixture
def usid(monkeypatch):
    """pyUSID 0.0.12 calls numpy.product, which NumPy 2 removed: give it back for the test."""
    if not hasattr(np, "product"):
        monkeypatch.setattr(np, "product", np.prod, raising=False)
    return pytest.importorskip("pyUSID")


def bglib_sho(f, amplitude, phase, f0, q):
    """BGlib's SHO, typed from its documentation: A e^{i phi} w0^2 / (f^2 - i f w0/Q - w0^2)."""
    return amplitude * np.exp(1j * phase) * f0**2 / (f**2 - 1j * f * f0 / q - f0**2)


def write_be(usid, path, response, f, bias=None, attrs=None):
    """``response`` (positions, [bias,] frequency) as BE data through pyUSID, X fastest."""
    spectral = [usid.Dimension("Frequency", "Hz", f)]
    if bias is not None:
        spectral.append(usid.Dimension("DC_Offset", "V", bias))
    with h5py.File(path, "w") as h5:
        meas = h5.create_group("Measurement_000")
        meas.attrs.update(attrs or {})
        usid.hdf_utils.write_main_dataset(
            meas.create_group("Channel_000"), response.reshape(NY * NX, -1), "Raw_Data", "Piezoresponse", "V",
            [usid.Dimension("X", "m", np.arange(NX) * 1e-7), usid.Dimension("Y", "m", np.arange(NY) * 1e-7)],
            spectral)
    return path


def sho_pixels(rng, f, q_range, n, spread=0.25):
    """Random SHO parameters: f0 within ``spread`` of the band's half width around its centre."""
    centre, half = (f[0] + f[-1]) / 2, (f[-1] - f[0]) / 2
    return {"f0": centre + spread * half * rng.uniform(-1, 1, n), "q": np.exp(rng.uniform(*np.log(q_range), n)),
            "amplitude": np.exp(rng.uniform(np.log(1e-4), np.log(1e-2), n)), "phase": rng.uniform(-np.pi, np.pi, n)}


def noisy(rng, clean, level):
    scale = level * np.abs(clean).max(axis=-1, keepdims=True)
    return clean + scale * (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)) / np.sqrt(2)


# Q range, band (relative width: a few line widths of the sharpest resonance), bins, noise of the peak
CASES = {"low_q": ((5, 15), 0.6, 128, 0.005), "mid_q": ((30, 120), 0.08, 96, 0.01),
         "high_q": ((150, 500), 0.012, 128, 0.01)}


@pytest.mark.parametrize("case", list(CASES))
def test_sho_frequency_and_q_at_95_percent_of_pixels_in_bglib_layout(usid, tmp_path, case):
    q_range, width, bins, level = CASES[case]
    rng = np.random.default_rng(list(CASES).index(case) + 11)
    centre = rng.uniform(250e3, 400e3)
    f = np.linspace(centre * (1 - width / 2), centre * (1 + width / 2), bins)
    p = sho_pixels(rng, f, q_range, NY * NX)
    clean = bglib_sho(f, *(p[k][:, None] for k in ("amplitude", "phase", "f0", "q")))
    path = write_be(usid, tmp_path / "be.h5", noisy(rng, clean, level), f)
    out = tmp_path / "out"
    assert main(["map", str(path), "--model", "sho", "--out", str(out), "--no-progress", "--scheduler", "sync",
                 "--block", "8"]) == 0
    with h5py.File(out / "be.h5", "r") as h5:
        group = h5["Measurement_000/Channel_000/Raw_Data-SHO_Fit_000"]
        fit, guess = group["Fit"][()], group["Guess"][()]
        assert list(fit.dtype.names) == FIELDS and fit.shape == guess.shape == (NY * NX, 1)
        assert np.all(group["completed_fit_positions"][()] == 1) and group["completed_fit_positions"].dtype == np.uint8
        assert [v.decode() for v in group["Spectroscopic_Values"].attrs["labels"]] == ["Single_Step"]
        # the input is untouched: the results went into the copy
    with h5py.File(path, "r") as h5:
        assert list(h5["Measurement_000/Channel_000"]) == ["Position_Indices", "Position_Values", "Raw_Data",
                                                           "Spectroscopic_Indices", "Spectroscopic_Values"]
    for table in (fit, guess):
        right = (np.abs(table["Frequency [Hz]"] / p["f0"][:, None] - 1) < 2e-4) & \
                (np.abs(table["Quality Factor"] / p["q"][:, None] - 1) < 0.03)
        assert right.mean() >= 0.95, (case, right.mean())
    # BGlib's conventions: A off resonance, phi with its +pi (a sign slip moves the phase by pi)
    assert np.median(np.abs(fit["Amplitude [V]"][:, 0] / p["amplitude"] - 1)) < 0.02
    assert np.median(np.abs(np.angle(np.exp(1j * (fit["Phase [rad]"][:, 0] - p["phase"]))))) < 0.05
    assert np.median(fit["R2 Criterion"]) > 0.99
    # the fit is calibrated: its standard errors describe its frequency errors
    result = open_result(out)
    z = (result["measured_resonance"].values.ravel() - p["f0"]) / result["measured_resonance_stderr"].values.ravel()
    assert 0.55 <= np.mean(np.abs(z) < 1) <= 0.8, np.mean(np.abs(z) < 1)
    np.testing.assert_array_equal(result["measured_resonance"].values.reshape(-1), fit["Frequency [Hz]"][:, 0])


def test_pyusid_reads_guess_and_fit_as_main_datasets(usid, tmp_path):
    rng = np.random.default_rng(5)
    f = np.linspace(290e3, 310e3, 64)
    p = sho_pixels(rng, f, (80, 200), NY * NX)
    path = write_be(usid, tmp_path / "be.h5",
                    noisy(rng, bglib_sho(f, *(p[k][:, None] for k in ("amplitude", "phase", "f0", "q"))), 0.01), f)
    assert main(["map", str(path), "--model", "sho", "--out", str(tmp_path / "o"), "--no-progress",
                 "--usid-inplace", "--workers", "2"]) == 0
    with h5py.File(path, "r") as h5:
        group = h5["Measurement_000/Channel_000/Raw_Data-SHO_Fit_000"]
        for name in ("Guess", "Fit"):
            assert usid.hdf_utils.check_if_main(group[name])
            dataset = usid.USIDataset(group[name])
            assert dataset.pos_dim_labels == ["X", "Y"] or dataset.pos_dim_labels == ["Y", "X"]
            assert h5[group.attrs["source_000"]].name == "/Measurement_000/Channel_000/Raw_Data"
    # a rerun from the same maps.zarr replaces its group rather than adding one
    assert main(["map", str(path), "--model", "sho", "--out", str(tmp_path / "o"), "--no-progress",
                 "--usid-inplace"]) == 0
    with h5py.File(path, "r") as h5:
        assert sorted(k for k in h5["Measurement_000/Channel_000"] if "SHO_Fit" in k) == ["Raw_Data-SHO_Fit_000"]


def test_beps_bias_steps_and_two_bands(usid, tmp_path):
    """BEPS: one SHO per DC step and per band; the steps in the file's order, a Band row fastest."""
    rng = np.random.default_rng(9)
    bands = [np.linspace(280e3, 320e3, 48), np.linspace(880e3, 960e3, 48)]
    f = np.concatenate(bands)
    bias = np.array([-4.0, 0.0, 4.0])
    f0 = np.stack([rng.uniform(295e3, 305e3, (NY * NX, 3)), rng.uniform(910e3, 930e3, (NY * NX, 3))], axis=-1)
    q = np.stack([np.full((NY * NX, 3), 60.0), np.full((NY * NX, 3), 150.0)], axis=-1)
    clean = sum(bglib_sho(f, 1e-3, 0.3, f0[..., b, None], q[..., b, None]) * (np.abs(f - band.mean()) < 1e5)
                for b, band in enumerate(bands))
    path = write_be(usid, tmp_path / "beps.h5", noisy(rng, clean, 0.003), f, bias)
    assert main(["map", str(path), "--model", "sho", "--out", str(tmp_path / "o"), "--no-progress",
                 "--scheduler", "sync"]) == 0
    with h5py.File(tmp_path / "o" / "beps.h5", "r") as h5:
        group = h5["Measurement_000/Channel_000/Raw_Data-SHO_Fit_000"]
        fit = group["Fit"][()]
        values = group["Spectroscopic_Values"]
        assert fit.shape == (NY * NX, 6)
        assert [v.decode() for v in values.attrs["labels"]] == ["DC_Offset", "Band"]
        np.testing.assert_allclose(values[()][0], np.repeat(bias, 2))
        np.testing.assert_allclose(values[()][1], np.tile([300e3, 920e3], 3))
    np.testing.assert_allclose(fit["Frequency [Hz]"], f0.reshape(NY * NX, 6), rtol=2e-4)
    np.testing.assert_allclose(fit["Quality Factor"], q.reshape(NY * NX, 6), rtol=0.05)
    result = open_result(tmp_path / "o")
    assert result["measured_quality_factor"].dims == ("y", "x", "bias", "band")
    assert result["band"].attrs["units"] == "Hz" and result["bias"].values.tolist() == bias.tolist()
    assert result["measured_resonance"].attrs == {"units": "Hz", "long_name": "SHO resonance frequency w0, as measured"}


def test_beam_fit_in_the_same_layout(usid, tmp_path):
    """``--model elastic`` on USID input: a Beam_Fit group whose fields are the maps (k1 of an FE beam)."""
    k, length, f1, height = 2.0, 225e-6, 75e3, 10e-6
    k1 = np.where(np.arange(NX)[None, :] < NX // 2, 150.0, 400.0) * np.ones((NY, 1))
    beams = {v: FEBeam(k, length, f1, height, k1=v, Q=60.0, n_elements=40) for v in (150.0, 400.0)}
    modes = [b.contact_resonances(1)[0] for b in beams.values()]
    f = np.linspace(0.85 * min(modes), 1.15 * max(modes), 48)
    shapes = {v: b.slope(f)[:, 0] for v, b in beams.items()}
    rng = np.random.default_rng(2)
    clean = np.stack([2e-3 * shapes[v] for v in k1.ravel()])
    free = float(FEBeam(k, length, f1, height, n_elements=40).free_resonances(1)[0])
    # the FE beam has k2 = 0: held there (one band cannot tell)
    attrs = {"SpringConstant": k, "CustomLeverLength": length, "tip_height_m": height, "free_resonance_hz": free,
             "k2": 0.0}
    path = write_be(usid, tmp_path / "be.h5", noisy(rng, clean, 0.005), f, attrs=attrs)
    assert main(["map", str(path), "--model", "elastic", "--out", str(tmp_path / "o"), "--no-progress",
                 "--scheduler", "sync"]) == 0
    with h5py.File(tmp_path / "o" / "be.h5", "r") as h5:
        group = h5["Measurement_000/Channel_000/Raw_Data-Beam_Fit_000"]
        fit = group["Fit"][()]
        assert group.attrs["model"] == "elastic" and fit.shape == (NY * NX, 1)
        assert usid.hdf_utils.check_if_main(group["Fit"])
    z = (fit["k1 [N/m]"][:, 0] - k1.ravel()) / fit["k1_stderr [N/m]"][:, 0]
    assert np.mean(np.abs(z) < 3) >= 0.95
    np.testing.assert_array_equal(open_result(tmp_path / "o")["k1"].values.ravel(), fit["k1 [N/m]"][:, 0])


def test_usid_inplace_needs_usid_input_and_the_copy_never_replaces_the_input(usid, tmp_path, capsys):
    path = tmp_path / "plain.h5"
    with h5py.File(path, "w") as h:
        h["response"], h["frequency_hz"] = np.ones((2, 2, 4), complex), np.arange(1.0, 5.0)
    assert main(["map", str(path), "--model", "sho", "--out", str(tmp_path / "o"), "--usid-inplace"]) == 2
    assert "--usid-inplace needs a USID input" in capsys.readouterr().err
    f = np.linspace(290e3, 310e3, 16)
    path = write_be(usid, tmp_path / "be.h5", np.broadcast_to(bglib_sho(f, 1e-3, 0.0, 3e5, 50.0), (NY, NX, 16)), f)
    before = path.read_bytes()
    assert main(["map", str(path), "--model", "sho", "--out", str(tmp_path), "--no-progress"]) == 2
    assert "--out is the input's folder" in capsys.readouterr().err
    assert path.read_bytes() == before and not (tmp_path / "maps.zarr").exists()


@pytest.mark.parametrize("bins", [64, 128])
def test_compiled_sho_fit_is_the_numpy_fit(bins):
    """The compiled fit (:mod:`pfmdyn.maps.sho_kernel`, the default) and its NumPy reference (the
    batched Levenberg-Marquardt of :mod:`pfmdyn.fitting.batched`) on the same spectra: guess and
    fit f0 and Q to 1e-9, amplitude, phase and R2 to 1e-9, noise and gap to 1e-12 (noisy spectra;
    without noise, the residual is rounding).  Q 5-500, resonances across the band and beyond its
    edges, half the spectra noise-free."""
    from pfmdyn.maps.sho import fit_spectra
    rng = np.random.default_rng(90 + bins)
    n = 200
    f = np.linspace(290e3, 310e3, bins)
    p = sho_pixels(rng, f, (5, 500), n, spread=1.3)
    clean = bglib_sho(f, p["amplitude"][:, None], p["phase"][:, None], p["f0"][:, None], p["q"][:, None])
    noisy_rows = np.arange(n) % 2 == 0
    y = np.where(noisy_rows[:, None], noisy(rng, clean, 0.02), clean)
    compiled, reference = fit_spectra(f, y), fit_spectra(f, y, compiled=False)
    assert compiled.keys() == reference.keys()
    for name in ("measured_resonance", "measured_quality_factor", "amplitude", "r2", "guess_measured_resonance",
                 "guess_measured_quality_factor", "guess_amplitude"):
        np.testing.assert_allclose(compiled[name], reference[name], rtol=1e-9, err_msg=name)
    for name in ("phase", "guess_phase"):
        np.testing.assert_allclose(np.exp(1j * compiled[name]), np.exp(1j * reference[name]), atol=1e-9, err_msg=name)
    for name, tolerance in (("gap", 1e-12), ("cost", 1e-9), ("measured_resonance_stderr", 1e-9),
                            ("measured_quality_factor_stderr", 1e-9)):
        np.testing.assert_allclose(compiled[name][noisy_rows], reference[name][noisy_rows], rtol=tolerance,
                                   err_msg=name)
    assert np.all(np.abs(compiled["measured_resonance"] - p["f0"])[~noisy_rows] < 1e-9 * p["f0"][~noisy_rows])
    # shared among threads: the same numbers; a spectrum of zeros, inf or NaN masked
    y[:3] = np.array([0.0, np.inf, np.nan])[:, None]
    threaded, alone = fit_spectra(f, y, threads=2), fit_spectra(f, y)
    for name in compiled:
        np.testing.assert_array_equal(threaded[name], alone[name], err_msg=name)
        assert np.isnan(alone[name][:3]).all() and np.isfinite(alone[name][3:]).all(), name


def test_a_store_begun_under_the_old_names_resumes_under_the_new(usid, tmp_path):
    """The SHO's Q was ``quality_factor`` in stores written before schema 1 (where everywhere else it is the
    lever's internal friction): a run resuming such a store renames the maps (``measured_quality_factor``,
    its stderr and guess), keeps the blocks done, fits the rest; ``open_result`` and the USID write-back
    read the one map."""
    from pfmdyn.maps.sho import RENAMED
    from pfmdyn.maps.store import consolidate, open_group, rename_map

    rng = np.random.default_rng(23)
    f = np.linspace(295e3, 305e3, 48)
    p = sho_pixels(rng, f, (40, 80), NY * NX)
    path = write_be(usid, tmp_path / "be.h5", bglib_sho(f, *(p[k][:, None] for k in ("amplitude", "phase", "f0", "q"))),
                    f)
    args = ["map", str(path), "--model", "sho", "--out", str(tmp_path / "o"), "--no-progress", "--scheduler", "sync",
            "--block", "8"]
    assert main([*args, "--max-blocks", "1"]) == 0
    store = open_group(str(tmp_path / "o" / "maps.zarr"), mode="a")
    first = np.asarray(store["measured_quality_factor"][...])
    for old, new in RENAMED.items():        # as the earlier version wrote it
        rename_map(store, new, old)
    consolidate(str(tmp_path / "o" / "maps.zarr"))
    assert set(RENAMED) <= set(open_result(tmp_path / "o").data_vars)
    assert main(args) == 0
    result = open_result(tmp_path / "o")
    assert not set(RENAMED) & set(result.data_vars) and set(RENAMED.values()) <= set(result.data_vars)
    q = result["measured_quality_factor"].values
    done = np.isfinite(first)
    assert done.any() and not done.all()
    np.testing.assert_array_equal(q[done], first[done])
    np.testing.assert_allclose(q.ravel(), p["q"], rtol=1e-4)      # noise-free spectra: each its own Q
    with h5py.File(tmp_path / "o" / "be.h5", "r") as h5:
        fit = h5["Measurement_000/Channel_000/Raw_Data-SHO_Fit_000"]["Fit"][()]
    np.testing.assert_array_equal(fit["Quality Factor"][:, 0], q.ravel())
