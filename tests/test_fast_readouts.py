"""The fast read-outs, compiled (``composed.readout._Compiled``: the system assembled and solved per member in
:mod:`pfmdyn.composed.kernels`) and written out (``composed.written_out._WrittenOut``: the clamp and, beyond a
set-back tip, the free end eliminated, the tip's 2 x 2 or 4 x 4 solved, no assembly), against the
assembled system in NumPy (the general path).

Random levers as ``tests/test_fast_characteristic.py``'s (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4,
tilt, tip mass, Q 5-500 with complex ``beta``), the tip at the end or set back to 0.7-1 L, the spot
anywhere before or beyond it, ``beta`` from 1e-3 to 200; every drive.  Slope and deflection to
1e-10 relative.  The partials to 1e-10 of the larger of themselves and the value over the parameter
(``|S / p|``): a partial far below that is the difference of nearly equal terms in either path
(the quasi-static ``d/d beta``, the base drive at high ``beta``), where neither is accurate to
1e-10 of itself (checked against central differences of ``tests/segment_beam.py``'s 70-digit
solution in :func:`test_cancelling_partials_are_as_good_as_the_general_path`).  Where the two
paths differ by more, both lose digits alike and the 70-digit solution decides (:func:`_assert_close`);
a few set-back levers are checked against it outright (:func:`test_set_back_against_the_exact_beam`).
"""
from __future__ import annotations

import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from pfmdyn import composed
from pfmdyn.composed import readout

sys.path.insert(0, str(Path(__file__).parent))
from segment_beam import DRIVES as MP_DRIVES, spot_response_mp  # noqa: E402
from test_fast_characteristic import BETAS, _damped, _lever  # noqa: E402

TOLERANCE = 1e-10
WRT = tuple(p for p in composed.SPOT_JACOBIAN_PARAMETERS if p != "gamma")


def _case(seed):
    """Seeds 0-23: the tip at the end; 100-123 set back, the spot before the tip (100-105 and
    112-117) or beyond it (at the free end for 107, 119)."""
    rng = np.random.default_rng(seed)
    p = {**_lever(rng), "gamma": 1.0 if seed < 100 else rng.uniform(0.7, 0.98)}
    p, beta = _damped(rng, p, BETAS) if seed % 2 else (p, BETAS)
    before = seed < 100 or (seed - 100) % 12 < 6
    sigma = rng.uniform(0.05, p["gamma"]) if before else 1.0 if seed % 12 == 11 else rng.uniform(p["gamma"], 1.0)
    return p, beta, sigma


SEEDS = [*range(24), *range(100, 124)]


@pytest.fixture(autouse=True, params=["compiled", "written out"])
def fast(request, monkeypatch):
    """Each test for both fast paths: the compiled kernel (:mod:`pfmdyn.composed.kernels`) and the
    NumPy written-out forms."""
    monkeypatch.setattr(composed, "KERNELS", request.param == "compiled")


def _general(f, *args, **kwargs):
    before = readout._written_out, composed.KERNELS
    readout._written_out, composed.KERNELS = (lambda *args, **kwargs: False), False
    try:
        return f(*args, **kwargs)
    finally:
        readout._written_out, composed.KERNELS = before


def _relative(got, want, scale=0.0):
    return np.max(np.abs(got - want) / np.maximum(np.abs(want), scale))


def _mp_value(beta, sigma, p, drive, part=0):
    """The 70-digit slope (``part`` 0) or deflection (1)."""
    return complex(spot_response_mp(beta, [sigma], dps=70, **p)[0][part][MP_DRIVES.index(drive)])


def _assert_close(got, want, scale, exact, exact_value, want_value):
    """``got`` (fast) within TOLERANCE of ``want`` (general) relative to ``max(|want|, scale)``.  Where
    not, both paths lose digits alike (the base drive read beyond a set-back tip at Q 5 and ``beta``
    200: its waves decay as ``e^{-Im beta x}`` along the lever, while the bounded basis' cos, sin
    grow as ``e^{|Im s|}``): there the fast one must be within TOLERANCE plus four times the general
    path's error in the value (of that order in either path) of the 70-digit solution (``exact(m)``,
    ``exact_value(m)``)."""
    scale = np.maximum(np.abs(want), scale)
    for m in np.flatnonzero(np.abs(got - want) > TOLERANCE * scale):
        value = exact_value(m)
        allowed = TOLERANCE + 4 * abs(want_value[m] - value) / abs(value)
        assert abs(got[m] - exact(m)) <= allowed * scale[m], m


