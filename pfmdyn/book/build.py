"""``pfmdyn book``'s build: the verified book with jupyter-book 1.x, every page executed.

The verdicts are computed once, before Sphinx starts, into ``<out>/verdicts.json``
(:func:`pfmdyn.book.records.write_verdicts`), unless :data:`~pfmdyn.book.records.VERDICTS_ENV` already
names a file of them (the tests compute them once for ``pfmdyn verify``'s tests and the book); Sphinx runs in this process and starts a kernel per
page, each of which finds the file through :data:`~pfmdyn.book.records.VERDICTS_ENV`, set only
while Sphinx runs (:func:`~pfmdyn.book.records.verdicts_from`).  The build is strict: notebook
execution is forced, a cell that raises fails the build, and Sphinx warnings are errors (``-W -n``).
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from ..errors import UserError
from .records import VERDICTS_ENV, verdicts_from, write_verdicts


def book_dir() -> Path:
    """The ``book/`` folder of the source tree.

    >>> (book_dir() / "_toc.yml").is_file()
    True
    """
    here = Path(__file__).resolve().parents[2] / "book"
    if not (here / "_config.yml").exists():
        raise UserError(f"book sources not found at {here} (pfmdyn book needs the source tree)")
    return here


@contextlib.contextmanager
def quiet_kernel():
    """While it lasts, the pages' kernel (``python3``) is this Python's ipykernel logging errors only: a
    kernel spec of our own first on ``JUPYTER_PATH`` (ipykernel 7 warns on every start that its local
    TCP transport is unencrypted, which says nothing about the book).

    >>> from jupyter_client.kernelspec import KernelSpecManager
    >>> with quiet_kernel():
    ...     KernelSpecManager().get_kernel_spec("python3").argv[-1]
    '--IPKernelApp.log_level=ERROR'
    """
    before = os.environ.get("JUPYTER_PATH")
    with tempfile.TemporaryDirectory() as folder:
        spec = Path(folder) / "kernels" / "python3"
        spec.mkdir(parents=True)
        (spec / "kernel.json").write_text(json.dumps({
            "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}",
                     "--IPKernelApp.log_level=ERROR"],
            "display_name": "Python 3", "language": "python"}))
        os.environ["JUPYTER_PATH"] = os.pathsep.join([folder] + ([before] if before else []))
        try:
            yield
        finally:
            if before is None:
                os.environ.pop("JUPYTER_PATH", None)
            else:
                os.environ["JUPYTER_PATH"] = before


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
    given = os.environ.get(VERDICTS_ENV)
    if given and Path(given).resolve() != verdict_file:
        shutil.copyfile(given, verdict_file)
    elif not given:
        write_verdicts(verdict_file)
    if progress is not None:
        done = f"taken from {given}" if given else f"computed in {time.perf_counter() - t0:.1f} s"
        progress(f"pfmdyn book: verdicts {done} -> {verdict_file}")
    with verdicts_from(verdict_file), quiet_kernel():
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
