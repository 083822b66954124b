"""Supported (pinned) tip: buckling under a distributed electrostatic load (Eqs. 19-20).

Equation: Eq. 2 with the clamped end of Eq. 3.  The tip is held at the surface and is
free to rotate (k1, k2 -> oo in the paper's words; Eq. 19a,b)::

    u0(L) = 0,   u0''(L) = 0

The only excitation is the uniform load ``q0`` (positive away from the surface);
``theta = u0'(L)``.  The zeros of the denominator, ``tan(beta) = tanh(beta)``, are the
contact (supported) resonances.
"""
from __future__ import annotations

from .beam import TipProblem, TipSolution, solve_tip_problem

__all__ = ["tip_conditions", "problem", "solve"]


def tip_conditions(U):
    """Zero displacement and zero moment at the tip.

    >>> tip_conditions([1, 2, 3, 4])
    [1, 3]
    """
    return [U[0], U[2]]


problem = TipProblem("pinned", tip_conditions, (), load=True,
                     description="tip supported: u0(L) = 0, u0''(L) = 0 (Eq. 19)")


def solve() -> TipSolution:
    """Slope response of the supported cantilever to the uniform load.

    >>> import sympy as sp
    >>> from .beam import beta, k, q0
    >>> sp.limit(solve().theta(q0), beta, 0)   # static slope per unit q0
    -1/(16*k)
    """
    return solve_tip_problem(problem)
