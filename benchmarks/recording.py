"""Benchmark results written beside the scripts, in ``benchmarks/results/<name>.md``.

A benchmark runs its main function inside :func:`recorded`: everything it prints goes to the
terminal and, when the run completes, to the file, under a header saying how it was run, when,
on which commit and under what machine load.  The file is committed when it changes, so the
history of a benchmark's results is git's history of that file (docstrings state the targets,
not the runs).  An interrupted or failed run leaves the previous file as it was.
"""
from __future__ import annotations

import contextlib
import io
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["RESULTS", "recorded", "tally"]

RESULTS = Path(__file__).resolve().parent / "results"
"""Where the result files go."""


class _Tee(io.TextIOBase):
    """A text stream writing to several streams."""

    def __init__(self, *streams):
        self.streams = streams

    def write(self, text):
        for stream in self.streams:
            stream.write(text)
        return len(text)

    def flush(self):
        for stream in self.streams:
            stream.flush()


def _commit() -> str:
    """The commit the code was at, marked when the work tree had changes."""
    root = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git work tree)"
    return head + (" with uncommitted changes" if dirty else "")


def _header(name: str, argv: list[str], started: float, elapsed: float) -> str:
    import numpy as np

    load = "/".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "unknown"
    return (f"# Benchmark `{name}`\n\n"
            f"- run: `python benchmarks/{name}.py{''.join(' ' + a for a in argv)}`\n"
            f"- finished: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(started + elapsed))}"
            f" ({elapsed:.0f} s wall)\n"
            f"- code: {_commit()}\n"
            f"- machine: {os.cpu_count()} cores, load average {load} at the start; "
            f"Python {platform.python_version()}, NumPy {np.__version__}\n\n")


@contextlib.contextmanager
def recorded(name: str, argv: list[str] | None = None, folder: Path = RESULTS, variant: str = ""):
    """Print to the terminal and, when the block completes, write ``folder/<name>.md`` (a ``variant`` of
    the script's run, e.g. one of its options: ``folder/<name>_<variant>.md``).

    ``argv``: the script's arguments (default ``sys.argv[1:]``), quoted in the header.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with recorded("demo", [], Path(tmp)):
    ...         print("speed: 1.5 s (target <= 2 s)")
    ...     text = (Path(tmp) / "demo.md").read_text()
    speed: 1.5 s (target <= 2 s)
    >>> text.splitlines()[0], text.splitlines()[2], text.splitlines()[-2]
    ('# Benchmark `demo`', '- run: `python benchmarks/demo.py`', 'speed: 1.5 s (target <= 2 s)')
    """
    argv = sys.argv[1:] if argv is None else argv
    captured = io.StringIO()
    started, clock = time.time(), time.perf_counter()
    with contextlib.redirect_stdout(_Tee(sys.stdout, captured)):
        yield
    text = _header(name, argv, started, time.perf_counter() - clock) + "```text\n" + captured.getvalue()
    text += ("" if text.endswith("\n") else "\n") + "```\n"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}{'_' + variant if variant else ''}.md").write_text(text, encoding="utf-8")


def tally(passed: int, cases: int, failures: list[str], label: str = "") -> None:
    """Print how many of ``cases`` passed, then each failure on a line of its own.

    >>> tally(1, 2, ["seed 7: exit 2"], "null pairs: ")
    null pairs: passed 1 of 2 (50%)
    - seed 7: exit 2
    """
    print(f"{label}passed {passed} of {cases} ({passed / cases:.0%})")
    for line in failures:
        print(f"- {line}")


def coverage(covered: int, cases: int, failures: list[str], z, name: str) -> None:
    """:func:`tally` of the cases whose truth lies within 2 stated sigma, then the median ``|z|`` of the
    errors in stated sigma (a normal's is 0.67: far below, the uncertainties are generous; above, too narrow).

    >>> coverage(2, 3, ["case 1: 5 +- 1, truth 8"], [0.5, -1.0, 3.0], "k1")
    k1 within 2 stated sigma: passed 2 of 3 (67%)
    - case 1: 5 +- 1, truth 8
    median |z| 1.00 (a normal's: 0.67)
    """
    tally(covered, cases, failures, f"{name} within 2 stated sigma: ")
    if len(z):
        print(f"median |z| {statistics.median(abs(v) for v in z):.2f} (a normal's: 0.67)")
