"""Renderers of the discrepancy model's effect substitutions (``generated/damping.py``,
``generated/tilt_rotation.py``).

The expressions and their printing live beside their derivations
(:func:`derivations.damping.render`, :func:`derivations.tilt.render_rotation`); this module
gives them the generator's header and source hash.
"""
from __future__ import annotations

import sympy as sp

from .. import damping, tilt
from .printing import header, source_hash

__all__ = ["render_damping", "render_rotation"]


def render_damping() -> str:
    """Text of ``generated/damping.py``."""
    return damping.render(header, source_hash)


def render_rotation() -> str:
    """Text of ``generated/tilt_rotation.py``: :func:`rotated` and its Jacobian."""
    text = tilt.render_rotation(header, source_hash)
    r = tilt.rotated()
    wrt = (tilt.k1, tilt.k2, tilt.alpha)
    printer = sp.printing.numpy.NumPyPrinter({"fully_qualified_modules": True})
    code = lambda e: printer.doprint(sp.simplify(e)).replace("numpy.", "np.")  # noqa: E731
    rows = ", ".join("(" + ", ".join(code(r[s].diff(p)) for p in wrt) + ")"
                     for s in (tilt.kvv, tilt.kll, tilt.kvl))
    text = text.replace("__all__ = ['rotated']", "__all__ = ['rotated', 'rotated_jacobian']")
    return text + f'''

def rotated_jacobian(k1, k2, alpha):
    """Partials of ``(kvv, kll, kvl)`` w.r.t. ``(k1, k2, alpha)``: a tuple of three 3-tuples."""
    return ({rows})
'''
