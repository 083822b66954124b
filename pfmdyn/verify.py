"""Verdicts for every claim of the paper and for every checkable sentence of its text.

The library side of ``pfmdyn verify`` (argparse and printing live in
:mod:`pfmdyn.commands.verify`).  :func:`compute` runs the checks registered in
``derivations.checks`` (the ids of the shared claims registry) and in ``pfmdyn.audit`` (the
ids of the text audit: ``xref.*``, ``symbol.*``, ``structure.*``, ``text.*``) and returns one
:class:`Verdict` each, its evidence as data.  :func:`gate` compares them with
``derivations/recorded_verdicts.yaml``; :func:`render_errata` writes the errata as Markdown with
LaTeX (typeset by :mod:`pfmdyn.typeset`, which the book uses too).  Nothing here writes a file
unless asked to (:func:`record`, :func:`write_errata`).

The sign convention of the electrostatic drives is :data:`SIGN_CONVENTION`
(:mod:`derivations.paper.convention`).
"""
from __future__ import annotations

import multiprocessing
import os
import sys
from collections import Counter
from pathlib import Path

import yaml

from . import typeset
from .derivations.checks.core import VERDICTS, Outcome
from .derivations.evidence import text
from .derivations.paper.convention import SIGN_CONVENTION, SIGN_CONVENTION_SENTENCE
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


def compute(ids: list[str] | None = None, progress: bool = False, workers: int | None = None):
    """Run the checks; returns the list of :class:`Verdict` in registry order.

    Heavy symbolic steps are shared within one call (solutions, series, lambdified
    expressions, verdicts that text statements reuse) and recomputed on the next call.  The
    checks run in ``workers`` processes (default: one per core), one module of checks at a
    time, so the solutions a module's checks share are computed in one process; the largest
    modules start first.
    """
    from tqdm import tqdm

    from . import audit
    from .derivations.checks import core
    audit.register()
    checks = [c for c in core.REGISTRY.values() if ids is None or c.id in ids]
    unknown = set(ids or ()) - set(core.REGISTRY)
    if unknown:
        raise UserError(f"unknown claim id(s): {', '.join(sorted(unknown))}")
    core.clear_results()
    groups: dict[str, list[str]] = {}
    for c in checks:
        module = c.run.__module__
        groups.setdefault(c.id if c.id in _COST else next((m for m in _TOGETHER if module.startswith(m)), module),
                          []).append(c.id)
    tasks = sorted(groups.values(), key=lambda g: -_COST.get(g[0], _COST.get(core.REGISTRY[g[0]].run.__module__, 0)))
    workers = min(workers or os.cpu_count() or 1, len(tasks))
    bar = tqdm(total=len(checks), desc="checking claims", unit="claim", disable=not progress, file=sys.stderr)
    found: dict = {}
    with bar:
        if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
            with multiprocessing.get_context("fork").Pool(workers) as pool:
                for group in pool.imap_unordered(_run_group, tasks):
                    found.update(group)
                    bar.update(len(group))
        else:
            for task in tasks:
                found.update(_run_group(task))
                bar.update(len(task))
    return [found[c.id] for c in checks]


_COST = {"pfmdyn.derivations.checks.detection": 3.3, "pfmdyn.derivations.checks.flexural": 2.0,
         "pfmdyn.audit.restated": 1.9, "pfmdyn.derivations.checks.electrostatics": 1.8,
         "pfmdyn.audit.statements": 1.5, "pfmdyn.derivations.checks.limits": 1.4,
         "pfmdyn.derivations.checks.numbers": 1.0, "pfmdyn.derivations.checks.calibration": 1.0}
"""Rough CPU seconds of the slow check modules and claims, each in a fresh process (measured; a
claim named here runs on its own): they are started first, so the processes finish together.  Only
the order depends on it, never a verdict."""


_TOGETHER = ("pfmdyn.audit.xref",)
"""Module prefixes whose checks run in one process: the cross-reference checkers (one module per
kind of target) share the text's cached readings, which each process would compute again."""


