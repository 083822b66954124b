"""Benchmark: ``pfmdyn resonances`` (pfmdyn.analysis.resonances) over random probes against the
independent finite-element lever of tests/fe_beam.py, and the size of the tip's rotary inertia.

Run ``python benchmarks/resonances.py [N]`` (default 40 probes).  Each probe: k 0.05-50 N/m,
L 100-500 um, H 3-20 um, k1/k 1-1e4, k2 = 0.85 k1, tilt 0-15 deg (the FE builds the springs
from the explicit geometry), tip at 0.85-1 L, tip mass ratio 0-0.5, radius of gyration H/4 times
0.5-2; the first 5 free and 5 contact modes.  Targets: every list certified, every resonance
within 2e-5 of the FE (the FE with 100 elements is good to ~2e-7 on these modes), < 1 s per
probe.  Also reported: how far the rotary inertia J = m_tip (H/4)**2 moves contact mode 1 and
free mode 2 (at the same measured f1).

Results: ``benchmarks/results/resonances.md``, written by each completed run.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fe_beam import random_probe  # noqa: E402
from pfmdyn import Cantilever, Contact  # noqa: E402
from pfmdyn.analysis.resonances import resonances  # noqa: E402
from recording import recorded  # noqa: E402

MODES = 5
N_ELEMENTS = 100


def _probe(rng):
    fe, p = random_probe(rng, N_ELEMENTS, tilt_deg=(0.0, 15.0), mass_ratio=(0.0, 0.5))
    return Cantilever(**{n: v for n, v in p.items() if n not in ("k1", "k2")}), Contact(k1=p["k1"], k2_over_k1=0.85), fe


def main(count: int) -> None:
    rng = np.random.default_rng(2026)
    errors, times, failed = [], [], 0
    for _ in range(count):
        lever, contact, fe = _probe(rng)
        start = time.perf_counter()
        result = resonances(lever, contact, MODES)
        times.append(time.perf_counter() - start)
        if not result.certified:
            failed += 1
            continue
        errors.append(max(np.max(np.abs(np.array(result.free.hz) / fe.free_resonances(MODES) - 1)),
                          np.max(np.abs(np.array(result.in_contact.hz) / fe.contact_resonances(MODES) - 1))))
    print(f"probes: {count}, {MODES} free + {MODES} contact modes each")
    print(f"proofs failed: {failed} (target 0)")
    print(f"largest relative difference to the FE lever: {max(errors):.2e} (target <= 2e-5), "
          f"median {np.median(errors):.2e}")
    print(f"time per probe: median {np.median(times):.2f} s, max {max(times):.2f} s (target < 1 s)")

    # The rotary inertia of a massive tip, J = m_tip (H/4)**2, at the same measured f1.
    shifts = []
    for _ in range(count):
        lever, contact, _ = _probe(rng)
        lever = Cantilever(**{**lever.to_dict(), "tip_mass_ratio": rng.uniform(0.05, 0.5)})
        with_j = resonances(Cantilever(**{**lever.to_dict(), "tip_gyration_radius": lever.tip_height / 4}),
                            contact, 2)
        without = resonances(Cantilever(**{**lever.to_dict(), "tip_gyration_radius": 0.0}), contact, 2)
        shifts.append((with_j.in_contact.hz[0] / without.in_contact.hz[0] - 1,
                       with_j.free.hz[1] / without.free.hz[1] - 1))
    shifts = np.array(shifts)
    for name, column in (("contact mode 1", 0), ("free mode 2", 1)):
        print(f"rotary inertia J = m_tip (H/4)^2, tip mass ratio 0.05-0.5, {name}: median {np.median(shifts[:, column]):.2e}, "
              f"range {shifts[:, column].min():.2e} to {shifts[:, column].max():.2e}")


if __name__ == "__main__":
    with recorded("resonances"):
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
