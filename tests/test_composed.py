"""``pfmdyn.composed`` against an independent high-precision solution of the two-segment beam.

The reference is :func:`tests.segment_beam.spot_response_mp`: the textbook basis
``cos, sin, cosh, sinh`` on each segment, the clamp, tip and free-end rows of
``tests/segment_beam.py`` solved in mpmath with 60 significant digits kept (the working precision
is raised by the digits the basis loses: it checks itself 20 digits higher); nothing from
``derivations/`` or ``generated/``.  Random levers over the real ranges (k 0.05-50 N/m,
L 100-500 um, H 3-20 um, k1/k 1-1e4, k2/k1 0-1, tilt 0-15 deg, tip at 0.7-1 L, tip mass 0-0.5,
r_g/L 0-0.05), fixed seeds; ``beta`` from the quasi-static 1e-3 to 200, undamped and damped (complex
``beta``; with complex ``k``, contact springs and tip mass as the damping substitutions make them);
every drive ``d1, d2, f0, q0``; slope and deflection at spots before, at and beyond the tip.
Each value to 1e-9 relative.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from pfmdyn import composed

sys.path.insert(0, str(Path(__file__).parent))
import segment_beam  # noqa: E402
from segment_beam import spot_response_mp  # noqa: E402

DRIVES = segment_beam.DRIVES      # the tip's, the load, the base and a couple at the tip
BETAS = (1e-3, 1e-2, 0.1, 0.6, 1.9, 4.2, 9.0, 23.0, 57.0, 120.0, 200.0)
TOLERANCE = 1e-9


def _lever(rng, gamma=None):
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    k1 = k * 10 ** rng.uniform(0, 4)
    k2 = k1 * rng.uniform(0, 1)
    t = math.radians(rng.uniform(0, 15))
    c, s = math.cos(t), math.sin(t)
    return dict(k=k, L=rng.uniform(100e-6, 500e-6), H=rng.uniform(3e-6, 20e-6),
                kvv=k1 * c**2 + k2 * s**2, kll=k1 * s**2 + k2 * c**2, kvl=-(k1 - k2) * s * c,
                mu=rng.uniform(0, 0.5), gamma=rng.uniform(0.7, 1.0) if gamma is None else gamma,
                rho_g=rng.uniform(0, 0.05))


def _damped(p, sign):
    """Internal (Q 100), contact (loss 0.05) and viscous (tip mass) damping on a lever."""
    return {**p, "k": p["k"] * (1 + sign * 0.01j), "kvv": p["kvv"] * (1 + sign * 0.05j),
            "kll": p["kll"] * (1 + sign * 0.05j), "kvl": p["kvl"] * (1 + sign * 0.05j),
            "mu": p["mu"] * (1 + sign * 0.02j)}


def _spots(rng, gamma):
    before = sorted(rng.uniform(0.05, gamma, 3))
    beyond = sorted(rng.uniform(gamma, 1.0, 2)) if gamma < 1 else []
    return np.array([*before, gamma, *beyond, 1.0])


def _worst(p, beta, sigma):
    """Largest relative difference (and where) of composed's slope and deflection to the reference."""
    lever = composed.Parameters(**{n: p[n] for n in composed.PARAMETERS})
    slopes, deflections = composed.response(beta, lever, sigma, drives=DRIVES)
    reference = spot_response_mp(beta, sigma, **p)
    worst = (0.0, None)
    for i, (ref_slope, ref_deflection) in enumerate(reference):
        for j, drive in enumerate(DRIVES):
            for what, got, ref in (("slope", slopes[j][i], ref_slope[j]), ("deflection", deflections[j][i],
                                                                            ref_deflection[j])):
                ref = complex(ref)
                # a drive that does not reach the beam (d2 without kll, kvl) must give exactly 0
                err = abs(complex(got) - ref) / abs(ref) if ref else abs(complex(got))
                if not err <= worst[0]:
                    worst = (err, (what, drive, float(sigma[i]), beta))
    return worst


CASES = [(seed, None) for seed in range(6)] + [(100, 1.0), (101, 1.0)]


@pytest.mark.parametrize("seed,gamma", CASES)
@pytest.mark.parametrize("damping", ["undamped", "damped+", "damped-"])
def test_response_matches_high_precision_beam(seed, gamma, damping):
    rng = np.random.default_rng(seed)
    p = _lever(rng, gamma)
    sigma = _spots(rng, p["gamma"])
    for beta in BETAS:
        if damping == "undamped":
            args, b = p, beta
        else:
            sign = 1 if damping == "damped+" else -1
            args, b = _damped(p, sign), beta * (1 + sign * 0.01j)
        err, where = _worst(args, b, sigma)
        assert err <= TOLERANCE, (err, where, p)


@pytest.mark.parametrize("p", [
    dict(k=50.0, L=100e-6, H=3e-6, kvv=5e5, kll=4e5, kvl=-2e4, mu=0.5, gamma=0.7, rho_g=0.05),   # stiffest
    dict(k=0.05, L=500e-6, H=20e-6, kvv=0.05, kll=0.0, kvl=0.0, mu=0.0, gamma=0.99, rho_g=0.0),   # softest
    dict(k=2.0, L=2.2e-4, H=1e-5, kvv=0.0, kll=0.0, kvl=0.0, mu=0.1, gamma=0.9, rho_g=0.02),      # free
], ids=["stiff", "soft", "free"])
def test_response_at_the_ends_of_the_ranges(p):
    sigma = np.array([0.1, 0.5 * p["gamma"], p["gamma"], 0.5 * (1 + p["gamma"]), 1.0])
    for beta in BETAS:
        for b in (beta, beta * (1 + 0.01j)):
            err, where = _worst(p, b, sigma)
            assert err <= TOLERANCE, (err, where)


def test_the_reference_checks_itself():
    """The reference's precision: re-solved 20 digits higher, it agrees to its 55 digits."""
    p = _lever(np.random.default_rng(3))
    for beta in (1e-3, 2.0, 200.0 * (1 + 0.01j)):
        spot_response_mp(beta, [0.4, p["gamma"], 1.0], check=True, **p)

