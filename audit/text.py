"""The paper's running text, read from its transcription and cut into what can be checked.

The transcription (``shared/paper/jesse2006_dynamic_pfm.md`` beside the source tree, or the
file named by ``$PFMDYN_PAPER``) is read at run time and never copied into the repository.
This module finds, in order of appearance:

- the sections (heading number, title, body) and their sentences;
- every cross-reference: to an equation, a figure or a figure panel, a section, a table;
- every subscripted or decorated symbol and where (if anywhere) it is defined;
- the panel lists of the figure captions, with the words that describe each panel.

Nothing here decides whether a statement is right; :mod:`pfmdyn.audit.xref` and
:mod:`pfmdyn.audit.statements` do.  :func:`quote` turns a passage into a sentence of evidence
(its ``$...$`` formulas typeset, not shown as LaTeX source).

The module stays whole past 450 lines because it is one reader: every extraction cuts the same
cached sections, and the checkers use it as one namespace (``from . import text as T``).
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from pfmdyn.derivations.evidence import Tex, say

PAPER_ENV = "PFMDYN_PAPER"
PAPER_NAME = "jesse2006_dynamic_pfm.md"

ROMAN = {"I": 1, "II": 2, "III": 3, "IV": 4, "V": 5, "VI": 6, "VII": 7, "VIII": 8}


def paper_path() -> Path | None:
    """The transcription: ``$PFMDYN_PAPER``, else ``shared/paper/`` in a parent of the source tree."""
    if os.environ.get(PAPER_ENV):
        path = Path(os.environ[PAPER_ENV])
        return path if path.exists() else None
    here = Path(__file__).resolve()
    for parent in here.parents:
        candidate = parent / "shared" / "paper" / PAPER_NAME
        if candidate.exists():
            return candidate
    return None


@dataclass
class Section:
    """One numbered (or named) part of the paper."""

    number: str            # "III.2", "VI", "abstract", "table1", "captions"
    title: str
    body: str
    tag: str = ""          # id-safe key: "III2", "VI", "conclusions"
    sentences: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Reference:
    """A cross-reference found in a sentence."""

    kind: str              # "equation" | "figure" | "section" | "table"
    section: str           # tag of the section it appears in
    sentence: str
    text: str              # the reference as printed
    targets: tuple         # equation labels / (figure, panels) / section numbers / table numbers
    start: int = 0         # position in the sentence
    end: int = 0
    context: str = ""      # words of the sentence that describe what is referred to


_ABBREVIATIONS = re.compile(r"\b(Eqs?|Figs?|Ref|e\.g|i\.e|al|vs|comp|No|ca|approx)\.$")


def _sentences(body: str) -> list[str]:
    """Split running text into sentences, keeping abbreviations and display math together."""
    out, start = [], 0
    for m in re.finditer(r"[.!?](?=\s+[A-Z$(\[])", body):
        piece = body[start:m.end()]
        if _ABBREVIATIONS.search(piece) or re.search(r"\b[IVX]+\.\d$", piece) or piece.count("$") % 2:
            continue
        out.append(piece.strip())
        start = m.end()
    if body[start:].strip():
        out.append(body[start:].strip())
    return [s for s in out if s]


def _tag(number: str, title: str, seen: set) -> str:
    tag = number.replace(".", "")
    if tag in seen:                      # a repeated section number: keep the id unique and readable
        tag = re.sub(r"[^a-z]", "", title.lower())[:16]
    seen.add(tag)
    return tag


_HEADING = re.compile(r"^(?:#{1,3}\s+|\*\*)(?:([IVX]+(?:\.\d+)?)\.\s*)?(.+?)(?:\*\*)?\s*$")


@lru_cache(maxsize=1)
def sections() -> tuple[Section, ...]:
    """The paper's sections in order (empty when the transcription is not found)."""
    path = paper_path()
    if path is None:
        return ()
    lines = path.read_text(encoding="utf-8").splitlines()
    out: list[Section] = []
    current: list[str] = []
    number, title = "front", ""

    def flush():
        text = re.sub(r"\s+", " ", " ".join(current)).strip()
        if text or number != "front":
            out.append(Section(number, title, text))

    for line in lines:
        m = _HEADING.match(line)
        is_heading = bool(m) and (line.startswith("#") or (m.group(1) and line.startswith("**") and line.endswith("**")))
        if line.strip() == "Table 1":
            is_heading, m = True, None
        if is_heading:
            flush()
            current = []
            if m is None:
                number, title = "table1", "Table 1"
            elif m.group(1):
                number, title = m.group(1), m.group(2).strip()
            else:
                title = m.group(2).strip()
                number = {"abstract": "abstract", "figure captions": "captions"}.get(title.lower(), title.lower())
            continue
        if re.match(r"^\*\*Figure \d+\.\*\*", line) or re.match(r"^\[\d+\]", line):
            continue                     # figure pages and the reference list
        current.append(line)
    flush()
    seen: set = set()
    keep = []
    for s in out:
        if s.number in ("front",) or s.number.startswith("dynamic behavior"):
            continue
        s.tag = _tag(s.number, s.title, seen)
        s.sentences = _sentences(s.body)
        keep.append(s)
    return tuple(keep)


