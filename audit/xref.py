"""Every cross-reference of the paper's text checked against its target.

References are extracted by :mod:`pfmdyn.audit.text` (ids ``xref.<section>.<n>``, in order
of appearance within a section; symbols ``symbol.<section>.<n>`` by first use; the numbering
of sections and equations ``structure.*``).  A reference is checked against what its target
contains:

- a figure or panel: the panel exists in the caption's list, and every panel cited agrees with
  the caption on each property the sentence names (material, contact regime, vertical/lateral,
  amplitude/phase, grain, cantilever, kind of plot);
- a section: the section exists; a formula "given in" it must be displayed there, experimental
  results "presented" there must cite a figure; and the sentence must be closer in wording to
  the cited section than to any other, or at least half as close as to the closest;
- an equation: the label exists; the equation (with the ones printed under its "where") holds
  the symbols a limit in the sentence sends somewhere, the boundary-condition family a
  "free"/"clamped" reference needs, the trigonometric denominator a resonance needs, a bias
  dependence needs an electrostatic drive that the sentence did not set to zero;
- a table: the table exists and has as many rows as the sentence counts;
- a symbol: it is defined (or used consistently), is not a one-off misspelling of another
  symbol, and is not defined twice with conflicting meanings.
"""
from __future__ import annotations

import math
import re
from collections import Counter
from functools import lru_cache

from pfmdyn.derivations import families as registry
from . import text as T
from pfmdyn.derivations.checks.core import ERRATUM, HOLDS, UNDECIDABLE, claim
from pfmdyn.derivations.evidence import Evidence, Tex, join, say

CHAPTER = "audit"


# --- figures -------------------------------------------------------------------------------------

def _describe(caption, panel: str) -> str:
    d = caption.described.get(panel, {})
    return ", ".join(f"{cat} {'/'.join(sorted(w))}" for cat, w in sorted(d.items())) or "no property named"


def check_figure(ref: T.Reference):
    caps = T.captions()
    problems, notes, fixes = [], [], []
    named = T.keywords(ref.context)
    for fig, panels in ref.targets:
        cap = caps.get(fig)
        if cap is None:
            return Evidence(ERRATUM, f"no caption for Fig. {fig} (captions exist for {sorted(caps)})",
                            correction="a figure that exists")
        missing = [p for p in panels if p not in cap.panels]
        if missing:
            listed = ",".join(cap.panels) or "none"
            problems.append(f"Fig. {fig} has no panel {','.join(missing)} (caption lists panels {listed})")
            fits = [p for p in cap.panels if all(cap.described.get(p, {}).get(c, set()) & w for c, w in named.items())]
            fixes.append(f"Fig. {fig} {','.join(fits)}" if named and fits else
                         f"a panel of Fig. {fig} among {listed}")
            continue
        cited = panels or tuple(cap.described) or ("",)
        for cat, words in named.items():
            described = {p: cap.described.get(p, {}).get(cat) for p in cited}
            described = {p: w for p, w in described.items() if w}
            if not described:
                continue
            if panels:
                wrong = [p for p, w in described.items() if not (w & words)]
            else:                        # the whole figure: one panel agreeing is enough
                wrong = [] if any(w & words for w in described.values()) else list(described)
            if wrong:
                fits = [p for p in cap.panels if cap.described.get(p, {}).get(cat, set()) & words]
                fixes.append(f"Fig. {fig} {','.join(fits)}" if fits else f"a figure whose caption shows {'/'.join(sorted(words))}")
                problems.append(f"the sentence names {cat} {'/'.join(sorted(words))}, but the caption of Fig. {fig} "
                                f"gives " + "; ".join(f"panel {p}: {'/'.join(sorted(described[p]))}" for p in wrong)
                                + (f" (panels with {'/'.join(sorted(words))}: {','.join(fits)})" if fits else ""))
            else:
                notes.append(f"{cat} {'/'.join(sorted(words))} agrees with the caption")
        if panels:
            notes.append("caption: " + "; ".join(f"{p}: {_describe(cap, p)}" for p in panels))
    if problems:
        return Evidence(ERRATUM, "; ".join(problems), correction="; ".join(dict.fromkeys(fixes)))
    return Evidence(HOLDS, "; ".join(notes) or "the figure exists; the sentence names no property the caption describes")


