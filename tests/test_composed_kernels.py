"""The compiled kernels of the composed lever (:mod:`pfmdyn.composed.kernels`) against the NumPy forms
of :mod:`pfmdyn.composed`, their reference, over drawn levers (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4,
Q 5-500 with complex ``beta`` and springs, the tip at the end or set back to 0.7-0.99 L, the spot
before or beyond it, ``beta`` from 1e-3 to 200).

The characteristic and its partials with the tip at the end take the same steps: 1e-12.  The
read-outs take the written-out form's steps but invert the 4 x 4 of a set-back tip by their own LU
(LAPACK's in NumPy), divide where NumPy multiplies by a reciprocal and compile the tip's jump (numba's
``beta**3`` and NumPy's differ in the last digit, which the load's column amplifies where its terms
cancel): 2e-11 (the worst seen 1.3e-11, 5e-12 with NumPy's jump),
the partials relative to the larger of themselves and ``|S / p|`` (as ``tests/test_fast_readouts.py``,
which also holds both to the assembled system and the 70-digit beam).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from pfmdyn import composed

NAMES = ("beta", "sigma", "k", "kvv", "kll", "kvl", "H", "L", "mu", "gamma", "rho_g")


def _levers(seed: int, count: int):
    """Drawn arguments ``(beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)``."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
        k1 = k * 10 ** rng.uniform(0, 4)
        gamma = 1.0 if i % 3 == 0 else rng.uniform(0.7, 0.99)
        sigma = [1.0, rng.uniform(0.5, gamma), rng.uniform(gamma, 1.0)][i % 3]
        beta = 10 ** rng.uniform(-3, math.log10(200), 40)
        damped = i % 2 == 1
        if damped:
            beta = beta * (1 - 1j / rng.uniform(5, 500)) ** 0.25
        loss = 1 + 1j * rng.uniform(0, 0.05) if damped else 1.0
        yield (beta, sigma, k, k1 * loss, k1 * rng.uniform(0.3, 1.0), k1 * rng.uniform(-0.2, 0.2),
               rng.uniform(3e-6, 20e-6), rng.uniform(100e-6, 500e-6), rng.uniform(0, 0.5), gamma, rng.uniform(0, 0.1))


def _both(f):
    """``f()`` compiled, then with the NumPy forms."""
    out = []
    for kernels in (True, False):
        composed.KERNELS = kernels
        try:
            out.append(f())
        finally:
            composed.KERNELS = True
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_read_outs_and_partials_agree_with_the_written_out_form(seed):
    wrt = tuple(p for p in composed.SPOT_JACOBIAN_PARAMETERS if p != "gamma")
    for args in _levers(seed, 12):
        at = dict(zip(NAMES, args))
        beta, sigma, *lever = args
        (values, jac), (want, want_jac) = _both(lambda: composed.slope_and_jacobian(
            beta, composed.Parameters(*lever), sigma, wrt=wrt, drives=composed.DRIVES))
        for i, value in enumerate(want):
            assert np.max(np.abs(values[i] - value) / np.abs(value)) <= 2e-11, (i, args[1:])
            for j, name in enumerate(composed.SPOT_JACOBIAN_PARAMETERS):
                if name in wrt:
                    scale = np.maximum(np.abs(want_jac[i][j]), np.abs(value) / np.where(at[name] == 0, 1.0, np.abs(at[name])))
                    assert np.max(np.abs(jac[i][j] - want_jac[i][j]) / scale) <= 2e-11, (i, name, args[1:])


@pytest.mark.parametrize("seed", [0, 1])
def test_characteristic_agrees_with_numpy(seed):
    """One lever per call, and a column of levers against a row of ``beta`` (a start grid)."""
    for args in _levers(seed, 30):
        lever = composed.Parameters(*args[2:])          # the characteristic takes no sigma
        got, want = _both(lambda: composed.characteristic(args[0], lever))
        assert got.dtype == want.dtype and np.max(np.abs(got - want) / np.abs(want)) <= 1e-12
    grid = np.linspace(0.3, 30.0, 50)
    column = [np.array([[2.0], [3.0]]), np.array([[98.0], [0.0]]), 52.0, 9.0, 1e-5, 2e-4, np.array([[0.1], [0.0]]),
              np.array([[0.9], [1.0]]), 0.05]
    got, want = _both(lambda: composed.characteristic(grid, composed.Parameters(*column)))
    assert got.shape == want.shape == (2, 50) and np.max(np.abs(got - want) / np.abs(want)) <= 1e-12


def test_characteristic_partials_with_the_tip_at_the_end_agree_with_numpy():
    wrt = ("beta", "k", "kvv", "kll", "kvl", "mu", "rho_g")
    for args in _levers(2, 12):
        lever = composed.Parameters(*args[2:9], 1.0, *args[10:])
        (value, partials), (want, want_partials) = _both(lambda: composed.characteristic_and_jacobian(args[0], lever,
                                                                                                        wrt=wrt))
        assert np.max(np.abs(value - want) / np.abs(want)) <= 1e-12
        for name, d, w in zip(composed.JACOBIAN_PARAMETERS, partials, want_partials):
            if name in wrt:
                assert np.max(np.abs(d - w) / np.maximum(np.abs(w), np.abs(want))) <= 1e-12, name


def test_resonances_agree_with_the_numpy_root_search():
    """The compiled root search (:func:`pfmdyn.composed.kernels.characteristic_roots`) takes
    :func:`pfmdyn.roots.bracket.grid_roots`' steps: the same roots to an ulp or two (the Chebyshev
    coefficients summed in another order), refined or interpolated, the tip at the end or set back."""
    from pfmdyn.composed.kernels import characteristic_roots
    from pfmdyn.roots.bracket import grid_roots

    for args in _levers(3, 8):
        lever = np.real(np.array([args[2:9] + (args[9], 0.0)]))      # undamped, no gyration: the model's roots
        grid = np.linspace(0.3, 12.0 + 20.0 * args[8], 200)
        for refine in (True, False):
            want = grid_roots(lambda b: composed.characteristic(b, composed.Parameters(*lever[0])), grid, refine)
            got = characteristic_roots(grid, lever, refine, 1e-13)
            assert len(got) == len(want) > 0 and np.max(np.abs(got / want - 1)) <= 1e-14


def test_characteristic_partials_by_complex_steps_agree_with_the_assembled_system():
    """The complex steps of :func:`pfmdyn.composed.kernels.characteristic_partials` against the
    assembled system's adjugate (the set-back tip's partials, ``gamma``'s at the end too) where the
    resonances are (``beta`` > 0.3): 1e-9 (the adjugate from the SVD loses a few digits; below, in the
    quasi-static range, many: there central differences side with the complex steps)."""
    from pfmdyn.discrepancy.model import characteristic_partials

    wrt = ("beta", "kvv", "kll", "kvl", "mu", "gamma")
    for args in _levers(4, 8):
        lever = composed.Parameters(*np.real(args[2:10]), 0.0)
        beta = np.real(args[0])
        beta = beta[beta > 0.3][:6]
        got = characteristic_partials(beta, lever, wrt)
        _, want = _both(lambda: composed.characteristic_and_jacobian(beta, lever, wrt=wrt))[1]
        for name, d in zip(wrt, got):
            w = want[composed.JACOBIAN_PARAMETERS.index(name)]
            assert np.max(np.abs(d - w) / np.abs(w)) <= 1e-9, name
