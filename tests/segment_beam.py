"""Independent reference: the exact beam solved numerically on two segments (NumPy only).

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
