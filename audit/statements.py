"""Qualitative statements of the paper's text, each decided by the derivations where they can be.

A statement is a sentence of the running text that asserts a trend, a dependence or its
absence, an order ("respectively"), a proportionality, a limit or a coincidence (see
:data:`TRIGGERS`).  Ids ``text.<section>.<n>`` number them in order within a section.

Each statement a derivation can decide has a decider in :data:`DECIDERS`, found by a phrase of
the sentence: either a computation here, or the check of a registry claim that states the same
thing (its verdict is then this statement's too).  Statements no derivation decides (mostly
observations of measured data) get ``undecidable`` with the reason.

The module stays whole past 450 lines because :data:`DECIDERS` is one table of (section, phrase,
decider) rows, in an order that matters: a sentence takes the first row that matches it.
"""
from __future__ import annotations

import re
from collections import Counter
from functools import lru_cache
from typing import Callable

import mpmath as mp
import sympy as sp

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS, UNDECIDABLE, claim, result
from pfmdyn.derivations.evidence import Evidence, Math, Tex, join, listing, say
from pfmdyn.derivations.paper import printed as P
from . import text as T
from . import wording as W
from .restated import same_as

CHAPTER = "audit"

TRIGGERS = re.compile(
    r"respectively|independent|does not (?:increase|decrease|depend|change|affect)|increases? with|"
    r"decreases? with|decays?|proportional|\bscales?\b|higher power|frequency dependen|bias dependen|"
    r"(?:depends?|determined) (?:only|solely)|solely|times (?:larger|smaller|the)|less pronounced|coincide|"
    r"identical|additive|linear in|limiting case|cannot be (?:separated|distinguished)|\bequal\b|"
    r"inversely|does not change|changes by 180", re.I)


# --- deciders computed here -----------------------------------------------------------------------

K2_ZERO, K2_INF = Tex(r"k_2 \to 0", "k2 -> 0"), Tex(r"k_2 \to \infty", "k2 -> oo")


def _sections_lateral_stiffness():
    from pfmdyn.derivations import elastic_contact, indentation
    from pfmdyn.derivations.beam import d1, k2
    from pfmdyn.derivations.checks.core import compare
    from pfmdyn.derivations.limits import param_limit
    nano = indentation.solve().theta(d1)
    general = elastic_contact.solve().theta(d1)
    zero = compare(param_limit(general, k2, 0), nano).is_(1)
    infinite_expr = param_limit(general, k2, sp.oo)
    infinite = infinite_expr != 0 and compare(infinite_expr, nano).is_(1)
    evidence = say("the derived nanoindentation slope (Section III.5) per unit ", Tex("d_1", "d1"),
                   " equals the general solution at ", K2_ZERO, f": {zero}; at ", K2_INF, f": {infinite} (", K2_INF,
                   " gives ", sp.factor(infinite_expr), "); Section III.5 neglects the lateral coupling (its own words: '",
                   Tex("k_2", "k2"), " neglected', stiff cantilever)")
    if zero and not infinite:
        return Evidence(ERRATUM, evidence, correction=say(
            "Sections III.4 and III.5 both have zero lateral stiffness (", K2_ZERO, "); III.5 adds ", Tex("k_1", "k1"),
            " finite with the distributed force ignored"))
    return Evidence(HOLDS, evidence)


