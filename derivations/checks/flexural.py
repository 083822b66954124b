"""Checks of the flexural equations: Eqs. 1-10 and 19-29, each against its derivation."""
from __future__ import annotations

import sympy as sp

from .. import (elastic_contact, free_end, frictionless, indentation, pinned,
                sliding_friction)
from ..beam import H, L, beta, d1, d2, f0, k, k1, k2, q0, x
from ..limits import low_frequency, param_limit
from ..paper import printed as P
from ..sliding_friction import f_l
from .core import ERRATUM, HOLDS, claim, compare, describe, same_resonances, sign_flip_verdict
from ..evidence import Evidence, Math, Tex, listing, say

K1_INF, K2_INF = Tex(r"k_1 \to \infty", "k1 -> oo"), Tex(r"k_2 \to \infty", "k2 -> oo")
K1_ZERO, K2_ZERO = Tex(r"k_1 \to 0", "k1 -> 0"), Tex(r"k_2 \to 0", "k2 -> 0")


def _total(sol, drives=None):
    drives = sol.drives if drives is None else drives
    return sum(sol.theta(d) * d for d in drives)


def _equation_verdict(printed, derived, anchors=None, convention=""):
    """holds / sign convention / erratum for a printed expression against its derivation."""
    cmp = compare(printed, derived)
    if cmp.is_(1):
        return Evidence(HOLDS, ratio=cmp)
    correct = (Math(describe(derived)),)
    if cmp.is_(-1):
        verdict, why = sign_flip_verdict(anchors or {}, convention)
        return Evidence(verdict, why, ratio=cmp, correct=correct, sign_convention=True)
    return Evidence(ERRATUM, ratio=cmp, correct=correct)


@claim("eq2.frequency_domain", "III.2, Eqs. 1-2",
       Tex(r"u_0'''' = \kappa^4 u_0 + q_0/EI,\; \kappa^4 = \omega^2 \rho S_c/EI",
           "u0'''' = kappa^4 u0 + q0/EI, kappa^4 = w^2 rho S_c/EI"), chapter="model")
def _eq2():
    E_I, rho, S, w, t = sp.symbols("EI rho S_c omega t", positive=True)
    u0 = sp.Function("u0")
    u = u0(x) * sp.exp(sp.I * w * t)
    eq1 = u.diff(x, 4) + rho * S / E_I * u.diff(t, 2) - q0 * sp.exp(sp.I * w * t) / E_I
    reduced = sp.expand(sp.simplify(eq1 / sp.exp(sp.I * w * t)))
    kap4 = w**2 * rho * S / E_I
    eq2 = u0(x).diff(x, 4) - kap4 * u0(x) - q0 / E_I
    ok = sp.simplify(reduced - eq2) == 0
    return Evidence(HOLDS if ok else ERRATUM,
                    say("Eq. 1 with ", Tex(r"u = u_0 e^{i \omega t}", "u = u0 e^(iwt)"), ", ",
                        Tex(r"q = q_0 e^{i \omega t}", "q = q0 e^(iwt)"), ", divided by ",
                        Tex(r"e^{i \omega t}", "e^(iwt)"), ": ", Math(0, reduced)))


@claim("k.from_beam", "III.2", Tex(r"k = 3EI/L^3 = E w h^3/(4 L^3),\; I = w h^3/12",
                                    "k = 3EI/L^3 = E w h^3/(4 L^3), I = w h^3/12"), chapter="model")
def _k():
    E, I, F, w, h = sp.symbols("E I F w h", positive=True)
    u = sp.Function("u")
    sol = sp.dsolve(u(x).diff(x, 4), u(x)).rhs
    cs = sorted(sol.free_symbols - {x}, key=str)
    bcs = [sol.subs(x, 0), sol.diff(x).subs(x, 0), sol.diff(x, 2).subs(x, L),
           E * I * sol.diff(x, 3).subs(x, L) + F]
    u_tip = sol.subs(sp.solve(bcs, cs, dict=True)[0]).subs(x, L)
    stiffness = sp.simplify(F / u_tip)
    rect = stiffness.subs(I, w * h**3 / 12)
    ok = sp.simplify(stiffness - 3 * E * I / L**3) == 0 and sp.simplify(rect - E * w * h**3 / (4 * L**3)) == 0
    return Evidence(HOLDS if ok else ERRATUM,
                    say("static clamped beam, tip force F: ", Math(u_tip, "u(L)"), ", so ",
                        Math(stiffness, "k = F/u(L)"), " = ", rect, " for ", Tex("I = w h^3/12", "I = w h^3/12")))


