"""The trigonometric-hyperbolic normal form, for any argument and any number of arguments.

Every solution in ``derivations`` is a polynomial in cos, sin, cosh, sinh of one argument
(``beta``, or ``xi L`` for torsion) or of two (``gamma beta`` and ``(1 - gamma) beta`` for
the set-back tip).  Computations run on *atoms*: one :class:`Atoms` set of four plain
symbols per argument.  This module is the one place that defines them, the canonical
normal form (:func:`normal_form`) and the stabilised form divided by a power of cosh
(:func:`scaled`, with the atoms ``tanh`` and ``sech``) used by codegen.
"""
from __future__ import annotations

from typing import Mapping, NamedTuple

import sympy as sp

__all__ = ["Atoms", "atoms", "ATOMS", "to_atoms", "from_atoms", "normal_form",
           "function_normal_form", "hyperbolic_degree", "scaled"]


class Atoms(NamedTuple):
    """Symbols standing for cos, sin, cosh, sinh of one argument, and the scaled tanh, sech."""

    c: sp.Symbol
    s: sp.Symbol
    ch: sp.Symbol
    sh: sp.Symbol
    tanh: sp.Symbol
    sech: sp.Symbol

    @property
    def functions(self) -> tuple[sp.Symbol, ...]:
        """The four atoms of cos, sin, cosh, sinh (in that order)."""
        return self[:4]


def atoms(tag: str = "") -> Atoms:
    """The atom set named with ``tag``: ``_c<tag>, _s<tag>, _ch<tag>, _sh<tag>, ...``.

    >>> atoms("a").ch
    _cha
    """
    return Atoms(*sp.symbols(" ".join(f"_{n}{tag}" for n in ("c", "s", "ch", "sh", "tanh", "sech"))))


ATOMS = atoms()
"""The atoms of a one-argument solution: ``_c, _s, _ch, _sh`` (scaled: ``_tanh, _sech``)."""

_FUNCTIONS = (sp.cos, sp.sin, sp.cosh, sp.sinh)


def to_atoms(expr: sp.Expr, arg: sp.Expr, at: Atoms = ATOMS) -> sp.Expr:
    """Replace cos, sin, cosh, sinh of ``arg`` by the atoms ``at``.

    >>> b = sp.Symbol("b"); to_atoms(sp.cos(b) * sp.sinh(b), b)
    _c*_sh
    """
    return sp.sympify(expr).xreplace({f(arg): a for f, a in zip(_FUNCTIONS, at.functions)})


def from_atoms(expr: sp.Expr, arg: sp.Expr, at: Atoms = ATOMS) -> sp.Expr:
    """Replace the atoms ``at`` by cos, sin, cosh, sinh of ``arg``.

    >>> b = sp.Symbol("b"); from_atoms(ATOMS.c * ATOMS.ch + 1, b)
    cos(b)*cosh(b) + 1
    """
    return sp.sympify(expr).xreplace({a: f(arg) for f, a in zip(_FUNCTIONS, at.functions)})


def normal_form(expr: sp.Expr, *sets: Atoms) -> sp.Expr:
    """Canonical form of a polynomial in the atom ``sets`` (default: :data:`ATOMS`).

    Powers of sin and sinh above one are removed with ``sin**2 = 1 - cos**2`` and
    ``sinh**2 = cosh**2 - 1`` for each argument.  The relations have coprime leading
    monomials, so they form a Groebner basis and the result is unique: two expressions
    are identical exactly when their normal forms are.

    >>> normal_form(ATOMS.s**2 + ATOMS.c**2)
    1
    """
    out = sp.expand(expr)
    for c, s, ch, sh, *_ in sets or (ATOMS,):
        poly = sp.Poly(out, s, sh)
        out = sp.S.Zero
        for (i, j), coeff in poly.terms():
            out += (coeff * (s if i % 2 else 1) * (1 - c**2) ** (i // 2)
                    * (sh if j % 2 else 1) * (ch**2 - 1) ** (j // 2))
        out = sp.expand(out)
    return out


def function_normal_form(expr: sp.Expr, arg: sp.Expr) -> sp.Expr:
    """:func:`normal_form` of a polynomial in cos, sin, cosh, sinh of ``arg``, in those functions.

    >>> b = sp.Symbol("b")
    >>> function_normal_form(sp.sin(b)**2 + sp.cos(b)**2 + sp.cosh(b)**2 - sp.sinh(b)**2, b)
    2
    """
    return from_atoms(normal_form(to_atoms(expr, arg)), arg)


def hyperbolic_degree(expr: sp.Expr, at: Atoms = ATOMS) -> int:
    """Total degree of ``expr`` in the hyperbolic atoms of ``at``.

    >>> hyperbolic_degree(ATOMS.ch**2 * ATOMS.sh + ATOMS.c)
    3
    """
    return sp.Poly(expr, at.ch, at.sh).total_degree()


def scaled(expr: sp.Expr, degrees: Mapping[Atoms, int]) -> sp.Expr:
    """``expr`` divided by ``cosh**d`` of each argument, in the atoms ``c, s, tanh, sech``.

    ``degrees`` maps each atom set to its power ``d`` (at least the hyperbolic degree).

    >>> scaled(ATOMS.c * ATOMS.ch + 1, {ATOMS: 1})
    _c + _sech
    """
    sets = list(degrees.items())
    # one polynomial in every set's (cosh, sinh) at once: expanding once per set was the cost
    poly = sp.Poly(sp.expand(expr), *(g for at, _ in sets for g in (at.ch, at.sh)))
    terms = []
    for monomial, coeff in poly.terms():
        factor = coeff
        for n, (at, d) in enumerate(sets):
            i, j = monomial[2 * n], monomial[2 * n + 1]
            factor = factor * at.tanh**j * at.sech**(d - i - j)
        terms.append(factor)
    return sp.expand(sp.Add(*terms))
