"""The assembled system ``A c = b`` of the composed lever, its partials and its determinant.

The lever is two uniform segments, clamp to tip (``0 < xi < gamma``) and tip to free end
(``gamma < xi < 1``; of zero length when the tip is at the end), joined at the tip point
(contact springs ``kvv, kll, kvl`` at height ``H``, tip mass ``mu``, rotary inertia ``rho_g``,
drives ``d1, d2, f0``) and loaded by ``q0`` along their length.  Assembled the dynamic-stiffness
way: per segment four unknowns (:mod:`.segments`), eight rows (clamp, continuity and jump at the
tip, free end), one right-hand side per drive, solved with NumPy and batched over every frequency
and parameter given.  Derivatives come from the same system (``dc = A^-1 (db - dA c)``), and the
characteristic is its determinant (:func:`_scaled_det`).

This is the general form: a probe's read-out and the partials w.r.t. ``gamma`` come from it, and it
is the reference the written-out forms (:mod:`.written_out`, :mod:`.determinant`) and the
compiled kernels (:mod:`.kernels`) are held to in the tests.
"""
from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..generated import lever_pieces as pieces
from .parameters import _POINT, _Q0, _Y0, DRIVES, PROBE_DRIVES
from .segments import _BOUNDED_AT_START, _columns, _Segment, _solve