@claim("A.from_theta", "III.2", (Tex(r"A = 2 \theta L/3", "A = 2 theta L/3"), " for a purely vertical displacement"),
       chapter="model")
def _a_from_theta():
    sol = free_end.solve()
    ratio = sp.simplify(low_frequency(sol.tip_deflection(f0)) / low_frequency(sol.theta(f0)))
    ok = sp.simplify(ratio - 2 * L / 3) == 0
    return Evidence(HOLDS if ok else ERRATUM,
                    say("static tip-loaded cantilever (the deflection shape of a vertical tip displacement): ",
                        Math(ratio, "u(L)/u'(L)")))


@claim("eq5.general_solution", "III.2, Eqs. 3-5",
       (Tex(r"\theta_{tot} = (A_v d_1 + A_l d_2 + A_e f_0 + A_q q_0)/N",
            "theta_tot = (A_v d1 + A_l d2 + A_e f0 + A_q q0)/N"), " with BCs Eq. 3a,b and 4a,b"), chapter="elastic_contact")
def _eq5():
    printed = sum(P.ELASTIC[d] * d for d in P.ELASTIC) / P.N
    return _equation_verdict(printed, _total(elastic_contact.solve()))


def _elastic_ratio(drive):
    def run():
        return _equation_verdict(P.ELASTIC[drive] / P.N, elastic_contact.solve().theta(drive))
    return run


for _id, _drive, _tex, _txt in [
        ("eq6.Av", d1, r"A_v = 3 \beta^4 k_1 k L \sin\beta \sinh\beta", "A_v = 3 beta^4 k1 k L sin sinh"),
        ("eq7.Al", d2, r"A_l = 3 \beta^2 H k_2 (\ldots)", "A_l = 3 beta^2 H k2 (...)"),
        ("eq8.Ae", f0, r"A_e = 3 \beta^4 k L \sin\beta \sinh\beta", "A_e = 3 beta^4 k L sin sinh"),
        ("eq9.Aq", q0, r"A_q = 3 L^2 (\ldots)", "A_q = 3 L^2 (...)")]:
    claim(_id, f"III.2, Eq. {_id[2]}", (Tex(_tex, _txt), " (compared as ", Tex("A_x/N", "A_x/N"), ")"),
          chapter="elastic_contact")(_elastic_ratio(_drive))


@claim("eq10.N", "III.2, Eq. 10", Tex(r"N = \beta^2 (9 H^2 k_1 k_2 + \beta^4 k^2 L^2 + \ldots)",
                                      "N = beta^2 (9 H^2 k1 k2 + beta^4 k^2 L^2 + ...)"), chapter="elastic_contact")
def _eq10():
    cmp = compare(P.N, elastic_contact.solve().denominator)
    ok, why = same_resonances(P.N, elastic_contact.solve().denominator)
    return Evidence(HOLDS if ok else ERRATUM, say("same zeros as the derived characteristic function (", why, ")"),
                    ratio=cmp, correct=() if ok else (Math(describe(elastic_contact.solve().denominator), "N"),))


@claim("eq6_8.same_shape", "III.2, after Eq. 10", "vertical and local-force contributions share their frequency dependence", chapter="elastic_contact")
def _same_shape():
    t = elastic_contact.transfer()
    ratio = sp.simplify(t[d1] / t[f0])
    return Evidence(HOLDS if not ratio.has(beta) else ERRATUM,
                    say("derived ", Math(ratio, Tex(r"\frac{A_v/N}{A_e/N}", "(A_v/N)/(A_e/N)")), ", independent of ",
                        Tex(r"\beta", "beta")))


@claim("eq10.resonances_independent", "III.2, after Eq. 10",
       "resonances depend only on the cantilever and the contact springs", chapter="elastic_contact")
