"""Renderer of ``generated/detection.py``: the beam read at a detection point ``x_s = sigma L``.

The detection solution (:mod:`derivations.detection`) has two branches, spot before and
beyond the tip, each a polynomial in the atoms of three arguments (``a = gamma beta``,
``b = (1 - gamma) beta`` and ``s = sigma beta`` or ``r = (1 - sigma) beta``).  They are
stabilised as the set-back family is (:mod:`.setback`): numerators and denominator divided
by ``cosh**d`` of every argument, ``tanh`` and ``sech`` built from clipped ``exp(-x)``.
Both branches are evaluated and ``numpy.where(sigma <= gamma, ...)`` picks one (each is
finite everywhere).

Written:

* ``slope``, ``deflection``: ``u'(sigma L)`` and ``u(sigma L)`` per unit d1, d2, f0, q0;
* ``slope_and_jacobian``: with the partials w.r.t. :data:`JACOBIAN`, for fits;
* ``q0_slope_before``, ``q0_slope_beyond``: the numerator of the slope per unit ``q0`` in
  dimensionless parameters, against a math namespace ``m`` (NumPy, mpmath or python-flint
  ``arb_series``, as in ``characteristic.py``): its zeros in ``sigma`` are the
  electrostatic blind spots (:mod:`pfmdyn.analysis.spot` certifies them).
"""
from __future__ import annotations

import sympy as sp

from .. import beam, detection, families as registry, tip_setback
from ..trig import hyperbolic_degree, normal_form, scaled
from .jacobian import partials, render_and_jacobian
from .printing import code, cse_lines, header, source_hash
from .setback import _grouped
from .stabilise import clipped_exp
from .transfer import symbol

__all__ = ["render", "JACOBIAN", "DIMENSIONLESS"]

JACOBIAN = ("beta", "sigma", "k", "kvv", "kll", "kvl", "mu", "gamma")
"""Parameters of ``slope_and_jacobian``, in column order."""

kvv_over_k, kll_ratio, kvl_ratio = sp.symbols("kvv_over_k kll_ratio kvl_ratio", real=True)
DIMENSIONLESS = {"kvv_over_k": "kvv / k", "kll_ratio": "kll H**2 / (k L**2)", "kvl_ratio": "kvl H / (k L)"}
"""The dimensionless stiffnesses of the blind-spot functions."""

_SETS = {"a": tip_setback.ATOMS_A, "b": tip_setback.ATOMS_B, "s": detection.ATOMS_S, "r": detection.ATOMS_R}
_ARGS = {"a": "gamma * beta", "b": "(1.0 - gamma) * beta", "s": "sigma * beta", "r": "(1.0 - sigma) * beta"}


def _atoms(tags: str, m: str = "np", indent: str = "    ") -> str:
    """Preamble defining the atoms (cos, sin, tanh, sech) of the arguments named in ``tags``.

    ``m``: the math namespace (``np``, with ``exp`` clipped as in :mod:`.setback`, or ``m``).
    """
    lines = []
    for t in tags:
        lines += [f"{t} = {_ARGS[t]}",
                  f"_c{t}, _s{t} = {m}.cos({t}), {m}.sin({t})",
                  f"_e{t} = " + (clipped_exp(t, f"np.real({t})") if m == "np" else f"m.exp(-{t})"),
                  f"_tanh{t} = (1 - _e{t} * _e{t}) / (1 + _e{t} * _e{t})",
                  f"_sech{t} = 2 * _e{t} / (1 + _e{t} * _e{t})"]
    return "".join(f"{indent}{line}\n" for line in lines)


def _scaled_branch(branch, params):
    """Values ``[D, N_d1.., N_q0]`` (slope), ``[D, ...]`` (deflection) and slope partials, scaled."""
    sets = branch.atoms
    exprs = [branch.denominator] + [branch.slope[d] for d in tip_setback.DRIVES]
    defl = [branch.denominator] + [branch.deflection[d] for d in tip_setback.DRIVES]
    degrees = {at: max(hyperbolic_degree(e, at) for e in exprs + defl) for at in sets}
    g, s = tip_setback.gamma, detection.sigma
    a, b, spot = sets
    beta_rate = {a: g, b: 1 - g, spot: s if spot == detection.ATOMS_S else 1 - s}
    rates = {beam.beta: beta_rate, g: {a: beam.beta, b: -beam.beta},
             s: {spot: beam.beta if spot == detection.ATOMS_S else -beam.beta}}
    by_name = {str(p): p for p in (beam.beta, s, *params)}
    wrt = [by_name[n] for n in JACOBIAN]
    d_exprs = [normal_form(d, *sets) for d in partials(exprs, wrt, rates)]
    assert all(hyperbolic_degree(e, at) <= degrees[at] for e in d_exprs for at in sets)
    grouped = [_grouped(scaled(e, degrees), params) for e in exprs]
    return grouped, [_grouped(scaled(e, degrees), params) for e in defl], \
        [_grouped(scaled(e, degrees), params) for e in d_exprs], wrt


