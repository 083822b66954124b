"""A value printed to the digits its standard uncertainty leaves: one rule for every report.

Two significant digits of the uncertainty fix the last digit of the value (six digits without one),
so a report never states more than the data carry (:func:`rounded`, :func:`plus_minus`).  A value that is
exact given its inputs (a resonance computed from a stated lever) keeps its digits: its spread over
assumed inputs is printed beside it, not cut into it.
"""
from __future__ import annotations

import math


def rounded(value: float, sigma: float) -> str:
    """``value`` to the second significant digit of its standard uncertainty ``sigma`` (six digits without one).

    >>> rounded(204.067, 23.0), rounded(300.0, 1.0), rounded(0.0012345, 2e-6), rounded(2.5e8, 1e6), rounded(3.14159, 0.0)
    ('204', '300.0', '0.0012345', '2.500e+08', '3.14159')
    """
    if not (sigma > 0 and math.isfinite(sigma)) or value == 0:
        return f"{value:.6g}"
    place = math.floor(math.log10(sigma)) - 1
    if 1e-4 <= abs(value) < 1e7:
        return f"{round(value, -place):.{max(0, -place)}f}"
    return f"{value:.{max(1, math.floor(math.log10(abs(value))) - place)}e}"


def plus_minus(value: float, sigma: float | None) -> str:
    """``value +- sigma`` to the digits ``sigma`` leaves; ``+- undetermined`` when it is not a number,
    the value alone (six digits) when it is zero or None (exact, or nothing moved it).

    >>> plus_minus(368990.0, 1.2e4), plus_minus(72969.0, 0.0), plus_minus(1.5, float("nan"))
    ('369000 +- 1.2e+04', '72969', '1.5 +- undetermined')
    """
    if sigma is None or sigma == 0:
        return f"{value:.6g}"
    if not math.isfinite(sigma):
        return f"{value:.6g} +- undetermined"
    return f"{rounded(value, sigma)} +- {sigma:.2g}"
