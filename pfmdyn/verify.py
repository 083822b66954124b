"""Verdicts for every claim of the paper and for every checkable sentence of its text.

The library side of ``pfmdyn verify`` (argparse and printing live in
:mod:`pfmdyn.commands.verify`).  :func:`compute` runs the checks registered in
``derivations.checks`` -- the ids of the shared claims registry and the ids of the text audit
(``xref.*``, ``symbol.*``, ``structure.*``, ``text.*``) -- and returns one :class:`Verdict`
each.  :func:`gate` compares them with ``derivations/recorded_verdicts.yaml``;
:func:`render_errata` writes the errata as Markdown with LaTeX.  Nothing here writes a file
unless asked to (:func:`record`, :func:`write_errata`).

The sign convention of the electrostatic drives is :data:`SIGN_CONVENTION`
(:mod:`derivations.paper.convention`).
"""
from __future__ import annotations

import os
import sys
from collections import Counter
from pathlib import Path

import yaml

from .derivations.checks.core import Outcome
from .derivations.paper.convention import SIGN_CONVENTION
from .errors import UserError
from .io import results

RECORDED = "recorded_verdicts.yaml"


KIND_ORDER = ("claim", "cross-reference", "symbol", "statement")


def shared_claims_path(arg: str | None = None) -> Path | None:
    """The shared claims file: ``arg``, ``$PFMDYN_CLAIMS``, else ``shared/claims.yaml`` in a parent."""
    if arg:
        return Path(arg)
    if os.environ.get("PFMDYN_CLAIMS"):
        return Path(os.environ["PFMDYN_CLAIMS"])
    from . import derivations
    for parent in Path(derivations.__file__).resolve().parents:
        if (parent / "shared" / "claims.yaml").exists():
            return parent / "shared" / "claims.yaml"
    return None


def shared_claim_ids(path: Path | None) -> list[str]:
    """Ids listed in the shared claims file (empty when it is absent)."""
    if path is None:
        return []
    if not path.exists():
        raise UserError(f"claims file not found: {path}")
    entries = yaml.safe_load(path.read_text()) or []
    return [e["id"] for e in entries]


def recorded_path() -> Path:
    from . import derivations
    return Path(derivations.__file__).resolve().parent / RECORDED


def load_recorded() -> dict[str, str]:
    path = recorded_path()
    return yaml.safe_load(path.read_text()) if path.exists() else {}


def compute(ids: list[str] | None = None, progress: bool = False):
    """Run the checks; returns the list of :class:`Verdict` in registry order.

    Heavy symbolic steps are shared within one call (solutions, series, lambdified
    expressions, verdicts that text statements reuse) and recomputed on the next call.
    """
    from tqdm import tqdm

    from .derivations.checks import core
    checks = [c for c in core.REGISTRY.values() if ids is None or c.id in ids]
    unknown = set(ids or ()) - set(core.REGISTRY)
    if unknown:
        raise UserError(f"unknown claim id(s): {', '.join(sorted(unknown))}")
    core.clear_results()
    return [core.result(check.id) for check in
            tqdm(checks, desc="checking claims", unit="claim", disable=not progress, file=sys.stderr)]


def gate(verdicts, recorded: dict[str, str], shared_ids: list[str] | None = None) -> list[str]:
    """Why the computed verdicts do not match the record (empty list: they do)."""
    computed = {v.id: str(v.verdict) for v in verdicts}
    problems = [f"{i}: listed in the claims file but has no check" for i in shared_ids or () if i not in computed]
    for v in verdicts:
        if v.id not in recorded:
            problems.append(f"{v.id}: no recorded verdict (computed {v.verdict})")
        elif recorded[v.id] != str(v.verdict):
            problems.append(f"{v.id}: computed {v.verdict}, recorded {recorded[v.id]}")
    return problems


def record(verdicts, path: Path | None = None, merge: bool = False) -> Path:
    """Write the computed verdicts as the recorded ones (after review); ``merge`` keeps the
    recorded verdicts of ids not computed in this run."""
    path = path or recorded_path()
    data = load_recorded() if merge else {}
    data.update({v.id: str(v.verdict) for v in verdicts})
    path.write_text(yaml.safe_dump(data, sort_keys=True))
    return path


