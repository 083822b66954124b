"""Deconvolution of frequency-bias data (Section VI.4, Eq. 41) and the ``pfmdyn deconvolve`` command."""
import csv
import sys
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import cli
from pfmdyn.analysis.deconvolve import deconvolve, nulling_bias, tip_quality
from pfmdyn.io.spectra import read_spectra

# The independent reference lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from segment_beam import spot_response  # noqa: E402

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


def test_surface_potential_not_given_is_zero_and_said_assumed(tmp_path, capsys):
    """One default for every command (diagram's and map's 0 V): stated on the terminal, assumed in the JSON."""
    import json

    data_file = write_csv(tmp_path / "data.csv", *synthetic(0.05, seed=5))
    for potential in (None, V_SURF):
        given = [] if potential is None else ["--surface-potential", str(potential)]
        assert cli.main(["deconvolve", str(data_file), *given, "--out", str(tmp_path / "o"),
                         "--json", str(tmp_path / "d.json")]) == 0
        printed = capsys.readouterr().out
        record = json.loads((tmp_path / "d.json").read_text())["lever"]["surface_potential"]
        assert ("assumed: surface potential 0 V" in printed) == (potential is None)
        assert (record["value"], record["status"]) == ((0.0, "assumed") if potential is None else (V_SURF, "given"))


def test_cli_rejects_an_output_path_that_is_a_file(tmp_path, capsys):
    data_file = write_csv(tmp_path / "data.csv", *synthetic())
    (tmp_path / "taken").write_text("")
    status = cli.main(["deconvolve", str(data_file), "--surface-potential", "0", "--out", str(tmp_path / "taken")])
    assert status == 2
    assert "not a directory" in capsys.readouterr().err


def test_help_states_the_lever_is_optional_and_offers_the_probe_flags():
    """Without lever flags no lever model enters; with them, the spot's calibration (default: the end)."""
    import argparse

    from pfmdyn.commands.deconvolve import add_arguments
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    dests = {a.dest for a in parser._actions}
    assert {"spring_constant", "k1", "spot_position", "tip_position", "width"} <= dests
    assert "no lever model enters" in parser.epilog and "--spot-position, default 1" in parser.epilog


OLD_COLUMNS = ["frequency_hz", "n_bias", "g_elec_x", "g_elec_y", "g_elec_abs", "g_elec_se", "intercept_x",
               "intercept_y", "d_eff_x", "d_eff_y", "d_eff_abs", "d_eff_se", "v_null_v", "v_null_se_v"]


def test_without_a_lever_the_table_is_the_model_free_one(tmp_path):
    data_file = write_csv(tmp_path / "data.csv", *synthetic(0.05, seed=5))
    assert cli.main(["deconvolve", str(data_file), "--surface-potential", "0.4", "--out", str(tmp_path / "o")]) == 0
    lines = (tmp_path / "o" / "deconvolution.csv").read_text().splitlines()
    assert lines[0] == "# surface_potential_v: 0.4" and lines[1].split(",") == OLD_COLUMNS


# --- True surface displacement at the spot, against the independent two-segment beam -------------

BETA1 = 1.8751040687119611  # first root of cos(b) cosh(b) = -1: free lever, massless tip


def _beam_data(p, f1, sigma, frequencies, d1, g_tip, q_per_volt, rng):
    """Frequency-bias data as an instrument gives them: slope at the spot, InvOLS from the static
    force-curve slope at the same spot (1 / theta_d1(beta = 0)), d1 and a tip force plus the
    distributed load both proportional to V - V_surf; rows shuffled."""
    invols = 1.0 / spot_response(0.0, sigma, **p, d1=1.0)[0].real
    rows = []
    for f in frequencies:
        beta = BETA1 * np.sqrt(f / f1)
        t_d1, t_f0, t_q0 = (spot_response(beta, sigma, **p, **{drive: 1.0})[0] for drive in ("d1", "f0", "q0"))
        for v in BIASES[::4]:
            rows.append((f, v, invols * (t_d1 * d1 + (t_f0 * g_tip + t_q0 * q_per_volt) * (v - V_SURF))))
    rows = [rows[i] for i in rng.permutation(len(rows))]
    return [np.array(c) for c in zip(*rows)], invols


