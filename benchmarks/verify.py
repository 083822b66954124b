"""Benchmark: ``pfmdyn verify`` cold (a fresh interpreter, as a user runs it) against a baseline commit.

Run ``python benchmarks/verify.py [--baseline REV]`` (default: 478d53d, the tree of issue 38).  The
baseline is checked out into a temporary git worktree (:func:`compose._baseline_tree`); the two trees
run alternately, :data:`REPEAT` times each, and the best wall time and the CPU time (user + system, all
processes: the checks run in one process per core) of each are kept.  Both must print the same
summary line (the same verdicts).  Target: the current tree >= 1.5x faster than the baseline (wall).

Timings on a loaded machine are unreliable: the load average is printed beside them, and the CPU
time, less sensitive to load, beside the wall time.
Results: ``benchmarks/results/verify.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from compose import ROOT, SHARED, _baseline_tree
from recording import recorded

BASELINE = "478d53d"
REPEAT = 3
ARGV = ["-m", "pfmdyn.cli", "verify", "--quiet"]


def _run(cwd: Path, env: dict) -> tuple[float, float, str]:
    """Wall and CPU seconds of one cold ``pfmdyn verify``, and its summary line."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, *ARGV], cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"verify failed in {cwd} ({proc.returncode}): {proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, proc.stdout.strip().splitlines()[-1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="the commit to compare with")
    rev = parser.parse_args().baseline
    with tempfile.TemporaryDirectory() as tmp:
        base, base_env = _baseline_tree(rev, Path(tmp))
        trees = {"current": (ROOT, {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, **SHARED}),
                 f"baseline {rev}": (base, {**base_env, **SHARED})}
        try:
            best = {name: (float("inf"), float("inf")) for name in trees}
            lines = {}
            for i in range(REPEAT):
                for name, (cwd, env) in trees.items():
                    load = os.getloadavg()[0]
                    wall, cpu, lines[name] = _run(cwd, env)
                    print(f"run {i + 1}, {name}: {wall:.1f} s wall, {cpu:.1f} s CPU (load {load:.2f})")
                    best[name] = (min(best[name][0], wall), min(best[name][1], cpu))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, check=False)
    (new_wall, new_cpu), (old_wall, old_cpu) = best.values()
    same = len(set(lines.values())) == 1
    print(f"\nsummary: {lines['current']}")
    print(f"verdicts: {'the same in both trees' if same else 'DIFFERENT: ' + repr(lines)}")
    print(f"best of {REPEAT}: current {new_wall:.1f} s wall ({new_cpu:.1f} s CPU), baseline {old_wall:.1f} s wall "
          f"({old_cpu:.1f} s CPU)")
    speedup = old_wall / new_wall
    print(f"speed-up {speedup:.2f}x wall, {old_cpu / new_cpu:.2f}x CPU "
          f"(target >= 1.5x: {'met' if speedup >= 1.5 and same else 'MISSED'})")


if __name__ == "__main__":
    with recorded("verify"):
        main()
