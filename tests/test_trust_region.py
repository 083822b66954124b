"""The compiled trust-region least squares (:mod:`pfmdyn.fitting.trust_region`) against SciPy's, the reference:
the same evaluations, the same stopping and the same solution, on problems drawn over wide ranges, with bounds
the solution presses against, a rank-deficient Jacobian, a residual that is not finite past a point, a start
on a bound, and evaluation budgets that stop a fit early (a discrepancy analysis's trials)."""
import numpy as np
import pytest
from scipy.optimize import least_squares as scipy_least_squares

from pfmdyn.fitting.trust_region import least_squares


def _resonance(seed):
    """An oscillator's amplitude and phase over a band around its resonance (f0, Q, scale as log10), noisy."""
    rng = np.random.default_rng(seed)
    f0, q, a = 10 ** rng.uniform(3.5, 6.5), 10 ** rng.uniform(0.7, 2.7), 10 ** rng.uniform(-3, 1)
    f = np.sort(rng.uniform(1 - 3 / q, 1 + 3 / q, rng.integers(40, 300))) * f0
    truth = np.log10([f0, q, a])

    def response(x):
        r = f / 10 ** x[0]
        return 10 ** x[2] / (1 - r * r + 1j * r / 10 ** x[1])

    y = response(truth)
    y = y + 0.02 * np.abs(y).max() * (rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f)))

    def fun(x):
        d = response(x) - y
        return np.concatenate([d.real, d.imag])

    def jac(x):
        r, q_ = f / 10 ** x[0], 10 ** x[1]
        h = response(x)
        dh_dr = -h * h / 10 ** x[2] * (-2 * r + 1j / q_)
        cols = [dh_dr * (-r * np.log(10)), -h * h / 10 ** x[2] * (-1j * r / q_) * np.log(10), h * np.log(10)]
        J = np.stack(cols, axis=1)
        return np.concatenate([J.real, J.imag])

    start = truth + rng.uniform(-1.0, 1.0, 3) * np.array([1.5 / q, 1.0, 1.0])
    lower, upper = truth - rng.uniform(0.05, 1.0, 3), truth + rng.uniform(0.05, 1.0, 3)
    return fun, jac, np.clip(start, lower, upper), (lower, upper)


def _same(fun, jac, x0, bounds, max_nfev):
    ours = least_squares(fun, jac, x0, bounds, max_nfev)
    ref = scipy_least_squares(fun, x0, jac=jac, bounds=bounds, method="trf", max_nfev=max_nfev, x_scale=1.0)
    assert (ours.nfev, ours.njev, ours.status) == (ref.nfev, ref.njev, ref.status)
    np.testing.assert_allclose(ours.x, ref.x, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(ours.cost, ref.cost, rtol=1e-10)
    np.testing.assert_allclose(ours.jac, ref.jac, rtol=1e-10, atol=1e-300)


@pytest.mark.parametrize("max_nfev", [4, 30, 200])
def test_resonance_fits_take_scipys_steps(max_nfev):
    # the same evaluations and stopping, and the same point within the tolerances of _same; here all 90 end on the
    # same bits too, but that depends on the platform (NumPy's vectorised power and its BLAS against SciPy's),
    # so it is not asserted
    for seed in range(30):
        _same(*_resonance(seed), max_nfev)


def test_bounds_that_hold_the_solution():
    """The unconstrained minimum lies outside: the steps reflect at the bounds and end on them."""
    t = np.linspace(0, 4, 60)
    y = 3.0 * np.exp(-0.7 * t) + 0.5

    def fun(x):
        return x[0] * np.exp(-x[1] * t) + x[2] - y

    def jac(x):
        e = np.exp(-x[1] * t)
        return np.stack([e, -x[0] * t * e, np.ones_like(t)], axis=1)

    for lower, upper in [([0, 0, 0], [2.0, 5, 5]), ([3.5, 0, 0], [9, 0.5, 5]), ([-1, 1.0, -1], [9, 5, 0.2])]:
        bounds = (np.array(lower, float), np.array(upper, float))
        x0 = np.clip([1.0, 2.0, 0.0], *bounds)
        _same(fun, jac, x0, bounds, 100)
        sol = least_squares(fun, jac, x0, bounds, 100)
        assert np.any(np.isclose(sol.x, bounds[0]) | np.isclose(sol.x, bounds[1]))


def test_rank_deficient_and_start_on_a_bound():
    """Two parameters that enter as a product (a Jacobian of rank one), from a start on a bound."""
    t = np.linspace(0, 1, 30)

    def fun(x):
        return x[0] * x[1] * t - 2.0 * t

    def jac(x):
        return np.stack([x[1] * t, x[0] * t], axis=1)

    _same(fun, jac, np.array([0.1, 1.0]), (np.array([0.1, 0.1]), np.array([10.0, 10.0])), 50)


def test_a_residual_not_finite_past_a_point():
    """A step into the region where the residual is not finite shrinks the trust region, as SciPy's."""
    t = np.linspace(0, 1, 25)

    def fun(x):
        r = np.exp(x[0] * t) - np.exp(2.0 * t)
        return r if x[0] < 2.5 else np.full_like(t, np.inf)

    def jac(x):
        return (t * np.exp(x[0] * t))[:, None]

    _same(fun, jac, np.array([-3.0]), (np.array([-5.0]), np.array([5.0])), 60)


def test_bad_starts_are_refused_as_scipy_does():
    fun, jac, x0, bounds = _resonance(0)
    with pytest.raises(ValueError, match="outside of provided bounds"):
        least_squares(fun, jac, bounds[1] + 1.0, bounds, 10)
    with pytest.raises(ValueError, match="not finite in the initial point"):
        least_squares(lambda x: np.full(3, np.nan), lambda x: np.ones((3, 1)), [0.0], ([-1.0], [1.0]), 10)