def _lever_args(k, f1, L, H, k1, k2, sigma, extra=()):
    return ["--spring-constant", repr(k), "--free-resonance", repr(f1), "--length", repr(L), "--tip-height",
            repr(H), "--k1", repr(k1), "--k2", repr(k2), *(["--spot-position", repr(sigma)] if sigma else []), *extra]


def _reference_poles_and_zeros(p, f1, sigma, low, high):
    """Frequencies in (low, high) Hz where the reference's d1 slope at the spot changes sign:
    through a pole (a contact resonance: large on both sides) or through a zero."""
    f = np.linspace(low, high, 4000)
    s = np.array([spot_response(BETA1 * np.sqrt(x / f1), sigma, **p, d1=1.0)[0].real for x in f])
    i = np.flatnonzero(np.sign(s[1:]) != np.sign(s[:-1]))
    pole = np.abs(s[i]) + np.abs(s[i + 1]) > 10 * np.median(np.abs(s))
    return f[i[pole]], f[i[~pole]]


@pytest.mark.parametrize("sigma", [0.7, None])
def test_cli_recovers_the_true_surface_displacement_at_the_spot(sigma, tmp_path, capsys):
    """Spot at 0.7 L (and at the end by default): d_eff_surface = d1 to 1e-6 wherever determined,
    NaN with a reason around the contact resonance, which the reference places inside that range."""
    k, f1, L, H, k1 = 2.0, 7e4, 2.25e-4, 1.5e-5, 300.0
    p = dict(k=k, L=L, H=H, kvv=k1, kll=0.5 * k1)
    spot = sigma or 1.0
    freqs = np.linspace(0.05, 9.0, 90) * f1
    d1, g_tip, q_per_volt = 12.5 * np.exp(0.4j), 0.02, 0.8       # pm, pm/V per N, pm/V per N/m
    (f, v, r), invols = _beam_data(p, f1, spot, freqs, d1, g_tip, q_per_volt, np.random.default_rng(1))
    data_file = write_csv(tmp_path / "data.csv", f, v, r)
    out = tmp_path / "out"
    assert cli.main(["deconvolve", str(data_file), "--surface-potential", str(V_SURF), "--out", str(out),
                     *_lever_args(k, f1, L, H, k1, 0.5 * k1, sigma)]) == 0
    text = (out / "deconvolution.csv").read_text()
    preamble = [line for line in text.splitlines() if line.startswith("#")]
    assert f"# spot_position: {spot:g}" in preamble and any("d_eff_surface" in x and "(pm" in x for x in preamble)
    with open(out / "deconvolution.csv") as handle:
        rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
    got = np.array([complex(float(x["d_eff_surface_x"]), float(x["d_eff_surface_y"])) for x in rows])
    determined = np.isfinite(got)
    assert determined.sum() > 0.6 * got.size and not determined.all()
    np.testing.assert_allclose(got[determined], d1, rtol=1e-6)
    # the electrostatic slope in surface units: (theta_f0 g + theta_q0 q) / theta_d1 of the reference
    beta = BETA1 * np.sqrt(freqs[determined] / f1)
    ref = [(spot_response(b, spot, **p, f0=g_tip)[0] + spot_response(b, spot, **p, q0=q_per_volt)[0])
           / spot_response(b, spot, **p, d1=1.0)[0] for b in beta]
    g = np.array([complex(float(x["g_elec_surface_x"]), float(x["g_elec_surface_y"])) for x in rows])[determined]
    np.testing.assert_allclose(g, ref, rtol=1e-6)
    undetermined = [line for line in preamble if line.startswith("# undetermined")]
    ranges = [tuple(float(x) for x in line.split()[2].split("-")) for line in undetermined]
    poles, zeros = _reference_poles_and_zeros(p, f1, spot, freqs[0], freqs[-1])
    assert len(poles) >= 1 and len(zeros) >= 1
    for where, words in ((poles, "contact resonance"), (zeros, "a zero of the spot's response")):
        for x in where:
            assert any(lo <= x <= hi and words in line for (lo, hi), line in zip(ranges, undetermined)), (x, ranges)
    assert "true surface displacement at x_s/L" in capsys.readouterr().out


