"""The composed lever's characteristic: the determinant of the assembled system, written out from the
segments' values (:func:`_transferred`), and its partials.

The determinant is scaled to be continuous across the two bases (by ``e^{-beta l}`` per short
segment) and formed without assembling: the Schur complements of the clamp's rows and of the segment
beyond the tip, each step explained where it is written (:func:`_short_from_clamp`,
:func:`_long_from_clamp`, :func:`_short_to_free_end`, :func:`_long_to_free_end`); with the tip at the
end the partials too (:func:`_tip_at_end_and_partials`), otherwise the assembled system's adjugate.
Separate because a root bracket reads only this (and its sign); the compiled kernels
(:func:`pfmdyn.composed.kernels.characteristic`) follow :func:`_transferred` step for step, and the
tests hold both to :func:`pfmdyn.composed.assembly._scaled_det`.
"""
from __future__ import annotations

import numpy as np

from .. import composed
from ..generated import lever_pieces as pieces
from .assembly import _adjugate, _Lever, _scaled_det
from .parameters import _POINT, JACOBIAN_PARAMETERS, Parameters
from .segments import _BOUNDED_AT_START, _CIRCULANT, _columns


def _by_basis(s, short, long):
    """The arrays (frequencies last) ``short(s)`` gives where ``|s| <= 1`` (the Krylov-Duncan field
    matrix) and ``long(s)`` elsewhere (the bounded basis), as the assembled system chooses (``s`` flat)."""
    is_short = np.abs(s) <= pieces.KD_SERIES_LIMIT
    if is_short.all() or not is_short.any():
        return (short if is_short.all() else long)(s)
    # the bounded basis is finite at any s: everywhere, then the short members overwritten
    out = [np.array(x, np.result_type(s, float)) for x in long(s)]
    for o, x in zip(out, short(s[is_short])):
        o[..., is_short] = x
    return out


def _short_from_clamp(s, derivative=False):
    """A short segment from the clamp: its state at the end per unit of the two unknowns the clamp
    leaves, ``R[m, c]``: its unknowns are its state at the clamp, which zeroes the first two, so ``R``
    is the field matrix's last two columns; and its factor in :func:`_scaled_det`.  With
    ``derivative``, also ``d R/d s`` and ``d log(factor)/d s``."""
    s_1, t, u, v = pieces.krylov_duncan(s)
    K = np.array((s_1 + 1.0, t, u, v))
    out = K[_CIRCULANT[:4, 2:]], np.exp(-s)
    return out + (K[_CIRCULANT[1:, 2:]], np.full(len(s), -1.0)) if derivative else out


def _long_from_clamp(s, derivative=False):
    """:func:`_short_from_clamp` in the bounded basis: the clamp's rows read ``[I, B]``, so
    ``R = E[:, 2:] - E[:, :2] B``; ``s`` moves the segment's end and, in the basis' ``e^{s - s_end}``
    column, its start (``B``'s second column)."""
    rows = np.array(pieces.bounded_basis(s, s)[:20 if derivative else 16]).reshape(-1, 4, len(s))
    at_clamp = pieces.bounded_basis(0.0, s)
    B = np.empty((4, len(s)), np.result_type(s, float))     # contiguous per entry: the products stream
    for i, j in enumerate((2, 3, 6, 7)):
        B[i] = at_clamp[j]
    B = B.reshape(2, 2, -1)
    clamped = lambda E: E[:, 2:] - E[:, 0, None] * B[0] - E[:, 1, None] * B[1]  # noqa: E731
    E = rows[:4]
    out = clamped(E), np.full(len(s), 1.0 / _BOUNDED_AT_START)
    if not derivative:
        return out
    dE = rows[1:].copy()
    dE[:, 3] -= E[:, 3]
    dR = clamped(dE)
    dR[:, 1] += E[:, 0] * B[0, 1] + E[:, 1] * B[1, 1]
    return out + (dR, np.zeros(len(s)))


def _across_tip(R, J):
    """Rows 2, 3 of the state beyond the tip per clamp unknown, ``R[2:] - J R[:2]`` (nested lists)."""
    return [[R[m, c] - J[2 * m - 4] * R[0, c] - J[2 * m - 3] * R[1, c] for c in (0, 1)] for m in (2, 3)]


_PAIRS = np.array([(i, j) for i in range(4) for j in range(i + 1, 4)])
"""Index pairs of the 2 x 2 minors; reversed, each pair's complement."""
_SIGNS = (-1.0) ** (_PAIRS.sum(1)[:, None] + _PAIRS.sum(1)[None, :])


