"""Renderer of ``generated/paper_inputs.py``: the paper's inputs as floats for numeric code."""
from __future__ import annotations

import hashlib

from ..paper import inputs
from . import templates
from .printing import header

__all__ = ["render"]


def _floats(value):
    if isinstance(value, dict):
        return {k: _floats(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return tuple(_floats(v) for v in value)
    return float(value)


def render() -> str:
    """Source text of ``generated/paper_inputs.py`` (``templates/paper_inputs.py.jinja``)."""
    body = templates.render("paper_inputs.py.jinja", exported=sorted(inputs.NUMERIC),
                            values={name: _floats(value) for name, value in inputs.NUMERIC.items()})
    return header("derivations/paper/inputs.py", hashlib.sha256(body.encode()).hexdigest(),
                  "the text below") + body
