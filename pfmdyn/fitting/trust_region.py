"""Bounded nonlinear least squares by the trust-region reflective method, its steps compiled.

:func:`least_squares` takes the steps of ``scipy.optimize.least_squares(method="trf")`` with the exact
trust-region solver, unit ``x_scale`` and the linear loss (Branch, Coleman and Li's scaling and reflection,
Moré's step from one SVD of the scaled Jacobian), for problems of a few parameters whose residual and
Jacobian are themselves compiled: a discrepancy analysis runs some three hundred such fits, and SciPy's
hundred NumPy calls on short vectors per evaluation were a fifth of its time.  Here an evaluation costs
one compiled call (:func:`pfmdyn.fitting.trust_region_kernel.trial`), an iteration two more and LAPACK's
SVD, which is SciPy's own (``gesdd`` with the workspace it asks).  SciPy's function is the reference
(:data:`COMPILED` False), and ``tests/test_trust_region.py`` holds the two to the same steps.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

__all__ = ["COMPILED", "Solution", "least_squares"]

COMPILED = True
"""Whether :func:`least_squares` runs the compiled steps; False: ``scipy.optimize.least_squares``, the
reference."""


@dataclass
class Solution:
    """A solution of :func:`least_squares`, named as SciPy's: the point ``x``, ``cost`` (half the sum of
    squares), the residual ``fun`` and Jacobian ``jac`` there, the gradient ``grad``, ``optimality`` (the
    scaled gradient's largest element), the evaluations ``nfev`` and ``njev``, and ``status`` (SciPy's
    codes: 0 out of evaluations, 1 gradient, 2 cost, 3 step, 4 cost and step)."""

    x: np.ndarray
    cost: float
    fun: np.ndarray
    jac: np.ndarray
    grad: np.ndarray
    optimality: float
    nfev: int
    njev: int
    status: int


def least_squares(fun, jac, x0, bounds, max_nfev: int, ftol: float = 1e-8, xtol: float = 1e-8,
                  gtol: float = 1e-8):
    """Minimise ``0.5 * sum(fun(x)**2)`` within ``bounds`` (lower, upper) from ``x0`` in at most ``max_nfev``
    evaluations of ``fun``; ``jac(x)``: the Jacobian (dense).  Returns a :class:`Solution`.

    >>> t = np.linspace(0.0, 1.0, 20)
    >>> y = 2.0 * np.exp(-3.0 * t)
    >>> fun = lambda x: x[0] * np.exp(-x[1] * t) - y
    >>> jac = lambda x: np.stack([np.exp(-x[1] * t), -x[0] * t * np.exp(-x[1] * t)], axis=1)
    >>> sol = least_squares(fun, jac, [1.0, 1.0], ([0.0, 0.0], [10.0, 10.0]), 50)
    >>> [round(float(v), 9) for v in sol.x], sol.status > 0
    ([2.0, 3.0], True)
    """
    lower, upper = (np.broadcast_to(np.asarray(b, float), np.shape(x0)).copy() for b in bounds)
    if not COMPILED:
        from scipy.optimize import least_squares as reference
        return reference(fun, x0, jac=jac, bounds=(lower, upper), method="trf", max_nfev=max_nfev, ftol=ftol,
                         xtol=xtol, gtol=gtol, x_scale=1.0)
    from . import trust_region_kernel as kernel

    x = np.atleast_1d(np.asarray(x0, float))
    if not ((x >= lower) & (x <= upper)).all():
        raise ValueError("Initial guess is outside of provided bounds")
    x = kernel.feasible(x, lower, upper, 1e-10)
    f, J = np.atleast_1d(fun(x)), np.atleast_2d(jac(x))
    if not np.all(np.isfinite(f)):
        raise ValueError("Residuals are not finite in the initial point.")
    m, n = J.shape
    nfev = njev = 1
    cost = 0.5 * np.dot(f, f)
    g = J.T.dot(f)
    v, dv, d, diag_h, g_h = (np.empty(n) for _ in range(5))
    J_h, A, f_aug = np.empty((m, n)), np.empty((m + n, n), order="F"), np.zeros(m + n)
    kernel.scaling(x, g, lower, upper, v, dv)
    delta = np.linalg.norm(x / v**0.5)
    if delta == 0:
        delta = 1.0
    svd, lwork = _svd(m + n, n)
    alpha, status = 0.0, None
    while True:
        g_norm = kernel.scaling(x, g, lower, upper, v, dv)
        if g_norm < gtol:
            status = 1
        if status is not None or nfev == max_nfev:
            break
        if not kernel.augmented(J, g, v, dv, d, diag_h, g_h, J_h, A):
            raise ValueError("array must not contain infs or NaNs")
        u, s, vt, info = svd(A, compute_uv=1, lwork=lwork, full_matrices=0, overwrite_a=1)
        if info > 0:
            raise np.linalg.LinAlgError("SVD did not converge")
        if info < 0:
            raise ValueError(f"illegal value in {-info}th argument of internal gesdd")
        f_aug[:m] = f
        uf, V = u.T.dot(f_aug), vt.T
        theta = max(0.995, 1 - g_norm)
        reduction = -1
        while reduction <= 0 and nfev < max_nfev:
            x_new, step_h_norm, step_norm, predicted, alpha = kernel.trial(
                x, J_h, diag_h, g_h, d, uf, s, V, delta, alpha, theta, lower, upper)
            f_new = fun(x_new)
            nfev += 1
            if not np.all(np.isfinite(f_new)):
                delta = 0.25 * step_h_norm
                continue
            cost_new = 0.5 * np.dot(f_new, f_new)
            reduction = cost - cost_new
            new_delta, ratio = _radius(delta, reduction, predicted, step_h_norm)
            status = _converged(reduction, cost, step_norm, np.linalg.norm(x), ratio, ftol, xtol)
            if status is not None:
                break
            alpha *= delta / new_delta
            delta = new_delta
        if reduction > 0:
            x, f, cost = x_new, f_new, cost_new
            J = jac(x)
            njev += 1
            g = J.T.dot(f)
    return Solution(x, cost, f, J, g, g_norm, nfev, njev, status or 0)


@functools.lru_cache(maxsize=32)
def _svd(m: int, n: int):
    """LAPACK's ``gesdd`` as ``scipy.linalg.svd`` takes it, and the workspace it asks for an ``m x n`` matrix."""
    from scipy.linalg import get_lapack_funcs

    gesdd, query = get_lapack_funcs(("gesdd", "gesdd_lwork"), (np.empty((m, n)),), ilp64="preferred")
    work, info = query(m, n, compute_uv=1, full_matrices=0)
    if info != 0:
        raise ValueError(f"Internal work array size computation failed: {info}")
    return gesdd, int(work.real)


def _radius(delta, reduction, predicted, step_norm):
    """The trust region's next radius and the ratio of the actual to the predicted reduction."""
    if predicted > 0:
        ratio = reduction / predicted
    elif predicted == reduction == 0:
        ratio = 1
    else:
        ratio = 0
    if ratio < 0.25:
        delta = 0.25 * step_norm
    elif ratio > 0.75 and step_norm > 0.95 * delta:
        delta *= 2.0
    return delta, ratio


def _converged(reduction, cost, step_norm, x_norm, ratio, ftol, xtol):
    """SciPy's status when the cost's change or the step is below its tolerance, else None."""
    cost_met = reduction < ftol * cost and ratio > 0.25
    step_met = step_norm < xtol * (xtol + x_norm)
    if cost_met and step_met:
        return 4
    if cost_met:
        return 2
    return 3 if step_met else None
