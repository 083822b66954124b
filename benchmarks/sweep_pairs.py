"""Benchmark: before/after drive-sweep pairs explained by :func:`pfmdyn.discrepancy.reference.compare_sweeps`.

The pairs come from the independent beam of ``tests/test_sweeps_fit.py`` (base-driven, Sader's load,
air and water alternately, k 0.05-50 N/m, L 50-500 um, widths 20-60 um, Q 2-1000), written as
Cytomass files with rows in random order and fresh noise in each sweep:

* mass pairs: a point mass of 0.2-5 % of the lever's at x/L 0.5-1, its position given; passing:
  ``added_mass`` named and the mass within 3 %; also counted, the masses within two of their standard
  errors (a mass whose shift the noise hides is not a failure to name it: its error says so);
* null pairs: the same lever measured twice; passing: ``nothing`` named.

Run ``python benchmarks/sweep_pairs.py [CASES]``; results in ``benchmarks/results/sweep_pairs.md``.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
from recording import recorded, tally

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_sweeps_fit import lever_case, sweep_of, write_sweep  # noqa: E402

from pfmdyn.discrepancy.reference import compare_sweeps  # noqa: E402
from pfmdyn.discrepancy.sweep import fit_sweep  # noqa: E402
from pfmdyn.io.sweeps import read_sweep_table  # noqa: E402
from pfmdyn.medium import mass_per_length  # noqa: E402


def _pair(tmp: Path, seed: int, mass: dict | None):
    rng, case = lever_case(seed)
    f, y0 = sweep_of(rng, case)
    before = fit_sweep(read_sweep_table(write_sweep(tmp / "b.txt", f, y0, rng)), case["k"], case["L"],
                       case["medium"], width=case["w"])
    rng2, _ = lever_case(seed)          # the same gain and background, fresh noise below
    f1, y1 = sweep_of(rng2, case, **(mass or {}))
    y1 = y1 + 1e-3 * (rng.standard_normal(len(y1)) + 1j * rng.standard_normal(len(y1))) / np.sqrt(2)
    out = compare_sweeps(read_sweep_table(write_sweep(tmp / "a.txt", f1, y1, rng)), before,
                         mass["x_m"] if mass else None)
    return case, out


def main(cases: int = 40) -> None:
    rows = {"mass": [0, []], "null": [0, []]}
    consistent = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(cases):
            seed = 5000 + i
            draw = np.random.default_rng(seed + 77)
            mass = dict(mass_ratio=10 ** draw.uniform(np.log10(0.002), np.log10(0.05)), x_m=draw.uniform(0.5, 1.0))
            case, out = _pair(Path(tmp), seed, mass)
            truth = mass["mass_ratio"] * mass_per_length(case["k"], case["L"], case["f_vac"]) * case["L"]
            found = out["parameters"]["added_mass"]
            error = found["value"] / truth - 1
            consistent += abs(found["value"] - truth) < 2 * found["stderr"]
            ok = out["effect"] == "added_mass" and abs(error) < 0.03
            rows["mass"][0] += ok
            if not ok:
                rows["mass"][1].append(f"seed {seed} ({case['medium'].name}, k {case['k']:.3g}, ratio "
                                       f"{mass['mass_ratio']:.3g} at {mass['x_m']:.2f}): {out['effect']}, mass {error:+.1%}"
                                       f" +- {found['stderr'] / truth:.1%}")
            case, out = _pair(Path(tmp), seed, None)
            ok = out["effect"] == "nothing"
            rows["null"][0] += ok
            if not ok:
                rows["null"][1].append(f"seed {seed} ({case['medium'].name}): named {out['effect']}")
    print(f"masses within two standard errors of the truth: {consistent} of {cases}")
    for name, (passed, failures) in rows.items():
        tally(passed, cases, failures, f"{name} pairs: ")


if __name__ == "__main__":
    with recorded("sweep_pairs"):
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 40)
