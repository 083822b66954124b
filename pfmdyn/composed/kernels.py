"""Compiled kernels of the composed lever (:mod:`pfmdyn.composed`): the read-out per frequency, the
tip point, the characteristic, its roots and its partials.

The written-out read-out of :class:`pfmdyn.composed.written_out._WrittenOut` (each segment's outer rows
eliminated, the tip's 2 x 2 or 4 x 4 solved: well conditioned from the quasi-static ``beta`` up, where
the assembled system is not), step for step per member in a compiled loop (numba), with its partials
(those of ``gamma`` too, which the NumPy forms take from the assembled system): no NumPy call and no
allocation per member.  The NumPy forms are the reference: ``tests/test_fast_readouts.py`` holds
both fast paths to the assembled system and, where both lose digits alike, to the 70-digit beam.

Imported lazily by :mod:`pfmdyn.composed.readout` and :mod:`pfmdyn.composed.determinant` (numba's
import and the on-disk cache's load stay out of the command line's start-up).  One file, not one per
kernel: the kernels call shared compiled steps (:func:`_segment`, :func:`_inverse`, :func:`_product`),
and numba's on-disk cache is keyed on the caller's file alone, so a step edited in another file would
leave its callers' cached machine code stale.
"""
from __future__ import annotations

import numba
import numpy as np

from ..compiled import forget_when_changed
from ..generated import lever_pieces as pieces
from ..roots import bracket
from ..roots.bracket import _LOBATTO, _TO_CHEBYSHEV
from . import segments
from .segments import _BOUNDED_AT_START

__all__ = ["BETA", "SIGMA", "K", "GAMMA", "TIP", "COMPILED_FROM", "read_out", "tip_point", "characteristic",
           "characteristic_roots", "characteristic_partials"]

BETA, SIGMA, K, GAMMA, TIP = range(5)
"""How a parameter enters (the codes of :func:`read_out`'s ``kinds``): ``beta`` moves every
segment, the load and the tip; ``sigma`` the read point; ``k`` the load and the tip; ``gamma`` the
segments' ends; any other of the tip's parameters its jump alone."""
_SERIES = np.array(pieces.KD_SERIES)
_LIMIT = pieces.KD_SERIES_LIMIT
_Q0, _Y0, _DRIVES = 4, 5, 6
"""The load's and the base's columns among the drives (``d1, d2, f0, m0, q0, y0``)."""


_bounded_basis = numba.njit(cache=True)(pieces.bounded_basis)


@numba.njit(cache=True)
def _krylov_duncan(s):
    """``(S - 1, T, U, V)`` of ``|s| <= 1`` by their series (:func:`pfmdyn.generated.lever_pieces.krylov_duncan`:
    ``S - 1`` free of cancellation)."""
    u = s * s * s * s
    h0 = h1 = h2 = h3 = s * 0.0
    power = s * 0.0 + 1.0
    for j in range(_SERIES.shape[1]):
        h0, h1, h2, h3 = (h0 + _SERIES[0, j] * power, h1 + _SERIES[1, j] * power, h2 + _SERIES[2, j] * power,
                          h3 + _SERIES[3, j] * power)
        power = power * u
    s2 = s * s
    return s2 * s2 * h0, s * h1, s2 * h2, s2 * s * h3


@numba.njit(cache=True)
def _segment(beta, t, ell, uc, rows, load):
    """A segment of length ``ell`` read at ``t``: ``rows[n, j]`` the basis' ``d**n/ds**n`` (n = 0..4),
    ``load[n]`` the load's, per unit q0 (as :class:`pfmdyn.composed.segments._Segment`).  Returns whether it
    is short (the Krylov-Duncan field matrix; else the bounded basis)."""
    s = beta * t
    if abs(beta * ell) <= _LIMIT:
        s_1, tt, uu, vv = _krylov_duncan(s)
        kd = (s_1 + 1.0, tt, uu, vv)
        for m in range(5):
            for j in range(4):
                rows[m, j] = kd[(j - m) % 4]
        load[0], load[1], load[2], load[3], load[4] = -uc * s_1, -uc * vv, -uc * uu, -uc * tt, -uc * kd[0]
        return True
    basis = _bounded_basis(s, beta * ell)      # the generated piece, compiled: nothing typed here
    for m in range(5):
        for j in range(4):
            rows[m, j] = basis[4 * m + j]
    load[0] = uc
    for m in range(1, 5):
        load[m] = 0.0
    return False


@numba.njit(cache=True)
def _segment_derivative(kind, beta, t, ell, moves_end, moves_start, short, rows, load, lo, hi, dE, dP):
    """``(dE, dP)`` (rows ``lo`` to ``hi - 1``, those read) w.r.t. ``beta``, ``gamma`` or ``sigma`` (``kind``;
    :meth:`pfmdyn.composed.segments._Segment.derivative`); ``moves_end``, ``moves_start``: ``d ell/d gamma``,
    ``d t/d gamma``."""
    if kind == BETA:
        four_over = 4.0 / beta
        for m in range(lo, hi):
            for j in range(4):
                dE[m, j] = t * rows[m + 1, j]
            if not short:
                dE[m, 3] += ell * -rows[m, 3]
            dP[m] = t * load[m + 1] - load[m] * four_over
    elif kind == GAMMA:
        ds = moves_start * beta
        for m in range(lo, hi):
            for j in range(4):
                dE[m, j] = ds * rows[m + 1, j]
            if not short:
                dE[m, 3] += moves_end * beta * -rows[m, 3]
            dP[m] = ds * load[m + 1]
    else:
        for m in range(lo, hi):
            for j in range(4):
                dE[m, j] = beta * rows[m + 1, j]
            dP[m] = beta * load[m + 1]