@pytest.mark.parametrize("seed,ends", [(0, None), (1, None), (2, None), (3, None), (4, (0.05, 1.2)), (5, (50.0, 1e4))])
def test_surface_displacement_over_real_levers(seed, ends):
    """k 0.05-50 N/m, k1/k 1-1e4 (random, and at both ends), L 100-500 um, spot 0.5-1, set-back tip:
    d1 to 1e-6 where determined, and the d_eff error of the distributed load as the reference gives it."""
    from pfmdyn.analysis.deconvolve import surface_displacement
    from pfmdyn.analysis.spot import EPSILON_0
    from pfmdyn.cantilever import Cantilever, Contact
    from pfmdyn.generated import formulas
    rng = np.random.default_rng(100 + seed)
    k = 10 ** rng.uniform(np.log10(0.05), np.log10(50))
    k1 = k * 10 ** rng.uniform(0, 4)
    if ends:
        k, k1 = ends[0], ends[0] * ends[1]
    L, H, w = rng.uniform(100e-6, 500e-6), rng.uniform(5e-6, 20e-6), rng.uniform(20e-6, 50e-6)
    f1, gamma, sigma = rng.uniform(1e4, 3e5), float(rng.choice([1.0, rng.uniform(0.9, 1.0)])), rng.uniform(0.5, 1.0)
    p = dict(k=k, L=L, H=H, kvv=k1, kll=0.6 * k1, gamma=gamma)
    q = float(formulas.capacitive_load_per_volt2(EPSILON_0, w, H))
    freqs = np.geomspace(0.02, 12.0, 60) * f1
    (f, v, r), invols = _beam_data(p, f1, sigma, freqs, 3e-12, 0.0, q, rng)
    order = np.lexsort((v, f))
    fit = deconvolve(f[order], v[order], r[order], surface_potential_v=V_SURF)
    lever = Cantilever(k, f1, L, tip_height=H, width=w, tip_position=gamma, spot_position=sigma)
    out = surface_displacement(fit, lever, Contact(k1=k1, k2=0.6 * k1))
    determined = np.isfinite(out.d_eff)
    assert determined.sum() > 0.4 * determined.size
    np.testing.assert_allclose(out.d_eff[determined], 3e-12, rtol=1e-6)
    beta = BETA1 * np.sqrt(freqs / f1)
    error = np.array([invols * spot_response(b, sigma, **p, q0=q)[0].real for b in beta])
    np.testing.assert_allclose(out.d_eff_error_per_volt, error, rtol=1e-6, atol=1e-6 * np.max(np.abs(error)))
    # the measured slope is the distributed load's alone: the reported error is what was measured
    np.testing.assert_allclose(fit.g_elec.real, error, rtol=1e-6, atol=1e-6 * np.max(np.abs(error)))


def test_a_lever_missing_its_k1_is_one_line_and_writes_nothing(tmp_path, capsys):
    data_file = write_csv(tmp_path / "data.csv", *synthetic())
    status = cli.main(["deconvolve", str(data_file), "--surface-potential", "0", "--out", str(tmp_path / "o"),
                       "--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4"])
    err = capsys.readouterr().err.strip()
    assert status == 2 and "give --k1" in err and "tip" not in err and "\n" not in err and not (tmp_path / "o").exists()