def counts(verdicts) -> dict:
    """Verdict counts overall and per kind (claim, cross-reference, symbol, statement)."""
    from .derivations.checks.core import VERDICTS
    by_kind = {kind: Counter(str(v.verdict) for v in verdicts if v.kind == kind) for kind in KIND_ORDER}
    total = Counter(str(v.verdict) for v in verdicts)
    return {"total": {str(k): total[str(k)] for k in VERDICTS},
            "by_kind": {kind: {str(k): c[str(k)] for k in VERDICTS} for kind, c in by_kind.items()},
            "n": {kind: sum(c.values()) for kind, c in by_kind.items()}}


def summary(verdicts) -> str:
    """One line: how many ids, how many of each verdict, and what the text audit extracted."""
    c = counts(verdicts)
    total = ", ".join(f"{n} {name}" for name, n in c["total"].items())
    n = c["n"]
    audit = (f"registry {n['claim']}; text audit {n['cross-reference']} references "
             f"({_short(c['by_kind']['cross-reference'])}), {n['symbol']} symbols "
             f"({_short(c['by_kind']['symbol'])}), {n['statement']} statements ({_short(c['by_kind']['statement'])})")
    if n["cross-reference"] + n["symbol"] + n["statement"] == 0:
        audit = f"registry {n['claim']}; text audit skipped (paper transcription not found; set $PFMDYN_PAPER)"
    return f"{len(verdicts)} claims: {total} [{audit}]"


def _short(counter: dict) -> str:
    abbrev = {Outcome.HOLDS: "hold", Outcome.SIGN: "sign", Outcome.ERRATUM: "errata", Outcome.UNDECIDABLE: "undecidable"}
    return ", ".join(f"{n} {abbrev[k]}" for k, n in counter.items() if n) or "none"


def to_json(verdicts) -> dict:
    """The JSON payload of ``pfmdyn verify --json``."""
    return {"summary": summary(verdicts), "counts": counts(verdicts), "sign_convention": SIGN_CONVENTION,
            "claims": [v.as_dict() for v in verdicts]}


def write_json(verdicts, path: Path) -> None:
    """Write :func:`to_json` to ``path`` (:func:`pfmdyn.io.results.write_json`)."""
    results.write_json(path, to_json(verdicts))


# --- errata as mathematics --------------------------------------------------------------------------

def render_errata(verdicts) -> str:
    """The errata as Markdown: printed form, correct form, proof (sentence + decisive expression).

    Registry errata whose check provides LaTeX forms show them as display math (long
    expressions broken over lines); the text audit's errata follow, one line each.
    """
    lines = ["<!-- generated — do not edit: written by `pfmdyn verify --errata` from derivations/checks -->",
             "# Errata of Jesse, Baddorf & Kalinin (2006), as computed by pfmdyn", "",
             f"Sign convention: {SIGN_CONVENTION}.", ""]
    registry = [v for v in verdicts if v.kind == "claim" and v.verdict in (Outcome.ERRATUM, Outcome.SIGN)]
    audit = [v for v in verdicts if v.kind != "claim" and v.verdict == Outcome.ERRATUM]
    for v in registry:
        lines += entry(v)
    if audit:
        lines += ["## Errata of the text (cross-references, symbols, statements)", ""]
        for v in audit:
            fix = f" Correct: {prose(v.correct)}." if v.correct else ""
            lines.append(f"- `{v.id}` ({v.where}): {prose(v.evidence)}.{fix}")
        lines.append("")
    return "\n".join(lines)


def write_errata(verdicts, path: Path) -> None:
    Path(path).write_text(render_errata(verdicts))


def table(verdicts, width: int = 110) -> str:
    """The plain-text verdict table printed by ``pfmdyn verify``."""
    w_id = max(len(v.id) for v in verdicts)
    w_where = min(28, max(len(v.where) for v in verdicts))
    rows = [f"{'id':<{w_id}}  {'where':<{w_where}}  {'verdict':<27}  evidence"]
    for v in verdicts:
        evidence = " ".join(v.evidence.split())
        evidence = evidence if len(evidence) <= width else evidence[:width - 3] + "..."
        rows.append(f"{v.id:<{w_id}}  {v.where[:w_where]:<{w_where}}  {str(v.verdict):<27}  {evidence}")
    return "\n".join(rows)


# --- LaTeX forms ------------------------------------------------------------------------------------

LINE_WIDTH = 64
"""Characters of LaTeX source (commands counted as one) per displayed line: fits the text column."""

