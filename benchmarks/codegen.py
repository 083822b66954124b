"""Benchmark of the generated transfer functions (a script, not a test).

Prints, in one run:

1. the time for all four elastic-contact transfer coefficients at 1e6 values of ``beta``,
   generated code vs ``sympy.lambdify(expr, "numpy")`` of the same four expressions, and the
   generated code of a baseline commit (``--baseline REV``, default 478d53d: read with ``git show``),
   the three alternating, best of 3 (target: generated >= 3x faster than lambdify);
2. the time of a 2000 frequency x 2000 bias response map (target < 50 ms).  The bias
   enters linearly (``d1 = d33 V``, first-harmonic force ``f0 = c_f V``, load
   ``q0 = c_q V``), so transfers are computed once per frequency and the map is an outer
   product.

Run: ``python benchmarks/codegen.py [--baseline REV]``.

Results: ``benchmarks/results/codegen.md``, written by each completed run.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import time
import types
import warnings
from pathlib import Path

import numpy as np
from recording import recorded

ROOT = Path(__file__).resolve().parent.parent
BASELINE = "478d53d"


def _module_at(rev: str, path: str) -> types.ModuleType:
    """The generated module ``path`` as it was at commit ``rev``."""
    source = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout
    module = types.ModuleType(f"baseline_{Path(path).stem}")
    exec(compile(source, f"{rev}:{path}", "exec"), module.__dict__)
    return module


def best_of(fn, repeat=5) -> float:
    """Smallest wall time of ``repeat`` calls, seconds."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    import sympy as sp

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default=BASELINE, help="commit of the generated code to compare with")
    rev = parser.parse_args().baseline
    baseline = _module_at(rev, "generated/elastic_contact.py")

    import pfmdyn
    from pfmdyn.derivations import elastic_contact
    from pfmdyn.derivations.beam import H, L, beta, d1, d2, f0, k, k1, k2, q0
    from pfmdyn.generated import elastic_contact as generated

    params = dict(k=2.0, k1=30.0, k2=500.0, H=8e-6, L=1.5e-4)
    # Up to beta = 700 so that the naive code does not overflow and the comparison is fair.
    betas = np.logspace(-1, np.log10(700.0), 1_000_000)
    t = elastic_contact.transfer()
    exprs = [t[d] for d in (d1, d2, f0, q0)]
    naive = sp.lambdify((beta, k, k1, k2, H, L), exprs, "numpy")
    args = tuple(params[s] for s in ("k", "k1", "k2", "H", "L"))

    runs = {"generated": lambda: generated.slope(betas, *args), f"generated at {rev}": lambda: baseline.slope(betas, *args),
            "sympy.lambdify": lambda: naive(betas, *args)}
    times = dict.fromkeys(runs, float("inf"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(3):
            for name, run in runs.items():
                times[name] = min(times[name], best_of(run, repeat=1))
    t_gen, t_base, t_naive = times.values()
    print(f"elastic contact, 4 transfer coefficients, {betas.size:.0e} beta values "
          f"(load {os.getloadavg()[0]:.2f}):")
    for name, t in times.items():
        print(f"  {name:22s} {t * 1e3:8.1f} ms  ({t_naive / t:.2f}x lambdify)")
    print(f"  speed-up over lambdify {t_naive / t_gen:8.2f} x  (target >= 3: {'met' if t_naive >= 3 * t_gen else 'MISSED'}); "
          f"over the generated code at {rev}: {t_base / t_gen:.2f} x")

    cantilever = pfmdyn.Cantilever(spring_constant=2.0, free_resonance=7e4, length=1.5e-4,
                                   quality_factor=150.0)
    freqs = np.linspace(1e4, 2e6, 2000)
    bias = np.linspace(-10.0, 10.0, 2000)
    d33, c_f, c_q = 50e-12, 2e-9, 1e-5       # m/V, N/V, N/(m V)

    def response_map():
        r = cantilever.elastic_response(freqs, k1=30.0, k2=500.0, H=8e-6)
        per_volt = d33 * r.vertical + c_f * r.local_force + c_q * r.distributed_load
        return np.multiply.outer(per_volt, bias)

    t_map = best_of(response_map)
    shape = response_map().shape
    print(f"response map {shape[0]} frequencies x {shape[1]} bias values: "
          f"{t_map * 1e3:.1f} ms  (target < 50 ms)")


if __name__ == "__main__":
    with recorded("codegen"):
        main()
