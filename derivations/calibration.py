"""Spring-constant calibration of the free lever: the thermal method's mode factors and Sader's method.

Both rest on the first free mode of Eq. 2 (clamp of Eq. 3, free end ``u'' = u''' = 0``), derived
here in ``xi = x/L``:

* **Thermal method** (Hutter & Bechhoefer 1993; Butt & Jaschke 1995, Nanotechnology 6, 1).  By
  equipartition the first mode's amplitude ``a`` (shape ``phi`` with ``int_0^1 phi**2 = 1``) has
  ``<a**2> = kB T / (EI beta1**4 / L**3)``.  What the instrument reports as deflection ``d*`` is the
  mode read at the laser spot ``sigma = x_s/L`` and converted with a *static* sensitivity (InvOLS,
  measured by pressing the tip at ``gamma = x_tip/L`` on a hard surface): for an optical lever
  ``d* = phi'(sigma) a * w(gamma)/w'(sigma)``, for a displacement sensor ``phi(sigma) a * w(gamma)/w(sigma)``,
  with ``w`` the static shape under a force at the tip.  The spring constant at the tip,
  ``k_tip = 3 EI / x_tip**3`` (Proksch et al. 2004, Nanotechnology 15, 1344), is then
  ``k_tip = chi kB T / <d*_1**2>`` with the factor ``chi`` of :func:`thermal_factor`: 12/beta1**4 =
  0.971 (deflection, spot and tip at the end) and 0.817 (optical lever).
* **Sader's method** (Sader, Chon & Mulvaney 1999, Rev. Sci. Instrum. 70, 3967).  The lever's
  effective mass ``k / omega_vac**2 = 3 m_c / beta1**4``; in a fluid whose load per length is
  ``pi rho b**2 Gamma / 4`` (Sader 1998, J. Appl. Phys. 84, 64) the first mode has
  ``omega_f = omega_vac (1 + T Gamma_r)**(-1/2)`` and ``Q = (1/T + Gamma_r)/Gamma_i``,
  ``T = pi rho b / (4 rho_c h)``; eliminating ``rho_c h`` gives
  ``k = (3 pi / (4 beta1**4)) rho b**2 L Q Gamma_i omega_f**2`` (:func:`sader_spring_constant`,
  the coefficient 0.1906 of the paper).
"""
from __future__ import annotations

from functools import lru_cache

import mpmath as mp
import sympy as sp

from .beam import EI, L, beta, general_solution, k, q0, x

__all__ = ["xi", "sigma", "gamma", "first_root", "mode_shape", "static_shape", "thermal_factor",
           "sader_spring_constant", "mass_per_length", "oscillator_mean_square"]

xi = sp.Symbol("xi", positive=True)
sigma, gamma = sp.symbols("sigma gamma", positive=True)
"""Laser spot ``x_s/L`` and tip position ``x_tip/L``."""

DIGITS = 30


@lru_cache(maxsize=None)
def _shape_in_beta() -> tuple[sp.Expr, sp.Expr]:
    """The free mode of Eq. 2 in ``xi`` with ``beta`` left symbolic: (shape up to scale, characteristic)."""
    u, constants = general_solution()
    u = u.subs({q0: 0, x: xi * L})
    conditions = [u.subs(xi, 0), u.diff(xi).subs(xi, 0), u.diff(xi, 2).subs(xi, 1), u.diff(xi, 3).subs(xi, 1)]
    matrix = sp.Matrix([[c.diff(a) for a in constants] for c in conditions])
    characteristic = matrix.det()
    # Three rows fix the constants up to scale (the last set to 1); the fourth holds at a root of the characteristic.
    head = matrix[:3, :3].LUsolve(-matrix[:3, 3])
    return u.subs(dict(zip(constants, [*head, 1]))), characteristic


@lru_cache(maxsize=None)
def first_root() -> sp.Float:
    """First root of the free lever's characteristic (``1 + cos(beta) cosh(beta) = 0``), to 30 digits.

    >>> round(float(first_root()), 10)
    1.8751040687
    """
    _, characteristic = _shape_in_beta()
    return sp.nsolve(characteristic, beta, 1.9, prec=DIGITS)


@lru_cache(maxsize=None)
def mode_shape() -> sp.Expr:
    """First free mode ``phi(xi)``, normalised ``int_0^1 phi**2 dxi = 1`` with ``phi(1) > 0``.

    >>> round(float(mode_shape().subs(xi, 1)), 10)      # the classic end value 2
    2.0
    """
    shape, _ = _shape_in_beta()
    shape = shape.subs(beta, first_root())
    with mp.workdps(DIGITS):
        norm = mp.sqrt(mp.quad(sp.lambdify(xi, shape**2, "mpmath"), [0, 1]))
        scale = sp.Float(mp.sign(shape.subs(xi, 1).evalf(DIGITS)) / norm, DIGITS)
    return shape * scale


