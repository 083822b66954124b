"""Tilted cantilever: tip-surface springs along the surface axes, beam inclined by alpha.

Geometry.  The cantilever axis makes the angle ``alpha`` with the surface (typically
10-15 degrees); the tip stands perpendicular to the beam with height ``H``.  The contact
springs act along the surface normal (``k1``) and the surface tangent in the plane of the
beam (``k2``).  In beam axes (transverse ``v`` = the beam normal, longitudinal ``l`` = the
beam axis) the apex moves by ``(u0(L), H u0'(L))`` (Eq. 4a's lever arm; the beam is
axially rigid) and the surface by ``(d1, d2)``, both now *beam-frame* components.  The
stiffness tensor rotates as ``K = R diag(k1, k2) R^T``::

    kvv = k1 cos**2 alpha + k2 sin**2 alpha
    kll = k1 sin**2 alpha + k2 cos**2 alpha
    kvl = (k1 - k2) sin alpha cos alpha

and the spring forces on the apex are ``F = -K (w - d)``.  The transverse force enters the
shear condition, the longitudinal one bends the beam through the lever arm ``H``::

    EI u0''(L)  = H F_l = -H [kvl (u0(L) - d1) + kll (H u0'(L) - d2)]
    EI u0'''(L) = -f0 - F_v = -f0 + kvv (u0(L) - d1) + kvl (H u0'(L) - d2)

At ``alpha = 0`` (``kvv = k1``, ``kll = k2``, ``kvl = 0``) this is Eq. 4a,b exactly.

Sign of ``alpha``.  ``K = k1 n n^T + k2 t t^T`` with the surface normal ``n = (cos alpha,
sin alpha)`` and tangent ``t = (-sin alpha, cos alpha)`` in beam components ``(v, l)``
(that is what :func:`rotated` expands to).  ``v`` is the side of the lever facing away
from the sample (``u0 > 0`` lifts it), so ``n`` is the normal pointing away from the sample,
and ``n . e_l = sin alpha``: walking along the lever from the clamp to the free end one
moves *away* from the sample when ``alpha > 0``.  So ``alpha > 0`` puts the free end farther
from the sample than the clamp, and the usual mounting (tip end nearer the sample, tilt
10-15 degrees in the public convention) is ``alpha < 0``::

    alpha = -radians(tilt)          (tilt in degrees, free end nearer the sample > 0)

(:attr:`pfmdyn.Cantilever.alpha` is that conversion.)  A check with the physics: in the
usual mounting the lever points down towards the sample, so a slope ``u0' > 0`` swings the
apex (``H`` below the lever) forward and down by ``H u0' sin(tilt)``, compressing the
normal spring, which pushes the free end back up: ``F_v = -kvl H u0' > 0``, so ``kvl < 0``,
and ``kvl = (k1 - k2) sin alpha cos alpha`` is negative for ``k1 > k2`` only at ``alpha < 0``.  The
generated code takes ``kvv, kll, kvl`` (polynomial parameters); :func:`rotated` gives them
from ``k1, k2, alpha``.  ``f0`` is taken along the beam normal: its longitudinal part, a
``sin alpha`` fraction, is absorbed by the fitted drive amplitudes.
"""
from __future__ import annotations

import sympy as sp

from .beam import EI, H, TipProblem, TipSolution, d1, d2, f0, k1, k2, q0, solve_tip_problem

__all__ = ["alpha", "kvv", "kll", "kvl", "rotated", "tip_conditions", "problem", "solve",
           "DRIVES"]

alpha = sp.Symbol("alpha", real=True)
kvv, kll = sp.symbols("kvv kll", positive=True)
kvl = sp.Symbol("kvl", real=True)

DRIVES = (d1, d2, f0, q0)


def rotated() -> dict[sp.Symbol, sp.Expr]:
    """Beam-frame stiffnesses in terms of ``k1, k2, alpha`` (``K = R diag(k1, k2) R^T``).

    >>> r = rotated()
    >>> [sp.simplify(r[s].subs(alpha, 0)) for s in (kvv, kll, kvl)]
    [k1, k2, 0]
    >>> sp.simplify(r[kvv] + r[kll] - k1 - k2)   # the trace is invariant
    0
    """
    c, s = sp.cos(alpha), sp.sin(alpha)
    return {kvv: k1 * c**2 + k2 * s**2, kll: k1 * s**2 + k2 * c**2, kvl: (k1 - k2) * s * c}


def tip_conditions(U):
    """Moment and shear conditions with the rotated spring tensor; ``U = [u, u', u'', u''']`` at L.

    >>> [sp.expand(e) for e in tip_conditions([0, 0, 0, 0])]
    [-H*d1*kvl - H*d2*kll, d1*kvv + d2*kvl + f0]
    """
    force_v = -(kvv * (U[0] - d1) + kvl * (H * U[1] - d2))
    force_l = -(kvl * (U[0] - d1) + kll * (H * U[1] - d2))
    return [EI * U[2] - H * force_l, EI * U[3] - (-f0 - force_v)]


problem = TipProblem(
    "tilt", tip_conditions, (d1, d2, f0), load=True,
    description="elastic contact with the cantilever tilted: springs kvv, kll, kvl in beam axes",
)


def solve() -> TipSolution:
    """Slope and deflection per unit d1, d2, f0, q0 (beam-frame drives).

    >>> from .elastic_contact import reduces_to_elastic_contact
    >>> reduces_to_elastic_contact(solve(), {kvv: k1, kll: k2, kvl: 0}, d2)   # untilted
    True
    """
    return solve_tip_problem(problem)
