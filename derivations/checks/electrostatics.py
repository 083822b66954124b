"""Checks of the electrostatic analyses: Eq. 36, Figs. 6-7, domain contrast (Eqs. 37-40), Eq. 41."""
from __future__ import annotations

from functools import lru_cache

import mpmath as mp
import sympy as sp

from .. import domain_contrast as dc
from .. import elastic_contact, frictionless, indentation, pinned
from ..beam import H, L, beta, d1, f0, k, k1, q0
from ..limits import envelope_exponent, low_frequency
from ..paper import inputs, printed as P
from .core import ERRATUM, HOLDS, SIGN, claim, compare, digits_check
from ..evidence import Evidence, Math, Tex, say

tau = sp.Symbol("tau", real=True)


@lru_cache(maxsize=None)
def q0_first_harmonic() -> sp.Expr:
    """First-harmonic amplitude per unit length of the parallel-plate force eps0 S (dV + V_ac cos)^2/(2 H^2)."""
    force = P.eps0 * P.S_area * (P.dV + P.V_ac * sp.cos(tau)) ** 2 / (2 * H**2)
    return sp.simplify(sp.integrate(force * sp.cos(tau), (tau, 0, 2 * sp.pi)) / sp.pi / L)


@lru_cache(maxsize=None)
def nonlocal_height() -> sp.Expr:
    """A_nl = (2L/3) theta of the supported cantilever at low frequency, q0 from the capacitive force."""
    theta = low_frequency(pinned.solve().theta(q0)) * q0_first_harmonic()
    return sp.simplify((2 * L / 3 * theta).subs(P.S_area, L * P.w_c))


@claim("eq36.q0", "IV.1", (Math(P.eps0 * P.S_area * P.dV**2 / (2 * H**2), Tex("F_{cap}", "F_cap")), "; ",
                           Math(P.q0_cap, Tex("q_0", "q0"))), chapter="domains")
def _q0():
    derived = q0_first_harmonic()
    cmp = compare(P.q0_cap, derived)
    evidence = say("Fourier coefficient of ", Tex(r"\cos \omega t", "cos(wt)"), " in ", Tex("F_{cap}", "F_cap"),
                   ", per unit length: ", derived)
    return Evidence(HOLDS if cmp.is_(1) else ERRATUM, evidence, ratio=cmp,
                    correct=() if cmp.is_(1) else (Math(derived, Tex("q_0", "q0")),))


@claim("eq36.A_nl", "IV.1", Math(P.A_nl, Tex("A_{nl}", "A_nl")), chapter="domains")
def _a_nl():
    derived = nonlocal_height()
    cmp = compare(P.A_nl, derived)
    with_printed_q0 = sp.simplify(2 * L / 3 * low_frequency(pinned.solve().theta(q0)) * P.q0_cap.subs(P.S_area, L * P.w_c))
    evidence = say(Tex(r"(2L/3) \times", "(2L/3) x"), " static supported-end slope ", Tex(r"\times\ q_0", "x q0"), ": ",
                   derived, "; ", cmp.sentence(), "; with the printed ", Tex("q_0", "q0"), " instead: ", with_printed_q0,
                   " (the factor 2 is inherited from Eq. 36's ", Tex("q_0", "q0"), ")")
    return Evidence(HOLDS if cmp.is_(1) else ERRATUM, evidence,
                    correct=() if cmp.is_(1) else (Math(derived, Tex("A_{nl}", "A_nl")),))


@claim("eq36.PR", "IV.1, Eq. 36", Math(P.PR_eq36_extra, Tex(r"PR - d_{eff}", "PR - d_eff")), chapter="domains")
def _pr():
    derived = sp.simplify(nonlocal_height() / P.V_ac)          # PR = A / V_ac
    cmp = compare(P.PR_eq36_extra, derived)
    evidence = say(Tex(r"PR = A/V_{ac} = d_{eff} + A_{nl}/V_{ac}", "PR = A/V_ac = d_eff + A_nl/V_ac"), ", with ",
                   Math(derived, Tex(r"A_{nl}/V_{ac}", "A_nl/V_ac")), "; printed term / derived term = ", cmp.exact_ratio,
                   " (contains ", Tex("V_{ac}", "V_ac"), ": the printed term is a length, not a length per volt)")
    return Evidence(HOLDS if cmp.is_(1) else ERRATUM, evidence,
                    correct=() if cmp.is_(1) else (Math(derived, Tex(r"PR - d_{eff}", "PR - d_eff")),))


