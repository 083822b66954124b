"""The drives beyond the tip's: the base (a dither piezo) and thermal noise.

Both come from the composed lever (:mod:`pfmdyn.composed`).  The references here are independent
of it: the free beam's mode shapes in closed form (``cosh - cos - s (sinh - sin)``) integrated
numerically, equipartition and the static compliance of a cantilever at a point.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from pfmdyn import Cantilever, composed
from pfmdyn.cantilever import BOLTZMANN

BETA1 = 1.8751040687119611


def _mode_shape(x):
    """The free cantilever's first mode on ``x = xi`` (0..1), ``phi(1) = 2``."""
    b = BETA1
    s = (math.cosh(b) + math.cos(b)) / (math.sinh(b) + math.sin(b))
    return np.cosh(b * x) - np.cos(b * x) - s * (np.sinh(b * x) - np.sin(b * x))


def _levers(seed, count):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (10 ** rng.uniform(math.log10(0.05), math.log10(50)), 10 ** rng.uniform(4, 6),
               rng.uniform(100e-6, 500e-6), 10 ** rng.uniform(math.log10(5), math.log10(500)))


@pytest.mark.parametrize("k,f1,L,q", list(_levers(7, 4)))
def test_base_drive_first_mode_and_quasi_static(k, f1, L, q):
    """Relative tip deflection per unit base motion: |beta**4 (1 - i g / r)| / 8 at rest (the uniform
    load of inertia and drag on a cantilever), Q times the first mode's participation ``phi(1) int(phi) / int(phi**2)`` at the
    resonance."""
    lever = Cantilever(k, f1, L, viscous_loss=1.0 / q)
    x = np.linspace(0.0, 1.0, 20001)
    phi = _mode_shape(x)
    participation = _mode_shape(1.0) * np.trapezoid(phi, x) / np.trapezoid(phi**2, x)
    low = 1e-3 * f1
    r = lever.base_driven([low, f1])
    beta = BETA1 * math.sqrt(1e-3)
    assert abs(r.deflection[0]) == pytest.approx(abs(beta**4 * (1 - 1j / (q * 1e-3))) / 8, rel=1e-3)
    assert abs(r.deflection[1]) == pytest.approx(q * participation, rel=3e-3 + 2.0 / q)


@pytest.mark.parametrize("k,f1,L,q", list(_levers(11, 6)))
@pytest.mark.parametrize("spot", [1.0, 0.7])
def test_thermal_noise_holds_kT_and_the_first_mode_fraction(k, f1, L, q, spot):
    """Equipartition: the deflection's spectrum integrates to ``k_B T`` times the static compliance at
    the spot, ``(x_s / L)**3 / k``; near the first mode it holds ``phi(x_s)**2 / int(phi**2)`` of
    the end's ``k_B T / k`` divided by the mode's share (0.971 at the end)."""
    T = 300.0
    lever = Cantilever(k, f1, L, viscous_loss=1.0 / q, spot_position=spot)
    # a log grid, refined across the first three modes' peaks
    peaks = [f1 * r * np.maximum(1 + np.linspace(-30, 30, 2001) / q, 1e-3) for r in (1.0, 6.2669, 17.547)]
    f = np.unique(np.concatenate([np.geomspace(1e-3 * f1, 3e3 * f1, 20001), *peaks]))
    total = np.trapezoid(lever.thermal_noise(f, T).deflection, f)
    assert total == pytest.approx(BOLTZMANN * T * spot**3 / k, rel=2e-3)
    if q < 50:              # a broad first mode overlaps its neighbours' tails: no band holds it alone
        return
    x = np.linspace(0.0, 1.0, 20001)
    # the first mode: modal stiffness k_1 = k beta1**4 / 3 int(phi**2) over phi(x_s)**2
    modal = (BETA1**4 / 3) * np.trapezoid(_mode_shape(x) ** 2, x) / _mode_shape(spot) ** 2
    band = np.linspace(f1 * (1 - 40 / q), f1 * (1 + 40 / q), 40001)
    peak = np.trapezoid(lever.thermal_noise(band, T).deflection, band)
    assert peak == pytest.approx(BOLTZMANN * T / (k * modal), rel=0.05)


