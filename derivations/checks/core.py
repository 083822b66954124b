"""Verdict registry and the comparison tools every check uses.

A check is a function decorated with :func:`claim`; it computes and returns a
:class:`~derivations.evidence.Evidence` (:func:`run_check` makes it a :class:`Verdict`).
Comparisons are always done two ways: exactly (ratio of canonical
trigonometric normal forms, see :func:`derivations.trig.normal_form`) and by
50-digit evaluation at seeded random parameter points.  A new check, in one of the modules
of this package (formulas as SymPy objects or ``Tex``, never written into the words)::

    @claim("eq20.pinned_response", "III.3, Eqs. 19-20", Math(P.theta_nlc, Tex(r"\theta_{nlc}", "theta_nlc")),
           chapter="pinned")
    def _eq20():
        cmp = compare(P.theta_nlc, derived)
        return Evidence(HOLDS if cmp.is_(1) else ERRATUM, say("derived ", Math(derived, "theta")), ratio=cmp,
                        correct=() if cmp.is_(1) else (Math(derived),))

then ``pfmdyn verify --record`` after review and ``pfmdyn verify --errata generated/errata.md``.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, Iterable

import mpmath as mp
import sympy as sp

from ..beam import beta
from ..paper.convention import SIGN_CONVENTION
from ..trig import ATOMS, from_atoms, normal_form, to_atoms
from ..evidence import Evidence, Math, Outcome, Sentence, Tex, join, say, text

HOLDS, SIGN, ERRATUM, UNDECIDABLE = Outcome.HOLDS, Outcome.SIGN, Outcome.ERRATUM, Outcome.UNDECIDABLE
VERDICTS = tuple(Outcome)


@dataclass(frozen=True)
class Verdict:
    """The outcome of one claim check: the claim (id, where, as printed) and its :class:`Evidence`."""

    id: str
    where: Sentence
    proof: Evidence
    printed: Sentence = ()
    chapter: str = ""
    kind: str = "claim"

    @property
    def verdict(self) -> Outcome:
        return self.proof.verdict

    @property
    def evidence(self) -> str:
        """The proof as plain text, with the sign convention when the evidence turns on it."""
        words = self.proof.evidence_text()
        return f"{words}; sign convention: {SIGN_CONVENTION}" if self.proof.sign_convention else words

    @property
    def correct(self) -> str:
        return self.proof.correct_text()

    def as_dict(self) -> dict:
        """Plain-text fields (the JSON of ``pfmdyn verify --json``)."""
        return {"id": self.id, "where": text(self.where), "verdict": str(self.verdict), "kind": self.kind,
                "chapter": self.chapter, "correct": self.correct, "evidence": self.evidence,
                "printed": text(self.printed)}


@dataclass(frozen=True)
class Check:
    id: str
    where: Sentence
    printed: Sentence
    run: Callable[[], Evidence]
    chapter: str = ""
    kind: str = "claim"


REGISTRY: dict[str, Check] = {}


def claim(claim_id: str, where, printed, *, chapter: str = "", kind: str = "claim"):
    """Register a check: a function of no arguments returning its :class:`Evidence`.

    ``where`` and ``printed`` are words or sentences (:func:`derivations.evidence.say`)
    naming the place in the paper and what it prints.  ``chapter`` names the book page that
    discusses the claim; ``kind`` is ``claim`` for the shared registry's ids, ``cross-reference``,
    ``symbol`` or ``statement`` for the text audit.
    """
    def wrap(fn: Callable[[], Evidence]):
        if claim_id in REGISTRY:
            raise ValueError(f"claim {claim_id!r} registered twice")
        REGISTRY[claim_id] = Check(claim_id, say(where), say(printed), fn, chapter, kind)
        return fn
    return wrap


_RESULTS: dict[str, "Verdict"] = {}


def clear_results() -> None:
    """Forget the verdicts computed so far (a new run starts from scratch)."""
    _RESULTS.clear()


def result(claim_id: str) -> "Verdict":
    """The verdict of a registered claim, computed once per run (statements reuse registry checks)."""
    if claim_id not in _RESULTS:
        _RESULTS[claim_id] = run_check(REGISTRY[claim_id])
    return _RESULTS[claim_id]


def run_check(check: Check) -> Verdict:
    evidence = check.run()
    if not isinstance(evidence, Evidence):
        raise TypeError(f"{check.id}: a check returns Evidence, not {type(evidence).__name__}")
    return Verdict(check.id, check.where, evidence, check.printed, check.chapter, check.kind)


# --- comparing expressions -----------------------------------------------------------------

DIGITS = 50
N_POINTS = 20


def random_points(symbols: Iterable[sp.Symbol], n: int = N_POINTS, seed: int = 2006,
                  beta_range=(0.05, 25.0)) -> list[dict]:
    """Seeded random parameter points; ``beta`` log-uniform, other symbols in [0.2, 5]."""
    rng = random.Random(seed)
    symbols = sorted(set(symbols), key=str)
    points = []
    for _ in range(n):
        point = {}
        for sym in symbols:
            if sym == beta:
                lo, hi = beta_range
                point[sym] = mp.mpf(lo) * (mp.mpf(hi) / lo) ** mp.mpf(rng.random())
            else:
                point[sym] = mp.mpf(rng.uniform(0.2, 5.0)) * (1 if sym.is_positive else rng.choice((-1, 1)))
        points.append(point)
    return points


def evaluate(expr: sp.Expr, point: dict) -> mp.mpc:
    """Evaluate with ``DIGITS`` significant digits (mpmath, exact inputs)."""
    return _evaluator(sp.sympify(expr), tuple(point))(point)


@lru_cache(maxsize=4096)
def _evaluator(expr: sp.Expr, symbols: tuple):
    """One mpmath function per expression and symbol order (lambdify is the slow step)."""
    f = sp.lambdify(list(symbols), expr, "mpmath")

    def at(point: dict) -> mp.mpc:
        with mp.workdps(DIGITS + 10):
            return mp.mpmathify(f(*(point[s] for s in symbols)))
    return at


@dataclass
class Comparison:
    """printed / derived, computed exactly and numerically."""

    exact_ratio: sp.Expr | None
    numeric_ratios: list = field(default_factory=list)

    @property
    def constant(self) -> bool:
        r = self.numeric_ratios
        return bool(r) and max(abs(v - r[0]) for v in r) <= mp.mpf(10) ** (-(DIGITS - 10)) * max(1, abs(r[0]))

    @property
    def spread(self) -> float:
        r = self.numeric_ratios
        return float(max(abs(v - r[0]) for v in r)) if r else float("nan")

    def is_(self, value) -> bool:
        """True when the ratio is exactly ``value`` (both exact and at every point)."""
        # the 50-digit test first: when it fails, the costly exact simplification is not needed
        numeric_ok = all(abs(v - complex(value)) < mp.mpf(10) ** (-(DIGITS - 10)) for v in self.numeric_ratios)
        return numeric_ok and self.exact_ratio is not None and sp.simplify(self.exact_ratio - value) == 0

    def sentence(self) -> Sentence:
        """The comparison in words and formulas: the exact ratio, then its 50-digit values (a ratio
        that is not constant is described by the range of its values, not written out)."""
        if self.constant:
            exact = "n/a" if self.exact_ratio is None else Math(self.exact_ratio)
            num = f"{mp.nstr(self.numeric_ratios[0], 8)} at all {len(self.numeric_ratios)} points"
        else:
            exact = "n/a" if self.exact_ratio is None else "not constant"
            vals = sorted(float(abs(v)) for v in self.numeric_ratios)
            num = f"|ratio| varies from {vals[0]:.3g} to {vals[-1]:.3g}"
        return say("printed/derived: exact ", exact, f"; {DIGITS}-digit {num}")

    def summary(self) -> str:
        return text(self.sentence())


def _atom_form(expr: sp.Expr) -> sp.Expr:
    num, den = sp.fraction(sp.together(sp.sympify(expr)))
    return normal_form(to_atoms(num, beta)) / normal_form(to_atoms(den, beta))


def compare(printed: sp.Expr, derived: sp.Expr, seed: int = 2006) -> Comparison:
    """Ratio printed/derived: exact (normal forms, cancelled) and at random 50-digit points."""
    ratio = sp.cancel(_atom_form(printed) / _atom_form(derived))
    exact = from_atoms(ratio, beta)
    syms = (sp.sympify(printed).free_symbols | sp.sympify(derived).free_symbols)
    values = []
    for point in random_points(syms, seed=seed):
        p, d = evaluate(printed, point), evaluate(derived, point)
        values.append(p / d)
    return Comparison(exact if not ratio.has(*ATOMS.functions) else None, values)


def describe(expr: sp.Expr) -> sp.Expr:
    """Compact (factored) form of an expression for the evidence and errata."""
    return sp.factor(expr)


def digits_check(printed: str, value) -> tuple[bool, str]:
    """Is the printed decimal the correctly rounded ``value`` at the printed precision?"""
    dec = printed.split(".")[1] if "." in printed else ""
    q = mp.mpf(10) ** (-len(dec))
    rounded = mp.nint(mp.mpf(value) / q) * q
    text = f"{float(rounded):.{len(dec)}f}"
    return text == printed, text


def sign_flip_verdict(anchors: dict, convention) -> tuple[Outcome, Sentence]:
    """Verdict for a printed result that is exactly minus the derived one.

    ``anchors`` maps the paper's own related printed results (same quantity, same boundary
    conditions; words or sentences) to whether their sign agrees with the derivation.  If any
    does, the printed sign contradicts the paper itself: an erratum.  Otherwise the flip is a
    convention (``convention``, words or a sentence, says which).
    """
    agreeing = [say(name) for name, agrees in anchors.items() if agrees]
    if agreeing:
        return ERRATUM, say("overall sign opposite to the derivation and to the paper's own ", join(agreeing, ", "))
    return SIGN, say("overall sign opposite to the derivation; convention: ", convention)


def same_resonances(a: sp.Expr, b: sp.Expr) -> tuple[bool, Sentence]:
    """Do two characteristic functions have the same zeros for beta > 0?

    True when their exact ratio is free of cos, sin, cosh, sinh and, as a rational
    function of beta, has neither zeros nor poles at positive beta.
    """
    ratio = sp.cancel(_atom_form(a) / _atom_form(b))
    if ratio.has(*ATOMS.functions):
        return False, say("ratio contains trigonometric terms")
    num, den = sp.fraction(sp.factor(ratio))
    for part in (num, den):
        poly = sp.Poly(part, beta)
        if any(r.is_positive for r in sp.real_roots(poly)) if poly.degree() > 0 else False:
            return False, say("ratio ", ratio, " vanishes or diverges at positive ", Tex(r"\beta", "beta"))
    return True, say("ratio ", ratio, " has no zero or pole at ", Tex(r"\beta > 0", "beta > 0"))
