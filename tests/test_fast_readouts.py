"""The read-outs with the tip at the end written out (``composed._WrittenOut``: the clamp eliminated,
the tip's 2 x 2 solved, no assembly), against the assembled system (the general path).

Random levers as ``tests/test_fast_characteristic.py``'s (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4,
tilt, tip mass, Q 5-500 with complex ``beta``), the spot anywhere before the tip, ``beta`` from
1e-3 to 200; every drive.  Slope and deflection to 1e-10 relative.  The partials to 1e-10 of the
larger of themselves and the value over the parameter (``|S / p|``): a partial far below that is
the difference of nearly equal terms in either path (the quasi-static ``d/d beta``, the base
drive at high ``beta``), where neither is accurate to 1e-10 of itself (checked against central
differences of ``tests/segment_beam.py``'s 70-digit solution in
:func:`test_cancelling_partials_are_as_good_as_the_general_path`).
"""
from __future__ import annotations

import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from pfmdyn import composed

sys.path.insert(0, str(Path(__file__).parent))
from segment_beam import DRIVES as MP_DRIVES, spot_response_mp  # noqa: E402
from test_fast_characteristic import BETAS, _damped, _lever  # noqa: E402

TOLERANCE = 1e-10
WRT = tuple(p for p in composed.SPOT_JACOBIAN_PARAMETERS if p != "gamma")


def _case(seed):
    rng = np.random.default_rng(seed)
    p = {**_lever(rng), "gamma": 1.0}
    p, beta = _damped(rng, p, BETAS) if seed % 2 else (p, BETAS)
    return p, beta, rng.uniform(0.05, 1.0)


def _general(f, *args, **kwargs):
    before, composed._written_out = composed._written_out, lambda *args, **kwargs: False
    try:
        return f(*args, **kwargs)
    finally:
        composed._written_out = before


def _relative(got, want, scale=0.0):
    return np.max(np.abs(got - want) / np.maximum(np.abs(want), scale))


@pytest.mark.parametrize("seed", range(24))
def test_response_matches_the_assembled_system(seed):
    p, beta, sigma = _case(seed)
    args = (beta, sigma, *(p[n] for n in composed.PARAMETERS))
    got = composed.response(*args, drives=composed.DRIVES)
    want = _general(composed.response, *args, drives=composed.DRIVES)
    for g, w in zip(got[0] + got[1], want[0] + want[1]):
        assert _relative(g, w) <= TOLERANCE


@pytest.mark.parametrize("seed", range(24))
def test_partials_match_the_assembled_system(seed):
    p, beta, sigma = _case(seed)
    args = (beta, sigma, *(p[n] for n in composed.PARAMETERS))
    values, jac = composed.slope_and_jacobian(*args, wrt=WRT, drives=composed.DRIVES)
    want_values, want_jac = _general(composed.slope_and_jacobian, *args, wrt=WRT, drives=composed.DRIVES)
    at = dict(p, beta=beta, sigma=sigma)
    for i, drive in enumerate(composed.DRIVES):
        assert _relative(values[i], want_values[i]) <= TOLERANCE, drive
        for j, name in enumerate(composed.SPOT_JACOBIAN_PARAMETERS):
            if name in WRT:
                scale = np.abs(want_values[i]) / np.where(at[name] == 0, 1.0, np.abs(at[name]))
                assert _relative(jac[i][j], want_jac[i][j], scale) <= TOLERANCE, (drive, name)


def _mp_partial(beta, sigma, p, name, drive):
    """A central difference of the 70-digit solution (steps 1e-25: exact to far below 1e-20)."""
    with mpmath.workdps(80):
        h, ends = mpmath.mpf(10) ** -25, []
        for sign in (1, -1):
            q = {n: mpmath.mpmathify(v) for n, v in p.items()}
            at = {"beta": mpmath.mpmathify(beta), "sigma": mpmath.mpmathify(sigma)}
            (at if name in at else q)[name] += sign * h
            ends.append(spot_response_mp(at["beta"], [at["sigma"]], dps=70, **q)[0][0][MP_DRIVES.index(drive)])
        return complex((ends[0] - ends[1]) / (2 * h))


@pytest.mark.parametrize("seed,index,drive,name", [(15, 0, "q0", "beta"), (28, 3, "y0", "beta"),
                                                   (15, 0, "d1", "beta"), (33, 59, "y0", "kll")])
def test_cancelling_partials_are_as_good_as_the_general_path(seed, index, drive, name):
    """Where the partial is far below ``|S / p|``, both paths lose digits alike: the fast one within
    1e-10 ``|S / p|`` of the exact partial, as is the general one."""
    p, beta, sigma = _case(seed)
    args = (beta[index:index + 1], sigma, *(p[n] for n in composed.PARAMETERS))
    i, j = composed.DRIVES.index(drive), composed.SPOT_JACOBIAN_PARAMETERS.index(name)
    exact = _mp_partial(beta[index], sigma, p, name, drive)
    scale = abs(composed.slope(*args, drives=(drive,))[0][0]) / abs(dict(p, beta=beta[index])[name])
    for path in (composed.slope_and_jacobian, lambda *a, **k: _general(composed.slope_and_jacobian, *a, **k)):
        got = path(*args, wrt=(name,), drives=(drive,))[1][0][j][0]
        assert abs(got - exact) <= TOLERANCE * scale


def test_shapes_as_the_general_path():
    """Springs as a column against a row of frequencies; ``gamma`` wider than the rest."""
    beta = np.linspace(0.5, 20.0, 7) * (1 + 0.01j)
    kvv = np.array([[0.0], [50.0], [400.0]])
    args = (beta, 0.8, 2.0, kvv, 52.0, 9.0, 1e-5, 2e-4, 0.1, np.ones((2, 1, 1)), 0.05)
    got, want = composed.slope_and_jacobian(*args), _general(composed.slope_and_jacobian, *args)
    for g, w in zip(got[0] + sum(got[1], ()), want[0] + sum(want[1], ())):
        assert (g is None) == (w is None) and (g is None or g.shape == w.shape == (2, 3, 7))
        assert g is None or _relative(g, w, 1e-300) <= TOLERANCE
