"""Jacobians of the transfer functions, generated with the functions (the SymForce way).

Every transfer coefficient is a ratio ``T = N / D`` of polynomials in the parameters and
in the atoms (cos, sin, cosh, sinh) of one or two arguments.  Its partial derivative with
respect to a parameter ``p`` is ``T_p = (N_p - T D_p) / D``, where ``N_p``, ``D_p`` are
again such polynomials (:func:`derivative`: the atoms differentiate into atoms of the same
argument, so the hyperbolic degree does not grow).  They are therefore stabilised exactly
as ``N`` and ``D`` are (same split into a basis, same series branch, same division by
``cosh**d``: the common factor cancels in ``T_p``), and printed with one CSE over the
values and all partials, so the Jacobian shares the function's subexpressions.

:data:`JACOBIANS` names the families that get a ``<function>_and_jacobian`` and the
parameters it differentiates with respect to (``beta`` carries the frequency and, by the
chain rule, damping).
"""
from __future__ import annotations

import sympy as sp

from ..trig import ATOMS, Atoms  # noqa: F401  (ATOMS: the doctest)
from .printing import cse_lines

__all__ = ["JACOBIANS", "derivative", "partials", "render_and_jacobian"]

JACOBIANS = {
    "elastic_contact": ("beta", "k1", "k2"),
    "tip_mass": ("beta", "k1", "k2", "mu"),
    "tilt": ("beta", "kvv", "kll", "kvl"),
    "tip_setback": ("beta", "k", "kvv", "kll", "kvl", "mu", "gamma", "rho_g"),
}
"""Family module -> parameters of its generated Jacobian, in column order."""


def derivative(expr: sp.Expr, var: sp.Symbol, rates: dict[Atoms, sp.Expr]) -> sp.Expr:
    """Total derivative of a polynomial in atoms; ``rates[at]`` is d(argument of ``at``)/d ``var``.

    >>> b = sp.Symbol("beta")
    >>> derivative(b**2 * ATOMS.c * ATOMS.ch, b, {ATOMS: 1})
    2*_c*_ch*beta + _c*_sh*beta**2 - _ch*_s*beta**2
    """
    out = sp.diff(expr, var)
    for at, rate in rates.items():
        # cos' = -sin, sin' = cos, cosh' = sinh, sinh' = cosh (of the atom set's argument).
        d = (-at.s * sp.diff(expr, at.c) + at.c * sp.diff(expr, at.s)
             + at.sh * sp.diff(expr, at.ch) + at.ch * sp.diff(expr, at.sh))
        out += rate * d
    return sp.expand(out)


def partials(exprs, wrt, rates) -> list[sp.Expr]:
    """``[d e / d p for p in wrt for e in exprs]`` (``rates[p]``: atom rates of ``p``)."""
    return [derivative(e, p, rates.get(p, {})) for p in wrt for e in exprs]


def render_and_jacobian(name: str, signature: str, summary: str, preamble: str, wrt,
                        value_exprs, partial_exprs, indent: str = "    ") -> str:
    """Source of ``<name>_and_jacobian``: the values, then one block per partial, each run
    only when asked for (``wrt``), so a caller pays for the partials it uses.

    ``value_exprs`` are ``[D, N_1, ..., N_n]`` and ``partial_exprs`` ``[D_p, N_1p, ...]`` for
    each ``p`` in ``wrt`` (SymPy, in the names the preamble defines); each list is printed
    with its own CSE.
    """
    n_out = len(value_exprs) - 1
    names = ", ".join(map(str, wrt))
    lines, reduced = cse_lines(value_exprs, indent)
    body = ["\n".join(lines), f"{indent}_r = 1.0 / ({reduced[0]})"]
    body += [f"{indent}_v{i} = ({n}) * _r" for i, n in enumerate(reduced[1:])]
    body.append(f"{indent}_jac = dict.fromkeys(JACOBIAN_PARAMETERS)")
    for j, p in enumerate(wrt):
        exprs = partial_exprs[j * (n_out + 1):(j + 1) * (n_out + 1)]
        lines, reduced = cse_lines(exprs, indent * 2, prefix=f"_d{j}_")
        body.append(f"{indent}if {str(p)!r} in wrt:")
        body += lines
        # T_p = (N_p - T D_p) / D, with D_p / D computed once.
        body.append(f"{indent * 2}_q = ({reduced[0]}) * _r")
        cols = [f"-_v{i} * _q" if d == "0" else f"({d}) * _r - _v{i} * _q" for i, d in enumerate(reduced[1:])]
        body.append(f"{indent * 2}_jac[{str(p)!r}] = ({', '.join(cols)}{',' if n_out == 1 else ''})")
    values = ", ".join(f"_v{i}" for i in range(n_out))
    text = "\n".join(b for b in body if b)
    return f'''

def {name}_and_jacobian({signature}, wrt=JACOBIAN_PARAMETERS):
    """{summary[0].upper() + summary[1:]}, and its partial derivatives w.r.t. ({names}).

    Arguments as :func:`{name}`; ``wrt``: the partials to compute (a subset of
    ``JACOBIAN_PARAMETERS``), the others are returned as None.

    Returns
    -------
    values : tuple of ndarray
        as :func:`{name}`
    jacobian : tuple of tuples of ndarray
        ``jacobian[i][j]``: derivative of ``values[i]`` w.r.t. ``JACOBIAN_PARAMETERS[j]``
    """
{preamble}{text}
    _cols = list(_jac.values())
    return ({values}{"," if n_out == 1 else ""}), tuple(tuple(None if c is None else c[i] for c in _cols) for i in range({n_out}))
'''