def _minors(X, rows, cols):
    """``det X[r][:, c]`` for the index pairs ``r`` in ``rows``, ``c`` in ``cols`` (X stacked, frequencies last)."""
    r, c = rows[:, None], cols[None, :]
    return X[r[..., 0], c[..., 0]] * X[r[..., 1], c[..., 1]] - X[r[..., 0], c[..., 1]] * X[r[..., 1], c[..., 0]]


def _short_to_free_end(s):
    """A short segment ending free: the weights ``v[K]`` of the minors of the state it starts from
    (rows ``K``, :data:`_PAIRS`, of two states) in the system's determinant, the minors of the free
    end's moment and shear rows of the field matrix (its unknowns are that state: Cauchy-Binet);
    and its factor in :func:`_scaled_det`."""
    s_1, t, u, v = pieces.krylov_duncan(s)
    G = np.array((s_1 + 1.0, t, u, v))[_CIRCULANT[2:4]]
    return _minors(G, _PAIRS[:1], _PAIRS)[0], np.exp(-s)


def _long_to_free_end(s):
    """:func:`_short_to_free_end` in the bounded basis: the segment's unknowns eliminated, the
    determinant is ``det(G E^-1 T) det E`` (``E`` its rows at the start, ``G`` the free end's); by
    Cauchy-Binet and Jacobi's complementary minors it is ``sum g_I (-1)^(I + K) det E[K', I'] t_K``:
    bounded terms, where ``G E^-1`` grows as ``e^s`` in both rows (and their 2 x 2 determinant
    would cancel)."""
    E = np.array(pieces.bounded_basis(np.zeros_like(s), s)[:16] + pieces.bounded_basis(s, s)[8:16]).reshape(6, 4, -1)
    g = _minors(E[4:], _PAIRS[:1], _PAIRS)[0]
    others = _PAIRS[::-1]
    return np.einsum("in,kin->kn", g, _SIGNS[..., None] * _minors(E[:4], others, others)), \
        np.full(len(s), 1.0 / _BOUNDED_AT_START)


def _transferred(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g):
    """:func:`characteristic` without assembling the system.  The segment from the clamp gives the
    tip's state per unit of the two unknowns the clamp leaves, ``R`` (4 x 2); the tip's jump ``J``
    maps it across, ``T = R`` but for rows 2, 3, ``R[2:] - J R[:2]``.  With the tip at the end the
    determinant is ``det T[2:]`` (the Schur complement of the clamp's rows); with a segment beyond,
    ``sum_K v[K] det T[K]`` over the row pairs ``K`` (:func:`_long_to_free_end`).  Times the
    segments' factors, written out over the arguments' broadcast shape; the segments depend on
    ``beta`` and ``gamma`` alone: evaluated once for a grid of springs.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> lever = _Lever(*args)           # the assembled system it stands for
    >>> f"{_transferred(*args) / _scaled_det(lever)[0][0]:.12f}"
    '1.000000000000'
    """
    beta, g = np.asarray(beta), np.real(np.asarray(gamma))
    if g.ndim and (g == g.flat[0]).all():           # one tip position: the segments once per beta
        g = g.flat[0]
    s = beta * g
    R, factor = (x.reshape(x.shape[:-1] + s.shape) for x in _by_basis(s.reshape(-1), _short_from_clamp,
                                                                        _long_from_clamp))
    T = [[R[0, 0], R[0, 1]], [R[1, 0], R[1, 1]]] + _across_tip(R, pieces.point_jump(beta, k, kvv, kll, kvl, H, L, mu,
                                                                                        rho_g))
    if not _tip_at_end(g):
        s = beta * (1.0 - g)
        v, beyond = _by_basis(s.reshape(-1), _short_to_free_end, _long_to_free_end)
        v, factor = v.reshape((6,) + s.shape), factor * beyond.reshape(s.shape)
        return sum(v[K] * (T[i][0] * T[j][1] - T[i][1] * T[j][0]) for K, (i, j) in enumerate(_PAIRS)) * factor
    return (T[2][0] * T[3][1] - T[2][1] * T[3][0]) * factor


