"""The fluid's load on a vibrating lever: Sader's hydrodynamic function (J. Appl. Phys. 84, 64, 1998).

A lever of width ``b`` oscillating at ``omega`` in a fluid of density ``rho`` and viscosity ``eta`` feels
the force per unit length ``(pi/4) rho omega**2 b**2 Gamma(Re) W`` (Sader's time dependence
``exp(-i omega t)``, so ``Gamma_i > 0`` is loss), ``Re = rho omega b**2 / (4 eta)``.  For a circular
cylinder of diameter ``b`` it is exact (Stokes/Rosenhead):

    Gamma_circ(Re) = 1 + 4 i K1(-i sqrt(i Re)) / (sqrt(i Re) K0(-i sqrt(i Re))).

For the thin rectangle Sader fitted the ratio ``Omega = Gamma_rect / Gamma_circ`` to his boundary-integral
solution as a rational function of ``tau = log10 Re`` (his Eq. 21, :data:`OMEGA`), stated accurate to
0.1 % over ``1e-6 <= Re <= 1e4``: a fit, not a derivation, and used only there.

pfmdyn's time dependence is ``exp(+i omega t)`` (:mod:`derivations.damping`): the same fluid is the
complex conjugate, and a beam in it has ``beta_fluid**4 = beta**4 (1 + T conj(Gamma))`` with
``T = pi rho b**2 / (4 rho_c h b)``, the loss entering as ``-i`` exactly as the viscous drag
``beta**4 (1 - i g / r)`` does.
"""
from __future__ import annotations

from functools import lru_cache

import mpmath as mp
import sympy as sp

__all__ = ["Re", "tau", "OMEGA", "circular", "rectangular_correction", "hankel_ratio", "high_reynolds",
           "circular_numeric", "rectangular_numeric", "fluid_first_mode"]

Re = sp.Symbol("Re", positive=True)
tau = sp.Symbol("tau", real=True)

OMEGA = {
    "real": ((0.91324, -0.48274, 0.46842, -0.12886, 0.044055, -0.0035117, 0.00069085),
             (1, -0.56964, 0.48690, -0.13444, 0.045155, -0.0035862, 0.00069085)),
    "imag": ((-0.024134, -0.029256, 0.016294, -0.00010961, 0.000064577, -0.000044510),
             (1, -0.59702, 0.55182, -0.18357, 0.079156, -0.014369, 0.0028361)),
}
"""Sader (1998) Eq. 21 as printed: (numerator, denominator) coefficients in ascending powers of tau."""


def circular(conjugate: bool = False, re: sp.Symbol = Re) -> sp.Expr:
    """``Gamma_circ(re)`` of the module docstring (Sader's convention, ``exp(-i omega t)``); ``conjugate``:
    pfmdyn's ``exp(+i omega t)`` form, ``i`` turned to ``-i``: the conjugate on real ``re``, analytic in it
    (a damped mode's complex Reynolds number; ``re`` then a symbol without assumptions).

    >>> sp.N(circular().subs(Re, 1), 8)
    3.9680148 + 4.5665706*I
    >>> z = sp.Symbol("z"); sp.N(circular(True, z).subs(z, 1), 8)
    3.9680148 - 4.5665706*I
    """
    unit = -sp.I if conjugate else sp.I
    root = sp.sqrt(unit * re)
    return 1 + 4 * unit * sp.besselk(1, -unit * root) / (root * sp.besselk(0, -unit * root))


def rectangular_correction(part: str) -> sp.Expr:
    """Real or imaginary part of Sader's ``Omega(tau)``, ``tau = log10 Re`` (the fit, :data:`OMEGA`).

    >>> [round(float(rectangular_correction(p).subs(tau, 0)), 6) for p in ("real", "imag")]
    [0.91324, -0.024134]
    """
    numerator, denominator = OMEGA[part]
    poly = lambda coeffs: sum(sp.Float(str(c), 15) * tau**i for i, c in enumerate(coeffs))   # noqa: E731
    return poly(numerator) / poly(denominator)


