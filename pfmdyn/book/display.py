"""Display helpers the book's chapters share: verdict tables, errata and typeset math, so that the
pages (``book/*.md``) contain prose and computation only.  The chapters reach them as
``from pfmdyn import book``.
"""
from __future__ import annotations

import html
import re

from .records import claims_of, counts

VERDICT_ORDER = ("holds", "holds_up_to_sign_convention", "erratum", "undecidable")
"""The verdict names in display order (the values of ``derivations.checks.core.Outcome``)."""

_BADGE = {"holds_up_to_sign_convention": "sign convention"}
"""Badge labels that differ from the verdict's name."""


def _badge(verdict: str) -> str:
    return f'<span class="pfm-verdict pfm-{verdict}">{_BADGE.get(verdict, verdict)}</span>'


class HTML:
    """Raw HTML output (rendered as is by myst-nb)."""

    def __init__(self, text: str):
        self.text = text

    def _repr_html_(self) -> str:
        return self.text


def counts_table() -> "HTML":
    """Verdict counts: the registry's claims, the text audit's references, symbols and statements."""
    kinds = (("claim", "registry claims"), ("cross-reference", "cross-references"), ("symbol", "symbols"),
             ("statement", "statements"))
    per = {kind: counts(kind) for kind, _ in kinds}
    out = ['<table class="pfm-claims pfm-counts"><thead><tr><th>verdict</th>']
    out += [f"<th>{label}</th>" for _, label in kinds] + ["<th>total</th></tr></thead><tbody>"]
    for verdict in VERDICT_ORDER + ("total",):
        cells = [sum(per[k].values()) if verdict == "total" else per[k][verdict] for k, _ in kinds]
        head = "total" if verdict == "total" else _badge(verdict)
        out.append(f"<tr><td>{head}</td>" + "".join(f"<td>{c}</td>" for c in cells) + f"<td>{sum(cells)}</td></tr>")
    out.append("</tbody></table>")
    return HTML("".join(out))


def anchor(claim_id: str) -> str:
    """HTML id of a claim's row on the verdicts page.

    >>> anchor("eq22.roots")
    'claim-eq22-roots'
    """
    return "claim-" + "".join(ch if ch.isalnum() else "-" for ch in claim_id)


def families_of(page: str) -> list:
    """The registry rows (``derivations/families.py``) a family chapter derives, in registry order.

    >>> [f.module for f in families_of("frictionless")]
    ['frictionless', 'frictionless_stiff']
    """
    from ..generated import families
    rows = [f for f in families.FAMILIES if f.chapter == page]
    if not rows:
        raise KeyError(f"no family of the registry has chapter {page!r}")
    return rows


def family_table(page: str) -> "HTML":
    """What the chapter's families are in numeric code, from the family registry: generated
    module, drives, parameters with their meaning, public function, :class:`pfmdyn.Cantilever`
    method and the ``pfmdyn roots`` / ``pfmdyn branches`` names.

    >>> "<code>pfmdyn.free_end_transfer</code>" in family_table("free_end").text
    True
    """
    from ..generated import families
    heads = ("family", "derived in", "per unit", "parameters", "Python", "roots / branches")
    out = ['<table class="pfm-claims pfm-families"><thead><tr>']
    out += [f"<th>{h}</th>" for h in heads] + ["</tr></thead><tbody>"]
    for f in families_of(page):
        params = "; ".join(f"{p}: {families.PARAMETER_HELP[p]}" for p in f.parameters)
        python = [f"pfmdyn.{f.function}"] + ([f"Cantilever.{f.method}"] if f.method else [])
        roots = " / ".join(n for n in (f.roots, f.branch and f"{f.branch} ({f.figure})") if n)
        cells = (f"<code>generated/{f.module}.py</code> ({html.escape(f.equations)})",
                 f"<code>{html.escape(f.source)}</code>", html.escape(", ".join(f.drives)),
                 re.sub(r"\*\*(\d+)", r"<sup>\1</sup>", html.escape(params)), "<br>".join(f"<code>{n}</code>" for n in python),
                 html.escape(roots or "—"))
        out.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    out.append("</tbody></table>")
    return HTML("".join(out))


def chapter_table(page: str) -> "HTML":
    """The verdict table that ends a chapter: its claims, each linked to its full evidence."""
    return claims_table(claims_of(page), columns=("id", "where", "verdict", "evidence"), link=True)


COLUMN_SHARES = {"id": 14, "where": 11, "verdict": 11, "printed": 30, "evidence": 40, "correct": 24, "chapter": 9}
"""Relative widths of the columns of a verdict table."""


