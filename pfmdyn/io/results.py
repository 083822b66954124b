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
from pathlib import Path

import numpy as np

from ..errors import UserError

__all__ = ["json_ready", "dumps", "write_json"]


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
