"""Code generation: the derived transfer functions as stable NumPy code in ``generated/``.

Every boundary-condition family is a ratio ``numerator / denominator`` of polynomials in
the parameters, ``beta`` and cos, sin, cosh, sinh of ``beta``.  The pipeline is

1. *split* each polynomial by parameter monomial: ``sum_m p_m * beta**a_m * h_m(beta)``,
   where each ``h_m`` is a primitive trigonometric-hyperbolic polynomial with rational
   coefficients and no parameter (:func:`split`).  The ``h`` functions form the family's
   *basis*; all transfer coefficients of a family share it, so cos, sin, and the scaled
   hyperbolics are computed once.
2. *stabilise* each basis function: for ``|beta|`` at or above a switch point it is
   divided by ``cosh(beta)**d`` (``d`` = the family's highest hyperbolic degree) and
   written with ``e = exp(-beta)``: ``tanh = (1 - e**2)/(1 + e**2)``,
   ``sech = 2 e/(1 + e**2)``, so nothing overflows; below the switch point it is its
   Taylor series, generated from the same expression (:func:`series_branch`).  Both
   branches scale numerator and denominator alike, so the ratio is unchanged.
3. *print* with CSE (numbered ``_t`` symbols, canonical order) into a module per family,
   with a header naming the source and a sha256 of the source expressions' ``srepr``.

``generated/characteristic.py`` holds each family's characteristic function in
dimensionless, scaled form, written against a math namespace ``m`` (NumPy, mpmath or
python-flint), for certified root finding.

Run through ``pfmdyn codegen`` (see :mod:`pfmdyn.commands.codegen`).
"""
from __future__ import annotations

import hashlib
import math
import textwrap
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import mpmath as mp
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from . import (codegen_setback, elastic_contact, free_end, frictionless, indentation, pinned,
               sliding_friction, tilt, tip_mass, torsion)
from .beam import H, L, beta, d1, d2, f0, k, k1, k2, q0

__all__ = ["Function", "Family", "families", "split", "from_atoms", "scaled", "series_branch",
           "switch_point", "source_hash", "render_family", "characteristic_families",
           "dimensionless", "beta1_free", "render_characteristic", "render_all", "write",
           "GENERATED"]

GENERATED = Path(__file__).resolve().parent.parent / "generated"
"""The committed output folder (``generated/`` at the repository root)."""

z = sp.Symbol("z", positive=True)
"""Dimensionless variable of the torsion families: ``z = xi L``."""

# Atoms of the closed form (large branch): the scaled hyperbolics and the trig functions.
_c, _s, _tanh, _sech = sp.symbols("_c _s _tanh _sech")
_ch, _sh = sp.symbols("_ch _sh")

# Switch-point search: the closed form must lose at most this factor to cancellation.
_MAX_CANCELLATION = 64
# Series truncation target, relative to the function's value at the switch point.
_SERIES_TOL = 2.0**-56
# Beyond Re(beta) = 100, e**-beta < 4e-44: far below the rounding error of the O(1)
# terms every scaled basis function contains, so the argument of exp is clipped there to
# avoid underflow (which `np.errstate(all="raise")` reports), also inside complex
# division, whose intermediate products are of order e**-4 Re(beta).
_CLIP = 100


@dataclass(frozen=True)
class Function:
    """One generated function: outputs ``numerator_i / denominator`` for the named drives."""

    name: str
    summary: str
    outputs: tuple[tuple[str, sp.Expr], ...]


@dataclass(frozen=True)
class Family:
    """A boundary-condition family: one generated module."""

    module: str
    source: str
    equations: str
    description: str
    variable: sp.Symbol
    parameters: tuple[sp.Symbol, ...]
    denominator: sp.Expr
    functions: tuple[Function, ...]

    def source_exprs(self) -> list[sp.Expr]:
        """Denominator then every numerator, in output order (hashed into the header)."""
        return [self.denominator] + [e for f in self.functions for _, e in f.outputs]


def _flexural(module, source, equations, sol, drives, params, deflection=False) -> Family:
    fns = [Function("slope", "tip slope theta = u0'(L) per unit drive",
                    tuple((name, sol.slope[d]) for name, d in drives))]
    if deflection:
        fns.append(Function("deflection", "tip displacement u0(L) per unit drive",
                            tuple((name, sol.deflection[d]) for name, d in drives)))
    return Family(module, source, equations, sol.problem.description, beta, params,
                  sol.denominator, tuple(fns))