def test_a_lever_without_its_tip_height_takes_the_typical_one(tmp_path, capsys):
    """No --tip-height: the typical PFM probe's (13 um), as every command takes it, said and marked assumed;
    the surface displacement is the reference's on a lever of that tip height (k2 = 0.5 k1 acts through it)."""
    import json
    k, f1, L, k1 = 2.0, 7e4, 2.25e-4, 300.0
    p = dict(k=k, L=L, H=13e-6, kvv=k1, kll=0.5 * k1)
    freqs = np.linspace(0.05, 3.0, 24) * f1
    (f, v, r), _ = _beam_data(p, f1, 1.0, freqs, 12.5, 0.02, 0.0, np.random.default_rng(2))
    data_file = write_csv(tmp_path / "data.csv", f, v, r)
    args = _lever_args(k, f1, L, 13e-6, k1, 0.5 * k1, None)
    del args[args.index("--tip-height"):args.index("--tip-height") + 2]
    assert cli.main(["deconvolve", str(data_file), "--surface-potential", str(V_SURF), "--out", str(tmp_path / "o"),
                     "--json", str(tmp_path / "d.json"), *args]) == 0
    assert "assumed: tip height 1.3e-05 m (a typical PFM probe's" in capsys.readouterr().out
    assert json.loads((tmp_path / "d.json").read_text())["lever"]["tip_height"]["status"] == "assumed"
    with open(tmp_path / "o" / "deconvolution.csv") as handle:
        rows = list(csv.DictReader(line for line in handle if not line.startswith("#")))
    got = np.array([complex(float(x["d_eff_surface_x"]), float(x["d_eff_surface_y"])) for x in rows])
    determined = np.isfinite(got)
    assert determined.sum() > 0.5 * got.size
    np.testing.assert_allclose(got[determined], 12.5, rtol=1e-6)


def test_calibration_is_that_of_pfmdyn_spot():
    """deconvolve's calibration factor and d_eff error at a frequency are pfmdyn spot's there."""
    from pfmdyn.analysis.deconvolve import surface_displacement
    from pfmdyn.analysis.spot import spot_analysis
    from pfmdyn.cantilever import Cantilever, Contact
    lever = Cantilever(0.8, 6e4, 3e-4, tip_height=1.2e-5, width=3e-5, tip_position=0.95, tip_mass_ratio=0.1,
                       tilt=11.0, spot_position=0.75)
    contact = Contact(k1=120.0, k2_over_k1=0.7)
    fit = deconvolve([45e3] * 3, [-1.0, 0.0, 1.0], [1, 2, 3], surface_potential_v=0.0)
    mine, spot = surface_displacement(fit, lever, contact), spot_analysis(lever, contact, 45e3, positions=5)
    assert mine.calibration_factor[0] == pytest.approx(spot.calibration_factor.real, rel=1e-12)
    assert mine.d_eff_error_per_volt[0] == pytest.approx(spot.d_eff_error_per_volt.real, rel=1e-12)
    assert abs(mine.calibration_factor[0] - 1) > 1e-3        # the frequency matters at all


