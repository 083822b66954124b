"""What the book's chapters (MyST notebooks in ``book/``) import as ``from pfmdyn import book``:
the verdict records of the build (:mod:`pfmdyn.book.records`) and the display helpers
(:mod:`pfmdyn.book.display`).  The build itself, ``pfmdyn book``, is :mod:`pfmdyn.book.build`;
no chapter needs it.
"""
from .display import (COLUMN_SHARES, HTML, VERDICT_ORDER, aligned, anchor, chapter_table, claims_table, conditions,
                      counts_table, errata, families_of, family_table, math, ratios, tip_values)
from .records import (VERDICTS_ENV, chapter_of, claims, claims_of, compute_verdicts, counts, record, verdicts,
                      verdicts_from, write_verdicts)

__all__ = ["COLUMN_SHARES", "HTML", "VERDICT_ORDER", "VERDICTS_ENV", "aligned", "anchor", "chapter_of", "chapter_table",
           "claims", "claims_of", "claims_table", "compute_verdicts", "conditions", "counts", "counts_table", "errata",
           "families_of", "family_table", "math", "ratios", "record", "tip_values", "verdicts", "verdicts_from",
           "write_verdicts"]
