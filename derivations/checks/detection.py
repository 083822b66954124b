"""Checks of the detection point (``x_s = sigma L``): the paper's slope is the ``sigma = 1`` case,
the static blind spot of a pinned tip, and the local force's missing blind spot.

Claims beyond the paper (ids ``spot.*``), discussed in the book chapter ``spot``.
"""
from __future__ import annotations

import sympy as sp

from .. import detection, elastic_contact, free_end, frictionless, indentation, pinned, sliding_friction
from ..beam import d1, f0, k1, k2, q0, x
from ..detection import sigma
from ..paper import printed as P
from ..tilt import kll, kvl, kvv
from ..tip_mass import mu
from ..tip_setback import ATOMS_B, gamma
from ..trig import normal_form
from ..evidence import Evidence, join, say
from .core import ERRATUM, HOLDS, claim, compare

_FAMILIES = {"free_end": (free_end, "Eqs. 21-22"), "pinned": (pinned, "Eqs. 19-20"),
             "elastic_contact": (elastic_contact, "Eqs. 5-10"), "frictionless": (frictionless, "Eq. 23"),
             "sliding_friction": (sliding_friction, "Eqs. 25-26"), "indentation": (indentation, "Eqs. 27-28")}


def _family_at_end(name: str):
    module, equations = _FAMILIES[name]
    sol = module.solve()
    den, slope, _ = detection.family_spot(module.problem)
    rows, ok = [], True
    for drive in slope:
        cmp = compare(sol.theta(drive), (slope[drive] / den).subs(sigma, 1))
        ok = ok and cmp.is_(1)
        rows.append(say(f"per unit {drive}: ", cmp.sentence()))
    return Evidence(HOLDS if ok else ERRATUM,
                    say(f"the slope of the {name} family solved with the spot free, then read at the free end, "
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
    before = detection.solve().before
    at_paper = {gamma: 1, mu: 0, kvv: k1, kll: k2, kvl: 0, sigma: 1}
    b_zero = {ATOMS_B.c: 1, ATOMS_B.s: 0, ATOMS_B.ch: 1, ATOMS_B.sh: 0}
    rows, ok = [], True
    for drive, printed in P.ELASTIC.items():
        derived = detection.to_functions((before.slope[drive] / before.denominator).subs(b_zero)).subs(at_paper)
        cmp = compare(printed / P.N, derived)
        ok = ok and cmp.is_(1)
        rows.append(say(f"per unit {drive}: ", cmp.sentence()))
    return Evidence(HOLDS if ok else ERRATUM,
                    say("the printed A/N (Eqs. 6-10) against the detection solution with spot and tip at the free "
                        "end: ", join(rows, "; ")))


def pinned_static_blind_spot() -> sp.Expr:
    """The static blind spot of a pinned tip, from the dynamic pinned solution at ``beta -> 0``.

    >>> pinned_static_blind_spot()
    15/16 - sqrt(33)/16
    """
    slope = detection.static_slope(pinned.problem, q0)
    roots = [r for r in sp.solve(sp.numer(sp.together(slope)) / sigma, sigma) if 0 < r <= 1]
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
        "the pinned solution read at the spot, in the limit of zero frequency: the slope per unit load is ",
        sp.factor(detection.static_slope(pinned.problem, q0)), ", zero in (0, 1] only at ", sp.Eq(sigma, root),
        f" = {sp.N(root, 12)}; a direct static integration of the propped cantilever gives the slope ",
        slope, " with the same zero"))


@claim("spot.blind_spot.local_force", "III.2, Eqs. 4b, 6, 8 (beyond the paper)",
       "the local tip force f0 has no blind spot of its own: its slope is d1's over k1 at every x_s and frequency",
       chapter="spot")
def _local_force():
    sol = detection.solve()
    rows, ok = [], True
    for name, branch in (("before", sol.before), ("beyond", sol.beyond)):
        diff = normal_form(sp.expand((kvv * branch.slope[f0] - branch.slope[d1]).subs(kvl, 0)), *branch.atoms)
        ok = ok and diff == 0
        rows.append(say(f"with the spot {name} the tip the numerators give ", sp.Eq(sp.Symbol("k_vv N_f0 - N_d1"), diff),
                        " exactly (normal form)"))
    return Evidence(HOLDS if ok else ERRATUM, say(
        "the local force and the spring's pull on the tip enter the shear condition only as one sum (no tilt), so at "
        "every spot and frequency the slope per unit force is the slope per unit surface displacement over k1: ",
        join(rows, "; "), "; where the one vanishes so does the other, so no spot separates them"))
