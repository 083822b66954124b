"""Renderer of ``generated/tip_setback.py``: the two-segment (set-back tip) family.

The set-back solution (:mod:`derivations.tip_setback`) is a polynomial in the atoms of two
arguments, ``a = gamma beta`` and ``b = (1 - gamma) beta``, so the one-argument basis of
:mod:`derivations.codegen.transfer` does not apply.  The same stabilisation is used per
argument: every numerator and the denominator are divided by ``cosh(a)**da cosh(b)**db``
(the highest hyperbolic degree in each, :func:`derivations.trig.scaled`), with ``tanh``
and ``sech`` built from ``exp(-a)``, ``exp(-b)``; nothing overflows.  There is no series
branch: the closed form cancels like the elastic family's below ``beta ~ 1`` (about
``beta**-6`` lost relative to the largest term, 1e-12 at ``beta = 0.3``), which is
documented as the domain of validity.  The scaled denominator is exported as
``characteristic`` for root finding, and as ``characteristic_balls`` (the same lines in a
math namespace, integer coefficients) for certified roots in ball arithmetic.  Every printed polynomial is grouped by monomials of
``beta`` and the parameters before CSE (:func:`_grouped`).  ``slope_and_jacobian`` and
``characteristic_and_jacobian`` add the partials of :data:`.jacobian.JACOBIANS`, ``beta``
and ``gamma`` through the atoms of both arguments.
"""
from __future__ import annotations

import sympy as sp

from .. import beam, families as registry, tip_setback
from ..trig import hyperbolic_degree, normal_form, scaled
from .jacobian import JACOBIANS, partials, render_and_jacobian
from .printing import cse_lines, header, source_hash
from .stabilise import clipped_exp
from .transfer import symbol

__all__ = ["render"]


def render() -> str:
    """Source text of ``generated/tip_setback.py``."""
    row = registry.by_module("tip_setback")
    params = [symbol(p, tip_setback) for p in row.parameters]
    sol = tip_setback.solve()
    drives = tip_setback.DRIVES
    assert tuple(map(str, drives)) == row.drives
    exprs = [sol.denominator] + [sol.slope[d] for d in drives]
    sets = (tip_setback.ATOMS_A, tip_setback.ATOMS_B)
    degrees = {at: max(hyperbolic_degree(e, at) for e in exprs) for at in sets}
    d_exprs, wrt = _partials(exprs, params)
    d_scaled = [_grouped(scaled(e, degrees), params) for e in d_exprs]
    # The atoms differentiate into atoms: the partials keep the degrees, so share the scaling.
    assert all(hyperbolic_degree(e, at) <= degrees[at] for e in d_exprs for at in sets)
    lines, reduced = cse_lines([_grouped(scaled(e, degrees), params) for e in exprs])
    den_lines, den = cse_lines([_grouped(scaled(sol.denominator, degrees), params)])
    names = ", ".join(map(str, params))
    da, db = degrees[tip_setback.ATOMS_A], degrees[tip_setback.ATOMS_B]
    atoms = f'''    beta = np.asarray(beta)
    a = gamma * beta
    b = (1.0 - gamma) * beta
    _ca, _sa, _cb, _sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    _ea = {clipped_exp("a", "np.real(a)")}
    _eb = {clipped_exp("b", "np.real(b)")}
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
    return (header(row.source, source_hash(exprs)) + f'''"""tip_setback: tip at x = gamma L with springs kvv, kll, kvl, tip mass mu; slope read at L.

Source: {row.source}, an extension of Eqs. 4-5 of Jesse, Baddorf,
Kalinin 2006; signs as there.  ``gamma = 1``, ``mu = 0``, ``kvv = k1``, ``kll = k2``,
``kvl = 0`` is Eq. 5 (elastic contact).

Numerators and denominator are polynomials in cos, sin, cosh, sinh of ``a = gamma beta``
and ``b = (1 - gamma) beta``, divided by ``cosh(a)**{da} cosh(b)**{db}`` with ``tanh``, ``sech``
built from ``exp(-a)``, ``exp(-b)`` so nothing overflows.  No series branch: use
``Re beta > 0.3``, where about 1e-12 relative to the largest term is lost at worst.
"""
import numpy as np

__all__ = {sorted(["PARAMETERS", "DRIVES", "JACOBIAN_PARAMETERS", *row.outputs, "slope_and_jacobian", "characteristic_and_jacobian", "characteristic_balls"])!r}

PARAMETERS = {tuple(map(str, params))!r}
JACOBIAN_PARAMETERS = {tuple(map(str, wrt))!r}
DRIVES = {row.drives!r}


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
{_jacobian([_grouped(scaled(e, degrees), params) for e in exprs], d_scaled, wrt, names, atoms)}