def characteristic(beta, parameters: Parameters):
    """The composed lever's characteristic: its zeros in ``beta`` are the resonances.

    The determinant of the assembled system, scaled (by ``e^{-beta l}`` per short segment) so that it
    is one analytic function of ``beta`` whichever basis each segment uses; formed without assembling
    the system (:func:`_transferred`).

    Examples
    --------
    >>> from scipy.optimize import brentq
    >>> free = Parameters(k=2.0, kvv=0.0, kll=0.0, kvl=0.0, H=1e-5, L=2e-4, mu=0.0, gamma=1.0, rho_g=0.0)
    >>> f = lambda b: characteristic(b, free)
    >>> round(brentq(f, 1.5, 2.5), 10)          # the free lever's first root
    1.8751040687
    """
    if composed.KERNELS:
        return _compiled_characteristic(beta, *parameters)
    return _shaped(_transferred(beta, *parameters), parameters.gamma)


def _compiled_characteristic(*args):
    """:func:`characteristic` by the compiled kernel (:func:`pfmdyn.composed.kernels.characteristic`,
    :func:`_transferred` step for step) for one lever or a column of levers against a row of ``beta``
    (other shapes: :func:`_transferred`).

    >>> args = (np.linspace(0.5, 30.0, 7), 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> bool(np.allclose(_compiled_characteristic(*args), _transferred(*args), rtol=1e-13, atol=0))
    True
    """
    from . import kernels

    arrays = [np.asarray(a) for a in args]
    dtype = np.result_type(*arrays, float)
    if all(a.ndim == 0 for a in arrays[1:]):        # one lever: its parameters once
        params, shape = np.array([[a.item() for a in arrays[1:]]], dtype), arrays[0].shape
    elif arrays[0].ndim == 1 and all(a.shape in ((), (a.size, 1)) for a in arrays[1:]):
        # levers as a column against a row of beta (a start grid's)
        shape = np.broadcast_shapes(*(a.shape for a in arrays))
        params = np.stack([np.broadcast_to(a, shape[:1] + (1,))[:, 0] for a in arrays[1:]], -1).astype(dtype)
    else:
        return _shaped(_transferred(*args), args[8])
    out = np.empty((len(params), arrays[0].size), dtype)
    # beta copied: writable (a read-only view compiles again) and flat
    kernels.characteristic(np.array(arrays[0], dtype).reshape(-1), params, out)
    return out.reshape(shape)


def _tip_at_end(gamma) -> bool:
    """Whether the tip is at the free end throughout: one segment."""
    if isinstance(gamma, float):            # one lever (a fit's): no array to build
        return gamma == 1.0
    return bool(np.all(np.asarray(gamma) == 1.0))


def _shaped(out, gamma):
    """``out`` as an array of the arguments' broadcast shape (``gamma`` may be wider than the rest)."""
    if isinstance(gamma, float):            # a number widens nothing
        return np.asarray(out)
    shape = np.broadcast_shapes(np.shape(out), np.shape(gamma))
    return np.asarray(out) if np.shape(out) == shape else np.broadcast_to(out, shape).copy()


def _tip_at_end_and_partials(beta, k, kvv, kll, kvl, H, L, mu, rho_g, names):
    """:func:`_transferred` with the tip at the end (``det T[2:]`` times the segment's factor) and its
    partials ``{name: value}`` w.r.t. ``names`` (of :data:`JACOBIAN_PARAMETERS` but ``gamma``), by the
    product rule: the tip's parameters move ``J`` alone, ``beta`` also the segment and its factor.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.05)
    >>> det, partials = _tip_at_end_and_partials(*args, ["beta", "kvv"])
    >>> step = 1e-6
    >>> up, down = (_tip_at_end_and_partials(2.5 + h, *args[1:], [])[0] for h in (step, -step))
    >>> f"{partials['beta'] / ((up - down) / (2 * step)):.6f}"
    '1.000000'
    """
    beta = np.asarray(beta)
    R, factor, dR, d_log = (x.reshape(x.shape[:-1] + beta.shape) for x in _by_basis(
        beta.reshape(-1), lambda s: _short_from_clamp(s, True), lambda s: _long_from_clamp(s, True)))
    point = (beta, k, kvv, kll, kvl, H, L, mu, rho_g)
    J, dJ = pieces.point_jump(*point), pieces.point_jump_partials(*point, wrt=names)
    T = _across_tip(R, J)
    det = T[0][0] * T[1][1] - T[0][1] * T[1][0]
    partials = {}
    for name in names:
        moved = _across_tip(np.concatenate([R[:2], np.zeros_like(R[2:])]), dJ[name])   # -dJ R[:2]
        if name == "beta":
            moved = [[a + b for a, b in zip(*rows)] for rows in zip(moved, _across_tip(dR, J))]
        d = moved[0][0] * T[1][1] + T[0][0] * moved[1][1] - moved[0][1] * T[1][0] - T[0][1] * moved[1][0]
        partials[name] = (d + det * d_log if name == "beta" else d) * factor
    return det * factor, partials


