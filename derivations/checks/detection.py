"""Checks of the detection point (``x_s = sigma L``): the paper's slope is the ``sigma = 1`` case,
the static blind spot of a pinned tip, and the local force's missing blind spot.

Claims beyond the paper (ids ``spot.*``), discussed in the book chapter ``spot``.  Every lever is
composed of the pieces of :mod:`derivations.pieces` (field matrix, load, tip point, clamp), so no
expanded closed form is needed.
"""
from __future__ import annotations

from functools import lru_cache

import sympy as sp

from .. import elastic_contact, free_end, frictionless, indentation, pinned, sliding_friction
from ..beam import L, beta, d1, f0, k1, k2, q0, x
from ..paper import printed as P
from ..pieces import POINT_DRIVES, clamped_segment_slope, point_jump, s, sigma
from ..tilt import kll, kvl, kvv
from ..tip_mass import mu
from ..evidence import Evidence, join, say
from .core import ERRATUM, HOLDS, claim, compare

_FAMILIES = {"free_end": (free_end, "Eqs. 21-22"), "pinned": (pinned, "Eqs. 19-20"),
             "elastic_contact": (elastic_contact, "Eqs. 5-10"), "frictionless": (frictionless, "Eq. 23"),
             "sliding_friction": (sliding_friction, "Eqs. 25-26"), "indentation": (indentation, "Eqs. 27-28")}


def family_slope(problem) -> tuple[sp.Expr, dict]:
    """A family's one-segment lever from the pieces: ``(denominator, slope)`` in ``s = beta sigma``.

    Its tip conditions take physical derivatives, ``u^(n)(L) = (beta/L)**n z[n]``.

    >>> den, slope = family_slope(pinned.problem)
    >>> sp.limit((slope[q0] / den).subs(s, beta / 2), beta, 0)
    1/(64*k)
    """
    return clamped_segment_slope(lambda z: problem.conditions([(beta / L)**n * z[n] for n in range(4)]),
                                 problem.drives, problem.load)


def _family_at_end(name: str):
    module, equations = _FAMILIES[name]
    sol = module.solve()
    den, slope = family_slope(module.problem)
    rows, ok = [], True
    for drive in slope:
        cmp = compare(sol.theta(drive), (slope[drive] / den).subs(s, beta))
        ok = ok and cmp.is_(1)
        rows.append(say(f"per unit {drive}: ", cmp.sentence()))
    return Evidence(HOLDS if ok else ERRATUM,
                    say(f"the slope of the {name} family as the one-segment system assembled from the pieces (clamp "
                        "state [0, 0, m, v], field matrix, load, its two tip conditions), read at the free end, "
                        f"against its transfer ({equations}): ", join(rows, "; ")))


def _register(name: str):
    equations = _FAMILIES[name][1]
    claim(f"spot.{name}.at_end", f"II and {equations}",
          f"the slope read at x_s = L is the {name} transfer ({equations})", chapter="spot")(
        lambda: _family_at_end(name))


for _name in _FAMILIES:
    _register(_name)


@claim("spot.setback.at_end", "II, Eqs. 5-10", "theta = u0'(L) of Eqs. 5-10 is the detection point x_s = L "
       "of the set-back solution (tip at L, no tip mass, no tilt)", chapter="spot")
def _setback_at_end():
    at_paper = {mu: 0, kvv: k1, kll: k2, kvl: 0}
    J, G = (part.subs(at_paper) for part in point_jump())
    drives = POINT_DRIVES[:3]           # the paper's: d1, d2, f0 (no couple)

    def tip_at_end(z):          # the tip's jump with nothing beyond the end: z_left = J z + G d
        jump = J * sp.Matrix(z[:2]) + G[:, :3] * sp.Matrix(drives)
        return [z[2] - jump[0], z[3] - jump[1]]
    den, slope = clamped_segment_slope(tip_at_end, drives)
    rows, ok = [], True
    for drive, printed in P.ELASTIC.items():
        cmp = compare(printed / P.N, (slope[drive] / den).subs(s, beta))
        ok = ok and cmp.is_(1)
        rows.append(say(f"per unit {drive}: ", cmp.sentence()))
    return Evidence(HOLDS if ok else ERRATUM,
                    say("the printed A/N (Eqs. 6-10) against the lever composed of the pieces with spot and tip at "
                        "the free end (one segment, the tip point's moment and shear jump as its end conditions): ",
                        join(rows, "; ")))