# --- sections ------------------------------------------------------------------------------------

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


# --- tables --------------------------------------------------------------------------------------

_NUMBER_WORDS = {"two": 2, "three": 3, "four": 4, "five": 5, "six": 6}


def check_table(ref: T.Reference):
    number = ref.targets[0]
    number = str(T.ROMAN.get(number, number))
    sec = T.section(f"table{number}")
    if sec is None:
        return Evidence(ERRATUM, f"there is no Table {number}", correction="a table that exists")
    rows = [line for line in re.findall(r"\|\s*([A-Z])\s*\|", sec.body)]
    m = re.search(r"\b(" + "|".join(_NUMBER_WORDS) + r")\s+(\w+)", ref.sentence)
    evidence = f"Table {number} exists (rows {', '.join(rows)})"
    if ref.targets[0] != number:
        # Roman and Arabic numerals name the same table (journals print either): a style difference.
        evidence += f"; cited as {ref.text} (Roman numeral), headed Table {number}: the same number"
    if m and m.group(2).rstrip("s")[:6] in sec.body.lower():
        if _NUMBER_WORDS[m.group(1)] != len(rows):
            return Evidence(ERRATUM, f"{evidence}; the sentence counts {m.group(1)} {m.group(2)}",
                            correction=f"{len(rows)} {m.group(2)}")
        evidence += f"; the sentence counts {m.group(1)} {m.group(2)}, the table has {len(rows)} rows"
    return Evidence(HOLDS, evidence)


# --- equations -------------------------------------------------------------------------------------

_TRIG = re.compile(r"\\(?:sin|cos|tan|sinh|cosh)")


def _number(label: str) -> int:
    return int(re.match(r"\d+", label).group())


@lru_cache(maxsize=1)
def _solved() -> dict[int, tuple[str, range]]:
    """Equation number -> (the derivation that solves it, the numbers of its family's equations),
    from the family registry (``derivations/families.py``: ``equations`` such as 'Eqs. 27-28')."""
    out = {}
    for fam in registry.FAMILIES:
        m = re.fullmatch(r"Eqs?\. (\d+)(?:-(\d+))?", fam.equations)
        if m:
            numbers = range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1)
            out.update({n: (fam.derivation, numbers) for n in numbers})
    return out


@lru_cache(maxsize=1)
def _families() -> dict[str, str]:
    """Equation label -> the tip boundary condition it was solved with: the derivation the family
    registry names for its number, else the last boundary condition printed before it in its
    section (read from the printed conditions)."""
    family, out, section = "", {}, None
    for label in sorted(T.equations(), key=lambda s: (_number(s), s)):
        tex = T.equations()[label]
        if T.equation_section(label) != section:       # a family never carries over into another section
            family, section = "", T.equation_section(label)
        if re.search(r"u_0'*\(0\)", tex) and "(L)" not in tex:
            out[label] = "boundary condition"
        elif re.search(r"u_0'*\(L\)", tex) and "=" in tex:
            if "u_0(L) = 0" in tex:
                family = "pinned"
            elif "k_1" in tex or "k_2" in tex:
                family = "elastic_contact"
            elif "f_l" in tex:
                family = "sliding_friction"
            elif "f_0" in tex:
                family = "free_end"
            out[label] = "boundary condition"
        else:
            out[label] = _solved().get(_number(label), (family,))[0]
    return out


def _content(label: str) -> str:
    """The printed equation and, for the first equation of a family in the registry, the ones
    displayed under its 'where' (Eq. 5 with Eqs. 6-10)."""
    eqs = T.equations()
    tex = eqs.get(label, "")
    numbers = _solved().get(_number(label), ("", range(0)))[1]
    if label == str(numbers.start):
        tex += " ".join(eqs.get(str(i), "") for i in numbers[1:])
    return tex


def _labels(target: str) -> list[str]:
    eqs = T.equations()
    return [target] if target in eqs else [lab for lab in eqs if re.fullmatch(re.escape(target) + r"[a-f]", lab)]


