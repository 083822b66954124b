"""The uniform segment read anywhere: its basis per member and the load's particular solution per unit
``q0``, with their derivatives along the segment and w.r.t. its length.

A segment with ``|beta l| <= 1`` uses the Krylov-Duncan field matrix (its state at the start as
unknowns, series free of cancellation, and the load's particular solution of zero initial state), a
longer one the bounded basis ``cos, sin, e^{-s}, e^{s - beta l}``: nothing overflows and nothing
cancels, from the quasi-static ``beta = 1e-3`` to ``Re beta = 200``.  Separate because the assembled
system (:mod:`.assembly`), its written-out forms (:mod:`.written_out`) and the characteristic
(:mod:`.determinant`) all read segments the same way, and share this choice of basis and its scale.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..generated import lever_pieces as pieces


_BOUNDED_AT_START = float(np.linalg.det(np.array(pieces.bounded_basis(0.0, 0.0)[:16], dtype=float).reshape(4, 4)))


def _solve(A, b=None):
    """``A^-1 b`` batched (``A^-1`` without ``b``); NaN for the members whose ``A`` is singular or not finite."""
    solve = np.linalg.inv if b is None else lambda A: np.linalg.solve(A, b)   # noqa: E731
    try:
        with np.errstate(all="ignore"):
            return solve(A)
    except np.linalg.LinAlgError:
        eye = np.eye(A.shape[-1])
        bad = ~np.isfinite(A).all(axis=(-2, -1))
        with np.errstate(all="ignore"):
            bad |= np.abs(np.linalg.det(np.where(bad[..., None, None], eye, A))) == 0
        out = solve(np.where(bad[..., None, None], eye, A))
        out[bad] = np.nan
        return out


_CIRCULANT = np.array([[(j - m) % 4 for j in range(4)] for m in range(5)])
"""``F[m][j] = K[(j - m) % 4]``: the field matrix and its ``d/ds`` (row 4) from ``K = (S, T, U, V)``."""


def _rows(values, n, dtype=None) -> np.ndarray:
    """``values`` (arrays of length ``n`` or scalars) as the rows of one ``(len(values), n)`` array."""
    dtype = dtype or np.result_type(*values, float)
    out = np.empty((len(values), n), dtype)
    for i, v in enumerate(values):
        out[i] = v
    return out


def _columns(values, n, dtype=None) -> np.ndarray:
    """``values`` as the columns of one ``(n, len(values))`` array."""
    return _rows(values, n, dtype).T


class _Segment:
    """A segment read at ``t`` (length ``ell``): basis ``E[:, n, j]``, load ``P[:, n]`` per unit q0, and
    their derivatives along ``s = beta t`` (``dE``, ``dP``) and w.r.t. ``s_end = beta ell`` (``dE_end``).

    Members with ``short`` use the Krylov-Duncan field matrix, the others the bounded basis.  The
    five rows ``d**n/ds**n``, ``n = 0..4``, are kept: the basis is rows 0-3, its ``d/ds`` rows 1-4."""

    def __init__(self, beta, t, ell, short, uc):
        s = beta * t
        if short.all():
            self.rows, self.load = self._krylov_duncan(s, uc)
        elif not short.any():
            self.rows, self.load = self._bounded(s, beta * ell, uc)
        else:
            rows = np.empty(beta.shape + (5, 4), np.result_type(beta, uc))
            load = np.empty(beta.shape + (5,), rows.dtype)
            for mask, make in ((short, self._krylov_duncan), (~short, self._bounded)):
                args = (s[mask], uc[mask]) if make == self._krylov_duncan else (s[mask], (beta * ell)[mask], uc[mask])
                rows[mask], load[mask] = make(*args)
            self.rows, self.load = rows, load
        self.short = short
        self.E, self.dE = self.rows[:, :4], self.rows[:, 1:]
        self.P, self.dP = self.load[:, :4], self.load[:, 1:]

    @staticmethod
    def _krylov_duncan(s, uc):
        s_1, t, u, v = pieces.krylov_duncan(s)
        K = _columns((s_1 + 1.0, t, u, v), s.shape[0])
        # the load of zero initial state, uc (e0 - F[:, 0]), and its d/ds: -uc (S - 1, V, U, T, S)
        return K[:, _CIRCULANT], -uc[:, None] * _columns((s_1, v, u, t, K[:, 0]), s.shape[0])

    @staticmethod
    def _bounded(s, s_end, uc):
        rows = _columns(pieces.bounded_basis(s, s_end), s.shape[0]).reshape(-1, 5, 4)
        load = np.zeros(s.shape + (5,), np.result_type(rows, uc))
        load[:, 0] = uc
        return rows, load

    @cached_property
    def dE_end(self):
        """``d E / d s_end``: only the bounded basis' ``e^{s - s_end}`` column depends on it."""
        out = np.zeros_like(self.E)
        out[:, :, 3] = np.where(self.short[:, None], 0.0, -self.E[:, :, 3])
        return out

    def parts(self, count, take=None, uc=None):
        """The segment evaluations of ``count`` stacked batches (one evaluation serves them all); with
        ``take``, each member's row among shared ones and its load constant ``uc`` (the rows' is 1)."""
        n = self.E.shape[0] // count
        return [_Part(self, slice(i * n, (i + 1) * n), take, uc) for i in range(count)]

    def derivative(self, name, beta, t, ell, moves_end, moves_start):
        """``(dE, dP)`` w.r.t. ``name``.  ``moves_end``, ``moves_start``: ``d ell/d gamma`` and
        ``d t/d gamma`` (the segment's length and the read point follow the tip)."""
        b = beta[:, None, None]
        if name == "beta":
            return (t[:, None, None] * self.dE + ell[:, None, None] * self.dE_end,
                    t[:, None] * self.dP - 4 * self.P / beta[:, None])
        if name == "gamma":
            ds = (moves_start * beta)[:, None, None]
            return ds * self.dE + moves_end[:, None, None] * b * self.dE_end, ds[:, 0] * self.dP
        if name == "sigma":
            return b * self.dE, b[:, 0] * self.dP
        return None


class _Part:
    """One batch of a stacked :class:`_Segment` evaluation (views; copies of shared rows with ``take``)."""

    def __init__(self, whole, part, take=None, uc=None):
        self.whole, self.part, self.take = whole, part, take
        rows, load = whole.rows[part], whole.load[part]
        if take is not None:
            rows, load = rows[take], load[take] * uc[:, None]
        self.E, self.dE, self.P, self.dP = rows[:, :4], rows[:, 1:], load[:, :4], load[:, 1:]

    @property
    def dE_end(self):
        d = self.whole.dE_end[self.part]
        return d if self.take is None else d[self.take]

    derivative = _Segment.derivative
