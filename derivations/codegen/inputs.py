"""Renderer of ``generated/paper_inputs.py``: the paper's inputs as floats for numeric code."""
from __future__ import annotations

import hashlib

from ..paper import inputs
from .printing import header

__all__ = ["render"]


def _floats(value):
    if isinstance(value, dict):
        return {k: _floats(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return tuple(_floats(v) for v in value)
    return float(value)


def render() -> str:
    """Source text of ``generated/paper_inputs.py``."""
    lines = "".join(f"{name} = {_floats(value)!r}\n" for name, value in inputs.NUMERIC.items())
    body = f'''"""The paper's inputs (from derivations/paper/inputs.py) as floats, SI units.

See :mod:`pfmdyn.derivations.paper.inputs` for what each one is.
"""

__all__ = {sorted(inputs.NUMERIC)!r}

{lines}'''
    return header("derivations/paper/inputs.py", hashlib.sha256(body.encode()).hexdigest(),
                  "the text below") + body
