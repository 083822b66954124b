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

__all__ = ["JACOBIANS", "derivative", "partials", "and_jacobian"]

JACOBIANS = {
    "elastic_contact": ("beta", "k1", "k2"),
}
"""Family module -> parameters of its generated Jacobian, in column order: the paper's probe, which the
maps fit in closed form; a set-back, heavy or tilted tip's partials come from the composed lever
(:func:`pfmdyn.composed.slope_and_jacobian`), so ``tip_mass`` and ``tilt`` have none."""


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


def and_jacobian(name: str, signature: str, summary: str, preamble: str, wrt,
                 value_exprs, partial_exprs, example, arrays=frozenset()) -> dict:
    """Template context of ``<name>_and_jacobian`` (``templates/jacobian.jinja``).

    ``value_exprs`` are ``[D, N_1, ..., N_n]`` and ``partial_exprs`` ``[D_p, N_1p, ...]`` for
    each ``p`` in ``wrt`` (SymPy, in the names the ``preamble`` lines define); each list is
    printed with its own CSE (``arrays``: the symbols that are arrays, :func:`.printing.code`).
    ``T_p = (N_p - T D_p) / D``, with ``D_p / D`` computed once.

    >>> x, p = sp.symbols("x p")
    >>> j = and_jacobian("f", "x, p", "f", "    x = np.asarray(x)", [p], [x, p * x], [0, x], None)
    >>> j["nums"], j["partials"][0]["columns"]
    (['p*x'], ['(x) * _r - _v0 * _q if 0 in drives else None'])
    """
    n_out = len(value_exprs) - 1
    lines, reduced = cse_lines(value_exprs, arrays=arrays)
    blocks = []
    for i, p in enumerate(wrt):
        exprs = partial_exprs[i * (n_out + 1):(i + 1) * (n_out + 1)]
        p_lines, p_reduced = cse_lines(exprs, "        ", prefix=f"_d{i}_", arrays=arrays)
        # a caller wanting few drives skips the others' columns (the maps' fit wants one of four)
        columns = [(f"-_v{m} * _q" if d == "0" else f"({d}) * _r - _v{m} * _q") + f" if {m} in drives else None"
                   for m, d in enumerate(p_reduced[1:])]
        blocks.append({"name": str(p), "lines": p_lines, "den": p_reduced[0], "columns": columns})
    return {"name": name, "signature": signature, "summary": summary, "preamble": preamble.rstrip("\n"),
            "wrt": [str(p) for p in wrt], "lines": lines, "den": reduced[0], "nums": reduced[1:],
            "partials": blocks, "example": example}
