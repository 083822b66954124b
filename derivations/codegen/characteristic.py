"""Renderer of ``generated/characteristic.py``: every root family's characteristic function.

Dimensionless and scaled, written against a math namespace ``m`` (NumPy, mpmath or
python-flint), for certified root finding.  The root families and their names are the
registry rows with a ``roots`` name (:mod:`derivations.families`).
"""
from __future__ import annotations

import sympy as sp

from .. import families as registry
from ..beam import H, L, k, k1, k2
from ..torsion import k2t
from ..trig import ATOMS, from_atoms, hyperbolic_degree, scaled, to_atoms
from . import examples, templates
from .examples import Example, beta1_free
from .printing import code, header, source_hash
from .transfer import families, z

__all__ = ["characteristic_families", "dimensionless", "render_characteristic"]

k1_over_k, k2_ratio, k2t_HL = sp.symbols("k1_over_k k2_ratio k2t_HL", positive=True)

_DIMENSIONLESS = {k1: k1_over_k * k, k2: k2_ratio * k * L**2 / H**2,
                  k2t: k2t_HL / (H * L)}
_PARAM_DOC = {str(s): registry.PARAMETER_HELP[str(s)] for s in (k1_over_k, k2_ratio, k2t_HL)}


def characteristic_families() -> list[tuple[str, str, sp.Expr, sp.Symbol]]:
    """(name, source, denominator, variable) of the families exported in ``FAMILIES``.

    >>> [name for name, *_ in characteristic_families()][:2]
    ['free', 'pinned']
    """
    by_module = {f.module: f for f in families()}
    return [(row.roots, by_module[row.module].source, by_module[row.module].denominator,
             by_module[row.module].variable) for row in registry.FAMILIES if row.roots]


def dimensionless(den: sp.Expr, var: sp.Symbol) -> sp.Expr:
    """Denominator in dimensionless parameters with monomial and integer content removed.

    The sign is fixed so that the term of highest power in ``var`` is positive.

    >>> from ..beam import beta
    >>> from ..free_end import solve
    >>> dimensionless(solve().denominator, beta)
    cos(beta)*cosh(beta) + 1
    >>> from ..torsion import solve_force, xi
    >>> dimensionless(solve_force().denominator.subs(xi, beta / L), beta)
    cos(beta)
    """
    expr = to_atoms(sp.expand(den.subs(_DIMENSIONLESS)), var)
    expr = sp.expand(sp.together(expr))
    num, _ = sp.fraction(sp.together(expr))
    gens = sorted(num.free_symbols, key=str)
    poly = sp.Poly(num, *gens)
    # Monomial content in the variable and the parameters has no positive zeros and goes;
    # a common power of cos, sin, cosh or sinh does have zeros and stays.
    exponents, poly = poly.terms_gcd()
    atoms = set(ATOMS.functions)
    poly = sp.Poly(poly.as_expr() * sp.Mul(*[g**e for g, e in zip(gens, exponents) if g in atoms]), *gens)
    _, poly = poly.clear_denoms()
    _, poly = poly.primitive()
    lead = sp.Poly(poly.as_expr(), var).LC()
    sign = -1 if sp.Poly(lead, *sorted(lead.free_symbols, key=str) or [var]).LC() < 0 else 1
    # Only the dimensionless parameters, the variable and the atoms may remain.
    result = sp.expand(sign * poly.as_expr())
    assert result.free_symbols <= {var, k1_over_k, k2_ratio, k2t_HL, *ATOMS.functions}, result
    return from_atoms(result, var)


def _example(name: str, fname: str, expr: sp.Expr, var: sp.Symbol, degree: int, params) -> Example:
    """The function at the stored point; the free family also at its first root, where it vanishes."""
    scaled_expr = expr.subs(var, z) / sp.cosh(z) ** degree
    symbols = [z, *sorted(scaled_expr.free_symbols - {z}, key=str)]
    keywords = "".join(f", {p}={examples.value(p)!r}" for p in params)
    example = Example().statement("import numpy as np").number(f"{fname}({examples.value('z')!r}, np{keywords})",
                               examples.evaluate(scaled_expr, symbols))
    if name == "free":
        example.statement("print(abs(free(BETA1_FREE, np)) < 1e-15)", "True")
    return example


def render_characteristic() -> str:
    """Source text of ``generated/characteristic.py`` (``templates/characteristic.py.jinja``)."""
    items = characteristic_families()
    digest = source_hash([den for _, _, den, _ in items])
    srcs = ", ".join(sorted({src.split(":")[0] for _, src, _, _ in items}))
    functions = []
    for name, src, den, var in items:
        expr = dimensionless(den, var)
        fname = name.replace("-", "_")
        params = sorted((str(s) for s in expr.free_symbols - {var}))
        atoms = to_atoms(expr.subs(var, z), z)
        degree = hyperbolic_degree(atoms) if atoms.has(ATOMS.ch, ATOMS.sh) else 0
        body = scaled(atoms, {ATOMS: degree}) if degree else atoms
        used = body.free_symbols
        lines = [line for atom, line in [(ATOMS.c, "_c = m.cos(z)"), (ATOMS.s, "_s = m.sin(z)")] if atom in used]
        if degree:
            lines += ["_e = m.exp(-z)", "_e2 = _e * _e"]
            lines += [line for atom, line in [(ATOMS.tanh, "_tanh = (1 - _e2) / (1 + _e2)"),
                                              (ATOMS.sech, "_sech = 2 * _e / (1 + _e2)")]
                      if atom in used]
        functions.append({"name": name, "function": fname, "parameters": params, "source": src,
                          "shown": sp.sstr(expr.subs(var, z)), "scale": f" / cosh(z)**{degree}" if degree else "",
                          "lines": lines, "body": code(body),
                          "example": _example(name, fname, expr, var, degree, params)})
    return templates.render("characteristic.py.jinja", header=header(srcs, digest), functions=functions,
                            parameter_help=sorted(_PARAM_DOC.items()), help=_PARAM_DOC,
                            beta1_free=beta1_free(30))
