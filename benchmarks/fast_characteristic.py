"""Benchmark: the characteristic written out from the segments, against the assembled system's
determinant (the general path), and what it does to the discrepancy.

Run ``python benchmarks/fast_characteristic.py [--repeat N]``.  In one run:

* per call, in this interpreter, alternating, with the tip at the end and set back to 0.9 L: the
  characteristic on 5 points above the bases' boundary (what root refinement calls), on 5 points
  with one at ``beta = 1`` (``benchmarks/compose.py``'s), on a 400-point grid from 0.3 (both
  bases), and on a start grid's batch (200 spring sets x 150 frequencies, each argument a column);
* per call, :func:`characteristic_and_jacobian` at 4 points as the resonances' sensitivity asks it;
* per call, the read-outs (written out) against the assembled system, at 4,000 damped frequencies,
  the tip at the end and set back to 0.9 L: the slope and 5 partials at a spot at 0.8 L
  (``benchmarks/compose.py``'s) and, set back, at the end; the partials a map fit asks at the end
  (``pfmdyn/maps/fit.py``'s: ``beta, kvv, kll, kvl, mu``), also on 64 frequencies (a pixel's); the
  response;
* end to end, each in a fresh interpreter, alternating: the discrepancy workload of
  ``benchmarks/compose.py`` (a spectrum with the spot away from the end) with the fast path, with
  it switched off (every characteristic and its partials from the assembled system), and on the
  previous design (expanded closed forms, commit 5e52f54, from a temporary git worktree).

Ratios are fast / general (below 1: the fast path is faster).  Measure on a quiet machine.
Results: ``benchmarks/results/fast_characteristic.md``.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from compose import BASELINE, ROOT, SHARED, WORKLOADS, _baseline_tree, _timed, best
from recording import recorded

from pfmdyn import composed
from pfmdyn.composed import assembly, determinant, readout

ARGS = (2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
"""``benchmarks/compose.py``'s lever."""
WORKLOAD = "discrepancy, spot away from the end"
GENERAL = """
def general(beta, parameters):
    lever = assembly._Lever(beta, *parameters)
    return lever.out(assembly._scaled_det(lever)[0])
"""
exec(GENERAL)
SWITCHED_OFF = ("import sys, pytest; from pfmdyn import composed; from pfmdyn.composed import assembly, determinant, readout" + GENERAL + "composed.characteristic = general; "
                "determinant._tip_at_end = lambda gamma: False; readout._written_out = lambda *a, **k: False; "
                "sys.exit(pytest.main(sys.argv[1:]))")
"""The workload with every characteristic, its partials and the read-outs from the assembled system."""


def _best(f, seconds: float = 0.4) -> float:
    """The best of five timings of ``f`` per call (each of about ``seconds / 5``)."""
    f()                 # warm, so that the next call sizes the repeat count
    t = time.perf_counter()
    f()
    return best(f, max(1, int(seconds / 5 / max(time.perf_counter() - t, 1e-7))))


def per_call() -> None:
    print("| characteristic | tip at | fast (us) | general (us) | fast / general |\n|---|---|---|---|---|")
    for gamma in (1.0, 0.9):
        args = (*ARGS[:7], gamma, ARGS[8])
        columns = [np.full((200, 1), a) for a in args]
        columns[1] = np.linspace(0.0, 300.0, 200)[:, None]
        cases = {"5 points in 2-10 (refinement)": (np.linspace(2.0, 10.0, 5), args),
                 "5 points in 1-10 (compose.py's)": (np.linspace(1.0, 10.0, 5), args),
                 "400-point grid, 0.3-30": (np.linspace(0.3, 30.0, 400), args),
                 "start grid: 200 springs x 150 points": (np.linspace(0.3, 20.0, 150), columns)}
        for label, (beta, a) in cases.items():
            a = composed.Parameters(*a)
            assert np.allclose(composed.characteristic(beta, a), general(beta, a), rtol=1e-10, atol=0)
            fast, slow = [], []
            for _ in range(2):
                fast.append(_best(lambda: composed.characteristic(beta, a)))
                slow.append(_best(lambda: general(beta, a)))
            new, old = min(fast), min(slow)
            print(f"| {label} | {gamma:g} L | {new * 1e6:.1f} | {old * 1e6:.1f} | {new / old:.2f} |")
    # the partials at the roots, as resonance_sensitivity asks them (the tip at the end, no gamma)
    beta, wrt = np.array([1.9, 4.7, 7.9, 11.0]), ("beta", "kvv", "kll", "kvl", "mu")
    at_end = composed.Parameters(*ARGS[:7], 1.0, ARGS[8])
    fast = _best(lambda: composed.characteristic_and_jacobian(beta, at_end, wrt=wrt))
    determinant._tip_at_end, before = (lambda gamma: False), determinant._tip_at_end
    slow = _best(lambda: composed.characteristic_and_jacobian(beta, at_end, wrt=wrt))
    determinant._tip_at_end = before
    print(f"| its partials (beta and 4 more) at 4 points | 1 L | {fast * 1e6:.1f} | {slow * 1e6:.1f} | "
          f"{fast / slow:.2f} |")