@numba.njit(cache=True)
def _inverse(M, out, work, pivots):
    """``M^-1`` into ``out`` (2 x 2 by the adjugate, larger by LU with partial pivoting, as
    :func:`pfmdyn.composed.written_out._small_inverse`); False where ``M`` is singular."""
    n = M.shape[0]
    if n == 2:
        det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
        if det == 0:
            return False
        out[0, 0], out[0, 1], out[1, 0], out[1, 1] = M[1, 1] / det, -M[0, 1] / det, -M[1, 0] / det, M[0, 0] / det
        return True
    work[:, :] = M
    for c in range(n):
        p, size = c, abs(work[c, c])
        for r in range(c + 1, n):
            if abs(work[r, c]) > size:
                p, size = r, abs(work[r, c])
        if not (size > 0.0 and np.isfinite(size)):
            return False
        pivots[c] = p
        if p != c:
            for j in range(n):
                work[c, j], work[p, j] = work[p, j], work[c, j]
        for r in range(c + 1, n):
            f = work[r, c] / work[c, c]
            work[r, c] = f
            for j in range(c + 1, n):
                work[r, j] -= f * work[c, j]
    out[:, :] = 0.0
    for c in range(n):
        out[c, c] = 1.0
    for c in range(n):
        p = pivots[c]
        if p != c:
            for j in range(n):
                out[c, j], out[p, j] = out[p, j], out[c, j]
    for j in range(n):
        for r in range(n):
            for i in range(r):
                out[r, j] -= work[r, i] * out[i, j]
        for r in range(n - 1, -1, -1):
            for i in range(r + 1, n):
                out[r, j] -= work[r, i] * out[i, j]
            out[r, j] /= work[r, r]
    return True


@numba.njit(cache=True)
def _product(A, B, out):
    """``out = A @ B`` (small, no allocation)."""
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            v = 0j
            for m in range(A.shape[1]):
                v += A[i, m] * B[m, j]
            out[i, j] = v


@numba.njit(cache=True)
def _across(V, J, two, out):
    """What the tip's rows ask of a state ``V`` (4 x drives) left of it (:meth:`pfmdyn.composed.written_out._WrittenOut._across`):
    the jump's ``V[2:] - J V[:2]``, after continuity's ``V[:2]`` when a segment lies beyond."""
    first = 2 if two else 0
    for d in range(V.shape[1]):
        if two:
            out[0, d], out[1, d] = V[0, d], V[1, d]
        for r in range(2):
            out[first + r, d] = V[2 + r, d] - J[r, 0] * V[0, d] - J[r, 1] * V[1, d]


