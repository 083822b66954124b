"""Independent reference: the exact beam solved numerically on two segments (NumPy; and in
mpmath at high precision, :func:`spot_response_mp` and :func:`determinant_mp`, at the end).

Nothing here uses ``derivations/`` or ``generated/``.  On each segment the frequency-domain
Euler-Bernoulli beam ``u'''' = kappa**4 u + q0/EI`` has the exact solution
``A cos(kappa x) + B sin(kappa x) + C cosh(kappa x) + D sinh(kappa x) - q0/(EI kappa**4)``;
the clamp at 0, the tip at ``gamma L`` (displacement and slope continuous, moment and shear
jumping by the tip loads) and the free end at ``L`` give an 8x8 (or, tip at the end, 4x4)
linear system solved with ``numpy.linalg.solve``.  The spot is read on whichever segment
holds it.  Tip loads (positive away from the surface): the springs
``F = -K (w - d)`` on ``w = (u, H u')`` with ``K = [[kvv, kvl], [kvl, kll]]``, the force
``f0``, the tip inertia ``mu k beta**4 / 3 * u``; the longitudinal force bends the beam
through the lever arm ``H``.  ``beta = 0`` is solved with the static basis ``1, x, x**2, x**3``.
"""
from __future__ import annotations

import math

import mpmath
import numpy as np


def _basis(kappa, x):
    """Rows: the four basis functions and their first three derivatives at ``x``."""
    if kappa == 0:
        return np.array([[1, x, x**2, x**3], [0, 1, 2 * x, 3 * x**2], [0, 0, 2, 6 * x], [0, 0, 0, 6]], dtype=complex)
    c, s, ch, sh = np.cos(kappa * x), np.sin(kappa * x), np.cosh(kappa * x), np.sinh(kappa * x)
    rows = [[c, s, ch, sh], [-s, c, sh, ch], [-c, -s, ch, sh], [s, -c, sh, ch]]
    return np.array([[v * kappa**n for v in r] for n, r in enumerate(rows)], dtype=complex)


def spot_response(beta, sigma, *, k, L, H, kvv, kll=0.0, kvl=0.0, mu=0.0, gamma=1.0, rho_g=0.0,
                  d1=0.0, d2=0.0, f0=0.0, q0=0.0):
    """``(u'(sigma L), u(sigma L))`` of the clamped beam with the tip at ``gamma L``."""
    EI = k * L**3 / 3
    kappa = beta / L
    # Particular solution: constant -q0/(EI kappa**4); static: q0 x**4 / (24 EI).
    static = beta == 0
    def particular(x, n):
        if static:
            return [q0 * x**4 / (24 * EI), q0 * x**3 / (6 * EI), q0 * x**2 / (2 * EI), q0 * x / EI][n]
        return -q0 / (EI * kappa**4) if n == 0 else 0.0
    a = gamma * L
    inertia = mu * k * beta**4 / 3
    # the tip body's rotary inertia J = m r_g**2 resists the rotation: a couple J omega**2 u'(a)
    # in the moment jump, as the mass's m omega**2 u(a) is in the shear jump
    rotary = inertia * (rho_g * L) ** 2
    segments = 1 if gamma == 1 else 2
    n = 4 * segments
    M = np.zeros((n, n), complex)
    rhs = np.zeros(n, complex)
    row = 0
    B0 = _basis(kappa, 0.0)
    for i in (0, 1):                                   # clamp: u(0) = u'(0) = 0
        M[row, :4] = B0[i]
        rhs[row] = -particular(0.0, i)
        row += 1
    left = _basis(kappa, a)
    # Tip state from the left segment: w = (u, H u'); spring forces F = -K (w - d).
    # Moment jump EI (u''- - u''+) = H F_l + J omega**2 u'; shear jump EI (u'''- - u'''+) = -(F_v + f0 + m w**2 u).
    # Written as linear rows in the left constants (and the right ones), constants on the rhs.
    u_row, du_row = left[0], left[1]
    u_p, du_p = particular(a, 0), particular(a, 1)
    Fv_row = -(kvv * u_row + kvl * H * du_row)
    Fv_const = -(kvv * (u_p - d1) + kvl * (H * du_p - d2))
    Fl_row = -(kvl * u_row + kll * H * du_row)
    Fl_const = -(kvl * (u_p - d1) + kll * (H * du_p - d2))
    right = _basis(kappa, a) if segments == 2 else None
    # moment
    M[row, :4] = EI * left[2] - H * Fl_row - rotary * du_row
    if right is not None:
        M[row, 4:] = -EI * right[2]
    rhs[row] = (H * Fl_const + rotary * du_p - EI * particular(a, 2)
                + (EI * particular(a, 2) if right is not None else 0))
    row += 1
    # shear
    M[row, :4] = EI * left[3] + Fv_row + inertia * u_row
    if right is not None:
        M[row, 4:] = -EI * right[3]
    rhs[row] = -(Fv_const + f0 + inertia * u_p) - EI * particular(a, 3) + (EI * particular(a, 3) if right is not None else 0)
    row += 1
    if right is not None:
        for i in (0, 1):                               # u, u' continuous at the tip
            M[row, :4], M[row, 4:] = left[i], -right[i]
            row += 1
        end = _basis(kappa, L)
        for i in (2, 3):                               # free end: u''(L) = u'''(L) = 0
            M[row, 4:] = end[i]
            rhs[row] = -particular(L, i)
            row += 1
    coef = np.linalg.solve(M, rhs)
    x = sigma * L
    seg = 0 if (x <= a or segments == 1) else 1
    B = _basis(kappa, x)
    c = coef[4 * seg:4 * seg + 4]
    return B[1] @ c + particular(x, 1), B[0] @ c + particular(x, 0)


