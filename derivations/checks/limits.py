"""Checks of the low-frequency limits (Eqs. 11-14, static statements) and of the
high-frequency scaling laws (Eqs. 15-18)."""
from __future__ import annotations

import mpmath as mp
import sympy as sp

from .. import elastic_contact, free_end, indentation, pinned
from ..beam import H, L, beta, d1, d2, f0, k, k1, k2, q0
from ..limits import envelope_exponent, low_frequency, param_limit
from ..paper import printed as P
from .core import ERRATUM, HOLDS, claim, compare, sign_flip_verdict
from ..evidence import Evidence, Math, Tex, say
from .flexural import K1_INF

_LABEL = {d1: "A_v/N", d2: "A_l/N", f0: "A_e/N", q0: "A_q/N"}
_BETA_ZERO = Tex(r"\beta \to 0", "beta -> 0")
_STIFF = Tex(r"k_1 \gg k", "k1 >> k")


def _static(drive):
    return low_frequency(elastic_contact.solve().theta(drive))


def _exact_limit(drive, eq):
    def run():
        derived = _static(drive)
        cmp = compare(P.LOW_FREQUENCY[drive][0], derived)
        sentence = say(_BETA_ZERO, " of the derived ", Math(derived, _LABEL[drive]))
        if cmp.is_(1):
            return Evidence(HOLDS, sentence, ratio=cmp)
        return Evidence(ERRATUM, sentence, ratio=cmp, correct=(Math(derived, _LABEL[drive]),))
    claim(f"eq{eq}.low_frequency", f"III.2, Eq. {eq}", (_BETA_ZERO, f" of {_LABEL[drive]}, exact form"),
          chapter="limits")(run)


def _approx_limit(drive, eq):
    def run():
        derived = _static(drive)
        approx = P.LOW_FREQUENCY[drive][1]
        ratio = param_limit(sp.cancel(derived / approx), k1, sp.oo)
        evidence = say("stiff contact ", _STIFF, ": leading term of the derived static ", Tex(_LABEL[drive], _LABEL[drive]),
                       " divided by the printed approximation tends to ", ratio)
        if ratio == 1:
            return Evidence(HOLDS, evidence)
        correct = (Math(sp.factor(approx * ratio), _LABEL[drive], "~="),)
        if ratio == -1:
            exact_agrees = compare(P.LOW_FREQUENCY[drive][0], derived).is_(1)
            verdict, why = sign_flip_verdict({f"exact form printed in Eq. {eq}": exact_agrees}, "")
            return Evidence(verdict, say(why, "; ", evidence), correct=correct, sign_convention=True)
        return Evidence(ERRATUM, evidence, correct=correct)
    claim(f"eq{eq}.approx", f"III.2, Eq. {eq}", (_STIFF, " approximation: ", Math(P.LOW_FREQUENCY[drive][1], _LABEL[drive], "~=")),
          chapter="limits")(run)


for _drive, _eq in [(d1, 11), (d2, 12), (f0, 13), (q0, 14)]:
    _exact_limit(_drive, _eq)
    _approx_limit(_drive, _eq)


@claim("eq11_14.stiff_cantilever", "III.2, after Eq. 14",
       (Tex(r"k L^2 \gg H^2 k_2", "k L^2 >> H^2 k2"), ": vertical displacement dominates; soft cantilever: "
        "in-plane displacement dominates"), chapter="limits")
