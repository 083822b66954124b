"""Renderer of ``generated/characteristic.py``: every root family's characteristic function.

Dimensionless and scaled, written against a math namespace ``m`` (NumPy, mpmath or
python-flint), for certified root finding.  The root families and their names are the
registry rows with a ``roots`` name (:mod:`derivations.families`).
"""
from __future__ import annotations

import mpmath as mp
import sympy as sp

from .. import families as registry
from ..beam import H, L, k, k1, k2
from ..torsion import k2t
from ..trig import ATOMS, from_atoms, hyperbolic_degree, scaled, to_atoms
from .printing import code, header, source_hash
from .transfer import families, z

__all__ = ["characteristic_families", "dimensionless", "beta1_free", "render_characteristic"]

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


def beta1_free(dps: int = 30) -> str:
    """First root of ``1 + cos(beta) cosh(beta)`` (free cantilever), to ``dps`` digits.

    >>> beta1_free(12)
    '1.87510406871'
    """
    with mp.workdps(dps + 10):
        root = mp.findroot(lambda b: mp.cos(b) + mp.sech(b), 1.875)
        return mp.nstr(root, dps, strip_zeros=False)


def render_characteristic() -> str:
    """Source text of ``generated/characteristic.py``."""
    items = characteristic_families()
    digest = source_hash([den for _, _, den, _ in items])
    srcs = ", ".join(sorted({src.split(":")[0] for _, src, _, _ in items}))
    out = [header(srcs, digest), '''"""Characteristic functions (resonance conditions) of every family, dimensionless and scaled.

Each ``<family>(z, m, **params)`` returns the family's denominator (see the transfer
modules) with dimensional factors, integer content and powers of ``z`` removed, divided by
``cosh(z)`` where hyperbolics occur, with ``tanh``/``sech`` built from ``m.exp(-z)`` so
nothing overflows.  ``z`` is ``beta`` (flexural families) or ``xi L`` (torsion).  Its real
zeros ``z > 0`` are the resonances.  ``m`` supplies ``cos``, ``sin``, ``exp``: pass
``numpy``, ``mpmath`` (or ``mpmath.iv``), or :data:`FLINT` for python-flint ``arb``,
``acb`` and ``arb_series`` (which have no ``cosh``/``sinh``).  Coefficients are integers,
so the arithmetic is exact in every namespace.  In float64 near ``z = 0`` prefer the
transfer modules, which switch to a series there.

Dimensionless parameters:

''' + "\n".join(f"* ``{k_}``: {v}" for k_, v in sorted(_PARAM_DOC.items())) + f'''
"""

__all__ = ["FAMILIES", "PARAMETERS", "FLINT", "BETA1_FREE", "BETA1_FREE_STR",
           {", ".join(repr(n.replace("-", "_")) for n, *_ in items)}]

BETA1_FREE_STR = "{beta1_free(30)}"
"""First free resonance root of ``1 + cos(beta) cosh(beta) = 0`` (30 digits, mpmath)."""
BETA1_FREE = float(BETA1_FREE_STR)


class _FlintMath:
    """``cos``, ``sin``, ``exp`` as methods of python-flint ``arb``/``acb``/``arb_series`` values."""

    @staticmethod
    def cos(x):
        return x.cos()

    @staticmethod
    def sin(x):
        return x.sin()

    @staticmethod
    def exp(x):
        return x.exp()


FLINT = _FlintMath()
''']
    params_table = {}
    for name, src, den, var in items:
        expr = dimensionless(den, var)
        fname = name.replace("-", "_")
        params = sorted((str(s) for s in expr.free_symbols - {var}))
        params_table[name] = tuple(params)
        atoms = to_atoms(expr.subs(var, z), z)
        degree = hyperbolic_degree(atoms) if atoms.has(ATOMS.ch, ATOMS.sh) else 0
        body = scaled(atoms, {ATOMS: degree}) if degree else atoms
        sig = "z, m" + (", *, " + ", ".join(params) if params else "")
        pdoc = "".join(f"\n    {p} : {_PARAM_DOC[p]}" for p in params)
        used = body.free_symbols
        lines = [line for atom, line in [(ATOMS.c, "    _c = m.cos(z)"), (ATOMS.s, "    _s = m.sin(z)")]
                 if atom in used]
        if degree:
            lines += ["    _e = m.exp(-z)", "    _e2 = _e * _e"]
            lines += [line for atom, line in [(ATOMS.tanh, "    _tanh = (1 - _e2) / (1 + _e2)"),
                                              (ATOMS.sech, "    _sech = 2 * _e / (1 + _e2)")]
                      if atom in used]
        shown = sp.sstr(expr.subs(var, z))
        scale = f" / cosh(z)**{degree}" if degree else ""
        out.append(f'''

def {fname}({sig}):
    """{name}: ``({shown}){scale}`` (from {src}).

    Parameters
    ----------
    z : number or array (``beta``, or ``xi L`` for torsion)
    m : math namespace with ``cos``, ``sin``, ``exp``{pdoc}
    """
{chr(10).join(lines)}
    return {code(body)}
''')
    out.append("\n\nFAMILIES = {\n" + "".join(
        f"    {n!r}: {n.replace('-', '_')},\n" for n, *_ in items) + "}\n")
    out.append('"""Family name -> characteristic function."""\n')
    out.append("PARAMETERS = {\n" + "".join(
        f"    {n!r}: {params_table[n]!r},\n" for n, *_ in items) + "}\n")
    out.append('"""Family name -> names of its dimensionless keyword parameters."""\n')
    return "".join(out)
