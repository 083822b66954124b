"""Compiled steps of the trust-region reflective least squares of :mod:`pfmdyn.fitting.trust_region`.

Each step is what ``scipy.optimize.least_squares(method="trf")`` does between two evaluations of the
residual, operation for operation (the same products through BLAS, the same square roots, the same order
of the bounds' tests), so that a fit takes the same steps; there it is some hundred NumPy calls on vectors
of a few parameters, their overhead a fifth of a discrepancy analysis.  Imported lazily (numba's import
stays out of the command line's start-up).
"""
from __future__ import annotations

import numba
import numpy as np

__all__ = ["feasible", "scaling", "augmented", "trial"]

EPS = np.finfo(float).eps


@numba.njit(cache=True)
def feasible(x, lower, upper, rstep):
    """``x`` moved inside the bounds: a coordinate within ``rstep`` (relative, at least absolute) of a bound
    to that distance from it, or, with ``rstep`` 0, to the next number inside; between two bounds closer
    than that, to their middle.

    >>> float(feasible(np.array([0.0]), np.array([0.0]), np.array([1.0]), 1e-10)[0])
    1e-10
    """
    out = x.copy()
    for i in range(x.shape[0]):
        lo, up = lower[i], upper[i]
        active = 0
        if rstep == 0.0:
            if x[i] <= lo:
                active = -1
            if x[i] >= up:
                active = 1
        else:
            below, above = x[i] - lo, up - x[i]
            if np.isfinite(lo) and below <= min(above, rstep * max(1.0, abs(lo))):
                active = -1
            if np.isfinite(up) and above <= min(below, rstep * max(1.0, abs(up))):
                active = 1
        if active == -1:
            out[i] = np.nextafter(lo, up) if rstep == 0.0 else lo + rstep * max(1.0, abs(lo))
        elif active == 1:
            out[i] = np.nextafter(up, lo) if rstep == 0.0 else up - rstep * max(1.0, abs(up))
        if out[i] < lo or out[i] > up:
            out[i] = 0.5 * (lo + up)
    return out


@numba.njit(cache=True)
def scaling(x, g, lower, upper, v, dv):
    """Coleman and Li's scaling ``v`` (the distance to the bound the gradient ``g`` points away from, else 1)
    and its derivative ``dv``, written into them; returns the largest ``|g v|`` (NaN if one is)."""
    largest, nan = 0.0, False
    for i in range(x.shape[0]):
        v[i], dv[i] = 1.0, 0.0
        if g[i] < 0 and np.isfinite(upper[i]):
            v[i], dv[i] = upper[i] - x[i], -1.0
        if g[i] > 0 and np.isfinite(lower[i]):
            v[i], dv[i] = x[i] - lower[i], 1.0
        a = abs(g[i] * v[i])
        nan = nan or a != a
        largest = max(largest, a)
    return np.nan if nan else largest


@numba.njit(cache=True)
def augmented(J, g, v, dv, d, diag_h, g_h, J_h, A):
    """The scaled problem of one iteration: ``d = sqrt(v)``, ``diag_h = g dv``, ``g_h = d g``, ``J_h = J d``
    and ``A`` (Fortran order, for LAPACK) ``J_h`` above ``diag(sqrt(diag_h))``; returns whether ``A`` is
    finite."""
    m, n = J.shape
    for j in range(n):
        d[j] = np.sqrt(v[j])
        diag_h[j] = g[j] * dv[j]
        g_h[j] = d[j] * g[j]
    finite = True
    for i in range(m):
        for j in range(n):
            J_h[i, j] = J[i, j] * d[j]
            A[i, j] = J_h[i, j]
            finite = finite and np.isfinite(J_h[i, j])
    for i in range(n):
        for j in range(n):
            A[m + i, j] = np.sqrt(diag_h[j]) if i == j else 0.0
        finite = finite and np.isfinite(A[m + i, i])
    return finite


@numba.njit(cache=True)
def _norm(x):
    return np.sqrt(np.dot(x, x))


@numba.njit(cache=True)
def _to_bound(x, s, lower, upper, hits):
    """The step along ``s`` from ``x`` to the first bound it meets; ``hits``: which (-1 lower, 1 upper)."""
    steps = np.full(x.shape[0], np.inf)
    for i in range(x.shape[0]):
        if s[i] != 0:
            steps[i] = max((lower[i] - x[i]) / s[i], (upper[i] - x[i]) / s[i])
    least = np.min(steps)
    for i in range(x.shape[0]):
        hits[i] = int(np.sign(s[i])) if steps[i] == least else 0
    return least


@numba.njit(cache=True)
def _quadratic(J_h, g_h, diag_h, s):
    """``0.5 s^T (J_h^T J_h + diag_h) s + g_h^T s``."""
    Js = np.dot(J_h, s)
    q = np.dot(Js, Js)
    q += np.dot(s * diag_h, s)
    return 0.5 * q + np.dot(s, g_h)


@numba.njit(cache=True)
def _least_on_segment(a, b, lo, up, c):
    """The least of ``a t^2 + b t + c`` for ``lo <= t <= up``: ``(t, value)``."""
    ts = np.array([lo, up, 0.0])
    k = 2
    if a != 0:
        extremum = -0.5 * b / a
        if lo < extremum < up:
            ts[2] = extremum
            k = 3
    ts = ts[:k]
    y = ts * (a * ts + b) + c
    i = np.argmin(y)
    return ts[i], y[i]


@numba.njit(cache=True)
def _sum(a):
    """NumPy's sum of a short vector (up to 128 terms): in turn below 8, else pairwise from eight partial sums."""
    n = a.shape[0]
    if n < 8:
        total = -0.0
        for i in range(n):
            total += a[i]
        return total
    r = a[:8].copy()
    i = 8
    while i < n - n % 8:
        for j in range(8):
            r[j] += a[i + j]
        i += 8
    total = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for j in range(i, n):
        total += a[j]
    return total