def _before(ref: T.Reference) -> str:
    """The words between the previous equation reference of the sentence and this one."""
    starts = [r.start + len(r.text) for r in T.references()
              if r.sentence == ref.sentence and r.kind == "equation" and r.start < ref.start]
    return ref.sentence[max(starts, default=0):ref.start]


def _owns_phrase(ref: T.Reference, pattern: str) -> bool:
    """Does a phrase of the sentence speak about this reference (the nearest one before it,
    or the first one after it when none precedes)?"""
    eq_refs = [r for r in T.references() if r.sentence == ref.sentence and r.kind == "equation"] or [ref]
    for m in re.finditer(pattern, ref.sentence):
        before = [r for r in eq_refs if r.start < m.start()]
        owner = max(before, key=lambda r: r.start) if before else min(eq_refs, key=lambda r: r.start)
        if owner.start == ref.start:
            return True
    return False


def check_equation(ref: T.Reference):
    sentence = re.sub(r"\$\$.*?\$\$", " ", ref.sentence)
    sentence = re.sub(r"(?:below|above|near|far from) the (?:first )?resonan\w*", " ", sentence)
    notes, problems, fixes = [], [], []
    for target in ref.targets:
        labels = _labels(target)
        if not labels:
            return Evidence(ERRATUM, f"no equation is printed with label ({target})", correction="an equation that exists")
        tex = " ".join(_content(lab) for lab in labels)
        family = _families().get(labels[0], "")
        for sym in re.findall(r"\$([^$]*?)\\to", re.sub(r"\$\$.*?\$\$", " ", _before(ref))):
            sym = sym.strip().split("=")[-1].strip()
            if sym and sym not in tex:
                problems.append(say("the sentence takes ", Tex(sym), f" to a limit, but Eq. ({target}) has no ", Tex(sym)))
                fixes.append(say("an equation containing ", Tex(sym)))
        free_ref = _owns_phrase(ref, r"free cantilever")
        if free_ref and family not in ("free_end", "elastic_contact", ""):
            free = [lab for lab, fam in _families().items() if fam == "free_end"]
            fixes.append(say(f"Eq. ({', '.join(free)})"))
            problems.append(say(f"the sentence needs a free cantilever, but Eq. ({target}) is solved with the "
                            f"{family.replace('_', ' ')} tip conditions (free-end solution: Eq. ({', '.join(free)}))"))
        elif free_ref:
            notes.append(say(f"Eq. ({target}) is solved with {family.replace('_', ' ') or 'its own'} tip conditions ",
                             ("(the free end is its ", Tex("k_1 = k_2 = 0"), " case)") if family == "elastic_contact" else ""))
        if re.search(r"clamped end", sentence) and family == "boundary condition" and "(0)" not in tex:
            problems.append(say(f"Eq. ({target}) is not a condition at the clamped end ", Tex("x = 0")))
            fixes.append(say("Eq. (3a,b)"))
        if re.search(r"resonan|roots|denominator", sentence) and family != "boundary condition":
            if not _TRIG.search(tex):
                problems.append(say(f"the sentence needs resonances, but Eq. ({target}) has no frequency-dependent denominator"))
                fixes.append(say("an equation with a resonant denominator"))
            else:
                notes.append(say(f"Eq. ({target}) has a trigonometric (resonant) denominator"))
        if re.search(r"potential difference|\\Delta V|bias", sentence) and family not in ("boundary condition",):
            zeroed = set(re.findall(r"\$(f|f_0|q_0|d_1)\s*=\s*0\$", sentence))
            drives = {d for d in ("f_0", "q_0") if d in tex} - {("f_0" if z == "f" else z) for z in zeroed}
            if re.search(r"\\Delta V|potential difference", sentence) and not drives and re.search(r"calculated|according", sentence):
                with_q0 = [lab for lab in T.equations() if "q_0" in _content(lab) and _TRIG.search(_content(lab))
                           and _families().get(lab) not in ("boundary condition",)]
                fixes.append(say("an equation with the distributed load ", Tex("q_0"),
                                 f", e.g. Eq. ({with_q0[0]})" if with_q0 else ""))
                present = [Tex(d) for d in ("f_0", "q_0") if d in tex]
                problems.append(say(f"the sentence computes a bias dependence from Eq. ({target}), whose electrostatic "
                                    "drives ", join([(t,) for t in present], ", ") or "none", " the sentence sets "
                                    "to zero or lacks (no ", Tex("q_0"), ": no non-local term)"))
        purely = re.findall(r"purely (electromechanical|electrostatic)", sentence)
        if len(set(purely)) == 1 and family not in ("boundary condition",):
            drives = {d for d in ("d_1", "f_0", "q_0") if d in tex}
            want = {"electromechanical": {"d_1"}, "electrostatic": {"f_0", "q_0"}}[purely[0]]
            if drives and not drives <= want:
                problems.append(say(f"Eq. ({target}) has drives ", _drives(drives), f", not only {purely[0]} ones"))
                fixes.append(say(f"Eq. ({target}) with the other drives set to zero"))
            else:
                notes.append(say(f"Eq. ({target}) drives: ", _drives(drives), f" ({purely[0]})"))
        if re.search(r"boundary condition", sentence) and family == "boundary condition":
            for term in re.findall(r"u_0'+\(L\)", sentence):
                if term not in tex:
                    problems.append(say(f"Eq. ({target}) does not contain ", Tex(term)))
                    fixes.append(say("the boundary condition on ", Tex(term)))
            terms = sorted(set(re.findall(r"u_0'*\([L0]\)", tex)))
            notes.append(say(f"Eq. ({target}) is a boundary condition on ", _drives(terms)))
        notes.append(say(f"Eq. ({target}) printed in Section {T.equation_section(labels[0])}"))
    if problems:
        return Evidence(ERRATUM, join(problems), correction=join(dict.fromkeys(fixes)))
    return Evidence(HOLDS, join(dict.fromkeys(notes)))


