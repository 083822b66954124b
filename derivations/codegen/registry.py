"""Renderer of ``generated/families.py``: the family registry as plain data for numeric code.

Numeric code never imports ``derivations``; it reads the registry
(:mod:`derivations.families`) from this generated copy.
"""
from __future__ import annotations

import dataclasses
import hashlib
import inspect

from .. import families as registry
from . import templates
from .examples import Example
from .printing import header

__all__ = ["render"]


def render() -> str:
    """Source text of ``generated/families.py`` (``templates/families.py.jinja``)."""
    fields = [f.name for f in dataclasses.fields(registry.Family)]
    rows = ["Family(" + ", ".join(f"{n}={getattr(row, n)!r}" for n in fields) + ")" for row in registry.FAMILIES]
    # The registry's properties, copied as source text so that both classes answer alike.
    properties = "".join("\n" + inspect.getsource(v.fget) for v in vars(registry.Family).values()
                         if isinstance(v, property))
    # The examples: the first family with a root name, looked up both ways.
    row = next(r for r in registry.FAMILIES if r.roots)
    body = templates.render(
        "families.py.jinja", fields=list(_types(fields)), properties=properties, rows=rows,
        help=registry.PARAMETER_HELP,
        by_module_example=Example().statement(f"by_module({row.module!r}).roots", repr(row.roots)),
        by_roots_example=Example().statement(f"by_roots({row.roots!r}).module", repr(row.module)))
    digest = hashlib.sha256(body.encode()).hexdigest()
    return header("derivations/families.py", digest, "the text below") + body


def _types(fields):
    hints = {f.name: f.type for f in dataclasses.fields(registry.Family)}
    for n in fields:
        hint = str(hints[n]).replace("tuple[str, ...]", "tuple").replace("str | None", "Optional[str]")
        yield n, hint