def _torsion(module, source, equations, sol, params) -> Family:
    # Write in z = xi L and multiply numerator and denominator by L: polynomials again.
    num = sp.expand(L * sol.numerator.subs(torsion.xi, z / L) / sol.drive)
    den = sp.expand(L * sol.denominator.subs(torsion.xi, z / L))
    fn = Function("twist", "tip twist Theta0(L) per unit drive", ((str(sol.drive), num),))
    return Family(module, source, equations, sol.name, z, params, den, (fn,))


@lru_cache(maxsize=None)
def families() -> tuple[Family, ...]:
    """Every family that gets a generated module, in a fixed order.

    >>> [f.module for f in families()][:3]
    ['elastic_contact', 'frictionless', 'frictionless_stiff']
    """
    fl = sliding_friction.f_l
    return (
        _flexural("elastic_contact", "derivations/elastic_contact.py: solve()", "Eqs. 5-10",
                  elastic_contact.solve(), (("d1", d1), ("d2", d2), ("f0", f0), ("q0", q0)),
                  (k, k1, k2, H, L)),
        _flexural("frictionless", "derivations/frictionless.py: solve()", "Eq. 23",
                  frictionless.solve(), (("d1", d1), ("f0", f0), ("q0", q0)), (k, k1, L)),
        _flexural("frictionless_stiff", "derivations/frictionless.py: solve_stiff()", "Eq. 24",
                  frictionless.solve_stiff(), (("d1", d1), ("q0", q0)), (k, L)),
        _flexural("pinned", "derivations/pinned.py: solve()", "Eqs. 19-20",
                  pinned.solve(), (("q0", q0),), (k,)),
        _flexural("free_end", "derivations/free_end.py: solve()", "Eqs. 21-22",
                  free_end.solve(), (("f0", f0), ("q0", q0)), (k, L)),
        _flexural("sliding_friction", "derivations/sliding_friction.py: solve()", "Eqs. 25-26",
                  sliding_friction.solve(), (("f_l", fl),), (k, H, L)),
        _flexural("indentation", "derivations/indentation.py: solve()", "Eqs. 27-28",
                  indentation.solve(), (("d1", d1), ("f0", f0)), (k, k1, L), deflection=True),
        _flexural("indentation_stiff", "derivations/indentation.py: solve_stiff()", "Eq. 29",
                  indentation.solve_stiff(), (("d1", d1),), (k, L)),
        _flexural("tip_mass", "derivations/tip_mass.py: solve()", "Eqs. 4-5 with tip inertia",
                  tip_mass.solve(), (("d1", d1), ("d2", d2), ("f0", f0), ("q0", q0)),
                  (k, k1, k2, H, L, tip_mass.mu)),
        _flexural("tilt", "derivations/tilt.py: solve()", "Eqs. 4-5 with a tilted cantilever",
                  tilt.solve(), (("d1", d1), ("d2", d2), ("f0", f0), ("q0", q0)),
                  (k, tilt.kvv, tilt.kll, tilt.kvl, H, L)),
        _torsion("torsion_elastic", "derivations/torsion.py: solve_elastic()", "Eqs. 32-33",
                 torsion.solve_elastic(), (torsion.k2t, H, L)),
        _torsion("torsion_force", "derivations/torsion.py: solve_force()", "Eqs. 34-35",
                 torsion.solve_force(), (L,)),
    )


def _to_atoms(expr: sp.Expr, var: sp.Symbol) -> sp.Expr:
    return expr.subs({sp.cos(var): _c, sp.sin(var): _s, sp.cosh(var): _ch, sp.sinh(var): _sh})


def from_atoms(expr: sp.Expr, var: sp.Symbol) -> sp.Expr:
    """Replace the atoms ``_c, _s, _ch, _sh`` by cos, sin, cosh, sinh of ``var``.

    >>> from_atoms(_c*_ch + 1, beta)
    cos(beta)*cosh(beta) + 1
    """
    return expr.subs({_c: sp.cos(var), _s: sp.sin(var), _ch: sp.cosh(var), _sh: sp.sinh(var)})


