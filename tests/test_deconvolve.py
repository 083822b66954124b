"""Deconvolution of frequency-bias data (Section VI.4, Eq. 41) and the ``pfmdyn deconvolve`` command."""
import csv

import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.analysis.deconvolve import deconvolve, nulling_bias, tip_quality
from pfmdyn.io.spectra import read_spectra

V_SURF = 0.4
BIASES = np.linspace(-5, 5, 21)
FREQUENCIES = np.linspace(20e3, 600e3, 60)


def oscillator(f, f0, q):
    return 1.0 / (1 - (f / f0) ** 2 + 1j * f / (q * f0))


def g_elec_true(f):
    """Electrostatic slope: a contact resonance plus a cantilever mode (complex, pm/V per V)."""
    return 2.0 * oscillator(f, 300e3, 40) + 0.8 * oscillator(f, 75e3, 15)


def d_eff_true(f, real_ratio=False):
    """Electromechanical response: the contact resonance only, so d_eff/G_elec varies with f."""
    d_eff = 5.0 * np.exp(0.3j) * oscillator(f, 300e3, 40)
    return np.real(d_eff / g_elec_true(f)) * g_elec_true(f) if real_ratio else d_eff


def synthetic(sigma=0.0, seed=0, real_ratio=False, frequencies=FREQUENCIES):
    f, v = (a.ravel() for a in np.meshgrid(frequencies, BIASES, indexing="ij"))
    response = d_eff_true(f, real_ratio) + g_elec_true(f) * (v - V_SURF)
    noise = np.random.default_rng(seed).normal(0.0, sigma, (2, f.size))
    return f, v, response + noise[0] + 1j * noise[1]


def write_csv(path, f, v, response, polar=False, metadata=("response_unit: pm",)):
    with open(path, "w", newline="") as handle:
        handle.writelines(f"# {line}\n" for line in metadata)
        writer = csv.writer(handle)
        if polar:
            writer.writerow(["frequency_hz", "bias_v", "amplitude", "phase_deg"])
            writer.writerows(zip(f, v, np.abs(response), np.degrees(np.angle(response))))
        else:
            writer.writerow(["frequency_hz", "bias_v", "x", "y"])
            writer.writerows(zip(f, v, response.real, response.imag))
    return path


def test_noise_free_data_is_recovered_exactly():
    fit = deconvolve(*synthetic(), surface_potential_v=V_SURF)
    np.testing.assert_allclose(fit.g_elec, g_elec_true(FREQUENCIES), rtol=1e-12)
    np.testing.assert_allclose(fit.d_eff, d_eff_true(FREQUENCIES), rtol=1e-11)
    assert np.max(np.abs(fit.residual)) < 1e-12
    assert fit.n_bias.tolist() == [len(BIASES)] * len(FREQUENCIES)


def test_noisy_data_is_recovered_within_the_noise():
    sigma = 0.05
    fit = deconvolve(*synthetic(sigma, seed=1), surface_potential_v=V_SURF)
    sxx = np.sum((BIASES - BIASES.mean()) ** 2)
    se_slope = sigma / np.sqrt(sxx)
    se_d_eff = sigma * np.sqrt(1 / len(BIASES) + (V_SURF - BIASES.mean()) ** 2 / sxx)
    for estimate, truth, se in ((fit.g_elec, g_elec_true(FREQUENCIES), se_slope),
                                (fit.d_eff, d_eff_true(FREQUENCIES), se_d_eff)):
        z = np.concatenate([(estimate - truth).real, (estimate - truth).imag]) / se
        # 120 independent standard normals: max |z| > 4.5 has probability ~1e-3, and the
        # mean square is chi2(120)/120 with standard deviation 0.13.
        assert np.max(np.abs(z)) < 4.5
        assert abs(np.mean(z**2) - 1) < 4 * np.sqrt(2 / z.size)
    # The reported standard errors estimate the true ones (chi2(38)/38 per frequency).
    np.testing.assert_allclose(np.median(fit.g_elec_se) / se_slope, 1.0, atol=0.1)
    np.testing.assert_allclose(np.median(fit.d_eff_se) / se_d_eff, 1.0, atol=0.1)
    assert np.std(np.concatenate([fit.residual.real, fit.residual.imag])) == pytest.approx(sigma, rel=0.05)


def test_nulling_bias_standard_error_matches_the_scatter_of_repeated_fits():
    frequencies = np.full(1, 250e3)
    estimates, reported = [], []
    for seed in range(300):
        fit = deconvolve(*synthetic(0.3, seed, frequencies=frequencies), surface_potential_v=V_SURF)
        estimates.append(fit.v_null[0])
        reported.append(fit.v_null_se[0])
    # 300 repeats: the sample standard deviation is within ~4% (1 sigma) of the true one.
    np.testing.assert_allclose(np.std(estimates, ddof=1) / np.median(reported), 1.0, atol=0.15)


