"""Benchmark: a contact-frequency map to k1 (pfmdyn.analysis.stiffness), and a recovery sweep.

Run ``python benchmarks/stiffness.py``.

1. Speed: a 1024 x 1024 map of contact frequencies (mode 1, k1/k from 1 to 1e4, 1 % of the
   pixels outside the model's range) converted to k1 with uncertainties; target <= 2 s.  The
   baseline, in the same run, is what one writes without the closed form: a per-pixel
   ``scipy.optimize.brentq`` on the same generated characteristic function between the
   certified limits, timed on 2 000 pixels and scaled to the map.
2. Accuracy sweep (quoted as a pass rate): 300 levers over the real ranges (k 0.05-50 N/m,
   f1 10-500 kHz, k1/k 1-1e4, modes 1-3, k2 ratio 0-2), contact frequencies from the
   certified roots; pass = k1 within 1e-9 relative.

Results: ``benchmarks/results/stiffness.md``, written by each completed run.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.optimize import brentq

from pfmdyn.analysis.stiffness import branch_proof, contact_stiffness
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


def speed() -> None:
    f1, k, n = 70e3, 2.0, 1024
    fc = _map(n, f1)
    contact_stiffness(fc[:2, :2], f1, k, out_of_range="nan")          # warm the certified limits
    start = time.perf_counter()
    result = contact_stiffness(fc, f1, k, contact_uncertainty_hz=50.0, out_of_range="nan")
    ours = time.perf_counter() - start
    sample = fc.ravel()[:2000]
    start = time.perf_counter()
    base_k1 = _brentq_k1(sample, f1, k)
    base = (time.perf_counter() - start) * fc.size / sample.size
    ok = np.isfinite(base_k1)
    agree = np.nanmax(np.abs(result.k1_n_per_m.ravel()[:2000][ok] / base_k1[ok] - 1))
    nan_share = np.isnan(result.k1_n_per_m).mean()
    verdict = "ok" if ours <= 2.0 else "OVER TARGET"
    print(f"1024 x 1024 map -> k1 and sigma: {ours:6.3f} s   brentq per pixel (scaled) {base:8.1f} s   "
          f"x{base / ours:7.1f}   target 2 s: {verdict}")
    print(f"  agreement with brentq: max relative difference {agree:.1e}; pixels out of range {nan_share:.2%}")


def sweep(n: int = 300, seed: int = 2026) -> None:
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
        got = float(contact_stiffness(fc, f1, k, mode=mode, k2_ratio=float(b)).k1_n_per_m)
        err = abs(got / (float(ratio) * k) - 1)
        worst = max(worst, err)
        passed += err < 1e-9
    print(f"recovery sweep: {passed}/{n} levers within 1e-9 relative ({passed / n:.1%}); worst {worst:.1e}")


if __name__ == "__main__":
    with recorded("stiffness"):
        speed()
        sweep()
