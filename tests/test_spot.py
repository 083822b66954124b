"""The detection point, blind spots and ``pfmdyn spot`` against an independent exact beam.

The reference is :mod:`tests.segment_beam` (the exact solution on two segments, solved
numerically with NumPy; no ``derivations/`` or ``generated/``).  Blind spots of the
reference are found by bracketing and ``scipy.optimize.brentq`` on its ``q0`` slope.
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from pfmdyn.analysis.spot import blind_spots, parameters, sensitivities, spot_analysis
from pfmdyn.cantilever import Cantilever, Contact
from pfmdyn.cli import main
from pfmdyn import composed
from pfmdyn.generated.characteristic import BETA1_FREE

# The independent reference lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from segment_beam import spot_response  # noqa: E402

DRIVES = ("d1", "d2", "f0", "q0")


def _random_lever(rng):
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    k1 = k * 10 ** rng.uniform(0, 4)
    return dict(k=k, L=rng.uniform(100e-6, 500e-6), H=rng.uniform(5e-6, 20e-6), kvv=k1,
                kll=k1 * rng.uniform(0, 1.2), kvl=k1 * rng.uniform(-0.2, 0.2), mu=rng.uniform(0, 0.3),
                gamma=float(rng.choice([1.0, rng.uniform(0.85, 1.0)])), rho_g=rng.uniform(0, 0.05))


@pytest.mark.parametrize("seed", range(6))
def test_slope_and_deflection_match_the_segment_beam(seed):
    """Every drive, both sides of the tip, x_s/L in 0.3-1, several frequencies: 1e-7 of the range."""
    rng = np.random.default_rng(seed)
    p = _random_lever(rng)
    sigma = np.sort(rng.uniform(0.3, 1.0, 25))
    for beta in (0.5, 1.7, 3.3, 6.1):
        lever = composed.Parameters(**p)
        got = composed.slope(beta, lever, sigma), composed.deflection(beta, lever, sigma)
        for i, drive in enumerate(DRIVES):
            ref = np.array([spot_response(beta, s, **p, **{drive: 1.0}) for s in sigma]).T
            for g, r in zip((got[0][i], got[1][i]), ref):
                assert np.max(np.abs(g - r)) <= 1e-7 * np.max(np.abs(r)), (drive, beta, p)


def test_jacobian_in_the_spot_position_is_the_slope_derivative():
    """d(slope)/d(sigma) of the composed lever against a central difference of the reference."""
    p = _random_lever(np.random.default_rng(7))
    sigma, h = np.array([0.45, 0.7, 0.93]), 1e-6
    _, jac = composed.slope_and_jacobian(2.2, composed.Parameters(**p), sigma, wrt=("sigma",))
    column = composed.SPOT_JACOBIAN_PARAMETERS.index("sigma")
    for i, drive in enumerate(DRIVES):
        ref = [(spot_response(2.2, s + h, **p, **{drive: 1.0})[0] - spot_response(2.2, s - h, **p, **{drive: 1.0})[0])
               / (2 * h) for s in sigma]
        np.testing.assert_allclose(jac[i][column], ref, rtol=1e-5, atol=1e-6 * np.max(np.abs(ref)))


def _reference_blind_spots(lever, contact, beta: float) -> list[float]:
    """Zeros in (0, 1] of the reference q0 slope (bracketed on a fine grid, then brentq)."""
    p = parameters(lever, contact)

    def slope(s):
        return spot_response(beta, s, **p, q0=1.0)[0].real
    grid = np.linspace(0.02, 1.0, 400)
    values = [slope(s) for s in grid]
    return [brentq(slope, a, b, xtol=1e-13) for a, b, fa, fb in zip(grid, grid[1:], values, values[1:])
            if fa * fb < 0]


HELD_OUT = [(k1_over_k, beta) for k1_over_k in (12.0, 30.0, 100.0, 1e3, 1e4) for beta in (0.0, 1.0, 2.0)]


@pytest.mark.parametrize("k1_over_k,beta", HELD_OUT)
def test_pfmdyn_spot_matches_held_out_blind_spots(k1_over_k, beta, tmp_path):
    """``pfmdyn spot`` (JSON key ``blind_spot``) against the reference to 5e-5 L, quasi-static
    (the reference at beta = 0, pfmdyn at f = 1e-4 f1) and below the first contact resonance."""
    k, f1 = 2.0, 70e3
    lever, contact = Cantilever(k, f1, 225e-6, tip_height=15e-6), Contact(k1=k1_over_k * k, k2=0.4 * k1_over_k * k)
    expected = _reference_blind_spots(lever, contact, beta)
    frequency = 1e-4 * f1 if beta == 0 else f1 * (beta / BETA1_FREE) ** 2
    out = tmp_path / "spot.json"
    assert main(["spot", "--spring-constant", str(k), "--free-resonance", str(f1), "--length", "225e-6",
                 "--tip-height", "15e-6", "--k1", str(contact.k1), "--k2", str(contact.k2),
                 "--drive-frequency", repr(frequency), "--json", str(out)]) == 0
    found = json.loads(out.read_text())["results"]["blind_spot"]["value"]
    assert len(found) == len(expected) >= 1
    np.testing.assert_allclose(found, expected, atol=5e-5)


def test_blind_spot_with_the_tip_set_back_and_tilt():
    """Set-back tip, tip mass and tilt: the certified zeros equal the reference's."""
    lever = Cantilever(0.8, 6e4, 3e-4, tip_height=1.2e-5, tip_position=0.93, tip_mass_ratio=0.1, tilt=11.0)
    contact = Contact(k1=80.0, k2=50.0)
    for beta in (0.7, 2.4):
        found = blind_spots(lever, contact, beta)
        assert found.certified
        np.testing.assert_allclose(found.positions, _reference_blind_spots(lever, contact, beta), atol=1e-8)


