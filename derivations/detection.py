"""The beam read at a detection point ``x_s = sigma L``: slope (optical lever) and deflection.

Equation: Eq. 2, ``u0'''' = kappa**4 u0 + q0/EI``, with the clamp of Eq. 3 and the tip of
:mod:`derivations.tip_setback` (tip at ``gamma L`` with springs ``kvv, kll, kvl`` and tip
mass ``mu``; ``gamma = 1``, ``mu = 0``, ``kvv = k1``, ``kll = k2``, ``kvl = 0`` is Eq. 4).
The paper reads the slope at ``x = L`` (Section II); a real laser spot sits at ``sigma L``.

Nothing new is solved here: the set-back solution already fixes the whole beam.  The
state ``z = [u, u', u'', u''']`` at the spot follows from it by a field matrix
(:func:`derivations.tip_setback.field_matrix`) over one segment:

* spot between clamp and tip (``sigma <= gamma``): from the clamp state
  ``[0, 0, u''(0), u'''(0)]`` (``SetbackSolution.clamp``) over ``sigma L``;
* spot beyond the tip (``sigma >= gamma``): from the free end ``[u(L), u'(L), 0, 0]``
  backwards over ``(1 - sigma) L`` (a field matrix of negative length: ``sin`` and
  ``sinh`` change sign).

The load enters through the constant particular solution ``u_p = -q0/(EI kappa**4)``
(homogeneous state ``z - [u_p, 0, 0, 0]``), exactly as in the set-back solver.  So any tip
term added to the set-back derivation (a rotary inertia, say) flows into the detection
point unchanged.  Results are polynomials in the atoms of ``a = gamma beta``,
``b = (1 - gamma) beta`` and of the spot argument, ``s = sigma beta`` (before the tip) or
``r = (1 - sigma) beta`` (beyond it).

:func:`family_spot` reads the paper's one-segment families (:mod:`derivations.beam`) at
``sigma L`` the same way, from their own constants; at ``sigma = 1`` it is their transfer.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from . import tip_setback
from .beam import EI, L, TipProblem, _linear_system, beta, kappa, q0, x
from .tip_setback import ATOMS_A, ATOMS_B, DRIVES, field_matrix, gamma
from .trig import atoms, from_atoms, normal_form

__all__ = ["sigma", "ATOMS_S", "ATOMS_R", "DetectionSolution", "solve", "to_functions", "family_spot",
           "static_slope"]

sigma = sp.Symbol("sigma", positive=True)
"""Detection point over the cantilever length, ``x_s / L`` (public name ``spot_position``)."""

ATOMS_S, ATOMS_R = atoms("s"), atoms("r")
"""Atoms of ``s = sigma beta`` (spot before the tip) and ``r = (1 - sigma) beta`` (beyond)."""

_rho = sp.Symbol("rho", positive=True)        # 1 - sigma, the spot's distance from the free end / L


@dataclass(frozen=True)
class Branch:
    """The response at the spot on one side of the tip: ``numerator[drive] / denominator``."""

    denominator: sp.Expr
    slope: dict
    deflection: dict
    atoms: tuple

    def theta(self, drive: sp.Symbol) -> sp.Expr:
        """Slope at the spot per unit ``drive``, in atoms."""
        return self.slope[drive] / self.denominator


@dataclass(frozen=True)
class DetectionSolution:
    """Slope ``u'(sigma L)`` and deflection ``u(sigma L)``: ``before`` (``sigma <= gamma``) and
    ``beyond`` (``sigma >= gamma``) the tip."""

    before: Branch
    beyond: Branch


def _state_times_det(F: sp.Matrix, z0_det: list[sp.Expr], offset_det: sp.Expr) -> list[sp.Expr]:
    """``F z0 + [offset, 0, 0, 0]`` (all already multiplied by the denominator), expanded."""
    z = F * sp.Matrix(z0_det)
    return [sp.expand(z[0] + offset_det), sp.expand(z[1])]


@lru_cache(maxsize=None)
def solve() -> DetectionSolution:
    """Slope and deflection at ``sigma L`` per unit d1, d2, f0, q0, on both sides of the tip.

    >>> sol = solve()
    >>> sorted(map(str, sol.before.slope))
    ['d1', 'd2', 'f0', 'q0']
    """
    setback = tip_setback.solve()
    det, clamp = setback.clamp
    u_p = -q0 / (EI * kappa**4)
    # Before the tip: z(sigma) = F(sigma) [-u_p, 0, u''(0), u'''(0)] + [u_p, 0, 0, 0].
    F_s = field_matrix(sigma, ATOMS_S)
    before = {}
    for dr in DRIVES:
        load = (-u_p / q0 if dr == q0 else 0) * det
        before[dr] = _state_times_det(F_s, [load, 0, *clamp[dr]], -load)
    # Beyond: z(sigma) = F(-rho) [u(L) - u_p, u'(L), 0, 0] + [u_p, 0, 0, 0], F(-rho) = F(rho)**-1.
    flip = {ATOMS_R.s: -ATOMS_R.s, ATOMS_R.sh: -ATOMS_R.sh}
    F_r = field_matrix(_rho, ATOMS_R).subs(_rho, 1 - sigma).subs(flip, simultaneous=True)
    den = setback.denominator
    beyond = {}
    for dr in DRIVES:
        load = (u_p / q0 if dr == q0 else 0) * den
        beyond[dr] = _state_times_det(F_r, [setback.deflection[dr] - load, setback.slope[dr], 0, 0], load)
    return DetectionSolution(_branch(det, before, (ATOMS_A, ATOMS_B, ATOMS_S)),
                             _branch(den, beyond, (ATOMS_A, ATOMS_B, ATOMS_R)))


def _branch(den: sp.Expr, states: dict, sets: tuple) -> Branch:
    reduced = tip_setback._reduce([den] + [states[d][1] for d in DRIVES] + [states[d][0] for d in DRIVES], sets)
    return Branch(reduced[0], dict(zip(DRIVES, reduced[1:5])), dict(zip(DRIVES, reduced[5:9])), sets)


def to_functions(expr: sp.Expr) -> sp.Expr:
    """Replace every atom by cos, sin, cosh, sinh of its argument.

    >>> to_functions(ATOMS_R.s)
    sin(beta*(1 - sigma))
    """
    expr = tip_setback.to_functions(expr)
    return from_atoms(from_atoms(expr, beta * sigma, ATOMS_S), beta * (1 - sigma), ATOMS_R)


@lru_cache(maxsize=None)
def family_spot(problem: TipProblem) -> tuple[sp.Expr, dict, dict]:
    """A one-segment family read at ``sigma L``: ``(denominator, slope, deflection)`` numerators
    per drive, in cos, sin, cosh, sinh of ``beta`` and ``sigma beta``.

    The family's own linear system (clamp plus its two tip conditions) is solved by Cramer's
    rule, and ``u0`` and ``u0'`` are evaluated at ``x = sigma L`` instead of ``L``.

    >>> from .pinned import problem
    >>> den, slope, _ = family_spot(problem)
    >>> sp.simplify(sp.limit((slope[q0] / den).subs(sigma, sp.Rational(1, 2)), beta, 0))
    1/(64*k)
    """
    u, consts, _, M, rhs, _ = _linear_system(problem)
    adj, det = M.adjugate(method="berkowitz"), M.det(method="berkowitz")
    drives = list(problem.drives) + ([q0] if problem.load else [])
    out = []
    for n in (1, 0):
        value = sp.expand(u.diff(x, n).subs(x, sigma * L))
        row = sp.Matrix([[sp.diff(value, c) for c in consts]])
        offset = value - sum(sp.diff(value, c) * c for c in consts)
        numer = sp.expand((row * adj * rhs)[0] + offset * det)
        out.append({d: numer.coeff(d) for d in drives})
    return sp.expand(det), out[0], out[1]


def static_slope(problem: TipProblem, drive: sp.Symbol) -> sp.Expr:
    """Static (``beta -> 0``) slope at ``sigma L`` of a one-segment family, per unit ``drive``.

    >>> from .pinned import problem
    >>> sp.factor(static_slope(problem, q0))
    sigma*(8*sigma**2 - 15*sigma + 6)/(16*k)
    """
    den, slope, _ = family_spot(problem)
    return sp.factor(sp.limit(slope[drive] / den, beta, 0))