def _torsion_crossover():
    from pfmdyn.derivations import torsion as Tor
    from pfmdyn.derivations.beam import H, L
    den = sp.denom(sp.together(Tor.solve_elastic().tip_twist))
    K, x = sp.symbols("K x", positive=True)
    # Dimensionless: xi L = x, H k2t L = K (the normalised contact stiffness of Fig. 5c).
    scaled = sp.simplify(den.subs(Tor.xi, x / L).subs(Tor.k2t, K / (H * L)) * L)
    rows = []
    for n in (1, 2, 3):
        mid = (n - sp.Rational(1, 4)) * sp.pi     # halfway from the free root (n-1/2)pi to the pinned root n pi
        Kn = sp.solve(sp.Eq(scaled.subs(x, mid), 0), K)
        rows.append(sp.nsimplify(Kn[0]) if Kn else None)
    increasing = all(a is not None and b is not None and b > a for a, b in zip(rows, rows[1:]))
    n = sp.Symbol("n")
    evidence = say("derived torsional characteristic function (Eq. 33 denominator) ", Math(0, scaled), " with ",
                   Math(Tor.xi * L, x), ", ", Math(H * Tor.k2t * L, K), ": mode n moves from the free root ",
                   (n - sp.Rational(1, 2)) * sp.pi, " to the pinned root ", n * sp.pi, " as K grows; it is halfway at ",
                   listing([r for r in rows if r is not None]), " for n = 1, 2, 3")
    if increasing:
        return Evidence(ERRATUM, evidence, correction=say("the cross-over stiffness increases with mode number, ",
                                                          Math((n - sp.Rational(1, 4)) * sp.pi, Tex("K_n", "K_n"))))
    return Evidence(HOLDS, evidence)


def _scaling_order(which: str):
    def decide():
        ids = ("eq15.scaling", "eq16.scaling", "eq17.scaling", "eq18.scaling")
        verdicts = [result(i) for i in ids]
        exps = {str(k): v for k, v in P.HIGH_FREQUENCY_EXPONENT.items()}
        ok_all = all(v.verdict == HOLDS for v in verdicts)
        if which == "nonlocal_fastest":
            ok = ok_all and exps["q0"] < min(e for s, e in exps.items() if s != "q0")
        elif which == "longitudinal_slowest":
            ok = ok_all and exps["d2"] > max(e for s, e in exps.items() if s != "d2")
        else:  # all decrease
            ok = ok_all and all(e < 0 for e in exps.values())
        labels = {"d1": "A_v/N", "d2": "A_l/N", "f0": "A_e/N", "q0": "A_q/N"}
        evidence = say(f"high-frequency exponents of |A_x/N| in omega, each confirmed by the derivation "
                       f"({', '.join(v.id + ' ' + str(v.verdict) for v in verdicts)}): ",
                       join([(Tex(rf"{labels[d]} \sim \omega^{{{sp.latex(e)}}}", f"{labels[d]} ~ omega^{e}"),)
                             for d, e in exps.items()], ", "))
        return Evidence(HOLDS if ok else ERRATUM, evidence)
    return decide


def _nonlocal_vs_k():
    from pfmdyn.derivations import indentation
    from pfmdyn.derivations.beam import L, d1, k, k1
    from pfmdyn.derivations.checks.electrostatics import nonlocal_height
    from pfmdyn.derivations.limits import low_frequency
    a_nl = nonlocal_height()
    inverse = sp.simplify(sp.diff(a_nl * k, k)) == 0
    em = sp.simplify(2 * L / 3 * low_frequency(indentation.solve().theta(d1)))
    em_limit = sp.limit(em, k1, sp.oo)
    evidence = say("derived ", Math(a_nl, Tex("A_{nl}", "A_nl")), " (", Tex(r"k A_{nl}", "k A_nl"),
                   f" independent of k: {inverse}); electromechanical height per unit ", Tex("d_1", "d1"),
                   " at low frequency = ", em, ", tending to ", em_limit, " for ", Tex(r"k_1 \gg k", "k1 >> k"),
                   " (spring-constant independent in that limit)")
    return Evidence(HOLDS if inverse and em_limit == 1 else ERRATUM, evidence)


def _phase_flip_at_lines():
    from pfmdyn.derivations import elastic_contact
    sol = elastic_contact.solve()
    real = all(not e.has(sp.I) for e in list(sol.slope.values()) + [sol.denominator])
    return Evidence(HOLDS if real else UNDECIDABLE, say(
        "without damping the derived transfer functions are real for real ", Tex(r"\beta", "beta"),
        f" (no i in slope or denominator: {real}): the response changes sign, i.e. the phase jumps by 180 deg, at "
        "every simple zero (antiresonance) and pole (resonance)"))