def claims_table(rows: list[dict], *, columns=("id", "verdict", "evidence", "correct"),
                 link=False) -> HTML:
    """An HTML table of verdicts: escaped text with typeset formulas.

    ``link=True`` links ids to their row on the verdicts page; ``link="anchor"`` makes this
    table the target of those links (the verdicts page).  Column widths are fixed shares of the
    text column (:data:`COLUMN_SHARES`), so a long formula never widens the table.
    """
    heads = {"id": "claim", "where": "where", "printed": "as printed", "verdict": "verdict",
             "evidence": "evidence", "correct": "correct form", "chapter": "chapter"}
    total = sum(COLUMN_SHARES[c] for c in columns)
    out = ['<table class="pfm-claims pfm-fixed"><colgroup>']
    out += [f'<col style="width: {100 * COLUMN_SHARES[c] / total:.1f}%">' for c in columns]
    out.append("</colgroup><thead><tr>")
    out += [f"<th>{heads[c]}</th>" for c in columns]
    out.append("</tr></thead><tbody>")
    for v in rows:
        out.append(f'<tr class="pfm-row-{v["verdict"]}">')
        for c in columns:
            if c == "verdict":
                cell = _badge(v["verdict"])
            elif c == "id":
                cell = f"<code>{html.escape(v['id'])}</code>"
                if link:
                    cell = f'<a href="verdicts.html#{anchor(v["id"])}">{cell}</a>'
            elif c == "where":
                cell = v["html"]["where"]
                if link == "anchor":
                    cell = f'<span id="{anchor(v["id"])}"></span>{cell}'
            elif c == "chapter":
                page = v.get("chapter") or None
                cell = f'<a href="{page}.html">{page}</a>' if page and link else html.escape(page or "—")
            else:
                cell = v["html"][c]
            out.append(f"<td>{cell}</td>")
        out.append("</tr>")
    out.append("</tbody></table>")
    return HTML("".join(out))


def errata(rows: list[dict]) -> None:
    """Display each erratum (records of :func:`verdicts`): head, the claim as printed and the
    correct forms as typeset math (long ones broken over lines), the proof as one sentence and
    the decisive expression."""
    from IPython.display import Math, display

    from ..derivations.paper.convention import SIGN_CONVENTION_SENTENCE
    from ..typeset import html as typeset_html
    for v in rows:
        f = v["erratum"]
        page = v.get("chapter")
        chapter = f' — <a href="{page}.html">{page}</a>' if page else ""
        display(HTML(f'<p class="pfm-erratum-head"><code>{html.escape(v["id"])}</code> '
                     f'({v["html"]["where"]}) {_badge(v["verdict"])}{chapter}</p>'))
        display(HTML(f'<div class="pfm-result"><b>As printed:</b> {f["printed"]}</div>'))
        if f["correct"]:
            display(HTML("<p><b>Correct:</b></p>"))
            for tex in f["correct"]:
                display(Math(tex))
        if f["correction"] or not f["correct"]:
            display(HTML(f'<div class="pfm-result"><b>Correct:</b> {f["correction"] or "(see proof)"}</div>'))
        display(HTML(f'<div class="pfm-result"><b>Proof:</b> {f["proof"]}.{" Decisive:" if f["decisive"] else ""}</div>'))
        if f["decisive"]:
            display(Math(f["decisive"]))
        if f["sign"]:
            display(HTML(f"<p><i>Sign convention:</i> {typeset_html(SIGN_CONVENTION_SENTENCE)}.</p>"))


def math(lhs, expr):
    """Display ``lhs = expr`` as typeset math (``lhs`` LaTeX or a SymPy object, ``expr`` a SymPy
    object or a LaTeX string); a long expression is broken over lines that fit the text column."""
    from IPython.display import Math
    if isinstance(expr, str):
        return Math(f"{lhs} = {expr}" if lhs else expr)
    return aligned([(lhs, expr)])


def aligned(rows, *, relation: str = "="):
    """Display several ``(lhs, rhs)`` pairs as one aligned block of typeset math, each broken
    over lines where it would be wider than the text column (:func:`pfmdyn.typeset.latex_rows`)."""
    from IPython.display import Math

    from ..typeset import latex, latex_rows
    lines = []
    for lhs, rhs in rows:
        if isinstance(rhs, str):
            lines.append(f"{latex(lhs)} &{relation} {rhs}")
        else:
            lines += latex_rows(lhs, rhs, relation=relation)
    return Math(r"\begin{aligned}" + r" \\[3pt] ".join(lines) + r"\end{aligned}")


def tip_values():
    """Symbols standing for the tip values of ``u0`` and its first three derivatives, typeset
    as such (:class:`pfmdyn.typeset.TipValue`)."""
    from ..typeset import TipValue
    return [TipValue(f"U_{i}") for i in range(4)]


def ratios(rows):
    r"""Display printed/derived for ``(label, printed, derived)`` rows: the exact ratio of the
    canonical trigonometric normal forms, or "not constant" (then the 50-digit spread).
    """
    from ..derivations.checks.core import compare
    out = []
    for label, printed, derived in rows:
        cmp = compare(printed, derived)
        if cmp.exact_ratio is not None and cmp.constant:
            value = cmp.exact_ratio
        else:
            value = (r"\text{not a constant: }|\text{ratio}| \in [%.3g, %.3g]"
                     % tuple(sorted(float(abs(v)) for v in cmp.numeric_ratios)[::len(cmp.numeric_ratios) - 1]))
        out.append((rf"\dfrac{{{label}\big|_\text{{printed}}}}{{{label}\big|_\text{{derived}}}}", value))
    return aligned(out)


def conditions(exprs):
    """Display boundary conditions, given as expressions that vanish, as ``expr = 0``."""
    return aligned([(e, 0) for e in exprs])
