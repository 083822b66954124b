"""Elastic contact with a point mass at the tip (extension of Eqs. 4a,b).

Equation: Eq. 2, ``u0'''' = kappa**4 u0 + q0/EI``, with the clamped end of Eq. 3.  The
tip carries a point mass ``m_t`` (this family leaves out its rotary inertia;
:func:`rotary_inertia` derives it for the tip point of :mod:`derivations.pieces`).  In harmonic motion ``u0 e^{i omega t}`` its inertia is a force
``+m_t omega**2 u0(L)`` on the beam end (positive away from the surface when the tip is
displaced that way), which adds to the local force ``f0`` in the shear condition::

    EI u0''(L)  = k2 H (d2 - H u0'(L))                              (Eq. 4a, unchanged)
    EI u0'''(L) = -f0 + k1 (u0(L) - d1) - m_t omega**2 u0(L)        (Eq. 4b + inertia)

Dimensionless mass ratio ``mu = m_t / (rho S L)`` (tip mass over beam mass).  From
``kappa**4 = omega**2 rho S / EI`` and ``kappa = beta / L``,
``omega**2 = beta**4 EI / (rho S L**4)``, so with ``EI = k L**3 / 3``::

    m_t omega**2 = mu rho S L * beta**4 EI / (rho S L**4) = mu beta**4 EI / L**3
                 = mu k beta**4 / 3.

(``mu beta**4 EI / L**3``: the factor 3 belongs to ``EI = k L**3/3``, not to ``m_t omega**2``.)
At ``mu = 0`` the problem is Eq. 4; at ``k1 = k2 = 0`` it is the free cantilever with a
tip mass, whose first root falls below 1.8751 as ``mu`` grows.  Signs as in
:mod:`derivations.beam`.
"""
from __future__ import annotations

import sympy as sp

from .beam import EI, H, L, TipProblem, TipSolution, beta, d1, d2, f0, k, k1, k2, q0, solve_tip_problem

__all__ = ["mu", "rho_g", "inertial_stiffness", "rotary_inertia", "tip_conditions", "problem", "solve", "DRIVES"]

mu = sp.Symbol("mu", nonnegative=True)
"""Tip mass over cantilever mass, ``m_t / (rho S L)``."""

rho_g = sp.Symbol("rho_g", nonnegative=True)
"""Tip radius of gyration over the cantilever length, ``r_g / L`` (``J = m_t r_g**2``)."""

DRIVES = (d1, d2, f0, q0)


def inertial_stiffness() -> sp.Expr:
    """``m_t omega**2`` in the derivation's variables: ``mu k beta**4 / 3``.

    >>> inertial_stiffness()
    beta**4*k*mu/3
    """
    return mu * k * beta**4 / 3


def rotary_inertia() -> sp.Expr:
    """``J omega**2`` in the derivation's variables: ``mu k beta**4 L**2 rho_g**2 / 3``.

    The tip is a rigid body of mass ``m_t`` and moment of inertia ``J = m_t r_g**2`` about
    the axis through its attachment point on the beam's neutral axis, normal to the plane
    of bending (a centre of mass a distance ``e`` from that axis contributes ``m_t e**2``:
    the beam is axially rigid, so the body turns about the attachment point).  It turns
    with the beam, through the angle ``u0'(a)``.  The rotating body resists angular
    acceleration: the couple the beam applies to it is ``J d**2 u0'(a)/dt**2
    = -J omega**2 u0'(a)`` (the moment ``-J omega**2 u'`` of the issue), so it returns
    ``+J omega**2 u0'(a)`` to the beam, counter-clockwise positive (the sense in which
    ``u0'`` grows), the same way the point mass returns ``+m_t omega**2 u0(a)``.  With
    ``m_t omega**2`` of :func:`inertial_stiffness` and ``r_g = rho_g L``::

        J omega**2 = m_t omega**2 r_g**2 = mu k beta**4 L**2 rho_g**2 / 3.

    It is a negative rotational spring: like the mass, it lowers every resonance.

    >>> rotary_inertia()
    L**2*beta**4*k*mu*rho_g**2/3
    """
    return inertial_stiffness() * L**2 * rho_g**2


def tip_conditions(U):
    """Eq. 4a and Eq. 4b with the tip inertia; ``U = [u(L), u'(L), u''(L), u'''(L)]``.

    >>> [sp.expand(e) for e in tip_conditions([1, 0, 0, 0])]
    [-H*d2*k2, beta**4*k*mu/3 + d1*k1 + f0 - k1]
    """
    return [EI * U[2] - k2 * H * (d2 - H * U[1]),
            EI * U[3] - (-f0 + k1 * (U[0] - d1) - inertial_stiffness() * U[0])]


problem = TipProblem(
    "tip_mass", tip_conditions, (d1, d2, f0), load=True,
    description="elastic contact (Eqs. 4a,b) with a point mass mu rho S L at the tip",
)


def solve() -> TipSolution:
    """Slope and deflection per unit d1, d2, f0, q0 with the tip mass.

    >>> from .elastic_contact import reduces_to_elastic_contact
    >>> reduces_to_elastic_contact(solve(), {mu: 0}, f0)   # massless tip
    True
    """
    return solve_tip_problem(problem)