@claim("eq36.spring_constant_condition", "IV.1",
       (Tex(r"k \gg \frac{L w \varepsilon_0 \Delta V}{48 d_{eff} H^2} = 0.55\ \mathrm{N/m}",
            "k >> L w eps0 dV/(48 d_eff H^2) = 0.55 N/m"), " for the printed inputs"), chapter="domains")
def _keff():
    values = {key: mp.mpf(v) for key, v in P.KEFF_INPUTS.items()}
    eps0 = mp.mpf(inputs.EPSILON_0)
    common = values["L"] * values["w"] * eps0 * values["dV"] / (values["d_eff"] * values["H"] ** 2)
    printed_formula = common / 48
    # |A_nl|/V_ac < d_eff with the derived A_nl:
    kk = sp.Symbol("k_min", positive=True)
    bound = sp.solve(sp.Eq(-nonlocal_height().subs(k, kk) / P.V_ac, sp.Symbol("d_eff")), kk)[0]
    derived_value = common * mp.mpf(str(sp.nsimplify(bound * sp.Symbol("d_eff") * H**2 / (L * P.w_c * P.eps0 * P.dV))))
    ok_arith, rounded = digits_check(P.keff_printed, printed_formula)
    ok_formula = abs(printed_formula - derived_value) < mp.mpf("1e-6") * derived_value
    evidence = say(f"printed formula with the printed inputs: {mp.nstr(printed_formula, 4)} N/m (-> {rounded}, "
                   f"arithmetic {'right' if ok_arith else 'wrong'}); the derived ", Tex("A_{nl}", "A_nl"), " gives ",
                   Math(bound, "k", ">>"), f" = {mp.nstr(derived_value, 4)} N/m")
    if ok_arith and ok_formula:
        return Evidence(HOLDS, evidence)
    return Evidence(ERRATUM, evidence, correction=say(Math(bound, "k", ">>"),
                                                      f" = {mp.nstr(derived_value, 2)} N/m for these inputs"))


_K1_1000 = Tex(r"k_1 = 1000\ \mathrm{N/m}", "k1 = 1000 N/m")
_D_EFF_5 = Tex(r"d_{eff} = 5\ \mathrm{pm/V}", "d_eff = 5 pm/V")


def _fig_values(cantilever: str) -> dict:
    c = P.TABLE1[cantilever]
    return {k: c["k"], k1: P.CONTACT_K1, H: P.TIP_HEIGHT, L: c["L"]}


def _crossover_bias(cantilever: str, model) -> mp.mpf:
    """Low-frequency bias |dV| where |A_piezo| = |A_nl| (d1 = d_eff V_ac, q0 from the capacitive force)."""
    v = {s: sp.Rational(x) for s, x in _fig_values(cantilever).items()}
    q_per_volt = (q0_first_harmonic() / (P.V_ac * P.dV)).subs({P.S_area: L * P.w_c, P.w_c: sp.Rational(P.TABLE1[cantilever]["w"]),
                                                             P.eps0: sp.Rational(inputs.EPSILON_0)})
    ratio = sp.Abs(model[d1] * sp.Rational(P.D_EFF_FIG) / (model[q0] * q_per_volt))
    return mp.mpf(str(sp.N(ratio.subs(v), 20)))


@claim("fig6.crossover_scales_with_k", "IV.2, Fig. 6", "low-frequency crossover bias (EM vs non-local) proportional to k",
       chapter="diagrams")
def _crossover():
    sol = frictionless.solve()
    static = {d: low_frequency(sol.theta(d)) for d in (d1, q0)}
    supported = {d1: low_frequency(sol.theta(d1)).limit(k1, sp.oo), q0: low_frequency(pinned.solve().theta(q0))}
    rows, per_k_model, per_k_supported = [], [], []
    for name in P.TABLE1:
        kk = mp.mpf(P.TABLE1[name]["k"])
        a, b = _crossover_bias(name, static), _crossover_bias(name, supported)
        per_k_model.append(a / kk)
        per_k_supported.append(b / kk)
        rows.append(say(f"{name}: {mp.nstr(a, 3)} V (", _K1_1000, f"), {mp.nstr(b, 3)} V (", Tex(r"k_1 \to \infty", "k1 -> oo"), ")"))
    spread = max(per_k_model) / min(per_k_model)
    exact = max(per_k_supported) / min(per_k_supported)
    evidence = say(Tex(r"|\Delta V|", "|dV|"), " where ", Tex(r"|A_{piezo}| = |A_{nl}|", "|A_piezo| = |A_nl|"), " at ",
                   Tex(r"\beta \to 0", "beta -> 0"), " (frictionless contact, ", _D_EFF_5, "): ",
                   [(("; " if i else ""), row) for i, row in enumerate(rows)], "; ", Tex(r"\Delta V/k", "dV/k"),
                   f" varies by a factor {mp.nstr(spread, 3)} across A, B, C with ", _K1_1000, " (",
                   Tex(r"k_1/(k_1 - 8k)", "k1/(k1 - 8k)"), f" correction, largest for A) and by {mp.nstr(exact, 6)} in the ",
                   Tex(r"k_1 \to \infty", "k1 -> oo"), " analysis of IV.1")
    ok = abs(exact - 1) < mp.mpf("1e-12") and spread < 2
    return Evidence(HOLDS if ok else ERRATUM, evidence)


