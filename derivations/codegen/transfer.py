"""Renderer of the transfer modules: one ``generated/<module>.py`` per one-argument family.

Every family is a ratio ``numerator / denominator`` of polynomials in the parameters, the
variable (``beta``, or ``z = xi L`` for torsion) and cos, sin, cosh, sinh of it.  Each
polynomial is *split* by parameter monomial, ``sum_m p_m * beta**a_m * h_m(beta)``
(:func:`derivations.codegen.stabilise.split`); the ``h`` form the family's *basis*, shared
by all its transfer coefficients and evaluated once per call, stabilised (series below a
switch point, scaled closed form above).  Printed with CSE, headed with the source's hash,
laid out by ``templates/transfer.py.jinja``; each function carries a doctest at the stored
point (:mod:`.examples`).
"""
from __future__ import annotations

import importlib
import textwrap
from dataclasses import dataclass
from functools import lru_cache

import sympy as sp

from .. import beam, families as registry, tilt, tip_mass, torsion
from ..trig import ATOMS, from_atoms, hyperbolic_degree, scaled
from ..trig import normal_form
from . import examples, templates
from .examples import Example
from .jacobian import JACOBIANS, and_jacobian, partials
from .printing import code, cse_lines, header, horner, source_hash
from .stabilise import clipped_exp, series_branch, split, switch_point

__all__ = ["Function", "Family", "families", "symbol", "render_family", "z"]

z = sp.Symbol("z", positive=True)
"""Dimensionless variable of the torsion families: ``z = xi L``."""

_SUMMARY = {
    "slope": "tip slope theta = u0'(L) per unit drive",
    "deflection": "tip displacement u0(L) per unit drive",
    "twist": "tip twist Theta0(L) per unit drive",
}


@dataclass(frozen=True)
class Function:
    """One generated function: outputs ``numerator_i / denominator`` for the named drives."""

    name: str
    summary: str
    outputs: tuple[tuple[str, sp.Expr], ...]


@dataclass(frozen=True)
class Family:
    """A registry family with its derived expressions: one generated module."""

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


def symbol(name: str, module) -> sp.Symbol:
    """The SymPy symbol of parameter ``name`` as the derivation ``module`` uses it.

    >>> symbol("mu", beam)
    mu
    """
    for ns in (module, beam, tilt, tip_mass):
        if isinstance(getattr(ns, name, None), sp.Symbol):
            return getattr(ns, name)
    raise KeyError(f"no symbol {name!r} for {module.__name__}")


def _derive(row: registry.Family) -> Family:
    module = importlib.import_module(f"{__package__.rsplit('.', 1)[0]}.{row.derivation}")
    sol = getattr(module, row.solver)()
    params = tuple(symbol(p, module) for p in row.parameters)
    if row.kind == "torsion":
        # Write in z = xi L and multiply numerator and denominator by L: polynomials again.
        L = symbol("L", module)
        assert (str(sol.drive),) == row.drives, (sol.drive, row.drives)
        num = sp.expand(L * sol.numerator.subs(torsion.xi, z / L) / sol.drive)
        den = sp.expand(L * sol.denominator.subs(torsion.xi, z / L))
        fns = (Function("twist", _SUMMARY["twist"], ((row.drives[0], num),)),)
        return Family(row.module, row.source, row.equations, sol.name, z, params, den, fns)
    by_output = {"slope": sol.slope, "deflection": sol.deflection}
    fns = []
    for output in row.outputs:
        exprs = {str(d): e for d, e in by_output[output].items()}
        fns.append(Function(output, _SUMMARY[output], tuple((d, exprs[d]) for d in row.drives)))
    return Family(row.module, row.source, row.equations, sol.problem.description, beam.beta,
                  params, sol.denominator, tuple(fns))


@lru_cache(maxsize=None)
def families() -> tuple[Family, ...]:
    """Every one-argument family of the registry with its derived expressions, in registry order.

    >>> [f.module for f in families()][:3]
    ['free_end', 'pinned', 'elastic_contact']
    """
    return tuple(_derive(row) for row in registry.FAMILIES)


def _partials(fam: Family) -> tuple[tuple[sp.Symbol, ...], list[sp.Expr]]:
    """The family's Jacobian parameters and ``d e / d p`` of every source expression (normal form)."""
    names = JACOBIANS.get(fam.module, ())
    wrt = tuple(fam.variable if n == str(fam.variable) else fam.parameters[[str(p) for p in fam.parameters].index(n)]
                for n in names)
    return wrt, [normal_form(d) for d in partials(fam.source_exprs(), wrt, {fam.variable: {ATOMS: 1}})]


def _unpack(vname: str, exprs, hsyms) -> str:
    """The line unpacking the basis rows that ``exprs`` use."""
    used = sorted({s for e in exprs for s in e.free_symbols if s in hsyms}, key=lambda s: int(str(s)[2:]))
    if len(used) == len(hsyms):
        return f"{', '.join(map(str, used))} = _basis({vname})"
    # Only part of the basis enters this function: pick its rows (views: indexing by a list would copy them).
    rows = [int(str(s)[2:]) for s in used]
    return f"{', '.join(map(str, used))}{',' if len(used) == 1 else ''} = map(_basis({vname}).__getitem__, {rows})"


