"""Limits and scaling of derived transfer functions: parameter limits, beta -> 0, beta -> oo.

* :func:`param_limit` sends a stiffness to 0 or infinity in a ratio of polynomials in it
  (leading coefficients, exact);
* :func:`low_frequency` expands numerator and denominator in powers of ``beta`` by
  substituting the Taylor series of cos, sin, cosh and sinh (exact, fast for the large
  expressions where ``sympy.limit`` is slow);
* :func:`envelope_exponent` measures the high-frequency power law of ``|expr|`` against
  ``omega`` (``omega ~ beta**2``) by a log-log fit of its envelope, in mpmath, far from
  resonances and anti-resonances.
"""
from __future__ import annotations

from functools import lru_cache

import mpmath as mp
import sympy as sp

from .beam import beta

__all__ = ["param_limit", "low_frequency", "envelope_exponent"]


def param_limit(expr: sp.Expr, sym: sp.Symbol, to) -> sp.Expr:
    """Limit of a rational function of ``sym`` as ``sym -> 0`` or ``sym -> oo``.

    >>> from .beam import k, k1
    >>> param_limit(k1 / (k + k1), k1, sp.oo), param_limit(k1 / (k + k1), k1, 0)
    (1, 0)
    """
    num, den = sp.fraction(sp.together(expr))
    if to == 0:
        return sp.cancel(sp.together(num.subs(sym, 0) / den.subs(sym, 0)))
    pn, pd = sp.Poly(sp.expand(num), sym), sp.Poly(sp.expand(den), sym)
    if pn.degree() < pd.degree():
        return sp.S.Zero
    if pn.degree() > pd.degree():
        return sp.oo * sp.sign(pn.LC() / pd.LC())
    return sp.cancel(pn.LC() / pd.LC())


@lru_cache(maxsize=None)
def _series(order: int) -> dict:
    """Taylor polynomials of cos, sin, cosh, sinh in beta (computed once per order)."""
    return {f(beta): sp.series(f(beta), beta, 0, order).removeO() for f in (sp.cos, sp.sin, sp.cosh, sp.sinh)}


def _taylor(expr: sp.Expr, order: int) -> dict[int, sp.Expr]:
    """The coefficients of ``beta**n``, ``n < order``, of the series of ``expr`` (absent when zero)."""
    terms: dict[int, list] = {}
    for term in sp.Add.make_args(sp.expand(expr.subs(_series(order)))):
        coeff, power = term.as_coeff_exponent(beta)
        if power.is_Integer and 0 <= power < order and not coeff.has(beta):
            terms.setdefault(int(power), []).append(coeff)
    return {n: c for n, parts in terms.items() if (c := sp.Add(*parts)) != 0}


def low_frequency(expr: sp.Expr, order: int = 14) -> sp.Expr:
    """Limit of ``expr`` as ``beta -> 0`` (leading terms of the Taylor series).

    >>> low_frequency((sp.cosh(beta) - sp.cos(beta)) / beta**2)
    1
    """
    num, den = sp.fraction(sp.together(expr))
    tn, td = _taylor(num, order), _taylor(den, order)
    ln = min(tn, default=None)
    # an expanded polynomial in the parameters is zero only when it reads 0
    ld = min((n for n, c in td.items() if c.is_polynomial() or sp.simplify(c) != 0), default=None)
    if ld is None:
        raise ValueError("denominator vanishes to the order used; raise `order`")
    if ln is None or ln > ld:
        return sp.S.Zero
    if ln < ld:
        return sp.zoo
    return sp.factor(sp.cancel(tn[ln] / td[ld]))


def envelope_exponent(expr: sp.Expr, values: dict, beta_lo=200.0, beta_hi=20000.0,
                      points: int = 40) -> float:
    """Exponent p of ``|expr| ~ omega**p`` at high frequency (``omega`` proportional to ``beta**2``).

    ``|expr|`` is sampled at ``beta = (m + 1/4) pi``, where ``|sin|`` and ``|cos|`` equal
    1/sqrt(2), so every sample sits on the envelope, away from the zeros of both
    numerator and denominator.  The slope of the log-log least-squares line in ``beta`` is
    halved to give the exponent in ``omega``.

    >>> round(envelope_exponent(sp.sin(beta) / beta**3, {}), 3)
    -1.5
    """
    f = sp.lambdify([beta, *values], expr, "mpmath")
    logs_b, logs_f = [], []
    with mp.workdps(30):
        for i in range(points):
            target = beta_lo * (beta_hi / beta_lo) ** (i / (points - 1))
            b = (mp.floor(target / mp.pi) + mp.mpf(1) / 4) * mp.pi
            logs_b.append(mp.log(b))
            logs_f.append(mp.log(abs(f(b, *[mp.mpf(v) for v in values.values()]))))
    mb, mf = sum(logs_b) / points, sum(logs_f) / points
    slope = sum((a - mb) * (c - mf) for a, c in zip(logs_b, logs_f)) / sum((a - mb) ** 2 for a in logs_b)
    return float(slope) / 2
