"""The composed lever in ball arithmetic: its characteristic function and its blind-spot numerator.

The pieces of ``generated/lever_pieces.py`` (field matrix, tip jump, load) multiplied together by
transfer matrices in any math namespace ``m`` with ``cos``, ``sin``, ``exp``: python-flint balls
and series (``generated.characteristic.FLINT``), exact rational series, mpmath.  Only sums and
products of entire functions are formed, so a series at ``beta = 0`` never divides by zero.

State ``z = [u, u_xi/beta, u_xixi/beta**2, u_xixixi/beta**3]``; a segment of length ``l``
(fractions of ``L``) maps it by ``F(beta l)``, ``F[n][j] = K[(j - n) % 4]``, ``K = (S, T, U, V)``
the Krylov-Duncan functions.  The tip maps ``z -> T z`` with ``T = I - J`` (``J`` the moment and
shear rows of :func:`~pfmdyn.generated.lever_pieces.point_jump`).  ``J`` carries ``1/beta**3``:
here ``beta**3 T`` is formed instead, from the jump's homogeneity
``beta**3 J(beta; H, mu, rho_g) = J(1; beta H, beta**4 mu, beta rho_g)`` (each term of the jump is
a monomial), so every entry is a polynomial in ``beta``.
"""
from __future__ import annotations

import flint

from ..generated.lever_pieces import KD_WEIGHTS, krylov_duncan_closed, point_jump

__all__ = ["characteristic_balls", "q0_slope_coefficients", "q0_slope"]

BRANCHES = ("before", "beyond")
"""The spot's branches: before the tip (``0 < sigma <= gamma``), beyond it (``gamma <= sigma <= 1``)."""


PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
"""Index pairs of the 2x2 minors (the second compound matrices)."""


def _minor_weights(rows, cols):
    """Integer weights of ``4 det F[rows][:, cols]`` on ``1, ch c, ch s, sh c, sh s, c c, c s, s s``.

    The products of two Krylov-Duncan functions expanded; ``cosh**2 - sinh**2 = 1`` removes the
    hyperbolic squares (a minor of ``F(s)`` grows like ``exp(s)``, not ``exp(2 s)``).
    """
    (n1, n2), (j1, j2) = rows, cols
    p, q, r, t = (KD_WEIGHTS[(j - n) % 4] for n, j in ((n1, j1), (n2, j2), (n1, j2), (n2, j1)))
    C = [[p[i] * q[j] - r[i] * t[j] for j in range(4)] for i in range(4)]
    assert C[0][0] + C[1][1] == 0 and C[0][1] + C[1][0] == 0, "a minor growing like exp(2 s)"
    return (C[0][0], C[0][2] + C[2][0], C[0][3] + C[3][0], C[1][2] + C[2][1], C[1][3] + C[3][1],
            C[2][2], C[2][3] + C[3][2], C[3][3])


_MINOR_WEIGHTS = {(I, J): _minor_weights(I, J) for I in PAIRS for J in PAIRS}


def _field(s, m):
    """The segment's field matrix ``F(s)`` as nested lists."""
    K = krylov_duncan_closed(s, m)
    return [[K[(j - n) % 4] for j in range(4)] for n in range(4)]


def _taylor_minors():
    """Exact Taylor coefficients, to degree ``_DEGREE``, of every 2x2 minor of ``F(s)``."""
    cap, flint.ctx.cap = flint.ctx.cap, _DEGREE + 1
    try:
        s = flint.fmpq_series([0, 1], prec=_DEGREE + 1)
        e, c, sn = s.exp(), s.cos(), s.sin()
        ch, sh = (e + 1 / e) / 2, (e - 1 / e) / 2
        basis = (1, ch * c, ch * sn, sh * c, sh * sn, c * c, c * sn, sn * sn)
        return {key: [(n, flint.fmpq(x) / 4) for n, x in enumerate(sum(w * b for w, b in zip(weights, basis) if w)
                                                                  .coeffs()) if x != 0]
                for key, weights in _MINOR_WEIGHTS.items()}
    finally:
        flint.ctx.cap = cap


