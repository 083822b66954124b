"""Benchmark: ``pfmdyn calibrate``, ``stiffness`` and ``resonances`` cold, on ordinary inputs, against a baseline.

Run ``python benchmarks/commands.py [--baseline REV]`` (default: 478d53d, the tree of issue 38).  The
baseline is checked out into a temporary git worktree (:func:`compose._baseline_tree`); each command
runs in a fresh interpreter, the two trees alternating, :data:`REPEAT` times, and the best wall and
CPU times are kept, beside the share of the imports (``python -X importtime``, current tree).  Both
trees must print the same.  Target: each command under a second (wall, on a quiet machine).

Results: ``benchmarks/results/commands.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import os
import re
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
TUNE = ROOT.parent / "shared" / "realdata" / "nsfopen_thermal_ACL-A" / "thermal.nid"
if not TUNE.exists():
    TUNE = Path("/work/shared/realdata/nsfopen_thermal_ACL-A/thermal.nid")
COMMANDS = {
    "calibrate (the shared Nanosurf tune)": ["calibrate", str(TUNE), "--length", "225e-6", "--width", "40e-6"],
    "stiffness (one contact mode)": ["stiffness", "--free-resonance", "70e3", "--contact", "300e3",
                                     "--spring-constant", "2"],
    "resonances (3 free and 3 contact modes)": ["resonances", "--spring-constant", "2", "--free-resonance", "70e3",
                                                "--length", "225e-6", "--tip-height", "10e-6", "--k1", "200",
                                                "--k2", "100"],
}


def _run(argv: list[str], cwd: Path, env: dict) -> tuple[float, float, str]:
    """Wall and CPU seconds of one cold command, and what it printed."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pfmdyn.cli", *argv], cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed in {cwd}: {proc.stderr[-1500:]}")
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime, proc.stdout


def _top_level(argv: list[str], env: dict) -> float:
    """Seconds the command spends importing modules (the top-level entries of ``-X importtime``)."""
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "pfmdyn.cli", *argv], cwd=ROOT, env=env,
                          capture_output=True, text=True)
    return sum(int(m.group(1)) for m in re.finditer(r"import time:\s+\d+ \|\s+(\d+) \| \S", proc.stderr)) * 1e-6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="the commit to compare with")
    rev = parser.parse_args().baseline
    now_env = {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, **SHARED}
    print(f"load average at the start: {os.getloadavg()[0]:.2f}")
    print("\n| command | current wall (s) | current CPU (s) | of which imports (s) | baseline wall (s) | "
          "baseline CPU (s) | same output | under 1 s |\n|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        base, base_env = _baseline_tree(rev, Path(tmp))
        trees = {"current": (ROOT, now_env), "baseline": (base, {**base_env, **SHARED})}
        try:
            for label, argv in COMMANDS.items():
                best = {name: (float("inf"), float("inf")) for name in trees}
                printed = {}
                for _ in range(REPEAT):
                    for name, (cwd, env) in trees.items():
                        wall, cpu, printed[name] = _run(argv, cwd, env)
                        best[name] = (min(best[name][0], wall), min(best[name][1], cpu))
                imports = _top_level(argv, now_env)
                (new_wall, new_cpu), (old_wall, old_cpu) = best.values()
                same = printed["current"] == printed["baseline"]
                print(f"| {label} | {new_wall:.2f} | {new_cpu:.2f} | {imports:.2f} | {old_wall:.2f} | {old_cpu:.2f} | "
                      f"{'yes' if same else 'NO'} | {'met' if new_wall < 1 else 'MISSED'} |")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, check=False)
    print(f"\nload average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    with recorded("commands"):
        main()