def _linear_in_bias():
    from pfmdyn.derivations.checks.electrostatics import q0_first_harmonic
    q = q0_first_harmonic()
    lin = sp.diff(q, P.dV, 2) == 0 and sp.diff(q, P.dV) != 0
    return Evidence(HOLDS if lin else ERRATUM, say(
        "first harmonic of the capacitive force per length ", Math(q, Tex("q_0", "q0")), ": linear in ",
        Tex(r"\Delta V", "dV"), f" ({lin}); it vanishes at ", Tex(r"\Delta V = 0", "dV = 0"),
        "; so the non-local (and, for the tip, the local) electrostatic term is linear in the bias"))


def _zeros_bias_dependent():
    from pfmdyn.derivations import elastic_contact
    from pfmdyn.derivations.beam import d1, q0
    from pfmdyn.derivations.checks.electrostatics import q0_first_harmonic
    sol = elastic_contact.solve()
    numerator = sol.slope[d1] * d1 + sol.slope[q0] * q0_first_harmonic().subs(P.S_area, sp.Symbol("S"))
    depends = numerator.has(P.dV)
    return Evidence(HOLDS if depends else ERRATUM, say(
        "the response vanishes where ", Tex(r"A_v d_1 + A_q q_0 = 0", "A_v d1 + A_q q0 = 0"), " with ", Tex("q_0", "q0"),
        " proportional to ", Tex(r"\Delta V", "dV"), "; that numerator contains ", Tex(r"\Delta V", "dV"),
        f" ({depends}) while the resonant denominator N does not: zeros move with bias, poles do not"))


def _domains(case: str):
    def decide():
        d, e, psi = sp.symbols("d e psi", positive=True)
        plus, minus = d + e * sp.exp(sp.I * psi), -d + e * sp.exp(sp.I * psi)
        if case == "low_frequency":
            pp, mm = plus.subs(psi, 0), minus.subs(psi, 0)
            args = {sp.arg(pp.subs({d: 2, e: 1})) - sp.arg(mm.subs({d: 2, e: 1})),
                    sp.arg(pp.subs({d: 1, e: 2})) - sp.arg(mm.subs({d: 1, e: 2}))}
            ok = args <= {sp.pi, -sp.pi, 0}
            return Evidence(HOLDS if ok else ERRATUM, say(
                "with ", Tex(r"\psi = 0", "psi = 0"), " (no dynamic phase) ", Tex(r"PR_\pm = \pm d_{eff} + d_{el}",
                                                                               "PR+- = +-d_eff + d_el"),
                " are real: phase difference ", listing(args), " for ", Tex(r"d_{eff} > d_{el}", "d_eff > d_el"), " and ",
                Tex(r"d_{eff} < d_{el}", "d_eff < d_el")))
        if case == "pure_em":
            pp, mm = plus.subs(e, 0), minus.subs(e, 0)
            ok = sp.Abs(pp) == sp.Abs(mm) and sp.simplify(sp.arg(pp) - sp.arg(mm)) in (sp.pi, -sp.pi)
            return Evidence(HOLDS if ok else ERRATUM, say(
                Tex(r"G_{elec} = 0", "G_elec = 0"), ": ", Math(pp, "PR_+"), ", ", Math(mm, "PR_-"),
                ": equal amplitudes, phases 180 deg apart"))
        if case == "weak_el":
            f = sp.lambdify((d, e, psi), (sp.Abs(plus), sp.Abs(minus), sp.arg(plus) - sp.arg(minus)), "mpmath")
            ap, am, dphi = f(mp.mpf(1), mp.mpf("0.1"), mp.mpf("0.7"))
            ok = ap != am and abs(abs(dphi) - mp.pi) > 0
            return Evidence(HOLDS if ok else ERRATUM, say(
                Tex(r"d_{el}/d_{eff} = 0.1,\ \psi = 0.7", "d_el/d_eff = 0.1, psi = 0.7"), ": ",
                Tex(rf"|PR_+| = {mp.nstr(abs(ap), 5)}", f"|PR+| = {mp.nstr(abs(ap), 5)}"), " differs from ",
                Tex(rf"|PR_-| = {mp.nstr(abs(am), 5)}", f"|PR-| = {mp.nstr(abs(am), 5)}"),
                f"; phase difference {mp.nstr(abs(dphi), 6)} rad, below ", Tex(r"\pi", "pi")))
        # strong electrostatic contribution: e >> d
        vals = {d: mp.mpf("0.01"), e: mp.mpf(1), psi: mp.mpf("0.7")}
        f = sp.lambdify((d, e, psi), (sp.Abs(plus), sp.Abs(minus), sp.arg(plus) - sp.arg(minus)), "mpmath")
        ap, am, dphi = f(*vals.values())
        ok = abs(dphi) < 0.05 and ap != am
        return Evidence(HOLDS if ok else ERRATUM, say(
            Tex(r"d_{el}/d_{eff} = 100,\ \psi = 0.7", "d_el/d_eff = 100, psi = 0.7"), ": ",
            Tex(rf"|PR_+| = {mp.nstr(abs(ap), 5)}", f"|PR+| = {mp.nstr(abs(ap), 5)}"), ", ",
            Tex(rf"|PR_-| = {mp.nstr(abs(am), 5)}", f"|PR-| = {mp.nstr(abs(am), 5)}"),
            f" (larger on one domain), phase difference {mp.nstr(abs(dphi), 3)} rad (small)"))
    return decide


