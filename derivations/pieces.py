"""The lever's pieces, each derived once from Eq. 2: a uniform segment, its load, a point on it, the ends.

A lever is composed of these, not solved as one closed form: :mod:`pfmdyn.composed` assembles them
per frequency into a small linear system (segments between the clamp, the tip and the free end),
and reads the beam anywhere from its solution.  So a new ingredient (a second point, a fluid
load, a base drive) is one more piece, and nothing is expanded across segments.

Variables.  Positions are fractions of ``L``; on a segment ``t`` runs from 0 at its start, and
the argument of its functions is ``s = beta t``.  The beam's state is scaled so that every
piece is of order one at any frequency::

    z = [u, u_xi / beta, u_xixi / beta**2, u_xixixi / beta**3]      (xi = x / L)

so the ``n``-th component is ``d**n u / ds**n``; the physical slope is ``u'(x) = beta z[1] / L``.

The pieces:

* :func:`unit_state`: the field matrix ``F(s)``, ``F[n][j] = d**n phi_j / ds**n`` for the
  solutions ``phi_j`` of the unloaded Eq. 2 (from :func:`derivations.beam.general_solution`)
  whose state at ``s = 0`` is the unit vector ``e_j``.  Its entries are the Krylov-Duncan
  functions; entire in ``s``, used on short segments (``|beta l| <= 1``) and in ball arithmetic.
* :func:`bounded_basis`: ``cos s, sin s, e^{-s}, e^{s - s_end}`` and their derivatives (each
  checked to solve Eq. 2): bounded on a segment of any length, used where ``|beta l| > 1``.
* :func:`load_constant`: the constant particular solution ``-q0 / (EI kappa**4)`` per unit ``q0``;
  on a short segment the load enters as ``u_c (e_0 - F[:, 0](s))``, the particular solution with
  zero state at the segment's start (no cancellation at low frequency).
* :func:`point_jump`: a point on the beam carrying the tip (contact springs ``kvv, kll, kvl`` at
  height ``H`` below the neutral axis, tip mass ``mu``, rotary inertia ``rho_g``, drives ``d1,
  d2, f0`` and a couple ``m0``; a bare point, nothing but its drives, probes the beam elsewhere):
  the state is continuous in ``u, u'``; moment and shear jump by
  ``z_left - z_right = J z + G [d1, d2, f0]`` (rows 2, 3), from the free-body balances of
  :mod:`derivations.tilt` and :mod:`derivations.tip_mass` moved to the point.
* The clamp (Eq. 3) fixes ``z[0] = z[1] = 0`` at ``xi = 0``; the free end ``z[2] = z[3] = 0`` to
  the right of ``xi = 1`` (a point at the end adds its jump there): :data:`CLAMPED`, :data:`FREE`.
  A clamp moved by the base (a dither piezo) by ``y0`` fixes ``z[0] = y0`` instead
  (:data:`BASE_DRIVE`): the deflection is then absolute, the base's own motion included.
* The read-outs: deflection ``z[0]`` and slope ``beta z[1] / L`` anywhere.
"""
from __future__ import annotations

from functools import lru_cache

import sympy as sp

from .beam import EI, H, L, beta, d1, d2, f0, general_solution, k, kappa, q0, x
from .tilt import kll, kvl, kvv
from .tip_mass import inertial_stiffness, mu, rho_g, rotary_inertia

__all__ = ["gamma", "sigma", "s", "s_end", "unit_state", "bounded_basis", "load_constant", "point_jump", "POINT_DRIVES",
           "CLAMPED", "FREE", "BASE_DRIVE", "y0", "m0", "solves_equation", "clamped_segment_slope"]

gamma, sigma = sp.symbols("gamma sigma", positive=True)
"""The tip's position ``x_tip / L`` (public name ``tip_position``) and the laser spot's ``x_s / L``
(``spot_position``)."""

s, s_end = sp.symbols("s s_end")
"""The segment's argument ``beta t`` and its value at the segment's end, ``beta l``."""