def test_stiff_pinned_tip_approaches_the_closed_form():
    """k1/k -> oo, k2 = 0, low frequency: (15 - sqrt(33))/16."""
    lever = Cantilever(1.0, 7e4, 2.25e-4, tip_height=1.5e-5)
    (position,) = blind_spots(lever, Contact(k1=1e7), 0.01).positions
    assert abs(position - (15 - math.sqrt(33)) / 16) < 1e-5


def test_soft_contact_has_no_static_blind_spot():
    """Static end slope per q0 is proportional to 8k - k1 (Eq. 14): none below k1 = 8k."""
    for k1_over_k, count in ((4.0, 0), (7.5, 0), (9.0, 1)):
        lever = Cantilever(1.0, 7e4, 2.25e-4, tip_height=1.5e-5)
        assert len(blind_spots(lever, Contact(k1=k1_over_k), 0.01).positions) == count


def test_local_force_reads_as_d1_over_k1_everywhere():
    """No tilt: theta_f0 = theta_d1 / k1 at every spot and frequency (no separate blind spot)."""
    p = {**_random_lever(np.random.default_rng(3)), "kvl": 0.0}
    sigma = np.linspace(0.3, 1, 11)
    for beta in (0.8, 4.0):
        s = composed.slope(beta, composed.Parameters(**p), sigma)
        np.testing.assert_allclose(s[2] * p["kvv"], s[0], rtol=1e-9)


def test_static_sensitivity_free_and_in_contact():
    """Free: 2/(3 sigma (2 - sigma)) (2/3 at the end: A = 2 theta L/3); in contact: the reference."""
    lever, contact = Cantilever(3.0, 8e4, 2e-4, tip_height=1e-5), Contact(k1=500.0, k2=300.0)
    for sigma in (0.6, 0.8, 1.0):
        s = sensitivities(lever, contact, sigma)
        assert abs(s["free"] - 2 / (3 * sigma * (2 - sigma))) < 1e-6
        theta = spot_response(0.0, sigma, **parameters(lever, contact), d1=1.0)[0].real
        assert abs(s["contact"] - 1 / (lever.length * theta)) < 1e-6 * abs(s["contact"])