def split(expr: sp.Expr, var: sp.Symbol, params) -> list[tuple[sp.Expr, sp.Expr]]:
    """``expr`` as ``[(coefficient, h), ...]`` with ``expr = sum coefficient * h``.

    ``coefficient`` is a rational times a monomial in the parameters and ``var``; ``h`` is
    a primitive polynomial in cos, sin, cosh, sinh of ``var`` (positive leading
    coefficient), written with the atoms ``_c, _s, _ch, _sh``.

    >>> split(3*L*beta**4*k + 3*L*beta**4*k*sp.cos(beta)*sp.cosh(beta), beta, (k, L))
    [(3*L*beta**4*k, _c*_ch + 1)]
    """
    poly = sp.Poly(_to_atoms(expr, var), var, *params)
    groups: dict[sp.Expr, sp.Expr] = {}
    for monom, coeff in poly.terms():
        mono = sp.Mul(*[g**e for g, e in zip(poly.gens, monom)])
        groups[mono] = groups.get(mono, 0) + coeff
    out = []
    for mono, h in groups.items():
        hp = sp.Poly(h, _c, _s, _ch, _sh)
        content, prim = hp.primitive()
        if prim.LC() < 0:
            content, prim = -content, -prim
        out.append((content * mono, prim.as_expr()))
    return sorted(out, key=lambda t: sp.default_sort_key(t))


def _hyperbolic_degree(h: sp.Expr) -> int:
    return sp.Poly(h, _ch, _sh).total_degree()


def scaled(h: sp.Expr, degree: int) -> sp.Expr:
    """``h / cosh**degree`` in the atoms ``_c, _s, _tanh, _sech``.

    >>> scaled(_c*_ch + 1, 1)
    _c + _sech
    """
    poly = sp.Poly(h, _ch, _sh)
    out = sp.S.Zero
    for (a, b), coeff in poly.terms():
        out += coeff * _tanh**b * _sech**(degree - a - b)
    return sp.expand(out)


def _mp_value(h: sp.Expr, var_value, var: sp.Symbol):
    f = sp.lambdify(var, from_atoms(h, var), "mpmath")
    return f(var_value)


def _cancellation(h: sp.Expr, x: float, degree: int) -> float:
    """Error amplification of the scaled closed form of ``h`` at ``x`` (mpmath).

    Sum of |terms| over |value|, where a term holding ``tanh`` counts ``1/(1 - e**-2x)``
    times: ``tanh = (1 - e**2)/(1 + e**2)`` cancels in floating point at small ``x``.
    """
    with mp.workdps(60):
        vals = {_c: mp.cos(x), _s: mp.sin(x), _tanh: mp.tanh(x), _sech: mp.sech(x)}
        tanh_cond = 1 / -mp.expm1(-2 * mp.mpf(x))
        terms = [(mp.mpf(sp.Float(t.subs(vals), 60)), tanh_cond if t.has(_tanh) else 1)
                 for t in sp.Add.make_args(scaled(h, degree))]
        total = abs(sum(t for t, _ in terms))
        return float(sum(abs(t) * c for t, c in terms) / total)


def switch_point(h: sp.Expr, degree: int) -> float:
    """Smallest ``|beta|`` (grid step 1/20) where the closed form of ``h`` loses < 64x to cancellation.

    >>> switch_point(_c*_ch + 1, 1)     # no cancellation near 0: no series branch needed
    0.0
    >>> switch_point(_c*_ch - 1, 1)     # cos cosh - 1 ~ -beta**4/6
    0.7
    """
    x = 0.0
    while _cancellation(h, x or 1e-3, degree) > _MAX_CANCELLATION:
        x = round(x + 0.05, 2)
    return x


