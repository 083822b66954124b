"""The one damped-root engine: complex zeros of a characteristic, followed from the undamped ones.

A damped lever's characteristic is analytic in the complex frequency ``r = f / f1`` (the generated
damping factors and :func:`pfmdyn.composed.characteristic` take complex arguments), so each
damped mode is a complex zero ``r_c`` near its undamped root ``r_n``.  :func:`follow` finds them
all at once: the losses are scaled by ``s`` from 0 (the undamped roots) to 1 in ``steps`` steps
``s = (i / steps)**2`` (fine first, where a root turns), each started from the path's linear
extrapolation and solved by Newton's method (the slope by a complex forward difference, in the
same vectorised call as the value).  One step suffices for light damping or a nearby guess;
a heavily damped mode's root lies far from the undamped one, where a single run may land on
another mode's root or on ``r = 0``, hence the continuation.  A root that fails to converge, or
jumps by more than half its size in one step, is lost; one that reaches the imaginary axis is
overdamped (no oscillation); two modes that end on one root are both unknown (shared).  Lost
and shared modes are followed again in finer steps (:func:`follow`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Followed", "follow"]

_SLOPE_STEP = 1e-7
"""Forward-difference step of the slope, relative to ``|r|``: the slope is good to about 1e-7, so a
Newton step ``d`` leaves an error of about ``1e-7 |d| + |d|**2 / |r|``."""


@dataclass(frozen=True)
class Followed:
    """Damped roots ``roots`` (NaN where lost, overdamped or shared), the last root reached on each
    path (``last``, for saying why one was lost), which were ``overdamped`` and which ``shared``
    their root with another mode."""

    roots: np.ndarray
    last: np.ndarray
    overdamped: np.ndarray
    shared: np.ndarray


def _newton(f, r, s: float, rtol: float, maxiter: int):
    """Zeros of ``f(., s)`` from ``r``; NaN where Newton does not converge within ``maxiter``."""
    done = ~np.isfinite(r)
    for _ in range(maxiter):
        h = _SLOPE_STEP * np.abs(r)
        value, ahead = f(np.stack([r, r + h]), s)
        step = value * h / (ahead - value)
        r = np.where(done, r, r - step)
        done |= ~(np.abs(step) > rtol * np.abs(r))      # converged, or NaN (then lost below)
        if done.all():
            break
    return np.where(done & np.isfinite(r), r, np.nan)


def _path(f, r0, steps: int, guess, rtol: float, maxiter: int):
    """One continuation (module docstring): roots (NaN where lost or overdamped), last roots reached,
    overdamped."""
    path = [r0]
    start, schedule = (r0, (np.arange(1, steps + 1) / steps) ** 2) if guess is None else \
        (np.asarray(guess, dtype=complex), np.ones(1))
    lost = ~np.isfinite(start)
    overdamped = np.zeros(r0.shape, bool)
    for i, s in enumerate(schedule):
        predicted = start if i == 0 else 2 * path[-1] - path[-2]
        rc = _newton(f, np.where(lost | overdamped, np.nan, predicted), s, rtol, maxiter)
        previous = path[-1] if guess is None else start
        lost |= ~overdamped & ~(np.abs(rc - previous) <= 0.5 * np.abs(previous))
        overdamped |= ~lost & (rc.real <= 1e-6 * np.abs(rc))
        path.append(np.where(lost | overdamped, path[-1], rc))
    return np.where(lost | overdamped, np.nan, path[-1]), path[-1], overdamped


def _shared(roots) -> np.ndarray:
    close = np.abs(roots[:, None] - roots[None, :]) <= 1e-9 * np.abs(roots)[:, None]
    return (close & ~np.eye(len(roots), dtype=bool)).any(axis=1)


def follow(f, r0, steps: int = 1, guess=None, rtol: float = 1e-7, maxiter: int = 50, finest: int = 32) -> Followed:
    """Complex zeros of ``f(r, s)`` continuing the real zeros ``r0`` of ``f(r, 0)`` up to ``s = 1``.

    A mode lost or ending on another's root is followed again from ``r0`` in four times finer
    steps, up to ``finest`` (a fast coarse path for most modes, a fine one where a root turns).

    Parameters
    ----------
    f : the characteristic at complex ``r`` (any shape; one value per point) with the losses scaled by ``s``
    r0 : undamped roots (one per mode)
    steps : loss steps ``s = (i / steps)**2`` (module docstring)
    guess : roots of a nearby model at ``s = 1``: one step from them instead of the continuation
    rtol : Newton stops after a step below ``rtol |r|`` (the default leaves ``~1e-14 |r|``, :data:`_SLOPE_STEP`)
    maxiter : Newton steps at most per loss step
    finest : the finest continuation tried again for a mode lost or shared

    Returns
    -------
    Followed

    Examples
    --------
    A viscous width ``g``: the zeros of ``r**2 - 1 - i g r`` (a mode at ``r = 1``) are ``sqrt(1 - g**2/4) + i g/2``.

    >>> out = follow(lambda r, s: r**2 - 1 - 0.02j * s * r, [1.0])
    >>> round(complex(out.roots[0]).real, 12), round(complex(out.roots[0]).imag, 12)
    (0.99994999875, 0.01)
    """
    r0 = np.atleast_1d(np.asarray(r0, dtype=float)).astype(complex)
    with np.errstate(all="ignore"):
        roots, last, overdamped = _path(f, r0, steps, guess, rtol, maxiter)
        shared = _shared(roots)
        while guess is not None or 4 * steps <= finest:
            redo = (np.isnan(roots) | shared) & ~overdamped & np.isfinite(r0)
            if not redo.any():
                break
            steps, guess = (steps if guess is not None else 4 * steps), None
            roots[redo], last[redo], overdamped[redo] = _path(f, r0[redo], steps, None, rtol, maxiter)
            shared = _shared(roots)
    return Followed(np.where(shared, np.nan, roots), last, overdamped, shared)
