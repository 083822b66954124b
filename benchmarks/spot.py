"""Blind spots of ``pfmdyn.analysis.spot`` against the independent two-segment beam, over real ranges.

Random levers (k 0.05-50 N/m, L 100-500 um, H 5-20 um, k1/k 8.5-1e4, k2/k1 0-1.2, tip at
0.85-1 L, tip mass 0-0.3, tilt -15-15 deg) at a random fraction (0.01-0.95) of the first
contact resonance.  The reference (``tests/segment_beam.py``: NumPy linear solve of the exact
segments, no ``derivations/`` or ``generated/``) is bracketed on 400 points and refined by
``brentq``; a certified list must have the same count and agree within 5e-5 L (the issue's
target).  Also reports the time per certified list.  Results go to ``results/spot.md``.
"""
from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from recording import recorded  # noqa: E402
from segment_beam import spot_response  # noqa: E402

from pfmdyn.analysis.spot import blind_spots, parameters  # noqa: E402
from pfmdyn.cantilever import Cantilever, Contact  # noqa: E402
from pfmdyn import composed  # noqa: E402

N_LEVERS = 200
TOLERANCE = 5e-5


def _first_contact_beta(p) -> float:
    """First zero of the composed characteristic above 0.3 (on a grid; a bound only)."""
    grid = np.linspace(0.31, 12.0, 2000)
    values = composed.characteristic(grid, composed.Parameters(**p))
    i = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0]
    return float(grid[i])


def _reference(p, beta) -> list[float]:
    def slope(s):
        return spot_response(beta, s, **p, q0=1.0)[0].real
    grid = np.linspace(0.005, 1.0, 400)
    values = [slope(s) for s in grid]
    return [brentq(slope, a, b, xtol=1e-13) for a, b, fa, fb in zip(grid, grid[1:], values, values[1:]) if fa * fb < 0]


def main() -> None:
    rng = np.random.default_rng(2106)
    worst, failures, uncertified, elapsed, counts = 0.0, 0, 0, [], {}
    for _ in range(N_LEVERS):
        k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
        lever = Cantilever(k, 5e4, rng.uniform(100e-6, 500e-6), tip_height=rng.uniform(5e-6, 20e-6),
                           tip_position=float(rng.choice([1.0, rng.uniform(0.85, 1.0)])),
                           tip_mass_ratio=rng.uniform(0, 0.3), tilt=rng.uniform(-15, 15))
        k1 = k * 10 ** rng.uniform(math.log10(8.5), 4)
        contact = Contact(k1=k1, k2=k1 * rng.uniform(0, 1.2))
        p = parameters(lever, contact)
        beta = rng.uniform(0.01, 0.95) * _first_contact_beta(p)
        start = time.perf_counter()
        found = blind_spots(lever, contact, beta)
        elapsed.append(time.perf_counter() - start)
        if not found.certified:
            uncertified += 1
            print(f"not certified: k={k:.3g} k1/k={k1 / k:.3g} beta={beta:.3g}: {found.reason}")
            continue
        expected = _reference(p, beta)
        counts[len(expected)] = counts.get(len(expected), 0) + 1
        if len(expected) != len(found.positions):
            failures += 1
            print(f"count differs: k={k:.3g} k1/k={k1 / k:.3g} beta={beta:.3g}: {found.positions} vs {expected}")
            continue
        if expected:
            err = max(abs(a - b) for a, b in zip(found.positions, expected))
            worst = max(worst, err)
            failures += err > TOLERANCE
    print(f"{N_LEVERS} levers below the first contact resonance: {failures} outside {TOLERANCE:g} L or "
          f"with another count, {uncertified} not certified; levers by number of blind spots {dict(sorted(counts.items()))}")
    print(f"largest difference to the reference: {worst:.2e} L (target <= {TOLERANCE:g} L)")
    print(f"time per certified list: median {np.median(elapsed) * 1e3:.1f} ms, max {max(elapsed) * 1e3:.1f} ms")


if __name__ == "__main__":
    with recorded("spot"):
        main()
