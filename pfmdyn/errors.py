"""Errors that pfmdyn reports to its user as one line, never as a traceback.

The library raises them; :mod:`pfmdyn.cli` catches them and prints
``pfmdyn COMMAND: error: MESSAGE`` with exit status 2.  A :class:`UserError` is a
:class:`ValueError`, so that a Python caller catches a bad input as any bad argument.

The library names quantities, never command-line flags: an error about a value the user
should give carries its name (:attr:`UserError.quantity`, a name of :mod:`pfmdyn.names`) and
the command line adds the flag that gives it.

>>> import pfmdyn
>>> try:
...     pfmdyn.Cantilever(-1.0, 7e4, 2e-4)
... except ValueError as exc:
...     print(exc)
spring_constant must be in (0.0001, 10000] N/m, got -1.0
"""
from __future__ import annotations


class UserError(ValueError):
    """A problem with the user's input (a file, a number, a name); reported as one line.

    ``quantity`` names the value to give or to fix: a name of :mod:`pfmdyn.names`, or, for what
    a command takes under an option of its own (``out``, ``model``, a contact resonance's
    ``contact``, the spot's drive ``frequency``), that option's name; a tuple of them when several
    values are missing; None when no value is at fault.

    >>> UserError("the contact needs k1", quantity="k1").quantity
    'k1'
    """

    def __init__(self, message: str, quantity: str | tuple[str, ...] | None = None):
        super().__init__(message)
        self.quantity = quantity


class MissingExtraError(UserError):
    """An optional dependency is not installed; the message names the extra that brings it."""

    def __init__(self, module: str, extra: str):
        super().__init__(f"{module} is not installed: pip install 'pfmdyn[{extra}]'")
        self.module, self.extra = module, extra


def listed(items, last: str = "and") -> str:
    """Items as a sentence lists them: ``a``, ``a and b``, ``a, b and c`` (``last``: the final word).

    >>> listed(["a"]), listed(["a", "b"], "or"), listed(["a", "b", "c"])
    ('a', 'a or b', 'a, b and c')
    """
    items = list(items)
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} {last} {items[-1]}"