@pytest.mark.parametrize("seed", SEEDS)
def test_response_matches_the_assembled_system(seed):
    p, beta, sigma = _case(seed)
    args = (beta, composed.Parameters(**p), sigma)
    got = composed.response(*args, drives=composed.DRIVES)
    want = _general(composed.response, *args, drives=composed.DRIVES)
    for part in (0, 1):
        for i, drive in enumerate(composed.DRIVES):
            exact = lambda m: _mp_value(beta[m], sigma, p, drive, part)   # noqa: E731
            _assert_close(got[part][i], want[part][i], 0.0, exact, exact, want[part][i])


@pytest.mark.parametrize("seed", SEEDS)
def test_partials_match_the_assembled_system(seed):
    p, beta, sigma = _case(seed)
    args = (beta, composed.Parameters(**p), sigma)
    values, jac = composed.slope_and_jacobian(*args, wrt=WRT, drives=composed.DRIVES)
    want_values, want_jac = _general(composed.slope_and_jacobian, *args, wrt=WRT, drives=composed.DRIVES)
    at = dict(p, beta=beta, sigma=sigma)
    for i, drive in enumerate(composed.DRIVES):
        exact_value = lambda m: _mp_value(beta[m], sigma, p, drive)   # noqa: E731
        _assert_close(values[i], want_values[i], 0.0, exact_value, exact_value, want_values[i])
        for j, name in enumerate(composed.SPOT_JACOBIAN_PARAMETERS):
            if name in WRT:
                scale = np.abs(want_values[i]) / np.where(at[name] == 0, 1.0, np.abs(at[name]))
                exact = lambda m: _mp_partial(beta[m], sigma, p, name, drive)   # noqa: E731
                _assert_close(jac[i][j], want_jac[i][j], scale, exact, exact_value, want_values[i])


@pytest.mark.parametrize("seed", [0, 5, 100, 107, 113, 119])
def test_tip_position_partial_matches_the_assembled_system(seed):
    """The partial w.r.t. ``gamma`` (compiled: from the written-out form; the NumPy forms take it from
    the assembled system, the tip at the end split into two segments), every drive, to TOLERANCE of
    the larger of itself and ``|S / gamma|``."""
    if not composed.KERNELS:
        pytest.skip("the NumPy forms' gamma partial is the general path's")
    p, beta, sigma = _case(seed)
    args = (beta, composed.Parameters(**p), sigma)
    values, jac = composed.slope_and_jacobian(*args, wrt=("gamma", "beta"), drives=composed.DRIVES)
    want_values, want_jac = _general(composed.slope_and_jacobian, *args, wrt=("gamma", "beta"),
                                     drives=composed.DRIVES)
    j = composed.SPOT_JACOBIAN_PARAMETERS.index("gamma")
    for i, drive in enumerate(composed.DRIVES):
        got, want = jac[i][j], want_jac[i][j]
        scale = np.maximum(np.abs(want), np.abs(want_values[i]) / p["gamma"])
        # where they differ, both lose digits (the base drive beyond the tip at high beta): the compiled
        # one within TOLERANCE plus four times the general one's error of the 70-digit partial
        for m in np.flatnonzero(np.abs(got - want) > TOLERANCE * scale):
            exact = _mp_partial(beta[m], sigma, p, "gamma", drive)
            assert abs(got[m] - exact) <= TOLERANCE * scale[m] + 4 * abs(want[m] - exact), (drive, m)


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
    args = (beta[index:index + 1], composed.Parameters(**p), sigma)
    i, j = composed.DRIVES.index(drive), composed.SPOT_JACOBIAN_PARAMETERS.index(name)
    exact = _mp_partial(beta[index], sigma, p, name, drive)
    scale = abs(composed.slope(*args, drives=(drive,))[0][0]) / abs(dict(p, beta=beta[index])[name])
    for path in (composed.slope_and_jacobian, lambda *a, **k: _general(composed.slope_and_jacobian, *a, **k)):
        got = path(*args, wrt=(name,), drives=(drive,))[1][0][j][0]
        assert abs(got - exact) <= TOLERANCE * scale


@pytest.mark.parametrize("seed,index,sigma", [(106, 59, 0.9), (113, 30, None), (119, 0, None), (119, 59, None),
                                                (110, 45, 1.0)])