def _dimensionless(expr, params):
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


def _blind_spot_functions(branch, name: str, tags: str, params) -> str:
    """``q0_slope_<name>_coefficients`` and ``q0_slope_<name>``: the q0 slope numerator in sigma.

    The numerator is linear in the spot's atoms, ``A cos + B sin + C cosh + E sinh + F`` of
    ``s`` (or ``r``): the coefficients depend only on the lever and the frequency, so they are
    evaluated once (tight balls) and the function of ``sigma`` is five terms.
    """
    q = _dimensionless(branch.slope[beam.q0], params)
    spot = branch.atoms[-1]
    lever = {at: hyperbolic_degree(q, at) for at in branch.atoms[:-1]}
    poly = sp.Poly(q, *spot.functions)
    assert poly.total_degree() <= 1, poly.total_degree()
    coeffs = [poly.coeff_monomial(g) for g in spot.functions] + [poly.coeff_monomial(1)]
    lines, reduced = cse_lines([scaled(c, lever) for c in coeffs])
    t = tags[-1]
    where = "0 < sigma <= gamma" if name == "before" else "gamma <= sigma <= 1"
    return f'''

def q0_slope_{name}_coefficients(m, *, beta, gamma, mu, kvv_over_k, kll_ratio, kvl_ratio):
    """Coefficients of cos, sin, cosh, sinh of ``{_ARGS[t]}`` and of 1 in :func:`q0_slope_{name}`.

    Dimensionless stiffnesses (module docstring); ``m`` supplies ``cos``, ``sin``, ``exp``
    (NumPy, mpmath, or ``characteristic.FLINT`` for python-flint balls); integer coefficients.
    """
{_atoms(tags[:-1], m="m")}''' + "\n".join(lines) + f'''
    return ({", ".join(reduced)})


def q0_slope_{name}(sigma, m, coefficients, beta):
    """Numerator of the slope at ``sigma L`` per unit ``q0``, spot {name} the tip.

    Its zeros in ``sigma`` (``{where}``) are the electrostatic blind spots: it is the ``q0``
    numerator of :func:`slope` times a positive factor (``cosh`` of the lever's arguments, a
    monomial in ``k``, ``L``, ``H``) and a sign fixed per branch.  ``coefficients``: from
    :func:`q0_slope_{name}_coefficients`; ``sigma`` may be a python-flint ``arb_series``.
    Unscaled in the spot's argument (an entire function: Taylor bounds are simple).
    """
    {t} = {_ARGS[t]}
    _e = m.exp({t})
    _A, _B, _C, _E, _F = coefficients
    return _A * m.cos({t}) + _B * m.sin({t}) + _C * (_e + 1 / _e) / 2 + _E * (_e - 1 / _e) / 2 + _F
'''


