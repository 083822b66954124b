"""Typesetting for the errata list of ``pfmdyn verify`` and the book: the one place that writes LaTeX.

SymPy objects become LaTeX with the project's symbol names (:func:`latex`); long expressions
are broken over lines that fit the text column (:func:`latex_rows`, :func:`display_latex`).
A sentence of evidence (:mod:`derivations.evidence`: words, SymPy formulas, LaTeX)
becomes Markdown (:func:`markdown`) or HTML (:func:`html`): short formulas inline, long ones
as broken display blocks, so that no line is wider than the column.  :func:`erratum` gathers
what an erratum shows: printed and correct forms, the correction, the proof and the decisive
ratio.
"""
from __future__ import annotations

import html as _html

import sympy as sp

from .derivations.evidence import RELATIONS, Math, Tex, join

LINE_WIDTH = 64
"""Characters of LaTeX source (commands counted as one) per displayed line: fits the text column."""

CELL_WIDTH = 36
"""The same for a formula inside a table cell (the evidence column of a verdict table)."""

NAMES = {"DeltaV": r"\Delta V", "epsilon0": r"\varepsilon_0", "k2t": r"\tilde{k}_2", "f_lat": r"\tilde{f}_{lat}",
         "d_efft": r"\tilde{d}_{eff}", "kappa": r"\kappa"}
"""Symbol names whose LaTeX SymPy would not guess."""

_ZERO_WIDTH = {"left", "right", "Big", "big", "quad", "", ",", ";", ":", "!", "displaystyle"}
_WIDE = {"sinh", "cosh", "sin", "cos", "tan", "sqrt", "frac", "dfrac", "log", "exp"}


def latex(expr) -> str:
    r"""SymPy's LaTeX with the project's symbol names, ``\sin{\left(\beta \right)}`` folded to
    ``\sin{\beta}``; a string is taken as LaTeX already.

    >>> latex(sp.sin(sp.Symbol("beta"))), latex(sp.Symbol("DeltaV")), latex(r"\theta")
    ('\\sin {\\beta}', '\\Delta V', '\\theta')
    """
    if isinstance(expr, str):
        return expr
    names = {s: NAMES[s.name] for s in getattr(expr, "free_symbols", ()) if getattr(s, "name", "") in NAMES}
    return sp.latex(expr, symbol_names=names, fold_func_brackets=True)


class TipValue(sp.Symbol):
    """A symbol ``U_i`` standing for the i-th derivative of ``u0`` at the tip, typeset as such.

    >>> latex(TipValue("U_2") + 1)
    "u_0''(L) + 1"
    """

    def _latex(self, printer) -> str:
        return "u_0" + "'" * int(self.name.rpartition("_")[2]) + "(L)"


def visible(tex: str) -> int:
    r"""Rough printed width of LaTeX source in characters: a function name (``\cos``) counts
    three, another command (``\beta``) one, braces, ``\left``/``\right``, spaces and spacing nothing.

    >>> visible(r"\frac{\beta}{\cos{x}}"), visible(r"\left( a + b \right)")
    (8, 5)
    """
    width, i = 0, 0
    while i < len(tex):
        if tex[i] == "\\":
            j = i + 1
            while j < len(tex) and tex[j].isalpha():
                j += 1
            name = tex[i + 1:j] if j > i + 1 else tex[i + 1:i + 2]
            i = max(j, i + 2)
            width += 0 if name in _ZERO_WIDTH else 3 if name in _WIDE else 1
        else:
            width += tex[i] not in "{} "
            i += 1
    return width


def _lines(expr, width: int) -> list[str]:
    """LaTeX of ``expr`` cut into lines at top-level + signs (and inside a long bracketed
    factor), each at most about ``width`` characters wide."""
    tex = latex(expr)
    if visible(tex) <= width:
        return [tex]
    if isinstance(expr, sp.Mul) and any(isinstance(f, sp.Add) for f in expr.args):
        big = max((f for f in expr.args if isinstance(f, sp.Add)), key=lambda f: len(latex(f)))
        inner = _lines(big, width - 4)
        pre = latex(expr / big)
        if len(inner) == 1:
            return [rf"{pre} \Big( {inner[0]} \Big)"]
        return [rf"{pre} \Big( {inner[0]}"] + inner[1:-1] + [rf"{inner[-1]} \Big)"]
    if isinstance(expr, sp.Mul):              # a long product: its factors over several lines
        return _joined([latex(f) for f in expr.as_ordered_factors()], width, " ")
    if not isinstance(expr, sp.Add):
        return [tex]
    lines, current = [], ""
    for i, term in enumerate(expr.args):
        for j, piece in enumerate(_lines(term, width)):
            if i and not j and not piece.startswith("-"):
                piece = "+ " + piece            # the sign joining this term to the previous one
            if current and visible(current + piece) > width:
                lines.append(current)
                current = piece
            else:
                current = f"{current} {piece}".strip()
    lines.append(current)
    return lines


def _joined(pieces: list[str], width: int, sep: str) -> list[str]:
    """Pieces of LaTeX packed greedily into lines of at most ``width``."""
    lines, current = [], ""
    for piece in pieces:
        if current and visible(current + sep + piece) > width:
            lines.append(current)
            current = piece
        else:
            current = f"{current}{sep}{piece}" if current else piece
    return lines + [current]


