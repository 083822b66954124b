"""Domain contrast and electrostatic deconvolution (Sections IV.3 and VI.4, Eqs. 37-41).

Model (Eqs. 37-38): over c+ and c- domains the first-harmonic response is

    PR+ = +d_eff + d_el exp(i psi),    PR- = -d_eff + d_el exp(i psi),

with ``d_el = G_elec (V_dc - V_av)`` and ``psi`` the phase of the electrostatic part
relative to the electromechanical one.  The phase difference between the domains is
``Delta phi = arg(PR+) - arg(PR-)``.  Eq. 41 is the same model read as a straight line in
the bias: ``PR = d + G (V_dc - V_surf)``.
"""
from __future__ import annotations

from functools import lru_cache

import sympy as sp

__all__ = ["responses", "amplitudes_squared", "amplitude_series", "tan_phase_difference", "phase_difference_series",
           "linear_fit_in_bias"]

d_eff, d_el, psi = sp.symbols("d_eff d_el psi", positive=True)
eps = sp.Symbol("epsilon", positive=True)


def responses() -> tuple[sp.Expr, sp.Expr]:
    """PR+ and PR- of Eqs. 37-38."""
    field = d_el * sp.exp(sp.I * psi)
    return d_eff + field, -d_eff + field


@lru_cache(maxsize=None)
def amplitudes_squared() -> tuple[sp.Expr, sp.Expr]:
    """|PR+|**2 and |PR-|**2.

    >>> amplitudes_squared()[0]
    d_eff**2 + 2*d_eff*d_el*cos(psi) + d_el**2
    """
    return tuple(sp.expand(sp.simplify(sp.expand_complex(r * sp.conjugate(r)))) for r in responses())


def amplitude_series(small: str, order: int = 2) -> tuple[sp.Expr, sp.Expr]:
    """|PR+| and |PR-| to first order in the small one of d_el/d_eff, d_eff/d_el.

    ``small="electrostatic"``: ``|PR+-| = d_eff sqrt(1 +- 2 epsilon cos psi + epsilon**2)``
    with epsilon = d_el/d_eff; otherwise the roles of d_eff and d_el swap (epsilon =
    d_eff/d_el).  The square root is expanded in epsilon and epsilon put back, so the
    result is in d_eff, d_el, psi (both positive here, as the module's symbols).

    >>> amplitude_series("electrostatic"), amplitude_series("piezoelectric")
    ((d_eff + d_el*cos(psi), d_eff - d_el*cos(psi)), (d_eff*cos(psi) + d_el, -d_eff*cos(psi) + d_el))
    """
    large, tiny = (d_eff, d_el) if small == "electrostatic" else (d_el, d_eff)
    out = []
    for amplitude in amplitudes_squared():
        unit = sp.expand(amplitude.subs(tiny, eps * large) / large**2)
        series = sp.series(sp.sqrt(unit), eps, 0, order).removeO()
        out.append(sp.expand(large * series.subs(eps, tiny / large)))
    return tuple(out)


def tan_phase_difference() -> sp.Expr:
    """tan(arg PR+ - arg PR-) = Im(PR+ conj PR-) / Re(PR+ conj PR-).

    >>> tan_phase_difference()
    2*d_eff*d_el*sin(psi)/(d_eff**2 - d_el**2)
    """
    plus, minus = responses()
    prod = sp.expand_complex(sp.expand(plus * sp.conjugate(minus)))
    return sp.simplify(sp.im(prod) / sp.re(prod))


def phase_difference_series(small: str, order: int = 3) -> sp.Expr:
    """Phase difference ``arg(PR+) - arg(PR-)`` (mod 2 pi, the module's convention) to first order.

    ``small="electrostatic"``: epsilon = d_el/d_eff; ``PR+/PR- = -(1 + z)/(1 - z)`` with
    ``z = epsilon e^(i psi)``.  Otherwise epsilon = d_eff/d_el and ``PR+/PR- = (1 + z)/(1 - z)``
    with ``z = epsilon e^(-i psi)``.  ``Im log((1 + z)/(1 - z))`` is expanded term by term.

    >>> phase_difference_series("electrostatic"), phase_difference_series("piezoelectric")
    (2*epsilon*sin(psi) + pi, -2*epsilon*sin(psi))
    """
    z = eps * sp.exp(sp.I * psi) if small == "electrostatic" else eps * sp.exp(-sp.I * psi)
    log_ratio = sp.series(sp.log((1 + z) / (1 - z)), eps, 0, order).removeO()
    im = sp.simplify(sp.im(sp.expand_complex(sp.expand(log_ratio))))
    return sp.expand(sp.pi + im) if small == "electrostatic" else sp.expand(im)


def linear_fit_in_bias() -> tuple[sp.Expr, sp.Expr]:
    """Slope and intercept of PR = d + G (V - V_surf) as a line b + c V in the bias V.

    >>> linear_fit_in_bias()
    (G, -G*V_surf + d)
    """
    d, G, V, Vs = sp.symbols("d G V V_surf", real=True)
    line = sp.Poly(sp.expand(d + G * (V - Vs)), V)
    return line.coeff_monomial(V), line.coeff_monomial(1)
