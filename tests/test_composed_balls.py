"""pfmdyn.composed.balls against the composed lever in NumPy (``pfmdyn.composed``) and the
independent two-segment beam solved in mpmath (``tests/segment_beam.py``: textbook basis, no
``derivations/`` or ``generated/``): the same resonances, certified balls holding the exact
beam's roots, the same blind spots."""
import sys
from fractions import Fraction
from pathlib import Path

import flint
import mpmath
import numpy as np
import pytest
from scipy.optimize import brentq

from pfmdyn import composed
from pfmdyn.derivations.certify import certify
from pfmdyn.generated.characteristic import FLINT
from pfmdyn.generated.lever_pieces import point_jump
from pfmdyn.composed.balls import PAIRS, _field, _field_minors, characteristic_balls, q0_slope, q0_slope_coefficients

# The independent reference lives beside the tests (importlib mode: not on sys.path).
sys.path.insert(0, str(Path(__file__).parent))
from segment_beam import determinant_mp, spot_response_mp  # noqa: E402

L, H = 2e-4, 1e-5
# (k, kvv/k, kll/kvv, tilt rad, mu, gamma, rho_g): free, heavy tip, soft and stiff contacts, tilted.
LEVERS = [(2.0, 0, 0, 0, 0.1, 1.0, 0.02), (0.05, 1, 0.5, 0.2, 0.5, 0.8, 0.05), (50.0, 1e4, 0.85, 0.25, 0.0, 0.95, 0.0),
          (1.3, 300, 0.3, 0.1, 0.25, 0.87, 0.03), (7.0, 30, 1.0, 0.3, 0.4, 0.92, 0.01)]


def _params(k, kvv_k, kll_kvv, tilt, mu, gamma, rho):
    kvv = kvv_k * k
    return (k, kvv, kll_kvv * kvv, -0.5 * kvv * np.tan(tilt), H, L, mu, gamma, rho)


def _roots(f, lo, hi, n=3000):
    x = np.linspace(lo, hi, n)
    y = [f(v) for v in x]
    return np.array([brentq(f, x[i], x[i + 1], xtol=1e-15) for i in range(n - 1) if y[i] * y[i + 1] < 0])


def test_scaled_jump_is_beta_cubed_jump():
    """The jump's matrix J (what the ball characteristic uses) at beta is beta**-3 times J at 1 with
    H, mu and rho_g rescaled."""
    args = (2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.05)
    for beta in (0.3, 2.5, 11.0):
        direct = np.array(point_jump(beta, *args)[:4]) * beta**3
        k, kvv, kll, kvl, H_, L_, mu, rho = args
        scaled = point_jump(1, k, kvv, kll, kvl, H_ * beta, L_, mu * beta**4, rho * beta)[:4]
        assert np.allclose(scaled, direct, rtol=1e-13)


@pytest.mark.parametrize("s", [0.3, 0.49, 0.51, 2.0, 7.5])
def test_minors_match_the_field_matrix(s):
    mpmath.mp.dps = 30
    F = _field(mpmath.mpf(s), mpmath)
    closed = _field_minors(mpmath.mpf(s), mpmath, [(I, J) for I in PAIRS for J in PAIRS])
    series = _field_minors(flint.arb_series([flint.arb(s)], prec=1), FLINT, list(closed)) if s <= 0.5 else None
    for (I, J), v in closed.items():
        plain = F[I[0]][J[0]] * F[I[1]][J[1]] - F[I[0]][J[1]] * F[I[1]][J[0]]
        assert abs(v - plain) < 1e-25 * mpmath.cosh(s) ** 2
        if series is not None:
            assert series[I, J][0].contains(flint.arb(mpmath.nstr(v, 28)) if abs(v) > 1e-20 else 0) or \
                abs(float(series[I, J][0].mid()) - float(v)) < 1e-25


def _named(p):
    return dict(zip(composed.PARAMETERS, p))


def _exact_root(p, near, width=1e-9):
    """The independent beam's root next to ``near`` (mpmath, 40 digits), bracketed within ``width``."""
    f = lambda b: determinant_mp(b, dps=40, **_named(p))   # noqa: E731
    lo, hi = mpmath.mpf(near) * (1 - width), mpmath.mpf(near) * (1 + width)
    assert f(lo) * f(hi) < 0, near
    with mpmath.workdps(40):
        root = mpmath.findroot(f, (lo, hi), solver="anderson", tol=mpmath.mpf(10) ** -70, verify=False)
    assert lo <= root <= hi
    return root


@pytest.mark.parametrize("lever", LEVERS)
def test_real_zeros_are_those_of_the_composed_characteristic(lever):
    """Every real zero below 20 of the ball characteristic (evaluated in mpmath) is one of the
    NumPy composed characteristic's, and a root of the exact beam (sign change within 1e-9)."""
    p = _params(*lever)
    mpmath.mp.dps = 40
    mine = _roots(lambda b: float(characteristic_balls(mpmath.mpf(b), mpmath, *map(mpmath.mpf, p))), 0.3, 20)
    theirs = _roots(lambda b: float(composed.characteristic(b, composed.Parameters(*p))), 0.3, 20)
    assert len(mine) == len(theirs) >= 4
    assert np.allclose(mine, theirs, rtol=1e-13, atol=0)
    exact = np.array([float(_exact_root(p, b)) for b in mine])
    assert np.allclose(mine, exact, rtol=1e-14, atol=0)