def render() -> str:
    """Source text of ``generated/detection.py``."""
    row = registry.by_module("tip_setback")
    params = [symbol(p, tip_setback) for p in row.parameters]
    sol = detection.solve()
    names = ", ".join(map(str, params))
    sig = f"beta, sigma, {names}"
    branches = {"before": (sol.before, "abs"), "beyond": (sol.beyond, "abr")}
    body, hashed = [], []
    for name, (branch, tags) in branches.items():
        values, defl, d_values, wrt = _scaled_branch(branch, params)
        hashed += [branch.denominator, *branch.slope.values(), *branch.deflection.values()]
        pre = "    beta = np.asarray(beta)\n" + _atoms(tags)
        for what, exprs in (("slope", values), ("deflection", defl)):
            lines, reduced = cse_lines(exprs)
            body.append(f'''

def _{what}_{name}({sig}):
    """{what} at the spot, spot {name} the tip (see :func:`{what}`)."""
{pre}''' + "\n".join(lines) + f'''
    _r = 1.0 / ({reduced[0]})
    return ({", ".join(f"({r}) * _r" for r in reduced[1:])})
''')
        body.append(render_and_jacobian(f"_slope_{name}", sig, f"slope at the spot, spot {name} the tip", pre,
                                        wrt, values, d_values))
        body.append(_blind_spot_functions(branch, name, tags, params))
    doc = f'''"""detection: the beam read at a detection point x_s = sigma L (slope and deflection).

Source: derivations/detection.py: solve(), from the set-back solution (tip at gamma L with
springs kvv, kll, kvl and tip mass mu; Eqs. 2-4 of Jesse, Baddorf, Kalinin 2006, signs as
there).  ``sigma = 1`` is the slope the paper reads (Eq. 5 at ``gamma = 1``, ``mu = 0``,
``kvv = k1``, ``kll = k2``, ``kvl = 0``).  Two branches, spot before (``sigma <= gamma``)
and beyond the tip; each is a ratio of polynomials in cos, sin, cosh, sinh of
``gamma beta``, ``(1 - gamma) beta`` and ``sigma beta`` or ``(1 - sigma) beta``, divided by
powers of cosh with tanh, sech from clipped ``exp(-x)``.  No series branch: use
``Re beta > 0.1`` (below, the closed form cancels: about ``beta**-6`` of the largest term
is lost).

Blind-spot functions ``q0_slope_before``, ``q0_slope_beyond`` take dimensionless stiffnesses:
''' + "".join(f"``{k_}`` = {v}; " for k_, v in DIMENSIONLESS.items()).rstrip("; ") + '''.
"""
import numpy as np

'''
    public = ["PARAMETERS", "DRIVES", "JACOBIAN_PARAMETERS", "slope", "deflection", "slope_and_jacobian",
              "q0_slope_before", "q0_slope_beyond", "q0_slope_before_coefficients", "q0_slope_beyond_coefficients"]
    consts = f'''__all__ = {sorted(public)!r}

PARAMETERS = {tuple(map(str, params))!r}
JACOBIAN_PARAMETERS = {JACOBIAN!r}
DRIVES = {row.drives!r}

''' + '''
def _pick(sigma, gamma, before, beyond):
    """The branch holding the spot, elementwise."""
    on = np.asarray(sigma) <= np.asarray(gamma)
    return tuple(np.where(on, x, y) for x, y in zip(before, beyond))
'''
    params_doc = f'''    Parameters
    ----------
    beta : array_like, real or complex, ``Re beta > 0.1`` (see module)
    sigma : array_like, detection point x_s / L, ``0 < sigma <= 1``
    {names} : array_like, broadcast against ``beta``; ``0 < gamma <= 1``
'''
    api = f'''

def slope({sig}):
    """Slope u0'(sigma L) at the detection point per unit drive.

{params_doc}
    Returns
    -------
    tuple of ndarray
        per unit d1, d2 (beam-frame surface displacements), f0, q0
    """
    return _pick(sigma, gamma, _slope_before({sig}), _slope_beyond({sig}))


def deflection({sig}):
    """Deflection u0(sigma L) at the detection point per unit drive (arguments as :func:`slope`)."""
    return _pick(sigma, gamma, _deflection_before({sig}), _deflection_beyond({sig}))


def slope_and_jacobian({sig}, wrt=JACOBIAN_PARAMETERS):
    """:func:`slope` and its partial derivatives w.r.t. ``JACOBIAN_PARAMETERS`` (those in ``wrt``).

    Returns
    -------
    values : tuple of ndarray
        as :func:`slope`
    jacobian : tuple of tuples of ndarray
        ``jacobian[i][j]``: derivative of ``values[i]`` w.r.t. ``JACOBIAN_PARAMETERS[j]`` (None
        when not in ``wrt``)
    """
    v0, j0 = _slope_before_and_jacobian({sig}, wrt)
    v1, j1 = _slope_beyond_and_jacobian({sig}, wrt)
    jac = tuple(tuple(None if x is None else np.where(np.asarray(sigma) <= np.asarray(gamma), x, y)
                      for x, y in zip(r0, r1)) for r0, r1 in zip(j0, j1))
    return _pick(sigma, gamma, v0, v1), jac
'''
    return header("derivations/detection.py: solve()", source_hash(hashed)) + doc + consts + api + "".join(body)