class _Lever:
    """The assembled system ``A c = b`` of one batch (all arguments broadcast and flattened).

    Segments run between the clamp, the points and the free end: the tip's point, and with
    ``probe`` a bare point at ``x = probe L`` driven by its own force and couple (:data:`PROBE_DRIVES`;
    on the same side of the tip for the whole batch).  One segment when the tip is at the end
    everywhere and nothing else is asked (``gamma = 1``, no ``gamma`` derivative, no probe); each
    segment four unknowns, one right-hand side per drive."""

    def __init__(self, beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g, *, split=False, derivatives=False,
                 probe=None):
        args = [np.asarray(a) for a in (beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g)]
        self.shape = np.broadcast_shapes(*(a.shape for a in args))
        dtype, n = np.result_type(*args, float), math.prod(self.shape)
        flat = [np.full(n, a, dtype) if a.ndim == 0 else np.broadcast_to(a.astype(dtype), self.shape).reshape(-1)
                for a in args]
        self.beta, k, kvv, kll, kvl, H, L, mu, gamma, rho_g = flat
        self.k, self.L, self.gamma = k, L, np.real(gamma)
        self.derivatives = derivatives      # solve for A^-1 with c: derivatives will be asked
        # the point's parameters as plain numbers where they are one value (cheaper than arrays)
        one = [a.item() if a.ndim == 0 else f for a, f in zip(args, flat)]
        self.uc = pieces.load_constant(self.beta, one[1], one[6]) + 0 * self.beta
        self.point = (self.beta, *one[1:8], one[9])
        self.jump = _columns(pieces.point_jump(*self.point), n, dtype)
        g = self.gamma
        self.drives = DRIVES if probe is None else DRIVES + PROBE_DRIVES
        # the points in order along the lever: (position, J, G over the drives); the tip's index
        tip_drives = self._drive_block(self.jump[:, 4:], DRIVES.index("d1"))
        points = [(g, self.jump[:, :4].reshape(-1, 2, 2), tip_drives)]
        self.tip = 0
        if probe is not None:
            if derivatives or split:
                raise ValueError("a probed lever is solved for its response only")
            at = np.broadcast_to(np.real(np.asarray(probe, dtype=float)), self.shape).reshape(-1)
            # a force and a couple act on a point through the f0 and m0 columns of its jump, which
            # hold no spring or mass: a bare point's drives are the tip's
            forced = np.zeros_like(tip_drives)
            forced[:, :, len(DRIVES):] = tip_drives[:, :, [DRIVES.index("f0"), DRIVES.index("m0")]]
            if np.all(at == g):             # at the tip: its point takes them
                points = [(g, points[0][1], tip_drives + forced)]
            else:
                first = at < g
                if first.any() and not first.all():
                    raise ValueError("the probe must lie on the same side of the tip throughout a batch")
                self.tip = int(first.all())
                points.insert(1 - self.tip, (at, np.zeros((n, 2, 2), dtype), forced))
        self.two = len(points) > 1 or split or bool(np.any(g != 1.0))
        self.points = points if self.two else []
        bounds = [np.zeros_like(g)] + [p[0] for p in self.points] + [np.ones_like(g)]
        self.starts = bounds[:-1]
        self.lengths = tuple(b - a for a, b in zip(bounds[:-1], bounds[1:]))
        self.short = [np.abs(self.beta * ell) <= pieces.KD_SERIES_LIMIT for ell in self.lengths]
        # (segment, t, d ell/d gamma, d t/d gamma) of the ends the rows use: each segment's start and
        # end (the tip moves the segments about it: d/d gamma is +1 on its left, -1 on its right)
        slopes = [1.0, -1.0] if len(self.lengths) == 2 and self.tip == 0 else [0.0] * len(self.lengths)
        self.ends = [end for j, ell in enumerate(self.lengths)
                     for end in ((j, np.zeros_like(g), slopes[j], 0.0), (j, ell, slopes[j], slopes[j]))]
        count = len(self.ends)
        rows, take = self._shared_rows([args[0], args[8]] + ([np.asarray(probe)] if probe is not None else []))
        pick = (lambda x: x) if rows is None else (lambda x: x[rows])      # noqa: E731
        uc = self.uc if rows is None else np.ones(len(rows), self.uc.dtype)
        stacked = _Segment(np.concatenate([pick(self.beta)] * count), np.concatenate([pick(t) for _, t, _, _ in self.ends]),
                           np.concatenate([pick(self.lengths[j]) for j, _, _, _ in self.ends]),
                           np.concatenate([pick(self.short[j]) for j, _, _, _ in self.ends]),
                           np.concatenate([uc] * count))
        self.at = stacked.parts(count, take, None if rows is None else self.uc)
        self.A, self.b = self._assemble(points, [(e.E, e.P) for e in self.at])

    def _shared_rows(self, args):
        """Members whose segments are the same (the same ``beta`` and points, other parameters
        varying: a grid of springs): one row per distinct set and each member's row among them,
        ``(rows, take)``; ``(None, None)`` when too little is shared to gain."""
        small = np.broadcast_shapes(*(np.shape(a) for a in args))
        m, n = math.prod(small), self.beta.shape[0]
        if 2 * m > n:
            return None, None
        take = np.broadcast_to(np.arange(m).reshape(small), self.shape).reshape(-1)
        rows = np.empty(m, int)
        rows[take] = np.arange(n)
        return rows, take

    def _drive_block(self, G, first):
        """A point's drive columns ``G`` (n, 2, m) placed among :attr:`drives` from column ``first``."""
        G = G.reshape(G.shape[0], 2, -1)
        out = np.zeros(G.shape[:2] + (len(self.drives),), G.dtype)
        out[:, :, first:first + G.shape[-1]] = G
        return out

    @cached_property
    def jump_partials(self):
        return pieces.point_jump_partials(*self.point)

    @cached_property
    def c(self):
        """The segments' coefficients per drive (NaN where the system is singular: an undamped
        resonance met exactly, or a non-finite argument)."""
        return self._solved[0] if self.derivatives else _solve(self.A, self.b)

    @cached_property
    def inverse(self):
        """``A^-1``, from the same solve as :attr:`c` (derivatives are products with it)."""
        return self._solved[1]

    @cached_property
    def _solved(self):
        size, nd = self.A.shape[-1], self.b.shape[-1]
        out = _solve(self.A, np.concatenate([self.b, np.broadcast_to(np.eye(size), self.A.shape)], -1))
        return out[..., :nd], out[..., nd:]

    def _assemble(self, points, ends, dpoints=None, dends=None):
        """``A``, ``b`` from the points ``(position, J, G)`` and the segments' end values; with
        ``dpoints``, ``dends`` given, their derivative (the system is linear in each but for each
        point's ``J`` times the state there)."""
        values = dends or ends
        n, size = self.beta.shape[0], 4 * len(self.lengths)
        dtype = np.result_type(values[1][0], points[0][1], values[1][1])
        A = np.zeros((n, size, size), dtype=dtype)
        b = np.zeros((n, size, len(self.drives)), dtype=dtype)
        E0, P0 = values[0]
        A[:, 0:2, 0:4], b[:, 0:2, _Q0] = E0[:, 0:2], -P0[:, 0:2]         # clamp
        if dpoints is None:
            b[:, 0, _Y0] = 1.0                                           # moved with the base: u(0) = y0
        for i, (_, J, G) in enumerate(points):
            (El, Pl), (dEl, dPl) = ends[2 * i + 1], values[2 * i + 1]
            if dpoints is None:
                JE, JP = J @ El[:, 0:2], np.einsum("nij,nj->ni", J, Pl[:, 0:2])
            else:
                dJ, G = dpoints[i]
                JE = dJ @ El[:, 0:2] + J @ dEl[:, 0:2]
                JP = np.einsum("nij,nj->ni", dJ, Pl[:, 0:2]) + np.einsum("nij,nj->ni", J, dPl[:, 0:2])
            if not self.points:                 # the tip at the free end: its jump ends the lever
                A[:, 2:4, 0:4], b[:, 2:4], b[:, 2:4, _Q0] = dEl[:, 2:4] - JE, G, JP - dPl[:, 2:4]
                return A, b
            left, right, r = slice(4 * i, 4 * i + 4), slice(4 * i + 4, 4 * i + 8), 4 * i + 2
            Er, Pr = values[2 * i + 2]
            A[:, r:r + 2, left], A[:, r:r + 2, right] = dEl[:, 0:2], -Er[:, 0:2]        # u, u' continuous
            b[:, r:r + 2, _Q0] = (Pr - dPl)[:, 0:2]
            A[:, r + 2:r + 4, left], A[:, r + 2:r + 4, right] = dEl[:, 2:4] - JE, -Er[:, 2:4]  # moment, shear jump
            b[:, r + 2:r + 4] = G
            b[:, r + 2:r + 4, _Q0] = JP + Pr[:, 2:4] - dPl[:, 2:4]
        Ee, Pe = values[-1]
        A[:, -2:, -4:], b[:, -2:, _Q0] = Ee[:, 2:4], -Pe[:, 2:4]         # free end
        return A, b

    def _tip_partial(self, name):
        """``(dJ, dG)`` of the tip's point w.r.t. ``name`` (zeros for a parameter it does not hold)."""
        if name not in _POINT:
            n = self.beta.shape[0]
            return np.zeros((n, 2, 2), self.jump.dtype), np.zeros((n, 2, len(self.drives)), self.jump.dtype)
        d = _columns(self.jump_partials[name], self.beta.shape[0], self.jump.dtype)
        return d[:, :4].reshape(-1, 2, 2), self._drive_block(d[:, 4:], DRIVES.index("d1"))

    def _d_ends(self, name):
        """Derivatives of the points and of the ends' values w.r.t. ``name``."""
        dpoints = [self._tip_partial(name)]
        dends = []
        for (j, t, d_ell, d_t), seg in zip(self.ends, self.at):
            d = seg.derivative(name, self.beta, t, self.lengths[j], np.full_like(t, d_ell), np.full_like(t, d_t))
            if d is None:
                d = (np.zeros_like(seg.E), -seg.P / self.k[:, None] if name == "k" else np.zeros_like(seg.P))
            elif name == "sigma":
                d = (np.zeros_like(seg.E), np.zeros_like(seg.P))
            dends.append(d)
        return dpoints, dends

    def _tip_points(self):
        return self.points or [(self.gamma, self.jump[:, :4].reshape(-1, 2, 2),
                                self._drive_block(self.jump[:, 4:], DRIVES.index("d1")))]

    def d_system_matrix(self, name):
        """``dA`` w.r.t. ``name``."""
        dpoints, dends = self._d_ends(name)
        return self._assemble(self._tip_points(), [(e.E, e.P) for e in self.at], dpoints, dends)[0]

    def d_det_at_tip(self, adjugate, names):
        """``tr(adj(A) dA)`` for parameters of the tip point alone (``k`` among them: the jump is
        in units of the lever's stiffness): ``dA`` is ``-dJ`` times the tip's state, in the jump's
        rows and the first segment's columns only."""
        rows, E = self._jump_rows, self.at[1].E[:, 0:2]
        adj = adjugate[:, 0:4, rows]
        return [-np.einsum("nji,nij->n", adj, self._tip_partial(name)[0] @ E) for name in names]

    @property
    def _jump_rows(self):
        return slice(4, 6) if self.two else slice(2, 4)

    def _tip_state(self):
        """``[u, z1]`` at the tip per drive (2 x drives): what a change of the jump acts on."""
        E, P = self.at[1].E, self.at[1].P
        z = E[:, 0:2] @ self.c[:, 0:4]
        z[:, :, _Q0] += P[:, 0:2]
        return z

    def d_system(self, names):
        """``{name: dc}``, one solve for all.  A parameter of the tip point alone changes only the
        jump's rows of the system: there ``db - dA c = dG d + dJ [u, z1]``."""
        rhs, tip = [], None
        for name in names:
            if name in _POINT and name not in ("beta", "k"):
                tip = self._tip_state() if tip is None else tip
                dJ, dG = self._tip_partial(name)
                r = np.zeros_like(self.b, dtype=np.result_type(self.b, dJ))
                r[:, self._jump_rows] = dJ @ tip + dG
            else:
                dpoints, dends = self._d_ends(name)
                dA, db = self._assemble(self._tip_points(), [(e.E, e.P) for e in self.at], dpoints, dends)
                r = db - dA @ self.c
            rhs.append(r)
        if not rhs:
            return {}
        nd = self.b.shape[-1]
        dc = self.inverse @ np.concatenate(rhs, -1)
        return {name: dc[..., nd * i:nd * (i + 1)] for i, name in enumerate(names)}

    def reader(self, sigma):
        """The read-out at ``sigma``: its segment evaluation, which coefficients it uses, and how it
        moves with the tip."""
        sigma = np.broadcast_to(np.real(np.asarray(sigma, dtype=float)), self.shape).reshape(-1)
        index = sum((sigma > p[0]).astype(int) for p in self.points) if self.points else np.zeros(sigma.shape, int)
        pick = lambda values: np.choose(index, values)   # noqa: E731  (one per segment, chosen per member)
        t = sigma - pick(self.starts)
        ell, short = pick(self.lengths), pick(self.short)
        seg = _Segment(self.beta, t, ell, short, self.uc)
        return seg, t, ell, index, self._coefficients(index, self.c)

    @staticmethod
    def _coefficients(index, c):
        """The coefficients of the segment each member reads (``index``)."""
        rows = 4 * index[:, None] + np.arange(4)
        return np.take_along_axis(c, rows[:, :, None], axis=1)

    def state(self, reader, dc=None):
        seg, _, _, index, coefficients = reader
        if dc is not None:
            coefficients = self._coefficients(index, dc)
        z = seg.E @ coefficients
        if dc is None:
            z[:, :, _Q0] += seg.P
        return z

    def d_state(self, reader, name, dc):
        """``d z(sigma)/d name`` (flat, 4 components x the drives)."""
        seg, t, ell, index, coefficients = reader
        z = self.state(reader, dc)
        before = index == 0
        d = seg.derivative(name, self.beta, t, ell, np.where(before, 1.0, -1.0), np.where(before, 0.0, -1.0))
        if d is None:
            if name == "k":
                z[:, :, _Q0] -= seg.P / self.k[:, None]
            return z
        dE, dP = d
        z = z + dE @ coefficients
        z[:, :, _Q0] += dP
        return z

    def out(self, x):
        """Flat results back to the arguments' broadcast shape (batch first)."""
        return x.reshape(self.shape + x.shape[1:])


