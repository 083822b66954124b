"""``pfmdyn branches``: resonance branches against normalised contact stiffness (Figs. 4b, 4e, 5c).

Every branch family's characteristic function is affine in its swept stiffness ``s``:
``f(z; s) = f0(z) + s f1(z)``.  So the soft limit (``s -> 0``) has the roots of ``f0`` and
the stiff limit (``s -> oo``) the roots of ``f1``; both are computed certified by
:mod:`pfmdyn.roots`.  Branch ``n`` rises from soft root ``n`` to stiff root ``n``, and the
sweep brackets it there: ``f = s f1`` at the soft root and ``f = f0`` at the stiff root, whose
signs are checked to differ, so each bracket holds a root for every ``s > 0``.  The sweep
itself is double precision: the one bracketing solver (:mod:`pfmdyn.roots.bracket`) on all stiffness
values and modes at once.  The crossover of a branch is the stiffness at which it passes
midway between its limits; affinity gives it in closed form, ``s = -f0(z_mid)/f1(z_mid)``.

Families and the reading of the paper's figures:

* ``indentation`` (Fig. 4b, Eq. 28; ``frictionless`` is the same equation): ``k1_over_k``
  swept; free cantilever (Eq. 22) -> supported end (Eq. 20).
* ``elastic`` (Fig. 4e, longitudinal coupling, case 4c): ``k2_ratio`` swept with the
  vertical spring held at ``k1_over_k`` (default 0, the figure's longitudinal spring
  alone); with k1 = 0: free cantilever -> tip slope held (``tan z = -tanh z``).
* ``torsion-elastic`` (Fig. 5c, Eq. 33): ``k2t_HL`` swept; clamped-free torsion
  ``(2n-1) pi/2`` -> clamped-clamped ``n pi``.

The y axis is the resonance frequency over the first free resonance: ``(z/z1)**2`` for
flexure (omega ~ beta**2) and ``z/z1`` for torsion (omega ~ xi).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..generated import characteristic, families, formulas
from .bracket import refine
from .core import CertificationError, certify, characteristic_function

__all__ = ["SWEPT", "LABELS", "FIGURE", "branch_limits", "sweep", "crossovers", "frequency_ratio"]

SWEPT = {f.roots: f.branch for f in families.FAMILIES if f.branch}
"""Branch family -> the stiffness parameter swept along the x axis."""

LABELS = {
    "k1_over_k": ("normalised vertical contact stiffness $k_1/k$", "soft limit: free end", "stiff limit: supported end"),
    "k2_ratio": ("normalised longitudinal contact stiffness $k_2H^2/(kL^2)$", "soft limit: free end",
                 "stiff limit: tip slope held"),
    "k2t_HL": ("normalised lateral contact stiffness $H^2k_2L/c_T$", "soft limit: free torsion",
               "stiff limit: clamped torsion"),
}
"""Swept parameter -> (x-axis label, soft-limit label, stiff-limit label)."""

FIGURE = {f.roots: f.figure for f in families.FAMILIES if f.branch}
"""Branch family -> the paper\'s figure it reproduces."""


def _split(family: str, fixed: dict):
    """Exact callables (``fmpq`` parameters) for ``f0`` and ``f1`` of ``f = f0 + s f1``."""
    name = SWEPT[family]
    f_soft = characteristic_function(family, **fixed, **{name: 0})
    # f1 = (f(S) - f(0))/S holds exactly for any S; a huge S makes the ball radii of the
    # terms free of s (which cancel only in exact arithmetic) negligible in the difference.
    big = 2**64
    f_big = characteristic_function(family, **fixed, **{name: big})
    return f_soft, lambda z, m: (f_big(z, m) - f_soft(z, m)) / big


def branch_limits(family: str, modes: int, **fixed) -> tuple[np.ndarray, np.ndarray]:
    """Certified soft (``s = 0``) and stiff (``s -> oo``) limits of the first ``modes`` branches.

    >>> soft, stiff = branch_limits("indentation", 2)
    >>> soft.round(4).tolist(), stiff.round(4).tolist()
    ([1.8751, 4.6941], [3.9266, 7.0686])
    """
    return _limits(family, modes, tuple(sorted(fixed.items())))


@lru_cache(maxsize=32)
def _limits(family: str, modes: int, fixed: tuple) -> tuple[np.ndarray, np.ndarray]:
    # Cached: the sweep, the crossovers, the plot and the CSV all need the same limits.
    out = []
    for g in _split(family, dict(fixed)):
        flint_g = lambda s, g=g: g(s, characteristic.FLINT)    # noqa: E731 (binds g per limit)
        balls, _ = certify(flint_g, modes, 17, f_exact=flint_g)
        out.append(np.array([float(b.mid()) for b in balls]))
    return out[0], out[1]


def _numeric(family: str, fixed: dict):
    name, base = SWEPT[family], characteristic.FAMILIES[family]
    values = {k: float(v) for k, v in fixed.items()}
    return lambda z, s: base(z, np, **values, **{name: s})


def sweep(family: str, stiffness: np.ndarray, modes: int = 5, **fixed) -> np.ndarray:
    """Branch roots ``z[i, n]`` at ``stiffness[i]`` for modes ``n < modes``, double precision.

    >>> z = sweep("torsion-elastic", np.array([1e-6, 1.0, 1e6]), 2)
    >>> z.round(4).tolist()
    [[1.5708, 4.7124], [2.0288, 4.9132], [3.1416, 6.2832]]
    """
    soft, stiff = branch_limits(family, modes, **fixed)
    f = _numeric(family, fixed)
    s = np.asarray(stiffness, dtype=float)[:, None]
    a, b = np.broadcast_to(soft, (s.size, modes)).copy(), np.broadcast_to(stiff, (s.size, modes)).copy()
    with np.errstate(under="ignore"):       # exp(-z) underflows harmlessly at large z
        fa, fb = f(a, s), f(b, s)
    if np.any(np.sign(fa) * np.sign(fb) > 0):
        raise CertificationError(f"{family}: a branch is not bracketed by its soft and stiff limits")
    return refine(lambda z: f(z, s), a, b, fa, fb)


def crossovers(family: str, modes: int = 5, **fixed) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness at which each branch passes midway between its limits, and that midpoint.

    >>> s, z = crossovers("indentation", 3)
    >>> np.round(np.log10(s), 2).tolist()
    [0.77, 1.68, 2.24]
    """
    soft, stiff = branch_limits(family, modes, **fixed)
    f = _numeric(family, fixed)
    mid = (soft + stiff) / 2
    f0 = f(mid, 0.0)
    return -f0 / (f(mid, 1.0) - f0), mid


def frequency_ratio(family: str, z: np.ndarray, z1: float) -> np.ndarray:
    """Resonance frequency over the first free one: ``(z/z1)**2`` for flexure, ``z/z1`` for torsion."""
    return z / z1 if family.startswith("torsion") else formulas.frequency_from_beta(z, 1.0, z1)
