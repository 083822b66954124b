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

_LABEL = {d1: "A_v/N", d2: "A_l/N", f0: "A_e/N", q0: "A_q/N"}


def _static(drive):
    return low_frequency(elastic_contact.solve().theta(drive))


def _exact_limit(drive, eq):
    def run():
        derived = _static(drive)
        cmp = compare(P.LOW_FREQUENCY[drive][0], derived)
        if cmp.is_(1):
            return HOLDS, f"beta -> 0 of the derived {_LABEL[drive]} = {sp.sstr(derived)}; {cmp.summary()}", ""
        return ERRATUM, f"beta -> 0 of the derived {_LABEL[drive]} = {sp.sstr(derived)}; {cmp.summary()}", sp.sstr(derived)
    claim(f"eq{eq}.low_frequency", f"III.2, Eq. {eq}", f"beta -> 0 of {_LABEL[drive]}, exact form", chapter="limits")(run)


def _approx_limit(drive, eq):
    def run():
        derived = _static(drive)
        approx = P.LOW_FREQUENCY[drive][1]
        ratio = param_limit(sp.cancel(derived / approx), k1, sp.oo)
        evidence = (f"stiff contact k1 >> k: leading term of the derived static {_LABEL[drive]} "
                    f"divided by the printed approximation -> {ratio}")
        if ratio == 1:
            return HOLDS, evidence, ""
        leading = sp.factor(approx * ratio)
        if ratio == -1:
            exact_agrees = compare(P.LOW_FREQUENCY[drive][0], derived).is_(1)
            verdict, why = sign_flip_verdict({f"exact form printed in Eq. {eq}": exact_agrees}, "")
            return verdict, f"{why}; {evidence}", sp.sstr(leading)
        return ERRATUM, evidence, sp.sstr(leading)
    claim(f"eq{eq}.approx", f"III.2, Eq. {eq}", f"k1 >> k approximation of {_LABEL[drive]}", chapter="limits")(run)


for _drive, _eq in [(d1, 11), (d2, 12), (f0, 13), (q0, 14)]:
    _exact_limit(_drive, _eq)
    _approx_limit(_drive, _eq)


@claim("eq11_14.stiff_cantilever", "III.2, after Eq. 14",
       "k L^2 >> H^2 k2: vertical displacement dominates; soft cantilever: in-plane displacement dominates", chapter="limits")
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
    evidence = (f"static signal per unit vertical / per unit longitudinal displacement (k1 >> k) = {ratio} "
                f"= {in_rho} with rho = kL^2/(H^2 k2); it exceeds 1 only for rho > L/(2H), not for rho > 1. "
                f"Cantilever A of Table 1 (k2 = k1/0.85): rho = {float(rho_A):.3g} (stiff by the printed test) "
                f"but the ratio is {float(ratio_A):.3g}; soft limit rho -> 0: ratio -> {soft} (in-plane dominates, as stated)")
    ok = bool(ratio_A > 3) or not bool(rho_A > 3)
    return (HOLDS if ok else ERRATUM, evidence,
            "" if ok else "vertical displacement dominates when k L >> H k2 / 2, i.e. k L^2 >> (L/2H) H^2 k2; "
            "the soft-cantilever statement holds")


def _scaling(drive, eq):
    def run():
        B = P.TABLE1["B"]
        values = {k: B["k"], k1: P.CONTACT_K1, k2: str(float(P.CONTACT_K1) / float(P.K1_OVER_K2)),
                  H: P.TIP_HEIGHT, L: B["L"]}
        expr = elastic_contact.solve().theta(drive)
        p = envelope_exponent(expr, values)
        printed = P.HIGH_FREQUENCY_EXPONENT[drive]
        evidence = (f"envelope of |{_LABEL[drive]}| for cantilever B, beta = 2e2..2e4 (50-digit): "
                    f"|{_LABEL[drive]}| ~ omega^{p:.4f}; printed omega^{printed}")
        ok = abs(p - float(printed)) < 0.02
        if drive == d1:
            g = sp.lambdify([beta, *values], expr, "mpmath")
            at = (mp.mpf(3000) + mp.mpf(1) / 4) * mp.pi      # deep in the asymptotic regime
            doubled = dict(values)
            doubled[k1] = str(2 * float(P.CONTACT_K1))
            with mp.workdps(30):
                r = abs(g(at, *map(mp.mpf, doubled.values())) / g(at, *map(mp.mpf, values.values())))
            evidence += f"; doubling k1 multiplies it by {mp.nstr(r, 6)} (proportional to k1)"
            ok = ok and abs(r - 2) < 0.01
        return (HOLDS if ok else ERRATUM, evidence, "" if ok else f"|{_LABEL[drive]}| ~ omega^{p:.2f}")
    claim(f"eq{eq}.scaling", f"III.2, Eq. {eq}", f"{_LABEL[drive]} ~ omega^{P.HIGH_FREQUENCY_EXPONENT[drive]}", chapter="limits")(run)


for _drive, _eq in [(d1, 15), (d2, 16), (f0, 17), (q0, 18)]:
    _scaling(_drive, _eq)


@claim("eq15_18.piezo_to_local_ratio", "III.2, after Eq. 18",
       "A_piezo/A_el = d1 k1/f0 at every frequency", chapter="limits")
def _piezo_local():
    t = elastic_contact.transfer()
    ratio = sp.simplify(t[d1] * d1 / (t[f0] * f0))
    ok = sp.simplify(ratio - d1 * k1 / f0) == 0
    return HOLDS if ok else ERRATUM, f"derived (A_v d1)/(A_e f0) = {ratio} for all beta", ""


