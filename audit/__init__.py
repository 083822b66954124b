"""The audit of the paper's text, installed as ``pfmdyn.audit``: cross-references, symbols,
numbering and qualitative statements, each checked against its target.

The transcription reader (:mod:`.text`) cuts the paper into sections, sentences, references
and symbols; :mod:`.xref` checks references, symbols and numbering; :mod:`.statements` (with
:mod:`.wording` and :mod:`.restated`) decides the sentences that assert something.  The checks
build on the registry's (``derivations.checks``), which never import this package.  Importing
it registers every check of the text (none when the transcription is absent).
"""
from ..derivations import checks  # noqa: F401  (the registry's claims first: statements reuse them)
# Import order is the order of the verdict table and of the errata list.
from . import statements, xref  # noqa: F401,I001  (registration)