_DEGREE = 40
_TAYLOR_MINORS = _taylor_minors()


def _field_minors(s, m, keys):
    """The 2x2 minors ``keys`` of ``F(s)``, ``{(rows, cols): value}``: sums of products of
    ``exp(s)``, ``cos``, ``sin`` (growing like ``exp(s)``); for python-flint ``|s| <= 1/2`` the exact
    Taylor polynomial and a remainder ball instead (the closed form cancels near 0, where a ball
    over an interval would be far wider than the minor)."""
    if isinstance(s, flint.fmpq_series) or (isinstance(s, flint.arb_series) and abs(s[0]).upper() <= 0.5):
        powers = [1, s]
        for _ in range(_DEGREE - 1):
            powers.append(powers[-1] * s)
        tail = _remainder(s) if isinstance(s, flint.arb_series) else 0
        return {key: sum(c * powers[n] for n, c in _TAYLOR_MINORS[key]) + tail for key in keys}
    e, c, sn = m.exp(s), m.cos(s), m.sin(s)
    ch, sh = (e + 1 / e) / 2, (e - 1 / e) / 2
    basis = (1, ch * c, ch * sn, sh * c, sh * sn, c * c, c * sn, sn * sn)
    return {key: sum(w * b for w, b in zip(_MINOR_WEIGHTS[key], basis) if w) / 4 for key in keys}


def _remainder(s):
    """A ball series holding the Taylor remainder beyond ``_DEGREE`` of any minor at ``s``, ``|s(0)| <= 1/2``.

    A minor's ``n``-th coefficient is at most ``2 * 2**n / n!`` (weights ``w / 4`` summing to at
    most 5/4; basis coefficients at most ``2**n / n!``), so the remainder's ``k``-th derivative
    over ``k!`` at ``|x| <= 1/2`` is below ``2 * 2**k / k! * 2 / (_DEGREE + 1 - k)!``; composed
    with ``s(t) = s(0) + u(t)`` as a series in ``u``.
    """
    n = len(s.coeffs())
    u = s - s[0]
    out = 0
    for k in reversed(range(n)):
        bound = 4 * flint.arb(2) ** k / flint.arb(k).fac() / flint.arb(_DEGREE + 1 - k).fac()
        out = out * u + flint.arb(0, bound.upper())
    return out


def _wedge(x, y):
    return {I: x[I[0]] * y[I[1]] - x[I[1]] * y[I[0]] for I in PAIRS}


def _lever(beta, m, k, kvv, kll, kvl, H, L, mu, gamma, rho_g):
    """The pieces, clamp to free end: ``F(gamma beta)``, its minors, ``beta**3 J``, ``beta**3 T``,
    the minors of ``beta**3 T``, and the minors of ``F((1 - gamma) beta)``."""
    J = point_jump(1, k, kvv, kll, kvl, H * beta, L, mu * beta**4, rho_g * beta)[:4]
    b3 = beta**3
    T = [[b3, 0, 0, 0], [0, b3, 0, 0], [-J[0], -J[1], b3, 0], [-J[2], -J[3], 0, b3]]
    T2 = {(I, K): T[I[0]][K[0]] * T[I[1]][K[1]] - T[I[0]][K[1]] * T[I[1]][K[0]] for I in PAIRS for K in PAIRS}
    a = gamma * beta
    columns = [(I, (2, 3)) for I in PAIRS] + [(I, (0, 2)) for I in PAIRS] + [(I, (0, 3)) for I in PAIRS]
    return (_field(a, m), _field_minors(a, m, columns), J, T, T2,
            _field_minors(beta - a, m, [((2, 3), I) for I in PAIRS]))


def _through_tip(T2, w):
    """``(T x) ^ (T y)`` from ``w = x ^ y``."""
    return {I: sum(T2[I, K] * w[K] for K in PAIRS) for I in PAIRS}


def _at_end(Fb2, w):
    """``det`` of rows 2, 3 of ``[F x, F y]`` (the free end's moment and shear) from ``w = x ^ y``."""
    return sum(Fb2[(2, 3), I] * w[I] for I in PAIRS)