@claim("fig6.resonances_keep_ratio", "IV.2, Fig. 6", "anti-resonances enhance the non-local share; resonances leave the ratio unchanged", chapter="diagrams")
def _keep_ratio():
    sol = frictionless.solve()
    share = sp.cancel(sol.theta(d1) * d1 / (sol.theta(d1) * d1 + sol.theta(q0) * q0))
    no_N = sp.cancel(sol.slope[d1] * d1 / (sol.slope[d1] * d1 + sol.slope[q0] * q0))
    same = sp.simplify(share - no_N) == 0
    vals = {s: sp.Rational(v) for s, v in _fig_values("B").items()}
    at_zero = [(sol.slope[d1].subs(beta, n * sp.pi), sp.N(sol.slope[q0].subs(vals).subs(beta, n * sp.pi), 6)) for n in (1, 2, 3)]
    ok = same and all(a == 0 and b != 0 for a, b in at_zero)
    evidence = say(Tex(r"\frac{A_{piezo}}{A_{piezo} + A_{nl}} = \frac{A_v d_1}{A_v d_1 + A_q q_0}",
                       "A_piezo/(A_piezo + A_nl) = A_v d1/(A_v d1 + A_q q0)"),
                   f": the resonant denominator N cancels exactly ({same}); at ", Tex(r"\beta = n \pi", "beta = n pi"),
                   " (zeros of ", Tex("A_v", "A_v"), ", n = 1..3) ", Tex("A_v = 0", "A_v = 0"), " while ",
                   Tex("A_q", "A_q"), f" = {', '.join(str(b) for _, b in at_zero)} (cantilever B): the share drops to 0 there")
    return Evidence(HOLDS if ok else ERRATUM, evidence)


@claim("fig6.high_frequency_em", "IV.2, Fig. 6", "the electromechanical share grows at high frequency", chapter="diagrams")
def _high_em():
    sol = frictionless.solve()
    values = {s: v for s, v in _fig_values("B").items()}
    p = envelope_exponent(sol.slope[d1] / sol.slope[q0], values)
    evidence = say("envelope of ", Tex(r"|A_v/A_q|", "|A_v/A_q|"), " (frictionless contact, cantilever B) ",
                   Tex(rf"\sim \omega^{{{p:.3f}}}", f"~ omega^{p:.3f}"))
    return Evidence(HOLDS if p > 0.25 else ERRATUM, evidence)


@claim("fig7.local_boundary_frequency_independent", "IV.2, Fig. 7", "local-electrostatic vs EM boundary independent of frequency", chapter="diagrams")
def _local_boundary():
    ratio = sp.simplify(elastic_contact.transfer()[d1] * d1 / (elastic_contact.transfer()[f0] * f0))
    return Evidence(HOLDS if not ratio.has(beta) else ERRATUM,
                    say("derived ", Math(ratio, Tex(r"A_{piezo}/A_{el}", "A_piezo/A_el")), " (elastic contact, all ",
                        Tex(r"\beta", "beta"), "): the boundary ", Tex(r"|A_{piezo}| = |A_{el}|", "|A_piezo| = |A_el|"),
                        " is ", Tex(r"|d_1| k_1 = |f_0|", "|d1| k1 = |f0|"), ", free of frequency"))


