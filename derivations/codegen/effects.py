"""Renderers of the discrepancy model's effect substitutions: ``generated/damping.py``
(:func:`derivations.damping.substitution`) and ``generated/tilt_rotation.py``
(:func:`derivations.tilt.rotated`), each with its partial derivatives.
"""
from __future__ import annotations

import sympy as sp

from .. import damping, tilt
from . import examples, templates
from .examples import Example
from .printing import code, header, source_hash

__all__ = ["render_damping", "render_rotation"]


def _simplified(expr: sp.Expr) -> str:
    return code(sp.simplify(expr))


def render_damping() -> str:
    """Text of ``generated/damping.py``: the substitution factors and their derivatives."""
    s = damping.substitution()
    outputs = {"beta_factor": (s["beta4"] / damping.beta0**4) ** sp.Rational(1, 4),
               "k_factor": s["k"] / damping.k, "k1_factor": s["k1"] / damping.k1,
               "mu_factor": s["mu"] / damping.mu}
    params = (damping.inv_q, damping.g, damping.xc)
    args = (damping.r, *params)
    at = examples.arguments(map(str, args))
    factors = Example().tuple_of(f"factors({at})", [examples.evaluate(e, args) for e in outputs.values()])
    d_factors = Example().tuple_of(f"d_factors({at})[0]",
                                   [examples.evaluate(outputs["beta_factor"].diff(p), args) for p in params])
    d_factors_wrt = Example().tuple_of(f"d_factors_wrt({at}, 1)",
                                       [examples.evaluate(e.diff(params[1]), args) for e in outputs.values()])
    return templates.render(
        "damping.py.jinja",
        header=header("derivations/damping.py: substitution()", source_hash(list(outputs.values()))),
        outputs=tuple(outputs), parameters=tuple(map(str, params)),
        values=[_simplified(e) for e in outputs.values()],
        derivatives=[[_simplified(e.diff(p)) for p in params] for e in outputs.values()],
        factors_example=factors, d_factors_example=d_factors,
        d_factors_wrt_example=d_factors_wrt)


def render_rotation() -> str:
    """Text of ``generated/tilt_rotation.py``: :func:`derivations.tilt.rotated` and its Jacobian."""
    r = tilt.rotated()
    rows = [r[s] for s in (tilt.kvv, tilt.kll, tilt.kvl)]
    wrt = (tilt.k1, tilt.k2, tilt.alpha)
    at = examples.arguments(map(str, wrt))
    rotated = Example().tuple_of(f"rotated({at})", [examples.evaluate(e, wrt) for e in rows])
    jacobian = Example().tuple_of(f"rotated_jacobian({at})[2]",
                                  [examples.evaluate(rows[2].diff(p), wrt) for p in wrt])
    return templates.render(
        "tilt_rotation.py.jinja", header=header("derivations/tilt.py: rotated()", source_hash(rows)),
        values=[code(e) for e in rows], derivatives=[[_simplified(e.diff(p)) for p in wrt] for e in rows],
        rotated_example=rotated, jacobian_example=jacobian)
