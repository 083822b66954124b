"""Stabilisation: split by parameter monomial, overflow-free closed form, series near zero.

Each basis function ``h`` (a primitive polynomial in the atoms of one argument) is
evaluated, for ``|beta|`` at or above a switch point, divided by ``cosh(beta)**d`` with
``tanh``, ``sech`` built from ``e = exp(-beta)`` (:func:`derivations.trig.scaled`,
:func:`clipped_exp`); below it, by its Taylor series from the same expression
(:func:`series_branch`).  Both scale numerator and denominator alike.
"""
from __future__ import annotations

import math

import mpmath as mp
import sympy as sp

from ..trig import ATOMS, from_atoms, scaled, to_atoms

__all__ = ["CLIP", "clipped_exp", "split", "switch_point", "series_branch"]

# Switch-point search: the closed form must lose at most this factor to cancellation.
_MAX_CANCELLATION = 64
# Series truncation target, relative to the function's value at the switch point.
_SERIES_TOL = 2.0**-56
CLIP = 100
"""Beyond ``Re(arg) = 100``, ``e**-arg < 4e-44``: far below the rounding error of the O(1)
terms every scaled basis function contains, so the argument of exp is clipped there to
avoid underflow (which ``np.errstate(all="raise")`` reports), also inside complex division,
whose intermediate products are of order ``e**-4 Re(arg)``."""


def clipped_exp(arg: str, real: str) -> str:
    """Source text of ``exp(-arg)``, clipped at :data:`CLIP` (``real`` is ``Re arg`` as text).

    >>> clipped_exp("x", "x.real")
    'np.exp(np.maximum(x.real - 100.0, 0.0) - x)'
    """
    return f"np.exp(np.maximum({real} - {CLIP}.0, 0.0) - {arg})"


def split(expr: sp.Expr, var: sp.Symbol, params) -> list[tuple[sp.Expr, sp.Expr]]:
    """``expr`` as ``[(coefficient, h), ...]`` with ``expr = sum coefficient * h``.

    ``coefficient`` is a rational times a monomial in the parameters and ``var``; ``h`` is
    a primitive polynomial in cos, sin, cosh, sinh of ``var`` (positive leading
    coefficient), written with the atoms ``_c, _s, _ch, _sh``.

    >>> b, k = sp.symbols("beta k")
    >>> split(3*b**4*k + 3*b**4*k*sp.cos(b)*sp.cosh(b), b, (k,))
    [(3*beta**4*k, _c*_ch + 1)]
    """
    poly = sp.Poly(to_atoms(expr, var), var, *params)
    groups: dict[sp.Expr, sp.Expr] = {}
    for monom, coeff in poly.terms():
        mono = sp.Mul(*[g**e for g, e in zip(poly.gens, monom)])
        groups[mono] = groups.get(mono, 0) + coeff
    out = []
    for mono, h in groups.items():
        hp = sp.Poly(h, *ATOMS.functions)
        content, prim = hp.primitive()
        if prim.LC() < 0:
            content, prim = -content, -prim
        out.append((content * mono, prim.as_expr()))
    return sorted(out, key=lambda t: sp.default_sort_key(t))


def _cancellation(h: sp.Expr, x: float, degree: int) -> float:
    """Error amplification of the scaled closed form of ``h`` at ``x`` (mpmath).

    Sum of |terms| over |value|, where a term holding ``tanh`` counts ``1/(1 - e**-2x)``
    times: ``tanh = (1 - e**2)/(1 + e**2)`` cancels in floating point at small ``x``.
    """
    with mp.workdps(60):
        vals = {ATOMS.c: mp.cos(x), ATOMS.s: mp.sin(x), ATOMS.tanh: mp.tanh(x), ATOMS.sech: mp.sech(x)}
        tanh_cond = 1 / -mp.expm1(-2 * mp.mpf(x))
        terms = [(mp.mpf(sp.Float(t.subs(vals), 60)), tanh_cond if t.has(ATOMS.tanh) else 1)
                 for t in sp.Add.make_args(scaled(h, {ATOMS: degree}))]
        total = abs(sum(t for t, _ in terms))
        return float(sum(abs(t) * c for t, c in terms) / total)


def switch_point(h: sp.Expr, degree: int) -> float:
    """Smallest ``|beta|`` (grid step 1/20) where the closed form of ``h`` loses < 64x to cancellation.

    >>> switch_point(ATOMS.c*ATOMS.ch + 1, 1)     # no cancellation near 0: no series branch
    0.0
    >>> switch_point(ATOMS.c*ATOMS.ch - 1, 1)     # cos cosh - 1 ~ -beta**4/6
    0.7
    """
    x = 0.0
    while _cancellation(h, x or 1e-3, degree) > _MAX_CANCELLATION:
        x = round(x + 0.05, 2)
    return x


def _taylor(h: sp.Expr, var: sp.Symbol, order: int) -> sp.Poly:
    """Taylor polynomial of ``h`` (in atoms) up to ``var**(order - 1)``, exact rationals."""
    f = sp.factorial
    series = {
        ATOMS.c: sum((-1)**j * var**(2*j) / f(2*j) for j in range(order // 2 + 1)),
        ATOMS.s: sum((-1)**j * var**(2*j + 1) / f(2*j + 1) for j in range(order // 2 + 1)),
        ATOMS.ch: sum(var**(2*j) / f(2*j) for j in range(order // 2 + 1)),
        ATOMS.sh: sum(var**(2*j + 1) / f(2*j + 1) for j in range(order // 2 + 1)),
    }
    full = sp.Poly(sp.expand(h.subs(series)), var)
    return sp.Poly.from_dict({m: c for m, c in full.as_dict().items() if m[0] < order}, var)


def series_branch(h: sp.Expr, var: sp.Symbol, at: float) -> tuple[int, int, list[sp.Rational]]:
    """Taylor series of ``h`` as ``var**p * P(var**q)``: returns ``(p, q, coefficients of P)``.

    Terms are added until the first omitted one is below 2**-56 of ``|h(at)|``: truncation
    error matches rounding error at the switch point ``at`` and is smaller below it.

    >>> series_branch(ATOMS.c*ATOMS.ch - 1, sp.Symbol("beta"), 0.7)
    (4, 4, [-1/6, 1/2520, -1/7484400, 1/81729648000])
    """
    with mp.workdps(40):
        value = sp.lambdify(var, from_atoms(h, var), "mpmath")(mp.mpf(at))
        target = abs(value) * _SERIES_TOL
    order = 12
    while True:
        ser = _taylor(h, var, order)
        exps = sorted(m[0] for m in ser.monoms())
        p = exps[0]
        q = math.gcd(*[e - p for e in exps[1:]]) if len(exps) > 1 else 4
        nxt = exps[-1] + q
        # The first omitted term bounds the truncation error (factorial decay).
        omitted = abs(_taylor(h, var, nxt + 1).coeff_monomial(var**nxt)) * mp.mpf(at) ** nxt
        if len(exps) > 2 and omitted < target:
            return p, q, [ser.coeff_monomial(var**e) for e in range(p, exps[-1] + 1, q)]
        order += 4