# --- The same beam in mpmath (high precision) -------------------------------------------------
#
# The rows of :func:`spot_response` with the right segment's basis taken from the tip
# (``x - gamma L``), solved by ``mpmath.lu_solve``.  The textbook basis is ill-conditioned at
# both ends of the range (``cos, cosh`` nearly dependent at small ``beta``, ``cosh(beta)``
# against ``cos(beta)`` at large ``beta``): the working precision is ``dps`` digits plus those
# the basis costs, so that about ``dps`` digits survive; ``check=True`` re-solves 20 digits
# higher and asserts agreement (the reference verifies itself).


def _extra_digits(beta) -> int:
    """Digits the basis loses: ``cosh`` against ``cos`` (``exp(2 |beta|)``), and ``beta**-6``
    at small ``beta`` (``cos + cosh``, ``sinh - sin`` nearly dependent, the load's ``beta**-4``)."""
    b = complex(beta)
    big = max(abs(b.real), abs(b.imag))
    return int(2 * big / math.log(10) + 6 * max(0.0, -math.log10(abs(b)))) + 10


DRIVES = ("d1", "d2", "f0", "q0", "y0", "m0")
"""The reference's drives: the tip's, the load, the base, a couple at the tip."""


def _mp_basis(mp, kappa, x):
    c, s, ch, sh = mp.cos(kappa * x), mp.sin(kappa * x), mp.cosh(kappa * x), mp.sinh(kappa * x)
    rows = [[c, s, ch, sh], [-s, c, sh, ch], [-c, -s, ch, sh], [s, -c, sh, ch]]
    return [[v * kappa**n for v in r] for n, r in enumerate(rows)]