def _certified(fn, p, count=4):
    exact = [flint.fmpq(*Fraction(v).as_integer_ratio()) for v in p]
    balls = [flint.arb(v) for v in exact]
    old = flint.ctx.prec
    try:
        return certify(lambda s: fn(s, FLINT, *balls), count, 15, f_exact=lambda s: fn(s, FLINT, *exact))
    finally:
        flint.ctx.prec = old


@pytest.mark.parametrize("lever", LEVERS)
def test_certified_roots_hold_the_exact_beams(lever):
    """The certified balls hold the exact beam's roots (same float parameters, 35 digits), and
    the composed NumPy characteristic changes sign across each."""
    p = _params(*lever)
    mine, top = _certified(characteristic_balls, p)
    for a in mine:
        root = _exact_root(p, float(a.mid()))
        assert a.overlaps(flint.arb(mpmath.nstr(root, 35), 1e-30)), (a, root)
        assert abs(float(a.mid()) / float(root) - 1) < 1e-13
        lo, hi = (float(v) for v in (a.lower(), a.upper()))
        h = 1e-12 * float(root)
        assert composed.characteristic(lo - h, composed.Parameters(*p)) * \
            composed.characteristic(hi + h, composed.Parameters(*p)) < 0
    assert float(top.mid()) >= float(mine[-1].mid())       # complete up to there


def test_order_six_at_the_origin():
    for lever in LEVERS:
        exact = [flint.fmpq(*Fraction(v).as_integer_ratio()) for v in _params(*lever)]
        coeffs = characteristic_balls(flint.fmpq_series([0, 1], prec=10), FLINT, *exact).coeffs()
        assert all(c == 0 for c in coeffs[:6]) and coeffs[6] > 0


def _exact_blind_spot(beta, p, near):
    """The independent beam's zero of the q0 slope next to ``near`` (mpmath, 60 digits)."""
    f = lambda x: mpmath.re(spot_response_mp(beta, [x], **_named(p))[0][0][3])   # noqa: E731
    with mpmath.workdps(30):
        return float(mpmath.findroot(f, mpmath.mpf(near), tol=mpmath.mpf(10) ** -25))


@pytest.mark.parametrize("lever, beta", [(LEVERS[1], 9.0), (LEVERS[3], 11.5), (LEVERS[4], 6.0), (LEVERS[2], 2.0),
                                         ((2.0, 20, 0.5, 0.1, 0.2, 0.8, 0.02), 14.0)])
def test_q0_slope_has_the_composed_blind_spots(lever, beta):
    """The numerator's zeros on each branch are the composed slope's and the exact beam's; its
    ratio to the composed slope does not depend on the spot; it is continuous at the tip."""
    k, kvv, kll, kvl, H_, L_, mu, gamma, rho = p = _params(*lever)
    dim = dict(kvv_over_k=kvv / k, kll_ratio=kll * H_**2 / (k * L_**2), kvl_ratio=kvl * H_ / (k * L_),
               mu=mu, gamma=gamma, rho_g=rho)
    mpmath.mp.dps = 50
    mine = q0_slope_coefficients(mpmath, beta=mpmath.mpf(beta), **{n: mpmath.mpf(v) for n, v in dim.items()})
    assert mine["before"][4] == 0 == mine["beyond"][4]
    for branch, lo, hi in (("before", 1e-6, gamma), ("beyond", gamma, 1.0)):
        if hi - lo < 1e-9:
            continue
        f = lambda x: float(q0_slope(mpmath.mpf(x), mpmath, mine[branch], mpmath.mpf(beta)))   # noqa: E731
        g = lambda x: float(composed.slope(beta, composed.Parameters(*p), x)[3])                 # noqa: E731
        zm, zt = _roots(f, lo, hi, 600), _roots(g, lo, hi, 600)
        assert len(zm) == len(zt) and np.allclose(zm, zt, atol=1e-12)
        exact = [_exact_blind_spot(beta, p, z) for z in zm]
        assert np.allclose(zm, exact, atol=1e-13)
        sigma = np.linspace(lo + 0.05 * (hi - lo), hi, 5)
        ratio = [f(s) / composed.slope(beta, composed.Parameters(*p), s)[3] for s in sigma]
        assert np.ptp(ratio) < 1e-10 * abs(np.mean(ratio))
    at_tip = [q0_slope(mpmath.mpf(gamma), mpmath, mine[b], mpmath.mpf(beta)) for b in ("before", "beyond")]
    assert abs(at_tip[0] - at_tip[1]) < 1e-30 * abs(at_tip[0])


def test_q0_slope_in_balls():
    c = q0_slope_coefficients(FLINT, beta=flint.arb(5), gamma=flint.arb("0.9"), mu=flint.arb("0.1"),
                              rho_g=flint.arb("0.02"), kvv_over_k=flint.arb(50), kll_ratio=flint.arb("0.1"),
                              kvl_ratio=flint.arb("-0.2"))
    m = q0_slope_coefficients(mpmath, beta=mpmath.mpf(5), gamma=mpmath.mpf("0.9"), mu=mpmath.mpf("0.1"),
                              rho_g=mpmath.mpf("0.02"), kvv_over_k=50, kll_ratio=mpmath.mpf("0.1"),
                              kvl_ratio=mpmath.mpf("-0.2"))
    for b in ("before", "beyond"):
        value = q0_slope(flint.arb_series([flint.arb("0.95"), 1], prec=2), FLINT, c[b], flint.arb(5))
        assert abs(float(value[0].mid()) / float(q0_slope(mpmath.mpf("0.95"), mpmath, m[b], 5)) - 1) < 1e-12
