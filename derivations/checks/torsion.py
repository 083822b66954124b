"""Checks of the torsional (lateral PFM) results, Eqs. 30-35."""
from __future__ import annotations

import mpmath as mp
import sympy as sp

from .. import torsion as T
from ..beam import L
from ..paper import printed as P
from ..roots import certified_roots
from .core import ERRATUM, HOLDS, claim, compare


def saint_venant_factor(aspect: mp.mpf, terms: int = 50) -> mp.mpf:
    """J / (w h^3 / 3) for a w x h rectangle (Saint-Venant series; Timoshenko & Goodier, Sec. 109)."""
    s = mp.nsum(lambda j: mp.tanh((2 * j + 1) * mp.pi * aspect / 2) / (2 * j + 1) ** 5, [0, terms])
    return 1 - 192 / (mp.pi**5 * aspect) * s


@claim("eq30.torsion_stiffness", "III.6, Eqs. 30-31", "c_T = w h^3 G/3; Theta0'' + xi^2 Theta0 = 0, xi^2 = rho J w^2/c_T", chapter="torsion")
def _eq30():
    eq = T.frequency_domain_equation()
    theta0 = sp.Function("Theta0")(T.x)
    expected = theta0.diff(T.x, 2) + T.rho * T.J * T.omega**2 / T.c_T * theta0
    ok_eq = sp.simplify(eq - expected) == 0
    factors = {name: saint_venant_factor(mp.mpf(c["w"]) / mp.mpf(c["h"])) for name, c in P.TABLE1.items()}
    thin = saint_venant_factor(mp.mpf(10) ** 6)
    evidence = (f"Eq. 30 with Theta = Theta0 e^(iwt): {eq} = 0 ({ok_eq}); Saint-Venant torsion constant / (w h^3/3) "
                f"-> {mp.nstr(thin, 6)} for w/h -> oo (thin strip); for Table 1: "
                + ", ".join(f"{n} (w/h = {mp.nstr(mp.mpf(P.TABLE1[n]['w']) / mp.mpf(P.TABLE1[n]['h']), 3)}): {mp.nstr(f, 3)}"
                            for n, f in factors.items()))
    ok = ok_eq and abs(thin - 1) < mp.mpf("1e-5")
    return HOLDS if ok else ERRATUM, evidence, ""


@claim("eq33.torsion_elastic", "III.6, Eqs. 32-33", "Theta0(L) = d3 k2t sin(xi L)/(xi cos(xi L) + H k2t sin(xi L))", chapter="torsion")
def _eq33():
    cmp = compare(P.torsion_elastic, T.solve_elastic().tip_twist)
    return (HOLDS, cmp.summary(), "") if cmp.is_(1) else (ERRATUM, cmp.summary(), sp.sstr(T.solve_elastic().tip_twist))


@claim("eq33.limits", "III.6", "stiff contact: Theta0(L) = d3/H; k2 -> 0: Theta0(L) = 0", chapter="torsion")
def _eq33_limits():
    twist = T.solve_elastic().tip_twist
    stiff, free = sp.limit(twist, T.k2t, sp.oo), sp.limit(twist, T.k2t, 0)
    ok = sp.simplify(stiff - P.torsion_stiff_limit) == 0 and sp.simplify(free - P.torsion_free_limit) == 0
    return HOLDS if ok else ERRATUM, f"derived: k2t -> oo gives {stiff}, k2t -> 0 gives {free}", ""


@claim("eq35.torsion_force", "III.6, Eqs. 34-35", "Theta0(L) = f_lat tan(xi L)/xi", chapter="torsion")
def _eq35():
    cmp = compare(P.torsion_force.rewrite(sp.sin), T.solve_force().tip_twist)
    return (HOLDS, cmp.summary(), "") if cmp.is_(1) else (ERRATUM, cmp.summary(), sp.sstr(T.solve_force().tip_twist))


@claim("eq35.roots", "III.6", "resonances at cos(xi L) = 0, xi = (2n - 1) pi/L", chapter="roots")
def _eq35_roots():
    z = sp.Symbol("z", positive=True)
    char = sp.expand(T.solve_force().denominator.subs(T.xi, z / L) * L)      # in z = xi L
    roots = [r.value for r in certified_roots(char, z, 3, 15)]
    printed = [mp.mpf(str(sp.N(P.torsion_force_roots.subs(P.n, n) * L, 30))) for n in (1, 2, 3)]
    ratios = [p / r for p, r in zip(printed, roots)]
    ok = all(abs(r - 1) < mp.mpf("1e-12") for r in ratios)
    evidence = (f"certified zeros of the derived denominator {char} in z = xi L: "
                f"{', '.join(mp.nstr(r, 10) for r in roots)}; printed xi L = (2n-1) pi gives "
                f"{', '.join(mp.nstr(p, 10) for p in printed)} (ratio {mp.nstr(ratios[0], 6)})")
    return (HOLDS if ok else ERRATUM, evidence, "" if ok else "xi_n = (2n - 1) pi/(2L)")
