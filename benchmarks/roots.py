"""Benchmark: certified roots (pfmdyn.roots) and branch sweeps against plain mpmath.findroot.

Run ``python benchmarks/roots.py``.  The baseline is what one would write without the
engine: ``mpmath.findroot`` started from the asymptotic guesses ``(2n-1) pi/2`` (free) and
``(4n+1) pi/4`` (pinned), uncertified.  Targets: 100 roots at 100 digits < 2 s, 10 roots at
1000 digits < 5 s, a 500 x 5 double-precision branch sweep < 1 s.

Results: ``benchmarks/results/roots.md``, written by each completed run.
"""
from __future__ import annotations

import time

import mpmath as mp
import numpy as np

from pfmdyn.roots import branches
from pfmdyn.roots.core import family_roots
from recording import recorded

EQUATIONS = {"free": (lambda b: mp.cos(b) + mp.sech(b), lambda n: (2 * n - 1) * mp.pi / 2),
             "pinned": (lambda b: mp.cos(b) * mp.tanh(b) - mp.sin(b), lambda n: (4 * n + 1) * mp.pi / 4)}


def _timed(fn):
    start = time.perf_counter()
    out = fn()
    return time.perf_counter() - start, out


def _mpmath_roots(family: str, n: int, digits: int) -> list:
    f, guess = EQUATIONS[family]
    with mp.workdps(digits + 10):
        return [mp.findroot(f, guess(i)) for i in range(1, n + 1)]


def _mpmath_sweep(stiffness: np.ndarray, modes: int) -> np.ndarray:
    soft, stiff = branches.branch_limits("indentation", modes)

    def f(z, s):
        return z**3 * (mp.cos(z) + mp.sech(z)) + 3 * s * (mp.sin(z) - mp.cos(z) * mp.tanh(z))

    return np.array([[float(mp.findroot(lambda z: f(z, s), (soft[m], stiff[m]), solver="anderson"))
                      for m in range(modes)] for s in stiffness])


def row(label: str, ours: float, base: float, target: float) -> str:
    """One line of the report: times in seconds and the speed-up over mpmath."""
    verdict = "ok" if ours < target else "OVER TARGET"
    return f"{label:<52} {ours:8.3f} s   mpmath {base:8.3f} s   x{base / ours:6.1f}   target {target:g} s: {verdict}"


def main() -> None:
    """Run every case and print one line each."""
    for family in ("free", "pinned"):
        for n, digits, target in ((100, 100, 2.0), (10, 1000, 5.0)):
            ours, result = _timed(lambda: family_roots(family, n, digits))
            base, ref = _timed(lambda: _mpmath_roots(family, n, digits))
            assert result.certified, result.reason
            with mp.workdps(digits + 10):
                worst = max(abs(mp.mpf(r) - x) / x for r, x in zip(result.roots, ref))
            assert worst < mp.mpf(10) ** (1 - digits), (family, n, digits, worst)
            print(row(f"{family}: first {n} roots, {digits} digits, certified", ours, base, target))
    stiffness = np.logspace(-3, 6, 500)
    branches._limits.cache_clear()            # include the certified limits in the time
    ours, z = _timed(lambda: branches.sweep("indentation", stiffness, 5))
    base, ref = _timed(lambda: _mpmath_sweep(stiffness, 5))
    assert np.allclose(z, ref, rtol=1e-13, atol=0), np.abs(z - ref).max()
    print(row("indentation sweep: 500 stiffnesses x 5 modes, float64", ours, base, 1.0))


if __name__ == "__main__":
    with recorded("roots"):
        main()