def test_set_back_against_the_exact_beam(seed, index, sigma):
    """Set back, before and beyond the tip: every drive's slope and deflection, and the map's partials
    of the slope, within 1e-10 of the 70-digit solution (the partials relative to ``|S / p|``)."""
    p, beta, drawn = _case(seed)
    sigma, beta = drawn if sigma is None else sigma, beta[index]
    args = (beta, composed.Parameters(**p), sigma)
    got = composed.response(*args, drives=composed.DRIVES)
    exact = spot_response_mp(beta, [sigma], dps=70, **p)[0]
    for part in (0, 1):
        for i, drive in enumerate(composed.DRIVES):
            want = complex(exact[part][MP_DRIVES.index(drive)])
            assert abs(got[part][i] - want) <= TOLERANCE * abs(want), (part, drive)
    names = ("beta", "kvv", "kll", "kvl", "mu")
    values, jac = composed.slope_and_jacobian(*args, wrt=names, drives=("d1", "y0"))
    for i, drive in enumerate(("d1", "y0")):
        for name in names:
            scale = abs(values[i]) / abs(dict(p, beta=beta)[name])
            got = jac[i][composed.SPOT_JACOBIAN_PARAMETERS.index(name)]
            assert abs(got - _mp_partial(beta, sigma, p, name, drive)) <= TOLERANCE * scale, (drive, name)


@pytest.mark.parametrize("gamma,sigma", [(np.ones((2, 1, 1)), 0.8), (np.array([0.75, 1.0]).reshape(2, 1, 1), 0.8),
                                         (0.85, np.linspace(0.5, 1.0, 7))])
def test_shapes_as_the_general_path(gamma, sigma):
    """Springs as a column against a row of frequencies; ``gamma`` wider than the rest, the tip set
    back for some members, the spot before and beyond the tip in one batch."""
    at = dict(beta=np.linspace(0.5, 20.0, 7) * (1 + 0.01j), sigma=sigma, k=2.0, kvv=np.array([[0.0], [50.0], [400.0]]),
              kll=52.0, kvl=9.0, H=1e-5, L=2e-4, mu=0.1, gamma=gamma, rho_g=0.05)
    args = [at["beta"], composed.Parameters(**{n: at[n] for n in composed.PARAMETERS}), at["sigma"]]
    shape = np.broadcast_shapes(np.shape(gamma), (3, 7))
    got, want = composed.slope_and_jacobian(*args, wrt=WRT), _general(composed.slope_and_jacobian, *args, wrt=WRT)
    for i, value in enumerate(want[0]):
        assert got[0][i].shape == value.shape == shape and _relative(got[0][i], value) <= TOLERANCE
        for j, name in enumerate(composed.SPOT_JACOBIAN_PARAMETERS):
            g, w = got[1][i][j], want[1][i][j]
            assert (g is None) == (w is None) and (g is None or g.shape == w.shape == shape)
            scale = np.abs(value) / np.where(at[name] == 0, 1.0, np.abs(at[name]))
            assert g is None or _relative(g, w, scale) <= TOLERANCE, name


@pytest.mark.parametrize("seed", [3, 104, 119])
def test_drives_asked_and_the_kept_read_out_change_nothing(seed):
    """A subset of the drives, in any order, gives the full set's columns bit for bit; a read-out
    asked again at the same point (a fit's kept lever) or after another point equals a fresh one."""
    p, beta, sigma = _case(seed)
    args = (beta, composed.Parameters(**p), sigma)
    full, full_jac = composed.slope_and_jacobian(*args, wrt=WRT, drives=composed.DRIVES)
    for drives in (("y0",), ("q0", "d1"), ("f0", "m0", "d2")):
        got, jac = composed.slope_and_jacobian(*args, wrt=WRT, drives=drives)
        for i, drive in enumerate(drives):
            k = composed.DRIVES.index(drive)
            assert np.array_equal(got[i], full[k], equal_nan=True)
            assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(jac[i], full_jac[k]) if a is not None)
    other, kept = (beta * 1.01, *args[1:]), composed.LastReadOut()
    first = composed.slope(*args, kept=kept)
    composed.slope(*other, kept=kept)
    again = composed.slope(*args, kept=kept)
    fresh = composed.slope(*args)
    assert all(np.array_equal(a, b, equal_nan=True) and np.array_equal(a, c, equal_nan=True)
               for a, b, c in zip(first, again, fresh))
    values, _ = composed.slope_and_jacobian(*args, wrt=("beta",), kept=kept)
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(values, first))
    # what a caller does to the results does not reach the kept read-out
    slopes, deflections = composed.response(*args, kept=kept)
    want = [d.copy() for d in deflections]
    for a in (*slopes, *deflections):
        a -= 1.0
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(composed.response(*args, kept=kept)[1], want))