def _stiff_cantilever():
    vertical = param_limit(_static(d1), k1, sp.oo)
    longitudinal = param_limit(_static(d2), k1, sp.oo)
    ratio = sp.simplify(vertical / longitudinal)          # per unit d1 vs per unit d2
    rho = sp.Symbol("rho", positive=True)                 # k L^2 / (H^2 k2)
    in_rho = sp.simplify(ratio.subs(k2, k * L**2 / (rho * H**2)))
    A = P.TABLE1["A"]
    kk, LL, HH = sp.Rational(A["k"]), sp.Rational(A["L"]), sp.Rational(P.TIP_HEIGHT)
    kk2 = sp.Rational(P.CONTACT_K1) / sp.Rational(P.K1_OVER_K2)
    rho_A = kk * LL**2 / (HH**2 * kk2)
    ratio_A = ratio.subs({k: kk, L: LL, H: HH, k2: kk2})
    soft = sp.limit(in_rho, rho, 0)
    evidence = say("static signal per unit vertical / per unit longitudinal displacement (", _STIFF, ") = ", ratio,
                   " = ", in_rho, " with ", Math(k * L**2 / (H**2 * k2), rho), "; it exceeds 1 only for ",
                   Math(L / (2 * H), rho, ">"), ", not for ", Math(1, rho, ">"), ". Cantilever A of Table 1 (",
                   Math(k1 / sp.Rational(P.K1_OVER_K2), k2), "): ", Tex(rf"\rho = {float(rho_A):.3g}", f"rho = {float(rho_A):.3g}"),
                   " (stiff by the printed test) "
                   f"but the ratio is {float(ratio_A):.3g}; soft limit ", Math(0, rho, "->"), ": ratio tends to ", soft,
                   " (in-plane dominates, as stated)")
    ok = bool(ratio_A > 3) or not bool(rho_A > 3)
    return Evidence(HOLDS if ok else ERRATUM, evidence, correction=() if ok else say(
        "vertical displacement dominates when ", Tex(r"k L \gg H k_2 / 2", "k L >> H k2 / 2"), ", i.e. ",
        Tex(r"k L^2 \gg \frac{L}{2H} H^2 k_2", "k L^2 >> (L/2H) H^2 k2"), "; the soft-cantilever statement holds"))


def _scaling(drive, eq):
    def run():
        B = P.TABLE1["B"]
        values = {k: B["k"], k1: P.CONTACT_K1, k2: str(float(P.CONTACT_K1) / float(P.K1_OVER_K2)),
                  H: P.TIP_HEIGHT, L: B["L"]}
        expr = elastic_contact.solve().theta(drive)
        p = envelope_exponent(expr, values)
        printed = P.HIGH_FREQUENCY_EXPONENT[drive]
        evidence = say(f"envelope of |{_LABEL[drive]}| for cantilever B, ",
                       Tex(r"\beta = 2 \cdot 10^2 \ldots 2 \cdot 10^4", "beta = 2e2..2e4"), " (50-digit): ",
                       Tex(rf"|{_LABEL[drive]}| \sim \omega^{{{p:.4f}}}", f"|{_LABEL[drive]}| ~ omega^{p:.4f}"),
                       "; printed ", Tex(rf"\omega^{{{sp.latex(printed)}}}", f"omega^{printed}"))
        ok = abs(p - float(printed)) < 0.02
        if drive == d1:
            g = sp.lambdify([beta, *values], expr, "mpmath")
            at = (mp.mpf(3000) + mp.mpf(1) / 4) * mp.pi      # deep in the asymptotic regime
            doubled = dict(values)
            doubled[k1] = str(2 * float(P.CONTACT_K1))
            with mp.workdps(30):
                r = abs(g(at, *map(mp.mpf, doubled.values())) / g(at, *map(mp.mpf, values.values())))
            evidence = say(evidence, f"; doubling k1 multiplies it by {mp.nstr(r, 6)} (proportional to k1)")
            ok = ok and abs(r - 2) < 0.01
        return Evidence(HOLDS if ok else ERRATUM, evidence, correction=() if ok else Tex(
            rf"|{_LABEL[drive]}| \sim \omega^{{{p:.2f}}}", f"|{_LABEL[drive]}| ~ omega^{p:.2f}"))
    exponent = P.HIGH_FREQUENCY_EXPONENT[drive]
    claim(f"eq{eq}.scaling", f"III.2, Eq. {eq}", Tex(rf"{_LABEL[drive]} \sim \omega^{{{sp.latex(exponent)}}}",
                                                    f"{_LABEL[drive]} ~ omega^{exponent}"), chapter="limits")(run)