def _determinant(Fa2, T2, Fb2):
    return _at_end(Fb2, _through_tip(T2, {I: Fa2[I, (2, 3)] for I in PAIRS}))


def characteristic_balls(beta, m, k, kvv, kll, kvl, H, L, mu, gamma, rho_g):
    """The lever's characteristic function: its real zeros ``beta > 0`` are the resonances.

    ``det M`` with ``M`` the free end's moment and shear (rows 2, 3 of
    ``F((1 - gamma) beta) beta**3 T F(gamma beta)``) per unit clamp moment and shear (columns 2,
    3): ``beta**6`` times the determinant of the unscaled transfer.  Entire in ``beta``, with a
    zero of order 6 at ``beta = 0`` (the static lever's determinant is positive).  Formed by
    Cauchy-Binet from the closed-form 2x2 minors of the segments, so the ``exp(2 beta)`` terms of
    the plain product never appear: a ball over an interval stays tight at any ``beta``.

    Parameters
    ----------
    beta : python-flint ``arb``, ``arb_series`` or exact ``fmpq_series`` (or an mpmath number)
    m : math namespace with ``cos``, ``sin``, ``exp`` (``generated.characteristic.FLINT``, mpmath)
    k, kvv, kll, kvl, H, L, mu, gamma, rho_g : ``arb`` or ``fmpq`` (or numbers of ``m``), as in
        ``generated/lever_pieces.py``; ``0 < gamma <= 1``

    Returns
    -------
    the determinant, of ``beta``'s type

    Examples
    --------
    >>> import flint
    >>> from pfmdyn.generated.characteristic import FLINT
    >>> args = [flint.arb(v) for v in (2.0, 150.0, 40.0, 3.0, 1e-05, 0.00022, 0.2, 0.9, 0.01)]
    >>> characteristic_balls(flint.arb(5), FLINT, *args) < 0 < characteristic_balls(flint.arb(4), FLINT, *args)
    True
    >>> exact = characteristic_balls(flint.fmpq_series([0, 1], prec=8), FLINT, *[flint.fmpq(1, 2)] * 9)
    >>> [int(c != 0) for c in exact.coeffs()]
    [0, 0, 0, 0, 0, 0, 1]
    """
    _, Fa2, _, _, T2, Fb2 = _lever(beta, m, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)
    return _determinant(Fa2, T2, Fb2)


