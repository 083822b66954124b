"""The public tilt sign (degrees, free end nearer the sample > 0) against a finite-element lever
whose contact springs are built from the explicit geometry (tests/fe_beam.py, ``tilt_deg``):
the lever pointing down towards the sample, springs along the sample's normal and surface."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).parent))
from fe_beam import BETA1, FEBeam  # noqa: E402
from pfmdyn import Cantilever, composed  # noqa: E402
from pfmdyn.generated.tilt_rotation import rotated  # noqa: E402


def _contact_hz(lever: Cantilever, k1, k2, alpha, count=3):
    """First contact resonances of the composed model with the springs rotated by ``alpha`` (Hz)."""
    kvv, kll, kvl = rotated(k1, k2, alpha)
    args = (lever.spring_constant, kvv, kll, kvl, lever.tip_height, lever.length, 0.0, 1.0, 0.0)
    grid = np.linspace(0.5, 30.0, 6000)
    parameters = composed.Parameters(*args)
    vals = composed.characteristic(grid, parameters)
    change = np.flatnonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[:count]
    roots = np.array([brentq(lambda b: composed.characteristic(b, parameters), grid[i], grid[i + 1], xtol=1e-14)
                      for i in change])
    return lever.free_resonance * (roots / BETA1) ** 2


def test_usual_mounting_is_negative_alpha():
    """Free end nearer the sample: the normal spring, compressed as a positive slope swings the
    apex down, pushes the free end back up, which needs ``kvl < 0`` (derivations/tilt.py)."""
    lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, tilt=12.0)
    assert lever.alpha == pytest.approx(-math.radians(12.0))
    kvl = rotated(300.0, 0.0, lever.alpha)[2]
    assert kvl < 0
    geometric = FEBeam(2.0, 2e-4, 7e4, 1e-5, tilt_deg=12.0).spring_tensor(300.0, 0.0)
    assert geometric[2] == pytest.approx(kvl, rel=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_tilted_contact_resonances_match_explicit_geometry(seed):
    rng = np.random.default_rng(100 + seed)
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    lever = Cantilever(k, 1e5, rng.uniform(100e-6, 500e-6), tip_height=rng.uniform(3e-6, 20e-6),
                       tilt=rng.uniform(8.0, 15.0))
    k1 = k * 10 ** rng.uniform(1, 3)
    k2 = 0.85 * k1 if seed else 0.0
    fe = FEBeam(k, lever.length, lever.free_resonance, lever.tip_height, k1=k1, k2=k2, tilt_deg=lever.tilt,
                n_elements=100).contact_resonances(3)
    right = _contact_hz(lever, k1, k2, lever.alpha)
    wrong = _contact_hz(lever, k1, k2, -lever.alpha)
    np.testing.assert_allclose(right, fe, rtol=1e-6)
    assert np.max(np.abs(wrong / fe - 1)) > 1e-4      # the other sign is far off
