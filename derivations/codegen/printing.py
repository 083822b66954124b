"""Printing for codegen: the one expression printer, CSE, Horner series, file header and source hash.

Every generated expression goes through :func:`code`: NumPy functions as ``np.<name>``
(the generated modules ``import numpy as np``), rationals as exact float literals.  Plain
arithmetic prints as Python, so the same text also runs on mpmath or python-flint numbers
(``generated/characteristic.py``).
"""
from __future__ import annotations

import hashlib

import sympy as sp
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import precedence

__all__ = ["IMPORTS", "imports", "code", "horner", "cse_lines", "source_hash", "header"]


class _Printer(NumPyPrinter):
    """NumPy printer writing ``np.<name>`` and rationals as float literals.

    ``arrays``: the symbols that stand for arrays (the rest are parameters, often scalars).  A
    product then multiplies its parameters first and the arrays after (one array operation per
    array factor), and an array's integer power is a product (``np.power`` is several times slower
    than multiplying).
    """

    def __init__(self, arrays=frozenset()):
        super().__init__({"fully_qualified_modules": True})
        self.arrays = frozenset(arrays)

    def _is_array(self, expr) -> bool:
        return bool(self.arrays & expr.free_symbols)

    def _print_Pow(self, expr, rational=False):
        base, exp = expr.args
        if base in self.arrays and exp.is_Integer and 2 < exp <= 8:
            return "(" + "*".join([self._print(base)] * int(exp)) + ")"
        return super()._print_Pow(expr, rational)

    def _print_Mul(self, expr):
        if not self.arrays:
            return super()._print_Mul(expr)
        coeff, factors = expr.as_coeff_mul()
        if coeff.is_negative:
            return "-" + self._print(-expr)
        params = [f for f in factors if not self._is_array(f)]
        arrays = [f for f in factors if self._is_array(f)]
        if not params or not arrays or any(f.is_Pow and f.exp.is_negative for f in factors):
            return super()._print_Mul(expr)
        return "*".join(self.parenthesize(f, precedence(expr)) for f in [sp.Mul(coeff, *params), *arrays])

    def _module_format(self, fqn, register=True):
        name = super()._module_format(fqn, register)
        return "np." + name[len("numpy."):] if name.startswith("numpy.") else name

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_besselk(self, expr):
        # SciPy's modified Bessel function of the second kind, complex arguments too (see IMPORTS)
        return f"kv({self._print(expr.args[0])}, {self._print(expr.args[1])})"


IMPORTS = {sp.besselk: "from scipy.special import kv"}
"""The import a printed function needs, made inside the function: SciPy is slow to import and few
generated functions need it (:func:`imports`)."""


def imports(expr: sp.Expr) -> list[str]:
    """The import lines a function computing ``expr`` needs (:data:`IMPORTS`).

    >>> x = sp.Symbol("x")
    >>> imports(sp.besselk(0, x) + sp.cos(x)), imports(sp.cos(x))
    (['from scipy.special import kv'], [])
    """
    return sorted({line for function, line in IMPORTS.items() if expr.atoms(function)})


def code(expr: sp.Expr, arrays=frozenset()) -> str:
    """Python source of ``expr`` (NumPy functions as ``np.``, rationals as float literals).

    ``arrays``: the symbols that are arrays (see :class:`_Printer`).

    >>> x, k = sp.symbols("x k")
    >>> code(sp.Rational(1, 2) * x)
    '(0.5)*x'
    >>> code(sp.cos(x)**2 + sp.sqrt(x))
    'np.sqrt(x) + np.cos(x)**2'
    >>> code(-3 * x**4 * k**2, arrays={x})
    '-(3*k**2)*(x*x*x*x)'
    """
    return _Printer(arrays).doprint(expr)


def horner(coeffs, u: str) -> str:
    """``c0 + u*(c1 + u*(...))`` as source text.

    >>> horner([1, 2, 3], "u")
    '1.0 + u*(2.0 + u*(3.0))'
    """
    text = repr(float(coeffs[-1]))
    for c in reversed(coeffs[:-1]):
        text = f"{float(c)!r} + {u}*({text})"
    return text


def cse_lines(exprs, indent="    ", prefix="_t", arrays=frozenset()) -> tuple[list[str], list[str]]:
    """Common subexpressions as assignment lines (``_t0 = ...``) and the reduced expressions.

    ``arrays``: the symbols that are arrays (:func:`code`); a subexpression of one is one too.

    >>> x = sp.Symbol("x")
    >>> cse_lines([(x + 1)**2, 2 * (x + 1)**2])
    (['    _t0 = (x + 1)**2'], ['_t0', '2*_t0'])
    """
    reps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix), order="canonical")
    arrays = set(arrays)
    lines = []
    for sym, val in reps:
        lines.append(f"{indent}{sym} = {code(val, arrays)}")
        if arrays & val.free_symbols:
            arrays.add(sym)
    return lines, [code(e, arrays) for e in reduced]


def source_hash(exprs) -> str:
    """sha256 of the ``srepr`` of the source expressions (recorded in generated headers).

    >>> len(source_hash([sp.Symbol("beta")]))
    64
    """
    return hashlib.sha256("\n".join(sp.srepr(e) for e in exprs).encode()).hexdigest()


def header(source: str, digest: str, hashed: str = "the source expressions' srepr") -> str:
    """The first lines of every generated file; ``digest`` is the sha256 of ``hashed``.

    >>> header("derivations/pinned.py: solve()", "0" * 64).splitlines()[0]
    '# generated — do not edit.'
    """
    return (
        "# generated — do not edit.\n"
        f"# Generated by `pfmdyn codegen` (derivations/codegen/) from {source}.\n"
        f"# SymPy {sp.__version__}; sha256 of {hashed}: {digest}\n"
    )
