"""Benchmark: a contact-frequency map to k1 (pfmdyn.analysis.stiffness), and recovery sweeps.

Run ``python benchmarks/stiffness.py``; the results go to ``benchmarks/stiffness.json``.

1. Speed: a 1024 x 1024 map of contact frequencies (mode 1, k1/k from 1 to 1e4, 1 % of the
   pixels outside the model's range) converted to k1 with uncertainties; target <= 2 s.  The
   baseline, in the same run, is what one writes without the closed form: a per-pixel
   ``scipy.optimize.brentq`` on the same generated characteristic function between the
   certified limits, timed on 2 000 pixels and scaled to the map.
2. Accuracy sweep (quoted as a pass rate): 300 levers over the real ranges (k 0.05-50 N/m,
   f1 10-500 kHz, k1/k 1-1e4, modes 1-3, k2 ratio 0-2), contact frequencies from the
   certified roots; pass = k1 within 1e-9 relative.
3. Whole-lever sweep (``pfmdyn stiffness`` on set-back, heavy, tilted tips): levers over the
   real ranges (k 0.05-50 N/m, L 100-500 um, k1/k 1-1e4, tip at 0.7-1 L, tip mass ratio
   0-0.5, tilt 0-15 deg; k2 = 0 or a stated k2/k1 of 0.3-1), contact resonances from the
   independent exact beam of ``tests/exact_beam.py``.  Two modes with ``--tip-position fit``:
   pass = the truth is the unique solution, k1 within 1e-4 relative and the tip position
   within 1e-4; the share of levers whose two modes admit a second (k1, tip position) in the
   searched box is counted apart, and for those a third contact mode is added (pass = the
   truth is then the unique solution, within 1e-4).  One mode at the stated tip position (k2
   by the stated ratio): pass = k1 within 1e-6.

Results: ``benchmarks/results/stiffness.md``, written by each completed run.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from pfmdyn.analysis.stiffness import branch_proof, contact_stiffness
from pfmdyn.analysis.stiffness_report import analyse
from pfmdyn.cantilever import Cantilever, Contact
from pfmdyn.errors import UserError
from pfmdyn.generated.characteristic import BETA1_FREE, elastic
from pfmdyn.roots.core import family_roots
from recording import recorded


def _map(n: int, f1: float, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    proof = branch_proof(1)
    z = rng.uniform(proof.soft_z, proof.stiff_z, (n, n))
    fc = f1 * (z / BETA1_FREE) ** 2
    fc.flat[rng.choice(n * n, n * n // 100, replace=False)] *= 1.5      # impossible pixels
    return fc


def _brentq_k1(fc: np.ndarray, f1: float, k: float) -> np.ndarray:
    """Baseline: solve F(z(fc); a) = 0 for a per pixel, bracketing a in [1e-9, 1e9]."""
    out = np.full(fc.shape, np.nan)
    for i, f in enumerate(fc):
        z = BETA1_FREE * np.sqrt(f / f1)
        g = lambda a: elastic(z, np, k1_over_k=a, k2_ratio=0.0)    # noqa: E731
        try:
            out[i] = k * brentq(g, 1e-9, 1e9, xtol=1e-14, rtol=1e-14)
        except ValueError:
            pass
    return out


def speed() -> dict:
    f1, k, n = 70e3, 2.0, 1024
    fc = _map(n, f1)
    contact_stiffness(fc[:2, :2], f1, k, out_of_range="nan")          # warm the certified limits
    start = time.perf_counter()
    result = contact_stiffness(fc, f1, k, contact_uncertainty=50.0, out_of_range="nan")
    ours = time.perf_counter() - start
    sample = fc.ravel()[:2000]
    start = time.perf_counter()
    base_k1 = _brentq_k1(sample, f1, k)
    base = (time.perf_counter() - start) * fc.size / sample.size
    ok = np.isfinite(base_k1)
    agree = np.nanmax(np.abs(result.k1.ravel()[:2000][ok] / base_k1[ok] - 1))
    nan_share = np.isnan(result.k1).mean()
    verdict = "ok" if ours <= 2.0 else "OVER TARGET"
    print(f"1024 x 1024 map -> k1 and sigma: {ours:6.3f} s   brentq per pixel (scaled) {base:8.1f} s   "
          f"x{base / ours:7.1f}   target 2 s: {verdict}")
    print(f"  agreement with brentq: max relative difference {agree:.1e}; pixels out of range {nan_share:.2%}")
    return {"map_seconds": ours, "brentq_seconds_scaled": base, "target_seconds": 2.0,
            "max_relative_difference": float(agree), "out_of_range_share": float(nan_share)}


def sweep(n: int = 300, seed: int = 2026) -> dict:
    rng = np.random.default_rng(seed)
    passed, worst = 0, 0.0
    for _ in range(n):
        k = 10 ** rng.uniform(np.log10(0.05), np.log10(50))
        f1 = 10 ** rng.uniform(4, np.log10(5e5))
        ratio = f"{10 ** rng.uniform(0, 4):.8e}"
        b = f"{rng.uniform(0, 2):.4f}" if rng.random() < 0.5 else "0"
        mode = int(rng.integers(1, 4))
        z = float(family_roots("elastic", mode, 25, k1_over_k=ratio, k2_ratio=b).roots[mode - 1])
        fc = f1 * (z / BETA1_FREE) ** 2
        got = float(contact_stiffness(fc, f1, k, mode=mode, k2_ratio=float(b)).k1)
        err = abs(got / (float(ratio) * k) - 1)
        worst = max(worst, err)
        passed += err < 1e-9
    print(f"recovery sweep: {passed}/{n} levers within 1e-9 relative ({passed / n:.1%}); worst {worst:.1e}")
    return {"levers": n, "passed": int(passed), "tolerance": 1e-9, "worst": worst}


def model_sweep(n: int = 40, seed: int = 2027) -> dict:
    """Whole-lever recovery on the independent exact beam (item 3 of the module)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from exact_beam import random_lever

    rng = np.random.default_rng(seed)
    fit = {"levers": n, "passed": 0, "second_solution_in_box": 0, "decided_by_a_third_mode": 0, "truth_missing": 0,
           "worst_k1": 0.0, "worst_tip_position": 0.0, "seconds": 0.0}
    one = {"levers": n, "passed": 0, "worst_k1": 0.0, "seconds": 0.0}
    for i in range(n):
        ratio = 0.0 if i % 2 else round(float(rng.uniform(0.3, 1.0)), 3)
        e = random_lever(rng, k2_over_k1=ratio)
        fc = e.contact_resonances(2)
        stated = dict(spring_constant=e.spring_constant, free_resonance=e.free_resonance, length=e.length,
                      tip_height=e.tip_height, tip_mass_ratio=e.tip_mass_ratio, tilt=e.tilt)
        contact = Contact(k2_over_k1=ratio) if ratio else Contact(k2=0.0)
        start = time.perf_counter()
        try:
            r = analyse(Cantilever(**stated), contact, fc, fit_tip_position=True)
        except UserError:
            r = None
        fit["seconds"] += time.perf_counter() - start
        truth = [s for s in r.solutions if abs(s.tip_position - e.tip_position) < 1e-3] if r else []
        if not truth:
            fit["truth_missing"] += 1
            continue
        err_k1, err_tip = abs(truth[0].k1 / e.k1 - 1), abs(truth[0].tip_position - e.tip_position)
        fit["worst_k1"] = max(fit["worst_k1"], err_k1)
        fit["worst_tip_position"] = max(fit["worst_tip_position"], err_tip)
        fit["second_solution_in_box"] += not r.unique
        fit["passed"] += r.unique and err_k1 < 1e-4 and err_tip < 1e-4
        if not r.unique:
            three = analyse(Cantilever(**stated), contact, e.contact_resonances(3), fit_tip_position=True)
            fit["decided_by_a_third_mode"] += bool(three.unique and abs(three.solution.k1 / e.k1 - 1) < 1e-4
                                                   and abs(three.solution.tip_position - e.tip_position) < 1e-4)
        start = time.perf_counter()
        single = analyse(Cantilever(**stated, tip_position=e.tip_position), contact, fc[:1])
        one["seconds"] += time.perf_counter() - start
        err = abs(single.solution.k1 / e.k1 - 1)
        one["worst_k1"] = max(one["worst_k1"], err)
        one["passed"] += err < 1e-6
    print(f"whole lever, two modes, --tip-position fit: {fit['passed']}/{n} unique and within 1e-4 "
          f"({fit['passed'] / n:.1%}); a second solution in the box for {fit['second_solution_in_box']} (a third mode "
          f"decides {fit['decided_by_a_third_mode']} of them), truth missed "
          f"for {fit['truth_missing']}; worst k1 {fit['worst_k1']:.1e}, tip position {fit['worst_tip_position']:.1e}; "
          f"{fit['seconds'] / n:.2f} s per lever")
    print(f"whole lever, one mode at the stated tip position: {one['passed']}/{n} within 1e-6 "
          f"({one['passed'] / n:.1%}); worst {one['worst_k1']:.1e}")
    return {"fit_tip_position": fit, "one_mode": one}


if __name__ == "__main__":
    with recorded("stiffness"):
        speed()
        sweep()
        model_sweep()