def q0_slope_coefficients(m, *, beta, gamma, mu, rho_g, kvv_over_k, kll_ratio, kvl_ratio):
    """Coefficients ``(A, B, C, E, F)`` of the slope numerator per unit ``q0``, for each branch.

    The slope at ``sigma L`` per unit uniform load is ``N(sigma) / D`` with ``D`` independent of
    the spot; ``N = A cos(sigma beta) + B sin(sigma beta) + C cosh(sigma beta) + E sinh(sigma
    beta) + F`` on each branch (``F = 0``: a constant deflection has no slope).  ``N`` is the
    scaled slope ``z[1]`` per unit load constant ``-3 L / (k beta**4)``, times ``beta**3`` and
    :func:`characteristic_balls` (at ``k = H = L = 1``): one function on both branches,
    continuous at the tip; its zeros in ``sigma`` are the blind spots.  The clamp's moment and
    shear come from Cramer's rule on the minors (as the determinant); beyond the tip the point
    forces are carried back to ``sigma = 0`` by ``F(-gamma beta)``, so there the coefficients
    grow like ``exp(gamma beta)`` (as the cancellation in ``N``).

    Parameters
    ----------
    m : math namespace with ``cos``, ``sin``, ``exp`` (``generated.characteristic.FLINT``, mpmath)
    beta, gamma, mu, rho_g : real numbers of ``m`` (``arb``); ``0 < gamma <= 1``
    kvv_over_k, kll_ratio, kvl_ratio : ``kvv / k``, ``kll H**2 / (k L**2)``, ``kvl H / (k L)``

    Returns
    -------
    dict
        ``{"before": (A, B, C, E, F), "beyond": (A, B, C, E, F)}``

    Examples
    --------
    >>> import mpmath
    >>> c = q0_slope_coefficients(mpmath, beta=mpmath.mpf(2), gamma=mpmath.mpf(1), mu=0, rho_g=0,
    ...                           kvv_over_k=0, kll_ratio=0, kvl_ratio=0)
    >>> [f"{float(q0_slope(x, mpmath, c['before'], 2) / q0_slope(1, mpmath, c['before'], 2)):.6f}" for x in (0.5, 1)]
    ['0.836236', '1.000000']
    """
    Fa, Fa2, J, T, T2, Fb2 = _lever(beta, m, 1, kvv_over_k, kll_ratio, kvl_ratio, 1, 1, mu, gamma, rho_g)
    b3, e0 = beta**3, [1, 0, 0, 0]
    column = [[Fa[n][j] for n in range(4)] for j in range(4)]
    tip = [[sum(T[n][j] * x[j] for j in range(4)) for n in range(4)] for x in column]     # T F(a) e_j
    loaded = [e0[n] - column[0][n] for n in range(4)]                 # the load from a clamp at rest
    # Cramer: det M z[2:](0) = -(det[r, M e_3], det[M e_2, r]), r = F(b) (T loaded - b3 e0) rows 2, 3.
    load_3 = {I: w - Fa2[I, (0, 3)] for I, w in _wedge(e0, column[3]).items()}        # loaded ^ F e_3
    load_2 = {I: w + Fa2[I, (0, 2)] for I, w in _wedge(column[2], e0).items()}        # F e_2 ^ loaded
    clamp = [-_at_end(Fb2, {I: w - b3 * v for (I, w), v in
                            zip(_through_tip(T2, load_3).items(), _wedge(e0, tip[3]).values())}),
             -_at_end(Fb2, {I: w - b3 * v for (I, w), v in
                            zip(_through_tip(T2, load_2).items(), _wedge(tip[2], e0).values())})]
    det = _determinant(Fa2, T2, Fb2)
    before = [-b3 * det, 0, b3 * clamp[0], b3 * clamp[1]]             # b3 det (z(0) - e0)
    u, slope = (column[2][n] * clamp[0] + column[3][n] * clamp[1] + det * loaded[n] for n in (0, 1))
    moment, shear = J[0] * u + J[1] * slope, J[2] * u + J[3] * slope     # b3 det times the tip's jumps
    back = _field(-gamma * beta, m)
    beyond = [before[n] - back[n][2] * moment - back[n][3] * shear for n in range(4)]
    return {name: _trigonometric(v) for name, v in zip(BRANCHES, (before, beyond))}


def _trigonometric(v):
    """``(A, B, C, E, F)`` of ``F[1] (s) @ v = v0 V + v1 S + v2 T + v3 U`` in cos, sin, cosh, sinh of ``s``."""
    return ((v[1] - v[3]) / 2, (v[2] - v[0]) / 2, (v[1] + v[3]) / 2, (v[0] + v[2]) / 2, 0)


def q0_slope(sigma, m, coefficients, beta):
    """The slope numerator ``A cos(s) + B sin(s) + C cosh(s) + E sinh(s) + F``, ``s = sigma beta``.

    Parameters
    ----------
    sigma : the spot ``x_s / L`` (a number of ``m``, or a python-flint ``arb_series``)
    m : math namespace with ``cos``, ``sin``, ``exp``
    coefficients : one branch of :func:`q0_slope_coefficients`
    beta : as given to :func:`q0_slope_coefficients`

    Examples
    --------
    >>> import mpmath
    >>> abs(round(float(q0_slope(mpmath.mpf(0.5), mpmath, (1, 0, 1, 0, 0), 2) - mpmath.cos(1) - mpmath.cosh(1)), 15))
    0.0
    """
    s = sigma * beta
    e = m.exp(s)
    A, B, C, E, F = coefficients
    return A * m.cos(s) + B * m.sin(s) + C * (e + 1 / e) / 2 + E * (e - 1 / e) / 2 + F
