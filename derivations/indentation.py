"""Piezoelectric nanoindentation: vertical tip-surface coupling only (Eqs. 27-29).

The longitudinal spring is neglected (stiff cantilever, ``k L**2 >> H**2 k2``) and so is
the distributed load.  Equation: Eq. 2 with ``q0 = 0`` and the clamped end of Eq. 3; at the
tip the boundary conditions of frictionless contact (:mod:`derivations.frictionless`)::

    u0''(L) = 0,   EI u0'''(L) = -f0 + k1 (u0(L) - d1)

Outputs: the tip displacement ``u0(L)`` (Eq. 27, interferometric detection) and the slope
``theta = u0'(L)`` (Eq. 28, beam-deflection detection).  Eq. 29 is the limit k1 -> oo,
obtained here both as a limit and from the condition ``u0(L) = d1``.  Sign conventions as
in :mod:`derivations.beam`.
"""
from __future__ import annotations

from .beam import TipProblem, TipSolution, d1, f0, solve_tip_problem
from .frictionless import stiff_tip_conditions, tip_conditions

__all__ = ["problem", "stiff_problem", "solve", "solve_stiff"]

problem = TipProblem("indentation", tip_conditions, (d1, f0), load=False,
                     description="vertical spring k1 only, no distributed load (Eqs. 27-28)")
stiff_problem = TipProblem("indentation-stiff", stiff_tip_conditions, (d1,), load=False,
                           description="k1 -> oo: u0(L) = d1, u0''(L) = 0 (Eq. 29)")


def solve() -> TipSolution:
    """Tip slope and displacement per unit d1 and f0.

    >>> import sympy as sp
    >>> from .beam import beta, k, k1
    >>> sp.simplify(solve().tip_deflection(d1) / solve().tip_deflection(f0))
    k1
    """
    return solve_tip_problem(problem)


def solve_stiff() -> TipSolution:
    """Tip slope when the tip follows the surface exactly (k1 -> oo).

    >>> import sympy as sp
    >>> from .beam import beta, L
    >>> sp.limit(solve_stiff().theta(d1), beta, 0)
    3/(2*L)
    """
    return solve_tip_problem(stiff_problem)