def _drives(names) -> tuple:
    """LaTeX names (``d_1``, ``u_0(L)``) as formulas, sorted, separated by commas."""
    return join([(Tex(n),) for n in sorted(names)], ", ")


# --- symbols -----------------------------------------------------------------------------------------

def _split(symbol: str) -> tuple[str, str, bool]:
    m = re.match(r"(\\tilde\{(\\?[A-Za-z]+)\}|\\?[A-Za-z]+)(?:_\{?([^{}]*)\}?)?$", symbol)
    if not m:
        return symbol, "", False
    tilde = bool(m.group(2))
    return (m.group(2) if tilde else m.group(1)), m.group(3) or "", tilde


def _edit(a: str, b: str) -> int:
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i]
        for j, cb in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb)))
        prev = cur
    return prev[-1]


def _neighbours(symbol: str) -> list[str]:
    """Symbols used more than once that this one-off symbol is one edit away from."""
    base, sub, tilde = _split(symbol)
    out = []
    for other, use in T.symbols().items():
        if other == symbol or use.uses < 2:
            continue
        ob, osub, otilde = _split(other)
        if ob != base:
            continue
        if tilde == otilde and len(sub) >= 2 and len(osub) >= 2 and _edit(sub, osub) == 1:
            out.append(other)
        elif tilde != otilde and sub == osub:
            out.append(other)
        elif tilde and otilde and not sub and osub:
            out.append(other)
    return out


def _used_in(symbol: str, tag: str) -> bool:
    sec = next((s for s in T.sections() if s.tag == tag), None)
    return bool(sec) and any(T.canonical(m.group(0)) == symbol for m in re.finditer(r"\\?[A-Za-z]+_(?:\{[^{}]+\}|.)", sec.body))


def _definitions(symbol: str) -> list[str]:
    """Right-hand sides printed as '$symbol = ...$' anywhere in the text."""
    pat = re.compile(r"\$\s*" + re.escape(symbol).replace(r"_", r"_\{?") + r"\}?\s*=\s*([^$]+)\$")
    # A value or a condition ("d_1 = d_2 = 0", "k = 2.4") sets the symbol; it does not define it.
    value = re.compile(r"^(?:[^=]*=\s*)?[-+\d.\s]*$")
    return [m.group(1) for s in T.text_sections() for m in pat.finditer(s.body) if not value.match(m.group(1))]


_TOKEN = re.compile(r"(?:\\[A-Za-z]+|[A-Za-z])_(?:\{[^{}]+\}|[A-Za-z0-9])")