for _drive, _eq in [(d1, 15), (d2, 16), (f0, 17), (q0, 18)]:
    _scaling(_drive, _eq)


@claim("eq15_18.piezo_to_local_ratio", "III.2, after Eq. 18",
       (Tex(r"A_{piezo}/A_{el} = d_1 k_1/f_0", "A_piezo/A_el = d1 k1/f0"), " at every frequency"), chapter="limits")
def _piezo_local():
    t = elastic_contact.transfer()
    ratio = sp.simplify(t[d1] * d1 / (t[f0] * f0))
    ok = sp.simplify(ratio - d1 * k1 / f0) == 0
    return Evidence(HOLDS if ok else ERRATUM, say("derived ", Math(ratio, Tex(r"\frac{A_v d_1}{A_e f_0}", "(A_v d1)/(A_e f0)")),
                                                  " for all ", Tex(r"\beta", "beta")))


def _static_pair(printed_theta, printed_A, derived_theta, anchors, label):
    """Verdict for a printed static slope and its height A = 2 theta L / 3."""
    derived_A = sp.expand(2 * derived_theta * L / 3)
    c_theta, c_A = compare(printed_theta, derived_theta), compare(printed_A, derived_A)
    theta = Tex(r"\theta", "theta")
    evidence = say("derived ", label, ": ", Math(derived_theta, theta), ", ",
                   Math(derived_A, Tex(r"A = 2 \theta L/3", "A = 2 theta L/3")))
    if c_theta.is_(1) and c_A.is_(1):
        return Evidence(HOLDS, evidence)
    correct = (Math(derived_theta, theta), Math(derived_A, "A"))
    if c_theta.is_(-1) and c_A.is_(-1):
        verdict, why = sign_flip_verdict(anchors, "force positive towards the surface")
        return Evidence(verdict, say(why, "; ", evidence), correct=correct, sign_convention=True)
    return Evidence(ERRATUM, evidence, correct=correct)


@claim("eq20.static", "III.3", ("low frequency: ", Math(P.pinned_static_theta, Tex(r"\theta_{nlc}", "theta_nlc")), ", ",
                                 Math(P.pinned_static_A, "A")), chapter="pinned")
def _eq20_static():
    derived = low_frequency(pinned.solve().theta(q0)) * q0
    anchors = {("Eq. 20 at ", _BETA_ZERO): compare(low_frequency(P.theta_nlc), derived).is_(1),
               (Tex("A_{nl}", "A_nl"), " of Section IV.1, negative for a positive load"): bool(
                   P.A_nl.subs({s: 1 for s in P.A_nl.free_symbols}) < 0)}
    return _static_pair(P.pinned_static_theta, P.pinned_static_A, derived, anchors, say("supported end, ", _BETA_ZERO))


@claim("eq22.static", "III.3", ("low frequency: ", Math(P.free_static_theta, Tex(r"\theta_f", "theta_f")), ", ",
                                 Math(P.free_static_A, "A")), chapter="free_end")
def _eq22_static():
    sol = free_end.solve()
    derived = low_frequency(sol.theta(q0)) * q0 + low_frequency(sol.theta(f0)) * f0
    return _static_pair(P.free_static_theta, P.free_static_A, derived, {}, say("free end, ", _BETA_ZERO))


@claim("eq22.nonlocal_8x", "III.3", "free cantilever: non-local response 8 times that of the supported one", chapter="free_end")
def _eight():
    free = low_frequency(free_end.solve().theta(q0))
    sup = low_frequency(pinned.solve().theta(q0))
    ratio = sp.simplify(free / sup)
    ok = sp.Abs(ratio) == P.nonlocal_free_to_supported
    return Evidence(HOLDS if ok else ERRATUM,
                    say("static slope per unit ", Tex("q_0", "q0"), ": free ", free, ", supported ", sup, "; ratio ", ratio,
                        " (magnitude ", sp.Abs(ratio), ", opposite directions)"),
                    correction=() if ok else f"{sp.Abs(ratio)} times", sign_convention=True)