def hankel_ratio(terms: int = 4) -> sp.Expr:
    """``K1(z)/K0(z)`` for large ``|z|`` (``|arg z| < 3 pi/2``) from Hankel's expansion
    ``K_nu(z) ~ sqrt(pi/(2z)) e^{-z} sum_k a_k(nu) / z**k``, ``a_k = prod_{j<=k} (4 nu**2 - (2j-1)**2) / (k! 8**k)``,
    as a series in ``w = 1/z``.

    >>> w = sp.Symbol("w"); hankel_ratio(3)
    1 + w/2 - w**2/8 + O(w**3)
    """
    w = sp.Symbol("w")

    def series(nu):
        return sum(sp.prod([4 * nu**2 - (2 * j - 1)**2 for j in range(1, n + 1)]) / (sp.factorial(n) * 8**n) * w**n
                   for n in range(terms + 1))
    return sp.series(series(1) / series(0), w, 0, terms)


def high_reynolds(order: int = 2) -> sp.Expr:
    """``Gamma_circ`` for large ``Re`` to ``order`` terms in ``1/sqrt(Re)``, from :func:`hankel_ratio`
    (``z = -i sqrt(i Re) = e^{-i pi/4} sqrt(Re)``, inside the sector where Hankel's expansion holds).

    >>> high_reynolds(2)
    1 + 2*I/Re + 2*sqrt(2)*(1 + I)/sqrt(Re)
    """
    s, w = sp.symbols("s w", positive=True)
    ratio = hankel_ratio(order + 1).removeO().subs(sp.Symbol("w"), w)
    z = sp.exp(-sp.I * sp.pi / 4) / s                    # s = 1/sqrt(Re)
    gamma = 1 + 4 * sp.I * s / sp.exp(sp.I * sp.pi / 4) * ratio.subs(w, 1 / z)
    expansion = sp.series(sp.expand(gamma), s, 0, order + 1).removeO()
    terms = sp.collect(sp.expand(sp.expand_complex(expansion)), s, evaluate=False)
    return sum(sp.factor(sp.nsimplify(c)) * s**p.as_base_exp()[1] if p != 1 else c
               for p, c in terms.items()).subs(s, 1 / sp.sqrt(Re))


def circular_numeric(re, conjugate: bool = False):
    """``Gamma_circ`` at a (complex) Reynolds number, mpmath; ``conjugate``: pfmdyn's ``exp(+i omega t)``
    form, analytic in ``re`` (equal to the conjugate for real ``re``).

    >>> mp.nstr(circular_numeric(1), 8)
    '(3.9680148 + 4.5665706j)'
    """
    unit = -1j if conjugate else 1j
    root = mp.sqrt(unit * re)
    z = -unit * root
    return 1 + 4 * unit * mp.besselk(1, z) / (root * mp.besselk(0, z))


@lru_cache(maxsize=None)
def _correction_numeric():
    return {part: sp.lambdify(tau, rectangular_correction(part), "mpmath") for part in OMEGA}


def rectangular_numeric(re, conjugate: bool = False):
    """``Gamma_rect = Omega Gamma_circ`` at a (complex) Reynolds number, mpmath (``conjugate`` as in
    :func:`circular_numeric`).

    >>> mp.nstr(rectangular_numeric(1), 6)
    '(3.73396 + 4.07461j)'
    """
    t = mp.log10(re)
    f = _correction_numeric()
    omega = f["real"](t) + (-1j if conjugate else 1j) * f["imag"](t)
    return omega * circular_numeric(re, conjugate)


def fluid_first_mode(frequency_vacuum, mass_per_length, density, viscosity, width):
    """The first mode of a rectangular lever in a fluid, exactly: the complex root ``omega`` (rad/s, pfmdyn's
    ``exp(+i omega t)``, ``Im > 0``) of ``(omega/omega_vac)**2 (1 + T conj(Gamma(Re(omega)))) = 1``, which is
    the free lever's ``1 + cos(beta) cosh(beta) = 0`` at ``beta_fluid**4 = beta**4 (1 + load)`` (the load is
    uniform along the lever, so the mode shape is the vacuum one).  Returns ``(frequency_hz, Q)`` with
    ``Q = Re omega / (2 Im omega)``.

    >>> f, q = fluid_first_mode(1.8e5, 3.9e-7, 1.13, 1.9e-5, 4e-5)
    >>> round(float(f), -1), round(float(q))
    (179480.0, 480)
    """
    wv = 2 * mp.pi * frequency_vacuum
    load = lambda w: mp.pi * density * width**2 / (4 * mass_per_length) * rectangular_numeric(   # noqa: E731
        density * w * width**2 / (4 * viscosity), conjugate=True)
    root = mp.findroot(lambda w: (w / wv)**2 * (1 + load(w)) - 1, mp.mpc(wv, wv * 1e-3))
    return root.real / (2 * mp.pi), root.real / (2 * root.imag)