def _meaning_clash(symbol: str, defs: list[str]):
    """Two definitions of one symbol that mean different things: their right-hand sides use
    different capacitance gradients (G_loc vs G_nl), or share no subscripted symbol at all."""
    for i, a in enumerate(defs):
        for b in defs[i + 1:]:
            ta = {T.canonical(x) for x in _TOKEN.findall(a)}
            tb = {T.canonical(x) for x in _TOKEN.findall(b)}
            gradients = [(x, y) for x in ta for y in tb if x[:2] == y[:2] == "G_" and x != y]
            if gradients:
                return a, b, f"{gradients[0][0]} vs {gradients[0][1]}"
            if ta and tb and not ta & tb:
                return a, b, f"{'/'.join(sorted(ta))} vs {'/'.join(sorted(tb))}"
    return None


def _condition_before(symbol: str) -> str | None:
    """The previous sentence when it states an inequality on the plain symbol (``$k \\gg ...$``)."""
    base = _split(symbol)[0]
    for sec in T.text_sections():
        for i, sentence in enumerate(sec.sentences):
            if re.search(re.escape(symbol).replace("_", r"_\{?"), sentence) and i:
                prev = sec.sentences[i - 1]
                if re.search(r"\$\s*" + re.escape(base) + r"\s*(?:\\gg|>|\\geq)", prev):
                    return prev
    return None


def _quote_definition(symbol: str, rhs: str) -> tuple:
    """A definition for the evidence: the equation number of a displayed one, else the formula."""
    tag = re.search(r"\\tag\{([^}]*)\}|\\quad\s*\((\d+[a-f]?)\)", rhs)
    if tag:
        return say(Tex(symbol), f" of Eq. ({tag.group(1) or tag.group(2)})")
    rhs = rhs.strip()
    return say(Tex(f"{symbol} = {rhs}")) if len(rhs) <= 80 else say(Tex(symbol), f" = (a {len(rhs)}-character formula)")


def _clash_reason(why: str) -> tuple:
    """'G_{loc} vs G_{nl}' as formulas."""
    return join([(Tex(x),) for x in why.split(" vs ")], " vs ")


def check_symbol(symbol: str):
    use = T.symbols()[symbol]
    defs = _definitions(symbol)
    clash = _meaning_clash(symbol, defs)
    if clash:
        a, b, why = clash
        base = _split(symbol)[0]
        subs = {re.sub(r"[^a-z]", "", x.split("_")[1]) for x in why.split(" vs ") if "_" in x}
        alt = [o for o in T.symbols() if _split(o)[0] == base and _split(o)[1] in subs and o != symbol]
        fix = say(Tex(alt[0]), " in the definition with ", _clash_reason(why)) if alt else "a distinct symbol for each meaning"
        return Evidence(ERRATUM, say(Tex(symbol), " is defined with different meanings: ",
                                     join([_quote_definition(symbol, d) for d in (a, b)], " and "),
                                     " (", _clash_reason(why), ")"), correction=fix)
    if use.uses == 1 and use.definition:
        base = _split(symbol)[0]
        mine = [d.strip() for d in defs]
        other = [d for d in _definitions(base) if any(m and m in d for m in mine)]
        if other:
            return Evidence(ERRATUM, say(Tex(f"{symbol} = {mine[0]}"), " is the definition of ", Tex(base), " (",
                                         Tex(f"{base} = {other[0].strip()}"), ") under another name, used once; the "
                                         "formula that follows uses ", Tex(base)), correction=Tex(base))
    near = _neighbours(symbol) if use.uses == 1 and not use.definition else []
    # The likeliest intended symbol: one used in the same section, then one whose subscript the misprint contains.
    near.sort(key=lambda n: (T.symbols()[n].section != use.section and not _used_in(n, use.section),
                             _split(n)[1] not in _split(symbol)[1]))
    if near:
        return Evidence(ERRATUM, say(Tex(symbol), f" is used once (Section {use.section}) and never defined; it is one "
                                     "edit away from ", join([(Tex(n), f" (used {T.symbols()[n].uses} times)") for n in near],
                                                             ", ")), correction=Tex(near[0]))
    if use.definition:
        return Evidence(HOLDS, say("defined: \"", T.quote(T.clip(use.definition, 160)), "\""))
    condition = _condition_before(symbol) if use.uses == 1 else None
    if condition:
        return Evidence(ERRATUM, say(Tex(symbol), " is used once and never defined; the sentence before states the "
                                     "condition on ", Tex(_split(symbol)[0]), ": \"", T.quote(T.clip(condition, 120)), "\""),
                        correction=Tex(_split(symbol)[0]))
    if use.uses >= 2:
        return Evidence(HOLDS, f"used {use.uses} times with one meaning, first in Section {use.section}; not a variant "
                               "of another symbol")
    return Evidence(UNDECIDABLE, f"used once (Section {use.section}) without an explicit definition; no symbol it "
                                 "could be a misprint of")


