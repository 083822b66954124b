"""Renderer of ``generated/families.py``: the family registry as plain data for numeric code.

Numeric code never imports ``derivations``; it reads the registry
(:mod:`derivations.families`) from this generated copy.
"""
from __future__ import annotations

import dataclasses
import hashlib
import inspect

from .. import families as registry
from .printing import header

__all__ = ["render"]


def render() -> str:
    """Source text of ``generated/families.py``."""
    fields = [f.name for f in dataclasses.fields(registry.Family)]
    rows = "".join(
        "    Family(" + ", ".join(f"{n}={getattr(row, n)!r}" for n in fields) + "),\n"
        for row in registry.FAMILIES)
    help_rows = "".join(f"    {k!r}: {v!r},\n" for k, v in registry.PARAMETER_HELP.items())
    # The registry's properties, copied as source text so that both classes answer alike.
    properties = "".join("\n" + inspect.getsource(v.fget) for v in vars(registry.Family).values()
                         if isinstance(v, property))
    body = f'''"""The family registry (from derivations/families.py), as plain data for numeric code.

See :mod:`pfmdyn.derivations.families` for the meaning of the fields.
"""
from typing import NamedTuple, Optional

__all__ = ["Family", "FAMILIES", "PARAMETER_HELP", "by_module", "by_roots"]


class Family(NamedTuple):
    """One boundary-condition family (fields as in derivations/families.py)."""

''' + "".join(f"    {n}: {t}\n" for n, t in _types(fields)) + properties + f'''

FAMILIES = (
{rows})
"""Every family with a generated module, in the order listed to users."""

PARAMETER_HELP = {{
{help_rows}}}
"""Parameter name -> meaning."""


def by_module(module):
    """The family whose generated module is ``module``."""
    return next(f for f in FAMILIES if f.module == module)


def by_roots(name):
    """The family known as ``name`` to ``pfmdyn roots``."""
    return next(f for f in FAMILIES if f.roots == name)
'''
    digest = hashlib.sha256(body.encode()).hexdigest()
    return header("derivations/families.py", digest, "the text below") + body


def _types(fields):
    hints = {f.name: f.type for f in dataclasses.fields(registry.Family)}
    for n in fields:
        hint = str(hints[n]).replace("tuple[str, ...]", "tuple").replace("str | None", "Optional[str]")
        yield n, hint
