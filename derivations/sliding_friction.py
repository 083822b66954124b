"""Tip sliding on the surface with linear friction (Eqs. 25-26).

Equation: Eq. 2 with the clamped end of Eq. 3 and no distributed load (q0 = 0).  The tip
slides, so it carries no vertical spring force; the friction force ``f_l`` acting at the
tip apex, a height ``H`` below the beam axis, applies a bending moment (Eq. 25a,b)::

    EI u0''(L) = f_l H,   u0'''(L) = 0

``f_l`` has the orientation of the longitudinal spring force in Eq. 4a (the force
``k2 (d2 - H u0'(L))`` there); ``theta = u0'(L)``.
"""
from __future__ import annotations

import sympy as sp

from .beam import EI, H, TipProblem, TipSolution, solve_tip_problem

__all__ = ["f_l", "tip_conditions", "problem", "solve"]

f_l = sp.Symbol("f_l", real=True)
"""First harmonic of the sliding-friction force at the tip apex."""


def tip_conditions(U):
    """Moment from the friction force, zero shear force.

    >>> tip_conditions([0, 0, 0, 0])
    [-H*f_l, 0]
    """
    return [EI * U[2] - f_l * H, U[3]]


problem = TipProblem("friction", tip_conditions, (f_l,), load=False,
                     description="sliding friction: EI u0''(L) = f_l H, u0'''(L) = 0 (Eq. 25)")


def solve() -> TipSolution:
    """Slope response per unit friction force.

    >>> from .beam import beta, k, L
    >>> sp.limit(solve().theta(f_l), beta, 0)   # static: a tip moment f_l H on a cantilever
    3*H/(L**2*k)
    """
    return solve_tip_problem(problem)
