"""``pfmdyn resonances`` against an independent route: the finite-element lever of tests/fe_beam.py
with set-back, a massive tip with rotary inertia, explicitly inclined springs (public tilt) and
k2 = 0.85 k1; the damped modes against the FE's complex eigenvalues and its dense response."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import FEBeam, random_probe  # noqa: E402
from pfmdyn import Cantilever, Contact, cli  # noqa: E402
from pfmdyn.analysis.resonances import resonances  # noqa: E402

N_ELEMENTS = 100


def _probe(seed):
    """A random probe (:func:`fe_beam.random_probe`), its contact and its FE twin."""
    fe, p = random_probe(np.random.default_rng(seed), N_ELEMENTS)
    lever = Cantilever(**{n: v for n, v in p.items() if n not in ("k1", "k2")})
    return lever, Contact(k1=p["k1"], k2_over_k1=0.85), fe


@pytest.mark.parametrize("seed", range(4))
def test_undamped_resonances_match_finite_elements(seed):
    lever, contact, fe = _probe(seed)
    result = resonances(lever, contact, modes=3)
    assert result.certified
    np.testing.assert_allclose(result.free.hz, fe.free_resonances(3), rtol=2e-5)
    np.testing.assert_allclose(result.in_contact.hz, fe.contact_resonances(3), rtol=2e-5)
    for modes in (result.free, result.in_contact):
        assert all(lo <= f <= hi for f, (lo, hi) in zip(modes.hz, modes.intervals_hz))
        assert modes.complete_below_hz >= modes.hz[-1]


def _fe_complex_modes(fe: FEBeam, count: int, scale_hz: float) -> np.ndarray:
    """Complex frequencies (Hz) of the damped FE lever: ``(Kc + lam C + lam**2 M) v = 0``, ``lam = i omega``,
    linearised; ``lam`` in units of ``2 pi scale_hz`` and the matrices in units of ``|M|`` keep the
    pencil balanced (unscaled, QZ loses percents on the lowest mode)."""
    K, T, M, C, D, _, _ = fe._matrices(parts=True)
    Kc = K * (1 + 1j / fe.Q if math.isfinite(fe.Q) else 1) + T
    s, m = 2 * math.pi * scale_hz, np.abs(M).max()
    n = len(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Kc / (s * s * m), -(C + D) / (s * m)]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M / m]])
    omega = -1j * s * scipy.linalg.eigvals(A, B)
    omega = omega[np.isfinite(omega) & (omega.real > 0)]
    return np.sort_complex(omega)[:count] / (2 * math.pi)


def _fe_peak(fe: FEBeam, centre_hz, width_hz, drive: int) -> float:
    """The amplitude peak of the FE tip slope by dense evaluation and a parabola through the top."""
    f = np.linspace(centre_hz - 3 * width_hz, centre_hz + 3 * width_hz, 1201)
    a = np.abs(fe.slope(f)[:, drive])
    i = int(np.argmax(a))
    y0, y1, y2 = a[i - 1], a[i], a[i + 1]
    return float(f[i] + 0.5 * (f[1] - f[0]) * (y0 - y2) / (y0 - 2 * y1 + y2))


@pytest.mark.parametrize("seed, mechanism", [(10, "internal"), (11, "viscous"), (12, "contact")])
def test_damped_modes_match_finite_elements(seed, mechanism):
    lever, contact, fe = _probe(seed)
    f1 = lever.free_resonance
    if mechanism == "internal":
        fe = FEBeam(**{**fe.__dict__, "Q": 60.0})
        lever = Cantilever(**{**lever.to_dict(), "quality_factor": 60.0})
    elif mechanism == "viscous":
        fe = FEBeam(**{**fe.__dict__, "viscous_hz": f1 / 40})
        lever = Cantilever(**{**lever.to_dict(), "viscous_loss": 1 / 40})
    else:
        eta = contact.k1 / (2 * math.pi * 20 * f1 * 3)        # contact mode 1 Q of tens
        fe = FEBeam(**{**fe.__dict__, "eta": eta})
        contact = Contact(k1=contact.k1, k2_over_k1=0.85, contact_loss=2 * math.pi * f1 * eta / contact.k1)
    result = resonances(lever, contact, modes=2)
    free_fe = FEBeam(**{**fe.__dict__, "k1": 0.0, "k2": 0.0, "eta": 0.0})
    shifts = []
    for modes, beam, drive in ((result.free, free_fe, 3), (result.in_contact, fe, 0)):
        fe_modes = _fe_complex_modes(beam, 2, f1)
        np.testing.assert_allclose(modes.damped_hz, fe_modes.real, rtol=1e-6)
        q_fe = np.abs(fe_modes) / (2 * np.abs(fe_modes.imag))
        damped = q_fe < 1e8                   # a contact dashpot leaves the free modes undamped
        # Loss factors 1/Q to 1e-6 (the FE's own accuracy on a lightly damped mode's width)
        np.testing.assert_allclose(1 / np.array(modes.q), np.where(damped, 1 / q_fe, 0.0), rtol=0, atol=1e-6)
        for i, z in enumerate(fe_modes[damped]):
            peak = _fe_peak(beam, z.real, abs(z.imag), drive)
            assert abs(modes.peak_hz[i] / peak - 1) < 1e-6, (i, modes.peak_hz[i], peak)
            shifts += [abs(modes.peak_hz[i] / modes.hz[i] - 1), abs(modes.damped_hz[i] / modes.hz[i] - 1)]
    # Peak, damped and undamped frequencies differ by far more than the tolerance.
    assert max(shifts) > 2e-5


def test_command_writes_the_named_keys(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = cli.main(["resonances", "--spring-constant", "2.5", "--free-resonance", "5e4", "--length", "200e-6",
                     "--tip-height", "10e-6", "--k1", "260", "--k2-over-k1", "0.85", "--tip-mass-ratio", "0.14",
                     "--tip-gyration-radius", "2.5e-6", "--tilt", "11.5", "--modes", "2", "--quality-factor", "300",
                     "--json", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "contact" in printed and "certified" in printed
    doc = json.loads(out.read_text())
    free, contact = (doc["results"][c]["resonance"]["value"] for c in ("free", "contact"))
    assert len(free) == len(contact) == 2
    assert free[0] == pytest.approx(5e4, rel=1e-12)
    assert free[1] < contact[1] and contact[0] > 5e4
    for condition in ("free", "contact"):
        for key in ("predicted_quality_factor", "damped_resonance", "amplitude_peak"):
            assert len(doc["results"][condition][key]["value"]) == 2
    assert doc["lever"]["tilt"] == {"value": 11.5, "stderr": None, "unit": "deg", "status": "given"}
    assert doc["lever"]["tip_gyration_radius"]["value"] == 2.5e-6


def test_bad_input_is_one_line(capsys):
    code = cli.main(["resonances", "--spring-constant", "2.5", "--free-resonance", "5e4", "--length", "-1"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--length" in err[0]


@pytest.mark.parametrize("seed", [20, 21])
def test_a_given_k1_uncertainty_moves_each_contact_resonance_as_the_fe_lever_moves(seed, tmp_path):
    """``--k1-uncertainty U``: each contact resonance's k1 part is half the FE lever's resonance change from
    k1 - U to k1 + U (k2 tied at 0.85, moving with it), added in quadrature to the tip height's part."""
    fe, p = random_probe(np.random.default_rng(seed), N_ELEMENTS)
    u = 0.05 * p["k1"]
    moved = [FEBeam(p["spring_constant"], p["length"], 1e5, p["tip_height"], k1=k1, k2=0.85 * k1, mu=fe.mu,
                    gamma=fe.gamma, gyration_radius=fe.gyration_radius, tilt_deg=fe.tilt_deg,
                    n_elements=N_ELEMENTS).contact_resonances(2) for k1 in (p["k1"] - u, p["k1"] + u)]
    want = np.abs(moved[1] - moved[0]) / 2
    common = ["resonances"] + [a for name in ("spring_constant", "free_resonance", "length", "tip_height",
                                              "tip_position", "tip_mass_ratio", "tip_gyration_radius", "tilt", "k1")
                               for a in (f"--{name.replace('_', '-')}", repr(p[name]))] + ["--k2-over-k1", "0.85",
                                                                                          "--modes", "2", "--quiet"]
    stderr = {}
    for extra in ([], ["--k1-uncertainty", repr(u)]):
        out = tmp_path / "r.json"
        assert cli.main(common + extra + ["--json", str(out)]) == 0
        doc = json.loads(out.read_text())
        stderr[bool(extra)] = np.array(doc["results"]["contact"]["resonance"]["stderr"])
        assert doc["lever"]["k1"]["stderr"] == (u if extra else None)      # the k1 taken, as given
    np.testing.assert_allclose(np.sqrt(stderr[True] ** 2 - stderr[False] ** 2), want, rtol=2e-3)
