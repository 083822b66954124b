"""Command-line options shared by several commands, and the hint that names them.

The readers name what a file lacks by its field (:class:`pfmdyn.io.record.MissingFieldError`);
only the commands know which option supplies it.
"""
from __future__ import annotations

from ..io.record import MissingFieldError

__all__ = ["OPTIONS", "option_hint"]

OPTIONS = {"spring_constant_n_per_m": "--spring-constant", "length_m": "--length",
           "width_m": "--width", "tip_height_m": "--tip-height",
           "free_resonance_hz": "--free-resonance"}
"""Field that may be given on the command line -> its option."""


def option_hint(error: Exception) -> str:
    """``": give --option"`` when ``error`` is a missing field an option supplies, else ``""``.

    >>> option_hint(MissingFieldError("tip height not in a.ibw", "tip_height_m"))
    ': give --tip-height'
    >>> option_hint(ValueError("x"))
    ''
    """
    if isinstance(error, MissingFieldError) and error.field in OPTIONS:
        return f": give {OPTIONS[error.field]}"
    return ""