def section(number: str) -> Section | None:
    """The first section printed with this number (``"III.2"``)."""
    return next((s for s in sections() if s.number == number), None)


def text_sections() -> list[Section]:
    """Sections of running text (abstract to conclusions; not the table or the captions)."""
    return [s for s in sections() if s.number not in ("table1", "captions")]


def quote(passage: str) -> tuple:
    """A passage of the transcription as a sentence of evidence: words, and its ``$...$`` and
    ``$$...$$`` formulas as LaTeX parts (an unpaired ``$`` is kept as a word).

    >>> quote("so $k_1$ here")
    ('so ', Tex(tex='k_1', plain=''), ' here')
    """
    pieces = passage.replace("$$", "$").split("$")
    if len(pieces) % 2 == 0:                 # unpaired: the last '$' starts no formula
        pieces[-2:] = [pieces[-2] + "$" + pieces[-1]]
    return say(*(Tex(p.strip()) if i % 2 else p for i, p in enumerate(pieces) if p))


def clip(text: str, n: int) -> str:
    """``text`` cut to about ``n`` characters without leaving a formula open (``$`` or ``$$``).

    >>> clip("a $x + y$ b $$z$$ c", 6)
    'a …'
    >>> clip("short", 10)
    'short'
    """
    if len(text) <= n:
        return text
    cut = text[:n]
    spans = list(re.finditer(r"\$\$.+?\$\$|\$[^$]+\$", text))
    for m in spans:
        if m.start() < n < m.end():      # the cut falls inside a formula: stop before it
            cut = text[:m.start()]
            break
    return cut.rstrip() + " …"


# --- equations ------------------------------------------------------------------------------------

_DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.S)
_LABEL = re.compile(r"(?:\\tag\{([^}]*)\}|\\quad\s*\(([^)]*)\)|\\qquad\s*\(([^)]*)\)|\(\s*(\d+[a-f]?(?:\s*,\s*[a-f])?)\s*\)\s*$)")


def _expand_labels(raw: str) -> list[str]:
    """'3a,b' -> ['3a', '3b']; '21 a,b' -> ['21a', '21b']; '23f' -> ['23f']; '11-14' -> 11..14."""
    raw = raw.replace(" ", "").replace("–", "-")
    out: list[str] = []
    for part in raw.split(","):
        if not part:
            continue
        m = re.fullmatch(r"(\d+)-(\d+)", part)
        if m:
            out += [str(i) for i in range(int(m.group(1)), int(m.group(2)) + 1)]
            continue
        m = re.fullmatch(r"(\d+)([a-f]?)", part)
        if m:
            out.append(part)
        elif re.fullmatch(r"[a-f]", part) and out:
            out.append(re.match(r"\d+", out[-1]).group(0) + part)
    return out


@lru_cache(maxsize=1)
def equations() -> dict[str, str]:
    """Printed equation label -> LaTeX of the display equation (``'4a'`` and ``'4b'`` share one)."""
    out: dict[str, str] = {}
    for s in sections():
        for m in _DISPLAY.finditer(s.body):
            tex = m.group(1).strip()
            lab = _LABEL.search(tex)
            if not lab:
                continue
            raw = next(g for g in lab.groups() if g)
            raw = re.sub(r"(\d+)\s+([a-f])", r"\1\2", raw)
            for label in _expand_labels(raw):
                out[label] = tex[:lab.start()].strip()
    return out


