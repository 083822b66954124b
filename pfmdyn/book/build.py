"""``pfmdyn book``'s build: the verified book with jupyter-book 1.x, every page executed.

The verdicts are computed once, before Sphinx starts, into ``<out>/verdicts.json``
(:func:`pfmdyn.book.records.write_verdicts`); Sphinx runs in this process and starts a kernel per
page, each of which finds the file through :data:`~pfmdyn.book.records.VERDICTS_ENV`, set only
while Sphinx runs (:func:`~pfmdyn.book.records.verdicts_from`).  The build is strict: notebook
execution is forced, a cell that raises fails the build, and Sphinx warnings are errors (``-W -n``).
"""
from __future__ import annotations

import time
from pathlib import Path

from ..errors import UserError
from .records import verdicts_from, write_verdicts


def book_dir() -> Path:
    """The ``book/`` folder of the source tree.

    >>> (book_dir() / "_toc.yml").is_file()
    True
    """
    here = Path(__file__).resolve().parents[2] / "book"
    if not (here / "_config.yml").exists():
        raise UserError(f"book sources not found at {here} (pfmdyn book needs the source tree)")
    return here


def build(out: Path, *, progress=None) -> int:
    """Build the book into ``out`` (HTML in ``out/html``); returns the Sphinx status (0 = success).

    ``progress``: None (quiet), or a callable taking a line of news (the command prints it);
    Sphinx reports its own progress only when one is given."""
    try:
        from jupyter_book.sphinx import build_sphinx
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise UserError(f"jupyter-book is not installed ({exc}); pip install -e '.[book]'") from exc
    src = book_dir()
    out = out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    verdict_file = out / "verdicts.json"
    write_verdicts(verdict_file)
    if progress is not None:
        progress(f"pfmdyn book: verdicts computed in {time.perf_counter() - t0:.1f} s -> {verdict_file}")
    with verdicts_from(verdict_file):
        result = build_sphinx(
            src, out / "html",
            doctreedir=out / ".doctrees",
            noconfig=True,
            path_config=str(src / "_config.yml"),
            confoverrides={"external_toc_path": (src / "_toc.yml").as_posix(), "nitpicky": True,
                           "latex_individualpages": False},
            builder="html",
            warningiserror=True,
            keep_going=True,
            freshenv=True,
            quiet=progress is None,
        )
    if isinstance(result, BaseException):
        return 1
    return int(result or 0)