@claim("fig7.local_force_value", "IV.2 and caption of Fig. 7", "Fig. 7: f = 14 and 0.7 N/V; text: 14 nN/V", chapter="diagrams")
def _local_force():
    k1v, d = mp.mpf(P.CONTACT_K1), mp.mpf(P.D_EFF_FIG)
    text = mp.mpf(P.LOCAL_FORCE_TEXT) / k1v
    caption = [mp.mpf(v) / k1v for v in P.LOCAL_FORCE_CAPTION]
    ratio = mp.mpf(P.LOCAL_FORCE_CAPTION[0]) / mp.mpf(P.LOCAL_FORCE_TEXT)
    evidence = say(Tex(r"A_{el} = f/k_1", "A_el = f/k1"), f" per volt: text {mp.nstr(text * 1e12, 3)} pm/V (comparable "
                   "with ", _D_EFF_5, ", as the three-colour map needs); caption "
                   f"{', '.join(mp.nstr(c * 1e3, 3) + ' mm/V' for c in caption)}, {mp.nstr(caption[0] / d, 2)} times ",
                   Tex("d_{eff}", "d_eff"), f"; caption/text = {mp.nstr(ratio, 2)}")
    consistent = abs(mp.mpf(P.LOCAL_FORCE_CAPTION[0]) / mp.mpf(P.LOCAL_FORCE_TEXT) - 1) < mp.mpf("0.01")
    return Evidence(HOLDS if consistent else ERRATUM, evidence,
                    correction="" if consistent else "f = 14 nN/V and 0.7 nN/V in the caption of Fig. 7")


@claim("fig6.model_reference", "IV.2, Fig. 6 (text)", "Fig. 6 (EM and non-local parts) is computed from Eq. (28) with f = 0", chapter="diagrams")
def _fig6_reference():
    printed_has_load = P.theta_indentation.has(q0)
    derived_has_load = q0 in indentation.solve().slope
    frictionless_has = q0 in frictionless.solve().slope
    evidence = say("Eq. 28 contains ", Tex("q_0", "q0"), f": printed {printed_has_load}, derived {derived_has_load} (its "
                   "boundary value problem has no distributed load), so it has no non-local term; the same boundary "
                   f"conditions with the load (Eq. 23) do: {frictionless_has}")
    if printed_has_load:
        return Evidence(HOLDS, evidence)
    return Evidence(ERRATUM, evidence, correction=say("Fig. 6 needs Eq. (23) (frictionless contact, with ", Tex("q_0", "q0"),
                                                      ") or Eq. (5); Eq. (28) has no non-local term"))


# --- domain contrast ----------------------------------------------------------------------------


@claim("eq39.amplitudes", "IV.3, Eqs. 37-39", (Math(P.PR_plus_amp, "|PR_+|"), ", ", Math(P.PR_minus_amp, "|PR_-|")),
       chapter="domains")
def _amplitudes():
    plus, minus = dc.amplitudes_squared()
    sub = {P.d_eff: dc.d_eff, P.d_el: dc.d_el, P.psi: dc.psi, P.phi: dc.psi}
    cp = compare(P.PR_plus_amp.subs(sub) ** 2, plus)
    cm_ = compare(P.PR_minus_amp.subs(sub) ** 2, minus)
    ok = cp.is_(1) and cm_.is_(1)
    evidence = say(Math(plus, "|PR_+|^2"), ", ", Math(minus, "|PR_-|^2"), " from Eqs. 37-38; printed (",
                   Tex(r"\varphi", "phi"), " read as ", Tex(r"\psi", "psi"), "): ", cp.sentence())
    if ok:
        return Evidence(HOLDS, evidence)
    return Evidence(ERRATUM, evidence, correct=(Math(sp.sqrt(plus), "|PR_+|"), Math(sp.sqrt(minus), "|PR_-|")))


@claim("eq39.phase_shift", "IV.3, Eq. 39", Math(P.tan_phase, Tex(r"\tan\varphi", "tan(phi)")), chapter="domains")
def _phase_shift():
    plus, minus = (sp.sqrt(a) for a in dc.amplitudes_squared())
    sub = {P.d_eff: dc.d_eff, P.d_el: dc.d_el, P.psi: dc.psi}
    printed = P.tan_phase.subs({P.PR_plus_amp: plus, P.PR_minus_amp: minus}).subs(sub)
    derived = dc.tan_phase_difference()
    c1, c2 = compare(printed, derived), compare(printed, -derived)
    dphi = Tex(r"\tan(\arg PR_+ - \arg PR_-)", "tan(arg PR+ - arg PR-)")
    evidence = say("derived ", Math(derived, dphi), "; printed vs it: ", c1.sentence(), "; vs minus it: ", c2.sentence())
    if c1.is_(1):
        return Evidence(HOLDS, evidence)
    if c2.is_(1):
        return Evidence(SIGN, say(evidence, " (phase difference taken as ", Tex(r"\arg PR_- - \arg PR_+", "arg PR- - arg PR+"),
                                  ")"))
    return Evidence(ERRATUM, evidence, correct=(Math(derived, dphi),))