def equation_section(label: str) -> str | None:
    """Tag of the section in which equation ``label`` is printed."""
    for s in sections():
        for m in _DISPLAY.finditer(s.body):
            lab = _LABEL.search(m.group(1).strip())
            if lab:
                raw = re.sub(r"(\d+)\s+([a-f])", r"\1\2", next(g for g in lab.groups() if g))
                if label in _expand_labels(raw):
                    return s.tag
    return None


# --- figures and their captions -----------------------------------------------------------------

_PANELS = r"[a-l](?:\s*[,\-–]\s*[a-l])*"
_GROUP = re.compile(r"\((" + _PANELS + r")\)")


def expand_panels(text: str) -> tuple[str, ...]:
    """'a-d' -> (a, b, c, d); 'c,e,g' -> (c, e, g)."""
    out: list[str] = []
    for part in re.split(r"\s*,\s*", text.strip()):
        m = re.fullmatch(r"([a-l])\s*[-–]\s*([a-l])", part)
        if m:
            out += [chr(c) for c in range(ord(m.group(1)), ord(m.group(2)) + 1)]
        elif re.fullmatch(r"[a-l]", part):
            out.append(part)
    return tuple(out)


# Words that describe a panel, by category.  A panel is described in a category when its
# caption says so; a sentence naming a category must agree with every panel it cites.
VOCABULARY: dict[str, dict[str, str]] = {
    "material": {"SiO": r"SiO", "LiNbO3": r"LiNbO", "PZT": r"\bPZT\b"},
    "regime": {"non-contact": r"non-contact", "contact": r"(?<!non-)\bcontact\b(?!\s+resonances?)"},
    "direction": {"vertical": r"\bvertical\b", "lateral": r"\blateral\b"},
    "signal": {"amplitude": r"(?i)\bamplitudes?\b", "phase": r"\bphase\b", "x-signal": r"x-signal",
               "error map": r"error maps?", "dominance": r"\bdominant\b"},
    "grain": {"grain 1": r"grain 1\b", "grain 2": r"grain 2\b"},
    "cantilever": {c: rf"cantilevers? {c}\b|\b{c}(?=\s*\([a-l])" for c in "ABC"},
    "plot": {"resonance plot": r"[Rr]esonan\w* frequenc\w*.{0,60}?(?:as a function|depend|increase|shift)|cross-?over",
             "circuit": r"circuit"},
}


def keywords(text: str) -> dict[str, set[str]]:
    """Category -> the vocabulary words present in ``text``."""
    found: dict[str, set[str]] = {}
    for cat, words in VOCABULARY.items():
        hits = {w for w, pat in words.items() if re.search(pat, text)}
        if hits:
            found[cat] = hits
    return found


@dataclass
class Caption:
    number: int
    text: str
    panels: tuple[str, ...]                       # every panel letter the caption defines
    described: dict[str, dict[str, set[str]]]     # panel -> category -> words


@lru_cache(maxsize=1)
def captions() -> dict[int, Caption]:
    """Figure number -> parsed caption.

    A panel group such as ``(a-d)`` takes the words of the text just before it (back to the
    previous group or the start of its sentence); if those name nothing, the words after it
    (up to the next group or the end of the sentence), then the head of its sentence.  A
    caption that opens with ``(a)`` labels its panels in front of their descriptions, so its
    groups read forwards first.  A group after "case" refers back and describes nothing.
    """
    sec = section("captions")
    if sec is None:
        return {}
    out: dict[int, Caption] = {}
    for m in re.finditer(r"\*\*Fig\. (\d+)\.\*\*(.*?)(?=\*\*Fig\. \d+\.\*\*|$)", sec.body, re.S):
        number, text = int(m.group(1)), m.group(2).strip()
        leading = text.startswith("(a)")
        described: dict[str, dict[str, set[str]]] = {}
        panels: list[str] = []
        for sentence in _sentences(text):
            groups = list(_GROUP.finditer(sentence))
            head = sentence[:groups[0].start()] if groups else ""
            for i, g in enumerate(groups):
                letters = expand_panels(g.group(1))
                before = sentence[groups[i - 1].end() if i else 0:g.start()]
                after = sentence[g.end():groups[i + 1].start() if i + 1 < len(groups) else len(sentence)]
                if re.search(r"\bcase\s*$", before):
                    continue
                for p in letters:
                    if p not in panels:
                        panels.append(p)
                order = (after, before, head) if leading else (before, after, head)
                words = next((kw for kw in map(keywords, order[:2]) if kw), {})
                if not words:            # the head of the sentence names only the kind of plot
                    words = {c: w for c, w in keywords(head).items() if c == "plot"}
                for p in letters:
                    for cat, hits in words.items():
                        described.setdefault(p, {}).setdefault(cat, set()).update(hits)
        if not panels:                   # a one-panel figure: the caption describes it whole
            described[""] = keywords(text)
        out[number] = Caption(number, text, tuple(sorted(panels)), described)
    return out