def test_calibration_factor_and_d_eff_error_at_the_spot():
    """At a blind spot the d_eff error vanishes; the calibration factor is 1 at low frequency."""
    lever, contact = Cantilever(2.0, 7e4, 2.25e-4, tip_height=1.5e-5, width=3.5e-5, spot_position=0.9), Contact(k1=400.0)
    low = spot_analysis(lever, contact, 70.0, positions=20)
    assert abs(low.calibration_factor - 1) < 1e-6
    (blind,) = low.blind_spot.positions
    at_blind = spot_analysis(replace(lever, spot_position=blind), contact, 70.0, positions=20)
    assert abs(at_blind.d_eff_error_per_volt) < 1e-6 * abs(low.d_eff_error_per_volt)
    assert spot_analysis(replace(lever, width=None), contact, 70.0, positions=20).d_eff_error_per_volt is None


@pytest.mark.parametrize("argv,message", [
    (["--k1", "-3"], "--k1"),
    (["--tip-position", "1.2"], "--tip-position"),
    (["--spot-position", "0"], "--spot-position"),
    (["--drive-frequency", "0"], "--drive-frequency"),
])
def test_bad_input_is_one_line(argv, message, capsys, tmp_path):
    base = {"--spring-constant": "2", "--free-resonance": "7e4", "--length": "2e-4", "--tip-height": "1e-5",
            "--k1": "100", "--drive-frequency": "1e4"}
    for flag, value in zip(argv[::2], argv[1::2]):
        base[flag] = value
    out = tmp_path / "x.json"
    args = [x for item in base.items() for x in item] + ["--json", str(out)]
    assert main(["spot", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and not out.exists()


def test_missing_lever_value_names_its_flag(capsys):
    args = ["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--k1", "100", "--drive-frequency", "1e4"]
    assert main(args) == 2
    assert "give --length" in capsys.readouterr().err
    assert main([*args, "--length", "2e-4"]) == 0      # no tip height: the typical PFM probe's, said
    assert "assumed: tip height 1.3e-05 m" in capsys.readouterr().out


def test_the_probe_and_the_map_model_read_the_lever_at_the_spot():
    """``Cantilever.response`` and the map model with ``spot_position`` against the independent
    two-segment beam (set-back, heavy, tilted tip with rotary inertia), and a map fit at the spot
    recovers k1 (the composed partials w.r.t. the springs at the spot drive it there)."""
    from pfmdyn import Cantilever, Contact
    from pfmdyn.generated.tilt_rotation import rotated
    from pfmdyn.maps.beam import BeamMapModel
    from pfmdyn.maps.fit import fit_block
    rng = np.random.default_rng(21)
    for _ in range(3):
        k, length, height = 10 ** rng.uniform(-1, 1.5), rng.uniform(150e-6, 450e-6), rng.uniform(5e-6, 20e-6)
        lever = Cantilever(k, rng.uniform(2e4, 3e5), length, tip_height=height, spot_position=rng.uniform(0.5, 0.95),
                           tip_position=rng.uniform(0.9, 1.0), tip_mass_ratio=rng.uniform(0, 0.2),
                           tip_gyration_radius=rng.uniform(0, 0.3) * height, tilt=rng.uniform(0, 15))
        k1 = k * 10 ** rng.uniform(1, 3)
        f = lever.free_resonance * np.geomspace(0.5, 8, 40)
        got = lever.response(f, Contact(k1=k1, k2=0.5 * k1)).vertical
        kvv, kll, kvl = rotated(k1, 0.5 * k1, lever.alpha)
        ref = [spot_response(b, lever.spot_position, k=k, L=length, H=height, kvv=kvv, kll=kll, kvl=kvl,
                             mu=lever.tip_mass_ratio, gamma=lever.tip_position, rho_g=lever.rho_g, d1=1.0)[0]
               for b in lever.beta(f).real]
        np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9 * np.max(np.abs(ref)))
        model = BeamMapModel(lever, f, contact=Contact(k2_over_k1=0.5))
        shape = model.shape_functions(np.array([k1]), np.array([np.inf]))[0]
        np.testing.assert_allclose(shape, ref, rtol=1e-7, atol=1e-9 * np.max(np.abs(ref)))
    band = lever.free_resonance * np.linspace(2.0, 7.0, 96)
    model = BeamMapModel(lever, band, contact=Contact(k2_over_k1=0.5))
    truth = k * np.array([30.0, 300.0])
    out = fit_block(model, 1e-3 * model.shape_functions(truth, np.array([80.0, 150.0])))
    np.testing.assert_allclose(out["k1"], truth, rtol=1e-6)


def test_a_real_calibration_factor_is_printed_as_a_real_number(capsys):
    """The lossless lever's factors are real: '+3.7', not '+3.7+0j'."""
    assert main(["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4",
                 "--tip-height", "1e-5", "--k1", "100", "--drive-frequency", "3e5"]) == 0
    [line] = [line for line in capsys.readouterr().out.splitlines() if "measured/true d_eff" in line]
    assert "j " not in line and "0j" not in line, line


def test_drive_frequency_under_its_name_and_its_old_flag(tmp_path, capsys):
    """spot called the drive frequency --frequency and JSON 'frequency', where files and inspect call it
    drive_frequency: now --drive-frequency and results.drive_frequency, the old flag still read (hidden)."""
    base = ["spot", "--spring-constant", "2", "--free-resonance", "7e4", "--length", "2e-4", "--tip-height", "1e-5",
            "--k1", "100"]
    docs = {}
    for flag in ("--drive-frequency", "--frequency"):
        out = tmp_path / f"{flag}.json"
        assert main([*base, flag, "3e4", "--json", str(out)]) == 0
        docs[flag] = json.loads(out.read_text())["results"]
    assert docs["--frequency"] == docs["--drive-frequency"] and "frequency" not in docs["--frequency"]
    assert docs["--drive-frequency"]["drive_frequency"]["value"] == 3e4
    assert "drive frequency 30000 Hz" in capsys.readouterr().out


@pytest.mark.parametrize("k, k1, spot", [(0.3, 40.0, 0.7), (12.0, 3000.0, 0.9)])
def test_a_given_k1_uncertainty_moves_the_contact_sensitivity_as_the_independent_beam(tmp_path, k, k1, spot):
    """``--k1-uncertainty U``: the contact sensitivity's k1 part is half the independent beam's change of
    ``1 / (L theta_d1(x_s))`` (static) from k1 - U to k1 + U (k2 tied at 0.85, moving with it)."""
    L, H, u = 225e-6, 12e-6, 0.1 * k1

    def sensitivity(k1):
        theta = spot_response(0.0, spot, k=k, L=L, H=H, kvv=k1, kll=0.85 * k1, d1=1.0)[0].real
        return 1.0 / (L * theta)
    want = abs(sensitivity(k1 + u) - sensitivity(k1 - u)) / 2
    argv = ["spot", "--spring-constant", repr(k), "--free-resonance", "6e4", "--length", repr(L), "--tip-height",
            repr(H), "--k1", repr(k1), "--k2-over-k1", "0.85", "--spot-position", repr(spot), "--drive-frequency",
            "1e4", "--quiet"]
    stderr = {}
    for extra in ([], ["--k1-uncertainty", repr(u)]):
        out = tmp_path / "s.json"
        assert main(argv + extra + ["--json", str(out)]) == 0
        stderr[bool(extra)] = json.loads(out.read_text())["results"]["contact_sensitivity"]["stderr"]
    assert math.sqrt(stderr[True] ** 2 - stderr[False] ** 2) == pytest.approx(want, rel=1e-6)
