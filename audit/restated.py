"""Sentences of the text that restate a claim of the registry: decided by that claim's check.

Both the statement audit (:mod:`.statements`) and the wording deciders (:mod:`.wording`) use
this; it imports neither of them.
"""
from __future__ import annotations

from typing import Callable

from pfmdyn.derivations.checks.core import HOLDS, result
from pfmdyn.derivations.evidence import Evidence, clip, join, say


def same_as(*claim_ids: str) -> Callable[[], Evidence]:
    """Decide a statement by registry claims that state the same thing: the first verdict other
    than *holds* decides (with its correction), the others are quoted as evidence."""
    def decide() -> Evidence:
        verdicts = [result(i) for i in claim_ids]
        worst = next((v for v in verdicts if v.verdict != HOLDS), verdicts[0])
        quoted = join([say(f"{v.id} ({v.verdict}): ", clip(v.proof.proof, 200)) for v in verdicts])
        return Evidence(worst.verdict, say("same statement as ", quoted), correct=worst.proof.correct,
                        correction=worst.proof.correction,
                        sign_convention=any(v.proof.sign_convention for v in verdicts))
    return decide