def _null_bias(case: str):
    def decide():
        d, G, V, Vs = sp.symbols("d_eff G_elec V_dc V_surf")
        nulls = [sp.solve(sign * d + G * (V - Vs), V)[0] for sign in (1, -1)]
        pr = Tex(r"PR_\pm = \pm d_{eff} + G_{elec} (V_{dc} - V_{surf})", "PR+- = +-d_eff + G_elec (V_dc - V_surf)")
        if case == "formula":
            ok = {sp.simplify(n - Vs) for n in nulls} == {d / G, -d / G}
            return Evidence(HOLDS if ok else ERRATUM, say(pr, " vanishes at ", Math(nulls[0], V), " and ", nulls[1]))
        if case == "limits":
            ok = all(n.subs(d, 0) == Vs for n in nulls)
            return Evidence(HOLDS if ok else ERRATUM, say(
                Math(nulls[0], Tex(r"V_{null}", "V_null")), ": equals ", Vs, " when ", Math(0, d), "; with ", Math(0, G),
                " the response is bias independent and has no zero"))
        # V_null is itself a bias: it can depend on frequency (through d_eff, G_elec), not on the bias.
        has_bias = nulls[0].has(V)
        return Evidence(ERRATUM if not has_bias else HOLDS, say(
            Math(nulls[0], Tex(r"V_{null}(\omega)", "V_null(omega)")), " (", listing([d, G]),
            " frequency dependent) contains no ", V, ": the nulling bias is a function of frequency; 'bias dependent' "
            "cannot describe it (the figures vary frequency)"), correction=say(
            Tex("V_{null}", "V_null"), " is strongly frequency dependent for a good tip, and virtually frequency "
            "independent for a deteriorated one"))
    return decide


def _null_frequency_dependent():
    from pfmdyn.derivations import elastic_contact
    from pfmdyn.derivations.beam import beta, d1, q0
    sol = elastic_contact.solve()
    ratio = sp.cancel(sol.slope[d1] / sol.slope[q0])
    dep = ratio.has(beta)
    return Evidence(HOLDS if dep else ERRATUM, say(
        Tex(r"V_{null} - V_{surf}", "V_null - V_surf"), " is proportional to ",
        Tex(r"A_v d_1/(A_q q_0 \text{ per volt})", "A_v d1/(A_q q0 per volt)"), "; the derived ", Tex("A_v/A_q", "A_v/A_q"),
        " depends on ", Tex(r"\beta", "beta"), f" ({dep}): a piezoelectric sample has a frequency-dependent nulling bias, "
        "a non-piezoelectric one (", Tex("d_1 = 0", "d1 = 0"), ") does not"))