def read_outs() -> None:
    five, fit = ("beta", "sigma", "kvv", "kll", "kvl"), ("beta", "kvv", "kll", "kvl", "mu")
    cases = [("slope and 5 partials", 4000, 1.0, 0.8, five), ("response", 4000, 1.0, 0.8, None),
             ("slope and 5 partials", 4000, 0.9, 0.8, five), ("slope and 5 partials", 4000, 0.9, 1.0, five),
             ("slope and a map fit's partials", 4000, 0.9, 1.0, fit), ("response", 4000, 0.9, 0.8, None),
             ("response", 4000, 0.9, 1.0, None),
             ("slope and a map fit's partials", 64, 0.9, 1.0, fit), ("response", 64, 0.9, 1.0, None)]
    print("\n| read-out | damped frequencies | tip at | spot at | fast (ms) | general (ms) | fast / general |\n"
          "|---|---|---|---|---|---|---|")
    before = readout._written_out
    for label, n, gamma, sigma, wrt in cases:
        args = (np.linspace(0.5, 30, n) * (1 + 0.01j), composed.Parameters(*ARGS[:7], gamma, ARGS[8]), sigma)
        f = (lambda: composed.response(*args)) if wrt is None else (lambda: composed.slope_and_jacobian(*args, wrt=wrt))
        fast, slow = [], []
        for _ in range(2):
            readout._written_out = before
            fast.append(_best(f))
            readout._written_out = lambda *args, **kwargs: False
            slow.append(_best(f))
        readout._written_out = before
        new, old = min(fast), min(slow)
        print(f"| {label} | {n:,} | {gamma:g} L | {sigma:g} L | {new * 1e3:.2f} | {old * 1e3:.2f} | {new / old:.2f} |")


def workload(repeat: int) -> None:
    test = ["-q", "-p", "no:cacheprovider", WORKLOADS[WORKLOAD]]
    with tempfile.TemporaryDirectory() as tmp:
        base, base_env = _baseline_tree(BASELINE, Path(tmp))
        env = {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, **SHARED}
        runs = {"fast path": (["-m", "pytest", *test], ROOT, env),
                "fast path off": (["-c", SWITCHED_OFF, *test], ROOT, env),
                f"previous design ({BASELINE})": (["-m", "pytest", *test], base, {**base_env, **SHARED})}
        try:
            times = {name: [] for name in runs}
            for _ in range(repeat):
                for name, (argv, cwd, e) in runs.items():
                    times[name].append(_timed(argv, cwd, e))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, check=False)
    fast = min(times["fast path"])
    print(f"\n| {WORKLOAD} (best of {repeat}) | s | fast path / this |\n|---|---|---|")
    for name, ts in times.items():
        print(f"| {name} | {min(ts):.1f} | {fast / min(ts):.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2, help="runs of each end-to-end variant")
    repeat = parser.parse_args().repeat
    print(f"machine load at start: {os.getloadavg()[0]:.2f}\n")
    per_call()
    read_outs()
    workload(repeat)
    print(f"\nmachine load at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    with recorded("fast_characteristic"):
        main()