def _run_group(ids: list[str]) -> dict:
    from .derivations.checks import core
    return {i: core.result(i) for i in ids}


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
    """The JSON payload of ``pfmdyn verify``."""
    return {"summary": summary(verdicts), "counts": counts(verdicts), "sign_convention": SIGN_CONVENTION,
            "claims": [v.as_dict() for v in verdicts]}


def write_json(verdicts, path: Path) -> None:
    """Write :func:`to_json` to ``path`` (:func:`pfmdyn.io.results.write_json`)."""
    results.write_json(path, to_json(verdicts))


# --- errata as mathematics --------------------------------------------------------------------------

def render_errata(verdicts) -> str:
    """The errata as Markdown with LaTeX (:mod:`pfmdyn.typeset`): for each registry erratum the claim
    as printed, the correct form, the proof (sentence and decisive expression); then the text
    audit's errata, one line each.  Long formulas are display blocks broken over lines.
    """
    lines = ["<!-- generated — do not edit: written by `pfmdyn verify` (its errata list) from derivations/checks and audit -->",
             "# Errata of Jesse, Baddorf & Kalinin (2006), as computed by pfmdyn", "",
             f"Sign convention: {typeset.markdown(SIGN_CONVENTION_SENTENCE)}.", ""]
    registry = [v for v in verdicts if v.kind == "claim" and v.verdict in (Outcome.ERRATUM, Outcome.SIGN)]
    audit = [v for v in verdicts if v.kind != "claim" and v.verdict == Outcome.ERRATUM]
    for v in registry:
        lines += entry(v)
    if audit:
        lines += ["## Errata of the text (cross-references, symbols, statements)", ""]
        for v in audit:
            fix = typeset.markdown(typeset.correction(v))
            lines.append(f"- `{v.id}` ({typeset.markdown(v.where)}): {typeset.markdown(v.proof.proof)}."
                         + (f" Correct: {fix}." if fix else ""))
        lines.append("")
    return "\n".join(lines)


def write_errata(verdicts, path: Path) -> None:
    Path(path).write_text(render_errata(verdicts))


def entry(v) -> list[str]:
    """Markdown lines of one erratum: printed, correct, proof (sentence and decisive expression)."""
    f = typeset.erratum(v)
    kind = "Erratum" if v.verdict == Outcome.ERRATUM else "Sign convention"
    lines = [f"## `{v.id}` ({typeset.markdown(v.where)}) — {kind}", "", f"**Printed:** {typeset.markdown(f['printed'])}", ""]
    if f["correct"]:
        lines += ["**Correct:**", ""] + [f"$$\n{t}\n$$" for t in f["correct"]] + [""]
    if f["correction"] or not f["correct"]:
        lines += [f"**Correct:** {typeset.markdown(f['correction']) or '(see proof)'}", ""]
    lines += [f"**Proof:** {typeset.markdown(f['proof'])}." + (" Decisive:" if f["decisive"] else ""), ""]
    if f["decisive"]:
        lines += [f"$$\n{f['decisive']}\n$$", ""]
    if f["sign"]:
        lines += [f"*Sign convention:* {typeset.markdown(SIGN_CONVENTION_SENTENCE)}.", ""]
    return lines


def table(verdicts, width: int = 110) -> str:
    """The plain-text verdict table printed by ``pfmdyn verify``."""
    w_id = max(len(v.id) for v in verdicts)
    where = {v.id: text(v.where) for v in verdicts}
    w_where = min(28, max(len(w) for w in where.values()))
    rows = [f"{'id':<{w_id}}  {'where':<{w_where}}  {'verdict':<27}  evidence"]
    for v in verdicts:
        evidence = " ".join(v.evidence.split())
        evidence = evidence if len(evidence) <= width else evidence[:width - 3] + "..."
        rows.append(f"{v.id:<{w_id}}  {where[v.id][:w_where]:<{w_where}}  {str(v.verdict):<27}  {evidence}")
    return "\n".join(rows)