m0 = sp.Symbol("m0", real=True)
"""A couple applied at a point (work-conjugate to the slope there, as ``f0`` is to the deflection)."""
POINT_DRIVES = (d1, d2, f0, m0)
CLAMPED = (0, 1)
"""State components fixed to zero at the clamp (Eq. 3: ``u(0) = u'(0) = 0``)."""
FREE = (2, 3)
"""State components zero beyond the free end (no moment, no shear)."""
y0 = sp.Symbol("y0")
"""The base's (the clamp's) displacement, a drive."""
BASE_DRIVE = {0: y0}
"""The clamp's state components a moving base sets (the others of :data:`CLAMPED` stay zero)."""


def solves_equation(phi: sp.Expr) -> bool:
    """True when ``phi(s)`` solves the unloaded Eq. 2 in the segment's argument (``phi'''' = phi``).

    >>> solves_equation(sp.exp(s - s_end)), solves_equation(sp.cosh(2 * s))
    (True, False)
    """
    return sp.simplify(phi.diff(s, 4) - phi) == 0


@lru_cache(maxsize=None)
def unit_state() -> sp.Matrix:
    """``F[n][j] = d**n phi_j/ds**n`` with ``phi_j`` the unloaded solution of unit initial state ``e_j``.

    From the general solution of Eq. 2 (``x = L s / beta``), its constants fixed by the initial
    state.  ``F(0)`` is the identity and ``F' `` shifts the rows (``F[4] = F[0]``, the equation).

    >>> F = unit_state()
    >>> F.subs(s, 0) == sp.eye(4)
    True
    >>> sp.simplify(F[0, 3] - (sp.sinh(s) - sp.sin(s)) / 2)
    0
    """
    u, consts = general_solution()
    u = sp.expand(u.subs(q0, 0).subs(x, L * s / beta))
    phi = sp.Matrix([[sp.diff(u, s, n).diff(c) for c in consts] for n in range(4)])
    F = phi * phi.subs(s, 0).inv()
    # each entry is a sum of cos, sin, cosh, sinh over 2: expanding is its simplest form
    return F.applyfunc(lambda e: sp.expand(e.rewrite(sp.cos).rewrite(sp.cosh)))


@lru_cache(maxsize=None)
def bounded_basis() -> sp.Matrix:
    """``B[n][j] = d**n b_j / ds**n`` (``n = 0..4``) of ``b = cos s, sin s, e^{-s}, e^{s - s_end}``.

    The general solution's exponentials re-anchored so that each is at most one on
    ``0 <= s <= s_end``; each column solves Eq. 2 (``B[4] = B[0]``).

    >>> B = bounded_basis()
    >>> all(solves_equation(b) for b in B.row(0)), B[4, :] == B[0, :]
    (True, True)
    """
    columns = [sp.cos(s), sp.sin(s), sp.exp(-s), sp.exp(s - s_end)]
    assert all(solves_equation(b) for b in columns)
    return sp.Matrix([[sp.diff(b, s, n) for b in columns] for n in range(5)])


def load_constant() -> sp.Expr:
    """The constant particular solution of Eq. 2 per unit ``q0``: ``-1 / (EI kappa**4) = -3 L / (k beta**4)``.

    >>> load_constant()
    -3*L/(beta**4*k)
    """
    c = sp.Symbol("c")
    (value,) = sp.solve(sp.Eq(0, kappa**4 * c + q0 / EI), c)
    return sp.simplify(value / q0)


