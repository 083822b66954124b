"""How often ``pfmdyn spot``'s stated uncertainties cover the truth, with the tip height and the k2 policy left
to pfmdyn, as default flags leave them.

Each case is a lever over the real ranges (``tests/exact_beam.random_lever``: k 0.05-50 N/m, L 100-500 um,
k1/k 1-1e4, tip set back, heavy and tilted) whose tip height is a PFM probe's, drawn uniform in the
datasheets' 10-17 um, in contact with a sample of Poisson's ratio drawn in 0.2-0.4 (k2 the Mindlin ratio of
it), read at a laser spot drawn in 0.6-1 L and driven at a fraction 0.05-0.9 of its first contact resonance.
The truth comes from the independent beam (``tests/segment_beam.py``: the exact segments solved with NumPy;
the resonance and the free root from ``tests/exact_beam.py`` in mpmath), at the true tip height and k2:

* the blind spots, the zeros along the lever of the slope's response to the uniform load (bracketed on
  400 points, refined by ``brentq``);
* the contact sensitivity ``d1 / (L theta_d1(x_s))`` of the static lever;
* the calibration factor ``theta_d1(x_s, omega) / theta_d1(x_s, 0)`` and the paper's
  ``2 L theta_d1(x_s, omega) / 3``.

The command is given the lever and the true k1, not the tip height nor k2, and states how far each result
moves over both.  A result is covered when its stated 2-sigma interval holds the truth (a blind spot: the
same count of them, each covered); each should be covered in at least 90 % of the cases.  Where a blind spot
appears or goes within the assumed inputs' spread, the command calls the blind spots' uncertainty undetermined
(a note of the document): those cases are listed apart, neither covered nor missed.

    python benchmarks/spot_coverage.py [--cases 200]

Results: ``benchmarks/results/spot_coverage.md``.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from exact_beam import random_lever  # noqa: E402
from recording import coverage, recorded  # noqa: E402
from segment_beam import spot_response  # noqa: E402
from stiffness_coverage import mindlin  # noqa: E402

from pfmdyn import cli  # noqa: E402

RESULTS = ("blind_spot", "contact_sensitivity", "calibration_factor", "paper_calibration_factor")


def truth(lever, beta: float, spot: float) -> dict:
    """The results of the lever at ``beta`` read at ``spot`` (x_s/L), from the independent beam."""
    kvv, kll, kvl = (float(v) for v in lever._springs(True))
    p = {"k": lever.spring_constant, "L": lever.length, "H": lever.tip_height, "kvv": kvv, "kll": kll, "kvl": kvl,
         "mu": lever.tip_mass_ratio, "gamma": lever.tip_position}

    def slope(s, b, **drive):
        return spot_response(b, s, **p, **drive)[0].real

    grid = np.linspace(0.005, 1.0, 400)
    values = [slope(s, beta, q0=1.0) for s in grid]
    blind = [brentq(lambda s: slope(s, beta, q0=1.0), a, b, xtol=1e-13)
             for a, b, fa, fb in zip(grid, grid[1:], values, values[1:]) if fa * fb < 0]
    static, moving = slope(spot, 0.0, d1=1.0), slope(spot, beta, d1=1.0)
    return {"blind_spot": blind, "contact_sensitivity": 1.0 / (lever.length * static),
            "calibration_factor": moving / static, "paper_calibration_factor": 2 * lever.length / 3 * moving}


def stated(results: dict, name: str) -> tuple:
    """Value and standard error of one result of the command's JSON (real parts; lists for the blind spots)."""
    record = results[name]
    value = record["value"]
    return (value["real"] if isinstance(value, dict) else value), record["stderr"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=200)
    args = parser.parse_args()
    rng = np.random.default_rng(29)
    covered = {name: 0 for name in RESULTS}
    failures = {name: [] for name in RESULTS}
    z = {name: [] for name in RESULTS}
    undetermined = []      # blind spots whose spread the command calls undetermined (one appears or goes within it)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "s.json"
        for case in range(args.cases):
            nu = rng.uniform(0.2, 0.4)
            lever = replace(random_lever(rng, k2_over_k1=mindlin(nu)), tip_height=rng.uniform(10e-6, 17e-6))
            spot, share = rng.uniform(0.6, 1.0), rng.uniform(0.05, 0.9)
            b1 = float(lever.roots(1, contact=False)[0])
            resonance = lever.contact_resonances(1)[0]
            frequency = share * resonance
            want = truth(lever, b1 * math.sqrt(frequency / lever.free_resonance), spot)
            argv = ["spot", "--spring-constant", repr(lever.spring_constant), "--free-resonance",
                    repr(lever.free_resonance), "--length", repr(lever.length), "--tip-position",
                    repr(lever.tip_position), "--tip-mass-ratio", repr(lever.tip_mass_ratio), "--tilt",
                    repr(lever.tilt), "--k1", repr(lever.k1), "--spot-position", repr(spot), "--drive-frequency",
                    repr(frequency), "--quiet", "--json", str(out)]
            label = (f"case {case} (k1/k {lever.k1 / lever.spring_constant:.3g}, nu {nu:.2f}, "
                     f"H {lever.tip_height * 1e6:.1f} um, spot {spot:.2f} L, at {share:.2f} of the resonance)")
            if cli.main(argv) != 0:
                for name in RESULTS:
                    failures[name].append(f"{label}: the command failed")
                continue
            document = json.loads(out.read_text())
            results = document["results"]
            for name in RESULTS:
                value, stderr = stated(results, name)
                if name == "blind_spot":
                    if stderr is None:
                        note = next(n for n in document["notes"] if n.startswith("blind_spot:"))
                        undetermined.append(f"{label}: {value}, {note}; truth {want[name]}")
                        continue
                    if len(value) != len(want[name]):
                        failures[name].append(f"{label}: {value} +- {stderr}, truth {want[name]}")
                        continue
                    zs = [(v - w) / s if s > 0 else (0.0 if v == w else math.inf)
                          for v, w, s in zip(value, want[name], stderr)]
                else:
                    zs = [(value - want[name]) / stderr if stderr else (0.0 if value == want[name] else math.inf)]
                z[name] += zs
                if all(abs(x) <= 2 for x in zs):
                    covered[name] += 1
                else:
                    failures[name].append(f"{label}: {value} +- {stderr}, truth {want[name]}")
    print(f"blind spots' spread stated undetermined (not counted above as covered): {len(undetermined)}")
    for line in undetermined:
        print(f"- {line}")
    for name in RESULTS:
        coverage(covered[name], args.cases, failures[name], z[name], name)


if __name__ == "__main__":
    with recorded("spot_coverage"):
        main()