def latex_rows(lhs, expr, *, relation: str = "=", width: int = LINE_WIDTH) -> list[str]:
    """Rows of an ``aligned`` block showing ``lhs relation expr``, none wider than ``width``.

    ``lhs`` is LaTeX or a SymPy object.  A long fraction becomes ``lhs = N/D`` followed by the
    rows of N and of D.
    """
    lhs = latex(lhs)
    expr = sp.sympify(expr)
    tex = latex(expr)
    if visible(f"{lhs} {relation} {tex}") <= width:
        return [f"{lhs} &{relation} {tex}"]
    num, den = sp.fraction(sp.together(expr)) if not isinstance(expr, sp.Add) else (expr, sp.S.One)
    rows = []
    if den != 1 and (visible(latex(num)) > width // 2 or visible(latex(den)) > width // 2):
        rows.append(rf"{lhs} &{relation} \frac{{\mathcal{{N}}}}{{\mathcal{{D}}}}")
        parts = ((r"\mathcal{N}", num), (r"\mathcal{D}", den))
    else:
        parts = ((lhs, expr),)
    for name, part in parts:
        lines = _lines(part, width - 6)
        rel = relation if name == lhs else "="
        rows.append(f"{name} &{rel} {lines[0]}")
        rows += [f"&\\quad {line}" for line in lines[1:]]
    return rows


def aligned(rows: list[str]) -> str:
    """Rows of ``&``-aligned LaTeX as one block (a single row without the ``&``)."""
    if len(rows) == 1:
        return rows[0].replace("&", "", 1)
    return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"


def display_latex(lhs, expr, width: int = LINE_WIDTH, relation: str = "=") -> str:
    r"""``lhs = expr`` as display LaTeX, broken over lines so that none is wider than ``width``.

    >>> x = sp.Symbol("x")
    >>> display_latex("y", x + 1)
    'y = x + 1'
    >>> print(display_latex("y", sum(x**i for i in range(40)), width=40).splitlines()[0])
    \begin{aligned}
    """
    return aligned(latex_rows(lhs, expr, relation=relation, width=width))


# --- sentences of evidence ------------------------------------------------------------------------

def _lhs(lhs) -> str:
    return lhs.tex if isinstance(lhs, Tex) else latex(lhs)


def formula(part, width: int = LINE_WIDTH) -> tuple[str, bool]:
    """LaTeX of a formula part and whether it is a display block (broken over lines).

    A formula is inline when it takes at most three quarters of ``width``; otherwise it is
    broken over lines of at most ``width``.
    """
    if isinstance(part, Tex):
        return part.tex, visible(part.tex) > width
    tex = latex(part.expr) if part.lhs is None else f"{_lhs(part.lhs)} {RELATIONS[part.relation]} {latex(part.expr)}"
    if visible(tex) <= width * 3 // 4:
        return tex, False
    return display(part, width), True


def display(part: Math, width: int = LINE_WIDTH) -> str:
    """A formula as display LaTeX, broken over lines of at most ``width``."""
    if part.lhs is None:
        return aligned(["&" + line for line in _lines(part.expr, width)])
    return aligned(latex_rows(_lhs(part.lhs), part.expr, relation=RELATIONS[part.relation], width=width))


def markdown(sentence, width: int = LINE_WIDTH) -> str:
    """A sentence as Markdown with ``$...$`` math (long formulas as ``$$`` blocks on their own lines)."""
    out = []
    for part in sentence:
        if isinstance(part, str):
            out.append(part)
            continue
        tex, block = formula(part, width)
        out.append(f"\n\n$$\n{tex}\n$$\n\n" if block else f"${tex}$")
    return "".join(out).rstrip()


def html(sentence, width: int = CELL_WIDTH) -> str:
    """A sentence as HTML: words escaped, formulas as MathJax spans (long ones as display blocks)."""
    out = []
    for part in sentence:
        if isinstance(part, str):
            out.append(_html.escape(part))
            continue
        tex, block = formula(part, width)
        if block:
            out.append(f'<span class="math notranslate nohighlight pfm-display">\\[{_html.escape(tex)}\\]</span>')
        else:
            out.append(f'<span class="math notranslate nohighlight">\\({_html.escape(tex)}\\)</span>')
    return "".join(out)


# --- an erratum ---------------------------------------------------------------------------------

def decisive(comparison) -> str | None:
    """``printed/derived = r`` as LaTeX when the exact ratio is a short constant, else None."""
    if comparison is None or comparison.exact_ratio is None or not comparison.constant:
        return None
    tex = rf"\frac{{\text{{printed}}}}{{\text{{derived}}}} = {latex(comparison.exact_ratio)}"
    return tex if visible(tex) <= LINE_WIDTH else None


def correction(v):
    """What is right, as a sentence: the check's correction, else its correct forms."""
    e = v.proof
    return e.correction or join([(m,) for m in e.correct], ", ")


def erratum(v, width: int = LINE_WIDTH) -> dict:
    """What an erratum shows, from its :class:`~derivations.checks.core.Verdict`.

    ``printed``: the claim as printed (a sentence; its long formulas become display blocks);
    ``correct``: display LaTeX of the correct forms, named like the printed ones when there are
    as many; ``correction``, ``proof``: sentences; ``decisive``: the exact ratio printed/derived
    as LaTeX (or None); ``sign``: whether the sign convention matters.  Display lines are at most
    ``width`` characters wide.
    """
    e = v.proof
    correct = list(e.correct)
    printed_lhs = [p.lhs for p in v.printed if isinstance(p, Math)]
    if len(correct) == len(printed_lhs):       # name the correct forms like the printed ones
        correct = [Math(c.expr, lhs if lhs is not None else c.lhs, c.relation) for c, lhs in zip(correct, printed_lhs)]
    return {"printed": v.printed, "correct": [display(m, width) for m in correct], "correction": e.correction,
            "proof": e.proof, "decisive": decisive(e.ratio),
            "sign": e.sign_convention or str(v.verdict) == "holds_up_to_sign_convention"}