def _basis(fam: Family, exprs):
    """Distinct basis functions ``h`` of ``exprs`` and each one's split over them."""
    basis: list[sp.Expr] = []
    splits = []
    for expr in exprs:
        parts = [(c, h) for c, h in split(expr, fam.variable, fam.parameters) if h != 0]
        for _, h in parts:
            if h not in basis:
                basis.append(h)
        splits.append(parts)
    basis.sort(key=sp.default_sort_key)
    return basis, splits


def _example(fam: Family, fn: Function, wrt) -> tuple[Example, Example | None]:
    """Doctests of ``fn`` and of its ``_and_jacobian`` at the stored point (:mod:`.examples`)."""
    args = (fam.variable, *fam.parameters)
    call = f"{fn.name}({examples.arguments(map(str, args))})"
    ratios = [num / fam.denominator for _, num in fn.outputs]
    example = Example().tuple_of(call, [examples.evaluate(e, args) for e in ratios])
    if not wrt:
        return example, None
    jac = Example().statement(f"values, jacobian = {fn.name}_and_jacobian({examples.arguments(map(str, args))})")
    jac.tuple_of("", [examples.derivative(ratios[0], args, p) for p in wrt], target="jacobian[0]")
    return example, jac


def render_family(fam: Family) -> str:
    """Source text of the generated module of one family (``templates/transfer.py.jinja``)."""
    var = fam.variable
    vname = str(var)
    wrt, d_exprs = _partials(fam)
    n_src = len(fam.source_exprs())
    basis, splits = _basis(fam, fam.source_exprs() + d_exprs)
    degree = max(hyperbolic_degree(h) for h in basis)
    switch = max(switch_point(h, degree) for h in basis)
    hsyms = [sp.Symbol(f"_h{i}") for i in range(len(basis))]
    combos = [sp.sympify(sum(coeff * hsyms[basis.index(h)] for coeff, h in parts)) for parts in splits]

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
    series = None
    if switch > 0:
        terms = [series_branch(h, var, switch) for h in basis]
        x = sp.Symbol("x")
        series = {"powers": {q: code(x**q, {x}) for q in sorted({q for _, q, _ in terms})},
                  "rows": [(f"{code(x**p, {x})} * " if p else "", horner(coeffs, f"_u{q}")) for p, q, coeffs in terms]}
    basis_lines, basis_code = cse_lines([scaled(h, {ATOMS: degree}) for h in basis],
                                        arrays={ATOMS.c, ATOMS.s, ATOMS.tanh, ATOMS.sech})
    names = ", ".join(str(p) for p in fam.parameters)
    functions = []
    start = 1
    for fn in fam.functions:
        n = len(fn.outputs)
        den = combos[0]
        nums = combos[start:start + n]
        d_combos = [combos[n_src * (1 + j) + i] for j in range(len(wrt)) for i in [0, *range(start, start + n)]]
        start += n
        lines, reduced = cse_lines([den, *nums], arrays={var, *hsyms})
        example, jac_example = _example(fam, fn, wrt)
        jacobian = None
        if wrt:
            preamble = f"    {_unpack(vname, [den, *nums, *d_combos], hsyms)}\n    {vname} = np.asarray({vname})"
            jacobian = and_jacobian(fn.name, f"{vname}, {names}", fn.summary, preamble, wrt,
                                    [den, *nums], d_combos, jac_example, arrays={var, *hsyms})
        functions.append({"name": fn.name, "summary": fn.summary, "drives": [d for d, _ in fn.outputs],
                          "unpack": _unpack(vname, [den, *nums], hsyms), "lines": lines, "den": reduced[0],
                          "nums": reduced[1:], "example": example, "jacobian": jacobian})
    exported = sorted([f.name for f in fam.functions] + ["PARAMETERS", "DRIVES", "SWITCH"]
                      + ([f"{f.name}_and_jacobian" for f in fam.functions] + ["JACOBIAN_PARAMETERS"] if wrt else []))
    return templates.render(
        "transfer.py.jinja", header=header(fam.source, source_hash(fam.source_exprs())), module=fam.module,
        description=fam.description, source=fam.source, equations=fam.equations, var=vname, names=names,
        basis_doc=[sp.sstr(from_atoms(h, var)) for h in basis], evaluation=evaluation, exported=exported,
        parameters=tuple(str(p) for p in fam.parameters),
        jacobian_parameters=tuple(map(str, wrt)) if wrt else None,
        drives=tuple(name for name, _ in fam.functions[0].outputs), switch=switch, series=series,
        degree=degree, clipped_exp=clipped_exp("x", "x.real"), basis_lines=basis_lines, basis_code=basis_code,
        functions=functions)