def _compiled_tip_at_end(beta, k, kvv, kll, kvl, H, L, mu, rho_g, names):
    """:func:`_tip_at_end_and_partials` of one lever by the compiled kernel
    (:func:`pfmdyn.composed.kernels.tip_at_end_and_partials`).

    >>> args = (np.array([2.5, 7.0]), 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.05, ["beta", "kvv", "mu"])
    >>> (det, d), (want, d_want) = _compiled_tip_at_end(*args), _tip_at_end_and_partials(*args)
    >>> bool(np.allclose(det, want, rtol=1e-13, atol=0) and all(np.allclose(d[p], d_want[p], rtol=1e-12, atol=0) for p in d))
    True
    """
    from . import kernels

    beta = np.asarray(beta)
    dtype = np.result_type(beta, k, kvv, kll, kvl, mu, rho_g, float)
    flat = np.array(beta.reshape(-1), dtype)       # writable and C-ordered: one specialisation to compile
    point = (flat, k, kvv, kll, kvl, H, L, mu, rho_g)
    jump = _columns(pieces.point_jump(*point), len(flat), dtype)
    partials = pieces.point_jump_partials(*point, wrt=names)
    djump = np.ascontiguousarray(np.stack([_columns(partials[p], len(flat), dtype) for p in names])) if names \
        else np.zeros((0, len(flat), 12), dtype)
    out, d = np.empty(len(flat), dtype), np.empty((len(names), len(flat)), dtype)
    kernels.tip_at_end_and_partials(flat, jump, djump, names.index("beta") if "beta" in names else -1, out, d)
    return out.reshape(beta.shape), {p: d[i].reshape(beta.shape) for i, p in enumerate(names)}


def characteristic_and_jacobian(beta, parameters: Parameters, wrt=JACOBIAN_PARAMETERS):
    """:func:`characteristic` and its partials w.r.t. :data:`JACOBIAN_PARAMETERS` (None where not in ``wrt``).

    At a zero only their ratios matter: a resonance moves with ``p`` as ``d beta/d p = -D_p / D_beta``.

    Examples
    --------
    >>> free = Parameters(k=2.0, kvv=0.0, kll=0.0, kvl=0.0, H=1e-5, L=2e-4, mu=0.0, gamma=1.0, rho_g=0.0)
    >>> value, partials = characteristic_and_jacobian(1.8751040687, free)
    >>> round(float(-partials[5] / partials[0]), 6)     # d beta1 / d mu of a free lever: -beta1
    -1.875104
    """
    k, kvv, kll, kvl, H, L, mu, gamma, rho_g = parameters
    if "gamma" not in wrt and _tip_at_end(gamma):
        tip_at_end = _compiled_tip_at_end if composed.KERNELS and all(np.ndim(a) == 0 for a in (k, kvv, kll, kvl, H, L, mu, rho_g)) \
            else _tip_at_end_and_partials
        det, partials = tip_at_end(beta, k, kvv, kll, kvl, H, L, mu, rho_g, [p for p in JACOBIAN_PARAMETERS if p in wrt])
        return _shaped(det, gamma), tuple(_shaped(partials[p], gamma) if p in partials else None
                                          for p in JACOBIAN_PARAMETERS)
    lever = _Lever(beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, split="gamma" in wrt)
    det, d_beta, d_gamma, scale = _scaled_det(lever)
    # Jacobi's formula d det = tr(adj(A) dA), the adjugate from the SVD: finite at a resonance,
    # where A is singular and its inverse is not.
    adjugate = _adjugate(lever.A) * scale[:, None, None]
    at_tip = [p for p in JACOBIAN_PARAMETERS if p in wrt and p in _POINT and p != "beta"]
    partials = dict(zip(at_tip, lever.d_det_at_tip(adjugate, at_tip)))
    for name in (p for p in JACOBIAN_PARAMETERS if p in wrt and p not in partials):
        d = np.einsum("nij,nji->n", adjugate, lever.d_system_matrix(name))
        partials[name] = d + det * (d_beta if name == "beta" else d_gamma if name == "gamma" else 0.0)
    return lever.out(det), tuple(lever.out(partials[p]) if p in partials else None for p in JACOBIAN_PARAMETERS)
