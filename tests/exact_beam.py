"""Independent test data: resonances of a two-segment Euler-Bernoulli lever with a set-back, heavy,
tilted tip in contact, exact, in mpmath.

Nothing here uses ``derivations/`` or ``generated/``.  The beam is :mod:`segment_beam`'s (the textbook
``cos, sin, cosh, sinh`` basis on each side of the tip, the clamp, the free end, continuity at the tip
and the jumps of shear and moment from its springs and inertia): its determinant
(:func:`segment_beam.determinant_mp`) vanishes at the resonances.  This module turns a lever given as
an AFM user describes it (SI, a tilt, ``k1`` and ``k2``) into that beam's springs, from the energy
``k1 (w.n)**2 / 2 + k2 (w.t)**2 / 2`` of the tip apex, ``w = u e_y + H u' e_x``, on a lever whose free
end is tilted by ``tilt`` towards the sample::

    kvv = k1 c**2 + k2 s**2,   kll = k1 s**2 + k2 c**2,   kvl = -(k1 - k2) s c   (c, s of the tilt)

and finds the roots by sign changes on a grid in ``beta``, refined to 28 digits;
``f_n = f1 (beta_n / beta_1)**2`` with ``beta_1`` the free root of the same lever (its tip has mass).
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import mpmath as mp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from segment_beam import determinant_mp  # noqa: E402

mp.mp.dps = 30


@dataclass(frozen=True)
class ExactLever:
    """A lever with a set-back, heavy, tilted tip in contact (SI; tilt in degrees, free end nearer the sample > 0)."""

    spring_constant: float
    free_resonance: float
    length: float
    tip_height: float
    k1: float = 0.0
    k2: float = 0.0
    tip_position: float = 1.0
    tip_mass_ratio: float = 0.0
    tip_gyration_radius: float = 0.0
    tilt: float = 0.0

    def _springs(self, contact: bool):
        if not contact:
            return mp.mpf(0), mp.mpf(0), mp.mpf(0)
        t = mp.radians(mp.mpf(self.tilt))
        c, s = mp.cos(t), mp.sin(t)
        k1, k2 = mp.mpf(self.k1), mp.mpf(self.k2)
        return k1 * c**2 + k2 * s**2, k1 * s**2 + k2 * c**2, -(k1 - k2) * s * c

    def determinant(self, beta, contact: bool = True):
        """The determinant of the beam's boundary and interface conditions at ``beta``."""
        kvv, kll, kvl = self._springs(contact)
        return determinant_mp(beta, dps=30, k=self.spring_constant, L=self.length, H=self.tip_height, kvv=kvv,
                              kll=kll, kvl=kvl, mu=self.tip_mass_ratio, gamma=self.tip_position,
                              rho_g=self.tip_gyration_radius / self.length)

    def roots(self, count: int, contact: bool = True, step: float = 0.05) -> list:
        """The first ``count`` roots in ``beta`` (mpf, 30 digits)."""
        f = lambda x: self.determinant(x, contact)     # noqa: E731
        out, x, fx = [], mp.mpf("0.3"), f(mp.mpf("0.3"))
        while len(out) < count:
            y = x + step
            fy = f(y)
            if fx == 0 or fx * fy < 0:
                # the determinant carries the beam's units: the bracket's width, not |f|, decides
                out.append(mp.findroot(f, (x, y), solver="anderson", tol=mp.mpf(10) ** -28, verify=False))
            x, fx = y, fy
            if x > 60:
                raise RuntimeError("roots not found below beta = 60")
        return out

    def contact_resonances(self, count: int = 2) -> list[float]:
        """The first ``count`` contact resonances (Hz) for the measured free resonance ``free_resonance``."""
        b1 = self.roots(1, contact=False)[0]
        return [float(self.free_resonance * (b / b1) ** 2) for b in self.roots(count)]


def random_lever(rng, *, k2_over_k1: float = 0.0) -> ExactLever:
    """A lever over the real ranges: k 0.05-50 N/m, L 100-500 um, H 3-20 um, f1 10-500 kHz,
    k1/k 1-1e4 (log-uniform), tip at 0.7-1 L, tip mass ratio 0-0.5, tilt 0-15 deg."""
    k = 10 ** rng.uniform(math.log10(0.05), math.log10(50))
    k1 = k * 10 ** rng.uniform(0, 4)
    return ExactLever(spring_constant=k, free_resonance=10 ** rng.uniform(4, math.log10(5e5)),
                      length=rng.uniform(100e-6, 500e-6), tip_height=rng.uniform(3e-6, 20e-6), k1=k1,
                      k2=k2_over_k1 * k1, tip_position=rng.uniform(0.7, 1.0),
                      tip_mass_ratio=rng.uniform(0.0, 0.5), tilt=rng.uniform(0.0, 15.0))
