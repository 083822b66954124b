"""``pfmdyn codegen``: write ``generated/`` from ``derivations/``, or check it is up to date.

``--check`` renders every file into a temporary folder and compares it with the committed
``generated/``; it fails, naming the files that differ, when anything is stale or edited
by hand.  Without a flag (or with ``--update``) the files are written.  SymPy is imported
only here, lazily: the numeric package never needs it.
"""
from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from ..errors import UserError

__all__ = ["add_arguments", "run", "stale_files"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``pfmdyn codegen``.

    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["--check"]).check
    True
    """
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="fail if generated/ differs from a fresh generation")
    mode.add_argument("--update", action="store_true", help="write generated/ (the default)")
    parser.add_argument("--output", type=Path, default=None,
                        help="folder to check or write (default: the repository's generated/)")


def stale_files(folder: Path) -> list[str]:
    """Names of generated files in ``folder`` that differ from a fresh generation, or are missing."""
    from pfmdyn.derivations import codegen

    with tempfile.TemporaryDirectory() as tmp:
        fresh = Path(tmp)
        codegen.write(fresh)
        return sorted(
            p.name for p in fresh.iterdir()
            if not (folder / p.name).exists()
            or (folder / p.name).read_bytes() != p.read_bytes()
        )


def run(args: argparse.Namespace) -> int:
    """Run ``pfmdyn codegen``; returns the exit status."""
    from pfmdyn.derivations import codegen

    folder = args.output or codegen.GENERATED
    if args.check:
        if not folder.is_dir():
            raise UserError(f"no such folder: {folder}")
        stale = stale_files(folder)
        if stale:
            print(f"pfmdyn codegen: stale or edited in {folder}: {', '.join(stale)}; "
                  "run `pfmdyn codegen` to regenerate")
            return 1
        print(f"pfmdyn codegen: {folder} is up to date")
        return 0
    changed = codegen.write(folder)
    print(f"pfmdyn codegen: wrote {len(changed)} file(s) to {folder}"
          + (f": {', '.join(changed)}" if changed else ""))
    return 0