def _mp_system(mp, beta, *, k, L, H, kvv, kll, kvl, mu, gamma, rho_g):
    """``M`` and the right-hand sides (per unit drive, :data:`DRIVES`) of the two-segment beam, and
    the particular solution (per unit ``q0``).  All arguments mpmath numbers, ``beta != 0``."""
    EI = k * L**3 / 3
    kappa = beta / L
    up = -1 / (EI * kappa**4)                    # particular deflection per unit q0 (constant)
    a = gamma * L
    inertia = mu * k * beta**4 / 3
    rotary = inertia * (rho_g * L) ** 2
    two = gamma != 1
    n = 8 if two else 4
    M = mp.zeros(n, n)
    R = mp.zeros(n, len(DRIVES))                  # columns: DRIVES
    B0, left = _mp_basis(mp, kappa, 0), _mp_basis(mp, kappa, a)
    for i in (0, 1):                              # clamp
        for j in range(4):
            M[i, j] = B0[i][j]
    R[0, 3] = -up
    R[0, 4] = 1                                   # the clamp moved with the base: u(0) = y0
    R[2, 5] = 1                                   # the couple m0 turns as the lateral force's moment does
    u_row, du_row = left[0], left[1]
    # springs F = -K (w - d), w = (u, H u'); constants per drive (d1, d2, q0 through u_p)
    Fv_row = [-(kvv * u + kvl * H * du) for u, du in zip(u_row, du_row)]
    Fl_row = [-(kvl * u + kll * H * du) for u, du in zip(u_row, du_row)]
    Fv_const = [kvv, kvl, 0, -kvv * up]          # per unit d1, d2, f0, q0
    Fl_const = [kvl, kll, 0, -kvl * up]
    right = _mp_basis(mp, kappa, 0) if two else None
    for j in range(4):                            # moment jump (row 2), shear jump (row 3)
        M[2, j] = EI * left[2][j] - H * Fl_row[j] - rotary * du_row[j]
        M[3, j] = EI * left[3][j] + Fv_row[j] + inertia * u_row[j]
        if two:
            M[2, 4 + j], M[3, 4 + j] = -EI * right[2][j], -EI * right[3][j]
    for d in range(4):
        R[2, d] = H * Fl_const[d]
        R[3, d] = -(Fv_const[d] + (1 if d == 2 else 0) + (inertia * up if d == 3 else 0))
    if two:
        end = _mp_basis(mp, kappa, L - a)
        for r, i in ((4, 0), (5, 1)):              # u, u' continuous
            for j in range(4):
                M[r, j], M[r, 4 + j] = left[i][j], -right[i][j]
        for r, i in ((6, 2), (7, 3)):              # free end
            for j in range(4):
                M[r, 4 + j] = end[i][j]
    return M, R, up


def _mp_args(mp, beta, params):
    names = ("k", "L", "H", "kvv", "kll", "kvl", "mu", "gamma", "rho_g")
    defaults = {"kll": 0.0, "kvl": 0.0, "mu": 0.0, "gamma": 1.0, "rho_g": 0.0}
    return mp.mpmathify(beta), {n: mp.mpmathify(params.get(n, defaults.get(n))) for n in names}


def spot_response_mp(beta, sigmas, *, dps=60, check=False, **params):
    """``[(slopes, deflections)]`` per ``sigma`` in ``sigmas``, each a tuple over :data:`DRIVES`
    (mpmath numbers at ``dps`` significant digits); arguments as :func:`spot_response` but
    ``beta != 0`` (complex allowed, as are complex springs, ``k`` and ``mu``)."""
    mp = mpmath.mp
    with mp.workdps(dps + _extra_digits(beta)):
        b, p = _mp_args(mp, beta, params)
        M, R, up = _mp_system(mp, b, **p)
        columns = [mp.lu_solve(M, R.column(d)) for d in range(len(DRIVES))]
        kappa, a, L = b / p["L"], p["gamma"] * p["L"], p["L"]
        out = []
        for sigma in sigmas:
            x = mp.mpmathify(sigma) * L
            beyond = p["gamma"] != 1 and x > a
            B = _mp_basis(mp, kappa, x - a if beyond else x)
            off = 4 if beyond else 0
            slopes = tuple(sum(B[1][j] * c[off + j] for j in range(4)) for c in columns)
            defl = tuple(sum(B[0][j] * c[off + j] for j in range(4)) + (up if d == 3 else 0)
                         for d, c in enumerate(columns))
            out.append((tuple(+v for v in slopes), tuple(+v for v in defl)))
    if check:
        finer = spot_response_mp(beta, sigmas, dps=dps + 20, **params)
        for (s, d), (s2, d2) in zip(out, finer):
            for v, w in zip(s + d, s2 + d2):
                assert abs(v - w) <= mpmath.mpf(10) ** (-dps + 5) * abs(w), (beta, v, w)
    return out


def determinant_mp(beta, *, dps=40, **params):
    """The determinant of :func:`spot_response_mp`'s system (its zeros in ``beta`` are the resonances)."""
    mp = mpmath.mp
    with mp.workdps(dps + _extra_digits(beta)):
        b, p = _mp_args(mp, beta, params)
        return +mp.det(_mp_system(mp, b, **p)[0])