_NAMES = {"DeltaV": r"\Delta V", "epsilon0": r"\varepsilon_0", "k2t": r"\tilde{k}_2", "f_lat": r"\tilde{f}_{lat}",
          "d_efft": r"\tilde{d}_{eff}", "kappa": r"\kappa"}


def _visible(tex: str) -> int:
    """Rough printed width of LaTeX source in characters: a function name (\\cos) counts three,
    another command (\\beta) one, braces and \\left/\\right nothing."""
    import re
    tex = re.sub(r"\\(?:left|right|Big|quad)", "", tex)
    tex = re.sub(r"\\(?:sinh|cosh|sin|cos|tan|sqrt|frac)", "xxx", tex)
    return len(re.sub(r"[{}]", "", re.sub(r"\\[a-zA-Z]+", "x", tex)))


def _lines(expr, width: int, printer=None) -> list[str]:
    """LaTeX of ``expr`` cut into lines at top-level + signs (and inside a long bracketed
    factor), each at most about ``width`` characters wide."""
    import sympy as sp
    printer = printer or latex
    tex = printer(expr)
    if _visible(tex) <= width:
        return [tex]
    if isinstance(expr, sp.Mul) and any(isinstance(f, sp.Add) for f in expr.args):
        big = max((f for f in expr.args if isinstance(f, sp.Add)), key=lambda f: len(printer(f)))
        inner = _lines(big, width - 4, printer)
        pre = printer(expr / big)
        if len(inner) == 1:
            return [rf"{pre} \Big( {inner[0]} \Big)"]
        return [rf"{pre} \Big( {inner[0]}"] + inner[1:-1] + [rf"{inner[-1]} \Big)"]
    if not isinstance(expr, sp.Add):
        return [tex]
    lines, current = [], ""
    for i, term in enumerate(expr.args):
        for j, piece in enumerate(_lines(term, width, printer)):
            if i and not j and not piece.startswith("-"):
                piece = "+ " + piece            # the sign joining this term to the previous one
            if current and _visible(current + piece) > width:
                lines.append(current)
                current = piece
            else:
                current = f"{current} {piece}".strip()
    lines.append(current)
    return lines


def latex(expr) -> str:
    """SymPy's LaTeX with the project's symbol names (Delta V, epsilon_0, ...)."""
    import sympy as sp
    names = {s: _NAMES[s.name] for s in getattr(expr, "free_symbols", ()) if s.name in _NAMES}
    return sp.latex(expr, symbol_names=names, fold_func_brackets=True)