@numba.njit(cache=True)
def _phi(alpha, suf, s, Delta):
    denom = s * s + alpha
    p_norm = _norm(suf / denom)
    return p_norm - Delta, -_sum(suf * suf / denom**3.0) / p_norm


@numba.njit(cache=True)
def _trust_region_step(m, uf, s, V, Delta, alpha):
    """Moré's solution of the trust-region subproblem from one SVD: ``(p_h, alpha)``."""
    n = s.shape[0]
    suf = s * uf
    full_rank = m >= n and s[-1] > EPS * m * s[0]
    if full_rank:
        p = -np.dot(V, uf / s)
        if _norm(p) <= Delta:
            return p, 0.0
    alpha_upper = _norm(suf) / Delta
    alpha_lower = 0.0
    if full_rank:
        phi, phi_prime = _phi(0.0, suf, s, Delta)
        alpha_lower = -phi / phi_prime
    if not full_rank and alpha == 0:
        alpha = max(0.001 * alpha_upper, (alpha_lower * alpha_upper) ** 0.5)
    for _ in range(10):
        if alpha < alpha_lower or alpha > alpha_upper:
            alpha = max(0.001 * alpha_upper, (alpha_lower * alpha_upper) ** 0.5)
        phi, phi_prime = _phi(alpha, suf, s, Delta)
        if phi < 0:
            alpha_upper = alpha
        ratio = phi / phi_prime
        alpha_lower = max(alpha_lower, alpha - ratio)
        alpha -= (phi + Delta) * ratio / Delta
        if np.abs(phi) < 0.01 * Delta:
            break
    p = -np.dot(V, suf / (s * s + alpha))
    p *= Delta / _norm(p)
    return p, alpha


@numba.njit(cache=True)
def trial(x, J_h, diag_h, g_h, d, uf, s, V, Delta, alpha, theta, lower, upper):
    """One trial step of an iteration: the trust region's step, reflected at a bound it crosses or along
    the gradient where either is better (Branch, Coleman and Li), kept strictly inside.  Returns the new
    point, the step's norm in the scaled variables, its predicted reduction of the cost, and ``alpha``."""
    m, n = J_h.shape
    p_h, alpha = _trust_region_step(m, uf, s, V, Delta, alpha)
    p = d * p_h
    hits = np.zeros(n, np.int64)
    inside = True
    for i in range(n):
        inside = inside and x[i] + p[i] >= lower[i] and x[i] + p[i] <= upper[i]
    if inside:
        step, step_h, predicted = p, p_h, -_quadratic(J_h, g_h, diag_h, p_h)
    else:
        p_stride = _to_bound(x, p, lower, upper, hits)
        r_h = p_h.copy()
        for i in range(n):
            if hits[i] != 0:
                r_h[i] *= -1
        r = d * r_h
        p = p * p_stride
        p_h = p_h * p_stride
        # where the reflected direction leaves the trust region
        a, b = np.dot(r_h, r_h), np.dot(p_h, r_h)
        if a == 0:
            raise ValueError("`s` is zero.")
        c = np.dot(p_h, p_h) - Delta * Delta
        if c > 0:
            raise ValueError("`x` is not within the trust region.")
        q = -(b + np.copysign(np.sqrt(b * b - a * c), b))
        to_tr = max(q / a, c / q)
        to_bound = _to_bound(x + p, r, lower, upper, hits)
        r_stride = min(to_bound, to_tr)
        if r_stride > 0:
            r_lo = (1 - theta) * p_stride / r_stride
            r_up = theta * to_bound if r_stride == to_bound else to_tr
        else:
            r_lo, r_up = 0.0, -1.0
        r_value = np.inf
        if r_lo <= r_up:
            v = np.dot(J_h, r_h)
            qa = np.dot(v, v)
            qa += np.dot(r_h * diag_h, r_h)
            qa *= 0.5
            qb = np.dot(g_h, r_h)
            u = np.dot(J_h, p_h)
            qb += np.dot(u, v)
            qc = 0.5 * np.dot(u, u) + np.dot(g_h, p_h)
            qb += np.dot(p_h * diag_h, r_h)
            qc += 0.5 * np.dot(p_h * diag_h, p_h)
            r_stride, r_value = _least_on_segment(qa, qb, r_lo, r_up, qc)
            r_h = r_h * r_stride
            r_h += p_h
            r = r_h * d
        p = p * theta
        p_h = p_h * theta
        p_value = _quadratic(J_h, g_h, diag_h, p_h)
        ag_h = -g_h
        ag = d * ag_h
        to_tr = Delta / _norm(ag_h)
        to_bound = _to_bound(x, ag, lower, upper, hits)
        ag_stride = theta * to_bound if to_bound < to_tr else to_tr
        v = np.dot(J_h, ag_h)
        qa = np.dot(v, v)
        qa += np.dot(ag_h * diag_h, ag_h)
        qa *= 0.5
        ag_stride, ag_value = _least_on_segment(qa, np.dot(g_h, ag_h), 0.0, ag_stride, 0.0)
        ag_h = ag_h * ag_stride
        ag = ag * ag_stride
        if p_value < r_value and p_value < ag_value:
            step, step_h, predicted = p, p_h, -p_value
        elif r_value < p_value and r_value < ag_value:
            step, step_h, predicted = r, r_h, -r_value
        else:
            step, step_h, predicted = ag, ag_h, -ag_value
    return feasible(x + step, lower, upper, 0.0), _norm(step_h), _norm(step), predicted, alpha