# --- references in the running text ---------------------------------------------------------------

_EQ_REF = re.compile(r"\b(?:Eqs?\.|[Ee]quations)\s*((?:\(\s*[0-9][0-9a-f,\s\-–]*\)(?:\s*(?:and|,)\s*)?)+)")
_FIG_REF = re.compile(r"\b(?:Figs?\.?|Figures?)\s*(\d+)((?:\s*,\s*\d+)*)"
                      r"((?:\s*[a-l](?![a-zA-Z0-9]))(?:\s*[,\-–]\s*[a-l](?![a-zA-Z0-9]))*)?"
                      r"(?:\s+and\s+(\d+)\b)?")
_SEC_REF = re.compile(r"\bSections?\s+([IVX]+(?:\.\d)?)\.?(?:\s*(?:and|,)\s*([IVX]+(?:\.\d)?))?")
_TAB_REF = re.compile(r"\bTable\s+(\d+|[IVX]+)\b")


def _figure_refs(sentence: str, tag: str) -> list[Reference]:
    refs = []
    for m in _FIG_REF.finditer(sentence):
        figures = [int(m.group(1))] + [int(x) for x in re.findall(r"\d+", m.group(2) or "")]
        if m.group(4):
            figures.append(int(m.group(4)))
        panels = expand_panels((m.group(3) or "").strip())
        targets = [(f, panels if len(figures) == 1 else ()) for f in figures]
        refs.append(Reference("figure", tag, sentence, m.group(0).strip(), tuple(targets), m.start(), m.end()))
    # Panel groups "(a,b)" later in a sentence that cites one figure without panels belong to it.
    bare = [r for r in refs if len(r.targets) == 1 and not r.targets[0][1]]
    if len(refs) == 1 and bare:
        fig = bare[0].targets[0][0]
        for g in _GROUP.finditer(sentence):
            if g.start() > bare[0].start:
                refs.append(Reference("figure", tag, sentence, f"Fig. {fig} ({g.group(1)})",
                                      ((fig, expand_panels(g.group(1))),), g.start(), g.end()))
    return refs


def _context(sentence: str, refs: list[Reference], ref: Reference) -> str:
    """The words describing a figure reference: those since the previous reference (or the
    sentence start) up to its end; when they name nothing, those after it up to the next."""
    spans = sorted((r.start, r.end) for r in refs if r.kind == "figure")
    i = spans.index((ref.start, ref.end))
    before = sentence[spans[i - 1][1] if i else 0:ref.end]
    if keywords(before):
        return before
    return sentence[ref.start:spans[i + 1][0] if i + 1 < len(spans) else len(sentence)]


@lru_cache(maxsize=1)
def references() -> tuple[Reference, ...]:
    """Every cross-reference of the running text, in order of appearance."""
    out: list[Reference] = []
    for sec in text_sections() + [s for s in sections() if s.number == "captions"]:
        for sentence in sec.sentences:
            found: list[Reference] = []
            for m in _EQ_REF.finditer(sentence):
                labels = []
                for grp in re.findall(r"\(([^)]*)\)", m.group(1)):
                    labels += _expand_labels(grp)
                found.append(Reference("equation", sec.tag, sentence, m.group(0).strip(), tuple(labels), m.start()))
            if sec.number != "captions":
                found += _figure_refs(sentence, sec.tag)
            for m in _SEC_REF.finditer(sentence):
                targets = tuple(x for x in m.groups() if x)
                found.append(Reference("section", sec.tag, sentence, m.group(0).strip().rstrip("."), targets, m.start()))
            for m in _TAB_REF.finditer(sentence):
                found.append(Reference("table", sec.tag, sentence, m.group(0), (m.group(1),), m.start()))
            found.sort(key=lambda r: r.start)
            for r in found:
                ctx = _context(sentence, found, r) if r.kind == "figure" else sentence
                out.append(Reference(r.kind, r.section, r.sentence, r.text, r.targets, r.start, r.end, ctx))
    return tuple(out)


