"""Tip-surface contact mechanics of Section III.1, derived from the contact laws.

* Hertz (sphere of radius R on a flat, reduced modulus E*): ``P = 4/3 E* sqrt(R) delta**(3/2)``;
  the vertical contact stiffness is ``k1 = dP/d delta`` at fixed load P.
* Mindlin (tangential, no slip): ``k2 = 8 a G*`` with contact radius ``a = sqrt(R delta)``;
  vertical ``k1 = 2 a E*``.  For a rigid tip on an isotropic sample, ``E* = E/(1 - nu**2)``
  and ``G* = G/(2 - nu)`` with ``G = E/(2 (1 + nu))``.
* Piezoelectric indentation (Section III.1's load-depth relation, transversely isotropic
  piezoelectric, spherical tip): the printed ``P(w0, V)``; the stiffness is ``dP/dw0``.

All functions return SymPy expressions; numbers are evaluated by the checks.
"""
from __future__ import annotations

import sympy as sp

__all__ = ["hertz_stiffness", "mindlin_ratio", "piezo_load", "piezo_stiffness"]

E_star, R, P, delta = sp.symbols("E_star R P delta", positive=True)
nu = sp.Symbol("nu", nonnegative=True)
w0, V, C1, C3 = sp.symbols("w0 V C1 C3", real=True)


def hertz_stiffness() -> sp.Expr:
    """k1 = dP/d(delta) of the Hertz law, written in terms of the load P.

    >>> sp.simplify(hertz_stiffness() / (E_star**sp.Rational(2, 3) * R**sp.Rational(1, 3) * P**sp.Rational(1, 3)))
    6**(1/3)
    """
    load = sp.Rational(4, 3) * E_star * sp.sqrt(R) * delta**sp.Rational(3, 2)
    stiffness = sp.diff(load, delta)
    depth = sp.solve(sp.Eq(load, P), delta)[0]
    return sp.simplify(stiffness.subs(delta, depth))


def mindlin_ratio() -> sp.Expr:
    """k1/k2 for a rigid spherical tip on an isotropic sample (Hertz normal, Mindlin tangential).

    >>> sp.factor(mindlin_ratio())
    (nu - 2)/(2*(nu - 1))
    """
    E, a = sp.symbols("E a", positive=True)
    G = E / (2 * (1 + nu))
    k1 = 2 * a * E / (1 - nu**2)
    k2 = 8 * a * G / (2 - nu)
    return sp.simplify(k1 / k2)


def piezo_load() -> sp.Expr:
    """The load-depth relation P(w0, V) of the piezoelectric indentation model (Section III.1).

    >>> piezo_load().subs(V, 0)
    4*C1*sqrt(R)*w0**(3/2)/(3*pi)
    """
    return (4 * w0**sp.Rational(3, 2) * sp.sqrt(R) * C1 + 6 * sp.sqrt(w0) * sp.sqrt(R) * V * C3) / (3 * sp.pi)


def piezo_stiffness() -> sp.Expr:
    """Contact stiffness dP/dw0 of the piezoelectric indentation model at fixed bias.

    >>> sp.expand(piezo_stiffness())
    2*C1*sqrt(R)*sqrt(w0)/pi + C3*sqrt(R)*V/(pi*sqrt(w0))
    """
    return sp.diff(piezo_load(), w0)