@numba.njit(cache=True)
def read_out(beta, sigma, gamma, uc, k, jump, djump, kinds, two, drives, z, dz):
    """The state ``[u, z1]`` at ``x = sigma L`` per unit of each drive, ``z[n, 2, c]``, and the partials of
    its slope ``z1``, ``dz[n, p, c]`` (what the read-outs ask), w.r.t. parameters of ``kinds`` (:data:`BETA` ...),
    per member ``n``, of the drives ``drives[c]`` (indices of ``d1, d2, f0, m0, q0, y0``; each drive's columns
    are solved alone, so the others are neither formed nor written): the
    written-out form of :class:`pfmdyn.composed.written_out._WrittenOut` (each segment's outer rows eliminated,
    the tip's 2 x 2 or 4 x 4 solved), step for step.

    ``jump[n, 12]`` the tip's point (:func:`pfmdyn.generated.lever_pieces.point_jump`), ``djump[p, n, 12]``
    its partials (zero for ``sigma`` and ``gamma``), ``uc`` the load constant; ``two``: the tip's
    point between two segments (set back, or at the end with ``gamma`` among the partials: the second
    of zero length), else the tip at the free end (``gamma`` unused).  NaN where the system is singular.

    Examples
    --------
    >>> beta, point = np.array([2.5 + 0j]), (2.5, 2.0, 98.0, 52.0, 9.0, 1e-5, 2e-4, 0.1, 0.05)
    >>> jump, uc = np.array([pieces.point_jump(*point)], complex), np.array([pieces.load_constant(2.5, 2.0, 2e-4)], complex)
    >>> z, dz = np.empty((1, 2, 6), complex), np.empty((1, 0, 6), complex)
    >>> read_out(beta, np.array([1.0]), np.array([1.0]), uc, np.array([2.0 + 0j]), jump, np.zeros((0, 1, 12), complex),
    ...          np.zeros(0, np.int64), False, np.arange(6), z, dz)
    >>> f"{(2.5 / 2e-4 * z[0, 1, 0]).real:.8g}"       # the slope at the free end per unit d1
    '5363.3808'
    """
    n, segments = beta.shape[0], 2 if two else 1
    batches = 2 * segments + 1                  # each segment's two ends, then the spot
    spot = batches - 1
    size = 2 * segments
    rows, load = np.empty((batches, 5, 4), np.complex128), np.empty((batches, 5), np.complex128)
    E, P = np.empty((batches, 4, 4), np.complex128), np.empty((batches, 4), np.complex128)
    short = np.empty(batches, np.bool_)
    t_at, ell_at = np.empty(batches), np.empty(batches)
    # how each read point moves with the tip: d ell / d gamma, d t / d gamma
    moves_end, moves_start = np.zeros(batches), np.zeros(batches)
    dE, dP = np.empty((4, 4), np.complex128), np.empty(4, np.complex128)
    B = np.empty((segments, 2, 2), np.complex128)
    b0 = np.zeros((segments, 2, _DRIVES), np.complex128)
    Gp_inv = np.empty((segments, 2, 2), np.complex128)
    R, w = np.empty((4, 2), np.complex128), np.zeros((4, _DRIVES), np.complex128)
    M, r = np.empty((size, size), np.complex128), np.zeros((size, _DRIVES), np.complex128)
    X = np.empty((size, 2), np.complex128)
    inverse, work = np.empty((size, size), np.complex128), np.empty((size, size), np.complex128)
    pivots = np.empty(size, np.int64)
    u = np.zeros((size, _DRIVES), np.complex128)
    coef = np.zeros((segments, 4, _DRIVES), np.complex128)
    J = np.empty((2, 2), np.complex128)
    z_tip = np.zeros((2, _DRIVES), np.complex128)
    e = np.zeros((batches, 4, _DRIVES), np.complex128)
    fixed = np.zeros((segments, 2, _DRIVES), np.complex128)
    share = np.zeros((4, _DRIVES), np.complex128)
    q, across = np.zeros((size, _DRIVES), np.complex128), np.zeros((size, _DRIVES), np.complex128)
    spot_row, spot_per_row = np.empty(2, np.complex128), np.empty(size, np.complex128)
    at_spot = np.zeros(_DRIVES, np.complex128)
    tmp2 = np.empty((2, 2), np.complex128)
    load_drive = drives[drives == _Q0]
    same_spot = -1
    for i in range(n):
        g = gamma[i] if two else 1.0
        before = (sigma[i] <= g) if two else True
        t_at[0], ell_at[0], t_at[1], ell_at[1] = 0.0, g, g, g
        if two:
            t_at[2], ell_at[2], t_at[3], ell_at[3] = 0.0, 1.0 - g, 1.0 - g, 1.0 - g
        t_at[spot] = sigma[i] if before else sigma[i] - g
        ell_at[spot] = g if before else 1.0 - g
        if two:
            moves_end[0], moves_end[1], moves_end[2], moves_end[3] = 1.0, 1.0, -1.0, -1.0
            moves_start[1], moves_start[3] = 1.0, -1.0
            moves_end[spot], moves_start[spot] = (1.0, 0.0) if before else (-1.0, -1.0)
        for b in range(batches):
            same = -1              # a spot at the tip or the free end reads their evaluation
            if b == spot:
                for a in range(1, spot, 2):
                    if t_at[a] == t_at[b] and ell_at[a] == ell_at[b]:
                        same = a
            if b == spot:
                same_spot = same
            if same >= 0:
                short[b] = short[same]
                rows[b], load[b] = rows[same], load[same]
                E[b], P[b] = E[same], P[same]
                continue
            short[b] = _segment(beta[i], t_at[b], ell_at[b], 1.0, rows[b], load[b])
            if two and short[b] and (b == 2 or b == 3 or (b == spot and not before)):
                for m in range(5):      # beyond the tip: the moment and shear first (_REORDERED)
                    a0, a1, a2, a3 = rows[b, m, 0], rows[b, m, 1], rows[b, m, 2], rows[b, m, 3]
                    rows[b, m, 0], rows[b, m, 1], rows[b, m, 2], rows[b, m, 3] = a2, a3, a0, a1
            for m in range(4):
                for j in range(4):
                    E[b, m, j] = rows[b, m, j]
                P[b, m] = uc[i] * load[b, m]
        for rr in range(2):
            for j in range(2):
                J[rr, j] = jump[i, 2 * rr + j]
        # the segments' outer rows eliminated: c = [b0 - B u, u]
        for rr in range(2):
            for j in range(2):
                B[0, rr, j] = E[0, rr, 2 + j]
            b0[0, rr, _Q0] = -P[0, rr]
        b0[0, 0, _Y0] = 1.0
        ok = True
        if two:
            for rr in range(2):
                for j in range(2):
                    tmp2[rr, j] = E[3, 2 + rr, j]
            ok = _inverse(tmp2, Gp_inv[1], work, pivots)
            for rr in range(2):
                for j in range(2):
                    B[1, rr, j] = Gp_inv[1, rr, 0] * E[3, 2, 2 + j] + Gp_inv[1, rr, 1] * E[3, 3, 2 + j]
                b0[1, rr, _Q0] = -(Gp_inv[1, rr, 0] * P[3, 2] + Gp_inv[1, rr, 1] * P[3, 3])
        # the tip's rows on the unknowns
        for seg in range(segments):
            at = 1 if seg == 0 else 2
            for m in range(4):
                for j in range(2):
                    R[m, j] = E[at, m, 2 + j] - (E[at, m, 0] * B[seg, 0, j] + E[at, m, 1] * B[seg, 1, j])
                for d in drives:
                    w[m, d] = E[at, m, 0] * b0[seg, 0, d] + E[at, m, 1] * b0[seg, 1, d]
                w[m, _Q0] += P[at, m]
            if seg == 0:
                _across(R, J, two, X)
                _across(w, J, two, r)
                for m in range(size):
                    for j in range(2):
                        M[m, j] = X[m, j]
                    for d in drives:
                        r[m, d] = -r[m, d]
                for rr in range(2):
                    for d in drives:
                        if d < 4:       # the jump drives d1, d2, f0, m0
                            r[size - 2 + rr, d] += jump[i, 4 + 4 * rr + d]
            else:
                for m in range(4):
                    M[m, 2], M[m, 3] = -R[m, 0], -R[m, 1]
                    for d in drives:
                        r[m, d] += w[m, d]
        ok = ok and _inverse(M, inverse, work, pivots)
        if not ok:
            z[i] = np.nan
            dz[i] = np.nan
            continue
        _product(inverse, r, u)
        for seg in range(segments):
            for m in range(2):
                for d in drives:
                    coef[seg, m, d] = b0[seg, m, d] - (B[seg, m, 0] * u[2 * seg, d] + B[seg, m, 1] * u[2 * seg + 1, d])
                    coef[seg, 2 + m, d] = u[2 * seg + m, d]
        on = 0 if before else 1
        for m in range(2):
            for c in range(drives.shape[0]):
                d = drives[c]
                value = E[spot, m, 0] * coef[on, 0, d] + E[spot, m, 1] * coef[on, 1, d] + \
                    E[spot, m, 2] * coef[on, 2, d] + E[spot, m, 3] * coef[on, 3, d]
                z[i, m, c] = value + P[spot, m] if d == _Q0 else value
                z_tip[m, d] = E[1, m, 0] * coef[0, 0, d] + E[1, m, 1] * coef[0, 1, d] + \
                    E[1, m, 2] * coef[0, 2, d] + E[1, m, 3] * coef[0, 3, d]
            z_tip[m, _Q0] += P[1, m]
        if kinds.shape[0] == 0:
            continue
        # the spot's slope per unit of the tip's rows: R inverse (R of its segment)
        for j in range(2):
            spot_row[j] = E[spot, 1, 2 + j] - (E[spot, 1, 0] * B[on, 0, j] + E[spot, 1, 1] * B[on, 1, j])
        for j in range(size):
            spot_per_row[j] = spot_row[0] * inverse[2 * on, j] + spot_row[1] * inverse[2 * on + 1, j]
        for p in range(kinds.shape[0]):
            kind = kinds[p]
            q[:, :] = 0.0
            for rr in range(2):             # the jump's change: dJ z_tip + dG d
                row = size - 2 + rr
                for d in drives:
                    q[row, d] = djump[p, i, 2 * rr] * z_tip[0, d] + djump[p, i, 2 * rr + 1] * z_tip[1, d]
                for d in drives:
                    if d < 4:
                        q[row, d] += djump[p, i, 4 + 4 * rr + d]
            moved = kind != TIP
            if moved:
                # k moves the load alone (its column), sigma the spot alone; a spot read where the tip or
                # the free end is moves as it with beta and k (not with gamma: the spot stays)
                moving = load_drive if kind == K else drives
                read = same_spot if same_spot >= 0 and (kind == BETA or kind == K) else spot
                for d in drives:
                    at_spot[d] = 0.0
                for b in range(batches):
                    if (kind == SIGMA and b != spot) or (b == spot and read != spot):
                        continue
                    # the rows read of each: the clamp's end and the free end's outer two (and the free end's
                    # slope where the spot reads it), the spot's slope
                    lo = 1 if b == spot or (b == 3 and read == 3) else 2 if b == 3 else 0
                    hi = 2 if b == spot or b == 0 else 4
                    c_seg = on if b == spot else b // 2
                    if kind == K:
                        for m in range(lo, hi):
                            e[b, m, _Q0] = -P[b, m] / k[i]
                        continue
                    _segment_derivative(kind, beta[i], t_at[b], ell_at[b], moves_end[b], moves_start[b], short[b],
                                        rows[b], load[b], lo, hi, dE, dP)
                    for m in range(lo, hi):
                        for d in drives:
                            e[b, m, d] = dE[m, 0] * coef[c_seg, 0, d] + dE[m, 1] * coef[c_seg, 1, d] + \
                                dE[m, 2] * coef[c_seg, 2, d] + dE[m, 3] * coef[c_seg, 3, d]
                        e[b, m, _Q0] += uc[i] * dP[m]
                if kind == SIGMA:           # nothing else moves: the spot's own change
                    for d in drives:
                        at_spot[d] = e[spot, 1, d]
                else:
                    # at fixed unknowns: less the eliminated rows' share
                    for m in range(2):
                        for d in moving:
                            fixed[0, m, d] = e[0, m, d]
                            if two:
                                fixed[1, m, d] = Gp_inv[1, m, 0] * e[3, 2, d] + Gp_inv[1, m, 1] * e[3, 3, d]
                    for d in moving:        # the spot's slope
                        at_spot[d] = e[read, 1, d] - (E[read, 1, 0] * fixed[on, 0, d] + E[read, 1, 1] * fixed[on, 1, d])
                    for role in range(2):   # the tip from the left, from the right
                        if role == 1 and not two:
                            continue
                        b, seg = (1, 0) if role == 0 else (2, 1)
                        for m in range(4):
                            for d in moving:
                                share[m, d] = e[b, m, d] - (E[b, m, 0] * fixed[seg, 0, d] +
                                                            E[b, m, 1] * fixed[seg, 1, d])
                        if role == 0:
                            _across(share, J, two, across)
                            for m in range(size):
                                for d in moving:
                                    q[m, d] -= across[m, d]
                        else:
                            for m in range(4):
                                for d in moving:
                                    q[m, d] += share[m, d]
            for c in range(drives.shape[0]):
                d = drives[c]
                v = 0j
                for j in range(size):
                    v += spot_per_row[j] * q[j, d]
                dz[i, p, c] = (at_spot[d] if moved else 0.0) + v


