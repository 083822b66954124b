"""Certified isolation and refinement of real zeros of analytic functions (ball arithmetic).

The project's one certified-root algorithm (python-flint ``arb`` balls throughout):

1. *Near the origin*: the Taylor coefficients at 0 are computed exactly in rationals
   (``fmpq_series``), giving the order ``p`` of a trivial zero there; on ``[0, a]`` the
   enclosure of ``f(z)/z**p`` (Taylor polynomial plus a Lagrange remainder bounded over the
   ball) must exclude 0, which proves ``(0, a]`` zero-free.
2. *Isolation*: ``arb_series.find_roots`` on ``[a, b]`` discards only pieces whose ball
   ``f(X)`` excludes 0 and keeps pieces with a sign change and ``f'(X)`` excluding 0, so
   the list is complete on ``(0, b]`` and every bracket holds exactly one simple zero.
3. *Refinement*: interval Newton ``N(X) = m - f(m)/f'(X)`` intersected with ``X`` (the
   zero stays inside by the mean value theorem), precision doubling with the accuracy, and
   a rigorous bisection step whenever Newton fails to halve the width.

Any failed proof raises :class:`CertificationError`.  The functions here know nothing of
beams: :mod:`pfmdyn.derivations.roots` applies them to SymPy expressions (the checks of
``pfmdyn verify``), :mod:`pfmdyn.roots` and the analyses to the generated characteristic
functions.  It lives at the bottom layer so that both sides use the one algorithm, and it
imports python-flint only (no SymPy): numeric code may import it at module level.
"""
from __future__ import annotations

from fractions import Fraction
from math import pi

import flint

__all__ = ["CertificationError", "certify", "zeros_in", "rounded", "interval_strings", "floor_string"]


_ORIGIN_ORDER_CAP = 10          # series length used for the exact Taylor expansion at 0
_ISOLATION_PREC = 96            # bits; isolation needs only signs, refinement raises precision
# find_roots works on at most this many pieces before giving up; a failing call is retried
# on halves (see _find_roots), far cheaper than its default 1e5, which only the last try gets.
_FIND_ROOTS_MAXN = 2000


class CertificationError(ArithmeticError):
    """A proof step failed; the message is the reason reported with ``certified = False``."""


def _fraction(x: flint.arb) -> Fraction:
    """Exact value of an exactly representable ``arb`` (a midpoint or radius)."""
    man, exp = (int(v) for v in x.man_exp())
    return Fraction(man) * Fraction(2) ** exp


def _endpoints(ball: flint.arb) -> tuple[Fraction, Fraction]:
    mid, rad = _fraction(ball.mid()), _fraction(flint.arb(ball.rad()))
    return mid - rad, mid + rad


