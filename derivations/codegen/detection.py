"""Renderer of ``generated/detection.py``: the beam read at a detection point ``x_s = sigma L``.

The detection solution (:mod:`derivations.detection`) has two branches, spot before and
beyond the tip, each a polynomial in the atoms of three arguments (``a = gamma beta``,
``b = (1 - gamma) beta`` and ``s = sigma beta`` or ``r = (1 - sigma) beta``).  They are
stabilised as the set-back family is (:mod:`.setback`): numerators and denominator divided
by ``cosh**d`` of every argument, ``tanh`` and ``sech`` built from clipped ``exp(-x)``.
Both branches are evaluated and ``numpy.where(sigma <= gamma, ...)`` picks one (each is
finite everywhere).  Layout: ``templates/detection.py.jinja``.

Written:

* ``slope``, ``deflection``: ``u'(sigma L)`` and ``u(sigma L)`` per unit d1, d2, f0, q0;
* ``slope_and_jacobian``: with the partials w.r.t. :data:`JACOBIAN`, for fits;
* ``q0_slope_before``, ``q0_slope_beyond`` and their ``_coefficients``: the numerator of the
  slope per unit ``q0`` in dimensionless parameters, ``A cos + B sin + C cosh + E sinh + F``
  of the spot's argument, against a math namespace ``m`` (NumPy, mpmath or python-flint, as
  in ``characteristic.py``): its zeros in ``sigma`` are the electrostatic blind spots
  (:mod:`pfmdyn.analysis.spot` certifies them).
"""
from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from functools import lru_cache

import sympy as sp

from .. import beam, detection, families as registry, tip_setback
from ..trig import hyperbolic_degree, normal_form, scaled
from . import examples, templates
from .examples import Example
from .jacobian import and_jacobian, partials
from .printing import cse_lines, header, source_hash
from .setback import _grouped
from .stabilise import clipped_exp
from .transfer import symbol

__all__ = ["render", "JACOBIAN", "DIMENSIONLESS"]

JACOBIAN = ("beta", "sigma", "k", "kvv", "kll", "kvl", "mu", "gamma")
"""Parameters of ``slope_and_jacobian``, in column order."""

kvv_over_k, kll_ratio, kvl_ratio = sp.symbols("kvv_over_k kll_ratio kvl_ratio", real=True)
DIMENSIONLESS = {"kvv_over_k": "kvv / k", "kll_ratio": "kll H**2 / (k L**2)", "kvl_ratio": "kvl H / (k L)"}
"""The dimensionless stiffnesses of the blind-spot functions."""

_ARGS = {"a": "gamma * beta", "b": "(1.0 - gamma) * beta", "s": "sigma * beta", "r": "(1.0 - sigma) * beta"}


def _atoms(tags: str, m: str = "np") -> str:
    """Preamble lines defining the atoms (cos, sin, tanh, sech) of the arguments in ``tags``.

    ``m``: the math namespace (``np``, with ``exp`` clipped as in :mod:`.setback`, or ``m``).
    """
    lines = ["beta = np.asarray(beta)"] if m == "np" else []
    for t in tags:
        lines += [f"{t} = {_ARGS[t]}",
                  f"_c{t}, _s{t} = {m}.cos({t}), {m}.sin({t})",
                  f"_e{t} = " + (clipped_exp(t, f"np.real({t})") if m == "np" else f"m.exp(-{t})"),
                  f"_tanh{t} = (1 - _e{t} * _e{t}) / (1 + _e{t} * _e{t})",
                  f"_sech{t} = 2 * _e{t} / (1 + _e{t} * _e{t})"]
    return "\n".join(f"    {line}" for line in lines)


