"""The audit of the paper's text, installed as ``pfmdyn.audit``: cross-references, symbols,
numbering and qualitative statements, each checked against its target.

The transcription reader (:mod:`.text`) cuts the paper into sections, sentences, references
and symbols; :mod:`.xref` checks references, symbols and numbering (with one ``xref_*`` module
per kind of target); :mod:`.statements` (with :mod:`.wording` and :mod:`.restated`) decides
the sentences that assert something.  The checks build on the registry's
(``pfmdyn.derivations.checks``), which never import this package.
:func:`register` adds the text's checks to the registry (none when the transcription is absent).
"""
from __future__ import annotations

from pfmdyn.derivations.checks import core

from . import statements, xref


def register() -> int:
    """Register every check of the text after the registry's claims (statements reuse them),
    in the order of the verdict table; a second call registers nothing.  Returns how many
    checks of the text are registered."""
    if not any(check.kind != "claim" for check in core.REGISTRY.values()):
        statements.register()
        xref.register()
    return sum(check.kind != "claim" for check in core.REGISTRY.values())