def latex_rows(lhs: str, expr, *, relation: str = "=", width: int = LINE_WIDTH, printer=None) -> list[str]:
    """Rows of an ``aligned`` block showing ``lhs = expr``, none wider than ``width``.

    A long fraction becomes ``lhs = N/D`` followed by the rows of N and of D.
    """
    import sympy as sp
    printer = printer or latex
    expr = sp.sympify(expr)
    tex = printer(expr)
    if _visible(f"{lhs} {relation} {tex}") <= width:
        return [f"{lhs} &{relation} {tex}"]
    num, den = sp.fraction(sp.together(expr)) if not isinstance(expr, sp.Add) else (expr, sp.S.One)
    rows = []
    if den != 1 and (_visible(printer(num)) > width // 2 or _visible(printer(den)) > width // 2):
        rows.append(rf"{lhs} &{relation} \frac{{\mathcal{{N}}}}{{\mathcal{{D}}}}")
        parts = ((r"\mathcal{N}", num), (r"\mathcal{D}", den))
    else:
        parts = ((lhs, expr),)
    for name, part in parts:
        lines = _lines(part, width - 6, printer)
        rel = relation if name == lhs else "="
        rows.append(f"{name} &{rel} {lines[0]}")
        rows += [f"&\\quad {line}" for line in lines[1:]]
    return rows


def display_latex(lhs: str, expr, width: int = LINE_WIDTH, printer=None) -> str:
    r"""``lhs = expr`` as display LaTeX, broken over lines so that none is wider than ``width``.

    >>> import sympy as sp
    >>> x = sp.Symbol("x")
    >>> display_latex("y", x + 1)
    'y = x + 1'
    >>> print(display_latex("y", sum(x**i for i in range(40)), width=40).splitlines()[0])
    \begin{aligned}
    """
    rows = latex_rows(lhs, expr, width=width, printer=printer)
    if len(rows) == 1:
        return rows[0].replace(" &=", " =", 1)
    return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"


def _parse_correct(text: str):
    """The correct form as ``[(lhs, expr)]`` when it is written as SymPy expressions, else None."""
    import re

    import sympy as sp
    from sympy.parsing.sympy_parser import parse_expr
    if not text or re.search(r"[a-z]{3,} [a-z]{3,} [a-z]{3,}", text.replace("sqrt", "")):
        return None
    parts = re.split(r",\s+(?=[A-Za-z_][\w]*\s*=)", text)
    out = []
    for part in parts:
        lhs, eq, rhs = part.partition(" = ")
        if not eq:
            lhs, rhs = "", part
        lhs = lhs.strip()
        if lhs and not re.fullmatch(r"[A-Za-z_][\w]*", lhs):
            return None
        try:
            expr = parse_expr(rhs.strip(), local_dict={"beta": sp.Symbol("beta", positive=True)})
        except Exception:
            return None
        if not isinstance(expr, sp.Expr):
            return None
        out.append((latex(sp.Symbol(lhs)) if lhs else "", expr))
    return out


def _decisive(evidence: str):
    """The exact ratio printed/derived quoted in the evidence, as LaTeX (None if not constant)."""
    import re

    from sympy.parsing.sympy_parser import parse_expr
    m = re.search(r"printed/derived: exact ([^;]+?)(?:;|$)", evidence)
    if not m or m.group(1).strip() == "n/a":
        return None
    try:
        return latex(parse_expr(m.group(1).strip()))
    except Exception:
        return None


def forms(v) -> dict:
    """LaTeX of the printed and correct forms and of the decisive expression of one verdict.

    Keys present only when known: ``printed`` and ``correct`` (lists of display-LaTeX strings),
    ``decisive`` (LaTeX), ``proof`` (one sentence).
    """
    from .derivations.paper import printed as P
    out: dict = {}
    if v.id in P.PRINTED_FORMS:
        out["printed"] = [display_latex(lhs, e) for lhs, e in P.PRINTED_FORMS[v.id]]
    parsed = _parse_correct(v.correct)
    if parsed:
        printed_lhs = [lhs for lhs, _ in P.PRINTED_FORMS.get(v.id, [])]
        if len(parsed) == len(printed_lhs):      # name the correct forms like the printed ones
            parsed = [(lhs or plhs, e) for (lhs, e), plhs in zip(parsed, printed_lhs)]
        out["correct"] = [display_latex(lhs, e) for lhs, e in parsed]
    decisive = _decisive(v.evidence)
    if decisive and _visible(decisive) <= LINE_WIDTH:
        out["decisive"] = rf"\frac{{\text{{printed}}}}{{\text{{derived}}}} = {decisive}"
    import re
    evidence = re.sub(r"printed/derived: exact n/a; (\d+)-digit \|ratio\| varies from (\S+) to (\S+)",
                      r"printed and derived forms differ by a non-constant factor (|printed/derived| from \2 to \3 "
                      r"at random \1-digit points)", v.evidence)
    out["proof"] = prose(evidence.split("; ")[0].rstrip("."))
    return out


def prose(text: str) -> str:
    """Evidence text for reading: SymPy's ``**`` and ``*`` as ``^`` and a middle dot.

    >>> prose("3*L**2*beta")
    '3·L^2·beta'
    """
    return text.replace("**", "^").replace("*", "·")


def entry(v) -> list[str]:
    """Markdown lines of one erratum: printed, correct, proof (sentence and decisive expression)."""
    f = forms(v)
    kind = "Erratum" if v.verdict == Outcome.ERRATUM else "Sign convention"
    lines = [f"## `{v.id}` ({v.where}) — {kind}", ""]
    if "printed" in f:
        lines += ["**Printed:**", ""] + [f"$$\n{t}\n$$" for t in f["printed"]] + [""]
    else:
        lines += [f"**Printed:** {prose(v.printed)}", ""]
    if "correct" in f:
        lines += ["**Correct:**", ""] + [f"$$\n{t}\n$$" for t in f["correct"]] + [""]
    else:
        lines += [f"**Correct:** {prose(v.correct) or '(see proof)'}", ""]
    lines += [f"**Proof:** {f['proof']}." + (" Decisive:" if "decisive" in f else ""), ""]
    if "decisive" in f:
        lines += [f"$$\n{f['decisive']}\n$$", ""]
    if v.verdict == Outcome.SIGN or "sign" in v.evidence:
        lines += [f"*Sign convention:* {SIGN_CONVENTION}.", ""]
    return lines
