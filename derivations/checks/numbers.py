"""Checks of printed numbers: resonance roots, frequency ratios, Table 1, contact mechanics.

A printed number holds when it is the correctly rounded value of the quantity recomputed
from the paper's own inputs; roots come certified from :mod:`derivations.roots`.  A ratio of
measured resonances holds when it is the correct rounding of some value the printed
uncertainties (``407.95 +- 0.3 kHz``, ...) allow: the last digit of such a ratio is not
determined more finely than the measurements.
"""
from __future__ import annotations

from functools import lru_cache

import mpmath as mp
import sympy as sp

from .. import contact_mechanics as cm
from .. import free_end, indentation, pinned
from ..beam import L, beta, k, k1
from ..paper import inputs, printed as P
from ..roots import certified_roots
from .core import ERRATUM, HOLDS, claim, digits_check
from ..evidence import Evidence, Math, Rounding, Tex, say

SILICON_E = tuple(map(float, inputs.SILICON_E))
SILICON_RHO = float(inputs.SILICON_DENSITY)


@lru_cache(maxsize=None)
def free_roots(n: int = 3) -> tuple[mp.mpf, ...]:
    """First n certified roots of the derived free-end characteristic function."""
    return tuple(r.value for r in certified_roots(free_end.solve().denominator, beta, n, 20, {k: 1, L: 1}))


@lru_cache(maxsize=None)
def pinned_roots(n: int = 3) -> tuple[mp.mpf, ...]:
    """First n certified roots of the derived supported-end characteristic function."""
    return tuple(r.value for r in certified_roots(pinned.solve().denominator, beta, n, 20, {k: 1, L: 1}))


def _digits_verdict(pairs, what):
    """pairs: [(printed string, value)] or [(printed, value, (low, high))] -> verdict on correct
    rounding of every entry; with an interval (a measured quantity), any value in it may be the one
    rounded."""
    rows, numbers = [], []
    for printed, value, *interval in pairs:
        ok, rounded = digits_check(printed, value)
        row = f"{printed} (computed {mp.nstr(value, 8)} -> {rounded}"
        if interval:
            lo, hi = interval[0]
            half = mp.mpf(10) ** -len(printed.partition(".")[2]) / 2
            ok = ok or (lo <= mp.mpf(printed) + half and mp.mpf(printed) - half <= hi)
            row += f", {mp.nstr(lo, 6)} to {mp.nstr(hi, 6)} within the printed uncertainties"
        rows.append(row + ")")
        numbers.append(Rounding(printed, value, rounded, interval[0] if interval else None, ok))
    wrong = [n for n in numbers if not n.ok]
    return Evidence(ERRATUM if wrong else HOLDS, say(what, ": ", ", ".join(rows)), numbers=tuple(numbers),
                    correction="; ".join(f"{n.printed} should read {n.rounded}" for n in wrong))


@claim("eq20.roots", "III.3", ("roots of ", Tex(r"\cosh\beta \sin\beta = \cos\beta \sinh\beta", "cosh sin = cos sinh"),
                                ": 3.927, 7.067, 10.21"), chapter="roots")
def _eq20_roots():
    return _digits_verdict(zip(P.pinned_roots, pinned_roots()), "certified roots of the derived supported-end denominator")


@claim("eq22.roots", "III.3", ("roots of ", Tex(r"\cosh\beta \cos\beta + 1 = 0", "cosh cos + 1 = 0"),
                                ": 1.875, 4.694, 7.855"), chapter="roots")
def _eq22_roots():
    return _digits_verdict(zip(P.free_roots, free_roots()), "certified roots of the derived free-end denominator")


@claim("eq22.contact_to_free_ratio", "III.3", ("first contact (buckling) resonance ", Tex(r"\approx 4.4 \times", "~ 4.4 x"),
                                                " first free resonance"), chapter="roots")
def _contact_to_free():
    ratio = (pinned_roots()[0] / free_roots()[0]) ** 2
    return _digits_verdict([(P.contact_to_free_ratio, ratio)],
                           say("omega ratio ", Tex(r"(\beta_{1,supported}/\beta_{1,free})^2", "(beta1_supported/beta1_free)^2")))


_W21 = Tex(r"\omega_2/\omega_1", "w2/w1")
_FREE_RATIOS = say("measured ", _W21, ", ", Tex(r"\omega_3/\omega_1", "w3/w1"), " and free-end theory ",
                   Tex(r"(\beta_n/\beta_1)^2", "(beta_n/beta1)^2"))


