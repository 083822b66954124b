"""Certified resonance roots of derived (SymPy) characteristic functions.

A thin adapter: :func:`certified_roots` turns a SymPy expression into a python-flint
callable and hands it to :func:`pfmdyn.derivations.certify.certify`, the project's one certified-root
engine (complete isolation with ``arb_series.find_roots``, then interval Newton).  It is
the symbolic entry point used by ``pfmdyn verify``; feeding it the SymPy denominators
gives a code path independent of the generated characteristic functions.
"""
from __future__ import annotations

from dataclasses import dataclass

import flint
import mpmath as mp
import sympy as sp

from .certify import certify, interval_strings

__all__ = ["CertifiedRoot", "certified_roots"]


def _cosh(z):
    return (z.exp() + (-z).exp()) / 2


def _sinh(z):
    return (z.exp() - (-z).exp()) / 2


_ARB_FUNCS = {"cos": lambda z: z.cos(), "sin": lambda z: z.sin(), "exp": lambda z: z.exp(),
              "cosh": _cosh, "sinh": _sinh, "tan": lambda z: z.sin() / z.cos()}


@dataclass(frozen=True)
class CertifiedRoot:
    """A simple root proven to lie in ``[lower, upper]`` (decimal strings, exact endpoints)."""

    lower: str
    upper: str

    @property
    def value(self) -> mp.mpf:
        """Midpoint of the certified bracket."""
        return (mp.mpf(self.lower) + mp.mpf(self.upper)) / 2


def _ball_callable(expr: sp.Expr, var: sp.Symbol, params: dict):
    """``expr`` with ``params`` substituted, as a function of ``var`` on python-flint balls and
    series, its rational constants exact (``fmpq``): the same function serves the exact Taylor
    series at the origin (:func:`pfmdyn.derivations.certify.certify`'s ``f_exact``)."""
    fixed = sp.sympify(expr).subs({s: sp.Rational(str(v)) for s, v in params.items()})
    if fixed.free_symbols - {var}:
        raise ValueError(f"unset parameters: {sorted(map(str, fixed.free_symbols - {var}))}")
    rationals = sorted({a for a in fixed.atoms(sp.Rational) if not a.is_Integer}, key=str)
    names = sp.symbols(f"_q0:{len(rationals)}")
    f = sp.lambdify((var, *names), fixed.subs(dict(zip(rationals, names))), modules=[_ARB_FUNCS])
    values = [flint.fmpq(int(r.p), int(r.q)) for r in rationals]
    return lambda s: f(s, *values)


def certified_roots(expr: sp.Expr, var: sp.Symbol, count: int, digits: int = 15,
                    params: dict | None = None, lower: float | None = None, step: float = 10.0) -> list[CertifiedRoot]:
    """The first ``count`` zeros of ``expr`` in ``var`` > ``lower``, certified.

    ``lower=None``: from the origin, whose neighbourhood the exact Taylor series proves free of
    zeros (a zero at the origin itself, of any order, is not counted).  The search interval
    grows by ``step`` until ``count`` roots are isolated; each bracket is then narrowed to a
    relative width below ``10**-(digits + 3)``.

    >>> b = sp.Symbol("beta", positive=True)
    >>> [str(r.value)[:8] for r in certified_roots(1 + sp.cos(b) * sp.cosh(b), b, 3, digits=8)]
    ['1.875104', '4.694091', '7.854757']
    """
    f = _ball_callable(expr, var, params or {})
    balls, _ = certify(f, count, digits, f_exact=f if lower is None else None, lower=lower, step=step)
    return [CertifiedRoot(*interval_strings(ball, digits + 6)) for ball in balls]