def _res_independent():
    N = elastic_contact.solve().denominator
    syms = N.free_symbols
    ok = not syms & {d1, d2, f0, q0} and syms <= {beta, k, k1, k2, H, L}
    return Evidence(HOLDS if ok else ERRATUM,
                    say("derived N depends on ", listing(syms), " only (no drive amplitude)"))


@claim("eq19.pinned_limit", "III.3, text before Eq. 19",
       ("the supported end ", Tex(r"u_0(L) = 0,\; u_0''(L) = 0", "u0(L) = 0, u0''(L) = 0"), " is Eq. 5 with ",
        K1_INF, " and ", K2_INF), chapter="pinned")
def _eq19_limit():
    N = elastic_contact.solve().denominator
    both = param_limit(param_limit(N / (k1 * k2), k1, sp.oo), k2, sp.oo)
    k2_zero = param_limit(N.subs(k2, 0) / k1, k1, sp.oo)
    pinned_N = pinned.solve().denominator
    ok, why_printed = same_resonances(both, pinned_N)
    _, why_k2_zero = same_resonances(k2_zero, pinned_N)
    evidence = say(Tex(r"k_1, k_2 \to \infty", "k1, k2 -> oo"), " in the derived N gives ", describe(both),
                   " (clamped-clamped end: the tip slope is fixed at ", Tex("d_2/H", "d2/H"),
                   "), vs the supported-end N: ", why_printed, "; ", K1_INF, " with ", K2_ZERO, " gives ",
                   describe(k2_zero), ", vs the supported-end N: ", why_k2_zero)
    return Evidence(HOLDS if ok else ERRATUM, evidence,
                    correction=() if ok else say("the supported end (Eq. 19) is Eq. 5 with ", K1_INF, " and ", K2_ZERO,
                                                 " (frictionless, stiff contact)"))


@claim("eq20.pinned_response", "III.3, Eqs. 19-20", Math(P.theta_nlc, Tex(r"\theta_{nlc}", "theta_nlc")), chapter="pinned")
def _eq20():
    return _equation_verdict(P.theta_nlc, pinned.solve().theta(q0) * q0)


@claim("eq20.eigenfrequencies", "III.3",
       Tex(r"\omega_n^2 = \frac{EI \beta^4}{\rho S L^4} = \frac{E h^2 \beta^4}{12 \rho L^4} = \frac{k \beta^4}{3m}",
           "w_n^2 = EI b^4/(rho S L^4) = E h^2 b^4/(12 rho L^4) = k b^4/(3m)"), chapter="pinned")
def _eigen():
    E, I, rho, S, w, h, omega = sp.symbols("E I rho S_c w h omega", positive=True)
    # beta = kappa L and kappa^4 = omega^2 rho S / (E I)  (Eq. 2)
    w2 = sp.solve(sp.Eq((beta / L) ** 4, omega**2 * rho * S / (E * I)), omega**2)[0]
    rect = w2.subs({I: w * h**3 / 12, S: w * h})
    kk, m = 3 * E * I / L**3, rho * w * h * L
    forms = [E * I * beta**4 / (rho * S * L**4), E * h**2 * beta**4 / (12 * rho * L**4),
             (kk * beta**4 / (3 * m)).subs(I, w * h**3 / 12)]
    ok = [sp.simplify(w2 - forms[0]) == 0, sp.simplify(rect - forms[1]) == 0, sp.simplify(rect - forms[2]) == 0]
    return Evidence(HOLDS if all(ok) else ERRATUM,
                    say("from ", Tex(r"\kappa^4 = \omega^2 \rho S/EI", "kappa^4 = w^2 rho S/EI"), ", ",
                        Tex(r"\beta = \kappa L", "beta = kappa L"), ": ", Math(w2, omega**2),
                        "; rectangular section and ", Tex(r"k = 3EI/L^3", "k = 3EI/L^3"), ", ",
                        Tex(r"m = \rho w h L", "m = rho w h L"), f" reproduce the three printed forms: {ok}"))


