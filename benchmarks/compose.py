"""Benchmark: the composed lever against the previous design (expanded two-segment closed forms).

Run ``python benchmarks/compose.py [--baseline REV]`` (default: the last commit with the closed
forms).  The baseline is checked out into a temporary git worktree and run from there, in the
same run, alternating with the current tree, each step in a fresh interpreter:

* ``pfmdyn verify`` and ``pfmdyn codegen --check`` cold (targets: 15 s and 20 s on 2 cores);
* the size of ``generated/`` (target: at most 2,500 lines);
* the forward model: the slope and its partials at 4,000 frequencies, the characteristic on
  small arrays (what root refinement calls) and on a grid;
* end to end: a spectrum with the laser spot away from the end through ``discrepancy``, and the
  map fits of the composed probe (their tests, as workloads; the best of :data:`REPEAT` runs each).

Ratios are current / baseline (below 1: faster now).  Measure on a quiet machine (load below 1).
Results: ``benchmarks/results/compose.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import inspect
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from recording import recorded

ROOT = Path(__file__).resolve().parent.parent
BASELINE = "5e52f54"
REPEAT = 3
"""Runs of each end-to-end workload per design (the best is kept)."""
SHARED = {"PFMDYN_CLAIMS": str(ROOT.parent / "shared" / "claims.yaml"),
          "PFMDYN_PAPER": str(ROOT.parent / "shared" / "paper" / "jesse2006_dynamic_pfm.md")}
"""The claims and paper both designs read (the baseline's worktree has no shared/ beside it)."""


def best(f, repeat: int) -> float:
    """The best of five timings of ``f`` per call, each over ``repeat`` calls, after one call to warm up."""
    f()
    out = []
    for _ in range(5):
        t = time.perf_counter()
        for _ in range(repeat):
            f()
        out.append((time.perf_counter() - t) / repeat)
    return min(out)


# Run in a fresh interpreter in either tree; it times with the source of best above, so both designs are timed alike.
FORWARD = """
import inspect, os, sys, time, numpy as np
import pfmdyn
# (by file: an editable install of the current tree would answer an import the baseline lacks)
if any(os.path.exists(os.path.join(os.path.dirname(pfmdyn.__file__), n)) for n in ("composed.py", "composed")):
    from pfmdyn import composed
    spot, char = composed.slope_and_jacobian, composed.characteristic
    if "parameters" in inspect.signature(char).parameters:      # one typed argument (after 606812a)
        lever = composed.Parameters(2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
        spot = lambda beta, sigma, *args, **kwargs: composed.slope_and_jacobian(beta, lever, sigma, **kwargs)
        char = lambda beta, *args: composed.characteristic(beta, lever)
else:
    from pfmdyn.generated import detection, tip_setback
    spot = detection.slope_and_jacobian
    char = tip_setback.characteristic
args = (2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
beta = np.linspace(0.5, 30, 4000) * (1 + 0.01j)
small = np.linspace(1.0, 10.0, 5)
grid = np.linspace(0.3, 30, 400)

{best}

print(best(lambda: spot(beta, 0.8, *args, wrt=("beta", "sigma", "kvv", "kll", "kvl")), 3),
      best(lambda: char(small, *args), 200), best(lambda: char(grid, *args), 50))
""".replace("{best}", inspect.getsource(best))

WORKLOADS = {
    "discrepancy, spot away from the end": "tests/test_discrepancy_spot.py::test_spot_away_from_the_end_is_named",
    "map fits of a set-back, heavy tip": "tests/test_maps_bias.py::test_known_tip_geometry_is_used",
}


def _baseline_tree(rev: str, where: Path) -> tuple[Path, dict]:
    """A worktree of ``rev`` importable as ``pfmdyn`` (its top-level folders linked into the package)."""
    tree = where / "tree"
    subprocess.run(["git", "worktree", "add", "--detach", "-q", str(tree), rev], cwd=ROOT, check=True)
    for name in ("derivations", "generated", "audit"):
        (tree / "pfmdyn" / name).symlink_to(tree / name)
    (where / "path").mkdir()
    (where / "path" / "pfmdyn").symlink_to(tree / "pfmdyn")
    return tree, {**os.environ, "PYTHONPATH": str(where / "path")}


def _timed(args, cwd, env) -> float:
    t = time.perf_counter()
    done = subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)} in {cwd} failed: {done.stdout[-1500:]}{done.stderr[-1500:]}")
    return time.perf_counter() - t


def _lines(folder: Path) -> int:
    return sum(len(p.read_text().splitlines()) for p in folder.glob("*.py"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="commit of the previous design")
    rev = parser.parse_args().baseline
    load = os.getloadavg()[0]
    print(f"machine load at start: {load:.2f}" + ("" if load < 1 else " (above 1: ratios are unreliable)"))
    with tempfile.TemporaryDirectory() as tmp:
        base, base_env = _baseline_tree(rev, Path(tmp))
        now = (ROOT, {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, **SHARED})
        trees = {"current": now, f"baseline {rev}": (base, {**base_env, **SHARED})}
        try:
            rows = []
            for label, argv, target in (("pfmdyn verify, cold", ["-m", "pfmdyn.cli", "verify", "--quiet"], 15),
                                        ("pfmdyn codegen --check, cold", ["-m", "pfmdyn.cli", "codegen", "--check"],
                                         20)):
                times = {name: _timed(argv, cwd, env) for name, (cwd, env) in trees.items()}
                rows.append((label, *times.values(), target))
            for label, test in WORKLOADS.items():
                argv = ["-m", "pytest", "-q", "-p", "no:cacheprovider", test]
                # the best of REPEAT runs, the two designs alternating: a run-to-run spread of about 5 %
                # would otherwise decide "no slower"
                times = {name: math.inf for name in trees}
                for _ in range(REPEAT):
                    for name, (cwd, env) in trees.items():
                        times[name] = min(times[name], _timed(argv, cwd, env))
                rows.append((label, *times.values(), None))
            print("\n| step | current (s) | baseline (s) | ratio | target |\n|---|---|---|---|---|")
            for label, new, old, target in rows:
                goal = "" if target is None else f"<= {target} s: {'met' if new <= target else 'MISSED'}"
                print(f"| {label} | {new:.1f} | {old:.1f} | {new / old:.2f} | {goal} |")
            forward = {}
            for name, (cwd, env) in trees.items():
                out = subprocess.run([sys.executable, "-c", FORWARD], cwd=cwd, env=env, capture_output=True,
                                     text=True, check=True).stdout.split()
                forward[name] = [float(x) for x in out]
            new, old = forward["current"], forward[f"baseline {rev}"]
            print("\n| forward model | current | baseline | ratio |\n|---|---|---|---|")
            for i, label in enumerate(("slope and 5 partials at a spot, 4,000 damped frequencies (ms)",
                                       "characteristic, 5 points (us per call)",
                                       "characteristic, 400-point grid (us per call)")):
                unit = 1e3 if i == 0 else 1e6
                print(f"| {label} | {new[i] * unit:.1f} | {old[i] * unit:.1f} | {new[i] / old[i]:.2f} |")
            lines = {"current": _lines(ROOT / "generated"), "baseline": _lines(base / "generated")}
            print(f"\ngenerated/: {lines['current']} lines (baseline {lines['baseline']}; target <= 2500: "
                  f"{'met' if lines['current'] <= 2500 else 'MISSED'})")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, check=False)


if __name__ == "__main__":
    with recorded("compose"):
        main()
