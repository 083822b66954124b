"""``pfmdyn book``: build the verified book (see :mod:`pfmdyn.book.build`)."""
from __future__ import annotations

import sys
import time
from pathlib import Path


def add_arguments(parser) -> None:
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="build directory; the HTML goes to DIR/html (default: book/_build)")


def run(args) -> int:
    from ..book.build import book_dir, build

    out = Path(args.out) if args.out else book_dir() / "_build"
    t0 = time.perf_counter()
    status = build(out, progress=lambda line: print(line, file=sys.stderr))
    elapsed = time.perf_counter() - t0
    index = out.resolve() / "html" / "index.html"
    if status != 0:
        print(f"pfmdyn book: build failed (status {status}) after {elapsed:.0f} s", file=sys.stderr)
        return 1
    print(f"pfmdyn book: built in {elapsed:.0f} s; open {index}")
    return 0
