"""Frequency-domain Euler-Bernoulli beam, clamped at x = 0 (Eqs. 1-3 of Jesse et al. 2006).

The equation solved is Eq. 2,

    u0''''(x) = kappa**4 u0(x) + q0 / EI,      kappa = beta / L,   EI = k L**3 / 3,

with the clamped-end conditions of Eq. 3: u0(0) = 0 and u0'(0) = 0.

Sign conventions used throughout ``derivations``:

* ``u0`` is positive away from the surface (upwards); ``q0`` and a tip force ``f0``
  are positive when they push the beam in the +u direction.
* The shear-force condition at the tip reads ``EI u0'''(L) = -F`` for a net upward tip
  force ``F`` (static check: ``EI u'' = F (L - x)``).
* ``theta = u0'(L)`` is the slope read by the optical lever at the free end.

The general solution comes from :func:`sympy.dsolve`; each boundary-condition family
(one module each) adds two conditions at ``x = L``. The resulting 4x4 linear system is
solved by Cramer's rule and every entry is brought to a canonical trigonometric normal
form (see :func:`derivations.trig.normal_form`), so results are exact and fast to obtain.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, Mapping, Sequence

import sympy as sp
from sympy.polys.constructor import construct_domain
from sympy.polys.matrices import DomainMatrix

from .trig import ATOMS, from_atoms, function_normal_form, to_atoms

# Symbols shared by every flexural family.  Positive where physics says so: it lets
# SymPy cancel |x| and square roots without case splits.
x = sp.Symbol("x", real=True)
L, k, beta = sp.symbols("L k beta", positive=True)
k1, k2, H = sp.symbols("k1 k2 H", positive=True)
d1, d2, f0, q0 = sp.symbols("d1 d2 f0 q0", real=True)
EI = k * L**3 / 3
kappa = beta / L

def is_identically_zero(expr: sp.Expr) -> bool:
    """Exact zero test for rational functions of beta, its trig/hyperbolic functions and parameters.

    >>> is_identically_zero(sp.sin(2*beta) - 2*sp.sin(beta)*sp.cos(beta))
    True
    """
    num, _ = sp.fraction(sp.together(sp.expand_trig(sp.sympify(expr))))
    return function_normal_form(num, beta) == 0


@lru_cache(maxsize=None)
def general_solution() -> tuple[sp.Expr, tuple[sp.Symbol, ...]]:
    """General solution of Eq. 2 from :func:`sympy.dsolve`, with its four constants.

    Exponentials are rewritten as ``cosh + sinh`` so that boundary values are polynomials
    in cos, sin, cosh, sinh of ``beta``.

    >>> u, C = general_solution()
    >>> sp.simplify(u.diff(x, 4) - kappa**4*u - q0/EI)
    0
    """
    u = sp.Function("u")
    sol = sp.dsolve(sp.Eq(u(x).diff(x, 4), kappa**4 * u(x) + q0 / EI), u(x)).rhs
    sol = sol.replace(sp.exp, lambda a: sp.cosh(a) + sp.sinh(a))
    constants = tuple(sorted(sol.free_symbols - {x, L, k, beta, q0}, key=str))
    return sp.expand(sol), constants


def tip_derivatives(u: sp.Expr, at: sp.Expr = L, upto: int = 3) -> list[sp.Expr]:
    """[u(at), u'(at), ..., u^(upto)(at)] of an expression in ``x``."""
    return [sp.expand(u.diff(x, n).subs(x, at)) for n in range(upto + 1)]


@dataclass(frozen=True)
class TipProblem:
    """A clamped beam with two boundary conditions at the tip, written as expressions equal to zero.

    ``conditions(U)`` receives ``U = [u(L), u'(L), u''(L), u'''(L)]`` and returns two
    expressions that vanish on the solution.  ``drives`` are the excitations the answer is
    linear in; ``load`` is True when the uniform load ``q0`` acts.
    """

    name: str
    conditions: Callable[[Sequence[sp.Expr]], Sequence[sp.Expr]]
    drives: tuple[sp.Symbol, ...]
    load: bool = True
    description: str = ""


@dataclass(frozen=True)
class TipSolution:
    """theta = u0'(L) and u0(L) as (sum_i numerator_i * drive_i) / denominator.

    ``denominator`` is the characteristic function (its zeros are the resonances);
    ``slope[drive]`` and ``deflection[drive]`` are the numerators.  Common polynomial
    factors are removed, so the normalisation is fixed but arbitrary: compare by ratio.
    """

    problem: TipProblem
    denominator: sp.Expr
    slope: Mapping[sp.Symbol, sp.Expr] = field(default_factory=dict)
    deflection: Mapping[sp.Symbol, sp.Expr] = field(default_factory=dict)

    def theta(self, drive: sp.Symbol) -> sp.Expr:
        """Tip slope per unit ``drive`` (a ratio A_x/N in the paper's notation)."""
        return self.slope[drive] / self.denominator

    def tip_deflection(self, drive: sp.Symbol) -> sp.Expr:
        """Tip displacement u0(L) per unit ``drive``."""
        return self.deflection[drive] / self.denominator

    @property
    def drives(self) -> tuple[sp.Symbol, ...]:
        return tuple(self.slope)


def _clear_and_reduce(ring, fractions):
    """Put rational functions of the atoms over one denominator, bring the numerators to the
    trigonometric normal form and cancel their common polynomial factor (elements of ``ring``).

    The normal form (:func:`derivations.trig.normal_form`) replaces even powers of sin and sinh
    by ``(1 - cos**2)`` and ``(cosh**2 - 1)``; here on the polynomials' terms, not expressions.
    """
    common = ring.one
    for f in fractions:
        common = common.lcm(f.denom)
    c, s, ch, sh = (ring.gens[ring.symbols.index(a)] for a in ATOMS.functions)
    i_s, i_sh = ring.symbols.index(ATOMS.s), ring.symbols.index(ATOMS.sh)

    def normal(poly):
        out = ring.zero
        for monom, coeff in poly.terms():
            m = list(monom)
            i, j = m[i_s], m[i_sh]
            m[i_s], m[i_sh] = i % 2, j % 2
            out += ring({tuple(m): coeff}) * (1 - c**2) ** (i // 2) * (ch**2 - 1) ** (j // 2)
        return out

    nums = [normal(f.numer * common.exquo(f.denom)) for f in fractions]
    g = ring.zero
    for n in nums:
        g = g.gcd(n)
    return [n.exquo(g) for n in nums]


def _linear_system(problem: TipProblem):
    """u0(x) with symbolic constants, the 4x4 system M C = rhs, and the tip values of u0."""
    u, consts = general_solution()
    if not problem.load:
        u = u.subs(q0, 0)
    atL = tip_derivatives(u, L, 3)
    equations = [sp.expand(e) for e in [*tip_derivatives(u, 0, 1), *problem.conditions(atL)]]
    M, rhs = sp.linear_eq_to_matrix(equations, consts)
    return u, consts, equations, M, rhs, atL


@lru_cache(maxsize=None)
def solve_tip_problem(problem: TipProblem) -> TipSolution:
    """Solve Eq. 2 with Eq. 3 at x = 0 and the problem's tip conditions, by Cramer's rule.

    The adjugate and determinant are taken over the field of rational functions in the
    atoms of ``beta`` and the parameters (SymPy's polynomial domains, not expression trees:
    the same result, several times faster).

    >>> free = TipProblem("free", lambda U: [U[2], EI*U[3] + f0], (f0,), load=False)
    >>> sol = solve_tip_problem(free)
    >>> sp.limit(sol.tip_deflection(f0), beta, 0)   # static: u(L) = f0 / k
    1/k
    """
    _, consts, _, M, rhs, atL = _linear_system(problem)
    excitations = list(problem.drives) + ([q0] if problem.load else [])
    values = [to_atoms(v, beta) for v in (atL[1], atL[0])]
    rows = [[sp.diff(v, c) for c in consts] for v in values]
    # The particular solution contributes to u(L) directly, not through the constants.
    offsets = [[sp.diff(v - sum(sp.diff(v, c) * c for c in consts), d) for d in excitations] for v in values]
    columns = [[to_atoms(sp.diff(e, d), beta) for e in rhs] for d in excitations]
    entries = [to_atoms(e, beta) for e in M]
    field, elements = construct_domain([*entries, *sum(rows, []), *sum(offsets, []), *sum(columns, [])], field=True)
    take = iter(elements)
    adj, det = DomainMatrix([[next(take) for _ in range(4)] for _ in range(4)], (4, 4), field).adj_det()
    rows = [DomainMatrix([[next(take) for _ in range(4)]], (1, 4), field) for _ in values]
    offsets = [[next(take) for _ in excitations] for _ in values]
    columns = [DomainMatrix([[next(take)] for _ in range(4)], (4, 1), field) for _ in excitations]
    outputs = [(row * adj * column)[0, 0].element + offset * det
               for row, offs in zip(rows, offsets) for column, offset in zip(columns, offs)]
    reduced = _clear_and_reduce(field.field.ring, [det, *outputs])
    # Fix the overall sign: leading coefficient (lex order) of the denominator positive.
    ordered = sorted(reduced[0].as_expr().free_symbols, key=str)
    sign = -1 if sp.Poly(reduced[0].as_expr(), *ordered).LC() < 0 else 1
    denominator, *numerators = [sp.expand(from_atoms(sign * r.as_expr(), beta)) for r in reduced]
    n = len(excitations)
    return TipSolution(problem, denominator, dict(zip(excitations, numerators[:n])),
                       dict(zip(excitations, numerators[n:])))


def residuals(solution: TipSolution) -> dict[str, sp.Expr]:
    """Residuals of the solution substituted back into Eq. 2, Eq. 3 and the tip conditions.

    The constants are recomputed from the raw linear system (``M^-1 rhs``), independently
    of the reduction that produced ``solution``; every residual is exactly zero when the
    reported slope and deflection are right (test with :func:`is_identically_zero`).
    """
    u, consts, equations, M, rhs, atL = _linear_system(solution.problem)
    values = dict(zip(consts, M.adjugate(method="berkowitz") * rhs / M.det(method="berkowitz")))
    load = q0 / EI if solution.problem.load else 0
    out = {"ode": sp.expand(u.diff(x, 4) - kappa**4 * u - load)}
    names = ["u(0)", "u'(0)", "tip condition 1", "tip condition 2"]
    out.update({n: e.subs(values) for n, e in zip(names, equations)})
    drives = solution.drives
    out["theta"] = atL[1].subs(values) - sum(solution.theta(d) * d for d in drives)
    out["u(L)"] = atL[0].subs(values) - sum(solution.tip_deflection(d) * d for d in drives)
    return out
