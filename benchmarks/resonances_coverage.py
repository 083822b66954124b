"""How often ``pfmdyn resonances``'s stated uncertainty of the first contact resonance covers the truth,
with the tip height and the k2 policy left to pfmdyn, as default flags leave them.

Each case is a lever over the real ranges (``tests/exact_beam.random_lever``: k 0.05-50 N/m, L 100-500
um, k1/k 1-1e4, tip set back, heavy and tilted) whose tip height is a PFM probe's, drawn uniform in the
datasheets' 10-17 um, in contact with a sample of Poisson's ratio drawn in 0.2-0.4 (k2 the Mindlin ratio
of it).  Its first contact resonance comes from the independent exact beam (mpmath,
``tests/segment_beam.py``).  The command is given the lever and the true k1, not the tip height nor k2:
it assumes its default tip height and ties k2 to k1 (Mindlin at 0.3), and states how far the resonance
moves over both.  With ``--k1-error E`` the command is given k1 off by a normal relative error of size E
and ``--k1-uncertainty`` saying so (results: ``resonances_coverage_k1_error.md``).  A case is covered when
the stated 2-sigma interval holds the true resonance; the uncertainty should cover at least 90 % of the
cases.

    python benchmarks/resonances_coverage.py [--cases 40] [--k1-error 0.1]

Results: ``benchmarks/results/resonances_coverage.md``.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from exact_beam import random_lever  # noqa: E402
from recording import coverage, recorded  # noqa: E402
from stiffness_coverage import mindlin  # noqa: E402

from pfmdyn import cli  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=40)
    parser.add_argument("--k1-error", type=float, default=0.0,
                        help="give k1 off by a normal relative error of this size, with --k1-uncertainty saying so")
    args = parser.parse_args()
    rng, errors = np.random.default_rng(23), np.random.default_rng(24)
    covered, failures, z = 0, [], []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "r.json"
        for case in range(args.cases):
            nu = rng.uniform(0.2, 0.4)
            truth = random_lever(rng, k2_over_k1=mindlin(nu))
            truth = replace(truth, tip_height=rng.uniform(10e-6, 17e-6))
            want = truth.contact_resonances(1)[0]
            argv = ["resonances", "--spring-constant", repr(truth.spring_constant), "--free-resonance",
                    repr(truth.free_resonance), "--length", repr(truth.length), "--tip-position",
                    repr(truth.tip_position), "--tip-mass-ratio", repr(truth.tip_mass_ratio), "--tilt",
                    repr(truth.tilt), "--modes", "1", "--quiet", "--json", str(out)]
            k1 = truth.k1 * (1 + args.k1_error * errors.standard_normal())
            argv += ["--k1", repr(k1)] + (["--k1-uncertainty", repr(args.k1_error * k1)] if args.k1_error else [])
            if cli.main(argv) != 0:
                failures.append(f"case {case}: the command failed")
                continue
            got = json.loads(out.read_text())["results"]["contact"]["resonance"]
            value, stderr = got["value"][0], got["stderr"][0]      # mode 1 of the list of modes
            z.append((value - want) / stderr)
            if abs(z[-1]) <= 2:
                covered += 1
            else:
                failures.append(f"case {case}: {value:.6g} +- {stderr:.2g} Hz, truth {want:.6g} "
                                f"(k1/k {truth.k1 / truth.spring_constant:.3g}, nu {nu:.2f}, "
                                f"H {truth.tip_height * 1e6:.1f} um, tilt {truth.tilt:.1f} deg)")
    coverage(covered, args.cases, failures, z, "first contact resonance")


if __name__ == "__main__":
    with recorded("resonances_coverage", variant="k1_error" if "--k1-error" in sys.argv else ""):
        main()