@lru_cache(maxsize=None)
def point_jump() -> tuple[sp.Matrix, sp.Matrix]:
    """``(J, G)``: moment and shear rows of ``z_left - z_right = J z + G [d1, d2, f0, m0]`` at the tip.

    ``J`` is 2x2 (rows: moment, shear; columns: ``z[0] = u``, ``z[1]``), ``G`` 2x4.  Free-body
    balances at the point ``a`` (left minus right)::

        EI [u''(a-) - u''(a+)]   = H F_l + m0 + J_t omega**2 u'(a)
        EI [u'''(a-) - u'''(a+)] = -(F_v + f0 + m_t omega**2 u(a))

    with the spring forces ``F = -K (w - d)`` of :mod:`derivations.tilt` (``w = [u, H u']``) and
    the tip body of :mod:`derivations.tip_mass`; at ``a = L`` with nothing beyond, Eqs. 4a,b.

    >>> J, G = point_jump()
    >>> sp.simplify(J[1, 0].subs(mu, 0))
    3*kvv/(beta**3*k)
    """
    z0, z1 = sp.symbols("z0 z1")
    u, slope = z0, beta * z1 / L
    force_v = -(kvv * (u - d1) + kvl * (H * slope - d2))
    force_l = -(kvl * (u - d1) + kll * (H * slope - d2))
    # the couple m0 enters as the lateral force's moment H F_l does: both do work on the slope
    moment = H * force_l + m0 + rotary_inertia() * slope            # EI u'' jump
    shear = -(force_v + f0 + inertial_stiffness() * u)             # EI u''' jump
    rows = [sp.expand(moment / (EI * kappa**2)), sp.expand(shear / (EI * kappa**3))]
    J = sp.Matrix([[r.coeff(v) for v in (z0, z1)] for r in rows])
    G = sp.Matrix([[r.coeff(dr) for dr in POINT_DRIVES] for r in rows])
    return J.applyfunc(sp.simplify), G.applyfunc(sp.simplify)


def clamped_segment_slope(end_conditions, drives, load: bool = True) -> tuple[sp.Expr, dict]:
    """The slope along a one-segment lever (clamp to ``xi = 1``), per unit drive, from the pieces.

    The clamp state is ``[0, 0, m, v]`` (:data:`CLAMPED`); the state along the segment is
    ``F(s) [0, 0, m, v] + u_c q0 (e_0 - F[:, 0](s))`` (:func:`unit_state`, :func:`load_constant`);
    the two end conditions on ``z(beta)`` make a 2x2 system in ``(m, v)``, solved by Cramer's rule.

    Parameters
    ----------
    end_conditions : callable
        ``end_conditions(z)`` of the end state ``z(beta)`` (a list of four scaled components),
        returning two expressions, linear in the state and the drives, that vanish on the solution.
    drives : sequence of sympy.Symbol
        The excitations in the end conditions; ``q0`` is added when ``load``.
    load : bool
        Whether the uniform load ``q0`` acts.

    Returns
    -------
    denominator : sympy.Expr
        The 2x2 system's determinant (its zeros are the resonances).
    slope : dict
        ``slope[drive] / denominator`` is ``u'(t L)`` per unit drive, in cos, sin, cosh, sinh of
        ``beta`` and of the segment's argument ``s = beta t``.

    Examples
    --------
    A free end pulled by a tip force: the static slope there is ``3 f0 / (2 k L)``.

    >>> from .beam import EI, f0
    >>> pulled = lambda z: [z[2], EI * (beta / L)**3 * z[3] + f0]
    >>> den, slope = clamped_segment_slope(pulled, (f0,), load=False)
    >>> sp.limit((slope[f0] / den).subs(s, beta), beta, 0)
    3/(2*L*k)
    """
    F, m, v = unit_state(), *sp.symbols("m v")
    particular = load_constant() * q0 * (sp.eye(4)[:, 0] - F[:, 0]) if load else sp.zeros(4, 1)
    z = F * sp.Matrix([0, 0, m, v]) + particular
    M, rhs = sp.linear_eq_to_matrix([sp.expand(c) for c in end_conditions(list(z.subs(s, beta)))], [m, v])
    den, mv = M.det(), M.adjugate() * rhs
    slope = sp.expand(beta / L * (z[1].subs({m: mv[0], v: mv[1]}) + particular[1] * (den - 1)))
    return sp.expand(den), {d: slope.coeff(d) for d in (*drives, *([q0] if load else []))}