_point_jump = numba.njit(cache=True)(pieces.point_jump)
_d_beta, _d_k, _d_kvv, _d_kll, _d_kvl, _d_mu, _d_rho_g = (numba.njit(cache=True)(f) for f in pieces.POINT_JUMP_PARTIALS)
assert pieces.JACOBIAN_PARAMETERS == ("beta", "k", "kvv", "kll", "kvl", "mu", "rho_g")   # tip_point's branches


@numba.njit(cache=True)
def _store(values, out):
    """The 12 pieces of a jump (a tuple of numbers and literal zeros) into ``out``."""
    out[0], out[1], out[2], out[3], out[4], out[5] = values[0], values[1], values[2], values[3], values[4], values[5]
    out[6], out[7], out[8], out[9], out[10], out[11] = values[6], values[7], values[8], values[9], values[10], values[11]


@numba.njit(cache=True)
def tip_point(beta, k, kvv, kll, kvl, H, L, mu, rho_g, codes, jump, djump):
    """The tip's point per member as :func:`read_out` takes it: the jump ``jump[n, 12]``
    (:func:`pfmdyn.generated.lever_pieces.point_jump`) and its partials ``djump[p, n, 12]`` w.r.t.
    ``JACOBIAN_PARAMETERS[codes[p]]`` (zeros for -1), the generated expressions compiled; every argument
    an array (n): ``beta``, ``k``, ``kvv``, ``kll``, ``kvl``, ``mu`` complex, ``H``, ``L``, ``rho_g`` real.

    >>> point = (2.5 + 0j, 2.0 + 0j, 98.0 + 0j, 52.0 + 0j, 9.0 + 0j, 1e-5, 2e-4, 0.1 + 0j, 0.05)
    >>> arrays = [np.array([v]) for v in point]
    >>> jump, djump = np.empty((1, 12), complex), np.empty((2, 1, 12), complex)
    >>> tip_point(*arrays, np.array([0, -1]), jump, djump)
    >>> bool(np.allclose(jump[0], pieces.point_jump(*point), rtol=1e-15, atol=0)), bool(np.all(djump[1] == 0))
    (True, True)
    >>> bool(np.allclose(djump[0, 0], pieces.point_jump_partials(*point, wrt=("beta",))["beta"], rtol=1e-15, atol=0))
    True
    """
    n = beta.shape[0]
    for i in range(n):
        _store(_point_jump(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), jump[i])
    for p in range(codes.shape[0]):     # a loop per partial: a branch per member would cost several times more
        code, out = codes[p], djump[p]
        if code == 0:
            for i in range(n):
                _store(_d_beta(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 1:
            for i in range(n):
                _store(_d_k(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 2:
            for i in range(n):
                _store(_d_kvv(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 3:
            for i in range(n):
                _store(_d_kll(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 4:
            for i in range(n):
                _store(_d_kvl(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 5:
            for i in range(n):
                _store(_d_mu(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        elif code == 6:
            for i in range(n):
                _store(_d_rho_g(beta[i], k[i], kvv[i], kll[i], kvl[i], H[i], L[i], mu[i], rho_g[i]), out[i])
        else:               # a parameter the tip does not hold
            out[:, :] = 0.0


_PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
_PAIR_ROWS = np.array(_PAIRS)
_PAIR_SIGNS = (-1.0) ** (_PAIR_ROWS.sum(1)[:, None] + _PAIR_ROWS.sum(1)[None, :])
"""The pairs as an array (indexed in a loop) and the sign of each pair of minors in Jacobi's expansion."""
_START = np.array(pieces.bounded_basis(0.0, 0.0)[:16], dtype=float).reshape(4, 4)
_START_MINORS = _PAIR_SIGNS * np.array([[_START[r0, c0] * _START[r1, c1] - _START[r0, c1] * _START[r1, c0]
                                         for c0, c1 in _PAIRS[::-1]] for r0, r1 in _PAIRS[::-1]])
"""A segment's rows at its start in the bounded basis but the growing column's ``exp(-s_end)`` (1 here),
and their signed minors (row pairs :data:`_PAIRS` reversed, column pairs reversed): small integers, so a
minor times ``exp(-s_end)`` is exactly the minor of the rows themselves."""


@numba.njit(cache=True)
def characteristic(beta, params, out):
    """:func:`pfmdyn.composed.characteristic` of each lever ``params[r]`` (``k, kvv, kll, kvl, H, L, mu,
    gamma, rho_g``) at each ``beta[i]``, ``out[r, i]`` (``_transferred`` step for step): the clamp's
    segment per unit of its two unknowns ``R``, the tip's jump across, and with the tip set back the
    free segment's minors; times the segments' factors.  The segments depend on ``beta`` and ``gamma``
    alone: with one ``gamma`` for all levers (a start grid's), once per ``beta``.

    Examples
    --------
    >>> out = np.empty((1, 1))
    >>> characteristic(np.array([1.8751040687119611]), np.array([[2.0, 0, 0, 0, 1e-5, 2e-4, 0, 1.0, 0]]), out)
    >>> bool(abs(out[0, 0]) < 1e-15)                  # the free lever's first root
    True
    """
    rows, load = np.empty((5, 4), out.dtype), np.empty(5, out.dtype)
    R, T = np.empty((4, 2), out.dtype), np.empty((4, 2), out.dtype)
    v, g_free = np.empty(6, out.dtype), np.empty(6, out.dtype)
    g = params[0, 7].real
    shared = True
    for r in range(params.shape[0]):
        shared = shared and params[r, 7].real == g
    if not shared:
        for n in range(out.size):
            r, i = n // beta.shape[0], n % beta.shape[0]
            out[r, i] = _characteristic_one(beta[i], params[r], params[r, 7].real, rows, load, R, T, v, g_free)
        return
    for i in range(beta.shape[0]):
        factor = _from_clamp(beta[i], g, rows, load, R)
        beyond = factor if g == 1.0 else _to_free_end(beta[i], g, v, g_free)
        for r in range(params.shape[0]):
            out[r, i] = _joined(beta[i], params[r], g, R, T, v, factor, beyond)


@numba.njit(cache=True)
def _characteristic_one(b, p, g, rows, load, R, T, v, g_free):
    """:func:`characteristic` of the lever ``p`` at ``b``, its tip at ``g`` (real, or complex for a
    complex step in ``gamma``); the other arguments are work arrays."""
    factor = _from_clamp(b, g, rows, load, R)
    beyond = factor if g == 1.0 else _to_free_end(b, g, v, g_free)
    return _joined(b, p, g, R, T, v, factor, beyond)


@numba.njit(cache=True)
def _from_clamp(b, g, rows, load, R):
    """The clamp's segment (to the tip at ``g``) per unit of its two unknowns into ``R``; its factor."""
    s = b * g
    if _segment(b, g, g, 1.0, rows, load):
        for m in range(4):
            for c in range(2):
                R[m, c] = rows[m, 2 + c]
        return np.exp(-s)
    # the clamp's rows: the growing column is exp(-s) there, the decaying one's value here
    B00, B01, B10, B11 = 1.0, rows[0, 2], -1.0, rows[0, 2]
    for m in range(4):
        R[m, 0] = rows[m, 2] - rows[m, 0] * B00 - rows[m, 1] * B10
        R[m, 1] = rows[m, 3] - rows[m, 0] * B01 - rows[m, 1] * B11
    return 1.0 / _BOUNDED_AT_START + 0.0 * s


@numba.njit(cache=True)
def _to_free_end(b, g, v, g_free):
    """The segment beyond a set-back tip: the weights ``v`` of the minors of the tip's state; its factor
    (``g_free``: work, the minors of the free end's rows)."""
    ell = 1.0 - g
    s = b * ell
    if abs(s) <= _LIMIT:
        s_1, tt, uu, vv = _krylov_duncan(s)
        K = (s_1 + 1.0, tt, uu, vv)
        for q in range(6):
            a, c = _PAIRS[q]
            v[q] = K[(a - 2) % 4] * K[(c - 3) % 4] - K[(c - 2) % 4] * K[(a - 3) % 4]
        return np.exp(-s)
    basis = _bounded_basis(s, s)        # the free end's rows: 2, 3
    for q in range(6):
        a, c = _PAIR_ROWS[q, 0], _PAIR_ROWS[q, 1]
        g_free[q] = basis[8 + a] * basis[12 + c] - basis[8 + c] * basis[12 + a]
    at_start = basis[2]                 # exp(-s): the growing column's value at the segment's start
    for kk in range(6):
        total = s * 0.0
        for q in range(6):
            total += g_free[q] * (_START_MINORS[kk, q] * at_start if _PAIR_ROWS[5 - q, 1] == 3 else
                                  _START_MINORS[kk, q])
        v[kk] = total
    return 1.0 / _BOUNDED_AT_START + 0.0 * s


@numba.njit(cache=True)
def _joined(b, p, g, R, T, v, factor, beyond):
    """The tip's jump across ``R`` (``T``), then ``det T[2:]`` (the tip at the end) or the free segment's
    minors weighted by ``v``; times the factors."""
    J = _point_jump(b, p[0], p[1], p[2], p[3], p[4].real, p[5].real, p[6], p[8])
    for c in range(2):
        T[0, c], T[1, c] = R[0, c], R[1, c]
        T[2, c] = R[2, c] - J[0] * R[0, c] - J[1] * R[1, c]
        T[3, c] = R[3, c] - J[2] * R[0, c] - J[3] * R[1, c]
    if g == 1.0:
        return (T[2, 0] * T[3, 1] - T[2, 1] * T[3, 0]) * factor
    total = b * 0.0 * (1.0 - g)
    for q in range(6):
        a, c = _PAIRS[q]
        total += v[q] * (T[a, 0] * T[c, 1] - T[a, 1] * T[c, 0])
    return total * (factor * beyond)


@numba.njit(cache=True)
def tip_at_end_and_partials(beta, jump, djump, at_beta, out, partials):
    """``pfmdyn.composed.determinant._tip_at_end_and_partials`` per member, step for step: the clamp's segment per
    unit of its two unknowns ``R`` and ``dR/ds``, the tip's jump ``jump[n]`` across, ``det T[2:]`` times
    the factor (``out[n]``), and by the product rule its partials ``partials[p, n]`` from the jump's
    ``djump[p, n]`` (``at_beta``: the row of ``beta``, which also moves the segment; -1: none).

    Examples
    --------
    >>> point = (1.8751040687119611, 2.0, 0.0, 0.0, 0.0, 1e-5, 2e-4, 0.0, 0.0)     # the free lever's first root
    >>> jump = np.array([pieces.point_jump(*point)], float)
    >>> djump = np.array([[pieces.point_jump_partials(*point, wrt=("beta",))["beta"],
    ...                    pieces.point_jump_partials(*point, wrt=("mu",))["mu"]]], float).swapaxes(0, 1)
    >>> out, partials = np.empty(1), np.empty((2, 1))
    >>> tip_at_end_and_partials(np.array([point[0]]), jump, djump, 0, out, partials)
    >>> round(float(-partials[1, 0] / partials[0, 0]), 6)      # d beta1 / d mu: -beta1
    -1.875104
    """
    rows, load = np.empty((5, 4), out.dtype), np.empty(5, out.dtype)
    R, dR = np.empty((4, 2), out.dtype), np.empty((4, 2), out.dtype)
    T, moved = np.empty((2, 2), out.dtype), np.empty((2, 2), out.dtype)
    for i in range(beta.shape[0]):
        s = beta[i]
        if _segment(s, 1.0, 1.0, 1.0, rows, load):
            for m in range(4):
                for c in range(2):
                    R[m, c], dR[m, c] = rows[m, 2 + c], rows[m + 1, 2 + c]
            factor, d_log = np.exp(-s), -1.0
        else:
            B01 = rows[0, 2]        # exp(-s) at the clamp, as in _from_clamp
            for m in range(4):
                R[m, 0] = rows[m, 2] - rows[m, 0] * 1.0 - rows[m, 1] * -1.0
                R[m, 1] = rows[m, 3] - rows[m, 0] * B01 - rows[m, 1] * B01
                d3 = rows[m + 1, 3] - rows[m, 3]
                dR[m, 0] = rows[m + 1, 2] - rows[m + 1, 0] * 1.0 - rows[m + 1, 1] * -1.0
                dR[m, 1] = d3 - rows[m + 1, 0] * B01 - rows[m + 1, 1] * B01
                dR[m, 1] += rows[m, 0] * B01 + rows[m, 1] * B01
            factor, d_log = 1.0 / _BOUNDED_AT_START + 0.0 * s, 0.0
        J = jump[i]
        for m in range(2):
            for c in range(2):
                T[m, c] = R[2 + m, c] - J[2 * m] * R[0, c] - J[2 * m + 1] * R[1, c]
        det = T[0, 0] * T[1, 1] - T[0, 1] * T[1, 0]
        out[i] = det * factor
        for p in range(djump.shape[0]):
            dJ = djump[p, i]
            for m in range(2):
                for c in range(2):
                    moved[m, c] = 0.0 - dJ[2 * m] * R[0, c] - dJ[2 * m + 1] * R[1, c]
                    if p == at_beta:
                        moved[m, c] += dR[2 + m, c] - J[2 * m] * dR[0, c] - J[2 * m + 1] * dR[1, c]
            d = moved[0, 0] * T[1, 1] + T[0, 0] * moved[1, 1] - moved[0, 1] * T[1, 0] - T[0, 1] * moved[1, 0]
            partials[p, i] = (d + det * d_log if p == at_beta else d) * factor


def _sign(x):
    """``np.sign``: NaN for NaN."""
    return 1.0 if x > 0 else -1.0 if x < 0 else 0.0 if x == 0 else x


_sign = numba.njit(cache=True)(_sign)


@numba.njit(cache=True)
def _characteristic_at(beta, params, at, out):
    """:func:`characteristic` of the lever ``params`` at the points ``beta`` into ``out`` (1-d)."""
    characteristic(beta, params, at)
    out[:] = at[0]


@numba.njit(cache=True)
def characteristic_roots(grid, params, refine_roots, rtol):
    """Real roots of :func:`characteristic` of one lever (``params``, 1 x 9, real) bracketed by sign
    changes on ``grid``: :func:`pfmdyn.roots.bracket.grid_roots` step for step (the degree-7 Chebyshev
    interpolant's root by Newton, confirmed ``rtol`` wide, else Illinois regula falsi from the better
    side), every bracket in one compiled loop.

    Examples
    --------
    >>> roots = characteristic_roots(np.linspace(0.3, 10.0, 150), np.array([[2.0, 0, 0, 0, 1e-5, 2e-4, 0, 1.0, 0]]),
    ...                              True, 1e-13)
    >>> roots.round(8).tolist()       # the free lever's first three roots
    [1.87510407, 4.69409113, 7.85475744]
    """
    vals = np.empty(len(grid))
    at = np.empty((1, len(grid)))
    _characteristic_at(grid, params, at, vals)
    count = 0
    for i in range(len(grid) - 1):
        if _sign(vals[i]) * _sign(vals[i + 1]) < 0:
            count += 1
    lo, hi, flo, fhi = np.empty(count), np.empty(count), np.empty(count), np.empty(count)
    j = 0
    for i in range(len(grid) - 1):
        if _sign(vals[i]) * _sign(vals[i + 1]) < 0:
            lo[j], hi[j], flo[j], fhi[j] = grid[i], grid[i + 1], vals[i], vals[i + 1]
            j += 1
    if not refine_roots or count == 0:
        return hi - fhi * (hi - lo) / (fhi - flo)
    # interpolated_roots: the interpolant's coefficients, its derivative's, Newton from the secant root
    nodes = _LOBATTO.shape[0]
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    inner = np.empty((count, nodes - 2))
    for b in range(count):
        for q in range(nodes - 2):
            inner[b, q] = mid[b] + half[b] * _LOBATTO[q + 1]
    flat = inner.reshape(-1)
    inner_vals = np.empty(flat.shape[0])
    _characteristic_at(flat, params, np.empty((1, flat.shape[0])), inner_vals)
    coef = np.zeros((nodes, count))
    slope = np.empty((nodes - 1, count))
    node_vals = np.empty(nodes)
    for b in range(count):
        node_vals[0], node_vals[nodes - 1] = fhi[b], flo[b]
        node_vals[1:nodes - 1] = inner_vals[b * (nodes - 2):(b + 1) * (nodes - 2)]
        for q in range(nodes):
            for m in range(nodes):
                coef[q, b] += _TO_CHEBYSHEV[q, m] * node_vals[m]
        c = coef[:, b].copy()
        n = nodes - 1
        for m in range(n, 2, -1):
            slope[m - 1, b] = (2 * m) * c[m]
            c[m - 2] += (m * c[m]) / (m - 2)
        slope[1, b] = 4 * c[2]
        slope[0, b] = c[1]
    t = np.empty(count)
    for b in range(count):
        t[b] = min(max(1 - 2 * fhi[b] / (fhi[b] - flo[b]), -1.0), 1.0)
    for _ in range(12):
        converged = True
        for b in range(count):
            step = _chebval(t[b], coef[:, b]) / _chebval(t[b], slope[:, b])
            moved = t[b] - step
            t[b] = -1.0 if moved < -1.0 else 1.0 if moved > 1.0 else moved
            converged = converged and abs(step) < 1e-15
        if converged:
            break
    c = mid + half * t
    # the sub-bracket holding the root: around c when confirmed, else the side whose sign differs
    half = 0.45 * rtol * np.abs(c)
    near = np.empty(2 * count)
    _characteristic_at(np.concatenate((c - half, c + half)), params, np.empty((1, 2 * count)), near)
    a, fa, bb, fb = np.empty(count), np.empty(count), np.empty(count), np.empty(count)
    for b in range(count):
        left = _sign(flo[b]) * _sign(near[b]) <= 0
        around = not left and _sign(near[b]) * _sign(near[count + b]) <= 0
        a[b] = lo[b] if left else c[b] - half[b] if around else c[b] + half[b]
        bb[b] = c[b] - half[b] if left else c[b] + half[b] if around else hi[b]
        fa[b] = flo[b] if left else near[b] if around else near[count + b]
        fb[b] = near[b] if left else near[count + b] if around else fhi[b]
    # refine: Illinois regula falsi, each bracket on its own (as the vectorised form, where a
    # bracket once done no longer moves)
    point, value, one = np.empty(1), np.empty(1), np.empty((1, 1))
    unbracketed = False
    for b in range(count):
        for _ in range(60):
            if abs(bb[b] - a[b]) <= rtol * abs(bb[b]) or fb[b] == 0 or _sign(fa[b]) * _sign(fb[b]) > 0:
                break
            point[0] = bb[b] - fb[b] * (bb[b] - a[b]) / (fb[b] - fa[b])
            _characteristic_at(point, params, one, value)
            if _sign(value[0]) * _sign(fb[b]) < 0:
                a[b], fa[b] = bb[b], fb[b]
            else:
                fa[b] = fa[b] / 2
            bb[b], fb[b] = point[0], value[0]
        unbracketed = unbracketed or _sign(fa[b]) * _sign(fb[b]) > 0
    if unbracketed:
        for b in range(count):
            if abs(fa[b]) < abs(fb[b]):
                bb[b] = a[b]
    return bb


@numba.njit(cache=True)
def _chebval(x, c):
    """``numpy.polynomial.chebyshev.chebval`` at a point (Clenshaw), ``len(c) >= 3``."""
    x2 = 2 * x
    c0, c1 = c[-2], c[-1]
    for i in range(3, len(c) + 1):
        tmp = c0
        c0 = c[-i] - c1
        c1 = tmp + c1 * x2
    return c0 + c1 * x


@numba.njit(cache=True)
def characteristic_partials(beta, params, wrt, partials):
    """Partials ``partials[j, i]`` of :func:`characteristic` of one undamped lever ``params`` (9, real)
    at real ``beta[i]`` w.r.t. the parameter ``wrt[j]`` (its index in ``params``; -1: ``beta``) by a
    complex step: the characteristic is analytic in each (``H`` and ``L`` excepted: read as real), so
    ``Im F(x + ih) / h`` is its derivative free of cancellation; ``gamma`` too, with the tip set back
    by ``ih`` where it stands at the end (the one-segment form is the two-segment one's limit).

    Examples
    --------
    >>> p = np.array([2.0, 0, 0, 0, 1e-5, 2e-4, 0.0, 1.0, 0])
    >>> d = np.empty((2, 1))
    >>> characteristic_partials(np.array([1.8751040687119611]), p, np.array([-1, 6]), d)
    >>> round(float(-d[1, 0] / d[0, 0]), 6)      # d beta1 / d mu of a free lever: -beta1
    -1.875104
    """
    rows, load = np.empty((5, 4), np.complex128), np.empty(5, np.complex128)
    R, T = np.empty((4, 2), np.complex128), np.empty((4, 2), np.complex128)
    v, g_free = np.empty(6, np.complex128), np.empty(6, np.complex128)
    stepped = params.astype(np.complex128)
    for i in range(beta.shape[0]):
        for j in range(wrt.shape[0]):
            w = wrt[j]
            b = beta[i] + 0j
            if w < 0:
                h = 1e-20 * max(abs(beta[i]), 1.0)
                b = complex(beta[i], h)
            else:
                h = 1e-20 * max(abs(params[w]), 1.0)
                stepped[w] = complex(params[w], h)
            if w == 7:
                value = _characteristic_one(b, stepped, stepped[7], rows, load, R, T, v, g_free)
            else:
                value = _characteristic_one(b, stepped, params[7] + 0j, rows, load, R, T, v, g_free)
            partials[j, i] = value.imag / h
            if w >= 0:
                stepped[w] = params[w]


COMPILED_FROM = (pieces, bracket, segments)
"""The modules whose functions and constants these kernels compile in: a change to one drops their cached machine
code (:func:`pfmdyn.compiled.forget_when_changed`), as a change to this file does."""
forget_when_changed(__name__, *COMPILED_FROM)