# --- numbering --------------------------------------------------------------------------------------

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


def check_equation_numbering():
    labels = sorted(T.equations(), key=lambda s: (int(re.match(r"\d+", s).group()), s))
    numbers = sorted({int(re.match(r"\d+", lab).group()) for lab in labels})
    gaps = [n for n in range(1, max(numbers) + 1) if n not in numbers]
    letter_gaps = []
    for n in numbers:
        letters = sorted(lab[len(str(n)):] for lab in labels if re.fullmatch(rf"{n}[a-f]?", lab) and lab != str(n))
        if letters:
            want = [chr(c) for c in range(ord("a"), ord(letters[-1]) + 1)]
            letter_gaps += [f"{n}{x}" for x in want if x not in letters]
    evidence = f"{len(labels)} labels, equations 1-{max(numbers)}; missing numbers: {gaps or 'none'}; " \
               f"missing sub-labels: {letter_gaps or 'none'}"
    if gaps or letter_gaps:
        relabel = []
        for gap in letter_gaps:
            n, letter = re.match(r"(\d+)([a-f])", gap).groups()
            later = [lab for lab in labels if re.fullmatch(rf"{n}[a-f]", lab) and lab[-1] > letter]
            if later:
                relabel.append(f"({later[0]}) should be ({gap})")
        return Evidence(ERRATUM, evidence, correction="; ".join(relabel) or "number the equations without gaps")
    return Evidence(HOLDS, evidence)


def check_caption_panels(number: int):
    """Within one caption: panel groups that share a property split the panels without gaps."""
    cap = T.captions()[number]
    problems, missing = [], set()
    for cat in sorted({c for d in cap.described.values() for c in d}):
        covered = [p for p in cap.panels if cat in cap.described.get(p, {})]
        if len(covered) < 4:
            continue
        gaps = [p for p in cap.panels if covered[0] < p < covered[-1] and p not in covered]
        if gaps:
            missing.update(gaps)
            problems.append(f"{cat}: panels {','.join(covered)} are described, panel {','.join(gaps)} "
                            f"(listed in the caption) is not")
    if problems:
        fixes = []
        for m in re.finditer(r"\(([a-l])\s*[-–]\s*([a-l])\)", cap.text):
            before = chr(ord(m.group(1)) - 1)
            if before in missing:
                fixes.append(f"({m.group(1)}-{m.group(2)}) should read ({before}-{m.group(2)})")
        return Evidence(ERRATUM, f"caption of Fig. {number}: " + "; ".join(problems),
                        correction="; ".join(fixes) or "describe every listed panel")
    return Evidence(HOLDS, f"caption of Fig. {number}: panels {','.join(cap.panels) or '(one)'}; every described "
                           "property covers its panels without gaps")


_UNIT = r"(?:[kMG]?Hz|m?V|[nμpm]m|pm/V|N/m|%|°|Å)"


def check_units():
    """Every measured value with an uncertainty (x ± y) carries a unit."""
    bare = []
    for sec in T.text_sections():
        for m in re.finditer(r"([\d.]+\s*(?:±|\\pm)\s*[\d.]*\d)", sec.body):
            after = sec.body[m.end():m.end() + 12].lstrip("$ ")
            if not re.match(_UNIT, after):
                bare.append(f"Section {sec.number}: '{m.group(1)}' followed by '{after[:8].strip()}'")
    if bare:
        units = Counter(re.findall(r"(?:±|\\pm)\s*[\d.]+\s*\$?\s*(" + _UNIT + ")", " ".join(s.body for s in T.text_sections())))
        unit = units.most_common(1)[0][0] if units else "a unit"
        return Evidence(ERRATUM, "values with an uncertainty but no unit: " + "; ".join(bare),
                        correction=f"add the unit ({unit}, the unit of the other values with uncertainties)")
    return Evidence(HOLDS, say("every value ", Tex(r"x \pm y", "x ± y"), " in the text carries a unit"))


