"""Compiled evaluation of one step of a peak fit (:func:`pfmdyn.discrepancy.peaks._peak_fit`).

A peak fit asks, a few dozen times per start, for the undamped resonances of one lever, their
sensitivities and their match to the measured peaks: in NumPy some fifty calls on arrays of two to
five numbers around a compiled root search of 25 us.  :func:`match_and_jacobian` takes the same steps
in one compiled call: the roots (:func:`pfmdyn.composed.kernels.characteristic_roots`), their
frequencies, the characteristic's partials there (the tip's jump compiled, where NumPy evaluates the
generated jump: the two differ in the last bit), the sensitivities
(:func:`pfmdyn.discrepancy.undamped_modes.resonance_sensitivity`) and the match with its Jacobian
(:func:`pfmdyn.discrepancy.peaks.peak_match`).  The NumPy path is the reference
(``tests/test_formulas.py``).

Imported lazily (numba's import stays out of the command line's start-up).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from ..compiled import forget_when_changed
from ..composed import kernels
from ..composed.kernels import characteristic_partials, characteristic_roots, tip_at_end_and_partials, tip_point
from ..generated import formulas

__all__ = ["match_and_jacobian"]

_frequency_from_beta, _beta_from_frequency, _frequency_change = (
    numba.njit(cache=True)(f) for f in (formulas.frequency_from_beta, formulas.beta_from_frequency,
                                        formulas.frequency_change))


@numba.njit(cache=True)
def _summed(a, n):
    """``numpy.sum(a[:n])`` in NumPy's order (one by one below eight terms, eight running sums up
    to 128), for its bits."""
    if n < 8:
        total = 0.0
        for i in range(n):
            total += a[i]
        return total
    r = a[:8].copy()
    top = n - n % 8
    for i in range(8, top, 8):
        for j in range(8):
            r[j] += a[i + j]
    total = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for i in range(top, n):
        total += a[i]
    return total


@numba.njit(cache=True, error_model="numpy")
def match_and_jacobian(grid, lever, b1, d_b1, f1, moved, per_unit, tip_at_end, peaks, band, unseen, out, jac):
    """The match of the resonances of ``lever`` (1 x 9, real: the characteristic's parameters) to
    ``peaks`` (Hz) in ``band`` into ``out`` (peaks + 1), its Jacobian w.r.t. the moving parameters into
    ``jac`` (peaks + 1, moving).  The roots are bracketed on ``grid`` (beta) and refined, the
    frequencies ``f1 (beta / b1)**2``; ``d_b1`` is the free root's change per moving parameter;
    ``per_unit[j, c]`` the change of the characteristic's parameter ``moved[j]`` (its index) per unit
    of moving parameter ``c``; ``tip_at_end``: the product rule over the tip's jump (``gamma`` 1 and
    fixed), else complex steps (:func:`pfmdyn.composed.kernels.characteristic_partials`).

    Examples
    --------
    >>> lever = np.array([[1.0, 100.0, 100.0, 0.0, 1e-5, 1e-4, 0.0, 1.0, 0.0]])
    >>> grid = np.linspace(0.3, 5.0, 150)
    >>> out, jac = np.empty(2), np.empty((2, 1))
    >>> match_and_jacobian(grid, lever, 1.8751040687119611, np.zeros(1), 1e4, np.array([1]), np.ones((1, 1)),
    ...                    True, np.array([4.6e4]), np.array([1e4, 5e4]), False, out, jac)
    >>> out.round(4).tolist(), bool(jac[0, 0] > 0)      # contact mode 1 at 4.61e4 Hz: kvv pushes it up
    ([0.0023, 0.0023], True)
    """
    roots = characteristic_roots(grid, lever, True, 1e-13)
    n, r, cols, count = roots.shape[0], moved.shape[0], jac.shape[1], peaks.shape[0]
    jac[:, :] = 0.0
    if n == 0:
        out[:] = 10.0
        return
    f, beta = np.empty(n), np.empty(n)
    for i in range(n):
        f[i] = _frequency_from_beta(roots[i], f1, b1)
        beta[i] = _beta_from_frequency(f[i], f1, b1)
    # the characteristic's partials at the roots: beta first, then the parameters that move
    d = np.empty((r + 1, n))
    if tip_at_end:
        params = lever[0]
        each = [np.full(n, params[j]) for j in range(9)]
        codes = np.empty(r + 1, np.int64)
        codes[0] = 0
        for j in range(r):
            codes[j + 1] = moved[j] + 1 if moved[j] < 4 else 5     # of JACOBIAN_PARAMETERS: kvv, kll, kvl or mu
        jump, djump = np.empty((n, 12)), np.empty((r + 1, n, 12))
        tip_point(beta, each[0], each[1], each[2], each[3], each[4], each[5], each[6], each[8], codes, jump, djump)
        tip_at_end_and_partials(beta, jump, djump, 0, np.empty(n), d)
    else:
        at = np.empty(r + 1, np.int64)
        at[0] = -1
        at[1:] = moved
        characteristic_partials(beta, lever[0], at, d)
    # the sensitivities d f / d p (frequency_change), then the match (peak_match)
    sens = np.empty((n, cols))
    for i in range(n):
        for c in range(cols):
            acc = 0.0
            for j in range(r):
                acc += d[j + 1, i] / d[0, i] * per_unit[j, c]
            value = _frequency_change(f[i], beta[i], -acc, b1, d_b1[c])
            sens[i, c] = value if np.isfinite(value) else 0.0
    lr = np.log(f)
    for k in range(count):
        lp = math.log(peaks[k])
        near = 0
        for i in range(1, n):
            if abs(lr[i] - lp) < abs(lr[near] - lp):
                near = i
        out[k] = abs(lr[near] - lp)
        sign = 1.0 if lr[near] > lp else -1.0 if lr[near] < lp else 0.0
        for c in range(cols):
            jac[k, c] = sign * (sens[near, c] / f[near])
    squares, gaps, inside = np.empty(n), np.empty(n), np.empty(n, np.int64)
    m = 0
    for i in range(n):
        if f[i] > band[0] and f[i] < band[1] and not unseen:
            partner = 0
            for k in range(1, count):
                if abs(math.log(peaks[k]) - lr[i]) < abs(math.log(peaks[partner]) - lr[i]):
                    partner = k
            gaps[m] = lr[i] - math.log(peaks[partner])
            squares[m] = gaps[m] ** 2
            inside[m] = i
            m += 1
    back = math.sqrt(_summed(squares, m))
    out[count] = back
    if back > 0:
        for c in range(cols):
            acc = 0.0
            for q in range(m):
                acc += gaps[q] * (sens[inside[q], c] / f[inside[q]])
            jac[count, c] = acc / back


# the composed lever's kernels (and what they compile in) and the generated formulas are compiled in here
forget_when_changed(__name__, kernels, *kernels.COMPILED_FROM, formulas)
