"""Torsional oscillations for lateral PFM (Eqs. 30-35).

Equation (Eq. 30): ``c_T Theta'' = rho J Theta_tt``; with ``Theta = Theta0(x) exp(i w t)``
this is Eq. 31, ``Theta0'' + xi**2 Theta0 = 0`` with ``xi**2 = rho J w**2 / c_T``.

Boundary conditions: clamped end ``Theta0(0) = 0``; at the tip either

* elastic lateral contact (Eq. 32): ``Theta0'(L) = -k2t (H Theta0(L) - d3)`` with
  ``k2t = H k2 / c_T`` (the lateral spring k2 acting at the apex, lever arm H); or
* a prescribed lateral force (Eq. 34): ``Theta0'(L) = f_lat`` with ``f_lat = F_lat H / c_T``.

Sign convention: ``Theta0`` is positive in the sense in which a positive in-plane surface
displacement ``d3`` (perpendicular to the cantilever axis) twists the beam through the
lateral spring.  Outputs are the tip twist ``Theta0(L)`` per unit drive.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .beam import H, L

__all__ = ["xi", "k2t", "d3", "f_lat", "c_T", "TorsionSolution", "frequency_domain_equation",
           "general_solution", "solve_elastic", "solve_force"]

x = sp.Symbol("x", real=True)
t, omega = sp.symbols("t omega", positive=True)
xi, c_T, rho, J = sp.symbols("xi c_T rho J", positive=True)
k2t = sp.Symbol("k2t", positive=True)
"""Normalised lateral contact stiffness ``H k2 / c_T`` (units 1/m**2)."""
d3, f_lat = sp.symbols("d3 f_lat", real=True)


def frequency_domain_equation() -> sp.Expr:
    """Eq. 30 with a harmonic twist substituted, divided by ``c_T exp(i w t)``.

    Returns ``Theta0'' + (rho J w**2 / c_T) Theta0`` (as an expression in ``Theta0(x)``),
    which is Eq. 31 with ``xi**2 = rho J w**2 / c_T``.

    >>> frequency_domain_equation()
    J*omega**2*rho*Theta0(x)/c_T + Derivative(Theta0(x), (x, 2))
    """
    theta0 = sp.Function("Theta0")
    wave = theta0(x) * sp.exp(sp.I * omega * t)
    eq30 = c_T * wave.diff(x, 2) - rho * J * wave.diff(t, 2)
    return sp.expand(sp.simplify(eq30 / (c_T * sp.exp(sp.I * omega * t))))


@lru_cache(maxsize=None)
def general_solution() -> tuple[sp.Expr, tuple[sp.Symbol, ...]]:
    """General solution of Eq. 31 from :func:`sympy.dsolve`.

    >>> general_solution()[0]
    C1*sin(x*xi) + C2*cos(x*xi)
    """
    theta0 = sp.Function("Theta0")
    sol = sp.dsolve(theta0(x).diff(x, 2) + xi**2 * theta0(x), theta0(x)).rhs
    return sol, tuple(sorted(sol.free_symbols - {x, xi}, key=str))


@dataclass(frozen=True)
class TorsionSolution:
    """Tip twist ``Theta0(L) = numerator / denominator`` for one drive."""

    name: str
    drive: sp.Symbol
    numerator: sp.Expr
    denominator: sp.Expr

    @property
    def tip_twist(self) -> sp.Expr:
        """``Theta0(L)`` as one expression."""
        return self.numerator / self.denominator


def _solve(name: str, tip_condition, drive: sp.Symbol) -> TorsionSolution:
    sol, consts = general_solution()
    tip = sol.subs(x, L)
    equations = [sol.subs(x, 0), tip_condition(tip, sol.diff(x).subs(x, L))]
    values = sp.solve(equations, consts, dict=True)[0]
    num, den = sp.fraction(sp.factor(sp.together(tip.subs(values))))
    return TorsionSolution(name, drive, sp.expand(num), sp.expand(den))


@lru_cache(maxsize=None)
def solve_elastic() -> TorsionSolution:
    """Elastic lateral contact, Eq. 32 -> Eq. 33.

    >>> s = solve_elastic()
    >>> sp.limit(s.tip_twist, k2t, sp.oo)   # infinitely stiff contact: twist d3 / H
    d3/H
    """
    return _solve("torsion-elastic", lambda th, dth: dth + k2t * (H * th - d3), d3)


@lru_cache(maxsize=None)
def solve_force() -> TorsionSolution:
    """Prescribed lateral force, Eq. 34 -> Eq. 35.

    >>> sp.simplify(solve_force().tip_twist - f_lat*sp.tan(xi*L)/xi)
    0
    """
    return _solve("torsion-force", lambda th, dth: dth - f_lat, f_lat)