@claim("eq22.free_response", "III.3, Eqs. 21-22", Math(P.theta_f, Tex(r"\theta_f", "theta_f")), chapter="free_end")
def _eq22():
    derived = _total(free_end.solve())
    eq5_free = (P.ELASTIC[f0] * f0 + P.ELASTIC[q0] * q0) / P.N
    eq5_free = eq5_free.subs({k1: 0, k2: 0})
    anchors = {("Eq. 5 at ", Tex("k_1 = k_2 = 0", "k1 = k2 = 0"), " (same tip conditions, Eq. 4b = Eq. 21b)"):
               compare(eq5_free, derived).is_(1),
               "static limit printed below Eq. 22": compare(P.free_static_theta, low_frequency(derived)).is_(1)}
    return _equation_verdict(P.theta_f, derived, anchors, (Tex("f_0", "f0"), " and ", Tex("q_0", "q0"),
                                                           " positive towards the surface"))


@claim("eq22.resonances_independent", "III.3", "free-cantilever resonances do not depend on the ratio of distributed to local force", chapter="free_end")
def _free_independent():
    N = free_end.solve().denominator
    ok = not N.free_symbols & {f0, q0}
    return Evidence(HOLDS if ok else ERRATUM, say("derived denominator ", describe(N), " contains neither ",
                                                  Tex("f_0", "f0"), " nor ", Tex("q_0", "q0")))


@claim("eq23.frictionless", "III.4, Eq. 23a-f",
       (Tex(r"A_v,\ A_l = 0,\ A_e,\ A_q", "A_v, A_l = 0, A_e, A_q"), " and N for ", K2_ZERO, ", with ",
        Math(P.N_frictionless, "N")), chapter="frictionless")
def _eq23():
    sol = frictionless.solve()
    from_elastic = param_limit(elastic_contact.solve().theta(d2), k2, 0)
    # The printed parts share one normalisation; take it from 23a and test every part with it.
    scale = sp.cancel(P.FRICTIONLESS[d1] / sol.slope[d1])
    parts = {"23a": (P.FRICTIONLESS[d1], sol.slope[d1]), "23c": (P.FRICTIONLESS[f0], sol.slope[f0]),
             "23d": (P.FRICTIONLESS[q0], sol.slope[q0]), "23f": (P.N_frictionless, sol.denominator)}
    wrong = [label for label, (pr, der) in parts.items() if not compare(pr, scale * der).is_(1)]
    if not (from_elastic == 0 and P.FRICTIONLESS[d2] == 0):
        wrong.append("23b")
    ratios = {label: compare(P.FRICTIONLESS[d] / P.N_frictionless, sol.theta(d)) for label, d in
              [("23a", d1), ("23c", f0), ("23d", q0)]}
    evidence = say("common scale ", Math(scale, Tex(r"\text{printed}/\text{derived}", "printed/derived")), "; parts that differ at that scale: ",
                   ", ".join(wrong) or "none", "; 23b: ", K2_ZERO, " of the derived ", Math(from_elastic, "A_l/N"),
                   "; A/N ratios: ", [(f"; {lab} " if i else f"{lab} ", c.sentence()) for i, (lab, c) in enumerate(ratios.items())])
    if not wrong:
        return Evidence(HOLDS, evidence)
    return Evidence(ERRATUM, evidence, correct=(Math(describe(scale * sol.denominator), "N"),))


@claim("eq24.frictionless_stiff_contact", "III.4, Eq. 24", (Math(P.theta_p_stiff, Tex(r"\theta_p", "theta_p")), " for ",
                                                           K2_ZERO, ", ", K1_INF), chapter="frictionless")
def _eq24():
    return _equation_verdict(P.theta_p_stiff, _total(frictionless.solve_stiff()))


@claim("eq26.sliding_friction", "III.4, Eqs. 25-26", Math(P.theta_friction, Tex(r"\theta_f", "theta_f")),
       chapter="sliding_friction")
def _eq26():
    return _equation_verdict(P.theta_friction, sliding_friction.solve().theta(f_l) * f_l)


@claim("eq26.resonances_reference", "III.4, after Eq. 26",
       "the resonances of Eq. 26 are like those of the electrostatically driven free cantilever of Eq. (20)", chapter="sliding_friction")
