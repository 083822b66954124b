"""The templates of the generated files: one Jinja template per output kind (SymForce's way).

A renderer computes the data of a file (names, printed expressions, examples); its
template in ``templates/`` lays out the text.  Shared pieces are macros: the
``<function>_and_jacobian`` function (``jacobian.jinja``) and the doctest example
(``example.jinja``).
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import jinja2

__all__ = ["render"]

FOLDER = Path(__file__).resolve().parent / "templates"


def _sentence(text: str) -> str:
    """First letter upper case, the rest as written (Jinja's ``capitalize`` lowers it)."""
    return text[:1].upper() + text[1:]


@lru_cache(maxsize=None)
def _environment() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(FOLDER), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
                             autoescape=False)
    env.filters["repr"] = repr
    env.filters["tuple"] = tuple
    env.filters["sentence"] = _sentence
    return env


def render(template: str, **context) -> str:
    """Text of ``templates/<template>`` filled with ``context``.

    >>> render("example.jinja", example=None)
    ''
    """
    return _environment().get_template(template).render(**context)
