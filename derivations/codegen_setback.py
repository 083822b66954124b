"""Code generation for the two-segment (set-back tip) family: ``generated/tip_setback.py``.

The set-back solution (:mod:`derivations.tip_setback`) is a polynomial in the trigonometric
and hyperbolic atoms of two arguments, ``a = gamma beta`` and ``b = (1 - gamma) beta``, so
the one-argument basis machinery of :mod:`derivations.codegen` does not apply.  The same
stabilisation is used per argument: every numerator and the denominator are divided by
``cosh(a)**da cosh(b)**db`` (the highest hyperbolic degree in each), with ``tanh`` and
``sech`` built from ``exp(-a)``, ``exp(-b)``; nothing overflows.  There is no series
branch: the closed form cancels like the elastic family's below ``beta ~ 1`` (about
``beta**-6`` lost relative to the largest term, 1e-12 at ``beta = 0.3``), which is
documented as the domain of validity.  The scaled denominator is exported as
``characteristic`` for root finding.
"""
from __future__ import annotations

import sympy as sp

from . import tip_setback
from .beam import H, L, k
from .tilt import kll, kvl, kvv
from .tip_mass import mu

__all__ = ["PARAMETERS", "scaled2", "render"]

PARAMETERS = (k, kvv, kll, kvl, H, L, mu, tip_setback.gamma)
_SCALED = {set_: sp.symbols(f"_c{t} _s{t} _tanh{t} _sech{t}") for set_, t in
           ((tip_setback.ATOMS_A, "a"), (tip_setback.ATOMS_B, "b"))}


def _degree(expr: sp.Expr, atoms) -> int:
    return sp.Poly(expr, atoms[2], atoms[3]).total_degree()


def scaled2(expr: sp.Expr, degrees: dict) -> sp.Expr:
    """``expr / (cosh(a)**da cosh(b)**db)`` in the atoms ``_ca, _sa, _tancha, _secha, ...``.

    >>> ca, sa, cha, sha = tip_setback.ATOMS_A
    >>> scaled2(ca * cha + 1, {tip_setback.ATOMS_A: 1, tip_setback.ATOMS_B: 0})
    _ca + _secha
    """
    out = sp.expand(expr)
    for atoms, d in degrees.items():
        c, s, ch, sh = atoms
        sc, ss, tanh, sech = _SCALED[atoms]
        poly = sp.Poly(out, ch, sh)
        out = sp.S.Zero
        for (i, j), coeff in poly.terms():
            out += coeff * tanh**j * sech**(d - i - j)
        out = sp.expand(out.subs({c: sc, s: ss}))
    return out


def render(header) -> str:
    """Source text of ``generated/tip_setback.py``; ``header(source, digest)`` as in codegen."""
    from .codegen import _cse_lines, source_hash

    sol = tip_setback.solve()
    drives = tip_setback.DRIVES
    exprs = [sol.denominator] + [sol.slope[d] for d in drives]
    degrees = {atoms: max(_degree(e, atoms) for e in exprs) for atoms in _SCALED}
    lines, reduced = _cse_lines([scaled2(e, degrees) for e in exprs])
    den_lines, den = _cse_lines([scaled2(sol.denominator, degrees)])
    names = ", ".join(map(str, PARAMETERS))
    da, db = degrees[tip_setback.ATOMS_A], degrees[tip_setback.ATOMS_B]
    atoms = '''    beta = np.asarray(beta)
    a = gamma * beta
    b = (1.0 - gamma) * beta
    _ca, _sa, _cb, _sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    _ea = np.exp(np.maximum(np.real(a) - 100.0, 0.0) - a)
    _eb = np.exp(np.maximum(np.real(b) - 100.0, 0.0) - b)
    _tanha = (1.0 - _ea * _ea) / (1.0 + _ea * _ea)
    _secha = 2.0 * _ea / (1.0 + _ea * _ea)
    _tanhb = (1.0 - _eb * _eb) / (1.0 + _eb * _eb)
    _sechb = 2.0 * _eb / (1.0 + _eb * _eb)
'''
    params_doc = f'''    Parameters
    ----------
    beta : array_like, real or complex, ``Re beta > 0.3`` (see module)
    {names} : array_like, broadcast against ``beta``; ``0 < gamma <= 1``
'''
    return (header("derivations/tip_setback.py: solve()", source_hash(exprs)) + f'''"""tip_setback: tip at x = gamma L with springs kvv, kll, kvl, tip mass mu; slope read at L.

Source: derivations/tip_setback.py: solve(), an extension of Eqs. 4-5 of Jesse, Baddorf,
Kalinin 2006; signs as there.  ``gamma = 1``, ``mu = 0``, ``kvv = k1``, ``kll = k2``,
``kvl = 0`` is Eq. 5 (elastic contact).

Numerators and denominator are polynomials in cos, sin, cosh, sinh of ``a = gamma beta``
and ``b = (1 - gamma) beta``, divided by ``cosh(a)**{da} cosh(b)**{db}`` with ``tanh``, ``sech``
built from ``exp(-a)``, ``exp(-b)`` so nothing overflows.  No series branch: use
``Re beta > 0.3``, where about 1e-12 relative to the largest term is lost at worst.
"""
import numpy as np

__all__ = ['DRIVES', 'PARAMETERS', 'characteristic', 'slope']

PARAMETERS = {tuple(map(str, PARAMETERS))!r}
DRIVES = {tuple(map(str, drives))!r}


def slope(beta, {names}):
    """Tip slope theta = u0'(L) per unit drive.

{params_doc}
    Returns
    -------
    tuple of ndarray
        per unit d1, d2 (beam-frame surface displacements), f0, q0
    """
{atoms}''' + "\n".join(lines) + f'''
    _r = 1.0 / ({reduced[0]})
    return ({", ".join(f"({r}) * _r" for r in reduced[1:])})


def characteristic(beta, {names}):
    """Scaled denominator: its real zeros in ``beta`` are the resonances.

{params_doc}    """
{atoms}''' + "\n".join(den_lines) + f'''
    return {den[0]}
''')