def characteristic(beta, {names}):
    """Scaled denominator: its real zeros in ``beta`` are the resonances.

{params_doc}    """
{atoms}''' + "\n".join(den_lines) + f'''
    return {den[0]}
''' + _characteristic_balls(den_lines, den[0], names)
            + _characteristic_jacobian(_grouped(scaled(exprs[0], degrees), params), d_scaled[::len(exprs)], wrt, names, atoms))


def _partials(exprs, params):
    """Partials of ``exprs`` w.r.t. the Jacobian parameters (``beta`` and ``gamma`` through the atoms)."""
    a, b = tip_setback.ATOMS_A, tip_setback.ATOMS_B
    g = tip_setback.gamma
    by_name = {str(p): p for p in (beam.beta, *params)}
    wrt = [by_name[n] for n in JACOBIANS["tip_setback"]]
    # a = gamma beta, b = (1 - gamma) beta.
    rates = {beam.beta: {a: g, b: 1 - g}, g: {a: beam.beta, b: -beam.beta}}
    return [normal_form(d, a, b) for d in partials(exprs, wrt, rates)], wrt


def _grouped(expr, params):
    """``expr`` collected by monomials of ``beta`` and the parameters other than ``gamma``,
    each coefficient (a polynomial in the atoms) with its common factors pulled out.

    The same sum regrouped: a third of the operations of the expanded form, and most of
    them on scalars when the parameters are scalars.
    """
    gens = [p for p in params if str(p) != "gamma"] + [beam.beta]
    poly = sp.Poly(expr, *gens)
    return sp.Add(*[sp.Mul(*[g**e for g, e in zip(gens, m)]) * sp.factor_terms(c) for m, c in poly.terms()])


def _jacobian(values, partials, wrt, names, atoms) -> str:
    """``slope_and_jacobian``: the scaled values and partials (see :func:`.jacobian.render_and_jacobian`)."""
    return render_and_jacobian("slope", f"beta, {names}", "tip slope theta = u0'(L) per unit drive", atoms, wrt,
                               values, partials).rstrip("\n") + "\n"


def _characteristic_balls(lines, value, names) -> str:
    """``characteristic_balls``: :func:`characteristic`'s lines in a math namespace ``m``.

    The same CSE lines and scaling with ``cos``, ``sin``, ``exp`` taken from ``m`` and integer
    literals only, so python-flint balls and exact series evaluate it without rounding
    anything but the balls' own arithmetic (certified root isolation uses it).
    """
    body = "\n".join(lines)
    # Integer coefficients: a float literal would be a rounded constant inside a proof.
    assert "." not in body + value, "non-integer literal in the set-back characteristic"
    return f'''

def characteristic_balls(beta, m, {names}):
    """:func:`characteristic` in a math namespace ``m`` with ``cos``, ``sin``, ``exp``.

    For certified roots: ``beta`` a python-flint ``arb_series`` (or an exact ``fmpq_series``),
    ``m`` the namespace ``generated.characteristic.FLINT``, parameters ``arb`` or ``fmpq``.
    Every coefficient is an integer.  Real ``beta`` (no clipping of the exponentials).
    """
    a = gamma * beta
    b = (1 - gamma) * beta
    _ca, _sa, _cb, _sb = m.cos(a), m.sin(a), m.cos(b), m.sin(b)
    _ea, _eb = m.exp(-a), m.exp(-b)
    _tanha = (1 - _ea * _ea) / (1 + _ea * _ea)
    _secha = 2 * _ea / (1 + _ea * _ea)
    _tanhb = (1 - _eb * _eb) / (1 + _eb * _eb)
    _sechb = 2 * _eb / (1 + _eb * _eb)
{body}
    return {value}
'''


def _characteristic_jacobian(den, d_dens, wrt, names, atoms) -> str:
    """``characteristic_and_jacobian``: the scaled denominator and its partials, scaled alike."""
    lines, reduced = cse_lines([den, *d_dens])
    body = "\n".join(lines)
    return f'''

def characteristic_and_jacobian(beta, {names}):
    """:func:`characteristic` and ``D_p / S`` for each ``p`` in ``JACOBIAN_PARAMETERS``.

    ``D`` is the unscaled denominator and ``S`` the scale of :func:`characteristic`; at a
    zero of ``D`` these are the partials of :func:`characteristic`, so a resonance moves
    with ``p`` as ``d beta / d p = -D_p / D_beta``.
    """
{atoms}{body}
    return {reduced[0]}, ({", ".join(reduced[1:])})
'''
