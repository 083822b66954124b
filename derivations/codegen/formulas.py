"""Renderer of ``generated/formulas.py``: the closed-form relations of :mod:`derivations.formulas`."""
from __future__ import annotations

import sympy as sp

from ..formulas import formulas
from . import examples, templates
from .examples import Example
from .printing import code, header, imports, source_hash

__all__ = ["render"]


def render() -> str:
    """Source text of ``generated/formulas.py`` (``templates/formulas.py.jinja``)."""
    items = formulas()
    functions = [{"name": f.name, "arguments": ", ".join(map(str, f.arguments)), "summary": f.summary,
                  "shown": sp.sstr(f.expr), "source": f.source, "body": code(f.expr), "imports": imports(f.expr),
                  "example": Example().number(f"{f.name}({examples.arguments(map(str, f.arguments))})",
                                              examples.evaluate(f.expr, f.arguments))}
                 for f in items]
    return templates.render("formulas.py.jinja",
                            header=header("derivations/formulas.py: formulas()", source_hash([f.expr for f in items])),
                            exported=sorted(f.name for f in items), functions=functions)
