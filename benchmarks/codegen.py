"""Benchmark of the generated transfer functions (a script, not a test).

Prints, in one run:

1. the time for all four elastic-contact transfer coefficients at 1e6 values of ``beta``,
   generated code vs ``sympy.lambdify(expr, "numpy")`` of the same four expressions
   (target: generated >= 2x faster);
2. the time of a 2000 frequency x 2000 bias response map (target < 50 ms).  The bias
   enters linearly (``d1 = d33 V``, first-harmonic force ``f0 = c_f V``, load
   ``q0 = c_q V``), so transfers are computed once per frequency and the map is an outer
   product.

Run: ``python benchmarks/codegen.py``.

Results: ``benchmarks/results/codegen.md``, written by each completed run.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
from recording import recorded


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

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t_naive = best_of(lambda: naive(betas, *args), repeat=3)
    t_gen = best_of(lambda: generated.slope(betas, *args), repeat=3)
    print(f"elastic contact, 4 transfer coefficients, {betas.size:.0e} beta values:")
    print(f"  generated          {t_gen * 1e3:8.1f} ms")
    print(f"  sympy.lambdify     {t_naive * 1e3:8.1f} ms")
    print(f"  speed-up           {t_naive / t_gen:8.2f} x  (target >= 2)")

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
