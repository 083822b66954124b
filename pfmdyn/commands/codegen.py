"""``pfmdyn codegen``: write ``generated/`` from ``derivations/``, or check it is up to date.

``--check`` renders every file in memory and compares it with the committed
``generated/``; it fails when a file is stale or edited by hand (printing its unified
diff, committed to fresh) or when ``generated/`` holds an orphan: a ``.py`` file that no
renderer writes.  Without a flag (or with ``--update``) the files are written.  SymPy is
imported only here, lazily: the numeric package never needs it.
"""
from __future__ import annotations

import argparse
import difflib
from dataclasses import dataclass
from pathlib import Path

from ..errors import UserError

__all__ = ["add_arguments", "run", "Comparison", "compare", "stale_files"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``pfmdyn codegen``.

    >>> p = argparse.ArgumentParser(); add_arguments(p)
    >>> p.parse_args(["--check"]).check
    True
    """
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="fail, with a diff, if generated/ differs from a fresh generation "
                           "or holds a file no renderer writes")
    mode.add_argument("--update", action="store_true", help="write generated/ (the default)")
    parser.add_argument("--output", type=Path, default=None,
                        help="folder to check or write (default: the repository's generated/)")


@dataclass(frozen=True)
class Comparison:
    """A folder against a fresh generation: stale files with their diffs, and orphans."""

    diffs: dict[str, str]
    """File name -> unified diff from the folder's text to the fresh text (missing: all added)."""
    orphans: list[str]
    """``.py`` files in the folder that no renderer writes."""

    @property
    def ok(self) -> bool:
        """Nothing stale, nothing orphaned.

        >>> Comparison({}, []).ok, Comparison({}, ["old.py"]).ok
        (True, False)
        """
        return not self.diffs and not self.orphans


def _diff(name: str, old: str, new: str) -> str:
    """Unified diff of one file, committed text to fresh text.

    >>> print(_diff("a.py", "x = 1\\n", "x = 2\\n"), end="")
    --- a.py (committed)
    +++ a.py (fresh)
    @@ -1 +1 @@
    -x = 1
    +x = 2
    """
    return "".join(difflib.unified_diff(old.splitlines(keepends=True), new.splitlines(keepends=True),
                                        f"{name} (committed)", f"{name} (fresh)"))


def compare(folder: Path, fresh: dict[str, str] | None = None) -> Comparison:
    """Compare ``folder`` with ``fresh`` (file name -> text; default: a fresh generation).

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = (Path(tmp) / "a.py").write_text("x = 1\\n")
    ...     _ = (Path(tmp) / "orphan.py").write_text("")
    ...     c = compare(Path(tmp), {"a.py": "x = 2\\n"})
    >>> sorted(c.diffs), c.orphans
    (['a.py'], ['orphan.py'])
    """
    from pfmdyn.derivations import codegen

    if fresh is None:
        fresh = codegen.render_all()
    diffs = {}
    for name, text in fresh.items():
        path = folder / name
        old = path.read_text(encoding="utf-8") if path.exists() else ""
        if not path.exists() or old != text:
            diffs[name] = _diff(name, old, text)
    orphans = sorted(p.name for p in folder.glob("*.py") if p.name not in fresh and p.name not in codegen.HAND_WRITTEN)
    return Comparison(diffs, orphans)


def stale_files(folder: Path) -> list[str]:
    """Names of generated files in ``folder`` that differ from a fresh generation, or are missing."""
    return sorted(compare(folder).diffs)


def run(args: argparse.Namespace) -> int:
    """Run ``pfmdyn codegen``; returns the exit status."""
    from pfmdyn.derivations import codegen

    folder = args.output or codegen.GENERATED
    if args.check:
        if not folder.is_dir():
            raise UserError(f"no such folder: {folder}")
        result = compare(folder)
        for name, diff in sorted(result.diffs.items()):
            print(diff, end="" if diff.endswith("\n") else "\n")
        if result.orphans:
            print(f"pfmdyn codegen: orphan file(s) in {folder}, written by no renderer: "
                  f"{', '.join(result.orphans)}; delete them or add their renderer")
        if result.diffs:
            print(f"pfmdyn codegen: stale or edited in {folder}: {', '.join(sorted(result.diffs))}; "
                  "run `pfmdyn codegen` to regenerate")
        if not result.ok:
            return 1
        print(f"pfmdyn codegen: {folder} is up to date")
        return 0
    fresh = codegen.render_all()
    changed = codegen.write(folder, fresh)
    print(f"pfmdyn codegen: wrote {len(changed)} file(s) to {folder}"
          + (f": {', '.join(changed)}" if changed else ""))
    orphans = compare(folder, fresh).orphans
    if orphans:
        print(f"pfmdyn codegen: orphan file(s) in {folder}, written by no renderer: {', '.join(orphans)}")
    return 0
