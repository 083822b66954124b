"""``pfmdyn verify``: derive every result, check every claim of the paper, gate on the verdicts.

Prints a table (id, where, verdict, evidence) and a summary line; optionally writes JSON
``{"claims": [{"id", "verdict", "correct", "evidence"}, ...]}``; rewrites the errata list
``generated/errata.md``.  Exits 1 when a computed verdict differs from the one recorded in
``derivations/recorded_verdicts.yaml`` or when a claim id (of the project or of the shared
claims file) has no verdict; ``--record`` rewrites the recorded verdicts instead.
"""
from __future__ import annotations

import json
import os
import sys
from collections import Counter
from pathlib import Path

import yaml

from .errors import UserError

HERE = Path(__file__).resolve().parent
RECORDED = "recorded_verdicts.yaml"


def add_arguments(parser) -> None:
    parser.add_argument("--json", metavar="PATH", help="write the verdicts as JSON to PATH")
    parser.add_argument("--errata", metavar="PATH",
                        help="where to write the errata list (default: errata.md in pfmdyn.generated)")
    parser.add_argument("--claims", metavar="PATH",
                        help="the shared claims file whose ids must all have verdicts "
                             "(default: $PFMDYN_CLAIMS or ../shared/claims.yaml beside the source tree)")
    parser.add_argument("--only", metavar="ID", action="append", help="check only these claim ids")
    parser.add_argument("--record", action="store_true",
                        help="write the computed verdicts as the recorded ones (after review)")
    parser.add_argument("--quiet", action="store_true", help="print only the summary line")


def _shared_claims_path(arg: str | None) -> Path | None:
    if arg:
        return Path(arg)
    if os.environ.get("PFMDYN_CLAIMS"):
        return Path(os.environ["PFMDYN_CLAIMS"])
    from . import derivations
    candidate = Path(derivations.__file__).resolve().parent.parent.parent / "shared" / "claims.yaml"
    return candidate if candidate.exists() else None


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


def compute(ids: list[str] | None = None, progress: bool = True):
    """Run the checks; returns the list of :class:`Verdict` in registry order."""
    from tqdm import tqdm

    from .derivations.checks import core
    checks = [c for c in core.REGISTRY.values() if ids is None or c.id in ids]
    unknown = set(ids or ()) - set(core.REGISTRY)
    if unknown:
        raise UserError(f"unknown claim id(s): {', '.join(sorted(unknown))}")
    out = []
    for check in tqdm(checks, desc="checking claims", unit="claim", disable=not progress, file=sys.stderr):
        out.append(core.run_check(check))
    return out


def render_errata(verdicts) -> str:
    """The errata list as Markdown: printed statement, correction, proof."""
    lines = ["<!-- generated — do not edit: written by `pfmdyn verify` from derivations/checks -->",
             "# Errata of Jesse, Baddorf & Kalinin (2006), as computed by pfmdyn", ""]
    for v in verdicts:
        if v.verdict not in ("erratum", "holds_up_to_sign_convention"):
            continue
        kind = "Erratum" if v.verdict == "erratum" else "Sign convention"
        lines += [f"## `{v.id}` ({v.where}) — {kind}", "",
                  f"- **Printed:** {v.printed}", f"- **Correct:** {v.correct or '(see proof)'}",
                  f"- **Proof:** {v.evidence}", ""]
    return "\n".join(lines)


def _table(verdicts) -> str:
    w_id = max(len(v.id) for v in verdicts)
    w_where = min(28, max(len(v.where) for v in verdicts))
    rows = [f"{'id':<{w_id}}  {'where':<{w_where}}  {'verdict':<27}  evidence"]
    for v in verdicts:
        evidence = v.evidence if len(v.evidence) <= 110 else v.evidence[:107] + "..."
        rows.append(f"{v.id:<{w_id}}  {v.where[:w_where]:<{w_where}}  {v.verdict:<27}  {evidence}")
    return "\n".join(rows)


def run(args) -> int:
    verdicts = compute(args.only, progress=not args.quiet)
    recorded = load_recorded()
    problems = []
    computed = {v.id: v.verdict for v in verdicts}
    if args.only is None:
        missing = [i for i in shared_claim_ids(_shared_claims_path(args.claims)) if i not in computed]
        problems += [f"{i}: listed in the claims file but has no check" for i in missing]
    if args.record:
        recorded_path().write_text(yaml.safe_dump(dict(sorted(computed.items())), sort_keys=True))
    else:
        for v in verdicts:
            if v.id not in recorded:
                problems.append(f"{v.id}: no recorded verdict (computed {v.verdict})")
            elif recorded[v.id] != v.verdict:
                problems.append(f"{v.id}: computed {v.verdict}, recorded {recorded[v.id]}")
    if args.only is None:
        if args.errata:
            errata_path = Path(args.errata)
        else:
            from . import generated
            errata_path = Path(generated.__file__).resolve().parent / "errata.md"
        errata_path.write_text(render_errata(verdicts))
    if args.json:
        payload = {"claims": [{"id": v.id, "where": v.where, "verdict": v.verdict, "correct": v.correct,
                               "evidence": v.evidence} for v in verdicts]}
        Path(args.json).write_text(json.dumps(payload, indent=2))
    if not args.quiet:
        print(_table(verdicts))
    counts = Counter(v.verdict for v in verdicts)
    summary = ", ".join(f"{counts[key]} {key}" for key in
                        ("holds", "holds_up_to_sign_convention", "erratum", "undecidable"))
    print(f"{len(verdicts)} claims: {summary}")
    for p in problems:
        print(f"verdict gate: {p}", file=sys.stderr)
    return 1 if problems else 0
