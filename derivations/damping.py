"""Three damping mechanisms as changes to Eq. 2 or to the tip condition, and what they do
to the undamped solution.

Each mechanism is a term of the damped beam problem (time dependence ``exp(i omega t)``):

* *internal* friction: a complex modulus ``E (1 + i/Q)``, so ``EI -> EI (1 + i/Q)``;
* *viscous* drag of air or liquid: a force ``c u_t`` per unit length along the beam,
  ``-rho S omega**2 u -> (-rho S omega**2 + i omega c) u``;
* *contact* loss: a dashpot ``eta`` in parallel with ``k1`` at the tip, so the normal
  contact force is ``(k1 + i omega eta) (u - d1)`` (rotated with ``k1`` by a tilt).

Dividing the damped Eq. 2 by the complex ``EI`` gives back Eq. 2 with complex
``beta``, ``k``, ``k1`` and tip mass ``mu`` (:func:`substitution`), so every undamped
family solution evaluated there *is* the damped solution; :func:`check_substitution`
proves it for the equation of motion, the dashpot and the tip mass's inertia (a point
mass feels no drag: ``mu beta**4`` must stay ``mu beta0**4 / (1 + i inv_q)``), and the
tip's rotary inertia (a rigid body turning in the medium is not dragged by it either:
``J omega**2 = mu k beta**4 L**2 rho_g**2 / 3`` scales like the mass, so it must come out
undamped, ``mu k beta0**4 L**2 rho_g**2 / 3``, with ``rho_g`` unchanged).  In terms of
the undamped dimensionless frequency ``beta0 = beta1 sqrt(r)``, ``r = f / f1``, and three dimensionless parameters,

* ``inv_q = 1/Q`` (internal loss factor, the same for every mode),
* ``g = c / (rho S omega1)`` (the inverse Q of free mode 1 under air damping alone; the
  half-power width ``g f1`` in Hz is the same for every mode, so ``Q`` grows with ``f``),
* ``x = omega1 eta / k1`` (the contact's loss tangent at ``f1``; its share of a mode's
  damping grows with the mode frequency and with ``k1``),

the substitution is::

    beta**4 = beta0**4 (1 - i g / r) / (1 + i inv_q),   k -> k (1 + i inv_q),
    k1 -> k1 (1 + i x r),   mu -> mu / (1 - i g / r)

A fluid around the lever (:mod:`pfmdyn.medium`: Sader's hydrodynamic function) loads it by
``rho S omega**2 Lambda u`` per unit length, ``Lambda`` the complex ratio of its load to the lever's
inertia at that frequency; it adds to the drag's term, so it is the drag ``g + i r Lambda``
(:func:`fluid_as_drag`): the generated substitution serves it unchanged.

``pfmdyn codegen`` writes it to ``generated/damping.py`` with its derivatives with respect
to ``inv_q``, ``g``, ``x`` (for the least-squares Jacobian; :mod:`derivations.codegen.effects`).
"""
from __future__ import annotations

import sympy as sp

from .beam import EI, L, beta, k, k1, q0, x as coordinate
from .tip_mass import mu, rotary_inertia

__all__ = ["MECHANISMS", "substitution", "check_substitution", "half_power_width", "fluid_as_drag"]

omega, omega1, rho_s, c, eta, Q = sp.symbols("omega omega1 rho_S c eta Q", positive=True)
r, g, xc, inv_q, beta0 = sp.symbols("r g x inv_q beta0", positive=True)
fluid = sp.Symbol("Lambda")
"""A fluid's load over the lever's inertia (complex, frequency dependent)."""

MECHANISMS = {"internal": inv_q, "viscous": g, "contact": xc}
"""Mechanism name -> its dimensionless parameter (0 switches it off exactly)."""


def substitution() -> dict[str, sp.Expr]:
    """Complex ``beta**4``, ``k``, ``k1`` and ``mu`` of the damped problem (module docstring).

    >>> s = substitution()
    >>> [sp.simplify(e.subs({inv_q: 0, g: 0, xc: 0})) for e in (s["beta4"], s["k"], s["k1"], s["mu"])]
    [beta0**4, k, k1, mu]
    """
    return {"beta4": beta0**4 * (1 - sp.I * g / r) / (1 + sp.I * inv_q),
            "k": k * (1 + sp.I * inv_q), "k1": k1 * (1 + sp.I * xc * r), "mu": mu / (1 - sp.I * g / r)}


def fluid_as_drag() -> sp.Expr:
    """The drag ``g`` that carries a fluid's load ``Lambda`` as well (module docstring).

    >>> fluid_as_drag()
    I*Lambda*r + g
    """
    return g + sp.I * r * fluid


def check_substitution() -> bool:
    """The damped Eq. 2 is Eq. 2 at the substituted ``beta``, ``k``: an exact identity.

    Damped: ``EI (1 + i/Q) u'''' = (rho S omega**2 - i omega c) u + q0`` with
    ``beta0**4 = rho S omega**2 L**4 / EI``, ``omega = r omega1``, ``c = g rho S omega1``;
    the contact dashpot: ``(k1 + i omega eta) = k1 (1 + i x r)`` with ``eta = x k1 / omega1``;
    the tip's mass and rotary inertia come out undamped; with a fluid's load ``Lambda`` added to the
    damped equation, the substitution holds with the drag :func:`fluid_as_drag`.

    >>> check_substitution()
    True
    """
    s = substitution()
    u = sp.Function("u")(coordinate)
    w = r * omega1
    b0 = sp.root(rho_s * w**2 * L**4 / EI, 4)
    damped = EI * (1 + sp.I * inv_q) * u.diff(coordinate, 4) - (rho_s * w**2 - sp.I * w * g * rho_s * omega1) * u - q0
    k_star = s["k"]
    undamped = (k_star * L**3 / 3) * (u.diff(coordinate, 4) - (s["beta4"].subs(beta0, b0) / L**4) * u
                                      - q0 / (k_star * L**3 / 3))
    dashpot = (k1 + sp.I * w * (xc * k1 / omega1)) - s["k1"]
    inertia = s["mu"] * s["beta4"] - mu * beta0**4 / (1 + sp.I * inv_q)
    rotary = (rotary_inertia().subs({mu: s["mu"], k: s["k"]}).subs(beta**4, s["beta4"])
              - rotary_inertia().subs(beta, beta0))
    wet = damped - rho_s * w**2 * fluid * u
    wet_undamped = undamped.subs(g, fluid_as_drag())
    return all(sp.simplify(sp.expand(e)) == 0 for e in (damped - undamped, dashpot, inertia, rotary,
                                                         wet - wet_undamped))


def half_power_width(mechanism: str) -> sp.Expr:
    """Half-power width ``Delta f / f1`` of a free mode at ``r = f/f1`` (light damping).

    Internal: ``r inv_q`` (constant Q); viscous: ``g`` (constant width in Hz).  The
    contact dashpot has no free-mode width; in contact it scales with ``k1`` and ``r``.

    >>> half_power_width("internal"), half_power_width("viscous")
    (inv_q*r, g)
    """
    # A mode beta**4 = beta_n**4 (1 - i delta) rings at omega = omega_n (1 - i delta / 2) to
    # first order, a half-power width of delta omega_n: read delta off the linearised factor.
    param = {"internal": inv_q, "viscous": g}[mechanism]
    factor = substitution()["beta4"].subs({p: 0 for p in MECHANISMS.values() if p is not param}) / beta0**4
    delta = -sp.im(sp.series(factor, param, 0, 2).removeO())
    return sp.simplify(r * delta)
