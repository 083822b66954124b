"""Benchmark: Nanosurf frequency sweeps in the easyScan 2 layout, fitted by ``pfmdyn discrepancy``.

Each case is a silicon lever drawn by its geometry (``tests/test_nid_sweep.py``: L 100-500 um,
width L/10, k 0.05-50 N/m) swept in air around its first resonance, the sweep a base-driven damped
oscillator's amplitude (Q 5-500, below the air's), quantised to 16 bits with noise.  Passing: exit
0, the fitted amplitude peak within max(2e-4, 0.05/Q) of the oscillator's, Q within 10 %, gap below 2.

Run ``python benchmarks/nid_sweeps.py [CASES]``; results in ``benchmarks/results/nid_sweeps.md``.
"""
from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np
from recording import recorded, tally

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_nid_sweep import oscillator_sweep, silicon_lever, write_sweep_nid  # noqa: E402

from pfmdyn import cli  # noqa: E402


def main(cases: int = 100) -> None:
    passed, failures = 0, []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(cases):
            rng = np.random.default_rng(1000 + seed)
            k, length, width, f0, thickness = silicon_lever(rng)
            q = rng.uniform(5, min(500.0, 500 * thickness / width))
            f, a = oscillator_sweep(f0, q, rng)
            path = write_sweep_nid(Path(tmp) / f"s{seed}.nid", f, a, f0, environment="Air")
            out = Path(tmp) / "fit.json"
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
                code = cli.main(["discrepancy", str(path), "--spring-constant", f"{k:.6g}", "--length",
                                 f"{length:.6g}", "--width", f"{width:.6g}", "--json", str(out)])
            if code:
                failures.append(f"seed {1000 + seed}: exit {code}: {err.getvalue().strip()}")
                continue
            doc = json.loads(out.read_text())
            fit = {"peak_hz": doc["results"]["amplitude_peak"]["value"],
                   "quality_factor": doc["results"]["free_quality_factor"]["value"], "gap": doc["fit"]["gap"]["value"]}
            peak = f0 / np.sqrt(1 - 0.5 / q**2)
            ok = (abs(fit["peak_hz"] / peak - 1) < max(2e-4, 0.05 / q) and abs(fit["quality_factor"] / q - 1) < 0.1
                  and fit["gap"] < 2)
            passed += ok
            if not ok:
                failures.append(f"seed {1000 + seed}: k {k:.3g} N/m, L {length:.3g} m, Q {q:.3g}: peak "
                                f"{fit['peak_hz'] / peak - 1:+.2e}, Q {fit['quality_factor']:.3g}, gap {fit['gap']:.3g}")
    tally(passed, cases, failures)


if __name__ == "__main__":
    with recorded("nid_sweeps"):
        main(int(sys.argv[1]) if len(sys.argv) > 1 else 100)
