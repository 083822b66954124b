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
from . import examples, templates
from .examples import Example
from .jacobian import JACOBIANS, and_jacobian, partials
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
    _balls(den_lines, den[0])
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
    _sechb = 2.0 * _eb / (1.0 + _eb * _eb)'''
    examples_ = _examples(exprs, params, wrt, degrees)
    slope = {"lines": lines, "den": reduced[0], "nums": reduced[1:], "example": examples_[0],
             "jacobian": _jacobian([_grouped(scaled(e, degrees), params) for e in exprs], d_scaled, wrt, names,
                                   atoms, examples_[1])}
    return templates.render(
        "tip_setback.py.jinja", header=header(row.source, source_hash(exprs)), source=row.source,
        degree_a=da, degree_b=db, names=names, atoms=atoms, parameters=tuple(map(str, params)),
        exported=sorted(["PARAMETERS", "DRIVES", "JACOBIAN_PARAMETERS", *row.outputs, "slope_and_jacobian",
                         "characteristic_and_jacobian", "characteristic_balls"]),
        jacobian_parameters=tuple(map(str, wrt)), drives=row.drives, slope=slope,
        characteristic=_characteristic(_grouped(scaled(exprs[0], degrees), params), den_lines, den[0],
                                       d_scaled[::len(exprs)], examples_[2:]))


def _balls(lines, value) -> None:
    """``characteristic_balls`` prints :func:`characteristic`'s lines in a math namespace; a
    float literal there would be a rounded constant inside a proof, so every coefficient
    must be an integer."""
    assert "." not in "".join(lines) + value, "non-integer literal in the set-back characteristic"


def _examples(exprs, params, wrt, degrees):
    """Doctests of slope, slope_and_jacobian, characteristic, characteristic_and_jacobian."""
    args = (beam.beta, *params)
    at = examples.arguments(map(str, args))
    den, *nums = [tip_setback.to_functions(e) for e in exprs]
    ratio = [n / den for n in nums]
    a, b = tip_setback.gamma * beam.beta, (1 - tip_setback.gamma) * beam.beta
    scale = sp.cosh(a) ** degrees[tip_setback.ATOMS_A] * sp.cosh(b) ** degrees[tip_setback.ATOMS_B]
    slope = Example().tuple_of(f"slope({at})", [examples.evaluate(e, args) for e in ratio])
    jac = Example().statement(f"values, jacobian = slope_and_jacobian({at})").tuple_of(
        "", [examples.derivative(ratio[0], args, p) for p in wrt], target="jacobian[0]")
    char = Example().number(f"characteristic({at})", examples.evaluate(den / scale, args))
    char_jac = Example().statement(f"value, partials = characteristic_and_jacobian({at})").tuple_of(
        "", [examples.derivative(den, args, p) / examples.evaluate(scale, args) for p in wrt], target="partials")
    return slope, jac, char, char_jac


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


def _jacobian(values, partials, wrt, names, atoms, example) -> dict:
    """``slope_and_jacobian``: the scaled values and partials (see :func:`.jacobian.and_jacobian`)."""
    return and_jacobian("slope", f"beta, {names}", "tip slope theta = u0'(L) per unit drive", atoms, wrt,
                        values, partials, example)


def _characteristic(den, lines, value, d_dens, example) -> dict:
    """``characteristic`` and ``characteristic_and_jacobian``: the scaled denominator and its
    partials, scaled alike."""
    jacobian_lines, jacobian = cse_lines([den, *d_dens])
    return {"lines": lines, "value": value, "jacobian_lines": jacobian_lines, "jacobian": jacobian,
            "example": example[0], "jacobian_example": example[1]}
