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

from ..trig import ATOMS, Atoms

__all__ = ["JACOBIANS", "derivative", "partials", "render_and_jacobian"]

JACOBIANS = {
    "elastic_contact": ("beta", "k1", "k2"),
    "tip_mass": ("beta", "k1", "k2", "mu"),
    "tilt": ("beta", "kvv", "kll", "kvl"),
    "tip_setback": ("beta", "k", "kvv", "kll", "kvl", "mu", "gamma"),
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


def render_and_jacobian(name: str, signature: str, summary: str, preamble: str, wrt, n_out: int,
                        den: str, nums: list[str], d_exprs: list[str], lines: list[str]) -> str:
    """Source of ``<name>_and_jacobian``: values and partials from shared CSE lines.

    ``den``, ``nums`` and ``d_exprs`` (``[D_p, N_1p, ..., N_np]`` for each ``p`` in ``wrt``)
    are the printed reduced expressions; ``lines`` the CSE assignments they use.
    """
    names = ", ".join(map(str, wrt))
    values = ", ".join(f"_v{i}" for i in range(n_out))
    rows = []
    for i in range(n_out):
        cols = []
        for j in range(len(wrt)):
            d_num = d_exprs[j * (n_out + 1) + 1 + i]
            # T_p = (N_p - T D_p) / D, with D_p / D computed once per parameter.
            cols.append(f"-_v{i} * _q{j}" if d_num == "0" else f"({d_num}) * _r - _v{i} * _q{j}")
        rows.append("(" + ", ".join(cols) + ("," if len(cols) == 1 else "") + ")")
    body = "\n".join(lines)
    assign = "\n".join([f"    _v{i} = ({n}) * _r" for i, n in enumerate(nums)]
                       + [f"    _q{j} = ({d_exprs[j * (n_out + 1)]}) * _r" for j in range(len(wrt))])
    return f'''

def {name}_and_jacobian({signature}):
    """{summary[0].upper() + summary[1:]}, and its partial derivatives w.r.t. ({names}).

    Arguments as :func:`{name}`.  Values and partials share their subexpressions.

    Returns
    -------
    values : tuple of ndarray
        as :func:`{name}`
    jacobian : tuple of tuples of ndarray
        ``jacobian[i][j]``: derivative of ``values[i]`` w.r.t. ``JACOBIAN_PARAMETERS[j]``
    """
{preamble}{body}
    _r = 1.0 / ({den})
{assign}
    return (({values}{"," if n_out == 1 else ""}), ({", ".join(rows)}{"," if n_out == 1 else ""}))
'''