def _noncontact_resonances_sample_free():
    from pfmdyn.derivations import free_end
    syms = free_end.solve().denominator.free_symbols
    ok = not {str(x) for x in syms} & {"k1", "k2"}
    return Evidence(HOLDS if ok else ERRATUM, say(
        "the derived free-end characteristic function depends on ", listing(syms), " only: no sample property enters "
        "the non-contact resonances"))


def _same_denominator_for_vertical_and_longitudinal():
    from pfmdyn.derivations import elastic_contact
    from pfmdyn.derivations.beam import d1, d2
    from pfmdyn.derivations.checks.core import same_resonances
    sol = elastic_contact.solve()
    same, why = same_resonances(sp.denom(sp.cancel(sol.theta(d1))), sp.denom(sp.cancel(sol.theta(d2))))
    evidence = say("the derived vertical and longitudinal responses ", Tex("A_v/N", "A_v/N"), " and ", Tex("A_l/N", "A_l/N"),
                   " have the same resonances (", why, "), as Section III.2 itself says; a choice of frequency cannot "
                   "separate them")
    if same:
        return Evidence(ERRATUM, evidence, correction=(
            "the vertical and longitudinal contributions share their resonances (one denominator N) and cannot be "
            "separated by the choice of frequency; the torsional (lateral) resonances differ"))
    return Evidence(HOLDS, evidence)


def _torsion_vs_flexure_resonances():
    from pfmdyn.derivations import torsion as Tor
    b = sp.denom(sp.together(Tor.solve_elastic().tip_twist))
    return Evidence(HOLDS, say("flexural characteristic function in ", Tex(r"\beta", "beta"), " (Eq. 10) and torsional one "
                               "in ", Tex(r"\xi L", "xi L"), " (", b, ") are different functions: different resonances"))


def _longitudinal_more_sensitive():
    from pfmdyn.derivations import elastic_contact
    from pfmdyn.derivations.beam import H, L, d1, d2, k1, k2
    from pfmdyn.derivations.limits import low_frequency, param_limit
    sol = elastic_contact.solve()
    vertical = param_limit(param_limit(low_frequency(sol.theta(d1)).subs(k2, 0), k1, sp.oo), k1, sp.oo)
    longitudinal = param_limit(param_limit(low_frequency(sol.theta(d2)), k2, sp.oo), k1, sp.oo)
    ratio = sp.simplify(longitudinal / vertical)
    return Evidence(HOLDS if ratio.has(L) and ratio.has(H) else ERRATUM, say(
        "static slope per unit displacement: vertical (stiff contact, free to slide) ", vertical, ", longitudinal "
        "(no slip) ", longitudinal, "; ratio ", ratio, ": larger than 1 whenever ", Math(2 * L / 3, H, "<")))


def _length_sensitive():
    from pfmdyn.derivations.beam import L, d1, d2
    ratio = sp.simplify(P.LOW_FREQUENCY[d2][0] / P.LOW_FREQUENCY[d1][0])
    return Evidence(HOLDS if ratio.has(L) or P.LOW_FREQUENCY[d1][0].has(L) else ERRATUM, say(
        "the low-frequency responses (Eqs. 11-14, confirmed by eq11-14 checks) contain L; e.g. ",
        Math(P.LOW_FREQUENCY[d1][0], "A_v/N")))


def _additive():
    from pfmdyn.derivations import elastic_contact
    sol = elastic_contact.solve()
    total = sum(sol.theta(dr) * dr for dr in sol.drives)
    linear = all(sp.diff(total, a, b) == 0 for a in sol.drives for b in sol.drives)
    return Evidence(HOLDS if linear else ERRATUM, say(
        "Eq. 2 and its boundary conditions are linear in the drives: the derived response is the sum of one term per "
        "drive ", listing(sol.drives), f" (all second derivatives in the drives vanish: {linear})"))


def _torsion_depends_on_k2():
    from pfmdyn.derivations import torsion as Tor
    den = sp.denom(sp.together(Tor.solve_elastic().tip_twist))
    return Evidence(HOLDS if den.has(Tor.k2t) else ERRATUM, say(
        "derived denominator of the torsional response: ", den, " (contains ",
        Tex(r"\tilde{k}_2 = H k_2/c_T", "k2t = H k2/c_T"), ")"))