def _static(expr: sp.Expr, order: int = 8) -> sp.Expr:
    """``beta -> 0`` limit of a ratio of entire functions of ``beta``, from their truncated series."""
    num, den = (sp.expand(sp.series(part, beta, 0, order).removeO()) for part in sp.fraction(sp.together(expr)))
    assert num != 0 and den != 0, "series too short"
    return sp.factor(sp.limit(num / den, beta, 0))


@lru_cache(maxsize=None)
def pinned_static_slope() -> sp.Expr:
    """Static (``beta -> 0``) slope at ``sigma L`` of the pinned lever per unit ``q0``, from the pieces.

    >>> pinned_static_slope()
    sigma*(8*sigma**2 - 15*sigma + 6)/(16*k)
    """
    den, slope = family_slope(pinned.problem)
    return _static((slope[q0] / den).subs(s, sigma * beta))


def pinned_static_blind_spot() -> sp.Expr:
    """The static blind spot of a pinned tip, from the dynamic pinned solution at ``beta -> 0``.

    >>> pinned_static_blind_spot()
    15/16 - sqrt(33)/16
    """
    roots = [r for r in sp.solve(sp.numer(sp.together(pinned_static_slope())) / sigma, sigma) if 0 < r <= 1]
    (root,) = roots
    return root


@claim("spot.blind_spot.static_pinned", "II, III.3 (beyond the paper)",
       "a pinned tip (Eq. 19) at low frequency: the uniform load q0 gives no slope at x_s = (15 - sqrt(33)) L/16",
       chapter="spot")
def _static_pinned():
    root = pinned_static_blind_spot()
    # Independent route: integrate EI u'''' = q0 four times with u(0) = u'(0) = u(L) = u''(L) = 0.
    c = sp.symbols("c0:4")
    L_, EI = sp.symbols("L EI", positive=True)
    u = q0 * x**4 / (24 * EI) + sum(ci * x**i for i, ci in enumerate(c))
    consts = sp.solve([u.subs(x, 0), u.diff(x).subs(x, 0), u.subs(x, L_), u.diff(x, 2).subs(x, L_)], c)
    slope = sp.factor(u.diff(x).subs(consts).subs(x, sigma * L_))
    direct = [r for r in sp.solve(slope, sigma) if r.is_positive and r <= 1]
    ok = direct == [root] and sp.simplify(root - (15 - sp.sqrt(33)) / 16) == 0
    return Evidence(HOLDS if ok else ERRATUM, say(
        "the pinned lever composed of the pieces read at the spot, in the limit of zero frequency (series in beta): "
        "the slope per unit load is ", pinned_static_slope(), ", zero in (0, 1] only at ", sp.Eq(sigma, root),
        f" = {sp.N(root, 12)}; a direct static integration of the propped cantilever gives the slope ",
        slope, " with the same zero"))


@claim("spot.blind_spot.local_force", "III.2, Eqs. 4b, 6, 8 (beyond the paper)",
       "the local tip force f0 has no blind spot of its own: its slope is d1's over k1 at every x_s and frequency",
       chapter="spot")
def _local_force():
    J, G = (part.subs(kvl, 0) for part in point_jump())
    column = {d: G[:, i] for i, d in enumerate(POINT_DRIVES)}
    g_diff = sp.simplify(column[d1] - kvv * column[f0])
    drives_free = not (J.free_symbols & set(POINT_DRIVES))
    ok = g_diff.is_zero_matrix is True and drives_free
    return Evidence(HOLDS if ok else ERRATUM, say(
        "the local force and the spring's pull on the tip enter the composed lever only through the tip point's "
        "jump G [d1, d2, f0] (the right-hand side; the jump's matrix J holds ", "no drive" if drives_free else "a drive", "), and with "
        "no tilt its columns satisfy ", sp.Eq(sp.Symbol("G_d1 - k_vv G_f0"), sp.Tuple(*g_diff)), "; the lever "
        "(clamp, segments, tip point, free end) is one linear system in that right-hand side, so at every spot and "
        "frequency the slope per unit force is the slope per unit surface displacement over k1, and where the one "
        "vanishes so does the other: no spot separates them"))
