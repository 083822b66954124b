"""How often ``pfmdyn discrepancy``'s stated uncertainties of a drive sweep's fitted parameters cover the truth.

Each case is a lever of ``tests/test_sweeps_fit.py`` (silicon of drawn k 0.05-50 N/m, L 50-500 um, width
20-60 um, air and water alternately, Q 2-1000 in the medium), its base-driven sweep from the independent
beam there (Sader's load, a drawn viscous damping, gain, background and complex noise), written as a
Cytomass file with the rows in random order and fitted with the lever's k, L and width given.  A
parameter is covered when its 2-sigma interval holds the truth: the first resonance in the medium
(the test's Sader relation, iterated) and the viscous damping beyond the fluid's; the uncertainty
should cover at least 90 % of the cases.

    python benchmarks/discrepancy_coverage.py [--cases 40]

Results: ``benchmarks/results/discrepancy_coverage.md``.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from recording import coverage, recorded  # noqa: E402
from test_sweeps_fit import in_medium, lever_case, sweep_of, write_sweep  # noqa: E402

from pfmdyn.discrepancy.sweep import fit_sweep  # noqa: E402
from pfmdyn.io.sweeps import read_sweep_table  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=40)
    args = parser.parse_args()
    names = ("free_resonance", "viscous_loss")
    covered = dict.fromkeys(names, 0)
    failures = {name: [] for name in names}
    z = {name: [] for name in names}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.cases):
            seed = 7000 + i
            rng, case = lever_case(seed)
            f, y = sweep_of(rng, case)
            fit = fit_sweep(read_sweep_table(write_sweep(Path(tmp) / "s.txt", f, y, rng)), case["k"], case["L"],
                            case["medium"], width=case["w"])
            truth = {"free_resonance": in_medium(case)[0], "viscous_loss": case["g"]}
            for name in names:
                p = fit["parameters"][name]
                z[name].append((p["value"] - truth[name]) / p["stderr"] if p["stderr"] else np.inf)
                if abs(z[name][-1]) <= 2:
                    covered[name] += 1
                else:
                    failures[name].append(f"seed {seed} ({case['medium'].name}, k {case['k']:.3g}, Q "
                                          f"{in_medium(case)[1]:.3g}): {p['value']:.6g} +- {p['stderr']:.2g}, truth "
                                          f"{truth[name]:.6g} ({z[name][-1]:+.1f} sigma)")
    for name in names:
        coverage(covered[name], args.cases, failures[name], z[name], name)


if __name__ == "__main__":
    with recorded("discrepancy_coverage"):
        main()
