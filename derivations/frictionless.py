"""Frictionless contact (Eqs. 23-24): the longitudinal spring removed, k2 -> 0.

Equation: Eq. 2 with the clamped end of Eq. 3.  At the tip the moment vanishes and the
vertical spring stays (Eq. 4a with k2 = 0, and Eq. 4b)::

    u0''(L) = 0
    EI u0'''(L) = -f0 + k1 (u0(L) - d1)

The stiff-contact limit (Eq. 24) replaces the spring by a prescribed tip displacement,
``u0(L) = d1``, ``u0''(L) = 0``, which is what k1 -> oo does to Eq. 4b.

Sign conventions as in :mod:`derivations.beam`: ``u0``, ``d1``, ``f0``, ``q0`` positive
away from the surface; ``theta = u0'(L)``.
"""
from __future__ import annotations

import sympy as sp  # noqa: F401  (the doctests)

from .beam import EI, TipProblem, TipSolution, d1, f0, k1, q0, solve_tip_problem

__all__ = ["tip_conditions", "problem", "stiff_problem", "solve", "solve_stiff", "DRIVES"]

DRIVES = (d1, f0, q0)


def tip_conditions(U):
    """Zero moment and the vertical spring k1 at the tip.

    >>> tip_conditions([0, 0, 0, 0])
    [0, d1*k1 + f0]
    """
    return [U[2], EI * U[3] - (-f0 + k1 * (U[0] - d1))]


def stiff_tip_conditions(U):
    """Tip pinned to the moving surface: ``u0(L) = d1``, ``u0''(L) = 0`` (k1 -> oo).

    >>> stiff_tip_conditions([0, 0, 0, 0])
    [-d1, 0]
    """
    return [U[0] - d1, U[2]]


problem = TipProblem("frictionless", tip_conditions, (d1, f0), load=True,
                     description="k2 -> 0: no moment at the tip, vertical spring k1 (Eq. 23)")
stiff_problem = TipProblem("frictionless-stiff", stiff_tip_conditions, (d1,), load=True,
                           description="k2 -> 0 and k1 -> oo: u0(L) = d1, u0''(L) = 0 (Eq. 24)")


def solve() -> TipSolution:
    """Frictionless contact with spring k1 (Eq. 23).

    >>> from .beam import beta, k, L
    >>> sp.factor(sp.limit(solve().theta(d1), beta, 0))   # static
    3*k1/(2*L*(k + k1))
    """
    return solve_tip_problem(problem)


def solve_stiff() -> TipSolution:
    """Frictionless, infinitely stiff vertical contact (Eq. 24).

    >>> from .beam import beta, L
    >>> sp.limit(solve_stiff().theta(d1), beta, 0)   # static: 3 d1 / (2 L)
    3/(2*L)
    """
    return solve_tip_problem(stiff_problem)
