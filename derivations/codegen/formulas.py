"""Renderer of ``generated/formulas.py``: the closed-form relations of :mod:`derivations.formulas`."""
from __future__ import annotations

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from ..formulas import formulas
from .printing import header, source_hash

__all__ = ["render"]


class _Printer(NumPyPrinter):
    """NumPy printer with rationals as float literals."""

    def _print_Rational(self, expr):
        return repr(float(expr))


def render() -> str:
    """Source text of ``generated/formulas.py``."""
    items = formulas()
    printer = _Printer({"fully_qualified_modules": False})
    bodies = [printer.doprint(f.expr) for f in items]
    # The NumPy names the bodies use, as the printer recorded them.
    names = ", ".join(sorted(set().union(*printer.module_imports.values())))
    out = [header("derivations/formulas.py: formulas()", source_hash([f.expr for f in items])),
           '''"""Closed-form relations (SI), vectorised over NumPy arrays; see derivations/formulas.py."""
from numpy import ''' + names + '''

__all__ = ''' + repr(sorted(f.name for f in items)) + "\n"]
    for f, body in zip(items, bodies):
        args = ", ".join(map(str, f.arguments))
        out.append(f'''

def {f.name}({args}):
    """{f.summary[0].upper() + f.summary[1:]}.

    ``{sp.sstr(f.expr)}``, from {f.source}.
    """
    return {body}
''')
    return "".join(out)
