"""Renderers of the discrepancy model's effect substitutions (``generated/damping.py``,
``generated/tilt_rotation.py``).

The expressions and their printing live beside their derivations
(:func:`derivations.damping.render`, :func:`derivations.tilt.render_rotation`); this module
gives them the generator's header and source hash.
"""
from __future__ import annotations

from .. import damping, tilt
from .printing import header, source_hash

__all__ = ["render_damping", "render_rotation"]


def render_damping() -> str:
    """Text of ``generated/damping.py``."""
    return damping.render(header, source_hash)


def render_rotation() -> str:
    """Text of ``generated/tilt_rotation.py``."""
    return tilt.render_rotation(header, source_hash)