# --- citations -----------------------------------------------------------------------------------------

@lru_cache(maxsize=1)
def bibliography() -> dict[int, str]:
    """Reference number -> entry, for the entries the transcription contains."""
    path = paper_path()
    if path is None:
        return {}
    return {int(m.group(1)): m.group(2) for m in
            re.finditer(r"^\[(\d+)\]\s+(.+)$", path.read_text(encoding="utf-8"), re.M)}


@lru_cache(maxsize=1)
def citations() -> tuple[tuple[str, tuple[int, ...], str], ...]:
    """(section tag, reference numbers, words just before) for every bracketed citation."""
    out = []
    for sec in text_sections():
        for m in re.finditer(r"\[(\d+(?:\s*[,\-–]\s*\d+)*)\]", sec.body):
            numbers = []
            for part in re.split(r"\s*,\s*", m.group(1)):
                lo, _, hi = part.partition("-")
                numbers += list(range(int(lo), int(hi or lo) + 1))
            out.append((sec.tag, tuple(numbers), sec.body[max(0, m.start() - 60):m.start()]))
    return tuple(out)


# --- symbols -----------------------------------------------------------------------------------------

_INLINE = re.compile(r"\$\$.+?\$\$|\$[^$]+\$", re.S)
_SYMBOL = re.compile(r"(\\tilde\{\\?[A-Za-z]+\}|\\[A-Za-z]+|(?<![A-Za-z])[A-Za-z])"
                     r"(_\{[^{}]+\}|_[A-Za-z0-9])?")
_CHEMICAL = re.compile(r"(SiO|LiNbO|BaTiO)$")


def canonical(symbol: str) -> str:
    """'d_{el}' and 'd_el' print alike."""
    return re.sub(r"_\{(.)\}", r"_\1", symbol)


@dataclass
class SymbolUse:
    symbol: str
    section: str           # tag of first use
    uses: int
    definition: str        # the sentence defining it ('' when none does)


def _defines(sym_tex: str, math: str, after: str, before: str) -> bool:
    """Is this occurrence a definition ('where $X$ is', '$X$ is the', '$X = ...$', ', $X$,')?"""
    esc = re.escape(sym_tex)
    if re.match(r"^\s*" + esc + r"(?:\([^)]*\))?\s*(?:=|\\equiv)", math):
        return True
    if math.strip() == sym_tex or re.fullmatch(r"\s*" + esc + r"\s*", math):
        if re.match(r"^\s*(?:,?\s*(?:and\s+\$[^$]+\$\s*)?(?:is|are|denotes)\b)", after):
            return True
        if re.search(r"(?:where|and)\s+(?:is\s+)?$", before) or re.search(r"\w,\s*$", before) and after.startswith(","):
            return True
    return False


@lru_cache(maxsize=1)
def symbols() -> dict[str, SymbolUse]:
    """Every subscripted or decorated symbol: first section, number of uses, defining sentence."""
    out: dict[str, SymbolUse] = {}
    for sec in text_sections():
        for sentence in sec.sentences:
            for m in _INLINE.finditer(sentence):
                math = m.group(0).strip("$")
                for s in _SYMBOL.finditer(math):
                    base, sub = s.group(1), s.group(2)
                    if not sub and not base.startswith("\\tilde"):
                        continue
                    if base in ("\\frac", "\\left", "\\right", "\\text", "\\mathrm") or base.startswith("\\tag"):
                        continue
                    if _CHEMICAL.search(math[:s.start()] + base):
                        continue
                    name = canonical(s.group(0))
                    rec = out.setdefault(name, SymbolUse(name, sec.tag, 0, ""))
                    rec.uses += 1
                    if not rec.definition and _defines(s.group(0), math, sentence[m.end():], sentence[:m.start()]):
                        rec.definition = sentence
    return out
