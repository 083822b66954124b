"""Section references checked against the sections' wording and content, and the numbering of
the top-level sections.

- a section: the section exists; a formula "given in" it must be displayed there, experimental
  results "presented" there must cite a figure; and the sentence must be closer in wording to
  the cited section than to any other, or at least half as close as to the closest;
- the numbering: the top-level sections are numbered I, II, III, ... without repeats.
"""
from __future__ import annotations

import math
import re
from collections import Counter
from functools import lru_cache

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS
from pfmdyn.derivations.evidence import Evidence, join, say
from . import text as T


_STOP = set("""a an the of and or in on to for is are be by with as at from that this these those it its
which can will than such into we our here below above also not no between both each any all only
more most their there when where while has have been was were may must should section sections
analyzed discussed discusses discuss presented present illustrated considered given studied
described derived detail briefly finally""".split())


def _words(text: str) -> list[str]:
    text = re.sub(r"\$[^$]*\$", " ", text)
    return [w[:6] for w in re.findall(r"[a-z][a-z\-]+", text.lower()) if w not in _STOP and len(w) > 2]


def _overview(sec) -> bool:
    """A section whose text is a table of contents of others (it would match any sentence)."""
    return sum(1 for r in T.references() if r.kind == "section" and r.section == sec.tag) >= 3


@lru_cache(maxsize=1)
def _section_vectors():
    secs = list(T.text_sections())
    docs = {s.tag: Counter(_words(s.title) * 3 + _words(s.body)) for s in secs}
    df = Counter(w for c in docs.values() for w in c)
    idf = {w: math.log(len(docs) / n) for w, n in df.items()}
    return secs, docs, idf


def _similarity(words: list[str], tag: str) -> float:
    _, docs, idf = _section_vectors()
    doc = docs[tag]
    q = Counter(words)
    dot = sum(q[w] * idf.get(w, 0) ** 2 * doc.get(w, 0) for w in q)
    nq = math.sqrt(sum((q[w] * idf.get(w, 0)) ** 2 for w in q)) or 1
    nd = math.sqrt(sum((doc[w] * idf.get(w, 0)) ** 2 for w in doc)) or 1
    return dot / (nq * nd)


def _clause(sentence: str, ref: T.Reference, target: str) -> str:
    """The part of a sentence that speaks about ``target`` (sentences listing several sections
    give each its own clause)."""
    parts = re.split(r"(?<=[IVX]\.\d)\s+and\s+(?=[a-z])|,\s+and\s+|;\s+", sentence)
    return next((p for p in parts if re.search(r"\b" + re.escape(target) + r"(?!\.?\d)", p)), sentence)


def _with_antecedent(ref: T.Reference, clause: str) -> str:
    """'This behavior is analyzed in Section X': the behaviour is named in the sentence before."""
    if re.match(r"\s*(?:This|These|Such|Here)\b", clause):
        own = next(s for s in T.sections() if s.tag == ref.section)
        i = own.sentences.index(ref.sentence)
        if i:
            return own.sentences[i - 1] + " " + clause
    return clause


def _cites_data(tag: str) -> bool:
    """Does the section cite a figure of measured data (a caption naming a sample material)?"""
    caps = T.captions()
    return any(r.kind == "figure" and any(fig in caps and "material" in T.keywords(caps[fig].text)
                                          for fig, _ in r.targets)
               for r in T.references() if r.section == tag)


MIN_SIMILARITY = 0.1      # below this no section is a clear match and wording decides nothing


def check_section(ref: T.Reference):
    secs, docs, _ = _section_vectors()
    out_verdict, notes, fixes = HOLDS, [], []
    for target in ref.targets:
        sec = T.section(target)
        if sec is None:
            return Evidence(ERRATUM, f"there is no Section {target}", correction="a section that exists")
        clause = _with_antecedent(ref, _clause(ref.sentence, ref, target))
        words = [w for w in _words(clause)]
        own = next((s for s in secs if s.tag == ref.section), None)
        others = set(ref.targets) - {target}
        # Summaries (abstract, introduction, conclusions, section overviews) resemble every sentence.
        candidates = [s for s in secs if (s is not own and not _overview(s) and s.number not in others
                                          and s.tag not in ("abstract", "I", "conclusions"))] + [sec]
        scores = {s.number: _similarity(words, s.tag) for s in candidates}
        best = max(scores, key=scores.get)
        why = say(f"Section {target} ('", T.quote(sec.title), f"'): wording similarity {scores[target]:.2f}")
        if best != target:
            why = say(why, f"; closest section {best} ('", T.quote(T.section(best).title), f"'): {scores[best]:.2f}")
        if re.search(r"\b(?:given|derived|described by)\s+in\b|\bis given in\b", clause) and "$$" not in sec.body:
            out_verdict = ERRATUM
            why = say(why, f"; the sentence says the result is given there, but Section {target} displays no equation")
            # The drives the sentence lists must all appear in the section's displayed equations.
            needed = {tok for word, tok in (("electromechanical", "d_1"), ("non-local", "q_0"),
                                            ("local", "f_0")) if word in clause}
            with_eqs = [n for n in sorted(scores, key=scores.get, reverse=True)
                        if all(tok in " ".join(re.findall(r"\$\$.*?\$\$", T.section(n).body, re.S)) for tok in needed)
                        and "$$" in T.section(n).body]
            fixes.append(f"Section {with_eqs[0]}" if with_eqs else "a section with equations")
        elif re.search(r"experimental", clause) and not _cites_data(sec.tag):
            out_verdict = ERRATUM
            why = say(why, f"; the sentence promises experimental results, but Section {target} cites no figure")
            with_figs = [n for n in sorted(scores, key=scores.get, reverse=True) if _cites_data(T.section(n).tag)]
            fixes.append(f"Section {with_figs[0]}" if with_figs else "a section with results")
        elif best != target and scores[best] >= MIN_SIMILARITY and scores[target] < 0.5 * scores[best]:
            out_verdict = ERRATUM
            why = say(why, f"; the sentence fits Section {best} better than the one cited")
            fixes.append(f"Section {best}")
        notes.append(why)
    return Evidence(out_verdict, join(notes), correction="; ".join(fixes))


# --- numbering ------------------------------------------------------------------------------------

def check_section_numbering():
    numbers = [s.number for s in T.text_sections() if re.fullmatch(r"[IVX]+", s.number)]
    expected = [k for k, v in sorted(T.ROMAN.items(), key=lambda kv: kv[1])][:len(numbers)]
    evidence = f"top-level sections printed as {', '.join(numbers)}"
    if numbers != expected:
        dup = [n for n, c in Counter(numbers).items() if c > 1]
        titles = [s.title for s in T.text_sections() if s.number in dup]
        return Evidence(ERRATUM, f"{evidence}; {', '.join(dup)} is used for {' and '.join(titles)}",
                        correction=f"{', '.join(expected)} (the last, '{titles[-1]}', is Section {expected[-1]})")
    return Evidence(HOLDS, evidence)
