"""Every cross-reference of the paper's text checked against its target, by the target's kind.

References are extracted by :mod:`pfmdyn.audit.text` (ids ``xref.<section>.<n>``, in order
of appearance within a section; symbols ``symbol.<section>.<n>`` by first use; the numbering
of sections and equations ``structure.*``).  A reference is checked against what its target
contains, by the module of its kind: :mod:`.xref_figures` (figures, panels and the panel groups
of each caption), :mod:`.xref_sections` (sections and their numbering), :mod:`.xref_tables`,
:mod:`.xref_equations` (equations and their numbering) and :mod:`.xref_symbols`.

Here: :func:`check_reference` picks the check of a reference's kind, :func:`register` registers
every check, and the two checks that read the whole text are made:

- units: every measured value with an uncertainty carries a unit;
- citations: references are numbered in order of first citation, and an author named before a
  citation appears in the entry.
"""
from __future__ import annotations

import re
from collections import Counter

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS, claim
from pfmdyn.derivations.evidence import Evidence, Tex, say
from . import text as T
from .xref_equations import check_equation, check_equation_numbering
from .xref_figures import check_caption_panels, check_figure
from .xref_sections import check_section, check_section_numbering
from .xref_symbols import check_symbol
from .xref_tables import check_table

CHAPTER = "audit"


# --- the whole text -------------------------------------------------------------------------------

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
