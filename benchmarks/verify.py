"""Benchmark: ``pfmdyn verify`` cold (a fresh interpreter, as a user runs it).

Run ``python benchmarks/verify.py``.  Target: <= 40 s on the project machine (2 shared cores).

The baseline, in the same run, is the same command with the per-run caches switched off:
every comparison point lambdified anew, the Taylor series of cos/sin/cosh/sinh rebuilt on
every ``beta -> 0`` limit, and every registry claim that a text statement reuses checked again.
These are the three steps a profile (``python -m cProfile -m pfmdyn.cli verify --quiet``) showed
to dominate before they were cached.

Results: ``benchmarks/results/verify.md``, written by each completed run.
"""
from __future__ import annotations

import subprocess
import sys
import time

from recording import recorded

UNCACHED = """
import functools
from pfmdyn import cli
from pfmdyn.derivations import limits
from pfmdyn.derivations.checks import core
limits._series = limits._series.__wrapped__
core._evaluator = core._evaluator.__wrapped__
core.result = lambda claim_id: core.run_check(core.REGISTRY[claim_id])
from pfmdyn.audit import restated, statements
statements.result = restated.result = core.result
raise SystemExit(cli.main(["verify", "--quiet"]))
"""


def _run(args: list[str]) -> tuple[float, str]:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"verify failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return elapsed, proc.stdout.strip().splitlines()[-1]


def main() -> None:
    cached, line = _run(["-m", "pfmdyn.cli", "verify", "--quiet"])
    uncached, _ = _run(["-c", UNCACHED])
    print(line)
    print(f"verify cold: {cached:.1f} s (target <= 40 s: {'met' if cached <= 40 else 'MISSED'})")
    print(f"baseline without the per-run caches: {uncached:.1f} s; speed-up {uncached / cached:.2f}x")


if __name__ == "__main__":
    with recorded("verify"):
        main()