def _scaled_det(lever):
    """``det A`` times a factor free of zeros that makes it one function of ``beta`` across the bases
    (a short segment's unknowns are its state, a long one's the bounded basis' coefficients) and
    across the one- and two-segment systems; ``d log(factor)/d beta``, ``/d gamma``; the factor."""
    scale, d_beta, d_gamma = (1.0 if lever.two else _ONE_SEGMENT), 0.0, 0.0
    for short, ell, side in zip(lever.short, lever.lengths, (1.0, -1.0)):
        scale = scale * np.where(short, np.exp(-lever.beta * ell), 1.0 / _BOUNDED_AT_START)
        d_beta = d_beta + np.where(short, -ell, 0.0)
        d_gamma = d_gamma + np.where(short, -side * lever.beta, 0.0)
    return _clamped_det(lever.A) * scale, d_beta, d_gamma, scale


def _clamped_det(A):
    """``det A`` by the Schur complement of the clamp's rows: in either basis they read
    ``[I, B]`` on the first segment's unknowns, so ``det A = det(A22 - A21 B)``."""
    return _det(A[:, 2:, 2:] - A[:, 2:, 0:2] @ A[:, 0:2, 2:])


def _det(A):
    with np.errstate(all="ignore"):
        return np.linalg.det(A)


def _adjugate(A):
    """``adj(A) = det(A) A^-1`` batched, from the SVD ``A = U diag(s) V^H``: ``det(U) det(V^H)
    V diag(prod_{j != i} s_j) U^H``, finite where ``A`` is singular."""
    u, sv, vh = np.linalg.svd(A)
    n = sv.shape[-1]
    others = np.stack([np.prod(np.delete(sv, i, axis=-1), axis=-1) for i in range(n)], -1)
    phase = np.linalg.det(u) * np.linalg.det(vh)
    return phase[:, None, None] * np.conj(np.swapaxes(vh, -1, -2)) @ (others[..., :, None] * np.conj(np.swapaxes(u, -1, -2)))


def _one_segment_factor() -> float:
    """``det`` of the two-segment system with a zero-length second segment over the one-segment
    ``det`` (a fixed sign: the second segment's unknowns are its state, eliminated by permutation)."""
    args = (2.5, 2.0, 98.0, 52.0, 9.0, 1e-5, 2e-4, 0.1, 1.0, 0.05)
    ratio = float(np.linalg.det(_Lever(*args, split=True).A)[0] / np.linalg.det(_Lever(*args).A)[0])
    return round(ratio)


_ONE_SEGMENT = _one_segment_factor()