@lru_cache(maxsize=None)
def static_shape(region: str = "beyond") -> sp.Expr:
    """Static deflection ``w(xi)`` under a unit force ``F`` at ``gamma``, in units of ``F L**3 / EI``: Eq. 2
    at ``beta = 0`` on ``[0, gamma]`` (clamp, no moment and shear ``-F`` at the force; ``region="inside"``),
    straight beyond it (``region="beyond"``, ``xi >= gamma``).

    >>> static_shape().subs({xi: 1, gamma: 1}), static_shape("inside").subs(xi, gamma)
    (1/3, gamma**3/3)
    """
    c = sp.symbols("c0:4")
    cubic = sum(ci * xi**i for i, ci in enumerate(c))
    assert sp.diff(cubic, xi, 4) == 0                               # Eq. 2 at beta = 0, no load
    solved = sp.solve([cubic.subs(xi, 0), cubic.diff(xi).subs(xi, 0), cubic.diff(xi, 2).subs(xi, gamma),
                       cubic.diff(xi, 3).subs(xi, gamma) + 1], c, dict=True)[0]
    cubic = cubic.subs(solved)
    if region == "inside":
        return cubic
    return cubic.subs(xi, gamma) + cubic.diff(xi).subs(xi, gamma) * (xi - gamma)


def thermal_factor(detection: str = "slope", region: str = "beyond") -> sp.Expr:
    """``chi(sigma, gamma)`` of ``k_tip = chi kB T / <d*_1**2>`` (module docstring), for an optical lever
    (``"slope"``) or a displacement sensor (``"deflection"``) calibrated statically, with the spot
    beyond the tip (``sigma >= gamma``) or inside (``sigma <= gamma``); both agree at ``sigma = gamma``.

    >>> [round(float(thermal_factor(d).subs({sigma: 1, gamma: 1})), 4) for d in ("deflection", "slope")]
    [0.9707, 0.8174]
    """
    phi, w = mode_shape(), static_shape(region)
    if detection == "slope":
        read, static = phi.diff(xi), w.diff(xi)
    elif detection == "deflection":
        read, static = phi, w
    else:
        raise ValueError(detection)
    # k_tip <d*^2> / kB T with <a^2> = kB T L^3 / (EI beta1^4), k_tip = 3 EI / (gamma L)^3.
    scale = (read * static_shape("inside").subs(xi, gamma) / static).subs(xi, sigma)
    return 3 / (gamma**3 * first_root()**4) * scale**2


rho_fluid, width, Q, gamma_r, gamma_i, f_fluid = sp.symbols(
    "density width quality_factor gamma_r gamma_i frequency", positive=True)
rho_c_h, omega_vac = sp.symbols("rho_c_h omega_vac", positive=True)


def sader_spring_constant() -> sp.Expr:
    """Sader's spring constant from the fluid's density, the lever's width and length, the fitted Q and
    frequency (Hz) and ``Gamma_i`` at that frequency (module docstring).

    >>> e = sader_spring_constant()
    >>> round(float(e / (rho_fluid * width**2 * L * Q * gamma_i * (2 * sp.pi * f_fluid)**2)), 4)
    0.1906
    """
    T = sp.pi * rho_fluid * width / (4 * rho_c_h)
    omega_f = 2 * sp.pi * f_fluid
    # Sader's closed forms for the first mode in the fluid, solved for the lever's rho_c h and omega_vac.
    mass = sp.solve(sp.Eq(Q, (1 / T + gamma_r) / gamma_i), rho_c_h)[0]
    vacuum = sp.solve(sp.Eq(omega_f, omega_vac * (1 + T * gamma_r)**sp.Rational(-1, 2)), omega_vac)[0]
    # Effective mass k / omega_vac**2 with k = 3 EI / L**3 and Eq. 2's omega_vac**2 = beta1**4 EI / (rho S L**4).
    effective = (3 * EI / L**3) / (beta**4 * EI / (rho_c_h * width * L**4))
    spring = (effective * vacuum**2).subs(rho_c_h, mass).subs(beta, first_root())
    return sp.simplify(spring)


def mass_per_length() -> sp.Expr:
    """``rho_c h b`` (kg/m) of a lever of spring constant ``k``, length ``L`` and first vacuum resonance
    ``f1`` (Hz): Eq. 2's ``beta1**4 = omega1**2 rho S L**4 / EI`` with ``EI = k L**3 / 3``.

    >>> f1 = sp.Symbol("free_resonance", positive=True)
    >>> sp.nsimplify(mass_per_length() * 3 * L * (2 * sp.pi * f1)**2 / k / first_root()**4)
    1
    """
    f1, rho_s = sp.Symbol("free_resonance", positive=True), sp.Symbol("rho_S", positive=True)
    return sp.solve(sp.Eq(first_root()**4, (2 * sp.pi * f1)**2 * rho_s * L**4 / EI), rho_s)[0]


def oscillator_mean_square() -> sp.Expr:
    """``<x**2>`` of the oscillator whose ASD is ``A f0**2 / |f0**2 - f**2 + i f f0/Q|`` (one-sided, per
    ``sqrt(Hz)``): the stationary variance of ``x'' + (w0/Q) x' + w0**2 x = w0**2 A xi(t)`` from its
    Lyapunov equation (white ``xi`` of one-sided PSD 1/Hz, i.e. intensity 1/2).

    >>> f0, q, a = sp.symbols("f0 q amplitude", positive=True)
    >>> oscillator_mean_square()
    pi*amplitude**2*f0*q/2
    """
    f0, q, a = sp.symbols("f0 q amplitude", positive=True)
    w0 = 2 * sp.pi * f0
    drift = sp.Matrix([[0, 1], [-w0**2, -w0 / q]])
    noise = sp.Matrix([0, w0**2 * a]) * sp.Matrix([0, w0**2 * a]).T / 2
    p = sp.Matrix(2, 2, sp.symbols("p0:4"))
    solved = sp.solve(list(drift * p + p * drift.T + noise) + [p[0, 1] - p[1, 0]], list(p), dict=True)[0]
    return sp.factor(solved[p[0, 0]])