def check_citations():
    """References are numbered in order of first citation; an author named before a citation
    appears in the entry (for the entries the transcription contains)."""
    cites = T.citations()
    first: list[int] = []
    for _, numbers, _ in cites:
        first += [n for n in numbers if n not in first]
    out_of_order = [(a, b) for a, b in zip(first, first[1:]) if b < a]
    bib = T.bibliography()
    named, wrong = [], []
    for tag, numbers, before in cites:
        m = re.search(r"(?:by |et al\.?|\b)([A-Z][a-z]+)(?: et al\.?)?\.?\s*$", before)
        if m and len(numbers) == 1 and numbers[0] in bib and m.group(1) not in ("Note", "Finally", "Here"):
            (named if m.group(1) in bib[numbers[0]] else wrong).append(f"{m.group(1)} [{numbers[0]}]")
    evidence = (f"{len(cites)} citations of references 1-{max(first)}; first citations in order: "
                f"{'yes' if not out_of_order else out_of_order}; authors found in their entries: {named or 'none checkable'}")
    if out_of_order or wrong:
        return Evidence(ERRATUM, evidence + (f"; authors not in the cited entry: {wrong}" if wrong else ""),
                        correction="number the references in order of first citation" if out_of_order
                        else "cite the entry of that author")
    return Evidence(HOLDS, evidence)


# --- registration ----------------------------------------------------------------------------------

def _where(tag: str) -> str:
    sec = next((s for s in T.sections() if s.tag == tag), None)
    return "captions" if tag == "captions" else (sec.number if sec else tag)


def check_reference(ref: T.Reference):
    """The check of one cross-reference, by its kind."""
    runners = {"figure": check_figure, "section": check_section, "table": check_table, "equation": check_equation}
    return runners[ref.kind](ref)


def register() -> int:
    """Register one check per extracted reference; returns how many (0 without the transcription)."""
    if not T.sections():
        return 0
    n = 0
    counters: Counter = Counter()
    for ref in T.references():
        counters[ref.section] += 1
        cid = f"xref.{ref.section}.{counters[ref.section]}"
        claim(cid, f"{_where(ref.section)}, {ref.text}", (f"{ref.kind} reference: ", T.quote(T.clip(ref.sentence, 200))),
              chapter=CHAPTER, kind="cross-reference")(lambda r=ref: check_reference(r))
        n += 1
    sym_counters: Counter = Counter()
    for sym, use in T.symbols().items():
        sym_counters[use.section] += 1
        claim(f"symbol.{use.section}.{sym_counters[use.section]}", (f"{_where(use.section)}, ", Tex(sym)),
              ("symbol ", Tex(sym), f" ({use.uses} uses)"), chapter=CHAPTER, kind="symbol")(lambda s=sym: check_symbol(s))
        n += 1
    claim("structure.sections", "section headings", "section numbers I-VI, Conclusions",
          chapter=CHAPTER, kind="cross-reference")(check_section_numbering)
    claim("structure.citations", "reference list", "references numbered by first citation; named authors",
          chapter=CHAPTER, kind="cross-reference")(check_citations)
    claim("structure.units", "values with uncertainties", (Tex(r"x \pm y", "x ± y"), " carries a unit"),
          chapter=CHAPTER, kind="cross-reference")(check_units)
    claim("structure.equations", "equation labels", "equations (1)-(41) with sub-labels",
          chapter=CHAPTER, kind="cross-reference")(check_equation_numbering)
    for number in T.captions():
        claim(f"structure.caption{number}", f"caption of Fig. {number}", "panel groups of the caption",
              chapter=CHAPTER, kind="cross-reference")(lambda k=number: check_caption_panels(k))
    return n + 4 + len(T.captions())