def _ratios(freqs, pm):
    """Measured f_i/f_1 with the range the printed uncertainties +-pm allow: [(ratio, (low, high))]."""
    f, d = [mp.mpf(x) for x in freqs], [mp.mpf(x) for x in pm]
    return [(fi / f[0], ((fi - di) / (f[0] + d[0]), (fi + di) / (f[0] - d[0]))) for fi, di in zip(f[1:], d[1:])]


def _measured(printed, freqs, pm):
    return [(p, r, interval) for p, (r, interval) in zip(printed, _ratios(freqs, pm))]


@claim("exp.tip1_contact_ratio", "VI.1", "contact resonances 407.95, 1075.020 kHz: 2.63:1, theory 3.24:1", chapter="roots")
def _tip1_contact():
    theory = (pinned_roots()[1] / pinned_roots()[0]) ** 2
    return _digits_verdict(_measured([P.TIP1_CONTACT_RATIO], P.TIP1_CONTACT, inputs.TIP1_CONTACT_PM)
                           + [(P.TIP1_CONTACT_THEORY, theory)],
                           say("measured ", _W21, " and supported-end theory ", Tex(r"(\beta_2/\beta_1)^2", "(beta2/beta1)^2")))


@claim("exp.tip1_noncontact_ratios", "VI.1", "63.2, 368.33, 1031.70 kHz: 16.32:5.83:1, theory 17.55:6.23:1", chapter="roots")
def _tip1_free():
    theory = [(r / free_roots()[0]) ** 2 for r in free_roots()[1:]]
    pairs = _measured(P.TIP1_FREE_RATIOS, P.TIP1_FREE, inputs.TIP1_FREE_PM) + list(zip(P.FREE_THEORY_RATIOS, theory))
    return _digits_verdict(pairs, _FREE_RATIOS)


@claim("exp.tip2_noncontact_ratios", "VI.1", "54.55, 346.73, 980.55 kHz: 17.97:6.35:1, theory 17.55:6.23:1", chapter="roots")
def _tip2_free():
    theory = [(r / free_roots()[0]) ** 2 for r in free_roots()[1:]]
    pairs = _measured(P.TIP2_FREE_RATIOS, P.TIP2_FREE, inputs.TIP2_FREE_PM) + list(zip(P.FREE_THEORY_RATIOS, theory))
    return _digits_verdict(pairs, _FREE_RATIOS)


def _free_resonance_hz(E, rho, h, Lc):
    """f1 = beta1^2/(2 pi L^2) sqrt(E I/(rho S)) for a rectangular section."""
    return free_roots()[0] ** 2 / (2 * mp.pi * Lc**2) * mp.sqrt(E * h**2 / (12 * rho))


@claim("exp.tip2_nominal_geometry", "VI.1", "tip 2: h = 3 um, w = 24 um, L = 223 um, k = 2.4 N/m, f1 = 54.55 kHz", chapter="roots")
def _tip2_geometry():
    g = {key: mp.mpf(v) for key, v in P.TIP2_GEOMETRY.items()}
    f_lo, f_hi = (_free_resonance_hz(E, SILICON_RHO, g["h"], g["L"]) for E in SILICON_E)
    mass = SILICON_RHO * g["w"] * g["h"] * g["L"]
    f_k = free_roots()[0] ** 2 * mp.sqrt(g["k"] / (3 * mass)) / (2 * mp.pi)    # omega^2 = k beta^4/(3m)
    h_eff = g["h"] * g["f1"] / ((f_lo + f_hi) / 2)
    evidence = say("Euler-Bernoulli, silicon (E = 130-188 GPa, ", Tex(r"\rho = 2330\ \mathrm{kg/m^3}", "rho = 2330 kg/m^3"),
                   f"): the printed geometry gives f1 = {mp.nstr(f_lo / 1e3, 4)}-{mp.nstr(f_hi / 1e3, 4)} kHz; "
                   f"from k = 2.4 N/m and the beam mass f1 = {mp.nstr(f_k / 1e3, 4)} kHz; measured "
                   f"{mp.nstr(g['f1'] / 1e3, 5)} kHz")
    if f_lo <= g["f1"] <= f_hi:
        return Evidence(HOLDS, evidence)
    return Evidence(ERRATUM, evidence, correction=(
        f"a 3 um thick, 223 um long silicon beam resonates near {mp.nstr((f_lo + f_hi) / 2e3, 2)} kHz; "
        f"54.55 kHz implies an effective thickness near {mp.nstr(h_eff * 1e6, 2)} um (k nearer "
        f"{mp.nstr(g['k'] * (h_eff / g['h']) ** 3, 2)} N/m): the supplied nominal values do not describe tip 2"))