def _static_pair(printed_theta, printed_A, derived_theta, anchors, label):
    """Verdict for a printed static slope and its height A = 2 theta L / 3."""
    derived_A = sp.expand(2 * derived_theta * L / 3)
    c_theta, c_A = compare(printed_theta, derived_theta), compare(printed_A, derived_A)
    evidence = f"derived {label}: theta = {sp.sstr(derived_theta)}, A = 2 theta L/3 = {sp.sstr(derived_A)}"
    if c_theta.is_(1) and c_A.is_(1):
        return HOLDS, evidence, ""
    correct = f"theta = {sp.sstr(derived_theta)}, A = {sp.sstr(derived_A)}"
    if c_theta.is_(-1) and c_A.is_(-1):
        verdict, why = sign_flip_verdict(anchors, "force positive towards the surface")
        return verdict, f"{why}; {evidence}", correct
    return ERRATUM, evidence, correct


@claim("eq20.static", "III.3", "low frequency: theta_nlc = q0/(16k), A = q0 L/(24k)", chapter="pinned")
def _eq20_static():
    derived = low_frequency(pinned.solve().theta(q0)) * q0
    anchors = {"Eq. 20 at beta -> 0": compare(low_frequency(P.theta_nlc), derived).is_(1),
               "A_nl of Section IV.1, negative for a positive load": bool(
                   P.A_nl.subs({s: 1 for s in P.A_nl.free_symbols}) < 0)}
    return _static_pair(P.pinned_static_theta, P.pinned_static_A, derived, anchors, "supported end, beta -> 0")


@claim("eq22.static", "III.3", "low frequency: theta_f = q0/(2k) + 3 f0/(2kL), A = q0 L/(3k) + f0/k", chapter="free_end")
def _eq22_static():
    sol = free_end.solve()
    derived = low_frequency(sol.theta(q0)) * q0 + low_frequency(sol.theta(f0)) * f0
    return _static_pair(P.free_static_theta, P.free_static_A, derived, {}, "free end, beta -> 0")


@claim("eq22.nonlocal_8x", "III.3", "free cantilever: non-local response 8 times that of the supported one", chapter="free_end")
def _eight():
    free = low_frequency(free_end.solve().theta(q0))
    sup = low_frequency(pinned.solve().theta(q0))
    ratio = sp.simplify(free / sup)
    ok = sp.Abs(ratio) == P.nonlocal_free_to_supported
    return (HOLDS if ok else ERRATUM,
            f"static slope per unit q0: free {free}, supported {sup}; ratio {ratio} (magnitude {sp.Abs(ratio)}, "
            "opposite directions)", "" if ok else f"{sp.Abs(ratio)} times")


def _indentation_static():
    sol = indentation.solve()
    return low_frequency(sol.theta(d1)) * d1 + low_frequency(sol.theta(f0)) * f0


@claim("eq28.low_frequency", "III.5", "theta_p0 = 3 (f0 + d1 k1)/((2 k1 + 2 k) L)", chapter="indentation")
def _eq28_low():
    derived = _indentation_static()
    cmp = compare(P.indentation_static, derived)
    return (HOLDS if cmp.is_(1) else ERRATUM, f"beta -> 0 of the derived Eq. 28: {sp.factor(derived)}; {cmp.summary()}",
            "" if cmp.is_(1) else sp.sstr(sp.factor(derived)))


@claim("eq28.stiff_contact_static", "III.5", "k1 -> oo: theta_f0 = 3 d1/(2L), A = d1", chapter="indentation")
def _eq28_stiff():
    derived = param_limit(_indentation_static(), k1, sp.oo)
    return _static_pair(P.stiff_static_theta, P.stiff_static_A, derived, {}, "static, k1 -> oo")


@claim("eq28.free_static", "III.5", "k1 -> 0: theta_f0 = -3 f0/(2kL), A = -f0/k", chapter="indentation")
def _eq28_free():
    derived = _indentation_static().subs(k1, 0)
    anchors = {"Eq. 28's printed low-frequency form at k1 = 0": compare(P.indentation_static.subs(k1, 0), derived).is_(1)}
    return _static_pair(P.free_static_theta_28, P.free_static_A_28, derived, anchors, "static, k1 = 0")


@claim("eq28.nonpiezo_contact_static", "III.5", "d1 = 0, contact: theta_p0 = -3 f0/(2 k1 L), A = -f0/k1", chapter="indentation")
def _eq28_nonpiezo():
    exact = _indentation_static().subs(d1, 0)
    leading = sp.factor(param_limit(exact * k1, k1, sp.oo) / k1)
    anchors = {"Eq. 28's printed low-frequency form for k1 >> k": compare(
        sp.factor(param_limit(P.indentation_static.subs(d1, 0) * k1, k1, sp.oo) / k1), leading).is_(1)}
    verdict, evidence, correct = _static_pair(P.nonpiezo_static_theta, P.nonpiezo_static_A, leading, anchors,
                                              "static, d1 = 0, k1 >> k")
    no_L = not sp.expand(2 * leading * L / 3).has(L)
    return verdict, f"{evidence}; exact: theta = {sp.sstr(exact)}; A independent of L: {no_L}", correct


@claim("contact.low_frequency_transfer", "III.1", "delta A = k1 delta w/(k + k1)", chapter="elastic_contact")
def _transfer():
    sol = indentation.solve()
    u = low_frequency(sol.tip_deflection(d1))
    a = sp.simplify(2 * low_frequency(sol.theta(d1)) * L / 3)
    ok = sp.simplify(u - k1 / (k + k1)) == 0 and sp.simplify(a - k1 / (k + k1)) == 0
    return (HOLDS if ok else ERRATUM,
            f"derived static tip displacement per unit surface displacement {u}; optical-lever height {a}", "")