def _indentation_static():
    sol = indentation.solve()
    return low_frequency(sol.theta(d1)) * d1 + low_frequency(sol.theta(f0)) * f0


@claim("eq28.low_frequency", "III.5", Math(P.indentation_static, Tex(r"\theta_{p0}", "theta_p0")), chapter="indentation")
def _eq28_low():
    derived = _indentation_static()
    cmp = compare(P.indentation_static, derived)
    return Evidence(HOLDS if cmp.is_(1) else ERRATUM, say(_BETA_ZERO, " of the derived Eq. 28: ", sp.factor(derived)),
                    ratio=cmp, correct=() if cmp.is_(1) else (Math(sp.factor(derived), Tex(r"\theta_{p0}", "theta_p0")),))


@claim("eq28.stiff_contact_static", "III.5", (K1_INF, ": ", Math(P.stiff_static_theta, Tex(r"\theta_{f0}", "theta_f0")), ", ",
                                               Math(P.stiff_static_A, "A")), chapter="indentation")
def _eq28_stiff():
    derived = param_limit(_indentation_static(), k1, sp.oo)
    return _static_pair(P.stiff_static_theta, P.stiff_static_A, derived, {}, say("static, ", K1_INF))


@claim("eq28.free_static", "III.5", (Tex(r"k_1 \to 0", "k1 -> 0"), ": ", Math(P.free_static_theta_28, Tex(r"\theta_{f0}", "theta_f0")),
                                      ", ", Math(P.free_static_A_28, "A")), chapter="indentation")
def _eq28_free():
    derived = _indentation_static().subs(k1, 0)
    anchors = {("Eq. 28's printed low-frequency form at ", Tex("k_1 = 0", "k1 = 0")):
               compare(P.indentation_static.subs(k1, 0), derived).is_(1)}
    return _static_pair(P.free_static_theta_28, P.free_static_A_28, derived, anchors,
                        say("static, ", Tex("k_1 = 0", "k1 = 0")))


@claim("eq28.nonpiezo_contact_static", "III.5", (Tex("d_1 = 0", "d1 = 0"), ", contact: ",
                                                  Math(P.nonpiezo_static_theta, Tex(r"\theta_{p0}", "theta_p0")), ", ",
                                                  Math(P.nonpiezo_static_A, "A")), chapter="indentation")
def _eq28_nonpiezo():
    exact = _indentation_static().subs(d1, 0)
    leading = sp.factor(param_limit(exact * k1, k1, sp.oo) / k1)
    anchors = {("Eq. 28's printed low-frequency form for ", _STIFF): compare(
        sp.factor(param_limit(P.indentation_static.subs(d1, 0) * k1, k1, sp.oo) / k1), leading).is_(1)}
    evidence = _static_pair(P.nonpiezo_static_theta, P.nonpiezo_static_A, leading, anchors,
                            say("static, ", Tex("d_1 = 0", "d1 = 0"), ", ", _STIFF))
    no_L = not sp.expand(2 * leading * L / 3).has(L)
    return evidence.but(sentence=say(evidence.sentence, "; exact: ", Math(exact, Tex(r"\theta", "theta")),
                                     f"; A independent of L: {no_L}"))


@claim("contact.low_frequency_transfer", "III.1", Tex(r"\delta A = k_1 \delta w/(k + k_1)", "delta A = k1 delta w/(k + k1)"),
       chapter="elastic_contact")
def _transfer():
    sol = indentation.solve()
    u = low_frequency(sol.tip_deflection(d1))
    a = sp.simplify(2 * low_frequency(sol.theta(d1)) * L / 3)
    ok = sp.simplify(u - k1 / (k + k1)) == 0 and sp.simplify(a - k1 / (k + k1)) == 0
    return Evidence(HOLDS if ok else ERRATUM,
                    say("derived static tip displacement per unit surface displacement ", u, "; optical-lever height ", a))