def _taylor(h: sp.Expr, var: sp.Symbol, order: int) -> sp.Poly:
    """Taylor polynomial of ``h`` (in atoms) up to ``var**(order - 1)``, exact rationals."""
    f = sp.factorial
    atoms = {
        _c: sum((-1)**j * var**(2*j) / f(2*j) for j in range(order // 2 + 1)),
        _s: sum((-1)**j * var**(2*j + 1) / f(2*j + 1) for j in range(order // 2 + 1)),
        _ch: sum(var**(2*j) / f(2*j) for j in range(order // 2 + 1)),
        _sh: sum(var**(2*j + 1) / f(2*j + 1) for j in range(order // 2 + 1)),
    }
    full = sp.Poly(sp.expand(h.subs(atoms)), var)
    return sp.Poly.from_dict({m: c for m, c in full.as_dict().items() if m[0] < order}, var)


def series_branch(h: sp.Expr, var: sp.Symbol, at: float) -> tuple[int, int, list[sp.Rational]]:
    """Taylor series of ``h`` as ``var**p * P(var**q)``: returns ``(p, q, coefficients of P)``.

    Terms are added until the first omitted one is below 2**-56 of ``|h(at)|``: truncation
    error matches rounding error at the switch point ``at`` and is smaller below it.

    >>> series_branch(_c*_ch - 1, beta, 0.7)
    (4, 4, [-1/6, 1/2520, -1/7484400, 1/81729648000])
    """
    with mp.workdps(40):
        target = abs(_mp_value(h, mp.mpf(at), var)) * _SERIES_TOL
    order = 12
    while True:
        ser = _taylor(h, var, order)
        exps = sorted(m[0] for m in ser.monoms())
        p = exps[0]
        q = math.gcd(*[e - p for e in exps[1:]]) if len(exps) > 1 else 4
        nxt = exps[-1] + q
        # The first omitted term bounds the truncation error (factorial decay).
        omitted = abs(_taylor(h, var, nxt + 1).coeff_monomial(var**nxt)) * mp.mpf(at) ** nxt
        if len(exps) > 2 and omitted < target:
            return p, q, [ser.coeff_monomial(var**e) for e in range(p, exps[-1] + 1, q)]
        order += 4


class _Printer(PythonCodePrinter):
    """Plain arithmetic printer: rationals as exact float literals, no module prefixes."""

    def _print_Rational(self, expr):
        return repr(float(expr))


def _code(expr: sp.Expr) -> str:
    return _Printer({"standard": "python3"}).doprint(expr)


def _horner(coeffs, u: str) -> str:
    text = repr(float(coeffs[-1]))
    for c in reversed(coeffs[:-1]):
        text = f"{float(c)!r} + {u}*({text})"
    return text


def _cse_lines(exprs, indent="    ") -> tuple[list[str], list[str]]:
    reps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_t"), order="canonical")
    lines = [f"{indent}{sym} = {_code(val)}" for sym, val in reps]
    return lines, [_code(e) for e in reduced]


def source_hash(exprs) -> str:
    """sha256 of the ``srepr`` of the source expressions (recorded in generated headers).

    >>> len(source_hash([beta]))
    64
    """
    return hashlib.sha256("\n".join(sp.srepr(e) for e in exprs).encode()).hexdigest()


def _header(source: str, digest: str) -> str:
    return (
        "# generated — do not edit.\n"
        f"# Generated by `pfmdyn codegen` (derivations/codegen.py) from {source}.\n"
        f"# SymPy {sp.__version__}; sha256 of the source expressions' srepr: {digest}\n"
    )


def _basis(fam: Family):
    """Distinct basis functions ``h`` of a family and each output's split over them."""
    basis: list[sp.Expr] = []
    splits = []
    for expr in fam.source_exprs():
        parts = split(expr, fam.variable, fam.parameters)
        for _, h in parts:
            if h not in basis:
                basis.append(h)
        splits.append(parts)
    basis.sort(key=sp.default_sort_key)
    return basis, splits


def render_family(fam: Family) -> str:
    """Source text of the generated module of one family."""
    var = fam.variable
    vname = str(var)
    basis, splits = _basis(fam)
    degree = max(_hyperbolic_degree(h) for h in basis)
    switch = max(switch_point(h, degree) for h in basis)
    hsyms = [sp.Symbol(f"_h{i}") for i in range(len(basis))]
    combos = [sum(coeff * hsyms[basis.index(h)] for coeff, h in parts) for parts in splits]

    if degree:
        evaluation = textwrap.fill(
            f"each evaluated once per call: by its Taylor series for ``|{vname}| < SWITCH`` "
            f"(where the closed form cancels), else in closed form divided by "
            f"``cosh({vname})**{degree}`` with ``tanh`` and ``sech`` built from "
            f"``exp(-{vname})``, so nothing overflows up to ``{vname} = 1e3`` and beyond.", 88)
    else:
        evaluation = textwrap.fill(
            "each evaluated once per call in closed form: there are no hyperbolics and no "
            "cancellation near 0, so no series branch (``SWITCH = 0``).", 88)
    out = [_header(fam.source, source_hash(fam.source_exprs()))]
    names = ", ".join(str(p) for p in fam.parameters)
    doc_basis = "\n".join(f"    h{i} = {sp.sstr(from_atoms(h, var))}" for i, h in enumerate(basis))
    out.append(f'''"""{fam.module}: {fam.description}.

Source: {fam.source}, {fam.equations} of Jesse, Baddorf, Kalinin 2006; signs as there.

Transfer coefficients as NumPy functions of ``{vname}``, vectorised over ``{vname}`` (real or
complex, ``Re {vname} > 0``) and broadcasting over the parameters ({names}).

Every numerator and the denominator are sums of parameter monomials times the basis

{doc_basis}

{evaluation}
"""
import numpy as np

__all__ = {sorted([f.name for f in fam.functions] + ["PARAMETERS", "DRIVES", "SWITCH"])!r}

PARAMETERS = {tuple(str(p) for p in fam.parameters)!r}
DRIVES = {tuple(name for name, _ in fam.functions[0].outputs)!r}
SWITCH = {switch!r}
"""``|{vname}|`` below which the basis is evaluated by its series."""


def _basis({vname}):
    """The basis functions h0... at ``{vname}`` (series or scaled closed form, see module)."""
    {vname} = np.asarray({vname})
    out = np.empty(({len(basis)},) + {vname}.shape, np.result_type({vname}, float))
''')
    body = []
    if switch > 0:
        body.append(f"    small = np.abs({vname}) < SWITCH")
        body.append(f"    x = {vname}[small]")
        series = [series_branch(h, var, switch) for h in basis]
        for q in sorted({q for _, q, _ in series}):
            body.append(f"    _u{q} = x**{q}")
        for i, (p, q, coeffs) in enumerate(series):
            lead = f"x**{p} * " if p > 1 else ("x * " if p == 1 else "")
            body.append(f"    out[{i}, small] = {lead}({_horner(coeffs, f'_u{q}')})")
        body.append("    large = ~small")
        body.append(f"    x = {vname}[large]")
        target = "large"
    else:
        body.append(f"    x = {vname}")
        target = "..."
    body.append("    _c = np.cos(x)")
    body.append("    _s = np.sin(x)")
    if degree:
        body.append(f"    _e = np.exp(np.maximum(x.real - {_CLIP}.0, 0.0) - x)")
        body.append("    _e2 = _e * _e")
        body.append("    _tanh = (1.0 - _e2) / (1.0 + _e2)")
        body.append("    _sech = 2.0 * _e / (1.0 + _e2)")
    lines, reduced = _cse_lines([scaled(h, degree) for h in basis])
    body.extend(lines)
    body.extend(f"    out[{i}, {target}] = {r}" for i, r in enumerate(reduced))
    body.append("    return out")
    out.append("\n".join(body) + "\n")

    start = 1
    for fn in fam.functions:
        n = len(fn.outputs)
        den = combos[0]
        nums = combos[start:start + n]
        start += n
        used = sorted({s for e in [den, *nums] for s in e.free_symbols if s in hsyms},
                      key=lambda s: int(str(s)[2:]))
        lines, reduced = _cse_lines([den, *nums])
        if len(used) == len(hsyms):
            unpack = f"{', '.join(map(str, used))} = _basis({vname})"
        else:
            # Only part of the basis enters this function: pick its rows.
            rows = [int(str(s)[2:]) for s in used]
            unpack = f"{', '.join(map(str, used))}{',' if len(used) == 1 else ''} = _basis({vname})[{rows}]"
        doc_out = "\n".join(f"        per unit {name}" for name, _ in fn.outputs)
        out.append(f'''

def {fn.name}({vname}, {names}):
    """{fn.summary[0].upper() + fn.summary[1:]}.

    Parameters
    ----------
    {vname} : array_like, real or complex, ``Re {vname} > 0``
    {names} : array_like, broadcast against ``{vname}``

    Returns
    -------
    tuple of ndarray
{doc_out}
    """
    {unpack}
    {vname} = np.asarray({vname})
''')
        out.append("\n".join(lines) + ("\n" if lines else ""))
        out.append(f"    _r = 1.0 / ({reduced[0]})\n")
        values = [f"({r}) * _r" for r in reduced[1:]]
        out.append(f"    return ({', '.join(values)}{',' if len(values) == 1 else ''})\n")
    return "".join(out)


# --- characteristic functions ------------------------------------------------------

k1_over_k, k2_ratio, k2t_HL = sp.symbols("k1_over_k k2_ratio k2t_HL", positive=True)

_DIMENSIONLESS = {k1: k1_over_k * k, k2: k2_ratio * k * L**2 / H**2,
                  torsion.k2t: k2t_HL / (H * L)}
_PARAM_DOC = {
    "k1_over_k": "k1 / k, vertical contact stiffness over the cantilever spring constant",
    "k2_ratio": "k2 H**2 / (k L**2), longitudinal contact stiffness seen through the lever arm H",
    "k2t_HL": "k2t H L = H**2 k2 L / c_T, lateral contact stiffness over torsional stiffness",
}


def characteristic_families() -> list[tuple[str, str, sp.Expr, sp.Symbol]]:
    """(name, source, denominator, variable) of the families exported in ``FAMILIES``.

    >>> [name for name, *_ in characteristic_families()][:2]
    ['free', 'pinned']
    """
    by_module = {f.module: f for f in families()}
    pick = [("free", "free_end"), ("pinned", "pinned"), ("elastic", "elastic_contact"),
            ("frictionless", "frictionless"), ("friction", "sliding_friction"),
            ("indentation", "indentation"), ("torsion-elastic", "torsion_elastic"),
            ("torsion-force", "torsion_force")]
    return [(name, by_module[m].source, by_module[m].denominator, by_module[m].variable)
            for name, m in pick]


def dimensionless(den: sp.Expr, var: sp.Symbol) -> sp.Expr:
    """Denominator in dimensionless parameters with monomial and integer content removed.

    The sign is fixed so that the term of highest power in ``var`` is positive.

    >>> dimensionless(free_end.solve().denominator, beta)
    cos(beta)*cosh(beta) + 1
    >>> from .torsion import L, solve_force, xi
    >>> dimensionless(solve_force().denominator.subs(xi, beta / L), beta)
    cos(beta)
    """
    expr = _to_atoms(sp.expand(den.subs(_DIMENSIONLESS)), var)
    expr = sp.expand(sp.together(expr))
    num, _ = sp.fraction(sp.together(expr))
    gens = sorted(num.free_symbols, key=str)
    poly = sp.Poly(num, *gens)
    # Monomial content in the variable and the parameters has no positive zeros and goes;
    # a common power of cos, sin, cosh or sinh does have zeros and stays.
    exponents, poly = poly.terms_gcd()
    atoms = {_c, _s, _ch, _sh}
    poly = sp.Poly(poly.as_expr() * sp.Mul(*[g**e for g, e in zip(gens, exponents) if g in atoms]), *gens)
    _, poly = poly.clear_denoms()
    _, poly = poly.primitive()
    lead = sp.Poly(poly.as_expr(), var).LC()
    sign = -1 if sp.Poly(lead, *sorted(lead.free_symbols, key=str) or [var]).LC() < 0 else 1
    # Only the dimensionless parameters, the variable and the atoms may remain.
    result = sp.expand(sign * poly.as_expr())
    assert result.free_symbols <= {var, k1_over_k, k2_ratio, k2t_HL, _c, _s, _ch, _sh}, result
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
    out = [_header(srcs, digest), '''"""Characteristic functions (resonance conditions) of every family, dimensionless and scaled.

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
        atoms = _to_atoms(expr.subs(var, z), z)
        degree = _hyperbolic_degree(atoms) if atoms.has(_ch, _sh) else 0
        body = scaled(atoms, degree) if degree else atoms
        sig = "z, m" + (", *, " + ", ".join(params) if params else "")
        pdoc = "".join(f"\n    {p} : {_PARAM_DOC[p]}" for p in params)
        used = body.free_symbols
        lines = [line for atom, line in [(_c, "    _c = m.cos(z)"), (_s, "    _s = m.sin(z)")]
                 if atom in used]
        if degree:
            lines += ["    _e = m.exp(-z)", "    _e2 = _e * _e"]
            lines += [line for atom, line in [(_tanh, "    _tanh = (1 - _e2) / (1 + _e2)"),
                                              (_sech, "    _sech = 2 * _e / (1 + _e2)")]
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
    return {_code(body)}
''')
    out.append("\n\nFAMILIES = {\n" + "".join(
        f"    {n!r}: {n.replace('-', '_')},\n" for n, *_ in items) + "}\n")
    out.append('"""Family name -> characteristic function."""\n')
    out.append("PARAMETERS = {\n" + "".join(
        f"    {n!r}: {params_table[n]!r},\n" for n, *_ in items) + "}\n")
    out.append('"""Family name -> names of its dimensionless keyword parameters."""\n')
    return "".join(out)


def render_all() -> dict[str, str]:
    """File name -> text of every generated file (deterministic)."""
    files = {f"{fam.module}.py": render_family(fam) for fam in families()}
    files["characteristic.py"] = render_characteristic()
    files["tip_setback.py"] = codegen_setback.render(_header)
    return dict(sorted(files.items()))


def write(folder: Path) -> list[str]:
    """Write every generated file into ``folder``; return the names of files that changed."""
    folder.mkdir(parents=True, exist_ok=True)
    changed = []
    for name, text in render_all().items():
        path = folder / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            changed.append(name)
    return changed
