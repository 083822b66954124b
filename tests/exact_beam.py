"""Independent test data: resonances of a two-segment Euler-Bernoulli lever, exact, in mpmath.

Nothing here uses ``derivations/`` or ``generated/``.  The lever (clamped at 0, free at L) is
split at the tip, ``x = gamma L``; on each segment the deflection is the textbook
``A cos(beta s) + B sin(beta s) + C cosh(beta s) + D sinh(beta s)`` (``s`` the position from the
segment's start over L), eight constants in all.  Eight conditions: clamp (2), free end (2),
continuity of deflection and slope at the tip (2), and the jumps of shear and moment there,
from the variation of the energy of the tip's springs and inertia::

    shear  : u'''(a-) - u'''(a+) = 3 (kvv u + kvl h u') / k - mu beta**4 u
    moment : u''(a-)  - u''(a+)  = -3 h (kvl u + kll h u') / k + mu beta**4 (r_g / L)**2 u'

(``h = H / L``; derivatives in ``s``; ``EI / L**3 = k / 3``; a tip of mass ``mu rho S L`` and
radius of gyration ``r_g``).  The contact springs come from the energy
``k1 (w.n)**2 / 2 + k2 (w.t)**2 / 2`` of the tip apex, ``w = u e_y + H u' e_x``, on a lever
whose free end is tilted by ``tilt`` towards the sample::

    kvv = k1 c**2 + k2 s**2,   kll = k1 s**2 + k2 c**2,   kvl = -(k1 - k2) s c   (c, s of the tilt)

The resonances are the zeros of the 8 x 8 determinant in ``beta``, found by sign changes on a
grid and refined by bisection at 30 digits; ``f_n = f1 (beta_n / beta_1)**2`` with ``beta_1``
the free root of the same lever (its tip has mass).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import mpmath as mp

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
        """The 8 x 8 determinant of the boundary and interface conditions at ``beta``."""
        b = mp.mpf(beta)
        g = mp.mpf(self.tip_position)
        k = mp.mpf(self.spring_constant)
        h = mp.mpf(self.tip_height) / mp.mpf(self.length)
        mu = mp.mpf(self.tip_mass_ratio)
        rg = mp.mpf(self.tip_gyration_radius) / mp.mpf(self.length)
        kvv, kll, kvl = self._springs(contact)

        def basis(s, n):
            """n-th derivative (in s) of cos, sin, cosh, sinh of beta s."""
            x = b * s
            c, sn, ch, sh = mp.cos(x), mp.sin(x), mp.cosh(x), mp.sinh(x)
            trig = [(c, sn), (-sn, c), (-c, -sn), (sn, -c)][n]
            hyp = [(ch, sh), (sh, ch)][n % 2]
            return [b**n * v for v in (*trig, *hyp)]

        zero = [mp.mpf(0)] * 4
        rows = [basis(0, 0) + zero, basis(0, 1) + zero,                          # clamp
                zero + basis(1 - g, 2), zero + basis(1 - g, 3)]                  # free end
        u_a, du_a = basis(g, 0), basis(g, 1)
        rows.append(u_a + [-v for v in basis(0, 0)])                            # deflection continuous
        rows.append(du_a + [-v for v in basis(0, 1)])                           # slope continuous
        shear = [t - 3 * (kvv * u + kvl * h * du) / k + mu * b**4 * u
                 for t, u, du in zip(basis(g, 3), u_a, du_a)]
        rows.append(shear + [-v for v in basis(0, 3)])
        moment = [m + 3 * h * (kvl * u + kll * h * du) / k - mu * b**4 * rg**2 * du
                  for m, u, du in zip(basis(g, 2), u_a, du_a)]
        rows.append(moment + [-v for v in basis(0, 2)])
        return mp.det(mp.matrix(rows))

    def roots(self, count: int, contact: bool = True, step: float = 0.05) -> list:
        """The first ``count`` roots in ``beta`` (mpf, 30 digits)."""
        f = lambda x: self.determinant(x, contact)     # noqa: E731
        out, x, fx = [], mp.mpf("0.3"), f(mp.mpf("0.3"))
        while len(out) < count:
            y = x + step
            fy = f(y)
            if fx == 0 or fx * fy < 0:
                out.append(mp.findroot(f, (x, y), solver="anderson", tol=mp.mpf(10) ** -28))
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
