"""Errors that pfmdyn reports to its user as one line, never as a traceback.

The library raises them; :mod:`pfmdyn.cli` catches them and prints
``pfmdyn COMMAND: error: MESSAGE`` with exit status 2.
"""


class UserError(Exception):
    """A problem with the user's input (a file, a number, a name); reported as one line."""


class MissingExtraError(UserError):
    """An optional dependency is not installed; the message names the extra that brings it."""

    def __init__(self, module: str, extra: str):
        super().__init__(f"{module} is not installed: pip install 'pfmdyn[{extra}]'")
        self.module, self.extra = module, extra