def _decimal(q: Fraction, digits: int, mode: str) -> str:
    """``q > 0`` rounded to ``digits`` significant digits: ``floor``, ``ceil`` or ``nearest``."""
    exp10 = len(str(q.numerator // q.denominator)) - 1 if q >= 1 else -len(str(q.denominator // q.numerator))
    while True:
        scaled = q * Fraction(10) ** (digits - 1 - exp10)
        n = {"floor": scaled.numerator // scaled.denominator,
             "ceil": -((-scaled.numerator) // scaled.denominator),
             "nearest": round(scaled)}[mode]
        if len(str(n)) <= digits:
            break
        exp10 += 1           # rounding carried into a new digit (9.99 -> 10.0)
    text = str(n).rjust(digits, "0")
    point = exp10 + 1
    if point <= 0:
        return "0." + "0" * (-point) + text
    if point >= digits:
        return text + "0" * (point - digits)
    return text[:point] + "." + text[point:]


def interval_strings(ball: flint.arb, digits: int) -> tuple[str, str]:
    """Decimal endpoints of a positive ball, rounded outward (so they still enclose it).

    Ball radii are stored rounded up, so even an exact-looking ball widens in the last digit.

    >>> interval_strings(flint.arb(2, 0.5), 3)
    ('1.49', '2.51')
    """
    lo, hi = _endpoints(ball)
    return _decimal(lo, digits, "floor"), _decimal(hi, digits, "ceil")


def _sign(f, point: flint.arb) -> int:
    value = f(flint.arb_series([point], prec=1))[0]
    if value > 0:
        return 1
    if value < 0:
        return -1
    raise CertificationError(f"sign of the characteristic function undecided at {point.mid().str(10)}")


def _origin_clearance(f_exact, f_ball, known_order: int | None = None) -> flint.arb:
    """A point ``a > 0`` with ``(0, a]`` proven free of zeros (see step 1 of the module doc).

    Without ``f_exact`` the zero at 0 must be known to be of order ``known_order`` (from the
    derivation, e.g. a slope at a clamp); its Taylor coefficients are then balls.
    """
    if f_exact is None:
        p = known_order
        coeffs = f_ball(flint.arb_series([0, 1], prec=p + 2)).coeffs()
        if coeffs[p].contains(0):
            raise CertificationError(f"order of the zero at 0 not proven to be {p}")
    else:
        coeffs = [flint.arb(c.p) / flint.arb(c.q)
                  for c in f_exact(flint.fmpq_series([0, 1], prec=_ORIGIN_ORDER_CAP)).coeffs()]
        nonzero = [j for j, c in enumerate(coeffs) if c != 0]
        if not nonzero:
            raise CertificationError(f"characteristic function vanishes to order {_ORIGIN_ORDER_CAP} at z = 0")
        p = nonzero[0]
    order = p + 2                     # Taylor polynomial of degree p+1, remainder of order p+2
    a = flint.arb("0.5")
    for _ in range(40):
        box = flint.arb(a / 2, a / 2)                       # the interval [0, a]
        tail = f_ball(flint.arb_series([box, 1], prec=order + 1))[order]
        poly = flint.arb(0)
        for j in range(order - 1, p - 1, -1):
            poly = poly * box + coeffs[j] if j < len(coeffs) else poly * box
        quotient = poly + tail * box ** (order - p)         # encloses f(z)/z^p on (0, a]
        if not quotient.contains(0):
            return a
        a = a / 2
    raise CertificationError("could not prove the neighbourhood of z = 0 free of resonances")


def _find_roots(f, a: flint.arb, b: flint.arb, depth: int = 8) -> list:
    """``arb_series.find_roots`` on ``[a, b]``, retried on halves when it gives up.

    Its bisection stops early where overestimation is large (big ``z**3`` terms that cancel
    only in exact arithmetic); on shorter pieces it succeeds.  A double root fails at
    every depth and is reported.
    """
    prec = flint.ctx.prec
    try:
        return flint.arb_series.find_roots(f, a, b, maxn=_FIND_ROOTS_MAXN if depth else 100000)
    except ValueError as exc:
        flint.ctx.prec = prec          # find_roots does not restore the precision it changed
        if depth == 0:
            raise CertificationError(f"isolation failed on [{a.mid().str(6)}, {b.mid().str(6)}] "
                                     f"(a double root?): {exc}") from exc
    mid = flint.arb(((a + b) / 2).mid())
    for _ in range(20):         # the split point must have a provable sign
        try:
            _sign(f, mid)
            break
        except CertificationError:
            mid = flint.arb((mid + (b - a) / 64).mid())
    return _find_roots(f, a, mid, depth - 1) + _find_roots(f, mid, b, depth - 1)


def _isolate(f, count: int, lower: flint.arb, step: float, limit: float) -> tuple[list, flint.arb]:
    """Complete isolation on ``[lower, b]``, growing ``b`` until ``count`` brackets are found."""
    brackets, a, b = [], lower, lower + step
    while True:
        brackets += _find_roots(f, a, b)
        if len(brackets) >= count:
            return brackets[:count], brackets[count - 1][1]
        if b > limit:
            raise CertificationError(f"only {len(brackets)} roots in (0, {b.mid().str(6)}]")
        a, b = b, b + step


def _refine(f, x: flint.arb, digits: int) -> flint.arb:
    """Narrow ``x`` (a ball proven to hold one simple root) to ``digits`` significant digits."""
    target = flint.arb(10) ** (-(digits + 3))
    final_prec = int(3.33 * (digits + 3)) + 64
    prec = max(64, min(final_prec, 2 * x.rel_accuracy_bits() + 32))
    for _ in range(8 * (digits + 60)):
        flint.ctx.prec = prec
        if 2 * x.rad() < target * x.mid():
            return x
        m = flint.arb(x.mid())
        fm = f(flint.arb_series([m], prec=1))[0]
        slope = f(flint.arb_series([x, 1], prec=2))[1]
        if slope.contains(0):
            raise CertificationError(f"derivative enclosure contains 0 near {m.str(10)}")
        newton = (m - fm / slope).intersection(x)
        if newton.rad() <= x.rad() / 2:
            x = newton
        elif fm.contains(0):
            # f(m) is lost in rounding: only more bits can tell which side the root is on.
            if prec >= final_prec:
                raise CertificationError(f"precision exhausted near {m.str(10)}")
            prec = min(final_prec, 2 * prec)
            continue
        else:
            # Newton gained less than a bisection would (wide first brackets): bisect with
            # the proven signs of f(m) and f'(X); the union encloses the kept half.
            end = x.lower() if (fm > 0) == (slope > 0) else x.upper()
            x = m.union(end).intersection(x)
        # Quadratic convergence: carry about twice the bits of the current accuracy.
        prec = max(prec, min(final_prec, 2 * x.rel_accuracy_bits() + 32))
    raise CertificationError("interval Newton did not converge")


def certify(f, count: int, digits: int, *, f_exact=None, lower=None, step: float | None = None,
            limit: float | None = None) -> tuple[list, flint.arb]:
    """The first ``count`` zeros of ``f`` above ``lower``, as certified balls, and ``z_max``.

    ``f`` maps an ``arb_series`` to an ``arb_series``.  With ``lower=None`` the search starts
    at 0 and ``f_exact`` (the same function on ``fmpq_series``) proves the origin's
    neighbourhood root-free; otherwise zeros in ``(lower, z_max]`` are listed.  Each ball
    is proven to contain exactly one zero and has relative width below ``10**-(digits+3)``;
    the list is complete on the range up to ``z_max``.  Raises :class:`CertificationError`.

    >>> balls, z_max = certify(lambda s: s.sin(), 2, 20, lower=1)
    >>> balls[1].str(20, radius=False)
    '6.2831853071795864769'
    """
    old = flint.ctx.prec
    flint.ctx.prec = _ISOLATION_PREC
    try:
        start = _origin_clearance(f_exact, f) if lower is None else flint.arb(str(lower))
        # Roots of every family are about pi apart, so one pass usually finds them all.
        step = step if step is not None else pi * (count + 1) + 1
        limit = limit if limit is not None else pi * (count + 3) + 20
        brackets, z_max = _isolate(f, count, start, step, limit)
        balls = [_refine(f, flint.arb((a + b) / 2, (b - a) / 2), digits) for a, b in brackets]
        return balls, z_max
    finally:
        flint.ctx.prec = old


def rounded(f, ball: flint.arb, digits: int) -> tuple[flint.arb, str]:
    """Refine until both ends of the ball round to the same ``digits``-digit decimal."""
    for extra in (0, 6, 20, 60):
        ball = _refine(f, ball, digits + extra)
        lo, hi = _endpoints(ball)
        text = _decimal(lo, digits, "nearest")
        if text == _decimal(hi, digits, "nearest"):
            break
    return ball, text        # after 60 extra digits the root is (almost) a rounding tie


def floor_string(x: flint.arb, digits: int) -> str:
    """The midpoint of ``x`` rounded down to ``digits`` significant digits.

    >>> floor_string(flint.arb("12.3456789"), 4)
    '12.34'
    """
    return _decimal(_fraction(x.mid()), digits, "floor")


def zeros_in(f, lower, upper, digits: int, *, zero_at_lower: int = 0, prec: int = _ISOLATION_PREC) -> list:
    """Every zero of ``f`` in ``(lower, upper]`` as certified balls (complete, none twice).

    ``zero_at_lower``: the known order of a zero at ``lower`` that is not to be reported
    (its neighbourhood is proven free of others, as at the origin in :func:`certify`).
    ``prec``: working bits for the isolation (raise it where ``f`` cancels heavily).

    >>> [b.str(8, radius=False) for b in zeros_in(lambda s: s.sin(), 0, 7, 8, zero_at_lower=1)]
    ['3.1415927', '6.2831853']
    """
    old = flint.ctx.prec
    flint.ctx.prec = prec
    try:
        lo = flint.arb(str(lower))
        start = lo
        if zero_at_lower:
            shifted = lambda s: f(s + lo)        # noqa: E731  (the clearance works at 0)
            start = lo + _origin_clearance(None, shifted, zero_at_lower)
        hi = flint.arb(str(upper))
        if start >= hi:
            return []
        brackets = _find_roots(f, start, hi)
        return [_refine(f, flint.arb((a + b) / 2, (b - a) / 2), digits) for a, b in brackets]
    finally:
        flint.ctx.prec = old