def _frictionless_from_4a():
    from pfmdyn.derivations.beam import H, d2, k2
    U1 = sp.Symbol("U1")
    moment = k2 * H * (d2 - U1 * H)
    return Evidence(HOLDS if sp.limit(moment, k2, 0) == 0 else ERRATUM, say(
        "Eq. 4a: ", Math(moment, Tex("EI u_0''(L)", "EI u0''(L)")), " tends to 0 as ", K2_ZERO, ", i.e. ",
        Tex("u_0''(L) = 0", "u0''(L) = 0")))


def _symbol_verdict(symbol: str) -> Callable:
    """Decide a sentence by the audit of a symbol it defines."""
    def decide():
        from .xref_symbols import check_symbol
        evidence = check_symbol(symbol)
        return evidence.but(sentence=say("the symbol audit of ", Tex(symbol), ": ", evidence.sentence))
    return decide


DECIDERS: list[tuple[str, str, Callable]] = [
    # (section tag, phrase of the sentence, decider)
    ("II", r"tip deflection is equal to surface displacement", same_as("contact.low_frequency_transfer")),
    ("II", r"more sensitive to the longitudinal", _longitudinal_more_sensitive),
    ("II", r"purely electromechanical response, the piezoresponse amplitude is equal", _domains("pure_em")),
    ("II", r"vary linearly with the tip-surface potential", _linear_in_bias),
    ("II", r"A = A_\{el\} \+ A_\{piezo\} \+ A_\{nl\}", _additive),
    ("II", r"no slip condition", _longitudinal_more_sensitive),
    ("II", r"non-local contribution can be well-approximated as being position independent", _symbol_verdict("A_{el}")),
    ("III1", r"relatively weak", W.stiffness_ratio),
    ("III2", r"describe the frequency dependence of the PFM signal", W.order_of_ratios),
    ("IV1", r"capacitive force can be approximated", same_as("eq36.q0")),
    ("III", r"Sections III\.4 and III\.5", _sections_lateral_stiffness),
    ("III", r"torsional and vertical oscillations\) are generally different", _torsion_vs_flexure_resonances),
    ("III1", r"tip deflection is almost equal", same_as("contact.low_frequency_transfer")),
    ("III1", r"ratio between the two is determined only by the Poisson", same_as("contact.lateral_to_vertical_ratio")),
    ("III2", r"providing purely electromechanical and purely electrostatic", W.limiting_cases_order),
    ("III2", r"similar frequency dependences", same_as("eq6_8.same_shape")),
    ("III2", r"resonance structure in Eq\. \(5\) is determined only", same_as("eq10.resonances_independent")),
    ("III2", r"roots of Eq\. \(10\) are independent", same_as("eq10.resonances_independent")),
    ("III2", r"cannot be separated by a proper choice", same_as("eq10.resonances_independent")),
    ("III2", r"sensitive to the length of the cantilever", _length_sensitive),
    ("III2", r"all four contributions decrease", _scaling_order("all_decrease")),
    ("III2", r"higher power of frequency", _scaling_order("nonlocal_fastest")),
    ("III2", r"scale in a similar manner", same_as("eq15_18.piezo_to_local_ratio")),
    ("III2", r"less pronounced for the longitudinal", _scaling_order("longitudinal_slowest")),
    ("III2", r"cantilever with a high spring constant", W.stiff_cantilever_vs_k1),
    ("III2", r"contributions to the PFM are additive", _additive),
    ("III2", r"cannot be distinguished by a choice of the operating frequency", same_as("eq15_18.piezo_to_local_ratio")),
    ("III3", r"8 times larger", W.eight_times),
    ("III3", r"4\.4 times", same_as("eq22.contact_to_free_ratio")),
    ("III3", r"independent of the ratio between the distributed", same_as("eq22.resonances_independent")),
    ("III4", r"changing the boundary condition given in Eq\. \(4a\)", _frictionless_from_4a),
    ("III4", r"resonances are similar to that of a free cantilever", same_as("eq26.resonances_reference")),
    ("III5", r"independent of the cantilever length", same_as("eq28.nonpiezo_contact_static")),
    ("III5", r"measured signal is equal to surface displacement", same_as("eq28.stiff_contact_static")),
    ("III5", r"resonant frequencies for the cantilever increase", same_as("eq28.resonances_increase_with_k1")),
    ("III5", r"Eq\. \(28\) becomes Eq\. \(5\)", same_as("eq28.free_limit_reference")),
    ("III6", r"depend on the stiffness constant", _torsion_depends_on_k2),
    ("III6", r"does not increase with the mode number", _torsion_crossover),
    ("III6", r"infinitely stiff contact", same_as("eq33.limits")),
    ("IV1", r"inversely proportional to the cantilever spring constant", _nonlocal_vs_k),
    ("IV1", r"non-local interactions are formally absent", _linear_in_bias),
    ("IV", r"dynamics of the cantilever is analyzed in Section IV\.2", W.where_it_is("IV", r"analyzed in Section IV\.2")),
    ("IV2", r"contributions is given in Section II\b", W.where_it_is("IV2", r"is given in Section II\b")),
    ("IV2", r"phase changes by 180° across resonance", _phase_flip_at_lines),
    ("IV2", r"independent of \$\\Delta V\$", _linear_in_bias),
    ("IV2", r"linear in \$\\Delta V\$", _linear_in_bias),
    ("IV2", r"position of the resonances is determined solely", same_as("eq10.resonances_independent")),
    ("IV2", r"zeroes on the response diagram are strongly bias dependent", _zeros_bias_dependent),
    ("IV2", r"scales proportionally to the cantilever spring constant", same_as("fig6.crossover_scales_with_k")),
    ("IV2", r"relative contribution of the electromechanical contrast increases", same_as("fig6.high_frequency_em")),
    ("IV2", r"resonances do not affect the relative", same_as("fig6.resonances_keep_ratio")),
    ("IV2", r"boundary between the local electrostatic and\s+electromechanical", same_as("fig7.local_boundary_frequency_independent")),
    ("IV2", r"frequency independent ratio between local", same_as("fig7.local_boundary_frequency_independent")),
    ("IV3", r"always 180° or 0°", _domains("low_frequency")),
    ("IV3", r"response amplitudes are equal in", _domains("pure_em")),
    ("IV3", r"purely electromechanical case, \$G_\{elec\}\$ is identically zero", _domains("pure_em")),
    ("IV3", r"strong electrostatic contribution, the phase changes weakly", _domains("strong_el")),
    ("IV3", r"small non-local electrostatic contribution", _domains("weak_el")),
    ("IV3", r"limit of a small piezoelectric contribution", same_as("eq40.small_piezo")),
    ("V", r"linear in the tip-surface potential difference", _linear_in_bias),
    ("VI1", r"checkerboard", _phase_flip_at_lines),
    ("VI1", r"Similarly to tip 1, the nulling bias is frequency independent", W.tip1_null_consistency),
    ("V", r"Co-Cr coated tips", W.nominal_resonance),
    ("VI4", r"greatest for PZT grain", W.fig15_grains),
    ("VI1", r"summarized in Fig\. 11a", W.where_it_is("VI1", r"summarized in Fig\. 11a")),
    ("VI4", r"Shown in Fig\. 14 are the bias", W.where_it_is("VI4", r"Shown in Fig\. 14 are the bias")),
    ("VI4", r"shown in Fig\. 15 a,b", W.where_it_is("VI4", r"shown in Fig\. 15 a,b")),
    ("VI4", r"Fig\. 15 c reveals", W.where_it_is("VI4", r"Fig\. 15 c reveals")),
    ("VI4", r"Also shown in Fig\. 15 d", W.where_it_is("VI4", r"Also shown in Fig\. 15 d")),
    ("III4", r"corresponds to frictionless contact", _frictionless_from_4a),
    ("VI1", r"non-contact mode are identical to that for", _noncontact_resonances_sample_free),
    ("VI1", r"nulling bias is now strongly frequency dependent", _null_frequency_dependent),
    ("VI2", r"nulling bias is \$V_\{null\}", _null_bias("formula")),
    ("VI2", r"nulling bias is equal to the surface potential", _null_bias("limits")),
    ("VI2", r"there is no nulling bias", _null_bias("limits")),
    ("VI2", r"close to nulling potential, the phase changes by 180", _domains("pure_em")),
    ("VI2", r"opposite for these two grains", _null_bias("formula")),
    ("VI3", r"virtually bias independent", _null_bias("bias")),
    ("VI1", r"frequency independent nulling bias is", _null_bias("limits")),
    ("VI3", r"strongly bias dependent for a good tip", _null_bias("bias")),
    ("VI4", r"coincide for a given sample", same_as("eq10.resonances_independent")),
    ("VI4", r"resonant frequencies of a cantilever in contact with the surface are identical",
     same_as("eq28.resonances_increase_with_k1")),
    ("VI4", r"determined unambiguously", same_as("eq41.deconvolution")),
    ("VI4", r"provides a more rigorous approach provided that the surface potential", same_as("eq41.deconvolution")),
    ("VI3", r"frequency dependence of the nulling bias, \$V_\{null\}\(\\omega\)\$, provides information",
     _null_bias("formula")),
    ("conclusions", r"frequency dependence of the nulling bias provides information", _null_bias("formula")),
    ("conclusions", r"determined solely by the cantilever spring constant", same_as("eq10.resonances_independent")),
    ("conclusions", r"decays faster with frequency", _scaling_order("nonlocal_fastest")),
    ("conclusions", r"are additive", _additive),
    ("conclusions", r"does not change significantly at the resonances", same_as("fig6.resonances_keep_ratio")),
    ("conclusions", r"electromechanical and local electrostatic contributions is frequency independent",
     same_as("eq15_18.piezo_to_local_ratio")),
    ("conclusions", r"vertical and longitudinal vibration modes are generally different",
     _same_denominator_for_vertical_and_longitudinal),
    ("conclusions", r"determined unambiguously as the slope", same_as("eq41.deconvolution")),
]


