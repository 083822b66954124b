"""The read-out of the composed lever written out: the system's Schur complements, not assembled.

The clamp's rows and, beyond a set-back tip, the free end's are eliminated per segment in closed
form, leaving the tip's rows (2 x 2 with the tip at the end, 4 x 4 set back) to solve per member;
:class:`_WrittenOut` says how and why it stays well conditioned where inverting a whole basis does
not.  Separate from :mod:`.assembly` because it is a different algorithm for the same numbers (the
doctest and ``tests/test_fast_readouts.py`` hold it to the assembled system), and it is the NumPy
reference of the compiled read-out (:func:`pfmdyn.composed.kernels.read_out`, the same steps).
"""
from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..generated import lever_pieces as pieces
from .assembly import _Lever
from .parameters import _POINT, DRIVES, _drive_columns
from .segments import _Part, _rows, _Segment, _solve


_REORDERED = [2, 3, 0, 1]
"""A short segment's unknowns (its state at the start) with the moment and shear first."""


class _WrittenOut:
    """The lever read at ``sigma`` without assembling the system: each segment's rows at its outer
    end eliminated, as in :func:`_transferred`, and the tip's rows solved (2 x 2 or 4 x 4).

    A segment's end rows ``E[rows] c + P[rows] q0 = h`` (the clamp's ``u, z1``, ``h`` the base's
    ``y0``; beyond a set-back tip, the free end's moment and shear, ``h = 0``) read ``[Gp, Gf]`` on
    its coefficients, so ``c = [b0 - B u, u]``, ``B = Gp^-1 Gf``, ``b0 = Gp^-1 (h - P[rows] q0)``:
    two unknowns ``u`` per segment, its state anywhere ``z = R u + w`` (``R = E[:, 2:] - E[:, :2] B``,
    ``w`` from ``b0`` and the load).  ``Gp`` is ``I`` at the clamp in either basis; at the free end
    the bounded basis' ``cos, sin`` columns (a rotation) and, the short members' columns reordered
    (:data:`_REORDERED`), the field matrix's last two: well conditioned, where inverting the whole
    basis at the segment's start is not (its ``e^{s - s_end}`` column is ``e^{-beta l}`` there).

    With the tip at the end its rows ``X(z) = G d`` (``X(V) = V[2:] - J V[:2]``) leave the 2 x 2
    ``X(R) x = G d - X(w)``; set back, the states either side of the tip (``z_l = R_l x + w_l``,
    ``z_r = R_r y + w_r``: continuity, then the jump) the 4 x 4 ``[T(R_l), -R_r] [x; y] = [0; G d] -
    T(w_l) + w_r``, ``T(V) = [V[:2], X(V)]`` (:meth:`_across`); each solved by :func:`_small_inverse`.
    The segments are evaluated at their ends and the spot in one stack.  Inside, arrays keep the
    members last (rows, columns, members), so that a product of the tiny matrices is a few products
    of whole arrays (:func:`_product`); the results (:attr:`z`, :meth:`partials`) have the interface
    of :class:`_Lever`'s read-outs (batch first, flat; one column per drive asked, of :data:`DRIVES`);
    NaN where the system is singular, as there.

    Examples
    --------
    >>> args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-05, 0.0002, 0.1, 0.9, 0.05)
    >>> general = _Lever(*args)
    >>> want = general.state(general.reader(0.95))[:, :2]
    >>> bool(np.allclose(_WrittenOut(args[0], 0.95, *args[1:]).z, want, rtol=1e-13, atol=0))
    True
    """

    def __init__(self, beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, drives=DRIVES):
        args = [np.asarray(a) for a in (beta, sigma, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)]
        self.shape = np.broadcast_shapes(*(a.shape for a in args))
        n = math.prod(self.shape)
        flat = [a if a.ndim == 0 else np.broadcast_to(a, self.shape).reshape(-1) for a in args]
        beta, sigma, g = (np.broadcast_to(a, (n,)) for a in (flat[0], np.real(flat[1]), np.real(flat[9])))
        self.beta, self.k, self.L = beta.astype(np.result_type(beta, float)), flat[2], flat[7]
        self.point = (self.beta, *flat[2:9], flat[10])
        # one right-hand side per drive asked (of DRIVES): the load's and the base's columns as slices
        self.drives = tuple(drives)
        _drive_columns(drives, DRIVES)      # an unknown drive raises
        self._q0, self._y0 = (slice(drives.index(d), drives.index(d) + 1) if d in drives else slice(0, 0)
                              for d in ("q0", "y0"))
        self._tip = {DRIVES.index(d): j for j, d in enumerate(drives) if d in DRIVES[:4]}   # the jump's G columns
        self.two = bool(np.any(g != 1.0))
        self.before = sigma <= g if self.two else np.ones(n, bool)
        # (t, segment length) of the clamp, the tip from the left, [the tip from the right, the free
        # end,] and the spot
        at = [(np.zeros(n), g), (g, g)] + ([(np.zeros(n), 1.0 - g), (1.0 - g, 1.0 - g)] if self.two else [])
        spot = (np.where(self.before, sigma, sigma - g), np.where(self.before, g, 1.0 - g))
        # the batch each read point takes: a spot where the tip or the free end is takes theirs
        self.batch = list(range(len(at)))
        self.batch.append(next((b for b, (t, ell) in enumerate(at)
                                if np.array_equal(t, spot[0]) and np.array_equal(ell, spot[1])), len(at)))
        if self.batch[-1] == len(at):
            at.append(spot)
        self.t, self.ell = (np.concatenate(x).astype(float) for x in zip(*at))
        self.count = len(self.batch)
        stacked = np.tile(self.beta, len(at))
        short = np.abs(stacked * self.ell) <= pieces.KD_SERIES_LIMIT
        self.seg = _Segment(stacked, self.t, self.ell, short, np.ones(len(stacked)))
        if self.two:
            beyond = short & np.concatenate([np.zeros(2 * n, bool), np.ones(2 * n, bool), ~self.before][:len(at) - 2])
            self.seg.rows[beyond] = self.seg.rows[beyond][:, :, _REORDERED]
        self.uc = pieces.load_constant(self.beta, self.k, self.L) + 0 * self.beta
        self.E = self._batches(_members_last(self.seg.E))
        self.P = [self.uc * P for P in self._batches(_members_last(self.seg.P))]
        jump = _rows(pieces.point_jump(*self.point), n)
        self.J = jump[:4].reshape(2, 2, n)
        self.G = np.zeros((2, len(drives), n), jump.dtype)
        self.G[:, list(self._tip.values())] = jump[4:].reshape(2, 4, n)[:, list(self._tip)]
        # (batch, rows) eliminated per segment: the clamp's u, z1; the free end's moment and shear
        self.ends = [(0, slice(0, 2))] + ([(3, slice(2, 4))] if self.two else [])
        self.eliminated = [self._eliminate(*end, base=j == 0) for j, end in enumerate(self.ends)]
        R, w = self._per_unknown(1, 0)
        M, r = self._across(R), -self._across(w)
        r[-2:] += self.G                    # the jump's rows
        if self.two:
            R, w = self._per_unknown(2, 1)
            M, r = np.concatenate([M, -R], 1), r + w
        with np.errstate(all="ignore"):
            self.inverse = _small_inverse(M)
            self.u = np.split(_product(self.inverse, r), len(self.ends))
        self._c = {}
        self.c_spot = self._on_spot_segment(self.coefficients)
        self.z = np.moveaxis(self._state(-1, self.c_spot), -1, 0)

    def coefficients(self, j):
        """Segment ``j``'s coefficients per drive, ``[b0 - B u, u]`` (once: the values need only the
        spot's segment)."""
        if j not in self._c:
            _, B, b0 = self.eliminated[j]
            self._c[j] = np.concatenate([b0 - _product(B, self.u[j]), self.u[j]])
        return self._c[j]

    def _batches(self, x):
        """``x``, stacked over the batches along its last axis, split per read point (views)."""
        n = self.beta.shape[0]
        return [x[..., i * n:(i + 1) * n] for i in self.batch]

    def _eliminate(self, batch, rows, base):
        """``(Gp^-1, B, b0)`` of a segment from its end rows; ``base``: the clamp's, moved by ``y0``,
        where ``Gp = I`` (``Gp^-1`` None: nothing to solve)."""
        E, P = self.E[batch][rows], self.P[batch][rows]
        b0 = np.zeros((2, len(self.drives), P.shape[-1]), np.result_type(E, P))
        if base:
            b0[:, self._q0], b0[0, self._y0] = -P[:, None], 1.0
            return None, E[:, 2:], b0
        inverse = _small_inverse(E[:, :2])
        b0[:, self._q0] = -_product(inverse, P[:, None])
        return inverse, _product(inverse, E[:, 2:]), b0

    def _per_unknown(self, batch, segment):
        """``(R, w)`` at ``batch`` of ``segment``: its state ``z = R u + w`` per its unknowns ``u``."""
        E, (_, B, b0) = self.E[batch], self.eliminated[segment]
        w = _product(E[:, :2], b0)
        w[:, self._q0] += self.P[batch][:, None]
        return E[:, 2:] - _product(E[:, :2], B), w

    def _across(self, V):
        """What the tip's rows ask of a state ``V`` left of it: the jump's ``X(V) = V[2:] - J V[:2]``,
        after continuity's ``V[:2]`` when a segment lies beyond."""
        X = V[2:] - _product(self.J, V[:2])
        return np.concatenate([V[:2], X]) if self.two else X

    def _on_spot_segment(self, f):
        """``f(j)`` of the segment ``j`` the spot lies on, per member."""
        if self.before.all() or not self.before.any():
            return f(0 if self.before.all() else 1)
        return np.where(self.before, f(0), f(1))

    def _state(self, batch, c):
        """``[u, z1]`` per drive at ``batch`` from its segment's coefficients ``c``."""
        z = _product(self.E[batch][:2], c)
        z[:, self._q0] += self.P[batch][:2, None]
        return z

    def partials(self, names):
        """``{name: d [u, z1](sigma) / d name}`` per drive (``names`` of :data:`SPOT_JACOBIAN_PARAMETERS`
        but ``gamma``; batch first).  The states' change at fixed coefficients, ``e = dE c + dP q0``, less
        the eliminated rows' share (``E[:, :2] Gp^-1 e_end[rows]``), is ``dw``, their change at fixed
        unknowns; the tip's rows then move the unknowns by ``inverse ([0; dG d + dJ z_l[:2]] -
        T(dw_l) + dw_r)``."""
        n, count = self.beta.shape[0], self.count
        spot = slice(self.batch[-1] * n, (self.batch[-1] + 1) * n)
        coefficients = [self.coefficients(j) for j in np.arange(count - 1) // 2] + [self.c_spot]
        moved, at_spot = [], []
        for name in names:
            e = [None] * count
            if name == "beta":
                dE, dP = (_members_last(x) for x in self.seg.derivative(name, np.tile(self.beta, len(self.t) // n),
                                                                          self.t, self.ell, 1.0, 0.0))
                e = [_product(E, c) for E, c in zip(self._batches(dE), coefficients)]
                for changed, P in zip(e, self._batches(dP)):
                    changed[:, self._q0] += (self.uc * P)[:, None]
            elif name == "sigma":       # the spot alone moves
                dE, dP = (_members_last(x) for x in _Part(self.seg, spot).derivative(name, self.beta, None, None,
                                                                                     1.0, 0.0))
                e[-1] = _product(dE, coefficients[-1])
                e[-1][:, self._q0] += (self.uc * dP)[:, None]
            elif name == "k":           # through the load constant: P is in units of 1/k
                e = [np.zeros_like(c) for c in coefficients]
                for changed, P in zip(e, self.P):
                    changed[:, self._q0] = (-P / self.k)[:, None]
            q = (self._jump_moved(pieces.point_jump_partials(*self.point, wrt=(name,))[name]) if name in _POINT
                 else np.zeros_like(self.G))
            if self.two:
                q = np.concatenate([np.zeros_like(q), q])
            if e[0] is not None:
                left, right, e[-1] = self._at_fixed_unknowns(e)
                q -= self._across(left)
                if self.two:
                    q += right
            moved.append(q)
            at_spot.append(0.0 if e[-1] is None else e[-1][:2])
        # the spot's state per unit of the moved rows: R inverse (R = E[:, 2:] - E[:, :2] B of its segment)
        E, inverse = self.E[-1][:2], np.split(self.inverse, len(self.ends))
        spot_per_row = self._on_spot_segment(
            lambda j: _product(E[:, 2:] - _product(E[:, :2], self.eliminated[j][1]), inverse[j]))
        return {name: np.moveaxis(_product(spot_per_row, q) + w, -1, 0) for name, q, w in zip(names, moved, at_spot)}

    def _jump_moved(self, d):
        """``dJ z_tip + dG d`` of a partial ``d`` of the jump's twelve entries (:func:`pieces.point_jump`),
        its zero entries skipped (most are: each parameter enters a few)."""
        q = np.zeros_like(self.G)
        for i, v in enumerate(d):
            if np.ndim(v) == 0 and v == 0:
                continue
            if i < 4:
                q[i // 2] += v * self.z_tip[i % 2]
            elif (i - 4) % 4 in self._tip:
                q[(i - 4) // 4, self._tip[(i - 4) % 4]] += v
        return q

    def _at_fixed_unknowns(self, e):
        """``dw`` at the tip (either side) and the spot from the changes ``e`` at fixed coefficients
        (per batch): less the eliminated rows' share, ``E[:, :2] Gp^-1 e_end[rows]``, of the segment
        each lies on; ``(dw_l, dw_r or None, dw at the spot)``."""
        fixed = [e[batch][rows] if inverse is None else _product(inverse, e[batch][rows])
                 for (batch, rows), (inverse, _, _) in zip(self.ends, self.eliminated)]
        share = lambda i, j: e[i] - _product(self.E[i][:, :2], fixed[j])      # noqa: E731
        return share(1, 0), share(2, 1) if self.two else None, self._on_spot_segment(lambda j: share(-1, j))

    @cached_property
    def z_tip(self):
        return self._state(1, self.coefficients(0))

    out = _Lever.out


def _members_last(x):
    """A batch-first array with its members last, contiguous (the products below then stream)."""
    return np.ascontiguousarray(np.moveaxis(x, 0, -1))


def _product(A, B):
    """``A @ B`` per member, members last (``A`` (i, j, n), ``B`` (j, k, n)): ``j`` products of whole
    arrays, where NumPy's batched product of tiny matrices costs several times more.

    Examples
    --------
    >>> A, B = np.random.default_rng(2).normal(size=(2, 3, 2, 5))
    >>> bool(np.allclose(_product(A, B[:2, :]), np.einsum("ijn,jkn->ikn", A, B[:2, :])))
    True
    """
    out = A[:, 0, None] * B[None, 0]
    for j in range(1, A.shape[1]):
        out += A[:, j, None] * B[None, j]
    return out


def _small_inverse(M):
    """``M^-1`` per member (members last, ``M`` (m, m, n)): 2 x 2 by the adjugate, larger by LAPACK;
    NaN where ``M`` is singular.

    Examples
    --------
    >>> M = np.random.default_rng(1).normal(size=(2, 2, 3))
    >>> bool(np.allclose(_product(_small_inverse(M), M), np.eye(2)[:, :, None], rtol=0, atol=1e-13))
    True
    """
    if M.shape[0] != 2:
        return _members_last(_solve(np.moveaxis(M, -1, 0)))
    det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
    return np.array([[M[1, 1], -M[0, 1]], [-M[1, 0], M[0, 0]]]) / np.where(det == 0, np.nan, det)
