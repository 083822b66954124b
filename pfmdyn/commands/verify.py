"""``pfmdyn verify``: derive every result, check every claim and every checkable sentence of the
paper, print the verdict table and a summary line, gate on the recorded verdicts.

Exits 1 when a computed verdict differs from ``derivations/recorded_verdicts.yaml`` or when an
id of the shared claims file has no check.  Files are written only where asked: ``--json``,
``--errata PATH``, and ``--record`` (which rewrites the recorded verdicts after review).
"""
from __future__ import annotations

import sys
from pathlib import Path

from . import flags


def add_arguments(parser) -> None:
    flags.add_json(parser, "the verdicts")
    parser.add_argument("--errata", metavar="PATH",
                        help="write the errata (Markdown with LaTeX) to PATH ('-': the errata alone on standard "
                             "output, the report on standard error)")
    parser.add_argument("--claims", metavar="PATH",
                        help="the shared claims file whose ids must all have verdicts "
                             "(default: $PFMDYN_CLAIMS or shared/claims.yaml beside the source tree)")
    parser.add_argument("--only", metavar="ID", action="append", help="check only these claim ids")
    parser.add_argument("--record", action="store_true",
                        help="write the computed verdicts as the recorded ones (after review)")
    parser.add_argument("--quiet", action="store_true", help="print only the summary line")


def run(args) -> int:
    from .. import verify
    from ..io.results import check_writable

    check_writable(args.json, args.errata)      # before the minutes of checks
    verdicts = verify.compute(args.only, progress=flags.progress_shown(args))
    shared = [] if args.only else verify.shared_claim_ids(verify.shared_claims_path(args.claims))
    if args.record:
        verify.record(verdicts, merge=bool(args.only))
        problems = [f"{i}: listed in the claims file but has no check" for i in shared
                    if i not in {v.id for v in verdicts}]
    else:
        problems = verify.gate(verdicts, verify.load_recorded(), shared)
    if args.errata and args.errata != "-":
        verify.write_errata(verdicts, Path(args.errata))
    if not args.quiet:
        print(verify.table(verdicts))
    print(verify.summary(verdicts))
    if args.errata == "-":
        print(verify.render_errata(verdicts), end="")
    flags.write_json(args.json, verify.to_json(verdicts))
    for p in problems:
        print(f"verdict gate: {p}", file=sys.stderr)
    return 1 if problems else 0