@claim("table1.spring_constants", "Table 1", "A, B, C (w = 24, L = 224, h = 8, 3, 1.05 um): k = 45, 2.4, 0.1 N/m", chapter="roots")
def _table1():
    # k = E w h^3/(4 L^3) is linear in E: find the moduli for which every printed k is correctly rounded.
    lo, hi = mp.mpf(0), mp.inf
    rows = []
    for name, c in P.TABLE1.items():
        per_E = mp.mpf(c["w"]) * mp.mpf(c["h"]) ** 3 / (4 * mp.mpf(c["L"]) ** 3)
        dec = c["k"].split(".")[1] if "." in c["k"] else ""
        half = mp.mpf(10) ** (-len(dec)) / 2 if dec else (mp.mpf(1) / 2 if mp.mpf(c["k"]) >= 1 else mp.mpf(c["k"]) / 2)
        lo, hi = max(lo, (mp.mpf(c["k"]) - half) / per_E), min(hi, (mp.mpf(c["k"]) + half) / per_E)
        rows.append(f"{name}: k/E = {mp.nstr(per_E * 1e9, 5)} N/m per GPa")
    evidence = say(Tex(r"k = E w h^3/(4 L^3)", "k = E w h^3/(4 L^3)"), f"; {'; '.join(rows)}; all printed values are "
                   f"correctly rounded for E in [{mp.nstr(lo / 1e9, 4)}, {mp.nstr(hi / 1e9, 4)}] GPa (silicon: 130-188 GPa)")
    ok = lo <= hi and lo <= SILICON_E[1] and hi >= SILICON_E[0]
    return Evidence(HOLDS if ok else ERRATUM, evidence,
                    correction="" if ok else "no single silicon modulus reproduces all three")


@claim("eq28.resonances_increase_with_k1", "III.5, Fig. 4b",
       "resonances grow with k1; branches separated by gaps; free-to-supported crossover moves to higher k1 with mode", chapter="roots")
def _branches():
    sol = indentation.solve()
    grid = [mp.mpf(10) ** (e / mp.mpf(2)) for e in range(-4, 13)]     # k1/k from 1e-2 to 1e6
    modes = 3
    # Three modes lie below the third supported root, 10.21: one isolation interval suffices.
    branches = [[r.value for r in certified_roots(sol.denominator, beta, modes, 4, {k: 1, L: 1, k1: g}, step=10.5)]
                for g in grid]
    free, sup = free_roots(), pinned_roots()
    increasing = all(branches[i][m] < branches[i + 1][m] for i in range(len(grid) - 1) for m in range(modes))
    gaps = all(free[m] < b[m] < sup[m] for b in branches for m in range(modes)) and all(sup[m] < free[m + 1] for m in range(modes - 1))
    crossover = []
    for m in range(modes):
        half = (free[m] + sup[m]) / 2
        i = next(i for i, b in enumerate(branches) if b[m] > half)
        crossover.append(grid[i])
    moves_up = all(crossover[m] < crossover[m + 1] for m in range(modes - 1))
    evidence = (f"certified roots of the derived Eq. 28 denominator on {len(grid)} values of k1/k in [1e-2, 1e6]: "
                f"every branch increases: {increasing}; branch n stays between free and supported roots, "
                f"and supported root n < free root n+1 (gaps): {gaps}; k1/k where branch n passes the midpoint "
                f"between its free and supported roots: {', '.join(mp.nstr(c, 3) for c in crossover)}")
    ok = increasing and gaps and moves_up
    return Evidence(HOLDS if ok else ERRATUM, evidence)


def _number(value, digits=3):
    return mp.nstr(mp.mpf(str(sp.N(value, 20))), digits)


@claim("contact.hertz_coefficient", "III.1", Tex(r"k_1 = 1.82\, (E^*)^{2/3} R^{1/3} P^{1/3}", "k1 = 1.82 (E*)^(2/3) R^(1/3) P^(1/3)"),
       chapter="elastic_contact")
