"""The medium and the fluid's load (pfmdyn.medium) against an independent route: mpmath's Bessel
functions and SymPy's rectangular fit (derivations/hydrodynamics.py), the exact complex root of the
lever in the fluid, and handbook values of air and water."""
from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from pfmdyn.derivations import hydrodynamics as hyd
from pfmdyn.errors import UserError
from pfmdyn.medium import Medium, hydrodynamic_function, load_ratio, mass_per_length


@pytest.mark.parametrize("name, temperature, density, viscosity", [
    # Handbook values (CRC: air at 1 atm; water, IAPWS): 0.5 % in density, 2 % in viscosity.
    ("air", 293.15, 1.204, 1.825e-5), ("air", 313.15, 1.127, 1.912e-5),
    ("water", 293.15, 998.21, 1.0016e-3), ("water", 310.15, 993.33, 0.6913e-3)])
def test_handbook_values(name, temperature, density, viscosity):
    m = getattr(Medium, name)(temperature)
    assert m.density == pytest.approx(density, rel=5e-3) and m.viscosity == pytest.approx(viscosity, rel=2e-2)


@pytest.mark.parametrize("re", [1e-6, 1e-3, 0.1, 1.0, 30.0, 1e3, 1e4])
def test_hydrodynamic_function_matches_mpmath(re):
    assert hydrodynamic_function(re) == pytest.approx(complex(hyd.rectangular_numeric(mp.mpf(re))), rel=1e-9)


def test_outside_the_fit_is_undetermined():
    assert np.isnan(hydrodynamic_function(1e5)) and np.isnan(hydrodynamic_function(1e-7))
    assert np.isnan(hydrodynamic_function(np.array([1.0, 1e6]))[1])


def test_vacuum_as_density_vanishes():
    loads = [abs(load_ratio(Medium(d, 1.8e-5), 1e5, 3e-5, 2e-7)) for d in (1.0, 1e-2, 1e-4)]
    assert loads[0] > loads[1] > loads[2] and loads[2] < 1e-3


@pytest.mark.parametrize("medium, f_vac, width, m", [
    (Medium.air(293.15), 3e5, 4e-5, 4e-7), (Medium.air(313.15), 7e4, 3e-5, 1e-7),
    (Medium.water(298.15), 3e5, 4e-5, 4e-7), (Medium.water(298.15), 1e5, 5e-5, 3e-7)])
def test_load_ratio_gives_the_exact_first_mode(medium, f_vac, width, m):
    """The closed forms from load_ratio at the fluid frequency against the exact complex root."""
    f_exact, q_exact = (float(v) for v in hyd.fluid_first_mode(f_vac, m, medium.density, medium.viscosity, width))
    f = f_vac
    for _ in range(50):
        r = load_ratio(medium, f, width, m)
        f = f_vac / math.sqrt(1 + r.real)
    q = (1 + r.real) / -r.imag
    assert q > 0
    assert f == pytest.approx(f_exact, rel=1 / q**2 + 1e-9)
    assert q == pytest.approx(q_exact, rel=0.6 / q + 1e-3)


def test_parse_and_errors():
    assert Medium.parse("AIR", 300.0).name == "air at 26.85 C"
    with pytest.raises(UserError, match="temperature"):
        Medium.water(400.0)
    with pytest.raises(UserError, match="positive"):
        Medium.parse("-1,1e-3")


def test_mass_per_length_inverts_the_resonance():
    k, length, f1 = 2.0, 2e-4, 7e4
    m = mass_per_length(k, length, f1)
    beta1 = 1.8751040687119612
    assert 2 * math.pi * f1 == pytest.approx(beta1**2 / length**2 * math.sqrt(k * length**3 / 3 / m), rel=1e-12)


def test_generated_circular_function_is_the_one_typed_before():
    """The circular cylinder's function, generated from derivations/hydrodynamics.py, equals the form
    medium.py typed by hand before (SciPy's K0, K1 in pfmdyn's convention) to 1e-12 over Re 1e-3..1e4,
    on the real axis and at a damped mode's complex Reynolds number (Im/Re = 1e-2)."""
    from scipy.special import kv

    from pfmdyn.generated.formulas import circular_hydrodynamic_function

    re = np.geomspace(1e-3, 1e4, 301)
    for r in (re, re * (1 + 1e-2j)):
        root = np.sqrt(-1j * r)
        typed = 1 - 4j * kv(1, 1j * root) / (root * kv(0, 1j * root))
        np.testing.assert_allclose(circular_hydrodynamic_function(r), typed, rtol=1e-12, atol=0)