def _scaled_branch(branch, params):
    """Scaled ``[D, N_d1.., N_q0]`` of the slope and of the deflection, and the slope partials."""
    sets = branch.atoms
    exprs = [branch.denominator] + [branch.slope[d] for d in tip_setback.DRIVES]
    defl = [branch.denominator] + [branch.deflection[d] for d in tip_setback.DRIVES]
    degrees = {at: max(hyperbolic_degree(e, at) for e in exprs + defl) for at in sets}
    g, s = tip_setback.gamma, detection.sigma
    a, b, spot = sets
    sign = 1 if spot == detection.ATOMS_S else -1          # s = sigma beta, r = (1 - sigma) beta
    rates = {beam.beta: {a: g, b: 1 - g, spot: s if sign > 0 else 1 - s},
             g: {a: beam.beta, b: -beam.beta}, s: {spot: sign * beam.beta}}
    by_name = {str(p): p for p in (beam.beta, s, *params)}
    wrt = [by_name[n] for n in JACOBIAN]
    d_exprs = [normal_form(d, *sets) for d in partials(exprs, wrt, rates)]
    # The atoms differentiate into atoms: the partials keep the degrees, so share the scaling.
    assert all(hyperbolic_degree(e, at) <= degrees[at] for e in d_exprs for at in sets)
    return ([_grouped(scaled(e, degrees), params) for e in exprs],
            [_grouped(scaled(e, degrees), params) for e in defl],
            [_grouped(scaled(e, degrees), params) for e in d_exprs], wrt)


def _dimensionless(expr):
    """The ``q0`` numerator in :data:`DIMENSIONLESS` parameters, monomial content removed."""
    k, H, L = beam.k, beam.H, beam.L
    kvv, kll, kvl = (symbol(n, tip_setback) for n in ("kvv", "kll", "kvl"))
    e = sp.expand(expr.subs({kvv: kvv_over_k * k, kll: kll_ratio * k * L**2 / H**2, kvl: kvl_ratio * k * L / H}))
    num, _ = sp.fraction(sp.together(e))
    poly = sp.Poly(num, *sorted(num.free_symbols, key=str))
    _, poly = poly.terms_gcd()
    _, poly = poly.primitive()
    out = sp.expand(poly.as_expr())
    assert not out.has(k, H, L), out.free_symbols
    return out


def _blind_spot_coefficients(branch) -> dict:
    """Printed coefficients of cos, sin, cosh, sinh of the spot's argument and of 1 (q0 numerator).

    The numerator is linear in the spot's atoms: the coefficients depend only on the lever
    and the frequency, so they are evaluated once (tight balls) and the function of
    ``sigma`` is five terms.
    """
    q = _dimensionless(branch.slope[beam.q0])
    spot = branch.atoms[-1]
    lever = {at: hyperbolic_degree(q, at) for at in branch.atoms[:-1]}
    poly = sp.Poly(q, *spot.functions)
    assert poly.total_degree() <= 1, poly.total_degree()
    coeffs = [poly.coeff_monomial(g) for g in spot.functions] + [poly.coeff_monomial(1)]
    lines, reduced = cse_lines([scaled(c, lever) for c in coeffs])
    return {"lines": lines, "coefficients": reduced}


def _examples(sol, params):
    """Doctests of slope, deflection and slope_and_jacobian at the stored point (before the tip)."""
    args = [beam.beta, detection.sigma, *params]
    at = examples.arguments(map(str, args))
    branch = sol.before
    assert examples.value("sigma") <= examples.value("gamma")

    def ratio(expr):
        return detection.to_functions(expr / branch.denominator)
    slope = [ratio(branch.slope[d]) for d in tip_setback.DRIVES]
    defl = [ratio(branch.deflection[d]) for d in tip_setback.DRIVES]
    return (Example().tuple_of(f"slope({at})", [examples.evaluate(e, args) for e in slope]),
            Example().tuple_of(f"deflection({at})", [examples.evaluate(e, args) for e in defl]),
            Example().statement(f"values, jacobian = slope_and_jacobian({at}, wrt=('sigma',))").tuple_of(
                "", [examples.derivative(e, args, detection.sigma) for e in slope],
                target=f"[row[{JACOBIAN.index('sigma')}] for row in jacobian]"))