def _small_limit(small: str, printed_amp, printed_phase, big, tiny):
    amp_plus = sp.sqrt(dc.amplitudes_squared()[0]).subs(tiny, dc.eps * big)
    first_order = sp.expand(sp.series(amp_plus, dc.eps, 0, 2).removeO().subs(dc.eps, tiny / big))
    phase = dc.phase_difference_series(small).subs(dc.eps, tiny / big)
    sub = {P.d_eff: dc.d_eff, P.d_el: dc.d_el, P.psi: dc.psi, P.phi: dc.psi}
    amp_ok = compare(printed_amp[0].subs(sub), first_order).is_(1)
    pr_phase = printed_phase.subs(sub)
    phase_ok = any(compare(pr_phase, s * phase).is_(1) for s in (1, -1)) if small == "piezoelectric" else \
        compare(pr_phase, phase).is_(1)
    ratio = tiny / big
    dphi = Tex(r"\Delta\varphi = \arg PR_+ - \arg PR_-", "Delta phi = arg PR+ - arg PR-")
    evidence = say("first order in ", ratio, ": ", Math(first_order, "|PR_+|"), " (printed, ", Tex(r"\varphi", "phi"),
                   " read as ", Tex(r"\psi", "psi"), f": {amp_ok}); phase difference ", Math(phase, dphi), " + ",
                   sp.Order(ratio**3), " (mod ", Tex(r"2 \pi", "2 pi"), "); printed ", pr_phase)
    if amp_ok and phase_ok:
        return Evidence(HOLDS, evidence)
    # |PR-| is |PR+| with the opposite sign of the first-order term.
    return Evidence(ERRATUM, evidence, correct=(Math(first_order, "|PR_+|"), Math(phase, Tex(r"\Delta\varphi", "Delta phi"))))


@claim("eq40.small_electrostatic", "IV.3, Eq. 40",
       (Tex(r"d_{el} \to 0", "d_el -> 0"), ": ", Tex(r"PR_\pm = d_{eff} \pm d_{el} \cos\varphi", "PR+- = d_eff +- d_el cos(phi)"),
        ", ", Math(P.small_el_phase, Tex(r"\Delta\varphi", "Delta phi"))), chapter="domains")
def _small_el():
    return _small_limit("electrostatic", P.small_el_amp, P.small_el_phase, dc.d_eff, dc.d_el)


@claim("eq40.small_piezo", "IV.3",
       (Tex(r"d_{eff} \to 0", "d_eff -> 0"), ": ", Tex(r"PR_\pm = d_{el} \pm d_{eff} \cos\varphi", "PR+- = d_el +- d_eff cos(phi)"),
        ", ", Math(P.small_piezo_phase, Tex(r"\Delta\varphi", "Delta phi"))), chapter="domains")
def _small_piezo():
    return _small_limit("piezoelectric", P.small_piezo_amp, P.small_piezo_phase, dc.d_el, dc.d_eff)


@claim("eq41.deconvolution", "VI.4, Eq. 41", ("fit ", Tex("y = b + c V", "y = b + c V"), " per frequency: ",
                                               Tex(r"G_{elec} = c,\ d_{eff} = b + c V_{surf}", "G_elec = c, d_eff = b + c V_surf")),
       chapter="deconvolution")
def _eq41():
    slope, intercept = dc.linear_fit_in_bias()
    d, G, Vs = sp.symbols("d G V_surf", real=True)
    ok_G = sp.simplify(P.eq41_G.subs(P.c_fit, slope) - G) == 0
    ok_d = sp.simplify(P.eq41_d.subs({P.c_fit: slope, P.b_fit: intercept, P.V_surf: Vs}) - d) == 0
    return Evidence(HOLDS if ok_G and ok_d else ERRATUM,
                    say(Tex(r"PR = d + G (V - V_{surf})", "PR = d + G (V - V_surf)"), " as a line in V: slope ", slope,
                        ", intercept ", intercept, "; so ", Tex("c = G", "c = G"), f": {ok_G}, ",
                        Tex(r"b + c V_{surf} = d", "b + c V_surf = d"), f": {ok_d}"))
