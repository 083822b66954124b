"""The characteristic written out from the segments (``composed.determinant._transferred``, no assembly), against
the assembled system's determinant (``composed.assembly._scaled_det``, the general path).

Random levers over the real ranges (k 0.05-50 N/m, L 100-500 um, H 3-20 um, k1/k 1-1e4,
k2/k1 0-1, tilt 0-15 deg, tip mass 0-0.5, r_g/L 0-0.05, the tip at the end or set back to
0.7-1 L), fixed seeds; ``beta`` from the
quasi-static 1e-3 to 200 across the two bases' boundary, undamped and damped (Q 5-500: complex
``beta``, ``k``, contact springs and tip mass).  The same value, sign and scale: the roots are
the same.  Each value to 1e-10 relative.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from pfmdyn import composed
from pfmdyn.composed import assembly

TOLERANCE = 1e-10
BETAS = np.concatenate([np.logspace(-3, math.log10(200), 60), [1.0 - 1e-12, 1.0, 1.0 + 1e-12]])


def _lever(rng):
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    k1 = k * 10 ** rng.uniform(0, 4)
    k2 = k1 * rng.uniform(0, 1)
    t = math.radians(rng.uniform(0, 15))
    c, s = math.cos(t), math.sin(t)
    return dict(k=k, kvv=k1 * c**2 + k2 * s**2, kll=k1 * s**2 + k2 * c**2, kvl=-(k1 - k2) * s * c,
                H=rng.uniform(3e-6, 20e-6), L=rng.uniform(100e-6, 500e-6), mu=rng.uniform(0, 0.5),
                gamma=1.0 if rng.uniform() < 0.5 else rng.uniform(0.7, 1.0), rho_g=rng.uniform(0, 0.05))


def _damped(rng, p, beta):
    """Internal, contact and viscous losses of a quality factor 5-500, either sign of the phase."""
    loss = rng.choice([-1, 1]) / 10 ** rng.uniform(math.log10(5), math.log10(500), 5)
    return ({**p, "k": p["k"] * (1 + 1j * loss[0]), "kvv": p["kvv"] * (1 + 1j * loss[1]),
             "kll": p["kll"] * (1 + 1j * loss[2]), "kvl": p["kvl"] * (1 + 1j * loss[3]),
             "mu": p["mu"] * (1 + 1j * loss[4])}, beta * (1 + 0.25j * loss[0]))


def _general(beta, p):
    lever = assembly._Lever(beta, *composed.Parameters(**p))
    return lever.out(assembly._scaled_det(lever)[0])


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("damping", ["undamped", "damped"])
def test_matches_the_assembled_system(seed, damping):
    rng = np.random.default_rng(seed)
    p = _lever(rng)
    if seed % 4 == 0:           # the free lever, and one with the springs alone
        p = {**p, "kvv": 0.0, "kll": 0.0, "kvl": 0.0} if seed % 8 == 0 else {**p, "mu": 0.0, "rho_g": 0.0}
    beta = BETAS
    if damping == "damped":
        p, beta = _damped(rng, p, beta)
    got = composed.characteristic(beta, composed.Parameters(**p))
    want = _general(beta, p)
    err = np.abs(got - want) / np.abs(want)
    assert err.max() <= TOLERANCE, (err.max(), beta[np.argmax(err)], p)


@pytest.mark.parametrize("gamma", [1.0, 0.85])
def test_broadcasts_as_the_general_path(gamma):
    """A grid of springs against a grid of frequencies (the start grids' call), a scalar, a
    ``gamma`` of one value wider than the rest, and tip positions varying over the batch."""
    p = {**_lever(np.random.default_rng(7)), "gamma": gamma}
    springs = np.array([0.0, 1.0, 30.0])[:, None] * p["kvv"]
    beta = np.linspace(0.3, 30.0, 50)
    args = {**p, "kvv": springs}
    got = composed.characteristic(beta, composed.Parameters(**args))
    assert got.shape == (3, 50)
    np.testing.assert_allclose(got, _general(beta, args), rtol=TOLERANCE, atol=0)
    scalar = composed.characteristic(2.5, composed.Parameters(**p))
    assert np.shape(scalar) == () and scalar == pytest.approx(float(_general(2.5, p)), rel=TOLERANCE)
    wide = {**p, "gamma": np.full((2, 1), gamma)}
    got = composed.characteristic(beta, composed.Parameters(**wide))
    assert got.shape == (2, 50)
    np.testing.assert_allclose(got, _general(beta, wide), rtol=TOLERANCE, atol=0)
    varying = {**p, "gamma": np.array([[1.0], [0.7], [0.999]])}
    got = composed.characteristic(beta, composed.Parameters(**varying))
    np.testing.assert_allclose(got, _general(beta, varying), rtol=TOLERANCE, atol=0)


WRT = tuple(p for p in composed.JACOBIAN_PARAMETERS if p != "gamma")


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("damping", ["undamped", "damped"])
def test_partials_with_the_tip_at_the_end(seed, damping):
    """:func:`composed.characteristic_and_jacobian` with the tip at the end (no ``gamma`` partial),
    written out, against the assembled system's (asked for ``gamma``: the general path) where that
    one's adjugate is accurate (``beta`` 0.9-110), to 1e-10; and its ``beta`` partial against
    central differences of the characteristic over the whole range (the assembled system's
    adjugate loses digits to the jump's ``1/beta**3`` below ``beta ~ 0.5``)."""
    rng = np.random.default_rng(seed)
    p = {**_lever(rng), "gamma": 1.0}
    beta = BETAS
    if damping == "damped":
        p, beta = _damped(rng, p, beta)
    value, partials = composed.characteristic_and_jacobian(beta, composed.Parameters(**p), wrt=WRT)
    assert partials[composed.JACOBIAN_PARAMETERS.index("gamma")] is None
    general_value, general = composed.characteristic_and_jacobian(beta, composed.Parameters(**p))
    np.testing.assert_allclose(value, general_value, rtol=TOLERANCE, atol=0)
    fair = (np.abs(beta) >= 0.9) & (np.abs(beta) <= 110)
    for name, got, want in zip(composed.JACOBIAN_PARAMETERS, partials, general):
        if name in WRT:
            np.testing.assert_allclose(got[fair], want[fair], rtol=TOLERANCE, atol=0, err_msg=name)
    h = 1e-6 * beta
    lever = composed.Parameters(**p)
    differences = (composed.characteristic(beta + h, lever) - composed.characteristic(beta - h, lever)) / (2 * h)
    np.testing.assert_allclose(partials[0], differences, rtol=2e-5, atol=0)