def _keywords(params) -> str:
    """Keyword arguments of the blind-spot coefficients: ``beta``, ``gamma``, the lever's other
    dimensionless parameters (``mu``, and any a tip term adds), the dimensionless stiffnesses."""
    dimensional = {"k", "kvv", "kll", "kvl", "H", "L", "gamma"}
    return ", ".join(["beta", "gamma", *(str(p) for p in params if str(p) not in dimensional), *DIMENSIONLESS])


def _render_branch(name: str) -> dict:
    """Template context of one branch, ``before`` or ``beyond`` the tip."""
    row = registry.by_module("tip_setback")
    params = [symbol(p, tip_setback) for p in row.parameters]
    signature = f"beta, sigma, {', '.join(map(str, params))}"
    branch, tags = {"before": (detection.solve().before, "abs"), "beyond": (detection.solve().beyond, "abr")}[name]
    values, defl, d_values, wrt = _scaled_branch(branch, params)
    atoms = _atoms(tags)
    printed = {}
    for what, exprs in (("slope", values), ("deflection", defl)):
        lines, reduced = cse_lines(exprs)
        printed[what] = {"lines": lines, "den": reduced[0], "nums": reduced[1:]}
    jacobian = and_jacobian(f"_slope_{name}", signature, f"slope at the spot, spot {name} the tip", atoms,
                            wrt, values, d_values, Example())
    return {"name": name, "atoms": atoms, **printed, "jacobian": jacobian,
            "lever_atoms": _atoms(tags[:-1], m="m"), "spot": tags[-1], "argument": _ARGS[tags[-1]],
            "where": "0 < sigma <= gamma" if name == "before" else "gamma <= sigma <= 1",
            "q0": _blind_spot_coefficients(branch)}


def _stored_examples() -> tuple:
    """The doctests (:func:`_examples`) of the registry's parameters."""
    row = registry.by_module("tip_setback")
    return _examples(detection.solve(), [symbol(p, tip_setback) for p in row.parameters])


def _rendered() -> tuple[list[dict], tuple]:
    """Both branches and the doctests; the ``beyond`` branch and the doctests in forked
    processes where there is a second core.

    The three share nothing after :func:`derivations.detection.solve` (solved here, before
    the fork, so the children inherit it) and each is made by the same code in any process:
    the text does not depend on where it was made.
    """
    detection.solve()
    if "fork" not in multiprocessing.get_all_start_methods() or (os.cpu_count() or 1) < 2:
        return [_render_branch("before"), _render_branch("beyond")], _stored_examples()
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork")) as pool:
        beyond, examples_ = pool.submit(_render_branch, "beyond"), pool.submit(_stored_examples)
        return [_render_branch("before"), beyond.result()], examples_.result()


@lru_cache(maxsize=None)
def render() -> str:
    """Source text of ``generated/detection.py`` (once per process: it takes minutes)."""
    row = registry.by_module("tip_setback")
    params = [symbol(p, tip_setback) for p in row.parameters]
    sol = detection.solve()
    names = ", ".join(map(str, params))
    signature = f"beta, sigma, {names}"
    branches, (slope_example, deflection_example, jacobian_example) = _rendered()
    hashed = [e for b in (sol.before, sol.beyond) for e in (b.denominator, *b.slope.values(), *b.deflection.values())]
    exported = ["PARAMETERS", "DRIVES", "JACOBIAN_PARAMETERS", "slope", "deflection", "slope_and_jacobian",
                *(f"q0_slope_{b}{suffix}" for b in ("before", "beyond") for suffix in ("", "_coefficients"))]
    return templates.render(
        "detection.py.jinja", header=header("derivations/detection.py: solve()", source_hash(hashed)),
        source="derivations/detection.py: solve()", names=names, signature=signature, keywords=_keywords(params),
        dimensionless="; ".join(f"``{k}`` = {v}" for k, v in DIMENSIONLESS.items()),
        exported=sorted(exported), parameters=tuple(map(str, params)), jacobian_parameters=JACOBIAN,
        drives=row.drives, slope_example=slope_example, deflection_example=deflection_example,
        jacobian_example=jacobian_example, branches=branches)
