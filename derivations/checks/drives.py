"""Checks of the drives beyond the paper's (ids ``drives.*``): the base drive.

A dither piezo moves the clamp (:data:`derivations.pieces.BASE_DRIVE`).  In the frame moving with
the base the same lever is clamped at rest and driven by the inertia of its own mass (a uniform
load), of the tip mass (a force at the tip) and by the sample seen moving the other way (the
surface displacement ``d1 = -y0``).  Both routes are the pieces' algebra, so the claim is proven
on them: the engines then need no second model for a base-driven lever.
"""
from __future__ import annotations

import sympy as sp

from ..beam import beta, k, L
from ..evidence import Evidence, say
from ..pieces import BASE_DRIVE, CLAMPED, load_constant, point_jump, y0
from ..tip_mass import mu
from .core import ERRATUM, HOLDS, claim


@claim("drives.base.moving_frame", "II, Eqs. 2-3 (beyond the paper)",
       "a lever driven at its base by y0 is, relative to the base, the lever at rest loaded by its inertia: "
       "q0 = k beta^4 y0 / (3 L), f0 = mu k beta^4 y0 / 3 at the tip and the surface displaced by -y0",
       chapter="calibrating")
def _base_moving_frame():
    J, G = point_jump()
    q_equivalent = k * beta**4 * y0 / (3 * L)
    f_equivalent = mu * k * beta**4 * y0 / 3
    # the tip's conditions act on the absolute state [w + y0, z1]: its y0 part must be the
    # moving frame's drives (surface -y0, force f_equivalent) through the drives' columns
    tip = sp.simplify(J[:, 0] * y0 - (G[:, 0] * (-y0) + G[:, 2] * f_equivalent))
    # the uniform load's particular solution cancels the base's rigid motion along the segments
    segment = sp.simplify(load_constant() * q_equivalent + y0)
    # and the clamp sets the absolute deflection to y0, the moving frame's to 0
    clamp = set(BASE_DRIVE) <= set(CLAMPED) and BASE_DRIVE[0] == y0
    ok = tip.is_zero_matrix is True and segment == 0 and clamp
    return Evidence(HOLDS if ok else ERRATUM, say(
        "with the absolute deflection u = w + y0, the tip point's jump J [u, z1] exceeds J [w, z1] by J[:, 0] y0, "
        "and J[:, 0] y0 - G [-y0, 0, mu k beta^4 y0 / 3] = ", sp.Tuple(*tip), "; the segment's particular solution "
        "per unit load times q0 = k beta^4 y0 / (3 L) plus y0 is ", segment,
        "; the clamp fixes u(0) = y0, that is w(0) = 0: the two drives are one"))
