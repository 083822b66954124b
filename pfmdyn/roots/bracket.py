"""The one double-precision bracketing root solver: vectorised Illinois regula falsi.

Every bracket ``[a, b]`` with ``f(a) f(b) <= 0`` is refined at once (one vectorised call
of ``f`` per iteration).  Regula falsi steps to the secant root; when the same end is kept
twice running, its stored value is halved (Illinois), so both ends move and convergence
stays superlinear (halving at every step would fall back to bisection-like speed).
Certified roots (interval arithmetic) are :mod:`pfmdyn.derivations.certify`'s business; this is
the fast path used by the discrepancy fits and by branch sweeps.
"""
from __future__ import annotations

import numpy as np

__all__ = ["refine", "grid_roots", "interpolated_roots"]


def refine(f, a, b, fa=None, fb=None, rtol: float = 4e-16, maxiter: int = 100) -> np.ndarray:
    """Roots of ``f`` in the brackets ``[a, b]`` (arrays of any one shape), elementwise.

    ``f`` maps an array of points to an array of values of the same shape; ``fa``, ``fb``
    may be given when already known.  A bracket without a sign change returns its end of
    smaller ``|f|``.

    >>> refine(np.cos, np.array([1.0, 4.0]), np.array([2.0, 5.0])).round(12).tolist()
    [1.570796326795, 4.712388980385]
    """
    a, b = np.array(a, dtype=float), np.array(b, dtype=float)
    with np.errstate(all="ignore"):
        fa = np.array(f(a) if fa is None else fa, dtype=float)
        fb = np.array(f(b) if fb is None else fb, dtype=float)
        for _ in range(maxiter):
            done = (np.abs(b - a) <= rtol * np.abs(b)) | (fb == 0) | (np.sign(fa) * np.sign(fb) > 0)
            if done.all():
                break
            c = np.where(done, b, b - fb * (b - a) / np.where(done, 1.0, fb - fa))
            fc = np.where(done, fb, f(c))
            flip = np.sign(fc) * np.sign(fb) < 0
            a, fa = np.where(flip, b, a), np.where(done, fa, np.where(flip, fb, fa / 2))
            b, fb = np.where(done, b, c), np.where(done, fb, fc)
    return np.where(np.abs(fa) < np.abs(fb), a, b) if np.any(np.sign(fa) * np.sign(fb) > 0) else b


def grid_roots(f, grid, refine_roots: bool = True, rtol: float = 1e-13) -> np.ndarray:
    """Real roots of ``f`` bracketed by sign changes on ``grid`` (ascending), ascending.

    Roots closer together than the grid step may be missed, so ``f`` should have no
    poles (an entire characteristic function) and the grid be fine enough.  With
    ``refine_roots`` False the roots are linear interpolations (for coarse searches).
    Refinement starts from :func:`interpolated_roots` and confirms each root by a sign change
    ``rtol`` wide around it; where that fails, :func:`refine` finishes from the better side.

    >>> grid_roots(np.sin, np.linspace(0.5, 10, 50)).round(10).tolist()
    [3.1415926536, 6.2831853072, 9.4247779608]
    """
    grid = np.asarray(grid, dtype=float)
    with np.errstate(all="ignore"):
        vals = np.asarray(f(grid), dtype=float)
    idx = np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)
    lo, hi, flo, fhi = grid[idx], grid[idx + 1], vals[idx], vals[idx + 1]
    if not refine_roots or not len(idx):
        return hi - fhi * (hi - lo) / (fhi - flo)
    with np.errstate(all="ignore"):
        c = interpolated_roots(f, lo, hi, flo, fhi)
        half = 0.45 * rtol * np.abs(c)
        near = np.asarray(f(np.concatenate([c - half, c + half])), dtype=float).reshape(2, -1)
    # the sub-bracket holding the root: around c when confirmed, else the side whose sign differs
    left = np.sign(flo) * np.sign(near[0]) <= 0
    around = ~left & (np.sign(near[0]) * np.sign(near[1]) <= 0)
    a = np.where(left, lo, np.where(around, c - half, c + half))
    b = np.where(left, c - half, np.where(around, c + half, hi))
    fa = np.where(left, flo, np.where(around, near[0], near[1]))
    fb = np.where(left, near[0], np.where(around, near[1], fhi))
    return refine(f, a, b, fa, fb, rtol=rtol, maxiter=60)


_NODES = 8
_LOBATTO = np.cos(np.pi * np.arange(_NODES) / (_NODES - 1))
_TO_CHEBYSHEV = np.linalg.inv(np.polynomial.chebyshev.chebvander(_LOBATTO, _NODES - 1))


def interpolated_roots(f, lo, hi, flo, fhi) -> np.ndarray:
    """Roots of ``f``'s degree-7 Chebyshev interpolants on the brackets ``[lo, hi]`` (one call of
    ``f`` for every bracket's interior nodes), by Newton's method on each interpolant from the
    secant root.  Near-exact for an analytic ``f`` on a bracket much narrower than its oscillations.

    >>> interpolated_roots(np.cos, np.array([1.5]), np.array([1.7]), np.cos([1.5]), np.cos([1.7])) - np.pi / 2
    array([0.])
    """
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    inner = mid[:, None] + half[:, None] * _LOBATTO[1:-1]
    vals = np.empty((len(lo), _NODES))
    vals[:, 0], vals[:, -1] = fhi, flo
    vals[:, 1:-1] = np.asarray(f(inner.ravel()), dtype=float).reshape(inner.shape)
    coef = _TO_CHEBYSHEV @ vals.T
    slope = np.polynomial.chebyshev.chebder(coef)
    t = np.clip(1 - 2 * fhi / (fhi - flo), -1.0, 1.0)
    for _ in range(12):
        step = (np.polynomial.chebyshev.chebval(t, coef, tensor=False)
                / np.polynomial.chebyshev.chebval(t, slope, tensor=False))
        t = np.clip(t - step, -1.0, 1.0)
        if np.all(np.abs(step) < 1e-15):
            break
    return mid + half * t
