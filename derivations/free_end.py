"""Free cantilever driven electrostatically: tip force and uniform load (Eqs. 21-22).

Equation: Eq. 2 with the clamped end of Eq. 3.  At the free end (Eq. 21a,b)::

    u0''(L) = 0,   EI u0'''(L) = -f0

``f0`` (first harmonic of the local force on the tip) and ``q0`` are positive away from
the surface; ``theta = u0'(L)``.  This is Eq. 4 with k1 = k2 = 0, so the same sign
convention for ``f0`` holds in both.  Resonances: ``1 + cos(beta) cosh(beta) = 0``.
"""
from __future__ import annotations

from .beam import EI, TipProblem, TipSolution, f0, solve_tip_problem

__all__ = ["tip_conditions", "problem", "solve"]


def tip_conditions(U):
    """Zero moment, tip shear force balancing ``f0``.

    >>> tip_conditions([0, 0, 0, 0])
    [0, f0]
    """
    return [U[2], EI * U[3] + f0]


problem = TipProblem("free", tip_conditions, (f0,), load=True,
                     description="free end with tip force f0 and uniform load q0 (Eq. 21)")


def solve() -> TipSolution:
    """Slope and deflection of the free cantilever per unit f0 and q0.

    >>> import sympy as sp
    >>> from .beam import beta, k, L, q0
    >>> sp.limit(solve().theta(q0), beta, 0), sp.limit(solve().theta(f0), beta, 0)
    (1/(2*k), 3/(2*L*k))
    """
    return solve_tip_problem(problem)