def test_nulling_bias_is_surface_potential_minus_d_eff_over_g_elec_for_real_ratios():
    fit = deconvolve(*synthetic(real_ratio=True), surface_potential_v=V_SURF)
    ratio = d_eff_true(FREQUENCIES, real_ratio=True) / g_elec_true(FREQUENCIES)
    assert np.max(np.abs(ratio.imag)) < 1e-12
    np.testing.assert_allclose(fit.v_null, V_SURF - ratio.real, rtol=1e-10, atol=1e-10)
    # At the nulling bias the fitted response vanishes.
    assert np.max(np.abs(fit.intercept + fit.g_elec * fit.v_null)) < 1e-10


def test_nulling_bias_minimises_the_fitted_amplitude_for_complex_ratios():
    b, c = np.array([1 + 2j, -3 + 0.5j]), np.array([0.5 - 1j, 2 + 2j])
    v = np.linspace(-20, 20, 400001)
    brute = v[np.argmin(np.abs(b[:, None] + c[:, None] * v), axis=1)]
    np.testing.assert_allclose(nulling_bias(b, c), brute, atol=1e-4)


def test_tip_quality_separates_good_and_worn_tips():
    good = deconvolve(*synthetic(0.05, seed=2), surface_potential_v=V_SURF)
    f, v, response = synthetic(0.05, seed=3)
    # A worn tip: the electromechanical contribution has almost gone.
    worn = deconvolve(f, v, response - 0.98 * d_eff_true(f), surface_potential_v=V_SURF)
    good_quality = tip_quality(good.v_null, good.v_null_se)
    worn_quality = tip_quality(worn.v_null, worn.v_null_se)
    assert good_quality.spread_v > 10 * worn_quality.spread_v
    assert worn_quality.mean_v == pytest.approx(V_SURF, abs=0.1)


def test_tip_quality_falls_back_to_equal_weights_without_usable_errors():
    assert tip_quality([1.0, 3.0, np.nan], [0.0, 0.0, 1.0]) == tip_quality([1.0, 3.0])
    assert tip_quality([1.0, 3.0], [1.0, 0.5]).mean_v == pytest.approx(2.6)


def test_two_biases_give_exact_lines_and_nan_errors():
    fit = deconvolve([1e5, 1e5], [0.0, 2.0], [1.0, 5.0], surface_potential_v=0.0)
    assert complex(fit.g_elec[0]) == 2.0 and np.isnan(fit.g_elec_se[0]) and np.isnan(fit.v_null_se[0])


def test_both_column_variants_give_the_same_result(tmp_path):
    data = synthetic(0.05, seed=4)
    cartesian = read_spectra(write_csv(tmp_path / "xy.csv", *data))
    polar = read_spectra(write_csv(tmp_path / "polar.csv", *data, polar=True))
    assert cartesian.response_columns == ("x", "y") and polar.response_columns == ("amplitude", "phase_deg")
    fits = [deconvolve(d.frequency_hz, d.bias_v, d.response, V_SURF) for d in (cartesian, polar)]
    for name in ("g_elec", "d_eff", "v_null", "v_null_se", "residual"):
        np.testing.assert_allclose(getattr(fits[0], name), getattr(fits[1], name), rtol=1e-9, atol=1e-12)


def test_cli_writes_tables_and_plots(tmp_path, capsys):
    data_file = write_csv(tmp_path / "data.csv", *synthetic(0.05, seed=5))
    out = tmp_path / "out"
    status = cli.main(["deconvolve", str(data_file), "--surface-potential", str(V_SURF), "--out", str(out)])
    assert status == 0
    names = {"deconvolution.csv", "error_map.csv", "spectra.png", "nulling_bias.png", "error_map.png"}
    assert {p.name for p in out.iterdir()} == names
    for png in out.glob("*.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(out / "deconvolution.csv") as handle:
        assert handle.readline().strip() == f"# surface_potential_v: {V_SURF}"
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(FREQUENCIES)
    np.testing.assert_allclose([float(r["g_elec_abs"]) for r in rows], np.abs(g_elec_true(FREQUENCIES)), rtol=0.1)
    with open(out / "error_map.csv") as handle:
        assert sum(1 for _ in csv.DictReader(handle)) == len(FREQUENCIES) * len(BIASES)
    printed = capsys.readouterr().out
    assert "frequencies: 60" in printed and "biases per frequency: 21" in printed
    assert "median |d_eff|" in printed and "pm" in printed and "tip-quality indicator" in printed


def test_cli_rejects_an_output_path_that_is_a_file(tmp_path, capsys):
    data_file = write_csv(tmp_path / "data.csv", *synthetic())
    (tmp_path / "taken").write_text("")
    status = cli.main(["deconvolve", str(data_file), "--surface-potential", "0", "--out", str(tmp_path / "taken")])
    assert status == 2
    assert "not a directory" in capsys.readouterr().err


def test_help_says_no_lever_model_enters_and_offers_no_probe_flags():
    """deconvolve fits a line in the bias per frequency: a probe flag would change nothing, so there is none."""
    import argparse

    from pfmdyn.commands.deconvolve import add_arguments
    from pfmdyn.names import NAMES
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    assert not [a.dest for a in parser._actions if a.dest in NAMES]
    assert "No lever model enters" in parser.epilog and "no --spot-position" in parser.epilog
