"""Checks of the torsional (lateral PFM) results, Eqs. 30-35."""
from __future__ import annotations

import mpmath as mp
import sympy as sp

from .. import torsion as T
from ..beam import L
from ..paper import printed as P
from ..roots import certified_roots
from .core import ERRATUM, HOLDS, claim, compare
from ..evidence import Evidence, Math, Tex, say

TIP_TWIST = Tex(r"\Theta_0(L)", "Theta0(L)")


def saint_venant_factor(aspect: mp.mpf, terms: int = 50) -> mp.mpf:
    """J / (w h^3 / 3) for a w x h rectangle (Saint-Venant series; Timoshenko & Goodier, Sec. 109)."""
    s = mp.nsum(lambda j: mp.tanh((2 * j + 1) * mp.pi * aspect / 2) / (2 * j + 1) ** 5, [0, terms])
    return 1 - 192 / (mp.pi**5 * aspect) * s


@claim("eq30.torsion_stiffness", "III.6, Eqs. 30-31",
       Tex(r"c_T = w h^3 G/3;\; \Theta_0'' + \xi^2 \Theta_0 = 0,\; \xi^2 = \rho J \omega^2/c_T",
           "c_T = w h^3 G/3; Theta0'' + xi^2 Theta0 = 0, xi^2 = rho J w^2/c_T"), chapter="torsion")
def _eq30():
    eq = T.frequency_domain_equation()
    theta0 = sp.Function("Theta0")(T.x)
    expected = theta0.diff(T.x, 2) + T.rho * T.J * T.omega**2 / T.c_T * theta0
    ok_eq = sp.simplify(eq - expected) == 0
    factors = {name: saint_venant_factor(mp.mpf(c["w"]) / mp.mpf(c["h"])) for name, c in P.TABLE1.items()}
    thin = saint_venant_factor(mp.mpf(10) ** 6)
    evidence = say("Eq. 30 with ", Tex(r"\Theta = \Theta_0 e^{i \omega t}", "Theta = Theta0 e^(iwt)"), ": ", Math(0, eq),
                   f" ({ok_eq}); Saint-Venant torsion constant / ", Tex(r"(w h^3/3)", "(w h^3/3)"),
                   f" tends to {mp.nstr(thin, 6)} for ", Tex(r"w/h \to \infty", "w/h -> oo"), " (thin strip); for Table 1: "
                   + ", ".join(f"{n} (w/h = {mp.nstr(mp.mpf(P.TABLE1[n]['w']) / mp.mpf(P.TABLE1[n]['h']), 3)}): {mp.nstr(f, 3)}"
                               for n, f in factors.items()))
    ok = ok_eq and abs(thin - 1) < mp.mpf("1e-5")
    return Evidence(HOLDS if ok else ERRATUM, evidence)


@claim("eq33.torsion_elastic", "III.6, Eqs. 32-33", Math(P.torsion_elastic, TIP_TWIST), chapter="torsion")
def _eq33():
    cmp = compare(P.torsion_elastic, T.solve_elastic().tip_twist)
    return Evidence(HOLDS, ratio=cmp) if cmp.is_(1) else Evidence(
        ERRATUM, ratio=cmp, correct=(Math(T.solve_elastic().tip_twist, TIP_TWIST),))


@claim("eq33.limits", "III.6", ("stiff contact: ", Math(P.torsion_stiff_limit, TIP_TWIST), "; ", Tex(r"k_2 \to 0", "k2 -> 0"),
                                 ": ", Math(P.torsion_free_limit, TIP_TWIST)), chapter="torsion")
def _eq33_limits():
    twist = T.solve_elastic().tip_twist
    stiff, free = sp.limit(twist, T.k2t, sp.oo), sp.limit(twist, T.k2t, 0)
    ok = sp.simplify(stiff - P.torsion_stiff_limit) == 0 and sp.simplify(free - P.torsion_free_limit) == 0
    return Evidence(HOLDS if ok else ERRATUM, say("derived: ", Tex(r"\tilde{k}_2 \to \infty", "k2t -> oo"), " gives ", stiff,
                                                  ", ", Tex(r"\tilde{k}_2 \to 0", "k2t -> 0"), " gives ", free))


@claim("eq35.torsion_force", "III.6, Eqs. 34-35", Math(P.torsion_force, TIP_TWIST), chapter="torsion")
def _eq35():
    cmp = compare(P.torsion_force.rewrite(sp.sin), T.solve_force().tip_twist)
    return Evidence(HOLDS, ratio=cmp) if cmp.is_(1) else Evidence(
        ERRATUM, ratio=cmp, correct=(Math(T.solve_force().tip_twist, TIP_TWIST),))


@claim("eq35.roots", "III.6", ("resonances at ", Math(0, sp.cos(T.xi * L)), ", ", Math(P.torsion_force_roots, T.xi)),
       chapter="roots")
def _eq35_roots():
    z = sp.Symbol("z", positive=True)
    char = sp.expand(T.solve_force().denominator.subs(T.xi, z / L) * L)      # in z = xi L
    roots = [r.value for r in certified_roots(char, z, 3, 15)]
    printed = [mp.mpf(str(sp.N(P.torsion_force_roots.subs(P.n, n) * L, 30))) for n in (1, 2, 3)]
    ratios = [p / r for p, r in zip(printed, roots)]
    ok = all(abs(r - 1) < mp.mpf("1e-12") for r in ratios)
    evidence = say("certified zeros of the derived denominator ", char, " in ", Math(T.xi * L, z), ": ",
                   f"{', '.join(mp.nstr(r, 10) for r in roots)}; printed ", Math((2 * P.n - 1) * sp.pi, T.xi * L),
                   f" gives {', '.join(mp.nstr(p, 10) for p in printed)} (ratio {mp.nstr(ratios[0], 6)})")
    xi_n = Tex(r"\xi_n", "xi_n")
    return Evidence(HOLDS if ok else ERRATUM, evidence,
                    correct=() if ok else (Math((2 * P.n - 1) * sp.pi / (2 * L), xi_n),))
