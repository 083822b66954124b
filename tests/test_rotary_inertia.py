"""The tip's rotary inertia (``rho_g = r_g / L``) in the composed model, against an independent
finite-element beam whose tip node carries ``J = m_tip r_g**2`` on its rotation.

Every check would catch a sign error of the rotary term: the shifts it causes (1e-5 to a
few 1e-2 here) are asserted to be much larger than the tolerance.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

# The independent FE beam lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import BETA1, FEBeam  # noqa: E402
from pfmdyn import composed  # noqa: E402
from pfmdyn.generated import damping, tip_mass  # noqa: E402
from pfmdyn.generated.tilt_rotation import rotated  # noqa: E402

N_ELEMENTS = 100   # Hermite cubics: about 1e-7 on the first three modes; more elements lose to rounding


def _roots(args, count=3):
    """First ``count`` zeros in beta of the composed characteristic (grid + Brent)."""
    grid, lever = np.linspace(0.3, 40.0, 8000), composed.Parameters(*args)
    with np.errstate(all="ignore"):
        vals = composed.characteristic(grid, lever)
    change = np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[:count]
    return np.array([brentq(lambda b: composed.characteristic(b, lever), grid[i], grid[i + 1], xtol=1e-15,
                            rtol=1e-15) for i in change])


def _lever(rng, n=N_ELEMENTS):
    """A random lever over the real ranges: tip at a node, massive tip with r_g about H/4."""
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    L, H = rng.uniform(100e-6, 500e-6), rng.uniform(3e-6, 20e-6)
    k1 = k * 10 ** rng.uniform(0, 4)
    return dict(k=k, L=L, f1=1e5, H=H, k1=k1, k2=0.85 * k1, mu=rng.uniform(0.05, 0.5),
                gamma=int(rng.integers(int(0.85 * n), n + 1)) / n, alpha=rng.uniform(-0.3, 0.3),
                gyration_radius=rng.uniform(0.5, 2.0) * H / 4)


def test_zero_gyration_radius_is_the_point_mass_tip():
    b = np.array([0.7, 1.9, 4.0, 7.5, 12.0]) * (1 - 0.01j)
    point = np.array(tip_mass.slope(b, 2.4, 120.0, 100.0, 1e-5, 223e-6, 0.3))
    lever = composed.Parameters(2.4, 120.0, 100.0, 0.0, 1e-5, 223e-6, 0.3, 1.0, 0.0)
    at_end = np.array(composed.at_end.slope(b, lever))
    np.testing.assert_allclose(at_end, point, rtol=1e-10)
    turning = np.array(composed.at_end.slope(b, lever._replace(rho_g=0.02)))
    assert np.max(np.abs(turning / point - 1)) > 1e-3


@pytest.mark.parametrize("seed", range(4))
def test_resonances_match_finite_elements(seed):
    """First three free and contact resonances with set-back, mass, rotary inertia, tilt, k2 = 0.85 k1."""
    p = _lever(np.random.default_rng(seed))
    beam = FEBeam(n_elements=N_ELEMENTS, **p)
    kvv, kll, kvl = rotated(p["k1"], p["k2"], p["alpha"])
    rho_g = p["gyration_radius"] / p["L"]
    for springs, fe in (((0.0, 0.0, 0.0), beam.free_resonances(3)), ((kvv, kll, kvl), beam.contact_resonances(3))):
        args = (p["k"], *springs, p["H"], p["L"], p["mu"], p["gamma"])
        with_j = p["f1"] * (_roots((*args, rho_g)) / BETA1) ** 2
        without = p["f1"] * (_roots((*args, 0.0)) / BETA1) ** 2
        np.testing.assert_allclose(with_j, fe, rtol=1e-6)
        assert np.all(with_j < without)                       # a turning body lowers every mode
        assert np.max(1 - with_j / without) > 2e-5            # ... by far more than the tolerance


def test_damped_slope_matches_finite_elements():
    """The damping substitution with the rotary term: internal, viscous and contact losses at once
    (the body is not dragged: ``rho_g`` passes through unchanged, ``mu`` takes the mass factor)."""
    rng = np.random.default_rng(7)
    p = _lever(rng)
    beam = FEBeam(n_elements=N_ELEMENTS, Q=80.0, viscous_hz=p["f1"] / 30, eta=p["k1"] / (2 * math.pi * 5e6), **p)
    f = np.linspace(0.3, 8.0, 60) * p["f1"]
    r = f / p["f1"]
    beta_f, k_f, k1_f, mu_f = damping.factors(r, 1 / 80.0, 1 / 30, 2 * math.pi * p["f1"] * beam.eta / p["k1"])
    kvv, kll, kvl = rotated(p["k1"] * k1_f, p["k2"], p["alpha"])
    lever = composed.Parameters(p["k"] * k_f, kvv, kll, kvl, p["H"], p["L"], p["mu"] * mu_f, p["gamma"],
                                p["gyration_radius"] / p["L"])
    ours = composed.at_end.slope(BETA1 * np.sqrt(r) * beta_f, lever)
    fe = beam.slope(f)
    for j in range(4):            # d1, d2, f0, q0; without the rotary term they differ by ~0.1
        assert np.max(np.abs(ours[j] - fe[:, j])) < 2e-6 * np.max(np.abs(fe[:, j])), j


def test_shift_of_the_size_an_independent_program_reports():
    """The lever of Bradler's Cantilever-dynamics example (L 200 um, H 10 um, k 2.5 N/m, tip mass
    9.34e-12 kg on a 6.63e-11 kg lever, tilt 0.2 rad, k1 260 N/m, k2 = 0.85 k1) with its
    J = m_tip (H/4)**2: the issue quotes contact mode 1 moved by 1.5-2.2e-4, free mode 2 by 7e-4."""
    k, L, H, mu = 2.5, 200e-6, 10e-6, 9.34129e-12 / 6.63322e-11
    kvv, kll, kvl = rotated(260.44, 0.85 * 260.44, -0.2)
    base = (k, 0.0, 0.0, 0.0, H, L, mu, 1.0)
    contact = (k, kvv, kll, kvl, H, L, mu, 1.0)
    rho_g = H / 4 / L
    free_shift = (_roots((*base, rho_g)) / _roots((*base, 0.0))) ** 2 - 1
    contact_shift = (_roots((*contact, rho_g)) / _roots((*contact, 0.0))) ** 2 - 1
    assert 1.5e-4 < -contact_shift[0] < 2.2e-4
    assert 6.5e-4 < -free_shift[1] < 7.5e-4


@pytest.mark.parametrize("seed", range(3))
def test_stiffness_model_recovers_k1_with_a_turning_tip(seed):
    """pfmdyn stiffness's whole-lever model with the rotary inertia: k1 from the first contact mode
    of the FE lever (J on the tip node), to 1e-5 (higher modes see k1 less: the FE's 1e-7 in
    frequency grows there); without J it is off by more."""
    from pfmdyn import Cantilever
    from pfmdyn import Contact
    from pfmdyn.analysis.contact_resonance import betas, k1_at
    p = _lever(np.random.default_rng(40 + seed))
    beam = FEBeam(n_elements=N_ELEMENTS, **p)
    f1 = float(beam.free_resonances(1)[0])
    contact_hz = beam.contact_resonances(1)
    found = {}
    for r_g in (p["gyration_radius"], 0.0):
        lever = Cantilever(p["k"], f1, p["L"], tip_height=p["H"], tip_position=p["gamma"], tip_mass_ratio=p["mu"],
                           tip_gyration_radius=r_g, tilt=-math.degrees(p["alpha"]))
        found[r_g] = [float(k1_at(betas(lever, f), mode, lever, Contact(k2_over_k1=0.85), p["gamma"]))
                      for mode, f in enumerate(contact_hz, 1)]
    error = abs(found[p["gyration_radius"]][0] / p["k1"] - 1)
    assert error < 1e-5
    assert abs(found[0.0][0] / p["k1"] - 1) > 10 * error       # leaving J out costs more
