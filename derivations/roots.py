"""Certified resonance roots of derived characteristic functions (ball arithmetic, python-flint).

:func:`certified_roots` isolates every zero of a characteristic function on an interval
with ``arb_series.find_roots``: each discarded sub-interval is proven zero-free and each
returned bracket has a sign change with a derivative that excludes zero, so the list is
complete and free of duplicates.  Brackets are then narrowed by bisection with rigorous
sign tests.  The input is a SymPy expression; this module is the symbolic side used by
``pfmdyn verify`` (the numeric package has its own generated characteristic functions).
"""
from __future__ import annotations

from dataclasses import dataclass

import flint
import mpmath as mp
import sympy as sp

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


def _arb_callable(expr: sp.Expr, var: sp.Symbol, params: dict):
    fixed = sp.sympify(expr).subs({s: sp.Rational(str(v)) for s, v in params.items()})
    if fixed.free_symbols - {var}:
        raise ValueError(f"unset parameters: {sorted(map(str, fixed.free_symbols - {var}))}")
    return sp.lambdify(var, fixed, modules=[_ARB_FUNCS])


def certified_roots(expr: sp.Expr, var: sp.Symbol, count: int, digits: int = 15,
                    params: dict | None = None, lower: float = 0.01, step: float = 10.0) -> list[CertifiedRoot]:
    """The first ``count`` positive zeros of ``expr`` (in ``var`` > ``lower``), certified.

    The search interval grows by ``step`` until ``count`` roots are isolated.  Each bracket
    is then bisected with proven signs until its width is below ``10**-(digits + 2)``.

    >>> b = sp.Symbol("beta", positive=True)
    >>> [str(r.value)[:8] for r in certified_roots(1 + sp.cos(b) * sp.cosh(b), b, 3, digits=8)]
    ['1.875104', '4.694091', '7.854757']
    """
    f = _arb_callable(expr, var, params or {})
    old_prec = flint.ctx.prec
    flint.ctx.prec = max(128, int(3.5 * digits) + 64)
    try:
        hi = lower + step
        while True:
            brackets = flint.arb_series.find_roots(lambda s: f(s), flint.arb(str(lower)), flint.arb(str(hi)))
            if len(brackets) >= count:
                break
            hi += step
        out = []
        for a, b in brackets[:count]:
            out.append(_narrow(f, a, b, digits))
        return out
    finally:
        flint.ctx.prec = old_prec


def _sign(f, point: flint.arb) -> int:
    value = f(flint.arb_series([point]))[0]
    if value > 0:
        return 1
    if value < 0:
        return -1
    raise ArithmeticError(f"sign of the characteristic function undecided at {point}")


def _narrow(f, a: flint.arb, b: flint.arb, digits: int) -> CertifiedRoot:
    """Bisect a certified bracket [a, b] (exact endpoints) with rigorous sign tests."""
    sa = _sign(f, a)
    width = flint.arb(10) ** (-(digits + 2))
    while (b - a) > width:
        mid = flint.arb((a + b).mid() / 2)
        if _sign(f, mid) == sa:
            a = mid
        else:
            b = mid
    return CertifiedRoot(a.mid().str(digits + 6, radius=False), b.mid().str(digits + 6, radius=False))