def _hertz():
    coeff = cm.hertz_stiffness() / (cm.E_star ** sp.Rational(2, 3) * cm.R ** sp.Rational(1, 3) * cm.P ** sp.Rational(1, 3))
    coeff = sp.nsimplify(sp.simplify(coeff))
    return _digits_verdict([(P.hertz_coefficient, mp.mpf(sp.N(coeff, 30)))],
                           say("Hertz ", Math(coeff * cm.E_star ** sp.Rational(2, 3) * cm.R ** sp.Rational(1, 3)
                                              * cm.P ** sp.Rational(1, 3), Tex(r"k_1 = dP/d\delta", "k1 = dP/d delta"))))


def _piezo_inputs():
    return {cm.C1: sp.Rational(P.PIEZO_INDENTATION["C1"]), cm.C3: sp.Rational(P.PIEZO_INDENTATION["C3"]),
            cm.R: sp.Rational(P.PIEZO_INDENTATION["R"])}


def _depth(load):
    eq = (cm.piezo_load().subs(cm.V, 0).subs(_piezo_inputs()) - load)
    return sp.nsolve(eq, cm.w0, 2e-10, prec=30)


@claim("contact.piezo_indentation_depth", "III.1",
       # in parts, so that the words between them wrap on a narrow page
       say(Tex(r"C_1^* = 403\ \mathrm{GPa}", "C1* = 403 GPa"), ", ", Tex(r"C_3^* = 15.4\ \mathrm{N/(V m)}", "C3* = 15.4 N/(V m)"),
           ", ", Tex(r"R = 50\ \mathrm{nm}", "R = 50 nm"), ", ", Tex(r"P = 100\ \mathrm{nN}", "P = 100 nN"), ": ",
           Tex(r"w_0 = 3.01\ \mathrm{\AA}", "w0 = 3.01 A")), chapter="elastic_contact")
def _piezo_depth():
    load = sp.Rational(P.PIEZO_INDENTATION["P"])
    w = _depth(load)
    w_printed = sp.Rational(P.piezo_depth_angstrom) * sp.Rational(1, 10**10)
    p_at_printed = cm.piezo_load().subs(cm.V, 0).subs(_piezo_inputs()).subs(cm.w0, w_printed)
    evidence = _digits_verdict([(P.piezo_depth_angstrom, mp.mpf(str(sp.N(w * 10**10, 20))))],
                               say(Tex("w_0", "w0"), " (Angstrom) solving the printed ", Tex("P(w_0)", "P(w0)"), " at ",
                                   Tex("V = 0", "V = 0"), " for P = 100 nN"))
    return evidence.but(sentence=say(evidence.sentence, f"; the printed 3.01 A corresponds to "
                                                        f"P = {_number(p_at_printed * 1e9, 4)} nN"))


@claim("contact.piezo_indentation_stiffness", "III.1",
       Tex(r"k_1 = R^{1/2} (2 w_0^{1/2} C_1^* - w_0^{-1/2} V C_3^*)/\pi = (993 - 63.3\, V)\ \mathrm{N/m}",
           "k1 = R^(1/2)(2 w0^(1/2) C1* - w0^(-1/2) V C3*)/pi = (993 - 63.3 V) N/m"), chapter="elastic_contact")
def _piezo_stiffness():
    stiff = sp.expand(cm.piezo_stiffness().subs(_piezo_inputs()))
    w = _depth(sp.Rational(P.PIEZO_INDENTATION["P"]))
    w_printed = sp.Rational(P.piezo_depth_angstrom) / 10**10
    at = {label: (sp.N(stiff.subs({cm.w0: ww, cm.V: 0}), 15), sp.N(stiff.diff(cm.V).subs(cm.w0, ww), 15))
          for label, ww in (("printed inputs (w0 from P = 100 nN)", w), ("printed w0 = 3.01 A", w_printed))}
    k0, kv = at["printed inputs (w0 from P = 100 nN)"]
    rows = [(f"; {lab}: ", _k1_of_bias(_number(a, 4), b)) for lab, (a, b) in at.items()]
    evidence = say(Math(sp.expand(cm.piezo_stiffness()), Tex(r"k_1 = dP/dw_0", "k1 = dP/dw0")),
                   " of the printed load law (bias term enters with + sign, the printed ", Tex("k_1", "k1"), " with -)",
                   rows, "; printed ", _k1_of_bias(P.piezo_k1[0], -sp.Float(P.piezo_k1[1])))
    ok = (digits_check(P.piezo_k1[0], mp.mpf(str(k0)))[0] and digits_check(P.piezo_k1[1], mp.mpf(str(-kv)))[0])
    return Evidence(HOLDS if ok else ERRATUM, evidence, correction="" if ok else say(
        _k1_of_bias(_number(k0, 3), kv), " for the printed inputs"))