def _eq26_ref():
    fr = sliding_friction.solve().denominator
    free_ok, free_why = same_resonances(fr, free_end.solve().denominator)
    pinned_ok, pinned_why = same_resonances(fr, pinned.solve().denominator)
    evidence = say("sliding friction vs free end (Eq. 22): ", free_why, "; vs supported end (Eq. 20): ", pinned_why)
    if pinned_ok:
        return Evidence(HOLDS, evidence)
    if free_ok:
        return Evidence(ERRATUM, evidence, correction=say(
            "the resonances of Eq. 26 are those of the free cantilever, Eq. (22): ",
            Math(0, describe(free_end.solve().denominator))))
    return Evidence(ERRATUM, evidence, correction="the resonances of Eq. 26 match neither Eq. (20) nor Eq. (22)")


@claim("eq27.indentation_displacement", "III.5, Eq. 27", Math(P.u_indentation, "u(L)"), chapter="indentation")
def _eq27():
    sol = indentation.solve()
    derived = sol.tip_deflection(d1) * d1 + sol.tip_deflection(f0) * f0
    evidence = _equation_verdict(P.u_indentation, derived)
    static = low_frequency(P.u_indentation.subs(f0, 0) / d1)
    return evidence.but(sentence=say(evidence.sentence, "; " if evidence.sentence else "", "printed form at ",
                                     Tex(r"\beta \to 0", "beta -> 0"), " per unit ", Tex("d_1", "d1"), ": ", static,
                                     " (derived: ", low_frequency(sol.tip_deflection(d1)), ")"))


@claim("eq28.indentation_angle", "III.5, Eq. 28", Math(P.theta_indentation, Tex(r"\theta_p", "theta_p")),
       chapter="indentation")
def _eq28():
    return _equation_verdict(P.theta_indentation, _total(indentation.solve()))


@claim("eq29.stiff_contact_dynamic", "III.5, Eq. 29", (Math(P.theta_stiff_dynamic, Tex(r"\theta_f", "theta_f")), " for ",
                                                       K1_INF), chapter="indentation")
def _eq29():
    derived = indentation.solve_stiff().theta(d1) * d1
    as_limit = param_limit(indentation.solve().theta(d1), k1, sp.oo) * d1
    consistent = compare(as_limit, derived).is_(1)
    anchors = {("Eq. 24 at ", Tex("q_0 = 0", "q0 = 0"), " (same limit)"): compare(P.theta_p_stiff.subs(q0, 0), derived).is_(1),
               ("the static limit ", P.stiff_static_theta, " printed in III.5"):
               compare(P.stiff_static_theta, low_frequency(derived)).is_(1)}
    evidence = _equation_verdict(P.theta_stiff_dynamic, derived, anchors, (Tex("d_1", "d1"), " positive towards the beam"))
    return evidence.but(sentence=say(evidence.sentence, "; " if evidence.sentence else "", K1_INF,
                                     " of Eq. 28's derivation equals the ", Tex("u(L) = d_1", "u(L) = d1"),
                                     f" solution: {consistent}"))


@claim("eq28.free_limit_reference", "III.5, after Eq. 29",
       ("for ", K1_ZERO, ", Eq. (28) becomes Eq. (5) for a free cantilever"), chapter="indentation")
def _eq28_free():
    limit = indentation.solve().theta(f0).subs(k1, 0)
    eq5_free = (P.ELASTIC[f0] / P.N).subs({k1: 0, k2: 0})
    eq22_f0 = sp.diff(P.theta_f, f0)
    to_eq5 = compare(eq5_free, limit).is_(1)
    to_eq22 = compare(eq22_f0, limit)
    evidence = say(K1_ZERO, " of the derived Eq. 28 equals printed Eq. 5 with ",
                   Tex(r"k_1 = k_2 = 0,\ q_0 = 0", "k1 = k2 = 0, q0 = 0"), f": {to_eq5}; against printed Eq. 22 "
                   "(the free cantilever's own equation): ", to_eq22.sentence())
    return Evidence(HOLDS if to_eq5 else ERRATUM, evidence, sign_convention=to_eq22.is_(-1))
