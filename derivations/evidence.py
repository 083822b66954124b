"""What a check returns: its verdict with the evidence as data, never as prose to parse back.

A sentence of evidence is a tuple of parts: plain words (``str``), formulas computed by SymPy
(:class:`Math`) and formulas written as LaTeX (:class:`Tex`, e.g. quoted from the paper).
:func:`say` builds one; :func:`text` renders it as plain text (the ``pfmdyn verify`` table and
its JSON).  Typesetting (LaTeX, HTML) is done from the same parts by :mod:`pfmdyn.typeset`.

>>> import sympy as sp
>>> x = sp.Symbol("x")
>>> text(say("the derivative is ", Math(2 * x, "f'(x)"), " for all x"))
"the derivative is f'(x) = 2*x for all x"
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from enum import Enum
from typing import Union

import sympy as sp


class Outcome(str, Enum):
    """The four verdicts a check can give (compare equal to their names as strings)."""

    HOLDS = "holds"
    SIGN = "holds_up_to_sign_convention"
    ERRATUM = "erratum"
    UNDECIDABLE = "undecidable"

    def __str__(self) -> str:
        return self.value


RELATIONS = {"=": "=", "->": r"\to", ">>": r"\gg", "~": r"\sim", ">=": r"\geq", "<": "<", ">": ">",
             "!=": r"\neq", "~=": r"\approx"}
"""Relations a :class:`Math` part may state, with their LaTeX."""


@dataclass(frozen=True)
class Tex:
    """A formula given as LaTeX (``tex``), with its plain-text reading (``plain``; default ``$tex$``)."""

    tex: str
    plain: str = ""

    def text(self) -> str:
        return self.plain or f"${self.tex}$"


@dataclass(frozen=True)
class Math:
    """A SymPy formula inside a sentence: ``lhs relation expr``, or ``expr`` alone.

    ``lhs`` is a SymPy object, a :class:`Tex`, or a short string read the same in text and in
    LaTeX (``"N"``, ``"u(L)"``).
    """

    expr: object
    lhs: object = None
    relation: str = "="

    def __post_init__(self):
        if self.relation not in RELATIONS:
            raise ValueError(f"unknown relation {self.relation!r}")

    def text(self) -> str:
        body = sp.sstr(self.expr)
        if self.lhs is None:
            return body
        lhs = self.lhs.text() if isinstance(self.lhs, Tex) else (
            self.lhs if isinstance(self.lhs, str) else sp.sstr(self.lhs))
        return f"{lhs} {self.relation} {body}"


Part = Union[str, Math, Tex]
Sentence = tuple


def say(*parts) -> Sentence:
    """A sentence from words, SymPy objects (become :class:`Math`), parts and other sentences.

    >>> say("a ", sp.Integer(2), (" b", " c"))
    ('a ', Math(expr=2, lhs=None, relation='='), ' b c')
    """
    out: list = []
    for part in parts:
        if isinstance(part, (tuple, list)):
            items = list(say(*part))
        elif isinstance(part, (str, Math, Tex)):
            items = [part]
        elif isinstance(part, sp.Basic):
            items = [Math(part)]
        else:
            raise TypeError(f"not a part of a sentence: {part!r} ({type(part).__name__})")
        for item in items:
            if isinstance(item, str) and out and isinstance(out[-1], str):
                out[-1] += item
            elif item != "":
                out.append(item)
    return tuple(out)


def text(sentence: Sentence) -> str:
    """Plain text of a sentence (SymPy's ``sstr`` for the formulas)."""
    return "".join(p if isinstance(p, str) else p.text() for p in sentence)


def join(sentences, sep: str = "; ") -> Sentence:
    """Sentences joined by ``sep``."""
    out: list = []
    for i, s in enumerate(s for s in sentences if s):
        out += [sep] if i else []
        out.append(s)
    return say(*out)


def listing(exprs, sep: str = ", ") -> Sentence:
    """SymPy objects as formulas separated by ``sep`` (symbols sorted by name)."""
    items = sorted(exprs, key=str) if isinstance(exprs, (set, frozenset)) else list(exprs)
    return join([(Math(e),) for e in items], sep)


def clip(sentence: Sentence, n: int) -> Sentence:
    """The parts of ``sentence`` that start within its first ``n`` characters of plain text;
    words are cut at ``n`` and marked with an ellipsis, formulas are kept whole or dropped."""
    out, used = [], 0
    for part in sentence:
        if used >= n:
            return say(*out, "…")
        if isinstance(part, str):
            if used + len(part) > n:
                return say(*out, part[:n - used].rstrip(), "…")
            used += len(part)
        else:
            used += len(part.text())
        out.append(part)
    return say(*out)


@dataclass(frozen=True)
class Rounding:
    """A printed number against the value it should be the rounding of."""

    printed: str
    value: object                       # mpmath number, computed
    rounded: str                        # ``value`` rounded to the printed precision
    interval: tuple | None = None       # (low, high) the printed uncertainties allow
    ok: bool = True


@dataclass(frozen=True)
class Evidence:
    """The outcome of one check, as data.

    ``sentence`` is the proof; ``ratio`` the decisive comparison printed/derived
    (:class:`derivations.checks.core.Comparison`) when one decides; ``numbers`` the printed
    numbers checked against their computed values (:class:`Rounding`); ``correct`` the correct
    forms (``Math`` parts) when they are formulas, otherwise ``correction`` says in words (with
    formulas) what is right.  The printed forms are the claim's own (``@claim(..., printed)``,
    whose ``Math`` parts are the formulas as printed).  ``sign_convention`` marks evidence that
    turns on the signs of f0, q0 or d1.
    """

    verdict: Outcome
    sentence: Sentence = ()
    ratio: object = None
    numbers: tuple = ()
    correct: tuple = ()
    correction: Sentence = ()
    sign_convention: bool = False

    def __post_init__(self):
        object.__setattr__(self, "verdict", Outcome(self.verdict))
        object.__setattr__(self, "sentence", say(self.sentence))
        object.__setattr__(self, "correction", say(self.correction))
        forms = tuple(self.correct)
        if not all(isinstance(f, Math) for f in forms):
            raise TypeError("correct forms must be Math parts")
        object.__setattr__(self, "correct", forms)

    @property
    def proof(self) -> Sentence:
        """The sentence, followed by the decisive ratio in words when there is one."""
        if self.ratio is None:
            return self.sentence
        return join([self.sentence, self.ratio.sentence()])

    def evidence_text(self) -> str:
        return text(self.proof)

    def correct_text(self) -> str:
        """The correct form(s) as plain text (empty when the claim holds)."""
        if self.correction:
            return text(self.correction)
        return ", ".join(m.text() for m in self.correct)

    def but(self, **changes) -> "Evidence":
        """A copy with some fields changed (e.g. more words in the sentence)."""
        return replace(self, **changes)
