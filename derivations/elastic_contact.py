"""Linear elastic tip-surface contact: the general solution of the paper (Eqs. 3-10).

Equation: Eq. 2, ``u0'''' = kappa**4 u0 + q0/EI`` with ``EI = k L**3/3``, ``beta = kappa L``.

Boundary conditions:

* clamped end (Eq. 3): ``u0(0) = 0``, ``u0'(0) = 0``;
* tip in elastic contact (Eq. 4a,b)::

      EI u0''(L)  = k2 H (d2 - H u0'(L))          # longitudinal spring k2 acting at tip height H
      EI u0'''(L) = -f0 + k1 (u0(L) - d1)         # vertical spring k1, local tip force f0

Sign conventions (as in :mod:`derivations.beam`): ``u0``, ``d1``, ``f0`` and ``q0`` are
positive away from the surface; ``d2`` is positive in the direction in which the
longitudinal spring force ``k2 (d2 - H u0'(L))`` bends the beam to positive curvature;
``theta = u0'(L)``.  With these conventions the result has the form of Eq. 5,

    theta = (A_v d1 + A_l d2 + A_e f0 + A_q q0) / N,

and the four ratios A_x/N are what :func:`transfer` returns.
"""
from __future__ import annotations

import sympy as sp

from .beam import EI, H, TipProblem, TipSolution, d1, d2, f0, is_identically_zero, k1, k2, q0, solve_tip_problem

__all__ = ["tip_conditions", "problem", "solve", "transfer", "reduces_to_elastic_contact", "DRIVES"]

DRIVES = (d1, d2, f0, q0)
"""Excitations in the order of Eq. 5: vertical, longitudinal, local force, uniform load."""


def tip_conditions(U):
    """Eq. 4a,b written as expressions that vanish; ``U = [u(L), u'(L), u''(L), u'''(L)]``.

    >>> [sp.simplify(e) for e in tip_conditions([0, 0, 0, 0])]
    [-H*d2*k2, d1*k1 + f0]
    """
    return [EI * U[2] - k2 * H * (d2 - H * U[1]), EI * U[3] - (-f0 + k1 * (U[0] - d1))]


problem = TipProblem(
    "elastic", tip_conditions, (d1, d2, f0), load=True,
    description="vertical spring k1 and longitudinal spring k2 at tip height H (Eqs. 4a,b)",
)


def solve() -> TipSolution:
    """Solution of the elastic-contact problem (slope and deflection numerators, N).

    >>> sol = solve()
    >>> sorted(map(str, sol.drives))
    ['d1', 'd2', 'f0', 'q0']
    """
    return solve_tip_problem(problem)


def transfer() -> dict[sp.Symbol, sp.Expr]:
    """The four transfer ratios A_x/N of Eq. 5: tip slope per unit d1, d2, f0, q0.

    >>> from .beam import beta, k, L
    >>> t = transfer()
    >>> sp.simplify(t[d1] / t[f0])   # Eqs. 6 and 8 differ by the factor k1 only
    k1
    """
    sol = solve()
    return {d: sol.theta(d) for d in DRIVES}


def reduces_to_elastic_contact(solution: TipSolution, limit: dict, drive: sp.Symbol) -> bool:
    """Whether ``solution``'s tip slope per ``drive`` becomes this problem's under the substitution ``limit``.

    The extensions of elastic contact (a tilted lever, a tip mass) must reduce to it when their own
    parameters vanish.  Without its lateral spring elastic contact is another problem (frictionless):

    >>> reduces_to_elastic_contact(solve(), {}, d2), reduces_to_elastic_contact(solve(), {k2: 0}, d1)
    (True, False)
    """
    return is_identically_zero(solution.theta(drive).subs(limit) - solve().theta(drive))