def _undecided(sec: str, sentence: str):
    measured = sec.startswith("VI") or sec in ("V",) or re.search(r"experiment|measured|observed|Fig\.", sentence)
    why = ("an observation of measured data; the model does not decide it" if measured else
           "a qualitative or methodological remark that no derivation in pfmdyn decides")
    return Evidence(UNDECIDABLE, why)


@lru_cache(maxsize=1)
def statements() -> tuple[tuple[str, str, str, Callable], ...]:
    """(id, section number, sentence, decider) for every extracted statement."""
    out, counters, used = [], Counter(), set()
    for sec in T.text_sections():
        if sec.tag in ("abstract", "I"):
            continue                     # the abstract and introduction restate, they do not claim anew
        for sentence in sec.sentences:
            flat = re.sub(r"\$\$.*?\$\$", " ", sentence)
            deciders = [(i, d) for i, (tag, pat, d) in enumerate(DECIDERS)
                        if tag == sec.tag and re.search(pat, sentence)]
            if not deciders and not TRIGGERS.search(flat):
                continue
            counters[sec.tag] += 1
            used.update(i for i, _ in deciders)
            decide = deciders[0][1] if deciders else (lambda s=sec.tag, t=sentence: _undecided(s, t))
            out.append((f"text.{sec.tag}.{counters[sec.tag]}", sec.number, sentence, decide))
    unused = [DECIDERS[i][:2] for i in range(len(DECIDERS)) if i not in used]
    if out and unused:
        raise RuntimeError(f"deciders that match no sentence of the transcription: {unused}")
    return tuple(out)


def register() -> int:
    if not T.sections():
        return 0
    for cid, number, sentence, decide in statements():
        claim(cid, number, T.quote(T.clip(sentence, 300)), chapter=CHAPTER, kind="statement")(decide)
    return len(statements())