def test_a_response_the_bias_does_not_change_leaves_the_nulling_bias_undetermined(tmp_path, capsys):
    """A pure piezoresponse (G_elec = 0 at every frequency): no 'nan' printed, no RuntimeWarning, the
    nulling bias and its spread undetermined with why, in print and in JSON."""
    import json
    import warnings

    data = tmp_path / "flat.csv"
    data.write_text("frequency_hz,bias_v,x,y\n" + "".join(f"{f},{v},2.5,-0.5\n" for f in (1e5, 2e5) for v in (-1, 1)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cli.main(["deconvolve", str(data), "--surface-potential", "0", "--out", str(tmp_path / "o"),
                         "--json", str(tmp_path / "d.json")]) == 0
    out = capsys.readouterr().out
    assert "nan" not in out and "nulling bias: undetermined at every frequency" in out
    results = json.loads((tmp_path / "d.json").read_text())["results"]
    assert results["mean_nulling_bias"]["status"] == results["nulling_bias_spread"]["status"] == "undetermined"


def _one_setpoint_rows(setpoints, frequencies, sigma, rng):
    """Rows at frequencies measured at one bias only, once per value of ``setpoints`` (one setpoint
    written as computed: e.g. ``-0.3 + 3 * 0.1`` beside 0), from the same truth and noise."""
    f, v = np.repeat(frequencies, len(setpoints)), np.tile(setpoints, len(frequencies))
    noise = rng.normal(0.0, sigma, (2, f.size))
    return f, v, d_eff_true(f) + g_elec_true(f) * (v - V_SURF) + noise[0] + 1j * noise[1]


@pytest.mark.parametrize("setpoints", [[0.1] * 3, [-2.7] * 3, [0.0, -0.3 + 3 * 0.1, 0.1 * 3 - 0.3]])
def test_a_line_through_one_setpoint_has_no_slope(setpoints):
    """Frequencies measured at one bias several times (the mean of equal biases off them by an ulp,
    or one bias written as computed), beside frequencies measured at the 21 biases, rows shuffled:
    the one-setpoint lines have no slope, nor intercept (NaN, no warning), the others are the
    truth within the noise."""
    from pfmdyn.fitting.bias_line import bias_lines
    rng = np.random.default_rng(7)
    extra = np.linspace(610e3, 700e3, 8)
    one_setpoint = _one_setpoint_rows(setpoints, extra, 0.01, rng)
    rows = [np.concatenate(pair) for pair in zip(synthetic(0.01, seed=6), one_setpoint)]
    order = rng.permutation(rows[0].size)
    with np.errstate(all="raise"):
        lines = bias_lines(*(a[order] for a in rows))
    one = np.isin(lines.frequency_hz, extra)
    assert np.all(np.isnan(lines.slope[one])) and np.all(np.isnan(lines.intercept[one]))
    assert np.all(lines.spread[one] == 0)
    at = lines.frequency_hz[~one]
    se = 0.01 / np.sqrt(np.sum((BIASES - BIASES.mean()) ** 2))      # of each part of the slope
    assert np.max(np.abs(lines.slope[~one] - g_elec_true(at))) < 5 * 2**0.5 * se


def test_cli_refuses_frequencies_at_one_setpoint_written_two_ways(tmp_path, capsys):
    """A spectrum whose frequencies beyond the bias ladder were swept twice at 0 V, the bias written
    as 0 and as computed (5.6e-17): one line naming the frequency, exit status 2, nothing written
    (it was G_elec ~1e15 pm/V there, silently)."""
    rng = np.random.default_rng(8)
    extra = np.linspace(610e3, 700e3, 6)
    rows = [np.concatenate(pair) for pair in zip(synthetic(0.05, seed=9),
                                                 _one_setpoint_rows([0.0, -0.3 + 3 * 0.1], extra, 0.05, rng))]
    order = rng.permutation(rows[0].size)
    data_file = write_csv(tmp_path / "data.csv", *(a[order] for a in rows))
    out = tmp_path / "out"
    assert cli.main(["deconvolve", str(data_file), "--surface-potential", str(V_SURF), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "610000 Hz" in err and "two distinct biases" in err, err
    assert not out.exists()


REAL = Path(__file__).resolve().parents[2] / "shared" / "realdata" / "asylum_pfm_images"


@pytest.mark.parametrize("name", ["IgorIBWReader_P0089OP0027.ibw", "PMN28Pt0000.h5"])
def test_cli_names_an_instrument_file_as_such(name, tmp_path, capsys):
    """An Asylum image or a pycroscopy file given to deconvolve: one line naming the file and what it is
    (it said 'not a UTF-8 text file'), exit 2, nothing written."""
    path = REAL / name
    if not path.exists():
        pytest.skip("the shared real data are absent")
    out = tmp_path / "out"
    assert cli.main(["deconvolve", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and name in err[0] and "an instrument file" in err[0] and "frequency-bias table" in err[0]
    assert not out.exists()
