"""The verdict records of the book: computed once per build, read by the chapters.

The verdicts of ``pfmdyn verify`` are computed once per build, before Sphinx starts, written to
``<out>/verdicts.json`` (each with its evidence already typeset by :mod:`pfmdyn.typeset`, the
module that also writes ``pfmdyn verify``'s errata list) and named to the notebook kernels by the
environment variable :data:`VERDICTS_ENV` (:func:`verdicts_from`); the chapters read them with
:func:`verdicts`.
"""
from __future__ import annotations

import json
import os
from collections import Counter
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

VERDICTS_ENV = "PFMDYN_BOOK_VERDICTS"
"""Path of the verdicts JSON written by ``pfmdyn book`` for the chapters to read."""


def chapter_of(claim_id: str) -> str | None:
    """The book page discussing a claim, as declared by its check (``@claim(..., chapter=...)``).

    >>> chapter_of("eq22.roots"), chapter_of("eq22.static"), chapter_of("nope")
    ('roots', 'free_end', None)
    """
    from .. import audit
    from ..derivations.checks import core
    audit.register()
    check = core.REGISTRY.get(claim_id)
    return (check.chapter or None) if check else None


ERRATUM_WIDTH = 46
"""Characters per line of the errata page's equations (:data:`pfmdyn.typeset.LINE_WIDTH` elsewhere)."""


def record(v) -> dict:
    """One verdict for the book: the plain fields of ``pfmdyn verify``'s JSON and, under ``html``,
    the claim's place, printed form, evidence and correction typeset for a table cell; errata also
    carry their typeset parts under ``erratum`` (:func:`pfmdyn.typeset.erratum`)."""
    from .. import typeset
    out = v.as_dict()
    out["html"] = {"where": typeset.html(v.where), "printed": typeset.html(v.printed),
                   "evidence": typeset.html(v.proof.proof), "correct": typeset.html(typeset.correction(v))}
    if str(v.verdict) in ("erratum", "holds_up_to_sign_convention"):
        # the errata page sets its equations in result boxes beside the page's contents, narrower
        # than a chapter's text: lines of ERRATUM_WIDTH characters (about 500 px) fit a laptop's browser
        width = ERRATUM_WIDTH
        f = typeset.erratum(v, width)
        out["erratum"] = {"printed": typeset.html(f["printed"], width), "correct": f["correct"],
                          "correction": typeset.html(f["correction"], width), "proof": typeset.html(f["proof"], width),
                          "decisive": f["decisive"], "sign": f["sign"]}
    return out


def compute_verdicts() -> list[dict]:
    """All verdicts of ``pfmdyn verify`` as :func:`record` dictionaries."""
    from ..verify import compute
    return [record(v) for v in compute(progress=False)]


def write_verdicts(path: Path, computed: list | None = None) -> list[dict]:
    """Write the verdicts to ``path`` (JSON): ``computed`` (:func:`pfmdyn.verify.compute`'s), or
    computed now when None."""
    data = compute_verdicts() if computed is None else [record(v) for v in computed]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"claims": data}, indent=1))
    return data


@contextmanager
def verdicts_from(path: Path):
    """Within the block, :func:`verdicts` reads ``path``, here and in every process started
    meanwhile (the notebook kernels inherit the environment when they start); afterwards
    :data:`VERDICTS_ENV` is as it was.

    >>> import tempfile
    >>> before = os.environ.get(VERDICTS_ENV)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "verdicts.json"
    ...     _ = path.write_text('{"claims": [{"id": "x.y", "verdict": "holds"}]}')
    ...     with verdicts_from(path):
    ...         print([v["id"] for v in verdicts()])
    ['x.y']
    >>> os.environ.get(VERDICTS_ENV) == before
    True
    """
    before = os.environ.get(VERDICTS_ENV)
    os.environ[VERDICTS_ENV] = str(path)
    try:
        yield
    finally:
        if before is None:
            del os.environ[VERDICTS_ENV]
        else:
            os.environ[VERDICTS_ENV] = before


@lru_cache(maxsize=None)
def _read(path: str) -> tuple[dict, ...]:
    return tuple(json.loads(Path(path).read_text())["claims"])


@lru_cache(maxsize=1)
def _computed() -> tuple[dict, ...]:
    return tuple(compute_verdicts())


def verdicts() -> list[dict]:
    """The verdicts of this build, in registry order.

    Read from the file named by :data:`VERDICTS_ENV` (set by ``pfmdyn book`` while it builds).
    When a page is executed outside ``pfmdyn book`` (e.g. ``jupyter-book build book``) they are
    computed in the kernel, once; nothing is written.
    """
    env = os.environ.get(VERDICTS_ENV)
    return list(_read(env) if env else _computed())


def claims(*ids: str) -> list[dict]:
    """The verdicts with these exact ids; a missing id raises (so a renamed claim fails the build)."""
    by_id = {v["id"]: v for v in verdicts()}
    missing = [i for i in ids if i not in by_id]
    if missing:
        raise KeyError(f"no verdict for claim id(s) {missing}")
    return [by_id[i] for i in ids]


def claims_of(page: str) -> list[dict]:
    """The verdicts a chapter discusses (declared by ``@claim(..., chapter=page)``), in registry order."""
    return [v for v in verdicts() if v.get("chapter") == page]


def counts(kind: str | None = None) -> Counter:
    """Number of claims per verdict (of one kind: claim, cross-reference, symbol, statement)."""
    return Counter(v["verdict"] for v in verdicts() if kind is None or v.get("kind", "claim") == kind)
