"""Results written as JSON: one writer, one policy for the numbers JSON cannot hold.

JSON has no NaN or infinity.  A number that is not finite (a quantity the data leave
undetermined, NaN; an undamped mode's Q, infinity) is written as ``null``, which every
command's documentation reads as "not determined"; NumPy scalars and arrays become plain
numbers and lists.  Every command that writes JSON goes through :func:`write_json` (or
:func:`dumps` to print it).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from ..errors import UserError

__all__ = ["json_ready", "dumps", "write_json", "check_writable", "check_directory"]


def json_ready(obj):
    """A copy of ``obj`` that JSON can hold: non-finite numbers to None, NumPy to Python.

    >>> json_ready({"q": [np.float64(80.0), float("inf")], "n": np.int64(2), "k1": float("nan")})
    {'q': [80.0, None], 'n': 2, 'k1': None}
    """
    if isinstance(obj, dict):
        return {key: json_ready(value) for key, value in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [json_ready(value) for value in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def dumps(document) -> str:
    """``document`` as JSON text (indented, non-finite numbers as null).

    >>> print(dumps({"value": float("nan")}))
    {
      "value": null
    }
    """
    return json.dumps(json_ready(document), indent=2, allow_nan=False)


def write_json(path, document) -> None:
    """Write ``document`` to ``path`` as JSON (:func:`dumps`, ending in a newline); a path that
    cannot be written is one :class:`~pfmdyn.errors.UserError` line.

    >>> write_json("/nonexistent/folder/out.json", {})
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /nonexistent/folder/out.json: No such file or directory
    """
    text = dumps(document) + "\n"
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from None


def check_writable(*paths, figure: bool = False) -> None:
    """A :class:`~pfmdyn.errors.UserError` naming the first of ``paths`` (None: skipped) that
    cannot be written as a file; checked before anything is computed, so that a command
    writing several outputs writes none when one of them would fail.  ``figure``: the paths
    are figures, their suffix must be a format matplotlib writes.  ``-`` (standard output) is
    a path of a document, not of a figure.

    >>> check_writable(None, "/nonexistent/folder/out.json")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write /nonexistent/folder/out.json: no such directory /nonexistent/folder
    """
    for path in paths:
        if path is None or (str(path) == "-" and not figure):
            continue
        path = Path(path)
        folder = path.parent if str(path.parent) else Path(".")
        if path.is_dir():
            problem = "it is a directory"
        elif not folder.is_dir():
            problem = f"{'not a directory' if folder.exists() else 'no such directory'} {folder}"
        elif not os.access(folder, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
            problem = "permission denied"
        elif figure and path.suffix.lower().lstrip(".") not in _figure_formats():
            problem = f"matplotlib writes no {path.suffix or 'suffix-less'} figures (use .png, .pdf or .svg)"
        else:
            continue
        raise UserError(f"cannot write {path}: {problem}")


def _figure_formats() -> set:
    from matplotlib.backend_bases import FigureCanvasBase
    return set(FigureCanvasBase.get_supported_filetypes())


def check_directory(path) -> None:
    """A :class:`~pfmdyn.errors.UserError` when ``path`` cannot be (or become) a directory that
    the command writes into: a file in the way, a file among its parents, no permission.

    >>> check_directory("/dev/null/results")
    Traceback (most recent call last):
    ...
    pfmdyn.errors.UserError: cannot write into /dev/null/results: /dev/null is not a directory
    """
    path = Path(path)
    existing = next((p for p in (path, *path.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise UserError(f"cannot write into {path}: {existing} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise UserError(f"cannot write into {path}: permission denied on {existing}")