def _k1_of_bias(k0: str, slope) -> Tex:
    """'k1 = (k0 + slope V) N/m' typeset."""
    sign, mag = ("+" if slope >= 0 else "-"), _number(abs(slope), 3)
    return Tex(rf"k_1 = ({k0} {sign} {mag}\, V)\ \mathrm{{N/m}}", f"k1 = ({k0} {sign} {mag} V) N/m")


@claim("contact.lateral_to_vertical_ratio", "III.1",
       (Tex("k_2 = 8 a G^*", "k2 = 8 a G*"), "; isotropic: ",
        Math(sp.sympify(P.lateral_ratio_formula, locals={"nu": cm.nu}), Tex("k_1/k_2", "k1/k2")), " ~ 0.85"),
       chapter="elastic_contact")
def _lateral_ratio():
    derived = sp.factor(cm.mindlin_ratio())
    printed = sp.sympify(P.lateral_ratio_formula, locals={"nu": cm.nu})
    printed_min = sp.minimum(printed, cm.nu, sp.Interval.Ropen(0, sp.Rational(1, 2)))
    nus = [sp.Rational(1, 5), sp.Rational(1, 4), sp.Rational(3, 10), sp.Rational(7, 20)]
    nu, ratio = Tex(r"\nu", "nu"), Tex("k_1/k_2", "k1/k2")
    table = [(", " if i else "", Tex(rf"\nu = {float(v):.2f}:\ k_1/k_2 = {float(derived.subs(cm.nu, v)):.3f},\ "
                                     rf"k_2/k_1 = {float(1 / derived.subs(cm.nu, v)):.3f}",
                                     f"nu={float(v):.2f}: k1/k2={float(derived.subs(cm.nu, v)):.3f}, "
                                     f"k2/k1={float(1 / derived.subs(cm.nu, v)):.3f}")) for i, v in enumerate(nus)]
    same = sp.simplify(printed - derived) == 0
    evidence = say("Hertz ", Tex("k_1 = 2aE^*", "k1 = 2aE*"), ", Mindlin ", Tex("k_2 = 8aG^*", "k2 = 8aG*"),
                   ", rigid tip, isotropic sample: ", Math(derived, ratio), "; ", table, ". The printed ",
                   Math(printed), " is at least ", printed_min, " for ", Tex(r"0 \le \nu < 1/2", "0 <= nu < 1/2"),
                   ", so it can never be 0.85")
    if same:
        return Evidence(HOLDS, evidence)
    nu_match = sp.nsolve(1 / derived - sp.Rational(P.lateral_ratio_value), cm.nu, 0.25)
    quarter = derived.subs(cm.nu, sp.Rational(1, 4))
    return Evidence(ERRATUM, evidence, correction=say(
        Math(derived, ratio), f" ({float(quarter):.2f} at ", nu, " = 0.25); the printed 0.85 is ",
        Tex("k_2/k_1", "k2/k1"), ", reached at ", nu, f" = {float(nu_match):.2f}"))


@claim("contact.local_electrostatic_amplitude", "III.1",
       Tex(r"F_{loc} = 1.4 \cdot 10^{-8}\ \mathrm{N/V},\ k_1 \approx 1000\ \mathrm{N/m}:\ A_{el} = 14\ \mathrm{pm/V}",
           "F_loc = 1.4e-8 N/V, k1 ~ 1000 N/m: A_el = 14 V pm"), chapter="elastic_contact")
def _local_amplitude():
    eps0 = mp.mpf(inputs.EPSILON_0)
    a_el = mp.mpf(P.F_loc) / mp.mpf(P.CONTACT_K1) * mp.mpf(10) ** 12
    sphere = mp.pi * eps0 * mp.mpf("50e-9") / mp.mpf("0.1e-9")      # pi eps0 R / z, sphere near a plane
    evidence = _digits_verdict([(P.A_el_pm, a_el)], say(Tex(r"A_{el} = F_{loc}/k_1", "A_el = F_loc/k1"), " in pm per volt"))
    return evidence.but(sentence=say(evidence.sentence, "; sphere-plane estimate ",
                                     Tex(r"\pi \varepsilon_0 R/z", "pi eps0 R/z"),
                                     f" = {mp.nstr(sphere, 3)} ", Tex(r"\mathrm{N/V^2}", "N/V^2"), " for R = 50 nm, z = 0.1 nm"))
