"""Table references checked against the tables: the table exists and has as many rows as the
sentence counts.
"""
from __future__ import annotations

import re

from pfmdyn.derivations.checks.core import ERRATUM, HOLDS
from pfmdyn.derivations.evidence import Evidence
from . import text as T


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