def test_thermal_noise_of_the_slope_matches_the_optical_lever_factor():
    """Read as slope and converted by the static end-loaded shape (u = 2 L theta / 3), the first
    mode's share of ``k_B T / k`` is Butt and Jaschke's 0.817 (high Q: the other modes' tails are
    below 1e-3)."""
    k, f1, L = 2.0, 7e4, 2e-4
    lever = Cantilever(k, f1, L, viscous_loss=1e-3)
    f = np.linspace(0.5, 1.5, 200001) * f1
    theta2 = np.trapezoid(lever.thermal_noise(f, 300.0).slope, f)
    assert theta2 * (2 * L / 3) ** 2 / (BOLTZMANN * 300.0 / k) == pytest.approx(0.817, abs=2e-3)


def test_the_probe_reads_the_static_compliance_anywhere():
    """A force at a bare point x deflects it by x**3 / (3 EI); a couple turns it by x / EI."""
    k, L = 2.0, 2e-4
    for sigma in (0.3, 0.8, 1.0):
        free = composed.Parameters(k=k, kvv=0.0, kll=0.0, kvl=0.0, H=1e-5, L=L, mu=0.0, gamma=1.0, rho_g=0.0)
        (s_force, s_couple), (d_force, d_couple) = composed.response(1e-3, free, sigma, drives=composed.PROBE_DRIVES,
                                                                     probe=sigma)
        assert float(d_force) * k == pytest.approx(sigma**3, rel=1e-9)
        assert float(s_couple) * k * L**2 == pytest.approx(3 * sigma, rel=1e-9)
        assert float(s_force) == pytest.approx(float(d_couple), rel=1e-9)     # Maxwell's reciprocity


def test_thermal_noise_refuses_a_temperature_at_or_below_zero():
    from pfmdyn.errors import UserError
    with pytest.raises(UserError, match="temperature"):
        Cantilever(2.0, 7e4, 2e-4).thermal_noise([7e4], 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_lever_in_a_fluid_is_the_loaded_beam(seed):
    """Base-driven in air or water: the lever's response is the high-precision beam's
    (``tests/segment_beam.py``) at ``beta**4 (1 + load)``, the load from Sader's function (itself
    checked against mpmath in ``tests/test_medium.py``), read at a spot."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parent))
    from segment_beam import DRIVES, spot_response_mp
    from pfmdyn.medium import Medium, load_ratio, mass_per_length

    rng = np.random.default_rng(seed)
    k, L = 10 ** rng.uniform(math.log10(0.05), math.log10(50)), rng.uniform(50e-6, 500e-6)
    width, spot = rng.uniform(20e-6, 60e-6), rng.uniform(0.6, 1.0)
    medium = (Medium.air if seed % 2 else Medium.water)(rng.uniform(285.0, 315.0))
    vacuum = Cantilever(k, 10 ** rng.uniform(4, 5.5), L, width=width, spot_position=spot)
    lever = vacuum.with_medium(medium)
    f = lever.free_resonance * np.array([0.3, 1.0, 4.0])
    got = lever.base_driven(f)
    load = load_ratio(medium, f, width, mass_per_length(k, L, vacuum.free_resonance))
    beta = BETA1 * np.sqrt(f / vacuum.free_resonance) * (1 + load) ** 0.25
    for i, b in enumerate(beta):
        (slopes, deflections), = spot_response_mp(complex(b), [spot], k=k, L=L, H=1e-5, kvv=0.0)
        j = DRIVES.index("y0")
        assert complex(got.slope[i]) == pytest.approx(complex(slopes[j]), rel=1e-8)
        assert complex(got.deflection[i]) == pytest.approx(complex(deflections[j]) - 1, rel=1e-8)


def test_the_map_model_loads_the_lever_as_the_lever_does():
    """A lever in air: the map's beam model substitutes the same fluid-loaded ``beta`` as the lever's
    own response (one damping substitution, the medium a drag in it)."""
    from pfmdyn.maps.beam import BeamMapModel
    from pfmdyn.medium import Medium

    lever = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, width=3e-5, medium=Medium.air(300.0))
    f = np.linspace(2e5, 4e5, 7)
    beta = BeamMapModel(lever, f)._arguments(0.0, 0.0, 100.0, 50.0, 0.0)[2]
    np.testing.assert_allclose(beta, lever.beta(f), rtol=1e-14)
    vacuum = Cantilever(2.0, 7e4, 2e-4, tip_height=1e-5, width=3e-5)
    assert np.all(np.abs(beta / vacuum.beta(f) - 1) > 1e-4)       # the fluid moved it
